//! End-to-end tests of the `ibeam` binary: `ibeam render` on the examples
//! writes PNGs, and every load or argument error exits with a message on
//! stderr and a non-zero code, never a panic (exit code 101); `ibeam ir`
//! and `ibeam eval` in [`ir`]; `ibeam serve` over HTTP in [`serve`]; output formats in [`formats`]; camera,
//! shadow and progress flags in [`view`]. One test binary.

#[path = "../common/mod.rs"]
mod common;
mod cpu;
mod export;
mod formats;
mod ir;
mod serve;
mod view;
mod watch;

use common::{ibeam, stderr};
use std::path::{Path, PathBuf};
use std::process::Output;

/// The evaluator flag every render here uses (one place, so the JIT
/// variants can be added beside it).
const EVAL: &str = "interp";

/// A scratch directory of its own for each test.
fn scratch(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ibeam-cli-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The path of examples/`name`.
fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name)
}

/// Renders `scene` to `out` with the usual test flags plus `extra`.
fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    render_by(EVAL, scene, out, extra)
}

/// [`render`] with the evaluator `eval`.
fn render_by(eval: &str, scene: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--eval",
        eval,
        "--quiet",
    ];
    args.extend_from_slice(extra);
    ibeam(&args)
}

/// Asserts a failed run: exit code 1 and every `needle` on stderr.
fn assert_fails(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "stderr:\n{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in stderr:\n{err}");
    }
}

