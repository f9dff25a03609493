//! The blocker hint of `point_segment_free` against the sweep alone.

use super::*;
use crate::eval::build::{EvalKind, build_evaluators};
use crate::ir::random::Rng;
use crate::render::view::camera::RayCamera;
use crate::scene::{Bounds, Camera, Light, Object, RenderSettings, Scene};

// Whatever point a blocker hint names, on the segment or off any
// solid, the answer is the sweep's own; and a hint that falls inside
// the occluder is where the answer comes from.
// f = y + 0.5 (a floor) and a ball of radius 0.3 at (0, 0.3, 0).
fn floor_and_ball() -> Scene {
    use crate::ir::{BinaryOp, Builder, UnaryOp, Var};
    let floor = {
        let mut b = Builder::new();
        let (y, h) = (b.var(Var::Y), b.constant(0.5));
        let f = b.binary(BinaryOp::Add, y, h);
        b.finish(f)
    };
    let ball = {
        let mut b = Builder::new();
        let (x, y, z) = (b.var(Var::X), b.var(Var::Y), b.var(Var::Z));
        let (c, r) = (b.constant(0.3), b.constant(0.3));
        let yc = b.binary(BinaryOp::Sub, y, c);
        let (x2, y2, z2) = (b.powi(x, 2), b.powi(yc, 2), b.powi(z, 2));
        let s = b.binary(BinaryOp::Add, x2, y2);
        let s = b.binary(BinaryOp::Add, s, z2);
        let d = b.unary(UnaryOp::Sqrt, s);
        let f = b.binary(BinaryOp::Sub, d, r);
        b.finish(f)
    };
    let object = |name: &str, function| Object {
        name: name.into(),
        function,
        color: [0.8; 3],
    };
    Scene {
        objects: vec![object("floor", floor), object("ball", ball)],
        camera: Camera::default(),
        lights: vec![Light {
            kind: LightKind::Point([0.0, 2.0, 0.0]),
            color: [1.0; 3],
            shadows: true,
        }],
        bounds: Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        },
        render: RenderSettings::default(),
    }
}

// Whatever point a blocker hint names, on the segment or off any
// solid, the answer is the sweep's own; and a hint that falls inside
// the occluder is where the answer comes from.
#[test]
fn blocker_hints_never_change_the_answer() {
    with_floor_and_ball(blocker_hints_hold);
}

