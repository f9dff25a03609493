//! The scene language end to end: parsing of every construct through
//! `load_scene_source`, point values of the lowered functions, every example
//! file, every diagnostic (message and position), `.vm` import, `import`
//! between scene files, and the limits on deep and long inputs, reading
//! files (UTF-8, size limit). One test binary; the topics are its modules.

mod errors;
mod expressions;
mod files;
mod functions;
mod imports;
mod input;
mod limits;
#[path = "../common/models.rs"]
mod models;

use ibeam::eval::Single;
use ibeam::eval::interp::Interpreter;
use ibeam::ir::{Function, Op};
use ibeam::lang::{LoadError, function_from_formula, load_scene, load_scene_source};
use ibeam::scene::{LightKind, Projection, Scene};
use std::path::{Path, PathBuf};

/// f(p) by the reference interpreter.
fn eval(f: &Function, p: [f64; 3]) -> f64 {
    Interpreter::new(f.clone()).point(p)
}

/// The scene of `src`, which must load.
fn scene(src: &str) -> Scene {
    load_scene_source("test.ib", src).unwrap_or_else(|e| panic!("{e}"))
}

/// The function of a formula, which must load.
fn formula(s: &str) -> Function {
    function_from_formula(s).unwrap_or_else(|e| panic!("{e}"))
}

/// The formula `s` at `p`.
fn at(s: &str, p: [f64; 3]) -> f64 {
    eval(&formula(s), p)
}

/// Equal up to a relative 1e-12.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

#[track_caller]
fn assert_close(a: f64, b: f64) {
    assert!(close(a, b), "{a} != {b}");
}

/// The load error of `src`, which must fail.
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

/// A point off every axis and plane of symmetry.
const P: [f64; 3] = [0.3, -0.7, 1.1];

/// The crate root.
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

/// Every `.ib` file of examples/, sorted.
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
        // An error inside an imported file names that file.
        assert!(e.file.starts_with("tests/diagnostics/"), "{e}");
        assert!(
            e.rendered
                .starts_with(&format!("{}:{}:{}: error: ", e.file, e.line, e.col))
        );
        let stem = f.file_name().unwrap().to_string_lossy().replace('.', "_");
        insta::assert_snapshot!(format!("diag_{stem}"), e.rendered);
    }
}
