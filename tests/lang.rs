//! The scene language end to end: parsing of every construct through
//! `load_scene_source`, point values of the lowered functions, every example
//! file, every diagnostic (message and position), `.vm` import, and the
//! limits on deep and long inputs.

use ibeam::eval::Evaluator;
use ibeam::eval::interp::Interpreter;
use ibeam::ir::{Function, Op};
use ibeam::lang::{LoadError, function_from_formula, load_scene, load_scene_source};
use ibeam::scene::{LightKind, Projection, Scene};
use std::path::{Path, PathBuf};

/// f(p) by the reference interpreter.
fn eval(f: &Function, p: [f64; 3]) -> f64 {
    Interpreter::new(f.clone()).point(p)
}

fn scene(src: &str) -> Scene {
    load_scene_source("test.ib", src).unwrap_or_else(|e| panic!("{e}"))
}

fn formula(s: &str) -> Function {
    function_from_formula(s).unwrap_or_else(|e| panic!("{e}"))
}

fn at(s: &str, p: [f64; 3]) -> f64 {
    eval(&formula(s), p)
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

#[track_caller]
fn assert_close(a: f64, b: f64) {
    assert!(close(a, b), "{a} != {b}");
}

fn err(src: &str) -> LoadError {
    match load_scene_source("test.ib", src) {
        Ok(_) => panic!("expected an error for:\n{src}"),
        Err(e) => e,
    }
}

/// Checks message (substring), line and column of the error for `src`.
#[track_caller]
fn assert_err(src: &str, message: &str, line: usize, col: usize) -> LoadError {
    let e = err(src);
    assert!(
        e.message.contains(message),
        "message {:?} lacks {message:?}\n{e}",
        e.message
    );
    assert_eq!((e.line, e.col), (line, col), "position of\n{e}");
    let header = format!("test.ib:{line}:{col}: error: {}", e.message);
    assert!(e.rendered.starts_with(&header), "header of\n{}", e.rendered);
    e
}

const P: [f64; 3] = [0.3, -0.7, 1.1];

// ---------------------------------------------------------------- expressions

#[test]
fn number_literals() {
    assert_close(at("x + 1", P), 1.3);
    assert_close(at("x + 2.5", P), 2.8);
    assert_close(at("x + 1e-3", P), 0.301);
    assert_close(at("x + .5", P), 0.8);
    assert_close(at("x + 2.", P), 2.3);
    assert_close(at("x * 1E2", P), 30.0);
}

#[test]
fn arithmetic_and_precedence() {
    let (x, y, z) = (P[0], P[1], P[2]);
    assert_close(at("x + y * z", P), x + y * z);
    assert_close(at("(x + y) * z", P), (x + y) * z);
    assert_close(at("x - y - z", P), x - y - z);
    assert_close(at("x / y / z", P), x / y / z);
    assert_close(at("x - (y - z)", P), x - (y - z));
    assert_close(at("-x + y", P), -x + y);
    assert_close(at("x * -y", P), x * -y);
    assert_close(at("- - x", P), x);
}

#[test]
fn integer_powers() {
    let (x, y) = (P[0], P[1]);
    assert_close(at("x^2", P), x * x);
    assert_close(at("-x^2", P), -(x * x));
    assert_close(at("x^-2", P), 1.0 / (x * x));
    assert_close(at("x^(-2)", P), 1.0 / (x * x));
    assert_close(at("y^3", P), y * y * y);
    // right-associative: x^2^3 = x^8
    assert_close(at("x^2^3", P), x.powi(8));
    assert_close(at("(x^2)^3", P), x.powi(6));
    assert_close(at("x^0", P), 1.0);
    let f = formula("x^4");
    assert!(f.ops.iter().any(|o| matches!(o, Op::Powi(_, 4))));
    // exponent may be a constant expression
    assert!(
        formula("x^(1+1)")
            .ops
            .iter()
            .any(|o| matches!(o, Op::Powi(_, 2)))
    );
}

#[test]
fn functions() {
    let (x, y, z) = (P[0], P[1], P[2]);
    assert_close(at("sqrt(z)", P), z.sqrt());
    assert_close(at("abs(y)", P), y.abs());
    assert_close(at("exp(x)", P), x.exp());
    assert_close(at("ln(z)", P), z.ln());
    assert_close(at("sin(x) + cos(y)", P), x.sin() + y.cos());
    assert_close(at("min(x, y)", P), y);
    assert_close(at("max(x, y, z)", P), z);
    assert_close(at("min(z, x, y) + 0*x", P), y);
    assert_close(at("atan2(y, x)", P), y.atan2(x));
    assert_close(at("square(y)", P), y * y);
    assert_close(at("pow(z, 0.5)", P), z.sqrt());
    assert_close(at("pi + 0*x", P), std::f64::consts::PI);
    // pow with a constant integer exponent lowers to powi
    let f = formula("pow(x, 3)");
    assert!(f.ops.iter().any(|o| matches!(o, Op::Powi(_, 3))));
    assert_close(eval(&f, P), x.powi(3));
    let g = formula("pow(z, x)");
    assert!(!g.ops.iter().any(|o| matches!(o, Op::Powi(..))));
}

#[test]
fn let_and_fn_definitions() {
    let s = scene(
        "let r = 0.5; let two_r = 2 * r;\n\
         fn ring(a, b) = sqrt(x^2 + y^2) - a + b;\n\
         object o = ring(two_r, r) + 0*z;",
    );
    let (x, y) = (P[0], P[1]);
    assert_close(
        eval(&s.objects[0].function, P),
        (x * x + y * y).sqrt() - 1.0 + 0.5,
    );
    // definitions may come after their use
    let s = scene("object o = f(1); fn f(r) = x - r;");
    assert_close(eval(&s.objects[0].function, P), P[0] - 1.0);
    // a let that uses x is re-evaluated where it is used
    let s = scene("let d = x; object o = translate(d, 1, 0, 0);");
    assert_close(eval(&s.objects[0].function, P), P[0] - 1.0);
}

#[test]
fn formulas_may_be_constant_but_objects_may_not() {
    let f = formula("2 * pi");
    assert_eq!(f.len(), 1);
    assert_close(eval(&f, P), 2.0 * std::f64::consts::PI);
    let e = function_from_formula("x +").unwrap_err();
    assert_eq!((e.line, e.col, e.file.as_str()), (1, 4, "<formula>"));
    assert!(err("object o = 2 * pi;").message.contains("not a shape"));
}

#[test]
fn hash_consing_merges_repeats() {
    let f = formula("x^2 + x^2");
    let powis = f.ops.iter().filter(|o| matches!(o, Op::Powi(..))).count();
    assert_eq!(powis, 1);
    // a fn used twice with the same argument shares its body
    let f = formula("sphere(1) + sphere(1)");
    let sqrts = f.ops.iter().filter(|o| o.mnemonic() == "sqrt").count();
    assert_eq!(sqrts, 1);
}

// ------------------------------------------------------------------ CSG

#[test]
fn csg_operators() {
    let a = "sphere(1)";
    let b = "box(0.5, 0.5, 2)";
    for p in [P, [0.0, 0.0, 0.0], [0.9, 0.1, 0.0], [0.2, 0.2, 1.5]] {
        let fa = at(a, p);
        let fb = at(b, p);
        assert_close(at(&format!("union({a}, {b})"), p), fa.min(fb));
        assert_close(at(&format!("intersect({a}, {b})"), p), fa.max(fb));
        assert_close(at(&format!("difference({a}, {b})"), p), fa.max(-fb));
        assert_close(at(&format!("complement({a})"), p), -fa);
        assert_close(
            at(&format!("union({a}, {b}, x - 5)"), p),
            fa.min(fb).min(p[0] - 5.0),
        );
        let k: f64 = 0.3;
        let h = (k - (fa - fb).abs()).max(0.0) / k;
        let expect = fa.min(fb) - h * h * k / 4.0;
        assert_close(at(&format!("blend({a}, {b}, {k})"), p), expect);
        let bl = at(&format!("blend({a}, {b}, {k})"), p);
        assert!(bl <= fa.min(fb) && bl >= fa.min(fb) - k / 4.0);
    }
}

// ------------------------------------------------------------ transforms

#[test]
fn translate_moves_shapes() {
    let f = formula("translate(sphere(0.5), 1, 2, 3)");
    assert_close(eval(&f, [1.0, 2.0, 3.0]), -0.5);
    assert_close(eval(&f, [1.0, 2.0, 4.0]), 0.5);
    // a user fn with x inside is moved too
    let s = scene("fn blob(r) = x^2 + y^2 + z^2 - r^2; object o = translate(blob(1), 0, 0, 5);");
    assert_close(eval(&s.objects[0].function, [0.0, 0.0, 5.0]), -1.0);
}

#[test]
fn transforms_apply_to_parameters() {
    // by-name arguments: the transform inside `shift` moves its argument
    let s = scene("fn shift(s) = translate(s, 2, 0, 0); object o = shift(sphere(1));");
    assert_close(eval(&s.objects[0].function, [2.0, 0.0, 0.0]), -1.0);
}

#[test]
fn scale_keeps_distances() {
    let f = formula("scale(sphere(1), 2)");
    assert_close(eval(&f, [0.0, 0.0, 0.0]), -2.0);
    assert_close(eval(&f, [3.0, 0.0, 0.0]), 1.0);
}

#[test]
fn rotations() {
    // a ball at +x rotated 90° about z ends up at +y
    let f = formula("rotate_z(translate(sphere(0.25), 1, 0, 0), 90)");
    assert_close(eval(&f, [0.0, 1.0, 0.0]), -0.25);
    assert!(eval(&f, [1.0, 0.0, 0.0]) > 0.5);
    // about x: +y goes to +z
    let f = formula("rotate_x(translate(sphere(0.25), 0, 1, 0), 90)");
    assert_close(eval(&f, [0.0, 0.0, 1.0]), -0.25);
    // about y: +z goes to +x
    let f = formula("rotate_y(translate(sphere(0.25), 0, 0, 1), 90)");
    assert_close(eval(&f, [1.0, 0.0, 0.0]), -0.25);
    // a non-right angle
    let f = formula("rotate_z(translate(sphere(0.25), 1, 0, 0), 30)");
    let t = 30f64.to_radians();
    assert!((eval(&f, [t.cos(), t.sin(), 0.0]) + 0.25).abs() < 1e-12);
}

// --------------------------------------------------------------- prelude

#[test]
fn prelude_primitives() {
    assert_close(at("sphere(2)", [1.0, 2.0, 2.0]), 1.0);
    assert_close(at("box(1, 2, 3)", [0.0, 0.0, 0.0]), -1.0);
    assert_close(at("box(1, 2, 3)", [1.5, 0.0, 0.0]), 0.5);
    assert_close(at("torus(1, 0.25)", [1.0, 0.0, 0.0]), -0.25);
    assert_close(at("torus(1, 0.25)", [0.0, 0.0, 0.0]), 0.75);
    assert_close(at("cylinder(1)", [0.0, 100.0, 2.0]), 1.0);
    assert_close(at("plane(0, 2, 0, 1)", [5.0, 3.0, 5.0]), 2.5);
    assert_close(at("ellipsoid(2, 1, 1)", [2.0, 0.0, 0.0]), 0.0);
    assert_close(at("capsule(1, 0.5)", [0.0, 2.0, 0.0]), 0.5);
}

// ----------------------------------------------------------- scene items

#[test]
fn scene_items() {
    let s = scene(
        "object ball = sphere(1) { color = (1, 0.5, 0); }\n\
         object floor = y + 1;\n\
         camera { eye = (0, 1, 5); target = (0, 0, 0); up = (0, 1, 0); fov = 35; }\n\
         light { position = (1, 2, 3); color = (0.5, 0.5, 0.5); shadows = true; }\n\
         light { direction = (0, -1, 0); }\n\
         bounds = (-2, -1.5, -2) .. (2, 2, 2);\n\
         render { size = (640, 480); background = (0.1, 0.2, 0.3); }\n",
    );
    assert_eq!(s.objects.len(), 2);
    assert_eq!(s.objects[0].name, "ball");
    assert_eq!(s.objects[0].color, [1.0, 0.5, 0.0]);
    assert_eq!(s.objects[1].name, "floor");
    assert_eq!(s.objects[1].color, ibeam::lang::scene::DEFAULT_OBJECT_COLOR);
    assert_close(eval(&s.objects[1].function, [0.0, 0.0, 0.0]), 1.0);
    assert_eq!(s.camera.eye, [0.0, 1.0, 5.0]);
    assert_eq!(
        s.camera.projection,
        Projection::Perspective { fov_deg: 35.0 }
    );
    assert_eq!(s.lights.len(), 2);
    assert_eq!(s.lights[0].kind, LightKind::Point([1.0, 2.0, 3.0]));
    assert_eq!(s.lights[0].color, [0.5; 3]);
    assert!(s.lights[0].shadows);
    assert_eq!(s.lights[1].kind, LightKind::Directional([0.0, -1.0, 0.0]));
    assert!(!s.lights[1].shadows);
    assert_eq!(s.bounds.min, [-2.0, -1.5, -2.0]);
    assert_eq!(s.bounds.max, [2.0, 2.0, 2.0]);
    assert_eq!(s.render.size, (640, 480));
    assert_eq!(s.render.background, [0.1, 0.2, 0.3]);
}

#[test]
fn orthographic_camera_and_constant_expressions() {
    let s = scene("let d = 4; object o = sphere(1); camera { eye = (0, 0, d); ortho = 2 * 1.5; }");
    assert_eq!(s.camera.eye, [0.0, 0.0, 4.0]);
    assert_eq!(s.camera.projection, Projection::Orthographic { width: 3.0 });
}

#[test]
fn defaults() {
    let s = scene("object o = sphere(1);");
    assert_eq!(s.camera, ibeam::scene::Camera::default());
    assert_eq!(s.lights, vec![ibeam::scene::Light::default_light()]);
    assert_eq!(s.bounds, ibeam::scene::Bounds::default());
    assert_eq!(s.render, ibeam::scene::RenderSettings::default());
}

#[test]
fn comments_and_whitespace() {
    let s = scene("// a comment\nobject o = // trailing\n  sphere(1); // end");
    assert_eq!(s.objects.len(), 1);
}

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

// ------------------------------------------------------------- limits

fn nested(open: &str, inner: &str, close: &str, n: usize) -> String {
    let mut s = String::with_capacity(n * (open.len() + close.len()) + 32);
    s.push_str("object o = ");
    for _ in 0..n {
        s.push_str(open);
    }
    s.push_str(inner);
    for _ in 0..n {
        s.push_str(close);
    }
    s.push(';');
    s
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let n = 100_000;
    for (open, close) in [("sin(", ")"), ("-", ""), ("(1+", ")"), ("abs(1*", ")")] {
        let src = nested(open, "x", close, n);
        let e = err(&src);
        assert!(e.message.contains("nested too deeply"), "{e}");
        assert_eq!(e.line, 1);
    }
    let e = err(&nested("sin(", "x", ")", n));
    // the innermost 511 calls are accepted (x is level 1); the 512th fails
    assert_eq!(e.col, 12 + 4 * (n - 512));
    // powers nest to the right
    let mut src = String::from("object o = x");
    for _ in 0..n {
        src.push_str("^x");
    }
    src.push(';');
    assert!(err(&src).message.contains("nested too deeply"));
}

#[test]
fn deep_parentheses_are_fine() {
    // parentheses add no tree node, so any number of them is accepted
    let s = scene(&nested("(", "x", ")", 100_000));
    assert_eq!(eval(&s.objects[0].function, P), P[0]);
}

#[test]
fn moderate_nesting_is_accepted() {
    let s = scene(&nested("sin(", "x", ")", 400));
    let mut v = P[0];
    for _ in 0..400 {
        v = v.sin();
    }
    assert_close(eval(&s.objects[0].function, P), v);
}

#[test]
fn deep_call_chains_are_limited() {
    let mut src = String::from("fn f0(a) = a + x;\n");
    for i in 1..1000 {
        src.push_str(&format!("fn f{i}(a) = f{}(a) + 1;\n", i - 1));
    }
    src.push_str("object o = f999(1);");
    let e = err(&src);
    assert!(e.message.contains("definitions nested too deeply"), "{e}");
}

#[test]
fn exponential_inlining_is_cut_off() {
    // each level uses the one below twice with distinct call sites: the
    // inlined size doubles per level; lowering must stop, not hang
    let mut src = String::from("fn d0(a) = a + x;\n");
    for i in 1..60 {
        src.push_str(&format!("fn d{i}(a) = d{p}(a) * d{p}(a + 1);\n", p = i - 1));
    }
    src.push_str("object o = d59(y);");
    let start = std::time::Instant::now();
    let e = err(&src);
    assert!(e.message.contains("too large to lower"), "{e}");
    assert!(start.elapsed().as_secs() < 60);
}

#[test]
fn a_million_terms() {
    let n = 1_000_000;
    let mut src = String::with_capacity(n * 4 + 32);
    src.push_str("object o = x");
    for _ in 1..n {
        src.push_str(" + x");
    }
    src.push(';');
    let start = std::time::Instant::now();
    let s = scene(&src);
    assert_eq!(s.objects[0].function.len(), n);
    assert_close(eval(&s.objects[0].function, [1.0, 0.0, 0.0]), n as f64);
    let mut src = String::with_capacity(n * 8 + 32);
    src.push_str("object o = y");
    for i in 1..n {
        src.push_str(if i % 2 == 0 { " * x" } else { " / x" });
    }
    src.push(';');
    let s = scene(&src);
    assert_close(eval(&s.objects[0].function, [1.0, 2.0, 0.0]), 2.0);
    assert!(start.elapsed().as_secs() < 30, "took {:?}", start.elapsed());
}

#[test]
fn a_hundred_thousand_terms() {
    let n = 100_000;
    let mut src = String::from("object o = x");
    for _ in 1..n {
        src.push_str(" - y");
    }
    src.push(';');
    let s = scene(&src);
    assert_close(
        eval(&s.objects[0].function, [1.0, 1.0, 0.0]),
        1.0 - (n - 1) as f64,
    );
    let mut src = String::from("object o = min(x");
    for _ in 1..n {
        src.push_str(", y");
    }
    src.push_str(");");
    assert_eq!(scene(&src).objects.len(), 1);
}

// ------------------------------------------------------------ files

#[test]
fn missing_file() {
    let e = load_scene(Path::new("/nonexistent/dir/scene.ib")).unwrap_err();
    assert!(
        e.message
            .starts_with("cannot read `/nonexistent/dir/scene.ib`"),
        "{e}"
    );
    assert_eq!((e.line, e.col), (0, 0));
    assert!(
        e.rendered
            .starts_with("/nonexistent/dir/scene.ib: error: cannot read")
    );
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

// ------------------------------------------------------------ examples

/// Every surface of shared/surfaces.md has a scene, plus the CSG scene.
const EXAMPLES: &[&str] = &[
    "orthocircle",
    "orthocircle_thin",
    "tangle_cube",
    "torus",
    "sphere",
    "steiner",
    "barth_sextic",
    "mitchell",
    "blobby",
    "metaballs",
    "drop",
    "double_sphere",
    "heart",
    "csg",
];

fn example_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("examples"))
        .expect("examples/ exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ib"))
        .collect();
    files.sort();
    files
}

