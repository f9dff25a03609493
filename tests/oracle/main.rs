//! The renderer against an oracle that shares no code with it
//! (`certify`): random scenes with domain edges, jumps, thin features and
//! long unions (`scenes`), rendered by the beam, pixel and IAA methods,
//! pruned and whole, on native code and on the interpreter. Every pixel
//! the oracle proves hit must be hit within its bracket, every pixel it
//! proves empty must stay empty, and every hit it proves shadowed (or lit)
//! must be drawn so.
//!
//! A renderer's hit is compared with the oracle's only where it lies
//! within the margin the oracle's shadow proof allowed for: the oracle
//! proves shadow for every start point that close to its own hit, which
//! covers the renderer's refinement tolerance and no more (a pixel's 32nd).

mod certify;
mod edges;
mod exact;
mod scenes;

use std::sync::Arc;

use certify::{Oracle, RayFate, ShadowFate, at, dot3};
use ibeam::eval::{EvalKind, Evaluator, build_evaluators};
use ibeam::ir::random::Rng;
use ibeam::render::shade::AMBIENT;
use ibeam::render::{Aa, Method, RenderOptions, RenderOutput, render_aa};
use ibeam::scene::Scene;

/// Image side of every render here: small, so the oracle stays cheap.
const SIZE: u32 = if cfg!(debug_assertions) { 20 } else { 32 };

/// One way of rendering a scene.
struct Variant {
    name: &'static str,
    kind: EvalKind,
    method: Method,
    prune: bool,
    aa: Aa,
}

const VARIANTS: [Variant; 5] = [
    Variant {
        name: "beam",
        kind: EvalKind::Jit,
        method: Method::Beam,
        prune: true,
        aa: Aa::None,
    },
    Variant {
        name: "beam, unpruned",
        kind: EvalKind::Jit,
        method: Method::Beam,
        prune: false,
        aa: Aa::None,
    },
    Variant {
        name: "pixel",
        kind: EvalKind::Jit,
        method: Method::Pixel,
        prune: true,
        aa: Aa::None,
    },
    Variant {
        name: "beam, interpreted",
        kind: EvalKind::Interp,
        method: Method::Beam,
        prune: true,
        aa: Aa::None,
    },
    Variant {
        name: "iaa",
        kind: EvalKind::Jit,
        method: Method::Beam,
        prune: true,
        aa: Aa::Iaa {
            threshold: 1.0 / 64.0,
            depth: 2,
        },
    },
];

/// What the oracle proves of every pixel: the ray, and for a hit the
/// shadow of its start points near the oracle's hit.
struct Proofs {
    rays: Vec<RayFate>,
    shadows: Vec<Option<(f64, f64, ShadowFate)>>,
    lambert: Vec<f64>,
}

fn prove(o: &Oracle, scene: &Scene) -> Proofs {
    let light = scene.lights[0].kind;
    let n = (SIZE * SIZE) as usize;
    let (mut rays, mut shadows, mut lambert) = (Vec::new(), vec![None; n], vec![0.0; n]);
    for j in 0..SIZE {
        for i in 0..SIZE {
            let fate = o.ray(i, j);
            rays.push(fate);
            let (lo, hi, cut) = match fate {
                RayFate::Hit { lo, hi } => (lo, hi, false),
                RayFate::Cut { lo, hi } => (lo, hi, true),
                _ => continue,
            };
            let k = (j * SIZE + i) as usize;
            let t = 0.5 * (lo + hi);
            let near = 0.5 * (hi - lo) + o.pixel / 32.0;
            let p = at(o.origin(i, j), o.dir(), t);
            let shadow = match o.shadow(p, light, near) {
                // A lit proof assumes the hit outside every solid.
                ShadowFate::Lit if cut => ShadowFate::Unknown,
                s => s,
            };
            shadows[k] = Some((t, near, shadow));
            // The renderer's normal faces the viewer.
            if let Some(nv) = o.normal(p) {
                let nv = if dot3(nv, o.dir()) > 0.0 {
                    nv.map(|c| -c)
                } else {
                    nv
                };
                lambert[k] = dot3(nv, o.light_dir(light, p));
            }
        }
    }
    Proofs {
        rays,
        shadows,
        lambert,
    }
}

