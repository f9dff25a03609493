//! `IBEAM_CPU=baseline` forces the tape passes' baseline code
//! (`src/eval/cpu.rs`): a render gives the same bytes as on the path the
//! CPU picks.

use std::process::Command;

use crate::scratch;

#[test]
fn the_baseline_path_renders_the_same_bytes() {
    let dir = scratch("cpu_paths");
    // A union large enough that pruned tapes answer most evaluations.
    let mut scene = String::from("object balls = union(\n");
    for i in 0..60 {
        let t = f64::from(i) * 0.7;
        let (x, y, z) = (0.8 * t.sin(), 0.8 * (1.3 * t).cos(), 0.8 * (0.7 * t).sin());
        scene += &format!("    translate(sphere(0.09), {x:.4}, {y:.4}, {z:.4}),\n");
    }
    scene += ");\n";
    let file = dir.join("balls.ib");
    std::fs::write(&file, scene).unwrap();
    let mut images = Vec::new();
    for (cpu, name) in [(None, "picked"), (Some("baseline"), "baseline")] {
        let out = dir.join(format!("{name}.png"));
        let depth = dir.join(format!("{name}-d.png"));
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_ibeam"));
        cmd.args([
            "render",
            file.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(["--depth", depth.to_str().unwrap(), "--size", "96x96"])
        .args(["--eval", "interp", "--quiet"]);
        match cpu {
            Some(v) => cmd.env("IBEAM_CPU", v),
            None => cmd.env_remove("IBEAM_CPU"),
        };
        let o = cmd.output().unwrap();
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        images.push((std::fs::read(&out).unwrap(), std::fs::read(&depth).unwrap()));
    }
    assert!(
        images[0] == images[1],
        "the two paths drew different images"
    );
    let hit = image::load_from_memory(&images[0].0).unwrap().to_rgb8();
    let background = *hit.get_pixel(0, 0);
    assert!(
        hit.pixels().filter(|&&p| p != background).count() > 500,
        "too little surface drawn to compare"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
