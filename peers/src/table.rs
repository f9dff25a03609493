//! The figures of a run and the table and CSV made from them.

use std::fmt::Write as _;

use crate::cold::ColdTimes;
use crate::views::View;
use crate::workloads::Workload;

/// What happened to one ibeam mode on one case.
#[derive(Clone, Debug)]
pub enum Outcome<T> {
    /// It rendered; the best figures.
    Done(T),
    /// Not run (too big without `--all`, or the mode is off).
    Skipped,
    /// Killed at `--timeout`.
    Timeout,
    /// It failed; the message says how.
    Failed(String),
}

impl<T> Outcome<T> {
    /// The figures, if it rendered.
    pub fn done(&self) -> Option<&T> {
        match self {
            Outcome::Done(t) => Some(t),
            _ => None,
        }
    }

    /// The table's cell for anything but figures.
    fn status(&self, timeout: f64) -> String {
        match self {
            Outcome::Done(_) => "ok".into(),
            Outcome::Skipped => "skipped".into(),
            Outcome::Timeout => format!("timeout (>{timeout} s)"),
            Outcome::Failed(_) => "failed".into(),
        }
    }
}

/// Fidget's best render of a case.
#[derive(Clone, Debug)]
pub struct FidgetFigures {
    /// Best render, ms.
    pub best_ms: f64,
    /// Reading or building the expression and the `JitShape`, ms.
    pub build_ms: f64,
    /// Pixels inside (2D) or with a surface (3D).
    pub hit: u64,
}

/// The warm child's figures (the AVX2 build, scene kept between reps).
#[derive(Clone, Debug)]
pub struct WarmFigures {
    /// Best `time_ms`.
    pub best_ms: f64,
    /// Native code compiled over all its renders, ms.
    pub compile_ms: f64,
    /// Parsing, lowering and building the evaluators, ms.
    pub load_ms: f64,
    /// Pixels hit.
    pub hit: u64,
}

/// The cold mode's figures (default build, a process per render).
#[derive(Clone, Debug)]
pub struct ColdFigures {
    /// Best `time_ms`.
    pub best_ms: f64,
    /// Best process wall time, ms.
    pub best_wall_ms: f64,
    /// `compile_ms` of the render with the best `time_ms`.
    pub compile_ms: f64,
    /// `compile_wait_ms` of the render with the best `time_ms`.
    pub compile_wait_ms: f64,
    /// `output_ms` of the render with the best `time_ms`.
    pub output_ms: f64,
    /// Pixels hit.
    pub hit: u64,
}

/// `best` updated with one more cold render.
pub fn best_cold(best: Option<ColdFigures>, t: &ColdTimes) -> ColdFigures {
    match best {
        None => ColdFigures {
            best_ms: t.time_ms,
            best_wall_ms: t.wall_ms,
            compile_ms: t.compile_ms,
            compile_wait_ms: t.compile_wait_ms,
            output_ms: t.output_ms,
            hit: t.hit,
        },
        Some(b) => {
            let faster = t.time_ms < b.best_ms;
            ColdFigures {
                best_ms: b.best_ms.min(t.time_ms),
                best_wall_ms: b.best_wall_ms.min(t.wall_ms),
                compile_ms: if faster { t.compile_ms } else { b.compile_ms },
                compile_wait_ms: if faster {
                    t.compile_wait_ms
                } else {
                    b.compile_wait_ms
                },
                output_ms: if faster { t.output_ms } else { b.output_ms },
                hit: t.hit,
            }
        }
    }
}

/// One line of the table: a workload seen from one view.
#[derive(Clone, Debug)]
pub struct Row {
    /// The workload.
    pub workload: Workload,
    /// Its view.
    pub view: View,
    /// Fidget's figures.
    pub fidget: Result<FidgetFigures, String>,
    /// ibeam in the warm child.
    pub warm: Outcome<WarmFigures>,
    /// ibeam as a cold process of the default build.
    pub cold: Outcome<ColdFigures>,
}

/// The default render of a flat model, whole processes against Fidget's
/// parse, build and frame.
#[derive(Clone, Debug)]
pub struct FlatRow {
    /// Fidget's parse + `JitShape` + one frame, best, ms.
    pub fidget_ms: Result<f64, String>,
    /// The `ibeam render` process's best wall time, ms.
    pub ibeam_ms: Outcome<f64>,
}

/// One line for the progress log.
pub fn describe(row: &Row) -> String {
    let f = match &row.fidget {
        Ok(f) => format!("Fidget {:.1} ms", f.best_ms),
        Err(e) => format!("Fidget failed: {e}"),
    };
    let mode = |name: &str, o: Option<f64>, out: String| match o {
        Some(ms) => format!("ibeam {name} {ms:.1} ms"),
        None => format!("ibeam {name} {out}"),
    };
    let w = mode(
        "warm",
        row.warm.done().map(|w| w.best_ms),
        failure(&row.warm),
    );
    let c = mode(
        "cold",
        row.cold.done().map(|c| c.best_ms),
        failure(&row.cold),
    );
    format!("{f}, {w}, {c}")
}

fn failure<T>(o: &Outcome<T>) -> String {
    match o {
        Outcome::Failed(e) => format!("failed: {e}"),
        o => o.status(0.0),
    }
}