/// The ways one render breaks the oracle's proofs, as messages.
fn disagreements(o: &Oracle, scene: &Scene, p: &Proofs, out: &RenderOutput) -> Vec<String> {
    let colors = scene.objects.iter().flat_map(|ob| ob.color);
    let dark = colors.clone().fold(0.0f64, f64::max) * AMBIENT;
    let dim = colors.fold(1.0f64, f64::min);
    let tol = o.pixel;
    let mut bad = Vec::new();
    for (k, fate) in p.rays.iter().enumerate() {
        let (i, j) = (k as u32 % SIZE, k as u32 / SIZE);
        let t = out.depth_t[k];
        let single = out.samples[k] <= 1;
        let hit = t.is_finite();
        match *fate {
            RayFate::Empty if single && hit => {
                bad.push(format!("({i}, {j}) surely empty, hit at {t}"))
            }
            RayFate::Hit { .. } | RayFate::Cut { .. } if !out.hit_mask[k] => {
                bad.push(format!("({i}, {j}) surely hit, missed"))
            }
            RayFate::Hit { lo, hi } | RayFate::Cut { lo, hi }
                if single && !(lo - tol <= t && t <= hi + tol) =>
            {
                bad.push(format!("({i}, {j}) hit at {t}, root in [{lo}, {hi}]"))
            }
            RayFate::Unknown { lo } if single && t < lo - tol => {
                bad.push(format!("({i}, {j}) hit at {t}, nothing before {lo}"))
            }
            _ => {}
        }
        let Some((t0, near, shadow)) = p.shadows[k] else {
            continue;
        };
        // Only where the renderer's hit lies within the proof's margin.
        if !single || !hit || (t - t0).abs() > near {
            continue;
        }
        let c = f64::from(out.linear[k][0]);
        let drawn_lit = c > dark + 0.02;
        match shadow {
            ShadowFate::Shadowed if drawn_lit => bad.push(format!(
                "({i}, {j}) at t = {t}: surely shadowed, drawn lit ({c})"
            )),
            ShadowFate::Lit if p.lambert[k] > 0.2 && c < dark + 0.5 * p.lambert[k] * dim => bad
                .push(format!(
                    "({i}, {j}) at t = {t}: surely lit, drawn dark ({c})"
                )),
            _ => {}
        }
    }
    bad
}

fn evaluators(scene: &Scene, kind: EvalKind) -> Vec<Arc<dyn Evaluator>> {
    build_evaluators(scene, kind).expect("the scene's IR is valid")
}

/// Renders `text` every way and checks each render against the oracle;
/// the failures, one line each (empty: all agree).
fn check_scene(label: &str, text: &str) -> Vec<String> {
    let scene = ibeam::lang::load_scene_source("oracle.ib", text)
        .unwrap_or_else(|e| panic!("{label}: does not load: {e}\n{text}"));
    let oracle = Oracle::new(&scene, SIZE, SIZE);
    let proofs = prove(&oracle, &scene);
    let mut failures = Vec::new();
    for v in &VARIANTS {
        let mut opts = RenderOptions::new(SIZE, SIZE);
        opts.method = v.method;
        opts.prune = v.prune;
        opts.threads = Some(1);
        let out = render_aa(&scene, &evaluators(&scene, v.kind), &opts, v.aa)
            .unwrap_or_else(|e| panic!("{label}: {} does not render: {e:?}\n{text}", v.name));
        let bad = disagreements(&oracle, &scene, &proofs, &out);
        if !bad.is_empty() {
            failures.push(format!(
                "{label}, {}: {} pixels, first {:?}",
                v.name,
                bad.len(),
                &bad[..bad.len().min(3)]
            ));
        }
    }
    failures
}

/// Runs `count` scenes from `make` (seeded by their index) and asserts
/// that every one rendered and agreed with the oracle.
fn run(name: &str, count: u64, make: impl Fn(&mut Rng, u64) -> String) {
    let mut failures = Vec::new();
    let mut rendered = 0;
    for seed in 0..count {
        let mut rng = Rng::new(0x0ac1e ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let text = make(&mut rng, seed);
        let bad = check_scene(&format!("{name} #{seed}"), &text);
        if !bad.is_empty() && std::env::var_os("ORACLE_SCENES").is_some() {
            eprintln!("{name} #{seed}:\n{text}");
        }
        failures.extend(bad);
        rendered += 1;
    }
    assert_eq!(rendered, count);
    assert!(
        failures.is_empty(),
        "{} of {} renders disagree with the oracle:\n{}",
        failures.len(),
        count as usize * VARIANTS.len(),
        failures.join("\n")
    );
}

/// Scenes per test: fewer where debug assertions slow the interpreter.
const SCENES: u64 = if cfg!(debug_assertions) { 3 } else { 8 };

#[test]
fn domain_edges_and_jumps() {
    run("edge", SCENES * 2, |rng, seed| {
        let solid = scenes::edge_solid(rng, seed as usize % scenes::EDGE_KINDS);
        scenes::scene_text(rng, &[solid])
    });
}

#[test]
fn thin_features() {
    run("thin", SCENES, |rng, _| {
        let objects = [scenes::thin_solid(rng), scenes::thin_solid(rng)];
        scenes::scene_text(rng, &objects)
    });
}

#[test]
fn unions_long_enough_to_prune() {
    run("union", SCENES, |rng, seed| {
        // 12 spheres: over the interpreter's pruning threshold (64 ops);
        // 60: over native code's (512).
        let count = if seed % 2 == 0 { 12 } else { 60 };
        let objects = [scenes::sphere_union(rng, count)];
        scenes::scene_text(rng, &objects)
    });
}
