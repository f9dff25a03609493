//! Every diagnostic: message and position.

use super::*;

// ------------------------------------------------------------ diagnostics

#[test]
fn unexpected_token() {
    let e = assert_err("object o = sphere(1) +;", "unexpected `;`", 1, 23);
    assert!(e.help.unwrap().contains("a number"));
    assert_err(
        "object o = sphere(1);\ncamera { eye = (1, 2, 3) }",
        "unexpected `}`",
        2,
        26,
    );
    assert_err("object o = x y;", "unexpected name `y`", 1, 14);
    assert_err("object o = x @ y;", "unexpected character `@`", 1, 14);
    let e = assert_err(
        "object o = x { color = (1, 0, 0); };",
        "unexpected `;`",
        1,
        36,
    );
    assert_eq!(
        e.help.as_deref(),
        Some("a block `{ … }` is not followed by `;`")
    );
    let e = assert_err("object o = x\nobject p = y;", "unexpected `object`", 2, 1);
    assert!(e.help.unwrap().ends_with("is a `;` missing before this?"));
}

#[test]
fn unterminated_input() {
    let e = assert_err("object o = (x + 1", "unexpected end of input", 1, 18);
    assert!(e.help.unwrap().contains("`)`"));
    assert_err("object o = sphere(1)\n", "unexpected end of input", 1, 21);
}

#[test]
fn unknown_names_suggest_a_fix() {
    let e = assert_err("object o = sphre(1);", "unknown function `sphre`", 1, 12);
    assert_eq!(e.help.as_deref(), Some("did you mean `sphere`?"));
    assert!(e.rendered.contains("help: did you mean `sphere`?"));
    let e = assert_err(
        "let radius = 1;\nobject o = sphere(raduis);",
        "unknown variable `raduis`",
        2,
        19,
    );
    assert_eq!(e.help.as_deref(), Some("did you mean `radius`?"));
    let e = assert_err("object o = w + 1;", "unknown variable `w`", 1, 12);
    assert!(
        e.help.is_none()
            || e.help
                .as_deref()
                .is_some_and(|h| h.contains("did you mean"))
    );
    let e = assert_err(
        "fn f(size) = x - sise; object o = f(1);",
        "unknown variable `sise`",
        1,
        18,
    );
    assert_eq!(e.help.as_deref(), Some("did you mean `size`?"));
    let e = assert_err("object o = qqqqqq(x);", "unknown function `qqqqqq`", 1, 12);
    assert_eq!(e.help, None);
}

#[test]
fn wrong_arity() {
    let e = assert_err(
        "object o = sphere(1, 2);",
        "`sphere` takes 1 argument, but 2 were given",
        1,
        12,
    );
    assert_eq!(e.help.as_deref(), Some("call it as `sphere(r)`"));
    assert_err(
        "object o = min(x);",
        "`min` takes at least 2 arguments, but 1 was given",
        1,
        12,
    );
    assert_err(
        "object o = x +\n  sqrt(x, y);",
        "`sqrt` takes 1 argument, but 2 were given",
        2,
        3,
    );
    assert_err(
        "fn f(a, b) = a + b;\nobject o = f(x);",
        "`f` takes 2 arguments, but 1 was given",
        2,
        12,
    );
    assert_err(
        "object o = blend(x, y);",
        "`blend` takes 3 arguments",
        1,
        12,
    );
}

#[test]
fn recursion() {
    let e = assert_err(
        "fn f(a) = f(a) + x;\nobject o = f(1);",
        "recursive use of `f` (f -> f)",
        1,
        11,
    );
    assert!(e.help.unwrap().contains("inlined"));
    assert_err(
        "fn f(a) = g(a);\nfn g(b) = f(b) + x;\nobject o = f(x);",
        "mutually recursive use of `f` (f -> g -> f)",
        2,
        11,
    );
    assert_err(
        "let a = b + x;\nlet b = a;\nobject o = a;",
        "mutually recursive use of `a`",
        2,
        9,
    );
}

#[test]
fn duplicate_definitions() {
    let e = assert_err(
        "let a = 1;\nlet a = 2;\nobject o = x;",
        "`a` is defined twice",
        2,
        5,
    );
    assert!(e.rendered.contains("first defined here"));
    assert_err(
        "fn sphere(r) = x;\nobject o = x;",
        "`sphere` is defined twice",
        1,
        4,
    );
    assert_err(
        "object o = x;\nobject o = y;",
        "object `o` is defined twice",
        2,
        8,
    );
    assert_err(
        "fn f(a, a) = a; object o = x;",
        "parameter `a` is defined twice",
        1,
        9,
    );
    assert_err(
        "let sin = 1; object o = x;",
        "cannot define `sin`: it is a built-in function",
        1,
        5,
    );
    assert_err(
        "fn f(x) = x; object o = x;",
        "cannot use as a parameter `x`",
        1,
        6,
    );
    assert_err(
        "object o = x;\ncamera { fov = 30; }\ncamera { fov = 40; }",
        "a second `camera` block",
        3,
        1,
    );
    assert_err(
        "object o = x;\ncamera { fov = 30; fov = 40; }",
        "`fov` is set twice in camera",
        2,
        20,
    );
    assert_err(
        "object o = x;\nbounds = (0,0,0)..(1,1,1);\nbounds = (0,0,0)..(1,1,1);",
        "`bounds` is set twice",
        3,
        1,
    );
}

