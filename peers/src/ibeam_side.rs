//! ibeam's side. Each workload is rendered in a child process (this binary
//! with `--worker`), so that a render past the time limit can be stopped by
//! killing the child; the child keeps its scene and evaluators between
//! renders, so native code is compiled once, in the first render, and
//! reported apart from the render time.
//!
//! Protocol: the child prints `ready {json}` once loaded, then answers each
//! line on its stdin (`render`, or `save PATH` to also write the image) with
//! one line `{json}` of times; any failure is one line `error MESSAGE`.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

use ibeam::eval::{EvalKind, build_evaluators};
use ibeam::render::{Enclosure, RenderOptions, render};
use ibeam::scene::Scene;

use crate::views::{View, camera};
use crate::workloads::{Workload, sphere_centres, spheres_scene};

/// What the child needs to know to build its workload.
#[derive(Clone, Debug)]
pub struct WorkerSpec {
    /// The workload.
    pub workload: Workload,
    /// Where it is seen from.
    pub view: View,
    /// Image side in pixels.
    pub size: u32,
    /// Render threads.
    pub threads: usize,
    /// Folder holding prospero.vm and colonnade.vm.
    pub models: PathBuf,
    /// Seed of the random spheres.
    pub seed: u64,
    /// ibeam's enclosure choice by its `--enclosure` name.
    pub enclosure: String,
}

impl WorkerSpec {
    fn args(&self) -> Vec<String> {
        vec![
            "--worker".into(),
            self.workload.name(),
            "--worker-view".into(),
            self.view.name().into(),
            "--size".into(),
            self.size.to_string(),
            "--threads".into(),
            self.threads.to_string(),
            "--models".into(),
            self.models.display().to_string(),
            "--seed".into(),
            self.seed.to_string(),
            "--enclosure".into(),
            self.enclosure.clone(),
        ]
    }
}

/// Loads the workload's scene, seen as Fidget sees it, without shadows.
pub fn load(spec: &WorkerSpec) -> Result<Scene, String> {
    let mut scene = match (&spec.workload, spec.workload.vm_file()) {
        (_, Some(file)) => {
            ibeam::lang::load_scene(&spec.models.join(file)).map_err(|e| e.to_string())?
        }
        (Workload::Spheres(n), None) => {
            let text = spheres_scene(&sphere_centres(*n, spec.seed));
            ibeam::lang::load_scene_source("spheres.ib", &text).map_err(|e| e.to_string())?
        }
        _ => unreachable!("every workload is a model or spheres"),
    };
    scene.camera = camera(spec.view);
    for light in &mut scene.lights {
        light.shadows = false;
    }
    Ok(scene)
}

/// The child's main loop (`--worker`). Returns the process exit code.
pub fn worker_main(spec: &WorkerSpec) -> i32 {
    let out = std::io::stdout();
    let mut out = out.lock();
    let t0 = Instant::now();
    let loaded = load(spec).and_then(|scene| {
        let evals = build_evaluators(&scene, EvalKind::Jit).map_err(|e| format!("{e:?}"))?;
        Ok((scene, evals))
    });
    let (scene, evals) = match loaded {
        Ok(v) => v,
        Err(e) => {
            let _ = writeln!(out, "error {}", e.replace('\n', " | "));
            return 1;
        }
    };
    let load_ms = t0.elapsed().as_secs_f64() * 1e3;
    let _ = writeln!(out, "ready {}", serde_json::json!({ "load_ms": load_ms }));
    let _ = out.flush();

    let mut opts = RenderOptions::new(spec.size, spec.size);
    opts.threads = Some(spec.threads);
    opts.want_depth = !spec.workload.is_2d();
    opts.want_normals = !spec.workload.is_2d();
    opts.enclosure = match spec.enclosure.as_str() {
        "interval" => Enclosure::Interval,
        "affine" => Enclosure::Affine,
        _ => Enclosure::Auto,
    };
    // Only the images are kept, as Fidget's side keeps only its image.
    opts.want_buffers = false;

    for line in std::io::stdin().lock().lines() {
        let Ok(line) = line else { break };
        let save = line.strip_prefix("save ").map(PathBuf::from);
        let reply = match render(&scene, &evals, &opts) {
            Ok(r) => {
                if let Some(path) = save {
                    // The normal map is what Fidget's voxel image shows too.
                    let img = r.normals.as_ref().unwrap_or(&r.image);
                    if let Err(e) = img.save(&path) {
                        eprintln!("cannot write {}: {e}", path.display());
                    }
                }
                serde_json::json!({
                    "time_ms": r.stats.time_ms,
                    "compile_ms": r.stats.compile_ms,
                    "output_ms": r.stats.output_ms,
                    "trace_cpu_ms": r.stats.trace_cpu_ms,
                    "shade_cpu_ms": r.stats.shade_cpu_ms,
                    "hit": r.stats.pixels_hit,
                })
                .to_string()
            }
            Err(e) => format!("error {e:?}"),
        };
        let _ = writeln!(out, "{reply}");
        let _ = out.flush();
    }
    0
}

