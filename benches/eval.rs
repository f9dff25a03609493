//! Criterion benchmarks of the evaluators: interpreter against JIT, single
//! calls and batches, on orthocircle, tangle cube and prospero.
//! `cargo bench --bench eval`; `ibeam bench eval` prints the same figures
//! as one table.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ibeam::eval::interp::Interpreter;
use ibeam::eval::jit::JitEvaluator;
use ibeam::eval::{Bulk, Evaluator};
use ibeam::interval::Interval;
use ibeam::ir::passes::simplify;
use std::hint::black_box;
use std::path::Path;

const N: usize = 256;

fn inputs() -> (Vec<[f64; 3]>, Vec<[Interval; 3]>) {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut unit = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 3.0 - 1.5
    };
    let points: Vec<[f64; 3]> = (0..N).map(|_| [unit(), unit(), unit()]).collect();
    let boxes = points
        .iter()
        .map(|p| p.map(|c| Interval::new(c, c + 0.05)))
        .collect();
    (points, boxes)
}

fn bench_scene(c: &mut Criterion, name: &str, path: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    if !path.exists() {
        return;
    }
    let scene = ibeam::lang::load_scene(&path).expect("benchmark scene loads");
    let f = simplify(&scene.objects[0].function);
    let interp = Interpreter::new(f.clone());
    let jit = JitEvaluator::new(&f).expect("JIT compiles");
    let (points, boxes) = inputs();
    let xs: Vec<f64> = points.iter().map(|p| p[0]).collect();
    let ys: Vec<f64> = points.iter().map(|p| p[1]).collect();
    let zs: Vec<f64> = points.iter().map(|p| p[2]).collect();
    let mut out = vec![0.0; N];
    let mut iout = vec![Interval::point(0.0); N];

    let mut g = c.benchmark_group(name);
    g.throughput(Throughput::Elements(N as u64));
    let evals: [(&str, &dyn Evaluator); 2] = [("interp", &interp), ("jit", &jit)];
    for (label, e) in evals {
        g.bench_function(format!("point/{label}"), |b| {
            b.iter(|| {
                points.iter().for_each(|p| {
                    black_box(e.point(*p));
                })
            })
        });
        g.bench_function(format!("interval/{label}"), |b| {
            b.iter(|| {
                boxes.iter().for_each(|x| {
                    black_box(e.interval(*x));
                })
            })
        });
    }
    g.bench_function("point_batch/jit", |b| {
        b.iter(|| jit.point_batch(&xs, &ys, &zs, black_box(&mut out)))
    });
    g.bench_function("interval_batch/jit", |b| {
        b.iter(|| jit.interval_batch(&boxes, black_box(&mut iout)))
    });
    g.finish();
}

fn evaluators(c: &mut Criterion) {
    bench_scene(c, "orthocircle", "examples/orthocircle.ib");
    bench_scene(c, "tangle_cube", "examples/tangle_cube.ib");
    bench_scene(c, "prospero", "../shared/models/prospero.vm");
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = evaluators
}
criterion_main!(benches);
