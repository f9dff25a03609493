//! The functions, shape operators and primitives added to the language,
//! and the `.vm` ops beyond arithmetic: values at points against Rust's
//! own functions, errors for bad constant arguments, and identities
//! between the operators (rotate about z is rotate_z, and so on).

use super::*;
use ibeam::interval::Interval;

#[test]
fn functions_match_rust_at_points() {
    for &v in &[-2.75f64, -1.5, -0.5, -0.0, 0.0, 0.25, 0.5, 0.9, 1.5, 3.0] {
        let p = [v, 0.4, -0.3];
        let cases: [(&str, f64); 14] = [
            ("tan(x)", v.tan()),
            ("atan(x)", v.atan()),
            ("sinh(x)", v.sinh()),
            ("cosh(x)", v.cosh()),
            ("tanh(x)", v.tanh()),
            ("floor(x)", v.floor()),
            ("ceil(x)", v.ceil()),
            ("round(x)", v.round()),
            ("fract(x)", v - v.floor()),
            ("mod(x, 0.75)", v.rem_euclid(0.75)),
            ("mod(x, -0.75)", v.rem_euclid(-0.75)),
            ("clamp(x, -1, 1)", v.clamp(-1.0, 1.0)),
            ("mix(x, y, 0.25)", v + (0.4 - v) * 0.25),
            ("sign(x)", if v == 0.0 { 0.0 } else { v.signum() }),
        ];
        for (f, want) in cases {
            assert_close(at(f, p), want);
        }
        if v.abs() <= 1.0 {
            assert_close(at("asin(x)", p), v.asin());
            assert_close(at("acos(x)", p), v.acos());
        } else {
            assert!(at("asin(x)", p).is_nan());
        }
        let t = ((v - -1.0) / 2.0f64).clamp(0.0, 1.0);
        assert_close(at("smoothstep(-1, 1, x)", p), t * t * (3.0 - 2.0 * t));
    }
    assert_err(
        "object a = smoothstep(1, 1, x) + sphere(1);",
        "smoothstep's edges are both 1",
        1,
        26,
    );
    // round: halves away from zero.
    assert_eq!(at("round(x)", [2.5, 0.0, 0.0]), 3.0);
    assert_eq!(at("round(x)", [-2.5, 0.0, 0.0]), -3.0);
}

#[test]
fn smooth_intersection_and_difference_bound_the_sharp_ones() {
    for i in 0..50 {
        let a = -1.0 + 0.04 * f64::from(i);
        let p = [a, 0.3 - 0.01 * f64::from(i), 0.0];
        let sharp = at("max(x, y)", p);
        let smooth = at("blend_intersect(x, y, 0.5)", p);
        assert!(smooth >= sharp && smooth <= sharp + 0.5 / 4.0 + 1e-15);
        let sharp_d = at("difference(x, y)", p);
        let smooth_d = at("blend_difference(x, y, 0.5)", p);
        assert!(smooth_d >= sharp_d && smooth_d <= sharp_d + 0.5 / 4.0 + 1e-15);
        if (p[0] - p[1]).abs() >= 0.5 {
            assert_eq!(smooth, sharp);
        }
    }
    assert_err(
        "object a = blend_intersect(x, y, 0);",
        "the blend radius must be positive",
        1,
        34,
    );
}

#[test]
fn shell_offset_and_mirrors() {
    let p = [0.3, -0.7, 1.1];
    assert_close(at("shell(sphere(1), 0.1)", p), (norm(p) - 1.0).abs() - 0.1);
    assert_close(at("offset(sphere(1), 0.1)", p), norm(p) - 1.1);
    let shifted = |q: [f64; 3]| norm([q[0] - 0.5, q[1], q[2]]) - 0.2;
    let f = "mirror_x(translate(sphere(0.2), 0.5, 0, 0))";
    assert_close(at(f, p), shifted([0.3, -0.7, 1.1]));
    assert_close(at(f, [-0.3, -0.7, 1.1]), shifted([0.3, -0.7, 1.1]));
    assert_close(
        at(
            "mirror_y(translate(sphere(0.2), 0, 0.5, 0))",
            [0.0, -0.5, 0.0],
        ),
        -0.2,
    );
    assert_close(
        at(
            "mirror_z(translate(sphere(0.2), 0, 0, 0.5))",
            [0.0, 0.0, -0.5],
        ),
        -0.2,
    );
}

