//! `ibeam render`'s camera flags (overrides, orbit, zoom, framing the
//! solid), shadow overrides and progress output, end to end.

use std::path::{Path, PathBuf};

use crate::common::stderr;
use crate::{assert_fails, example, render, scratch};

fn ok(o: &std::process::Output) {
    assert_eq!(o.status.code(), Some(0), "{}", stderr(o));
}

/// Renders `scene` at `size` with `extra` flags and returns the image.
fn image_of(scene: &Path, dir: &Path, size: &str, extra: &[&str]) -> image::RgbImage {
    let out = dir.join("v.png");
    ok(&render(
        scene,
        &out,
        &[&["--size", size][..], extra].concat(),
    ));
    image::open(&out).unwrap().to_rgb8()
}

/// The pixel bounding box (x0, y0, x1, y1) of what differs from the
/// top-left pixel (the background, in every scene here).
fn drawn_box(img: &image::RgbImage) -> (u32, u32, u32, u32) {
    let bg = *img.get_pixel(0, 0);
    let mut b = (u32::MAX, u32::MAX, 0, 0);
    for (x, y, p) in img.enumerate_pixels() {
        if *p != bg {
            b = (b.0.min(x), b.1.min(y), b.2.max(x + 1), b.3.max(y + 1));
        }
    }
    b
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn camera_overrides_replace_the_scenes_camera() {
    let dir = scratch("view-overrides");
    let sphere = example("sphere.ib");
    let base = image_of(&sphere, &dir, "24x24", &[]);
    // The scene's own camera, given as flags, is the same image.
    let same = [
        "--eye",
        "2.36,1.97,3.93",
        "--target",
        "0,0,0",
        "--up",
        "0,1,0",
        "--fov",
        "35",
    ];
    assert_eq!(image_of(&sphere, &dir, "24x24", &same), base);
    assert_ne!(image_of(&sphere, &dir, "24x24", &["--eye", "-4,1,0"]), base);
    assert_ne!(
        image_of(&sphere, &dir, "24x24", &["--target", "0.5,0,0"]),
        base
    );
    assert_ne!(image_of(&sphere, &dir, "24x24", &["--up", "1,1,0"]), base);
    let narrow = drawn_box(&image_of(&sphere, &dir, "24x24", &["--fov", "20"]));
    let wide = drawn_box(&image_of(&sphere, &dir, "24x24", &["--fov", "70"]));
    assert!(narrow.2 - narrow.0 > wide.2 - wide.0, "{narrow:?} {wide:?}");
    // An orthographic view 4 wide shows the sphere (2 across) at half width.
    let o = drawn_box(&image_of(&sphere, &dir, "40x40", &["--ortho", "4"]));
    assert!((18..=22).contains(&(o.2 - o.0)), "{o:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn orbit_and_zoom_move_the_eye_about_the_target() {
    let dir = scratch("view-orbit");
    let sphere = example("sphere.ib");
    let base = image_of(&sphere, &dir, "24x24", &[]);
    assert_eq!(image_of(&sphere, &dir, "24x24", &["--orbit", "0,0"]), base);
    assert_eq!(image_of(&sphere, &dir, "24x24", &["--zoom", "1"]), base);
    // The lights stay put, so turning the eye changes the shading.
    assert_ne!(
        image_of(&sphere, &dir, "24x24", &["--orbit", "-90,10"]),
        base
    );
    let near = drawn_box(&image_of(&sphere, &dir, "24x24", &["--zoom", "2"]));
    let far = drawn_box(&base);
    assert!(near.2 - near.0 > far.2 - far.0, "{near:?} {far:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A sphere of radius 0.2 off centre in wide bounds, seen from far away.
const SMALL_SPHERE: &str = "object s = (x - 1)^2 + (y + 0.5)^2 + z^2 - 0.04;\n\
    camera { eye = (0, 0, 30); target = (0, 0, 0); up = (0, 1, 0); fov = 40; }\n\
    bounds = (-3, -3, -3) .. (3, 3, 3);\n";

#[test]
fn fit_frames_the_solid_at_about_80_percent() {
    let dir = scratch("view-fit");
    let scene = write(&dir, "small.ib", SMALL_SPHERE);
    let before = drawn_box(&image_of(&scene, &dir, "50x50", &[]));
    assert!(before.2 - before.0 < 5, "{before:?}");
    // The box around the solid fills 80% of the view: seen straight on
    // and orthographic, the sphere does (40 of 50 pixels); in perspective
    // the box's front face does, and the sphere behind it a little less.
    for (extra, fill) in [
        (&["--fit", "--ortho", "1"][..], 37..=42),
        (&["--fit"], 28..=36),
    ] {
        let b = drawn_box(&image_of(&scene, &dir, "50x50", extra));
        let (w, h) = (b.2 - b.0, b.3 - b.1);
        assert!(fill.contains(&w) && fill.contains(&h), "{extra:?}: {b:?}");
        // Centred.
        assert!(
            b.0.abs_diff(50 - b.2) <= 2 && b.1.abs_diff(50 - b.3) <= 2,
            "{b:?}"
        );
    }
    // An orbit picks the direction, the fit the distance; zoom applies
    // last (twice as far: about half as wide).
    let turned = ["--fit", "--orbit", "60,20"];
    let b = drawn_box(&image_of(&scene, &dir, "50x50", &turned));
    assert!(
        b.0.abs_diff(50 - b.2) <= 2 && (20..=40).contains(&(b.2 - b.0)),
        "{b:?}"
    );
    let z = drawn_box(&image_of(
        &scene,
        &dir,
        "50x50",
        &[&turned[..], &["--zoom", "0.5"]].concat(),
    ));
    assert!((2 * (z.2 - z.0)).abs_diff(b.2 - b.0) <= 4, "{b:?} {z:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Fidget's `.vm` text of a sphere of radius 0.25 centred at (0.5, 0.5, 0).
const SMALL_VM: &str = "_0 var-x\n_1 const 0.5\n_2 sub _0 _1\n_3 square _2\n\
    _4 var-y\n_5 sub _4 _1\n_6 square _5\n_7 var-z\n_8 square _7\n\
    _9 add _3 _6\n_a add _9 _8\n_b const 0.0625\n_c sub _a _b\n";

#[test]
fn vm_models_are_framed_unless_a_camera_flag_is_given() {
    let dir = scratch("view-vm");
    let model = write(&dir, "ball.vm", SMALL_VM);
    // Seen along a diagonal, the ball's box fills 80% of the view and the
    // ball about half of it, centred.
    let framed = drawn_box(&image_of(&model, &dir, "40x40", &[]));
    assert!((15..=24).contains(&(framed.2 - framed.0)), "{framed:?}");
    assert!(framed.0.abs_diff(40 - framed.2) <= 2, "{framed:?}");
    // The model's default camera frames the whole [-1, 1] cube instead.
    for extra in [&["--no-fit"][..], &["--fov", "40"]] {
        let b = drawn_box(&image_of(&model, &dir, "40x40", extra));
        assert!(
            (b.2 - b.0) * 3 < (framed.2 - framed.0) * 2,
            "{extra:?}: {b:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn degenerate_views_are_errors_not_panics() {
    let dir = scratch("view-bad");
    let sphere = example("sphere.ib");
    let out = dir.join("x.png");
    let run = |extra: &[&str]| render(&sphere, &out, &[&["--size", "8x8"][..], extra].concat());
    assert_fails(
        &run(&["--eye", "1,1,1", "--target", "1,1,1"]),
        &["bad camera", "eye equals target"],
    );
    assert_fails(
        &run(&["--eye", "0,5,0", "--target", "0,0,0"]),
        &["bad camera", "parallel"],
    );
    assert_fails(&run(&["--up", "0,0,0"]), &["bad camera", "up"]);
    assert_fails(
        &run(&["--eye", "0,0,5", "--orbit", "0,90"]),
        &["after --orbit", "parallel"],
    );
    for (flag, value, needle) in [
        ("--fov", "0", "between 0 and 180"),
        ("--fov", "180", "between 0 and 180"),
        ("--ortho", "0", "positive"),
        ("--zoom", "-2", "positive"),
        ("--eye", "1,2", "expected 3"),
        ("--orbit", "a,b", "not a list of numbers"),
    ] {
        let o = run(&[flag, value]);
        assert_ne!(o.status.code(), Some(0), "{flag} {value}");
        assert!(
            stderr(&o).contains(needle),
            "{flag} {value}: {}",
            stderr(&o)
        );
    }
    for both in [&["--fov", "30", "--ortho", "2"][..], &["--fit", "--no-fit"]] {
        assert!(
            stderr(&run(both)).contains("cannot be used with"),
            "{both:?}"
        );
    }
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A ball over a slab, lit from above by a light that casts no shadow.
const SHADOWED: &str = "object ball = x^2 + (y - 0.6)^2 + z^2 - 0.16 { color = (0.9, 0.9, 0.9); }\n\
    object slab = max(abs(y + 0.5) - 0.1, max(abs(x), abs(z)) - 1.5) { color = (0.9, 0.9, 0.9); }\n\
    camera { eye = (0, 3, 4); target = (0, 0, 0); up = (0, 1, 0); fov = 45; }\n\
    light { direction = (0, -1, 0); color = (1, 1, 1); shadows = false; }\n\
    bounds = (-2, -2, -2) .. (2, 2, 2);\n";

#[test]
fn shadow_flags_override_every_light() {
    let dir = scratch("view-shadows");
    let scene = write(&dir, "shadowed.ib", SHADOWED);
    let base = image_of(&scene, &dir, "32x32", &[]);
    assert_eq!(image_of(&scene, &dir, "32x32", &["--no-shadows"]), base);
    let shadowed = image_of(&scene, &dir, "32x32", &["--shadows"]);
    assert_ne!(shadowed, base);
    // The shadow darkens the slab under the ball, never brightens it.
    let sum = |img: &image::RgbImage| img.pixels().map(|p| u64::from(p[0])).sum::<u64>();
    assert!(sum(&shadowed) < sum(&base));
    let o = render(&scene, &dir.join("x.png"), &["--shadows", "--no-shadows"]);
    assert!(stderr(&o).contains("cannot be used with"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

// Stderr is a pipe here: the summary is printed, but no progress bar.
#[test]
fn no_progress_bar_when_stderr_is_not_a_terminal() {
    let dir = scratch("view-progress");
    let out = dir.join("p.png");
    let o = crate::common::ibeam(&[
        "render",
        example("sphere.ib").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "64x64",
        "--eval",
        crate::EVAL,
    ]);
    ok(&o);
    let err = stderr(&o);
    assert!(
        !err.contains('\r') && !err.contains("ETA") && !err.contains('\u{1b}'),
        "{err}"
    );
    assert!(!err.is_empty(), "the summary is missing");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn quiet_prints_nothing_and_fit_without_a_solid_warns() {
    let dir = scratch("view-quiet");
    let out = dir.join("q.png");
    let o = render(&example("sphere.ib"), &out, &["--size", "16x16"]);
    ok(&o);
    assert_eq!(stderr(&o), "");
    // Nothing inside the bounds: --fit keeps the camera and says why.
    let scene = write(&dir, "far.ib", "object s = (x - 9)^2 + y^2 + z^2 - 1;\n");
    let o = crate::common::ibeam(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--size",
        "16x16",
        "--eval",
        crate::EVAL,
        "--fit",
    ]);
    ok(&o);
    assert!(stderr(&o).contains("nothing to frame"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}
