use super::*;

fn cams() -> Vec<Camera> {
    vec![
        Camera::default(),
        Camera {
            eye: [0.3, -4.0, 1.0],
            target: [0.1, 0.2, -0.3],
            up: [0.0, 0.0, 1.0],
            projection: Projection::Orthographic { width: 3.0 },
        },
    ]
}

// A camera's tolerance made `f` times finer is that of the camera with
// `f` times the resolution (IAA's sub-samples at a coarse level take
// the finest level's), and roots are refined 16 times finer still.
#[test]
fn a_finer_tolerance_is_the_finer_cameras() {
    for cam in cams() {
        let coarse = RayCamera::new(&cam, 160, 120).unwrap();
        for f in [1u32, 2, 8] {
            let fine = RayCamera::new(&cam, 160 * f, 120 * f).unwrap();
            let scaled = coarse.with_tolerance_of_finer(f);
            for t in [0.5, 3.0, 40.0] {
                let (a, b) = (scaled.tolerance(t), fine.tolerance(t));
                assert!((a - b).abs() <= 1e-12 * b, "{f} {t}: {a} {b}");
                assert_eq!(scaled.spacing(t), coarse.spacing(t));
                let r = scaled.root_tolerance(t);
                assert!((r * ROOT_REFINEMENT - a).abs() <= 1e-12 * a, "{r} {a}");
            }
        }
    }
}

#[test]
fn shared_origins_or_directions_give_the_corners_hull_to_the_bit() {
    let mut rng = crate::ir::random::Rng::new(5);
    let perspective = Camera {
        eye: [1e3, -2e-3, 7.0],
        ..Camera::default()
    };
    let mut shortcuts = 0;
    for cam in cams().into_iter().chain([perspective]) {
        let rc = RayCamera::new(&cam, 640, 480).unwrap();
        for _ in 0..2000 {
            let x0 = rng.range(-50.0, 700.0);
            let y0 = rng.range(-50.0, 500.0);
            let c = rc.corners(
                (x0, x0 + rng.range(0.0, 64.0)),
                (y0, y0 + rng.range(0.0, 64.0)),
            );
            let a = rng.range(-3.0, 20.0);
            let t = Interval::new(a, a + rng.range(0.0, 10.0));
            assert_eq!(bits(&c.hull(t)), bits(&c.hull_of_corners(t)), "{t:?} {c:?}");
            let same = |k: usize| {
                c.rays
                    .iter()
                    .all(|r| bits(&[r.0, r.1][k]) == bits(&[c.rays[0].0, c.rays[0].1][k]))
            };
            shortcuts += usize::from(same(0) || same(1));
        }
    }
    // Both cameras' blocks take the shortcut (parallel rays share a
    // direction, a pinhole's an origin).
    assert!(shortcuts > 5000, "{shortcuts} of 6000");
}

#[test]
fn a_blocks_slab_range_holds_every_pixels_slab() {
    let mut rng = crate::ir::random::Rng::new(11);
    let perspective = Camera {
        eye: [0.5, -3.0, 2.0],
        ..Camera::default()
    };
    let bounds = crate::scene::Bounds {
        min: [-1.0, -0.5, -2.0],
        max: [1.5, 0.75, 0.25],
    };
    let (mut blocks, mut pixels) = (0, 0);
    for cam in cams().into_iter().chain([perspective]) {
        let rc = RayCamera::new(&cam, 96, 64).unwrap();
        for _ in 0..300 {
            let (x0, y0) = (rng.below(90) as u32, rng.below(60) as u32);
            let (x1, y1) = (x0 + 1 + rng.below(32) as u32, y0 + 1 + rng.below(32) as u32);
            let c = rc.corners(
                (f64::from(x0) + 0.5, f64::from(x1) - 0.5),
                (f64::from(y0) + 0.5, f64::from(y1) - 0.5),
            );
            let range = c.slab_range(&bounds);
            blocks += usize::from(range.is_some());
            for (i, j) in (x0..x1).flat_map(|i| (y0..y1).map(move |j| (i, j))) {
                if let Some((a, b)) = rc.pixel_ray(i, j).slab(&bounds) {
                    let r = range.expect("a block with a pixel in the bounds has a range");
                    assert!(r.lo <= a && b <= r.hi, "{r:?} misses ({a}, {b})");
                    pixels += 1;
                }
            }
        }
    }
    assert!(
        blocks > 300 && pixels > 10_000,
        "{blocks} blocks, {pixels} pixels"
    );
}

#[test]
fn a_tiles_rays_are_the_single_pixel_rays() {
    for cam in cams() {
        let rc = RayCamera::new(&cam, 37, 23).unwrap();
        let rays = rc.pixel_rays((5, 2), (9, 7));
        assert_eq!(rays.len(), 63);
        for j in 0..7 {
            for i in 0..9 {
                assert_eq!(rays[(j * 9 + i) as usize], rc.pixel_ray(5 + i, 2 + j));
            }
        }
    }
}

