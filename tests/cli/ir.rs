//! `ibeam ir` and `ibeam eval` end to end through the binary, and snapshots
//! of every example's IR after simplification.

use ibeam::ir::passes::simplify;
use ibeam::ir::print::print;
use std::path::{Path, PathBuf};

use crate::common::{ibeam, stderr, stdout};

/// Every `.ib` file of examples/, sorted.
fn examples() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("examples/ exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ib"))
        .collect();
    files.sort();
    files
}

#[test]
fn simplified_ir_snapshots() {
    for path in examples() {
        let scene = ibeam::lang::load_scene(&path).expect("example loads");
        let mut text = String::new();
        for object in &scene.objects {
            text.push_str(&format!("; object {}\n", object.name));
            text.push_str(&print(&simplify(&object.function)));
        }
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        insta::assert_snapshot!(format!("simplified_{stem}"), text);
    }
}

#[test]
fn ir_prints_simplified_ops() {
    let o = ibeam(&["ir", "examples/sphere.ib"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.starts_with("; object sphere\nv0 = var x\n"), "{text}");
    // x^2 + y^2 + z^2 is specialised to squares, never to multiplications.
    assert_eq!(text.matches(" = square ").count(), 3, "{text}");
    assert!(!text.contains(" = powi "), "{text}");
    assert!(
        text.trim_end()
            .lines()
            .last()
            .unwrap()
            .starts_with("return v")
    );
}

#[test]
fn ir_passes_shows_every_pass() {
    let o = ibeam(&["ir", "examples/tangle_cube.ib", "--passes"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("; before simplification\n"));
    for pass in ibeam::ir::passes::PASSES {
        assert!(
            text.contains(&format!("; after {}\n", pass.name)),
            "{}",
            pass.name
        );
    }
}

#[test]
fn ir_stats_counts_ops_and_compile_times() {
    let o = ibeam(&["ir", "examples/orthocircle.ib", "--stats"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let total = text
        .lines()
        .find(|l| l.starts_with("; total"))
        .expect("a total line");
    let counts: Vec<usize> = total
        .split_whitespace()
        .skip(2)
        .map(|n| n.parse().unwrap())
        .collect();
    assert_eq!(counts.len(), 2, "{total}");
    assert!(
        counts[1] <= counts[0],
        "simplification never grows: {total}"
    );
    for kind in ["point", "interval", "interval_grad"] {
        assert!(
            text.lines()
                .any(|l| l.starts_with(&format!("; jit compile {kind} "))),
            "{kind}: {text}"
        );
    }
}

#[test]
fn ir_clif_prints_each_evaluator() {
    let o = ibeam(&["ir", "examples/sphere.ib", "--clif"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("; evaluator: point"), "{text}");
    assert!(text.contains("; evaluator: interval"), "{text}");
    assert!(text.contains("function"), "{text}");
}

#[test]
fn ir_reads_fidget_models() {
    let Some(model) = crate::common::models::shared_model("colonnade.vm") else {
        return;
    };
    let o = ibeam(&["ir", model.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).lines().count() > 100);
}

/// Parses `NAME: f = V  grad = (A, B, C)`.
fn parse_at(line: &str) -> (f64, [f64; 3]) {
    let (_, rest) = line.split_once("f = ").expect("f = ");
    let (v, rest) = rest.split_once("  grad = (").expect("grad");
    let d: Vec<f64> = rest
        .trim_end_matches(')')
        .split(", ")
        .map(|s| s.parse().unwrap())
        .collect();
    (v.parse().unwrap(), [d[0], d[1], d[2]])
}

#[test]
fn eval_at_prints_value_and_gradient_with_negative_coordinates() {
    for eval in ["jit", "interp"] {
        let o = ibeam(&[
            "eval",
            "examples/sphere.ib",
            "--at",
            "-2,0,0",
            "--eval",
            eval,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let (v, d) = parse_at(stdout(&o).trim());
        // examples/sphere.ib is x² + y² + z² - 1.
        assert_eq!(v, 3.0);
        assert_eq!(d, [-4.0, 0.0, 0.0]);
    }
}

#[test]
fn eval_box_contains_the_range_and_jit_equals_interp() {
    let args = [
        "eval",
        "examples/torus.ib",
        "--box",
        "-1.5,-0.5,-0.25,0.25,-0.1,0.1",
    ];
    let jit = ibeam(&args);
    let interp = ibeam(&[&args[..], &["--eval", "interp"]].concat());
    assert!(jit.status.success(), "{}", stderr(&jit));
    assert_eq!(stdout(&jit), stdout(&interp));
    let text = stdout(&jit);
    let inner = text
        .split_once('[')
        .and_then(|(_, r)| r.split_once(']'))
        .expect("[lo, hi]")
        .0;
    let (lo, hi) = inner.split_once(", ").unwrap();
    let (lo, hi): (f64, f64) = (lo.parse().unwrap(), hi.parse().unwrap());
    // The box holds points inside the tube (f < 0) and outside it.
    assert!(lo < 0.0 && hi > 0.0, "{text}");
}

/// The `[lo, hi]` of `ibeam eval --box`'s output.
fn printed_interval(text: &str) -> (f64, f64) {
    let inner = text
        .split_once('[')
        .and_then(|(_, r)| r.split_once(']'))
        .expect("[lo, hi]")
        .0;
    let (lo, hi) = inner.split_once(", ").unwrap();
    (lo.parse().unwrap(), hi.parse().unwrap())
}

#[test]
fn eval_box_affine_enclosure_is_inside_the_interval_one() {
    // The Kummer quartic over a cube 0.01 wide, where intervals
    // overestimate (issue 40).
    let dir = std::env::temp_dir().join(format!("ibeam-affine-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("kummer.ib");
    std::fs::write(
        &file,
        "object k = (x^2 + y^2 + z^2 - 1.69)^2 - 3.1068702290076335*(1 - z - sqrt(2)*x)\
         *(1 - z + sqrt(2)*x)*(1 + z + sqrt(2)*y)*(1 + z - sqrt(2)*y);\n",
    )
    .unwrap();
    let b = "0.30,0.31,-0.52,-0.51,0.7,0.71";
    let run = |extra: &[&str]| {
        let o = ibeam(&[&["eval", file.to_str().unwrap(), "--box", b][..], extra].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        stdout(&o)
    };
    let default = run(&[]);
    assert_eq!(default, run(&["--enclosure", "interval"]));
    let affine = run(&["--enclosure", "affine"]);
    assert_eq!(affine, run(&["--enclosure", "affine", "--eval", "interp"]));
    let (il, ih) = printed_interval(&default);
    let (al, ah) = printed_interval(&affine);
    assert!(il <= al && ah <= ih, "{default} {affine}");
    assert!((ah - al) * 1.2 < ih - il, "{default} {affine}");
    // f at the box's corners (the function's own point values).
    for c in 0..8 {
        let p: Vec<String> = (0..3)
            .map(|k| {
                let s: Vec<&str> = b.split(',').collect();
                s[2 * k + (c >> k & 1)].to_string()
            })
            .collect();
        let o = ibeam(&["eval", file.to_str().unwrap(), "--at", &p.join(",")]);
        let text = stdout(&o);
        let v: f64 = text
            .split_once("f = ")
            .and_then(|(_, r)| r.split_whitespace().next())
            .unwrap()
            .parse()
            .unwrap();
        assert!(al <= v && v <= ah, "f = {v} at {p:?} outside {affine}");
    }
    let o = ibeam(&[
        "eval",
        file.to_str().unwrap(),
        "--box",
        b,
        "--enclosure",
        "taylor",
    ]);
    assert_eq!(o.status.code(), Some(2), "clap usage error");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bench_enclosure_prints_every_surface() {
    let o = ibeam(&["bench", "enclosure", "--boxes", "4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for name in ["kummer", "klein", "power_minus_expansion", "expansion"] {
        assert!(text.contains(&format!("{name} (4 boxes)")), "{text}");
    }
}

#[test]
fn eval_reports_bad_arguments() {
    let o = ibeam(&["eval", "examples/sphere.ib", "--at", "1,2"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("expected 3"), "{}", stderr(&o));
    let o = ibeam(&["eval", "examples/sphere.ib", "--box", "1,0,0,1,0,1"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("reversed"), "{}", stderr(&o));
    let o = ibeam(&["eval", "examples/sphere.ib"]);
    assert_eq!(o.status.code(), Some(2), "clap usage error");
}

#[test]
fn load_errors_have_position_and_caret() {
    let dir = std::env::temp_dir().join(format!("ibeam-ir-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("typo.ib");
    std::fs::write(&file, "object a = sphre(1);\n").unwrap();
    let o = ibeam(&["ir", file.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("typo.ib:1:12: error:"), "{err}");
    assert!(err.contains('^'), "{err}");
    assert!(err.contains("sphere"), "did-you-mean hint: {err}");
    let o = ibeam(&["ir", "no/such/file.ib"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no/such/file.ib"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The scene shown in the README loads and has one object.
#[test]
fn readme_scene_loads() {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md is readable");
    let start = readme
        .find("A scene:\n\n```\n")
        .expect("README shows a scene")
        + 14;
    let len = readme[start..].find("```").expect("the scene block ends");
    let scene = ibeam::lang::load_scene_source("README.md", &readme[start..start + len])
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.lights.len(), 1);
    assert!(scene.lights[0].shadows);
}
