//! The cold mode: the `ibeam` binary a user gets from `cargo build
//! --release` (the x86-64 baseline, no CPU flags), run as a fresh process
//! per render, as users run it. Its render time is the `time_ms` of
//! `--stats-json` (native code compiles in the background during the
//! render, and whatever the render waits for is inside it); the process's
//! wall time adds start-up, parsing, lowering, building the evaluators and
//! writing the images.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::views::{View, camera_flags};

/// The repository root (the main crate), beside this folder.
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Builds the main crate's release binary as users build it and returns
/// its path. `RUSTFLAGS` is set empty and the build runs from the
/// repository root, so neither this workspace's `.cargo/config.toml`
/// (`target-cpu=haswell`) nor the caller's flags reach it.
pub fn build_default(target_dir: &Path) -> Result<PathBuf, String> {
    let root = repo_root();
    let status = Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
        .args(["build", "--release", "--bin", "ibeam"])
        .current_dir(&root)
        .env("RUSTFLAGS", "")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env("CARGO_TARGET_DIR", target_dir)
        .stdout(Stdio::null())
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("cargo build of {} failed", root.display()));
    }
    Ok(target_dir.join("release").join("ibeam"))
}

/// One cold render's figures.
#[derive(Clone, Debug, Default)]
pub struct ColdTimes {
    /// `time_ms` from `--stats-json`.
    pub time_ms: f64,
    /// The process's wall time, from start to exit, ms.
    pub wall_ms: f64,
    /// `compile_ms` from `--stats-json` (background compilation included).
    pub compile_ms: f64,
    /// `compile_wait_ms` from `--stats-json`: the render's time waiting
    /// for native code to compile, outside `time_ms` (NaN from a binary
    /// too old to report it).
    pub compile_wait_ms: f64,
    /// `output_ms` from `--stats-json`: encoding and writing the images,
    /// inside `time_ms` (the warm mode writes none).
    pub output_ms: f64,
    /// Pixels whose ray hit a surface.
    pub hit: u64,
}

/// Why a cold render gave no figures.
#[derive(Clone, Debug)]
pub enum ColdError {
    /// Still running at the time limit (killed).
    Timeout,
    /// It failed; the message says how.
    Failed(String),
}

/// One cold render of a scene file: what to run and where to write.
#[derive(Clone, Debug)]
pub struct ColdRender<'a> {
    /// The default-build binary.
    pub exe: &'a Path,
    /// The scene (`.ib`) or model (`.vm`).
    pub scene: &'a Path,
    /// Where it is seen from.
    pub view: View,
    /// Whether depth and normals are written (3D workloads).
    pub layers: bool,
    /// Image side.
    pub size: u32,
    /// Render threads.
    pub threads: usize,
    /// Folder of the images and the stats; the normal map (or the colour
    /// image of a flat model) is `{stem}.png`.
    pub out: &'a Path,
    /// File stem of this render's outputs.
    pub stem: &'a str,
    /// `--enclosure`'s value.
    pub enclosure: &'a str,
}

impl ColdRender<'_> {
    /// Runs `ibeam render` with the benchmark's flags once, up to `limit`.
    pub fn run(&self, limit: Duration) -> Result<ColdTimes, ColdError> {
        let file = |suffix: &str| self.out.join(format!("{}{suffix}", self.stem));
        let stats = file("-stats.json");
        let _ = std::fs::remove_file(&stats);
        let mut cmd = Command::new(self.exe);
        cmd.arg("render")
            .arg(self.scene)
            .arg("-o")
            .arg(file(if self.layers { "-colour.png" } else { ".png" }))
            .args(["--size", &format!("{0}x{0}", self.size)])
            .args(["--threads", &self.threads.to_string()])
            .args(["--no-shadows", "--quiet", "--enclosure", self.enclosure])
            .arg("--stats-json")
            .arg(&stats)
            .args(camera_flags(self.view));
        if self.layers {
            cmd.arg("--depth").arg(file("-depth.png"));
            cmd.arg("--normals").arg(file(".png"));
        }
        let wall_ms = run_timed(&mut cmd, limit)?;
        let text = std::fs::read_to_string(&stats)
            .map_err(|e| ColdError::Failed(format!("no stats: {e}")))?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| ColdError::Failed(format!("bad stats: {e}")))?;
        Ok(ColdTimes {
            time_ms: v["time_ms"].as_f64().unwrap_or(f64::NAN),
            wall_ms,
            compile_ms: v["compile_ms"].as_f64().unwrap_or(f64::NAN),
            compile_wait_ms: v["compile_wait_ms"].as_f64().unwrap_or(f64::NAN),
            output_ms: v["output_ms"].as_f64().unwrap_or(f64::NAN),
            hit: v["pixels_hit"].as_u64().unwrap_or(0),
        })
    }
}

/// The wall time of a default `ibeam render MODEL -o OUT --size SxS`: the
/// scene's own light with its shadows, the `.vm` default framing, the PNG
/// written; nothing else asked for. Returns ms.
pub fn default_render(exe: &Path, model: &Path, out: &Path, size: u32) -> Result<f64, ColdError> {
    let mut cmd = Command::new(exe);
    cmd.arg("render")
        .arg(model)
        .arg("-o")
        .arg(out)
        .args(["--size", &format!("{size}x{size}")]);
    run_timed(&mut cmd, Duration::from_secs(600))
}

/// Runs `cmd` to its end (killed past `limit`) and returns its wall time.
fn run_timed(cmd: &mut Command, limit: Duration) -> Result<f64, ColdError> {
    cmd.stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    let t0 = Instant::now();
    let mut child = cmd
        .spawn()
        .map_err(|e| ColdError::Failed(format!("cannot start ibeam: {e}")))?;
    // Polled rather than waited on, so a render past the limit can be
    // killed; the poll's granularity (0.2 ms) is far below the times.
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if t0.elapsed() > limit => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(ColdError::Timeout);
            }
            Ok(None) => std::thread::sleep(Duration::from_micros(200)),
            Err(e) => return Err(ColdError::Failed(e.to_string())),
        }
    };
    let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
    if !status.success() {
        let mut err = String::new();
        if let Some(mut s) = child.stderr.take() {
            use std::io::Read;
            let _ = s.read_to_string(&mut err);
        }
        return Err(ColdError::Failed(format!(
            "ibeam render: {status}: {}",
            err.trim()
        )));
    }
    Ok(wall_ms)
}
