use super::*;
use crate::eval::build::{EvalKind, build_evaluators};
use crate::render::view::camera::RayCamera;
use crate::scene::{Bounds, Camera, Light, Object, Projection, RenderSettings, Scene};

// Two discs of a 2D model, left and right of x = 0, in two colours,
// seen along z through a parallel camera, under two directional
// lights without shadows: every hit is a cut face.
fn two_discs() -> Scene {
    use crate::ir::{BinaryOp, Builder, Var};
    let disc = |cx: f64| {
        let mut b = Builder::new();
        let (x, y) = (b.var(Var::X), b.var(Var::Y));
        let (c, r) = (b.constant(cx), b.constant(0.16));
        let dx = b.binary(BinaryOp::Sub, x, c);
        let (x2, y2) = (b.powi(dx, 2), b.powi(y, 2));
        let s = b.binary(BinaryOp::Add, x2, y2);
        let f = b.binary(BinaryOp::Sub, s, r);
        b.finish(f)
    };
    let object = |name: &str, function, color| Object {
        name: name.into(),
        function,
        color,
    };
    let light = |dir| Light {
        kind: LightKind::Directional(dir),
        color: [0.7, 0.6, 0.5],
        shadows: false,
    };
    Scene {
        objects: vec![
            object("left", disc(-0.5), [0.9, 0.2, 0.1]),
            object("right", disc(0.5), [0.1, 0.3, 0.8]),
        ],
        camera: Camera {
            eye: [0.0, 0.0, 3.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Orthographic { width: 2.0 },
        },
        lights: vec![light([-0.3, -0.4, -1.0]), light([0.5, 0.1, -0.8])],
        bounds: Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        },
        render: RenderSettings::default(),
    }
}

// Cut faces lit once per object get the colour and normal that lighting
// each of them gives, bit for bit.
#[test]
fn cut_faces_lit_once_per_object_match_each_pixels_own_lighting() {
    let scene = two_discs();
    let evals = build_evaluators(&scene, EvalKind::Interp).expect("evaluators");
    let size = 48;
    let tr = Scope::new(
        &scene,
        &evals,
        RayCamera::new(&scene.camera, size, size).unwrap(),
        true,
    );
    assert!(tr.ctx.flat);
    let mut opts = RenderOptions::new(size, size);
    opts.want_normals = true;
    let out = render_tile(&tr, &opts, spec_of(size), [0.0; 3]);
    let grid = RayGrid::new(&tr.ctx.cam, (0, 0), (size, size));
    let normals = out.normals.as_ref().expect("normals asked for");
    let mut hits = [0; 2];
    for (k, &t) in out.depth.iter().enumerate() {
        if !t.is_finite() {
            continue;
        }
        let ray = grid.ray_at_index(k);
        let obj = usize::from(ray.om[0] > 0.0);
        hits[obj] += 1;
        let hit = crate::render::Hit {
            t,
            obj,
            inside: true,
            grad: None,
            front: None,
        };
        let mut st = TileState::default();
        let s = shade::surface(&tr, &ray, &hit, &mut st.stats);
        let memo = &mut shade::LightMemo::default();
        let (c, shadowed) = shade::shade(&tr, &s, shade::KnownShadows::default(), memo, &mut st);
        assert_eq!(
            out.linear[k].map(f64::to_bits),
            c.to_array().map(f64::to_bits)
        );
        assert_eq!(out.shadowed[k], shadowed);
        assert_eq!(
            normals[k].map(f64::to_bits),
            s.n.to_array().map(f64::to_bits)
        );
    }
    assert!(hits[0] > 50 && hits[1] > 50, "hits {hits:?}");
    let tile = tile_rays(&tr, &opts, &spec_of(size));
    assert!(
        CutFaces::of(&tr, &tile).is_some(),
        "the shared path was not taken"
    );
}

// A tile whose spec turns the mean-value form off never tries it, and
// draws the same pixels (the form only tightens intervals).
#[test]
fn a_tile_without_the_mean_value_form_never_tries_it() {
    // A ball seen in perspective: a 3D scene, whose blocks try the form.
    let mut scene = two_discs();
    scene.objects.truncate(1);
    scene.objects[0].function = {
        use crate::ir::{BinaryOp, Builder, Var};
        let mut b = Builder::new();
        let r2 = b.constant(0.5);
        let mut sum = r2;
        for v in [Var::X, Var::Y, Var::Z] {
            let c = b.var(v);
            let c2 = b.powi(c, 2);
            sum = b.binary(BinaryOp::Add, sum, c2);
        }
        let twice = b.binary(BinaryOp::Add, r2, r2);
        let f = b.binary(BinaryOp::Sub, sum, twice);
        b.finish(f)
    };
    scene.camera = Camera {
        eye: [0.0, 1.5, 2.5],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Perspective { fov_deg: 40.0 },
    };
    let evals = build_evaluators(&scene, EvalKind::Interp).expect("evaluators");
    let size = 32;
    let tr = Scope::new(
        &scene,
        &evals,
        RayCamera::new(&scene.camera, size, size).unwrap(),
        true,
    );
    let opts = RenderOptions::new(size, size);
    let with = render_tile(&tr, &opts, spec_of(size), [0.0; 3]);
    let without = render_tile(
        &tr,
        &opts,
        TileSpec {
            mean_value: false,
            ..spec_of(size)
        },
        [0.0; 3],
    );
    assert!(with.state.stats.mean_value_tries > 0);
    assert_eq!(without.state.stats.mean_value_tries, 0);
    let hit = |o: &TileOut| o.depth.iter().map(|t| t.is_finite()).collect::<Vec<_>>();
    assert_eq!(hit(&with), hit(&without));
    assert!(hit(&with).iter().filter(|&&h| h).count() > 100);
}

// The whole `size`² image as one tile.
fn spec_of(size: u32) -> TileSpec<'static> {
    TileSpec::plain(0, 0, size, size)
}
