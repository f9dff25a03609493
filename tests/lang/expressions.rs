//! Expressions, CSG, transforms, the prelude and scene items.

use super::*;

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
