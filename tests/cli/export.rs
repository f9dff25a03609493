//! `ibeam export --vm`: the written model loads back (ours, and in the
//! format Fidget reads) with the same values as the scene's objects.

use super::{assert_fails, example, scratch};
use crate::common::ibeam;
use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::ir::random::Rng;
use ibeam::lang::load_scene;

fn value(f: &ibeam::ir::Function, p: [f64; 3]) -> f64 {
    Interpreter::new(f.clone()).point(p)
}

#[test]
fn exported_models_load_back_with_the_same_values() {
    let dir = scratch("export");
    let scene = load_scene(&example("shapes.ib")).unwrap();
    let all = dir.join("all.vm");
    let one = dir.join("one.vm");
    let o = ibeam(&[
        "export",
        "examples/shapes.ib",
        "--vm",
        all.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::common::stderr(&o));
    let o = ibeam(&[
        "export",
        "examples/shapes.ib",
        "--vm",
        one.to_str().unwrap(),
        "--object",
        "floor_tiles",
    ]);
    assert!(o.status.success(), "{}", crate::common::stderr(&o));
    let back_all = load_scene(&all).unwrap();
    let back_one = load_scene(&one).unwrap();
    let mut rng = Rng::new(3);
    for _ in 0..500 {
        let p = [0, 1, 2].map(|_| rng.range(-2.0, 2.0));
        let want_one = value(&scene.objects[1].function, p);
        let want_all = scene
            .objects
            .iter()
            .map(|o| value(&o.function, p))
            .fold(f64::INFINITY, f64::min);
        for (want, got) in [
            (want_one, value(&back_one.objects[0].function, p)),
            (want_all, value(&back_all.objects[0].function, p)),
        ] {
            assert!(
                (want - got).abs() <= 1e-12 * want.abs().max(1.0),
                "at {p:?}: {want} vs {got}"
            );
        }
    }
    // A render of the export draws what the scene draws.
    let png = dir.join("all.png");
    let o = ibeam(&[
        "render",
        all.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
        "--size",
        "32x32",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", crate::common::stderr(&o));
}

#[test]
fn export_errors_name_the_problem() {
    let dir = scratch("export-errors");
    let out = dir.join("x.vm");
    let o = ibeam(&[
        "export",
        "examples/shapes.ib",
        "--vm",
        out.to_str().unwrap(),
        "--object",
        "nope",
    ]);
    assert_fails(&o, &["no object named `nope`", "shapes, floor_tiles"]);
    assert!(!out.exists());
    let o = ibeam(&[
        "export",
        "examples/shapes.ib",
        "--vm",
        "/nonexistent-dir/x.vm",
    ]);
    assert_fails(&o, &["cannot write /nonexistent-dir/x.vm"]);
    let o = ibeam(&[
        "export",
        "examples/no-such-file.ib",
        "--vm",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
}