fn norm(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

#[test]
fn repeat_is_periodic_and_zero_means_no_repetition() {
    let f = formula("repeat(sphere(0.2), 1, 0, 2)");
    let base = eval(&f, [0.1, 0.3, 0.2]);
    for (k, m) in [(3.0, 1.0), (-2.0, -1.0), (7.0, 4.0)] {
        let v = eval(&f, [0.1 + k, 0.3, 0.2 + 2.0 * m]);
        assert!((v - base).abs() < 1e-12, "{v} vs {base}");
    }
    // y does not repeat.
    assert!(eval(&f, [0.0, 5.0, 0.0]) > 4.0);
    assert_close(eval(&f, [0.0, 0.0, 0.0]), -0.2);
    assert_err(
        "object a = repeat(sphere(1), 1, -1, 0);",
        "the repetition period must be 0 or positive",
        1,
        33,
    );
}

#[test]
fn rotate_about_an_axis_agrees_with_the_axis_rotations() {
    let shape = "translate(box(0.3, 0.2, 0.1), 0.4, 0.1, 0.2)";
    let p = [0.3, -0.7, 1.1];
    for (axis, named) in [
        ("1, 0, 0", "rotate_x"),
        ("0, 2, 0", "rotate_y"),
        ("0, 0, 3", "rotate_z"),
    ] {
        for deg in [30.0, 90.0, -135.0] {
            let a = at(&format!("rotate({shape}, {axis}, {deg})"), p);
            let b = at(&format!("{named}({shape}, {deg})"), p);
            assert!((a - b).abs() < 1e-12, "{axis} {deg}: {a} vs {b}");
        }
    }
    // 120° about (1, 1, 1) cycles the axes: x → y → z → x.
    let f = "rotate(translate(sphere(0.1), 1, 0, 0), 1, 1, 1, 120)";
    assert!((at(f, [0.0, 1.0, 0.0]) - -0.1).abs() < 1e-9);
    // Huge components are scaled, not overflowed.
    let big = at(
        "rotate(translate(sphere(0.1), 1, 0, 0), 0, 0, 1e308, 90)",
        [0.0, 1.0, 0.0],
    );
    assert!((big - -0.1).abs() < 1e-9, "{big}");
    assert_err(
        "object a = rotate(sphere(1), 0, 0, 0, 30);",
        "the rotation axis must be a non-zero vector",
        1,
        30,
    );
}

#[test]
fn scale_xyz_stretches_and_stays_a_bound() {
    let f = formula("scale_xyz(sphere(1), 2, 1, 0.5)");
    // The ellipsoid's surface points are on its zero set.
    for p in [[2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.5]] {
        assert!(eval(&f, p).abs() < 1e-12, "{p:?}");
    }
    // A bound: never more than the distance to the surface point (2, 0, 0).
    let v = eval(&f, [3.0, 0.0, 0.0]);
    assert!(v > 0.0 && v <= 1.0 + 1e-12);
    assert_err(
        "object a = scale_xyz(sphere(1), 1, 0, 1);",
        "must be positive",
        1,
        36,
    );
}

#[test]
fn primitives_have_their_documented_shape() {
    // Cone: base disc radius 1 at y = 0, apex at y = 2.
    let cone = formula("cone(1, 2)");
    assert!(eval(&cone, [0.0, 1.0, 0.0]) < 0.0);
    assert!(eval(&cone, [0.0, 2.1, 0.0]) > 0.0);
    assert!(eval(&cone, [0.0, -0.1, 0.0]) > 0.0);
    assert!(eval(&cone, [0.55, 1.0, 0.0]) > 0.0);
    assert!(eval(&cone, [0.45, 1.0, 0.0]) < 0.0);
    assert!(eval(&cone, [1.0, 0.0, 0.0]).abs() < 1e-12);
    // Capped cylinder: radius 0.5, y in [-1, 1].
    let cyl = formula("capped_cylinder(0.5, 1)");
    assert_close(eval(&cyl, [0.0, 1.5, 0.0]), 0.5);
    assert_close(eval(&cyl, [0.8, 0.0, 0.0]), 0.3);
    assert!(eval(&cyl, [0.0, 0.9, 0.4]) < 0.0);
    // Rounded box: the exact distance, so corners are r-rounded.
    let rb = formula("rounded_box(1, 1, 1, 0.25)");
    assert_close(eval(&rb, [1.5, 0.0, 0.0]), 0.5);
    let c = 0.75 + 1.0 / 3f64.sqrt();
    assert_close(eval(&rb, [c, c, c]), 1.0 - 0.25);
    assert!(eval(&rb, [0.99, 0.99, 0.99]) > 0.0);
}

#[test]
fn new_functions_have_sound_intervals_over_boxes() {
    let fs = [
        "tan(x) - y",
        "asin(x) + acos(y)",
        "atan(x*y) + sinh(z) - cosh(x) + tanh(y)",
        "floor(3*x) + ceil(y) + round(z) + sign(x - y)",
        "fract(2*x) - mod(y, 0.3)",
        "smoothstep(-0.5, 0.5, x) + clamp(y, -0.2, 0.3) + mix(x, z, y)",
        "repeat(sphere(0.2), 0.5, 0.7, 0)",
        "blend_difference(box(0.5, 0.5, 0.5), sphere(0.6), 0.2)",
    ];
    for (k, s) in fs.iter().enumerate() {
        let f = formula(s);
        let e = Interpreter::new(f.clone());
        for i in 0..40 {
            let c = [0, 1, 2].map(|j| ((i * 7 + j * 13 + k) % 17) as f64 / 8.5 - 1.0);
            let w = 0.02 + 0.05 * (i % 5) as f64;
            let b = c.map(|c| Interval::new(c - w, c + w));
            let r = e.interval(b);
            for t in 0..27 {
                let q = [0, 1, 2].map(|j| {
                    let s = [0.0, 0.5, 1.0][(t / [1, 3, 9][j]) % 3];
                    b[j].lo + (b[j].hi - b[j].lo) * s
                });
                let v = e.point(q);
                assert!(
                    v.is_nan() || r.contains(v),
                    "{s}: f{q:?} = {v} not in {r:?}"
                );
            }
        }
    }
}

#[test]
fn bad_calls_name_the_function_and_arity() {
    assert_err(
        "object a = clamp(x, 1);",
        "`clamp` takes 3 arguments",
        1,
        12,
    );
    assert_err(
        "object a = rotate(sphere(1), 0, 0, 1);",
        "`rotate` takes 5 arguments",
        1,
        12,
    );
    assert_err(
        "object a = sphere(1) + tan(y, z);",
        "`tan` takes 1 argument",
        1,
        24,
    );
}

// ------------------------------------------------------------ .vm ops

/// The single object of a `.vm` model whose last lines are `tail`, with x,
/// y, z as `_x _y _z`.
fn vm_value(tail: &str, p: [f64; 3]) -> f64 {
    let text = format!("_x var-x\n_y var-y\n_z var-z\n_0 const 0\n_1 const 1\n{tail}");
    let s = load_scene_source("model.vm", &text).unwrap_or_else(|e| panic!("{e}"));
    eval(&s.objects[0].function, p)
}

#[test]
fn vm_logic_and_rounding_ops_mean_what_fidget_means() {
    for &(a, b) in &[
        (0.0f64, 2.0f64),
        (1.5, 2.0),
        (-3.0, 0.0),
        (2.0, 2.0),
        (-0.25, -4.0),
    ] {
        let p = [a, b, 0.0];
        let cmp = if a < b {
            -1.0
        } else if a > b {
            1.0
        } else {
            0.0
        };
        assert_eq!(vm_value("_r compare _x _y\n", p), cmp, "compare {a} {b}");
        assert_eq!(
            vm_value("_r and _x _y\n", p),
            if a == 0.0 { 0.0 } else { b },
            "and {a} {b}"
        );
        assert_eq!(
            vm_value("_r or _x _y\n", p),
            if a != 0.0 { a } else { b },
            "or {a} {b}"
        );
        assert_eq!(
            vm_value("_r not _x\n", p),
            if a == 0.0 { 1.0 } else { 0.0 },
            "not {a}"
        );
        if b != 0.0 {
            assert_eq!(
                vm_value("_r mod _x _y\n", p),
                a.rem_euclid(b),
                "mod {a} {b}"
            );
        }
        assert_eq!(vm_value("_r floor _x\n", p), a.floor());
        assert_eq!(vm_value("_r ceil _x\n", p), a.ceil());
        assert_eq!(vm_value("_r round _x\n", p), a.round());
        assert_close(vm_value("_r atan _x\n", p), a.atan());
        assert_close(vm_value("_r tan _x\n", p), a.tan());
    }
    let half = [0.5, 0.0, 0.0];
    assert_close(vm_value("_r asin _x\n", half), 0.5f64.asin());
    assert_close(vm_value("_r acos _x\n", half), 0.5f64.acos());
    // Fidget's if_nonzero_else(c, a, b) = or(and(c, a), and(not(c), b)).
    let ite = "_c sub _x _1\n_a and _c _y\n_n not _c\n_b and _n _z\n_r or _a _b\n";
    assert_eq!(vm_value(ite, [3.0, 5.0, 7.0]), 5.0);
    assert_eq!(vm_value(ite, [1.0, 5.0, 7.0]), 7.0);
}

#[test]
fn vm_random_ops_are_refused_with_their_line() {
    let e = load_scene_source("model.vm", "_0 var-x\n_1 rand _0\n").unwrap_err();
    assert!(e.message.contains("`rand` is not supported"), "{e}");
    assert_eq!((e.line, e.col), (2, 4));
}

// Every "E.g." example of docs/language.md loads as a formula, so the
// documentation cannot drift from the language.
#[test]
fn documented_examples_load() {
    let doc = std::fs::read_to_string(root().join("docs/language.md")).unwrap();
    let mut n = 0;
    for line in doc.lines() {
        let Some((_, after)) = line.split_once("E.g. ") else {
            continue;
        };
        for (i, span) in after.split('`').enumerate() {
            if i % 2 == 1 {
                function_from_formula(span).unwrap_or_else(|e| panic!("{span}: {e}"));
                n += 1;
            }
        }
    }
    assert!(n >= 12, "only {n} examples found");
}