fn label(w: &Workload, view: View, size: u32) -> String {
    let what = match w {
        Workload::Prospero => format!("prospero 2D {size}²"),
        Workload::Colonnade => format!("colonnade {size}²"),
        Workload::Spheres(n) => format!("{n} spheres {size}²"),
    };
    match (w.is_2d(), view) {
        (true, _) => what,
        (false, View::Top) => format!("{what}, from above"),
        (false, View::Corner) => format!("{what}, corner"),
    }
}

fn ratio(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => format!("{:.2}", a / b),
        _ => String::new(),
    }
}

fn ms(v: Option<f64>) -> String {
    v.map(|v| format!("{v:.1}")).unwrap_or_default()
}

/// A figure, or the outcome's status when there is none.
fn cell<T>(o: &Outcome<T>, v: impl Fn(&T) -> f64, timeout: f64) -> String {
    match o.done() {
        Some(t) => format!("{:.1}", v(t)),
        None => o.status(timeout),
    }
}

/// The results as Markdown: the render table, then the flat model's
/// default render.
pub fn markdown(rows: &[Row], flat: Option<&FlatRow>, size: u32, timeout: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| workload, view | Fidget ms | warm ms | warm/Fidget | cold ms | cold/Fidget | cold/warm | cold/warm, images' output left out | cold process ms | compile ms warm / cold (cold waited) | hit px Fidget / warm / cold |"
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let f = r.fidget.as_ref().ok();
        let fms = f.map(|f| f.best_ms);
        let (w, c) = (r.warm.done(), r.cold.done());
        let (wms, cms) = (w.map(|w| w.best_ms), c.map(|c| c.best_ms));
        let hit = |h: Option<u64>| h.map(|h| h.to_string()).unwrap_or_default();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} / {} ({}) | {} / {} / {} |",
            label(&r.workload, r.view, size),
            fms.map_or("failed".into(), |v| format!("{v:.1}")),
            cell(&r.warm, |w| w.best_ms, timeout),
            ratio(wms, fms),
            cell(&r.cold, |c| c.best_ms, timeout),
            ratio(cms, fms),
            ratio(cms, wms),
            ratio(c.map(|c| c.best_ms - c.output_ms), wms),
            ms(c.map(|c| c.best_wall_ms)),
            ms(w.map(|w| w.compile_ms)),
            ms(c.map(|c| c.compile_ms)),
            ms(c.map(|c| c.compile_wait_ms)),
            hit(f.map(|f| f.hit)),
            hit(w.map(|w| w.hit)),
            hit(c.map(|c| c.hit)),
        );
    }
    if let Some(flat) = flat {
        let fms = flat.fidget_ms.as_ref().ok().copied();
        let _ = writeln!(
            s,
            "\n| default render of a flat model | Fidget parse + JitShape + frame ms | `ibeam render prospero.vm -o p.png --size {size}x{size}` process ms | ibeam/Fidget |"
        );
        let _ = writeln!(s, "|---|---:|---:|---:|");
        let _ = writeln!(
            s,
            "| prospero {size}² | {} | {} | {} |",
            fms.map_or("failed".into(), |v| format!("{v:.1}")),
            cell(&flat.ibeam_ms, |v| *v, timeout),
            ratio(flat.ibeam_ms.done().copied(), fms),
        );
    }
    s
}

/// The results as CSV, every figure.
pub fn csv(rows: &[Row], size: u32, reps: u32, threads: usize) -> String {
    let mut s = String::from(
        "workload,view,size,reps,threads,fidget_ms,fidget_build_ms,fidget_hit,\
         warm_status,warm_ms,warm_compile_ms,warm_load_ms,warm_hit,\
         cold_status,cold_ms,cold_process_ms,cold_compile_ms,cold_compile_wait_ms,cold_output_ms,cold_hit\n",
    );
    let opt = |v: Option<String>| v.unwrap_or_default();
    for r in rows {
        let f = r.fidget.as_ref().ok();
        let (w, c) = (r.warm.done(), r.cold.done());
        let _ = writeln!(
            s,
            "{},{},{size},{reps},{threads},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.workload.name(),
            r.view.name(),
            opt(f.map(|f| f.best_ms.to_string())),
            opt(f.map(|f| f.build_ms.to_string())),
            opt(f.map(|f| f.hit.to_string())),
            r.warm.status(0.0).split(' ').next().unwrap_or(""),
            opt(w.map(|w| w.best_ms.to_string())),
            opt(w.map(|w| w.compile_ms.to_string())),
            opt(w.map(|w| w.load_ms.to_string())),
            opt(w.map(|w| w.hit.to_string())),
            r.cold.status(0.0).split(' ').next().unwrap_or(""),
            opt(c.map(|c| c.best_ms.to_string())),
            opt(c.map(|c| c.best_wall_ms.to_string())),
            opt(c.map(|c| c.compile_ms.to_string())),
            opt(c.map(|c| c.compile_wait_ms.to_string())),
            opt(c.map(|c| c.output_ms.to_string())),
            opt(c.map(|c| c.hit.to_string())),
        );
    }
    s
}