#[test]
fn a_grids_rays_and_corners_are_the_cameras_to_the_bit() {
    let perspective = Camera {
        eye: [1e3, -2e-3, 7.0],
        ..Camera::default()
    };
    for cam in cams().into_iter().chain([perspective]) {
        let rc = RayCamera::new(&cam, 37, 23).unwrap();
        let grid = RayGrid::new(&rc, (5, 2), (9, 7));
        for k in 0..63 {
            let (i, j) = (k as u32 % 9, k as u32 / 9);
            let (a, b) = (grid.ray_at_index(k), rc.pixel_ray(5 + i, 2 + j));
            assert_eq!((bits(&a.o), bits(&a.d)), (bits(&b.o), bits(&b.d)));
            assert_eq!(a.om.map(f64::to_bits), b.om.map(f64::to_bits));
        }
        for (i0, j0, i1, j1) in [(0, 0, 9, 7), (2, 3, 3, 4), (4, 1, 8, 7)] {
            let xs = (f64::from(5 + i0) + 0.5, f64::from(5 + i1) - 0.5);
            let ys = (f64::from(2 + j0) + 0.5, f64::from(2 + j1) - 0.5);
            let (a, b) = (grid.corners((i0, j0), (i1, j1)), rc.corners(xs, ys));
            for (p, q) in a.rays().iter().zip(b.rays()) {
                assert_eq!((bits(&p.0), bits(&p.1)), (bits(&q.0), bits(&q.1)));
            }
            let t = Interval::new(0.5, 9.0);
            assert_eq!(bits(&a.hull(t)), bits(&b.hull(t)));
        }
    }
}

#[test]
fn every_pixel_ray_point_lies_in_its_block_hull() {
    for cam in cams() {
        let rc = RayCamera::new(&cam, 37, 23).unwrap();
        let (x0, x1, y0, y1) = (3u32, 11u32, 5u32, 9u32);
        let t = Interval::new(1.25, 6.5);
        let h = rc.hull(
            (x0 as f64 + 0.5, x1 as f64 - 0.5),
            (y0 as f64 + 0.5, y1 as f64 - 0.5),
            t,
        );
        for i in x0..x1 {
            for j in y0..y1 {
                let r = rc.pixel_ray(i, j);
                for k in 0..=16 {
                    let tk = t.lo + (t.hi - t.lo) * k as f64 / 16.0;
                    let p = r.at(tk);
                    let b = crate::interval::boxes::ray_box(r.o, r.d, Interval::point(tk));
                    for c in 0..3 {
                        assert!(h[c].contains(p[c]), "{cam:?} {i} {j} {tk} {c}");
                        assert!(h[c].lo <= b[c].lo && b[c].hi <= h[c].hi);
                    }
                }
            }
        }
    }
}

#[test]
fn centre_ray_looks_at_target() {
    let rc = RayCamera::new(&Camera::default(), 64, 64).unwrap();
    let (_, d) = rc.ray_at(32.0, 32.0);
    let dm = d.map(|c| c.mid());
    let w = normalize(-DVec3::from_array(Camera::default().eye)).unwrap();
    let n = normalize(DVec3::from_array(dm)).unwrap();
    assert!((n.dot(w) - 1.0).abs() < 1e-12);
}

// Edge cases of the normalize contract (see its doc): zero, the
// smallest subnormals, huge and non-finite components; glam's own test
// agrees on all of them, bit for bit.
#[test]
fn normalize_refuses_exactly_zero_and_non_finite_lengths() {
    let tiny = f64::from_bits(1);
    let cases = [
        ([0.0, 0.0, 0.0], false),
        ([-0.0, 0.0, -0.0], false),
        ([tiny, 0.0, 0.0], false),
        ([1e-160, 0.0, 0.0], true),
        ([1e300, 1e300, 0.0], false),
        ([1e150, -1e150, 1e150], true),
        ([f64::INFINITY, 0.0, 0.0], false),
        ([f64::NAN, 1.0, 0.0], false),
        ([3.0, -4.0, 12.0], true),
    ];
    for (a, some) in cases {
        let a = DVec3::from_array(a);
        let n = normalize(a);
        assert_eq!(n.is_some(), some, "{a:?}");
        let g = a.try_normalize();
        assert_eq!(
            n.map(|v| v.to_array().map(f64::to_bits)),
            g.map(|v| v.to_array().map(f64::to_bits))
        );
    }
}

#[test]
fn degenerate_cameras_are_errors() {
    let mut c = Camera::default();
    c.target = c.eye;
    assert_eq!(RayCamera::new(&c, 8, 8), Err(CameraError::EyeIsTarget));
    let mut c = Camera::default();
    c.up = (DVec3::from_array(c.target) - DVec3::from_array(c.eye)).to_array();
    assert_eq!(RayCamera::new(&c, 8, 8), Err(CameraError::UpParallel));
    assert_eq!(
        RayCamera::new(&Camera::default(), 0, 8),
        Err(CameraError::ZeroSize)
    );
}

#[test]
fn slab_is_inside_bounds() {
    let rc = RayCamera::new(&Camera::default(), 16, 16).unwrap();
    let b = Bounds::default();
    let r = rc.pixel_ray(8, 8);
    let (t0, t1) = r.slab(&b).unwrap();
    assert!(t0 > 0.0 && t1 > t0);
    for t in [t0 + 1e-6, 0.5 * (t0 + t1), t1 - 1e-6] {
        let p = r.at(t);
        assert!(p.iter().all(|c| c.abs() <= 2.0 + 1e-6));
    }
}
