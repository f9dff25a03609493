//! Limits on deep and long inputs, and random inputs never crash.

use super::*;

// ------------------------------------------------------------- limits

/// An object `open`ⁿ `inner` `close`ⁿ.
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
fn long_let_chains_load_and_evaluate() {
    // As SSA exporters write them: each let reads the one before.
    let mut src = String::from("let v0 = x * x + y * y + z * z - 1;\n");
    let n = 10_000;
    for i in 1..=n {
        src.push_str(&format!(
            "let v{i} = v{} + 0.0001 * sin(x * {});\n",
            i - 1,
            i % 7 + 1
        ));
    }
    src.push_str(&format!("object o = v{n};"));
    let scene = load_scene_source("chain.ib", &src).unwrap();
    let it = Interpreter::new(scene.objects[0].function.clone());
    let p = [0.5, 0.5, 0.5];
    let expected = (1..=n).fold(0.75 - 1.0, |v, i| {
        v + 0.0001 * (0.5 * f64::from(i % 7 + 1)).sin()
    });
    assert!(
        (it.point(p) - expected).abs() < 1e-9,
        "{} vs {expected}",
        it.point(p)
    );
}

#[test]
fn long_let_chains_still_refuse_recursion() {
    let mut src = String::from("let v0 = v100 + x;\n");
    for i in 1..=100 {
        src.push_str(&format!("let v{i} = v{} + 1;\n", i - 1));
    }
    src.push_str("object o = v100;");
    let e = err(&src);
    assert!(e.message.contains("recursive"), "{e}");
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

// ------------------------------------------------------------ robustness

/// Tokens and pieces of the language, for random token soup.
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

/// Random well-formed expressions, calls and operators nested.
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