#[test]
fn missing_object() {
    let e = assert_err("", "the scene has no object", 1, 1);
    assert!(e.help.unwrap().contains("object ball"));
    assert_err(
        "let a = 1;\ncamera { fov = 30; }\n",
        "the scene has no object",
        3,
        1,
    );
}

#[test]
fn bad_number_literals() {
    assert_err("object o = 1.2.3 + x;", "bad number literal `1.2.3`", 1, 12);
    assert_err("object o = x + 1e;", "bad number literal `1e`", 1, 16);
    let e = assert_err("object o = 2x;", "bad number literal `2x`", 1, 12);
    assert!(e.help.unwrap().contains("2*x"));
    assert_err(
        "object o = x + 1e999;",
        "bad number literal `1e999`: out of range",
        1,
        16,
    );
}

#[test]
fn non_integer_exponent() {
    let e = assert_err(
        "object o = x^0.5;",
        "the exponent of `^` must be an integer, but it is 0.5",
        1,
        14,
    );
    assert!(e.help.unwrap().contains("pow(a, b)"));
    assert_err(
        "object o = x^y;",
        "the exponent of `^` must be a constant integer",
        1,
        14,
    );
    assert_err("object o = x^(1/3);", "must be an integer", 1, 14);
    assert_err(
        "object o = x^1e10;",
        "the exponent of `^` is too large",
        1,
        14,
    );
}

#[test]
fn not_a_shape() {
    assert_err("object o = 3 + 4;", "this is not a shape", 1, 12);
    assert_err(
        "let r = 2;\nobject o =\n  sin(r) * 2;",
        "this is not a shape",
        3,
        3,
    );
}

#[test]
fn invalid_values() {
    assert_err(
        "object o = scale(sphere(1), -2);",
        "the scale factor must be positive",
        1,
        29,
    );
    assert_err(
        "object o = scale(sphere(1), x);",
        "the scale factor must be a constant",
        1,
        29,
    );
    assert_err(
        "object o = blend(x, y, 0);",
        "the blend radius must be positive",
        1,
        24,
    );
    assert_err("object o = x + sqrt(-1);", "not a number (NaN)", 1, 16);
    assert_err(
        "object o = x;\ncamera { eye = (0, 0, 0); }",
        "`eye` and `target` are the same point",
        2,
        1,
    );
    assert_err(
        "object o = x;\ncamera { eye = (0, 5, 0); }",
        "`up` is zero or parallel",
        2,
        1,
    );
    assert_err(
        "object o = x;\ncamera { up = (0, 0, 0); }",
        "`up` is zero or parallel",
        2,
        15,
    );
    assert_err(
        "object o = x;\ncamera { fov = 180; }",
        "`fov` must be between 0 and 180",
        2,
        16,
    );
    assert_err(
        "object o = x;\ncamera { ortho = 0; }",
        "`ortho` (the view width) must be positive",
        2,
        18,
    );
    assert_err(
        "object o = x;\ncamera { fov = 30; ortho = 2; }",
        "either `fov` or `ortho`",
        2,
        20,
    );
    assert_err(
        "object o = x;\ncamera { eye = (x, 0, 1); }",
        "`eye` must be a constant",
        2,
        17,
    );
    assert_err(
        "object o = x;\ncamera { eye = (1, 2); }",
        "`eye` must have 3 components",
        2,
        16,
    );
    let e = assert_err(
        "object o = x;\ncamera { ey = (1, 2, 3); }",
        "unknown property `ey` in camera",
        2,
        10,
    );
    assert_eq!(e.help.as_deref(), Some("did you mean `eye`?"));
    assert_err(
        "object o = x;\nrender { size = (0, 10); }",
        "image sizes must be whole numbers",
        2,
        18,
    );
    assert_err(
        "object o = x;\nrender { size = (20000, 10); }",
        "image sizes must be whole numbers",
        2,
        18,
    );
    assert_err(
        "object o = x;\nrender { size = (10.5, 10); }",
        "image sizes must be whole numbers",
        2,
        18,
    );
    assert_err(
        "object o = x;\nbounds = (0, 0, 0) .. (1, 0, 1);",
        "empty bounds: the minimum y",
        2,
        10,
    );
    assert_err(
        "object o = x { color = (1, 0, -1); }",
        "`color` components must not be negative",
        1,
        24,
    );
    assert_err(
        "object o = x { color = (1, 0, 1e308*10); }",
        "must be finite",
        1,
        31,
    );
    assert_err(
        "object o = x;\nlight { color = (1, 1, 1); }",
        "a light needs a `position` or a `direction`",
        2,
        1,
    );
    assert_err(
        "object o = x;\nlight { direction = (0, 0, 0); }",
        "must not be zero",
        2,
        21,
    );
    assert_err(
        "object o = x;\nlight { position = (0, 0, 0); shadows = 1; }",
        "`shadows` must be `true` or `false`",
        2,
        41,
    );
    assert_err(
        "object o = sphere;",
        "`sphere` is a function, not a value",
        1,
        12,
    );
    assert_err(
        "let r = 1; object o = r(x);",
        "`r` is a value, not a function",
        1,
        23,
    );
}
