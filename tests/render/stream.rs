//! The streamed render ([`Frame::stream`]) against the in-memory one: the
//! same pixels in every image, the same counters, for any thread count and
//! anti-aliasing, on example scenes.

use std::path::Path;

use ibeam::eval::{EvalKind, build_evaluators};
use ibeam::render::output::depth_range;
use ibeam::render::{Aa, Band, Frame, RenderOptions, RenderStats, render_aa};

/// The render counters, times (which vary run to run) zeroed.
fn counters(s: &RenderStats) -> RenderStats {
    RenderStats {
        time_ms: 0.0,
        compile_ms: 0.0,
        trace_cpu_ms: 0.0,
        shade_cpu_ms: 0.0,
        shadow_cpu_ms: 0.0,
        aa_cpu_ms: 0.0,
        aa_tests_cpu_ms: 0.0,
        output_ms: 0.0,
        ..s.clone()
    }
}

#[test]
fn streamed_bands_are_the_in_memory_images() {
    for name in ["sphere.ib", "csg.ib", "torus.ib"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples")
            .join(name);
        let scene = ibeam::lang::load_scene(&path).unwrap();
        let ev = build_evaluators(&scene, EvalKind::Interp).unwrap();
        let aas = [
            Aa::None,
            Aa::Grid(2),
            Aa::Iaa {
                threshold: 1.0 / 64.0,
                depth: 2,
            },
        ];
        for aa in aas {
            // Not a multiple of the tile size either way, several tile rows.
            let o = RenderOptions {
                threads: Some(1),
                want_depth: true,
                want_normals: true,
                want_classify: true,
                ..RenderOptions::new(45, 70)
            };
            let whole = render_aa(&scene, &ev, &o, aa).unwrap();
            for threads in [1, 3] {
                let o = RenderOptions {
                    threads: Some(threads),
                    ..o.clone()
                };
                let frame = Frame::new(&scene, &ev, &o, aa).unwrap();
                assert_eq!(
                    frame.depth_range(),
                    depth_range(&scene.camera, &scene.bounds)
                );
                let mut bands: Vec<Band> = Vec::new();
                let stats = frame
                    .stream(|b| {
                        bands.push(b.clone());
                        Ok::<(), ()>(())
                    })
                    .unwrap();
                let what = format!("{name} {aa:?} threads {threads}");
                assert_eq!(counters(&stats), counters(&whole.stats), "{what}");
                let mut next = 0;
                for b in &bands {
                    assert_eq!((b.y0, b.width), (next, 45), "{what}");
                    next += b.rows;
                }
                assert_eq!(next, 70, "{what}");
                let cat = |f: &dyn Fn(&Band) -> Vec<u8>| -> Vec<u8> {
                    bands.iter().flat_map(f).collect()
                };
                assert_eq!(cat(&|b| b.color.clone()), whole.image.as_raw().clone());
                assert_eq!(
                    cat(&|b| b.normals.clone().unwrap()),
                    whole.normals.as_ref().unwrap().as_raw().clone(),
                    "{what}"
                );
                assert_eq!(
                    cat(&|b| b.classify.clone().unwrap()),
                    whole.classify.as_ref().unwrap().as_raw().clone(),
                    "{what}"
                );
                let depth: Vec<u16> = bands
                    .iter()
                    .flat_map(|b| b.depth.clone().unwrap())
                    .collect();
                assert_eq!(&depth, whole.depth.as_ref().unwrap().as_raw(), "{what}");
            }
        }
    }
}

#[test]
fn a_failing_sink_stops_the_stream() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/sphere.ib");
    let scene = ibeam::lang::load_scene(&path).unwrap();
    let ev = build_evaluators(&scene, EvalKind::Interp).unwrap();
    let frame = Frame::new(&scene, &ev, &RenderOptions::new(40, 100), Aa::None).unwrap();
    let mut calls = 0;
    let r = frame.stream(|_| {
        calls += 1;
        if calls == 2 { Err("disk full") } else { Ok(()) }
    });
    assert_eq!(r, Err("disk full"));
    assert_eq!(calls, 2);
}
