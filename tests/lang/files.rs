//! Files: a missing file, every example, `.vm` import, the documented
//! example.

use super::*;

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

// ------------------------------------------------------------ examples

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

// ------------------------------------------------------------ .vm import

/// The scene of `.vm` model text.
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
    let (Some(prospero), Some(colonnade)) = (
        models::shared_model("prospero.vm"),
        models::shared_model("colonnade.vm"),
    ) else {
        return;
    };
    let s = load_scene(&prospero).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.objects[0].name, "prospero");
    assert_eq!(s.objects[0].function.uses_vars(), [true, true, false]);
    assert!(matches!(
        s.camera.projection,
        Projection::Orthographic { .. }
    ));
    assert!(s.objects[0].function.len() > 1000);
    let s = load_scene(&colonnade).unwrap_or_else(|e| panic!("{e}"));
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