// Runs `test` on `floor_and_ball`'s scope, a tile state and the segment
// end of its light.
fn with_floor_and_ball(test: impl FnOnce(&Scope<'_>, &mut TileState, SegEnd)) {
    let scene = floor_and_ball();
    let evals = build_evaluators(&scene, EvalKind::Interp).expect("evaluators");
    let cam = RayCamera::new(&scene.camera, 16, 16).expect("camera");
    let tr = Scope::new(&scene, &evals, cam, false);
    test(
        &tr,
        &mut TileState::default(),
        SegEnd::Point(DVec3::new(0.0, 2.0, 0.0)),
    );
}

fn blocker_hints_hold(tr: &Scope<'_>, st: &mut TileState, light: SegEnd) {
    let mut rng = Rng::new(7);
    let (mut shadowed, mut settled_by_hint) = (0, 0);
    for _ in 0..400 {
        // Points just above the floor, some under the ball.
        let p = DVec3::new(rng.range(-0.9, 0.9), -0.49, rng.range(-0.9, 0.9));
        let free = segment_free(tr, point_box(p.to_array()), &[p], light, 1e-4, st);
        shadowed += usize::from(!free);
        for hint in [
            None,
            Some(0.0),
            Some(0.3),
            Some(0.32),
            Some(0.5),
            Some(0.99),
        ] {
            let (hinted, found) = point_segment_free(tr, p, light, 1e-4, hint, st);
            assert_eq!(hinted, free, "{p:?} with hint {hint:?}");
            // A point inside a solid is found only on a shadowed segment.
            assert!(
                found.is_none() || !free,
                "{p:?}: found {found:?} on a free segment"
            );
            if hint.is_some() && found == hint {
                settled_by_hint += 1;
            }
        }
    }
    assert!(
        shadowed > 20 && shadowed < 380,
        "shadowed {shadowed} of 400"
    );
    assert!(settled_by_hint > 0);
}

// A segment with no point in the bounds is free without a sweep, as the
// sweep finds it; segments from outside that cross the bounds, or from
// inside them, still sweep.
#[test]
fn segments_missing_the_bounds_skip_the_sweep() {
    with_floor_and_ball(missing_segments_skip);
}

fn missing_segments_skip(tr: &Scope<'_>, st: &mut TileState, light: SegEnd) {
    let mut rng = Rng::new(11);
    let (mut missed, mut crossing) = (0, 0);
    for _ in 0..400 {
        let p = DVec3::new(
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
            rng.range(-1.5, 1.5),
        );
        let free = segment_free(tr, point_box(p.to_array()), &[p], light, 1e-4, st);
        let evaluated = st.stats.interval_evals + st.stats.point_evals;
        let (answer, found) = point_segment_free(tr, p, light, 1e-4, None, st);
        assert_eq!(answer, free, "{p:?}");
        let swept = st.stats.interval_evals + st.stats.point_evals > evaluated;
        if misses_bounds(tr, p, light) {
            missed += 1;
            assert!(free && found.is_none() && !swept, "{p:?}");
        } else if p.y < -1.0 && p.x.abs() < 0.5 && p.z.abs() < 0.5 {
            // From below the bounds up through them (and the floor).
            crossing += 1;
            assert!(!free && swept, "{p:?}");
        }
    }
    assert!(
        missed > 50 && crossing > 0,
        "{missed} missed, {crossing} crossing"
    );
}

// A shadow beam answers as without a blocker hint, whatever the hint; a
// hint inside the ball fails a beam under it without a sweep (no
// interval evaluation), and a failed beam leaves where it found the
// ball for the next.
#[test]
fn beam_blocker_hints_never_change_the_answer() {
    with_floor_and_ball(beam_hints_hold);
}

// Four floor points around (x, z), 0.002 apart, as a beam's surfaces.
fn floor_patch(x: f64, z: f64) -> Vec<HitSurface> {
    let at = |dx: f64, dz: f64| {
        let p = DVec3::new(x + dx, -0.5, z + dz);
        HitSurface {
            p,
            n: DVec3::Y,
            q: p + DVec3::new(0.0, 1e-3, 0.0),
            v: DVec3::Y,
            min_w: 1e-3,
            color: DVec3::ONE,
            grad_len: 1.0,
        }
    };
    vec![
        at(0.0, 0.0),
        at(0.002, 0.0),
        at(0.0, 0.002),
        at(0.002, 0.002),
    ]
}

fn beam_hints_hold(tr: &Scope<'_>, st: &mut TileState, _: SegEnd) {
    let light = LightKind::Point([0.0, 2.0, 0.0]);
    let mut rng = Rng::new(13);
    let mut lit = 0;
    for _ in 0..200 {
        let patch = floor_patch(rng.range(-0.9, 0.9), rng.range(-0.9, 0.9));
        let free = shadow_beam(tr, &patch, light, &mut None, st);
        lit += usize::from(free);
        for hint in [0.0, 0.3, 0.5, 0.99] {
            let mut blocker = Some(hint);
            assert_eq!(shadow_beam(tr, &patch, light, &mut blocker, st), free);
        }
    }
    assert!(lit > 20 && lit < 190, "{lit} of 200 lit");
    // Under the ball: the first beam finds it and says where.
    let under = floor_patch(0.01, 0.01);
    let mut blocker = None;
    assert!(!shadow_beam(tr, &under, light, &mut blocker, st));
    let found = blocker.expect("a failed beam under the ball names its blocker");
    // Its neighbour fails on that point alone.
    let before = st.stats.interval_evals;
    let next = floor_patch(0.02, 0.01);
    assert!(!shadow_beam(tr, &next, light, &mut blocker, st));
    assert_eq!(st.stats.interval_evals, before, "swept despite the hint");
    assert_eq!(blocker, Some(found));
}