#[test]
fn renders_examples_to_png() {
    let dir = scratch("examples");
    for (name, size) in [
        ("sphere.ib", "24x24"),
        ("csg.ib", "32x24"),
        ("torus.ib", "24x20"),
        ("double_sphere.ib", "24x24"),
    ] {
        let png = dir.join(name.replace(".ib", ".png"));
        let o = render(&example(name), &png, &["--size", size]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        let img = image::open(&png).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (w, h) = size.split_once('x').unwrap();
        assert_eq!(
            (img.width(), img.height()),
            (w.parse().unwrap(), h.parse().unwrap())
        );
        // Something was drawn: not every pixel is the background.
        let rgb = img.to_rgb8();
        let first = *rgb.get_pixel(0, 0);
        assert!(rgb.pixels().any(|p| *p != first), "{name}: blank image");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn auxiliary_outputs_and_stats() {
    let dir = scratch("aux");
    let (png, depth, stats) = (dir.join("a.png"), dir.join("d.png"), dir.join("s.json"));
    let o = render(
        &example("sphere.ib"),
        &png,
        &[
            "--size",
            "24x24",
            "--depth",
            depth.to_str().unwrap(),
            "--stats-json",
            stats.to_str().unwrap(),
            "--method",
            "pixel",
            "--threads",
            "1",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(image::open(&depth).unwrap().width(), 24);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(json.is_object());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compile_waits_are_reported_apart_from_the_render_time() {
    let dir = scratch("waits");
    let stats = dir.join("s.json");
    let args = ["--size", "24x24", "--threads", "1", "--stats-json"];
    let args = [&args[..], &[stats.to_str().unwrap()]].concat();
    let o = render_by("jit", &example("torus.ib"), &dir.join("t.png"), &args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    // The derivative kinds of a short function compile at their first
    // use, on the thread that asks, which waits: reported, and a part of
    // what compiled.
    let ms = |key: &str| json[key].as_f64().unwrap_or_else(|| panic!("{key}"));
    assert!(ms("compile_wait_ms") > 0.0, "{json}");
    assert!(ms("compile_wait_ms") <= ms("compile_ms"), "{json}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn enclosure_flag_chooses_the_forms_counted_in_the_stats() {
    let dir = scratch("enclosure");
    let tries = |choice: &str| {
        let stats = dir.join(format!("{choice}.json"));
        let args = ["--size", "24x24", "--threads", "1", "--enclosure", choice];
        let mut args: Vec<&str> = args.to_vec();
        args.extend(["--stats-json", stats.to_str().unwrap()]);
        let o = render(&example("steiner.ib"), &dir.join("e.png"), &args);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let find = |v: &serde_json::Value| -> Option<u64> {
            v.as_object()?
                .values()
                .find_map(|g| g.get("affine_tries").and_then(serde_json::Value::as_u64))
                .or_else(|| v.get("affine_tries")?.as_u64())
        };
        find(&json).expect("affine_tries in the stats")
    };
    assert_eq!(tries("interval"), 0);
    assert!(tries("affine") > 0);
    let o = render(
        &example("steiner.ib"),
        &dir.join("e.png"),
        &["--enclosure", "taylor"],
    );
    assert_ne!(o.status.code(), Some(0));
    assert!(stderr(&o).contains("taylor"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn syntax_error_points_at_file_line_and_column() {
    let dir = scratch("syntax");
    let scene = dir.join("bad.ib");
    std::fs::write(&scene, "// a comment\nobject s = x^2 + * y;\n").unwrap();
    let o = render(&scene, &dir.join("x.png"), &["--size", "8x8"]);
    let loc = format!("{}:2:", scene.display());
    assert_fails(&o, &[&loc, "error", "^"]);
    // Nothing is left behind when the render fails.
    assert!(!dir.join("x.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unknown_name_suggests_the_closest() {
    let dir = scratch("unknown");
    let scene = dir.join("typo.ib");
    std::fs::write(&scene, "object ball = sphre(1);\n").unwrap();
    let o = render(&scene, &dir.join("x.png"), &["--size", "8x8"]);
    let loc = format!("{}:1:15", scene.display());
    assert_fails(&o, &[&loc, "sphre", "did you mean `sphere`"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_scene_file() {
    let dir = scratch("missing");
    let o = render(
        &dir.join("no-such-scene.ib"),
        &dir.join("x.png"),
        &["--size", "8x8"],
    );
    assert_fails(&o, &["cannot read", "no-such-scene.ib"]);
    assert!(!dir.join("x.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unwritable_output_path() {
    let o = render(
        &example("sphere.ib"),
        Path::new("/nonexistent/dir/x.png"),
        &["--size", "8x8"],
    );
    assert_fails(&o, &["cannot write", "/nonexistent/dir/x.png"]);
}

#[test]
fn bad_sizes_are_usage_errors() {
    let dir = scratch("sizes");
    for size in ["0x0", "20000x10", "10", "axb"] {
        let o = render(&example("sphere.ib"), &dir.join("x.png"), &["--size", size]);
        let err = stderr(&o);
        // clap's usage errors exit with 2.
        assert_eq!(o.status.code(), Some(2), "{size}: {err}");
        assert!(err.contains("--size"), "{size}: {err}");
        assert!(!dir.join("x.png").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn scene_without_objects() {
    let dir = scratch("empty");
    let scene = dir.join("empty.ib");
    std::fs::write(&scene, "camera { eye = (0, 0, 5); }\n").unwrap();
    let o = render(&scene, &dir.join("x.png"), &["--size", "8x8"]);
    assert_fails(&o, &["no object"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn vm_model_with_errors_reports_its_line() {
    let dir = scratch("vm");
    let scene = dir.join("bad.vm");
    std::fs::write(&scene, "_0 var-x\n_1 frobnicate _0\n").unwrap();
    let o = render(&scene, &dir.join("x.png"), &["--size", "8x8"]);
    let loc = format!("{}:2:", scene.display());
    assert_fails(&o, &[&loc, "frobnicate"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The default evaluator (the JIT) and `--eval interp` draw the same
/// pixels: point and interval values agree bit for bit; only gradient
/// rounding may differ, which moves a shaded colour by at most a step.
#[test]
fn jit_and_interp_renders_agree() {
    let dir = scratch("jit-vs-interp");
    for name in ["csg.ib", "orthocircle_thin.ib"] {
        let mut stats = Vec::new();
        let mut images = Vec::new();
        for eval in ["jit", "interp"] {
            let png = dir.join(format!("{name}-{eval}.png"));
            let json = dir.join(format!("{name}-{eval}.json"));
            let o = ibeam(&[
                "render",
                example(name).to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
                "--size",
                "48x40",
                "--eval",
                eval,
                "--quiet",
                "--stats-json",
                json.to_str().unwrap(),
            ]);
            assert!(o.status.success(), "{name} {eval}: {}", stderr(&o));
            let v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
            stats.push(v["pixels_hit"].as_u64().unwrap());
            images.push(image::open(&png).unwrap().to_rgb8());
        }
        assert_eq!(stats[0], stats[1], "{name}: pixels hit");
        assert!(stats[0] > 0, "{name}: something is drawn");
        let worst = images[0]
            .as_raw()
            .iter()
            .zip(images[1].as_raw())
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        assert!(worst <= 2, "{name}: colours differ by {worst}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn object_undefined_everywhere_is_an_error() {
    let dir = scratch("undefined");
    // A plane with a zero normal divides by zero at every point; a square
    // root of a negative constant part is undefined everywhere too.
    for (name, body) in [
        ("plane", "plane(0, 0, 0, 1)"),
        ("root", "sqrt(-1 - x^2) - 1"),
    ] {
        let scene = dir.join(format!("{name}.ib"));
        std::fs::write(&scene, format!("object {name} = {body};\n")).unwrap();
        let out = dir.join(format!("{name}.png"));
        let o = render(&scene, &out, &["--size", "8x8"]);
        assert_fails(&o, &[&format!("object `{name}`"), "undefined everywhere"]);
        assert!(!out.exists(), "{name}: no image is written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn non_utf8_scene_names_the_byte_offset_and_position() {
    let dir = scratch("utf8");
    let scene = dir.join("latin1.ib");
    // 0xB0 is Latin-1 '°': byte offset 25, line 2, column 13.
    std::fs::write(&scene, b"// a comment\nlet a = 90; \xb0\n").unwrap();
    let o = render(&scene, &dir.join("x.png"), &["--size", "8x8"]);
    let loc = format!("{}:2:13: error: file is not valid UTF-8", scene.display());
    assert_fails(&o, &[&loc, "invalid byte 0xB0 at byte offset 25", "^"]);
    assert!(!dir.join("x.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// An endless device reports no length; the read stops past the limit, so
/// this is quick and bounded in memory instead of hanging.
#[cfg(unix)]
#[test]
fn endless_input_is_refused_by_size() {
    let dir = scratch("zero");
    let t = std::time::Instant::now();
    let o = render(
        Path::new("/dev/zero"),
        &dir.join("x.png"),
        &["--size", "8x8"],
    );
    assert_fails(
        &o,
        &[
            "/dev/zero: error: `/dev/zero` is too large",
            "limited to 268435456 bytes (256 MiB)",
        ],
    );
    assert!(t.elapsed().as_secs() < 20, "took {:?}", t.elapsed());
    assert!(!dir.join("x.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `ibeam args…`, killing it and failing if it takes longer than
/// `limit` (a hang must fail the test, not hang the suite); returns its
/// output and wall time. Never a panic: exit code 101 or "panicked at"
/// on stderr fails.
fn ibeam_within(args: &[&str], limit: std::time::Duration) -> (Output, std::time::Duration) {
    use std::process::{Command, Stdio};
    let start = std::time::Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_ibeam"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run ibeam");
    while child.try_wait().expect("wait for ibeam").is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("ibeam {args:?} still running after {limit:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let took = start.elapsed();
    let o = child.wait_with_output().expect("ibeam output");
    let err = stderr(&o);
    assert_ne!(
        o.status.code(),
        Some(101),
        "ibeam {args:?} panicked:\n{err}"
    );
    assert!(!err.contains("panicked at"), "ibeam {args:?}:\n{err}");
    (o, took)
}

#[test]
fn adversarial_scenes_render_at_64_or_fail_with_a_message_in_time() {
    // The scenes of tests/stability/adversarial.rs through the binary:
    // each either renders a 64×64 PNG (exit 0) or exits 1 with the error
    // named, within 20 s (generous: release takes well under a second,
    // the ci-debug profile and a loaded machine more), by beam, pixel and
    // beam with IAA, on the JIT the CLI uses by default.
    let dir = scratch("adversarial");
    let scene = |object: &str, half: f64| {
        let e = [2.0, 1.5, 3.5].map(|c: f64| c * half / 1.2);
        format!(
            "object s = {object};\n\
             camera {{ eye = ({:e}, {:e}, {:e}); target = (0, 0, 0); up = (0, 1, 0); fov = 35; }}\n\
             bounds = ({:e}, {:e}, {:e}) .. ({half:e}, {half:e}, {half:e});\n",
            e[0], e[1], e[2], -half, -half, -half
        )
    };
    // (file, scene text, what stderr must hold if the run fails; None
    // where it must render).
    let cases = [
        ("sin", scene("sin(1e300*x) + y*y + z*z - 1", 2.0), None),
        ("huge", scene("1.7e308*x*x + y - 1", 2.0), None),
        ("slab", scene("abs(x) - 1e-300", 1.2), None),
        ("ln", scene("ln(-abs(x)) + y", 1.2), None),
        ("cancel", scene("1/(x - x)", 1.2), None),
        (
            "undefined",
            scene("sqrt(x - 1e300)", 1.2),
            Some("undefined everywhere"),
        ),
        // The camera 1e300 away: its squared distance overflows, and the
        // loader refuses the camera.
        (
            "far",
            scene("scale(sphere(1), 1e300)", 1.2e300),
            Some("camera"),
        ),
    ];
    for (name, text, fails_with) in cases {
        let file = dir.join(format!("{name}.ib"));
        std::fs::write(&file, text).unwrap();
        for extra in [
            &["--method", "beam"][..],
            &["--method", "pixel"],
            &["--aa", "iaa"],
        ] {
            let png = dir.join(format!("{name}.png"));
            let _ = std::fs::remove_file(&png);
            let mut args = vec![
                "render",
                file.to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
                "--size",
                "64x64",
                "--quiet",
            ];
            args.extend_from_slice(extra);
            let (o, took) = ibeam_within(&args, std::time::Duration::from_secs(20));
            println!("{name} {extra:?}: {took:.2?}, exit {:?}", o.status.code());
            match fails_with {
                None => {
                    assert_eq!(o.status.code(), Some(0), "{name} {extra:?}: {}", stderr(&o));
                    let img = image::open(&png).unwrap_or_else(|e| panic!("{name}: {e}"));
                    assert_eq!((img.width(), img.height()), (64, 64), "{name}");
                }
                Some(needle) => {
                    assert_fails(&o, &[needle]);
                    assert!(!png.exists(), "{name}: no image is written");
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn streamed_pngs_match_the_in_memory_render() {
    use ibeam::eval::{EvalKind, build_evaluators};
    use ibeam::render::{Aa, RenderOptions, render_aa};
    let dir = scratch("stream");
    for name in ["sphere.ib", "csg.ib", "torus.ib"] {
        let scene = ibeam::lang::load_scene(&example(name)).unwrap();
        let ev = build_evaluators(&scene, EvalKind::Interp).unwrap();
        let aas = [
            ("none", Aa::None),
            ("grid:2", Aa::Grid(2)),
            (
                "iaa",
                Aa::Iaa {
                    threshold: ibeam::render::aa::DEFAULT_THRESHOLD,
                    depth: ibeam::render::aa::DEFAULT_DEPTH,
                },
            ),
        ];
        for (flag, aa) in aas {
            let o = RenderOptions {
                want_depth: true,
                want_normals: true,
                want_classify: true,
                ..RenderOptions::new(37, 66)
            };
            let want = render_aa(&scene, &ev, &o, aa).unwrap();
            let mut first: Option<Vec<Vec<u8>>> = None;
            for threads in ["1", "2"] {
                let files = ["c.png", "d.png", "n.png", "k.png"].map(|f| dir.join(f));
                let [c, d, n, k] = files.each_ref().map(|p| p.to_str().unwrap());
                let args = [
                    "--size",
                    "37x66",
                    "--aa",
                    flag,
                    "--threads",
                    threads,
                    "--depth",
                    d,
                    "--normals",
                    n,
                    "--classify",
                    k,
                ];
                let out = render(&example(name), Path::new(c), &args);
                let what = format!("{name} --aa {flag} --threads {threads}");
                assert_eq!(out.status.code(), Some(0), "{what}: {}", stderr(&out));
                let read = |p: &Path| image::open(p).unwrap();
                assert_eq!(read(&files[0]).to_rgb8(), want.image, "{what}");
                assert_eq!(read(&files[1]).to_luma16(), *want.depth.as_ref().unwrap());
                assert_eq!(read(&files[2]).to_rgb8(), *want.normals.as_ref().unwrap());
                assert_eq!(read(&files[3]).to_rgb8(), *want.classify.as_ref().unwrap());
                // The files themselves are the same for any thread count.
                let bytes: Vec<Vec<u8>> = files.iter().map(|p| std::fs::read(p).unwrap()).collect();
                match &first {
                    None => first = Some(bytes),
                    Some(f) => assert!(*f == bytes, "{what}"),
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unwritable_auxiliary_output_fails_before_rendering() {
    let dir = scratch("unwritable-aux");
    let png = dir.join("a.png");
    let o = render(
        &example("sphere.ib"),
        &png,
        &["--size", "8x8", "--normals", "/nonexistent/dir/n.png"],
    );
    assert_fails(&o, &["cannot write", "/nonexistent/dir/n.png"]);
    // The colour image this run created is removed again.
    assert!(!png.exists());
    let _ = std::fs::remove_dir_all(&dir);
}
