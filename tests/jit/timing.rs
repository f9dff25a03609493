//! Compile times and evaluation speed (ignored; run in release with
//! `--ignored --nocapture`).

use super::big::wide;
use super::*;

/// Compile times of each kind for the big test functions (run with
/// `--ignored --nocapture`, ideally in release).
#[test]
#[ignore]
fn print_compile_times() {
    for (name, f) in [("wide100", wide(100))] {
        let jit = JitEvaluator::new(&f).unwrap();
        for k in Kind::ALL {
            let t = std::time::Instant::now();
            jit.compile(k).unwrap();
            println!("{name} ({} ops) {}: {:?}", f.len(), k.name(), t.elapsed());
        }
    }
}

/// The prospero model through the crate's own `.vm` importer, simplified
/// as the CLI does (see `common::models` for when it is `None`).
fn prospero() -> Option<Function> {
    let path = common::models::shared_model("prospero.vm")?;
    let scene = ibeam::lang::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    Some(ibeam::ir::passes::simplify(&scene.objects[0].function))
}

/// Compile times and speed on ../shared/models/prospero.vm (run with
/// `cargo test --release --test jit -- --ignored prospero --nocapture`).
#[test]
#[ignore]
fn prospero_timing() {
    let Some(f) = prospero() else { return };
    let clif = clif_text(&f).unwrap();
    for part in clif.split("; evaluator: ").skip(1) {
        let name = part.lines().next().unwrap_or("");
        println!("{name}: {} CLIF lines", part.lines().count());
    }
    let jit = JitEvaluator::new(&f).unwrap();
    for k in Kind::ALL {
        let t = std::time::Instant::now();
        jit.compile(k).unwrap();
        println!("prospero ({} ops) {}: {:?}", f.len(), k.name(), t.elapsed());
    }
}

/// Evaluation speed of the JIT against the interpreter, on prospero (run in release
/// with `--ignored prospero_speed --nocapture`).
#[test]
#[ignore]
fn prospero_speed() {
    let Some(f) = prospero() else { return };
    let jit = JitEvaluator::new(&f).unwrap();
    let n = 20_000;
    let mut r = Rng::new(1);
    let pts: Vec<[f64; 3]> = (0..n)
        .map(|_| [r.range(-1.0, 1.0), r.range(-1.0, 1.0), 0.0])
        .collect();
    let bxs: Vec<[Interval; 3]> = pts
        .iter()
        .map(|p| p.map(|c| Interval::new(c, c + 1.0 / 64.0)))
        .collect();
    let time = |name: &str, g: &mut dyn FnMut() -> f64| {
        let t = std::time::Instant::now();
        let s = g();
        let dt = t.elapsed();
        println!(
            "{name}: {:.1} ns/eval (checksum {s:e})",
            dt.as_nanos() as f64 / n as f64
        );
        dt
    };
    let interp = Interpreter::new(f.clone());
    jit.compile_all().unwrap();
    let ti = time("interp point", &mut || {
        pts.iter().map(|p| Single::point(&interp, *p)).sum()
    });
    let tj = time("jit point", &mut || pts.iter().map(|p| jit.point(*p)).sum());
    println!("point speedup {:.1}x", ti.as_secs_f64() / tj.as_secs_f64());
    let ti = time("interp interval", &mut || {
        bxs.iter().map(|b| Single::interval(&interp, *b).lo).sum()
    });
    let tj = time("jit interval", &mut || {
        bxs.iter().map(|b| jit.interval(*b).lo).sum()
    });
    println!(
        "interval speedup {:.1}x",
        ti.as_secs_f64() / tj.as_secs_f64()
    );
    let (xs, ys, zs): (Vec<f64>, Vec<f64>, Vec<f64>) = (
        pts.iter().map(|p| p[0]).collect(),
        pts.iter().map(|p| p[1]).collect(),
        pts.iter().map(|p| p[2]).collect(),
    );
    let mut out = vec![0.0; n];
    for _ in 0..2 {
        time("jit point_batch", &mut || {
            jit.point_batch(&xs, &ys, &zs, &mut out);
            out.iter().sum()
        });
        time("jit point", &mut || pts.iter().map(|p| jit.point(*p)).sum());
    }
    let mut iout = vec![Interval::EMPTY; n];
    time("jit interval_batch", &mut || {
        jit.interval_batch(&bxs, &mut iout);
        iout.iter().map(|i| i.lo).sum()
    });
    for (name, t) in jit.compile_times() {
        println!("compile {name}: {t:?}");
    }
}

/// Interval evaluation time per box, the best of 15 rounds (robust against a
/// busy machine), JIT and interpreter, on the example scenes and prospero.
/// Run in release with `--ignored interval_speed --nocapture`.
#[test]
#[ignore]
fn interval_speed() {
    let mut fs = Vec::new();
    for file in ["examples/orthocircle.ib", "examples/tangle_cube.ib"] {
        let scene = ibeam::lang::load_scene(std::path::Path::new(file)).unwrap();
        fs.push((
            file,
            ibeam::ir::passes::simplify(&scene.objects[0].function),
        ));
    }
    if let Some(f) = prospero() {
        fs.push(("prospero", f));
    }
    for (name, f) in fs {
        let jit = JitEvaluator::new(&f).unwrap();
        let interp = Interpreter::new(f.clone());
        let n = if f.len() > 1000 { 500 } else { 20_000 };
        let mut r = Rng::new(3);
        let bxs: Vec<[Interval; 3]> = (0..n)
            .map(|_| {
                [0, 1, 2].map(|_| {
                    let c = r.range(-1.25, 1.25);
                    Interval::new(c, c + 2.5 / 64.0)
                })
            })
            .collect();
        let best = |e: &dyn Evaluator| {
            (0..15)
                .map(|_| {
                    let t = std::time::Instant::now();
                    for b in &bxs {
                        std::hint::black_box(e.interval(std::hint::black_box(*b)));
                    }
                    t.elapsed().as_nanos() as f64 / n as f64
                })
                .fold(f64::INFINITY, f64::min)
        };
        let (tj, ti) = (best(&jit), best(&interp));
        println!(
            "{name}: jit {tj:.1} ns/box, interp {ti:.1} ns/box, {:.2}x",
            ti / tj
        );
    }
}