#[test]
fn every_example_loads() {
    let files = example_files();
    for name in EXAMPLES {
        assert!(
            files
                .iter()
                .any(|f| f.file_stem().is_some_and(|s| s == *name)),
            "examples/{name}.ib is missing"
        );
    }
    for f in &files {
        let s = load_scene(f).unwrap_or_else(|e| panic!("{e}"));
        assert!(!s.objects.is_empty());
        for o in &s.objects {
            ibeam::ir::validate::validate(&o.function).unwrap_or_else(|e| panic!("{e}"));
        }
        assert!(
            s.lights.iter().any(|l| l.shadows),
            "{} has no shadowed light",
            f.display()
        );
    }
}

/// The bounds frame each surface: the camera looks from outside them at a
/// point inside, the function is negative somewhere inside, and (for bounded surfaces)
/// never negative on the boundary.
#[test]
fn example_bounds_enclose_the_surface() {
    for f in example_files() {
        let stem = f.file_stem().unwrap().to_string_lossy().into_owned();
        let s = load_scene(&f).unwrap_or_else(|e| panic!("{e}"));
        let (lo, hi) = (s.bounds.min, s.bounds.max);
        for i in 0..3 {
            assert!(
                lo[i] <= s.camera.target[i] && s.camera.target[i] <= hi[i],
                "{stem}: target"
            );
        }
        let eye = s.camera.eye;
        assert!(
            !(0..3).all(|i| lo[i] <= eye[i] && eye[i] <= hi[i]),
            "{stem}: eye inside the bounds"
        );
        let n = 24;
        let lerp = |i: usize, t: usize| lo[i] + (hi[i] - lo[i]) * t as f64 / n as f64;
        for o in &s.objects {
            let mut min_inside = f64::INFINITY;
            for a in 0..=n {
                for b in 0..=n {
                    for c in 0..=n {
                        let v = eval(&o.function, [lerp(0, a), lerp(1, b), lerp(2, c)]);
                        min_inside = min_inside.min(v);
                    }
                }
            }
            if stem == "double_sphere" {
                assert!((0.0..0.05).contains(&min_inside), "{stem}: {min_inside}");
            } else {
                assert!(
                    min_inside < 0.0,
                    "{stem}/{}: nothing inside the bounds",
                    o.name
                );
            }
            if stem == "csg" {
                continue; // the ground plane is cut by the bounds on purpose
            }
            for axis in 0..3 {
                for side in [lo[axis], hi[axis]] {
                    for a in 0..=n {
                        for b in 0..=n {
                            let mut p = [0.0; 3];
                            p[axis] = side;
                            p[(axis + 1) % 3] = lerp((axis + 1) % 3, a);
                            p[(axis + 2) % 3] = lerp((axis + 2) % 3, b);
                            let v = eval(&o.function, p);
                            assert!(
                                v >= 0.0,
                                "{stem}: surface crosses the bounds at {p:?} ({v})"
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn example_ir_snapshots() {
    for f in example_files() {
        let stem = f.file_stem().unwrap().to_string_lossy().into_owned();
        let s = load_scene(&f).unwrap_or_else(|e| panic!("{e}"));
        let mut text = String::new();
        for o in &s.objects {
            text.push_str(&format!("# object {}\n", o.name));
            text.push_str(&ibeam::ir::print::print(&o.function));
        }
        insta::assert_snapshot!(format!("ir_{stem}"), text);
    }
}

/// One snapshot of the rendered diagnostic per file in tests/diagnostics.
#[test]
fn diagnostic_snapshots() {
    let dir = root().join("tests/diagnostics");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/diagnostics exists")
        .map(|e| e.expect("readable entry").path())
        .collect();
    files.sort();
    assert!(files.len() >= 10);
    for f in files {
        let name = format!(
            "tests/diagnostics/{}",
            f.file_name().unwrap().to_string_lossy()
        );
        let text = std::fs::read_to_string(&f).expect("readable");
        let e = match load_scene_source(&name, &text) {
            Ok(_) => panic!("{name} loads without error"),
            Err(e) => e,
        };
        assert!(
            e.rendered
                .starts_with(&format!("{name}:{}:{}: error: ", e.line, e.col))
        );
        let stem = f.file_name().unwrap().to_string_lossy().replace('.', "_");
        insta::assert_snapshot!(format!("diag_{stem}"), e.rendered);
    }
}

// ------------------------------------------------------------ .vm import

fn vm(text: &str) -> Result<Scene, LoadError> {
    load_scene_source("model.vm", text)
}

#[test]
fn vm_every_op() {
    let text = "# every op\n\
        _0 var-x\n_1 var-y\n_2 var-z\n_3 const 0.5\n\
        _4 neg _0\n_5 abs _4\n_6 recip _2\n_7 sqrt _2\n_8 square _1\n\
        _9 exp _3\n_a ln _2\n_b sin _0\n_c cos _1\n\
        _d add _5 _6\n_e sub _d _7\n_f mul _e _8\n_10 div _f _9\n\
        _11 min _10 _a\n_12 max _11 _b\n_13 atan2 _12 _c\n";
    let s = vm(text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.objects.len(), 1);
    assert_eq!(s.objects[0].name, "model");
    let [x, y, z] = P;
    let v = ((((x.abs() + 1.0 / z) - z.sqrt()) * (y * y)) / 0.5f64.exp()).min(z.ln());
    let expect = v.max(x.sin()).atan2(y.cos());
    assert_close(eval(&s.objects[0].function, P), expect);
    // 3D model: perspective default
    assert!(matches!(
        s.camera.projection,
        Projection::Perspective { .. }
    ));
}

#[test]
fn vm_2d_model_gets_a_top_down_orthographic_view() {
    let s = vm("_0 var-x\n_1 var-y\n_2 square _0\n_3 square _1\n_4 add _2 _3\n_5 const 0.25\n_6 sub _4 _5\n")
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.camera.projection, Projection::Orthographic { width: 2.0 });
    assert!(s.camera.eye[2] > s.camera.target[2]);
    assert_eq!(s.bounds.min, [-1.0; 3]);
    assert_eq!(s.bounds.max, [1.0; 3]);
    assert_close(eval(&s.objects[0].function, [0.0, 0.0, 0.0]), -0.25);
}

#[test]
fn vm_malformed_lines() {
    let e = vm("_0 var-x\n_1 foo _0\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("unknown op `foo`", 2, 4)
    );
    let e = vm("_0 var-x\n_1 ad _0 _0\n").unwrap_err();
    assert_eq!(e.help.as_deref(), Some("did you mean `add`?"));
    let e = vm("_0 var-x\n_1 add _0 _9\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("`_9` is not defined before this line", 2, 11)
    );
    let e = vm("_0 var-x\n_1 add _0\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("`add` takes 2 arguments, but 1 was given", 2, 4)
    );
    let e = vm("_0 var-x\n_1 neg _0 _0\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("`neg` takes 1 argument, but 2 were given", 2, 11)
    );
    let e = vm("_0 const 1.2.3\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("bad number literal `1.2.3`", 1, 10)
    );
    let e = vm("_0 var-x\n  _0 var-y\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("`_0` is defined twice", 2, 3)
    );
    let e = vm("# nothing\n\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("the file has no ops", 1, 1)
    );
    let e = vm("_0 var-x\n_1\n").unwrap_err();
    assert_eq!(
        (e.message.as_str(), e.line, e.col),
        ("`_1` has no op", 2, 1)
    );
    let e = vm("_0 const 2\n").unwrap_err();
    assert!(e.message.contains("not a shape"));
    assert!(e.rendered.starts_with("model.vm:"));
}

#[test]
fn vm_benchmark_models() {
    let dir = root().join("../shared/models");
    if !dir.join("prospero.vm").exists() {
        eprintln!("skipped: {} is not present", dir.display());
        return;
    }
    let s = load_scene(&dir.join("prospero.vm")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.objects[0].name, "prospero");
    assert_eq!(s.objects[0].function.uses_vars(), [true, true, false]);
    assert!(matches!(
        s.camera.projection,
        Projection::Orthographic { .. }
    ));
    assert!(s.objects[0].function.len() > 1000);
    let s = load_scene(&dir.join("colonnade.vm")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.objects[0].function.uses_vars(), [true, true, true]);
    assert!(matches!(
        s.camera.projection,
        Projection::Perspective { .. }
    ));
}

/// The example at the top of docs/language.md loads.
#[test]
fn documented_example_loads() {
    let doc = std::fs::read_to_string(root().join("docs/language.md")).expect("docs exist");
    let start = doc.find("```text\n").expect("an example block") + 8;
    let len = doc[start..].find("```").expect("closed block");
    let s = scene(&doc[start..start + len]);
    assert_eq!(s.objects.len(), 2);
    assert!(s.lights[0].shadows);
}

// ------------------------------------------------------------ robustness

const FRAGMENTS: &[&str] = &[
    "object",
    "o",
    "=",
    "x",
    "y",
    "z",
    "1",
    "2.5",
    "(",
    ")",
    ",",
    ";",
    "{",
    "}",
    "+",
    "-",
    "*",
    "/",
    "^",
    "sphere",
    "min",
    "blend",
    "translate",
    "rotate_z",
    "scale",
    "let",
    "fn",
    "f",
    "a",
    "camera",
    "light",
    "bounds",
    "..",
    "render",
    "eye",
    "fov",
    "color",
    "true",
    "0",
    "1e",
    "@",
    "// c\n",
    "\n",
    "pow",
    "-1",
    "0.5",
];

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(300))]

    /// Any token soup loads or fails with a positioned diagnostic; the
    /// loader never panics.
    #[test]
    fn token_soup_never_panics(picks in proptest::collection::vec(0..FRAGMENTS.len(), 0..40)) {
        let src: Vec<&str> = picks.iter().map(|&i| FRAGMENTS[i]).collect();
        let src = src.join(" ");
        if let Err(e) = load_scene_source("soup.ib", &src) {
            proptest::prop_assert!(!e.message.contains("internal error"), "{}", e);
            proptest::prop_assert!(e.line >= 1 && e.col >= 1, "{}", e);
            proptest::prop_assert!(e.rendered.starts_with("soup.ib:") || e.rendered.starts_with("prelude.ib:"));
        }
    }

    /// Random (mostly well-formed) expression trees over every built-in,
    /// with right and wrong arities, load or fail with a diagnostic; the
    /// loader never panics.
    #[test]
    fn random_expressions_never_panic(e in expr_strategy()) {
        let src = format!("fn g(a, b) = a * x - b;\nlet k = 2;\nobject o = {e};");
        if let Err(err) = load_scene_source("rand.ib", &src) {
            proptest::prop_assert!(!err.message.contains("internal error"), "{}", err);
            proptest::prop_assert!(err.line >= 1 && err.col >= 1, "{}", err);
        }
    }
}

fn expr_strategy() -> impl proptest::strategy::Strategy<Value = String> {
    use proptest::prelude::*;
    let leaf = prop_oneof![
        Just("x".to_string()),
        Just("y".to_string()),
        Just("z".to_string()),
        Just("k".to_string()),
        Just("q".to_string()),
        (-3i32..4).prop_map(|v| v.to_string()),
        Just("0.5".to_string()),
    ];
    leaf.prop_recursive(5, 40, 4, |inner| {
        let names = [
            "sqrt",
            "abs",
            "exp",
            "ln",
            "sin",
            "cos",
            "square",
            "min",
            "max",
            "pow",
            "atan2",
            "union",
            "intersect",
            "difference",
            "complement",
            "blend",
            "translate",
            "scale",
            "rotate_x",
            "rotate_y",
            "rotate_z",
            "sphere",
            "box",
            "torus",
            "plane",
            "g",
            "h",
        ];
        prop_oneof![
            (
                0..names.len(),
                proptest::collection::vec(inner.clone(), 0..5)
            )
                .prop_map(move |(i, args)| format!(
                    "{}({})",
                    names[i],
                    args.join(", ")
                )),
            (inner.clone(), 0..5usize, inner.clone())
                .prop_map(|(a, op, b)| format!("({a} {} {b})", ["+", "-", "*", "/", "^"][op])),
            inner.prop_map(|a| format!("-{a}")),
        ]
    })
}

#[test]
fn nested_calls_of_one_function_are_not_recursion() {
    let s = scene("fn f(a) = a + 1;\nobject o = f(f(f(x)));");
    assert_close(eval(&s.objects[0].function, P), P[0] + 3.0);
    let s = scene("fn f(a) = translate(a, 1, 0, 0);\nobject o = f(f(sphere(0.5)));");
    assert_close(eval(&s.objects[0].function, [2.0, 0.0, 0.0]), -0.5);
    // but a definition used inside its own argument is
    assert_err(
        "fn f(a) = a;\nfn g(b) = f(g(b));\nobject o = g(x);",
        "recursive use of `g`",
        2,
        13,
    );
}

#[test]
fn deep_inlining_is_limited_without_overflow() {
    // each body is 200 levels deep and calls the previous one at the
    // bottom: 100 of them inline to 20,000 levels
    let mut src = String::from("fn f0(a) = a + x;\n");
    for i in 1..100 {
        src.push_str(&format!(
            "fn f{i}(a) = {}f{}(a){};\n",
            "sin(".repeat(200),
            i - 1,
            ")".repeat(200)
        ));
    }
    src.push_str("object o = f99(y);");
    let e = err(&src);
    assert!(e.message.contains("nested too deeply"), "{e}");
    // 40 of them (8,000 levels) are fine
    let mut src = String::from("fn f0(a) = a + x;\n");
    for i in 1..40 {
        src.push_str(&format!(
            "fn f{i}(a) = {}f{}(a){};\n",
            "sin(".repeat(200),
            i - 1,
            ")".repeat(200)
        ));
    }
    src.push_str("object o = f39(y);");
    let s = scene(&src);
    let mut v = P[1] + P[0];
    for _ in 0..39 * 200 {
        v = v.sin();
    }
    assert_close(eval(&s.objects[0].function, P), v);
}