/// One render's figures, as the child reports them.
#[derive(Clone, Debug, Default)]
pub struct IbeamTimes {
    /// Render time without parsing and compiling, ms.
    pub time_ms: f64,
    /// Native code compiled during this render, ms.
    pub compile_ms: f64,
    /// Pixels whose ray hit a surface.
    pub hit: u64,
}

/// Why a child gave no answer.
#[derive(Clone, Debug)]
pub enum WorkerError {
    /// No answer within the time limit (the child has been killed).
    Timeout,
    /// The child failed or answered something else.
    Failed(String),
}

/// A running child for one workload.
pub struct Worker {
    child: Child,
    stdin: ChildStdin,
    lines: Receiver<String>,
    /// Parse, lowering and evaluator construction, ms.
    pub load_ms: f64,
}

impl Worker {
    /// Starts the child and waits (up to `limit`) until it has loaded.
    pub fn start(spec: &WorkerSpec, limit: Duration) -> Result<Worker, WorkerError> {
        let exe = std::env::current_exe().map_err(|e| WorkerError::Failed(e.to_string()))?;
        let mut child = Command::new(exe)
            .args(spec.args())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| WorkerError::Failed(format!("cannot start worker: {e}")))?;
        let stdin = child.stdin.take().expect("piped stdin");
        let stdout = child.stdout.take().expect("piped stdout");
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let mut w = Worker {
            child,
            stdin,
            lines: rx,
            load_ms: 0.0,
        };
        let line = w.answer(limit)?;
        let json = line
            .strip_prefix("ready ")
            .ok_or_else(|| WorkerError::Failed(line.clone()))?;
        w.load_ms = parse_json(json)?["load_ms"].as_f64().unwrap_or(f64::NAN);
        Ok(w)
    }

    /// Renders once (and writes the image to `save`), up to `limit`.
    pub fn render(
        &mut self,
        save: Option<&Path>,
        limit: Duration,
    ) -> Result<IbeamTimes, WorkerError> {
        let cmd = match save {
            Some(p) => format!("save {}\n", p.display()),
            None => "render\n".into(),
        };
        self.stdin
            .write_all(cmd.as_bytes())
            .and_then(|_| self.stdin.flush())
            .map_err(|e| WorkerError::Failed(format!("worker gone: {e}")))?;
        let line = self.answer(limit)?;
        let v = parse_json(&line)?;
        Ok(IbeamTimes {
            time_ms: v["time_ms"].as_f64().unwrap_or(f64::NAN),
            compile_ms: v["compile_ms"].as_f64().unwrap_or(f64::NAN),
            hit: v["hit"].as_u64().unwrap_or(0),
        })
    }

    fn answer(&mut self, limit: Duration) -> Result<String, WorkerError> {
        match self.lines.recv_timeout(limit) {
            Ok(line) if line.starts_with("error ") => Err(WorkerError::Failed(line[6..].into())),
            Ok(line) => Ok(line),
            Err(RecvTimeoutError::Timeout) => {
                self.kill();
                Err(WorkerError::Timeout)
            }
            Err(RecvTimeoutError::Disconnected) => Err(WorkerError::Failed(
                "worker exited without an answer".into(),
            )),
        }
    }

    fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.kill();
    }
}

fn parse_json(s: &str) -> Result<serde_json::Value, WorkerError> {
    serde_json::from_str(s).map_err(|e| WorkerError::Failed(format!("bad answer `{s}`: {e}")))
}
