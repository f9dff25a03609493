//! `ibeam render` output formats, chosen by each file's extension:
//! 16-bit PNG, OpenEXR colour (linear), depth and normals, and the usage
//! errors of extensions it cannot write.

use std::path::Path;

use ibeam::render::output::srgb_u8;

use crate::common::stderr;
use crate::{assert_fails, example, render, scratch};

const SIZE: [&str; 2] = ["--size", "24x20"];

fn ok(o: &std::process::Output) {
    assert_eq!(o.status.code(), Some(0), "{}", stderr(o));
}

#[test]
fn png16_matches_the_8bit_render_within_rounding() {
    let dir = scratch("png16");
    let (a, b) = (dir.join("a.png"), dir.join("b.PNG"));
    ok(&render(&example("sphere.ib"), &a, &SIZE));
    ok(&render(
        &example("sphere.ib"),
        &b,
        &[&SIZE[..], &["--bit-depth", "16"]].concat(),
    ));
    let eight = image::open(&a).unwrap();
    let sixteen = image::open(&b).unwrap();
    assert_eq!(eight.color(), image::ColorType::Rgb8);
    assert_eq!(sixteen.color(), image::ColorType::Rgb16);
    let (eight, sixteen) = (eight.to_rgb8(), sixteen.to_rgb16());
    assert_eq!(eight.dimensions(), sixteen.dimensions());
    for (p8, p16) in eight.pixels().zip(sixteen.pixels()) {
        for c in 0..3 {
            let d = (i32::from(p16[c]) / 257 - i32::from(p8[c])).abs();
            assert!(d <= 1, "{p8:?} vs {p16:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn exr_holds_linear_colour_matching_the_png() {
    let dir = scratch("exr");
    let (png, exr) = (dir.join("a.png"), dir.join("a.EXR"));
    ok(&render(&example("sphere.ib"), &png, &SIZE));
    ok(&render(&example("sphere.ib"), &exr, &SIZE));
    let want = image::open(&png).unwrap().to_rgb8();
    let got = image::open(&exr).unwrap();
    assert_eq!(got.color(), image::ColorType::Rgb32F);
    let got = got.to_rgb32f();
    let mut mid_tones = 0;
    for (p8, pf) in want.pixels().zip(got.pixels()) {
        for c in 0..3 {
            let enc = srgb_u8(f64::from(pf[c]));
            assert!(
                (i32::from(enc) - i32::from(p8[c])).abs() <= 1,
                "{p8:?} vs {pf:?}"
            );
            // Linear, not sRGB-encoded: mid-tones sit well below code/255.
            if (0.05..0.8).contains(&pf[c]) && f32::from(p8[c]) / 255.0 - pf[c] > 0.05 {
                mid_tones += 1;
            }
        }
    }
    assert!(mid_tones > 10, "the EXR looks sRGB-encoded");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn depth_and_normals_exr_read_back() {
    let dir = scratch("exr-aux");
    let [c, d, n, d16] = ["c.png", "d.exr", "n.exr", "d.png"].map(|f| dir.join(f));
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let (ds, ns) = (s(&d), s(&n));
    ok(&render(
        &example("sphere.ib"),
        &c,
        &[&SIZE[..], &["--depth", &ds, "--normals", &ns]].concat(),
    ));
    ok(&render(
        &example("sphere.ib"),
        &c,
        &[&SIZE[..], &["--depth", &s(&d16)]].concat(),
    ));
    let depth = image::open(&d).unwrap().to_rgb32f();
    let normals = image::open(&n).unwrap().to_rgb32f();
    let coded = image::open(&d16).unwrap().to_luma16();
    let mut hits = 0;
    for ((dp, np), code) in depth.pixels().zip(normals.pixels()).zip(coded.pixels()) {
        let t = dp[0];
        assert_eq!((dp[1], dp[2]), (t, t));
        if code[0] == u16::MAX {
            // Background: +inf depth, zero normal.
            assert_eq!(t, f32::INFINITY);
            assert_eq!(np.0, [0.0; 3]);
        } else {
            hits += 1;
            // The eye is about 4.8 from the unit sphere's centre.
            assert!(t.is_finite() && (3.0..5.0).contains(&t), "depth {t}");
            let len = np.0.iter().map(|v| v * v).sum::<f32>().sqrt();
            assert!((len - 1.0).abs() < 1e-4, "normal {np:?}");
        }
    }
    assert!(hits > 50);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unsupported_extensions_fail_before_rendering() {
    let dir = scratch("bad-ext");
    let sphere = example("sphere.ib");
    let jpg = dir.join("picture.jpg");
    assert_fails(&render(&sphere, &jpg, &SIZE), &["`.jpg`", ".png, .exr"]);
    let bare = dir.join("out");
    assert_fails(
        &render(&sphere, &bare, &SIZE),
        &["no file extension", ".png, .exr"],
    );
    let png = dir.join("a.png");
    let tiff = dir.join("d.tiff");
    let o = render(
        &sphere,
        &png,
        &[&SIZE[..], &["--depth", tiff.to_str().unwrap()]].concat(),
    );
    assert_fails(&o, &["--depth", "`.tiff`"]);
    let k = dir.join("k.exr");
    let o = render(
        &sphere,
        &png,
        &[&SIZE[..], &["--classify", k.to_str().unwrap()]].concat(),
    );
    assert_fails(&o, &["--classify", "`.exr`", "supported: .png"]);
    let exr = dir.join("a.exr");
    assert_fails(
        &render(&sphere, &exr, &["--bit-depth", "16"]),
        &["--bit-depth 16"],
    );
    let o = render(&sphere, &png, &["--bit-depth", "12"]);
    assert_ne!(o.status.code(), Some(0));
    assert!(stderr(&o).contains("8 or 16"), "{}", stderr(&o));
    for p in [jpg, bare, png, tiff, k, exr] {
        assert!(!p.exists(), "{} was written", p.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn png_compression_levels_change_the_file_size_not_the_pixels() {
    let dir = scratch("png_compression");
    let size = ["--size", "96x80"];
    let mut decoded = Vec::new();
    let mut bytes = Vec::new();
    for level in ["fast", "balanced", "high"] {
        let (c, d) = (
            dir.join(format!("{level}.png")),
            dir.join(format!("{level}-d.png")),
        );
        let flags = [&size[..], &["--png-compression", level, "--depth"]].concat();
        let o = render(
            &example("csg.ib"),
            &c,
            &[&flags[..], &[d.to_str().unwrap()]].concat(),
        );
        ok(&o);
        decoded.push((image::open(&c).unwrap(), image::open(&d).unwrap()));
        bytes.push(std::fs::metadata(&c).unwrap().len());
    }
    for (c, d) in &decoded[1..] {
        assert_eq!(c.to_rgb8(), decoded[0].0.to_rgb8());
        assert_eq!(d.to_luma16(), decoded[0].1.to_luma16());
    }
    // A level that did not reach the encoder would leave the sizes equal.
    assert!(
        bytes[2] < bytes[0],
        "high {} bytes, fast {}",
        bytes[2],
        bytes[0]
    );
    let bad = render(
        &example("csg.ib"),
        &dir.join("x.png"),
        &[&size[..], &["--png-compression", "zip"]].concat(),
    );
    assert_eq!(bad.status.code(), Some(2), "a usage error");
    assert!(stderr(&bad).contains("zip"), "{}", stderr(&bad));
    let _ = std::fs::remove_dir_all(&dir);
}
