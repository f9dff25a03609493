//! `ibeam watch`: renders a scene, then again each time the scene file or
//! a file it imports is saved, first a quick preview and then the full
//! image, until Ctrl-C.
//!
//! The folders of the files are watched rather than the files, because
//! many editors save by writing a new file and renaming it over the old
//! one, which ends a watch on the old file. Events are read for the files
//! of the last load only (so the images written beside the scene do not
//! trigger renders), and a burst of them (an editor's several writes)
//! gives one render once the files have been quiet for [`QUIET`].
//! Every image is written to a temporary file beside its destination and
//! renamed over it, so the output is always a whole PNG; Ctrl-C removes a
//! temporary file in progress and exits with code 0.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use notify::event::{AccessKind, AccessMode};
use notify::{EventKind, RecursiveMode, Watcher};

use super::CliError;
use super::render;
use ibeam::scene::Scene;

/// How long the files must be quiet after a change before the render
/// starts: long enough to cover an editor's write-rename-chmod burst,
/// short enough not to be noticed.
const QUIET: Duration = Duration::from_millis(150);

/// Arguments of `ibeam watch`: those of `ibeam render`, plus the preview.
#[derive(clap::Args, Debug)]
// clap names a flattened struct's group after the type; both are `Args`.
#[group(id = "watch_args")]
pub struct Args {
    /// What to render and how, as for `ibeam render`.
    #[command(flatten)]
    pub render: render::Args,
    /// Each side of the quick preview written before every full image is
    /// this many times smaller (1: no preview); it costs about 1/N² of a
    /// full render.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub preview: u32,
}

/// Temporary files being written, removed by the Ctrl-C handler.
#[derive(Default)]
struct InFlight {
    temps: Vec<PathBuf>,
    stopping: bool,
}

type Shared = Arc<Mutex<InFlight>>;

/// Runs `ibeam watch` until Ctrl-C.
pub fn run(args: &Args) -> Result<(), CliError> {
    let in_flight: Shared = Arc::default();
    let handler_state = Arc::clone(&in_flight);
    ctrlc::set_handler(move || {
        let mut s = handler_state.lock().unwrap_or_else(PoisonError::into_inner);
        s.stopping = true;
        for t in s.temps.drain(..) {
            let _ = std::fs::remove_file(t);
        }
        // The lock is held on purpose: no render registers a new
        // temporary file between here and the exit.
        std::process::exit(0);
    })
    .map_err(|e| format!("cannot install the Ctrl-C handler: {e}"))?;

    let (tx, rx) = channel();
    let mut watcher = notify::recommended_watcher(move |event| {
        let _ = tx.send(event);
    })
    .map_err(|e| format!("cannot watch files: {e}"))?;
    // The main file's folder is watched before the first load, so a save
    // while it loads is not missed.
    let mut files = vec![ibeam::lang::imports::file_identity(&args.render.file)];
    let mut dirs: BTreeSet<PathBuf> = BTreeSet::new();
    watch_folders(&mut watcher, &mut dirs, &files);
    let quiet = args.render.quiet;
    loop {
        let loaded = ibeam::lang::load_scene_with_files(&args.render.file);
        // A failed load may have stopped before some imports: the files of
        // the last good load stay watched, so fixing any of them re-renders.
        if loaded.scene.is_ok() {
            files.clear();
        }
        for f in loaded.files {
            if !files.contains(&f) {
                files.push(f);
            }
        }
        watch_folders(&mut watcher, &mut dirs, &files);
        match loaded.scene {
            Err(e) => eprintln!("{e}"),
            Ok(scene) => {
                if let Err(e) = render_twice(args, &scene, &in_flight) {
                    eprintln!("{e}");
                }
            }
        }
        if !quiet {
            eprintln!(
                "watching {} file{} for changes (Ctrl-C to stop)",
                files.len(),
                if files.len() == 1 { "" } else { "s" }
            );
        }
        wait_for_change(&rx, &files)?;
    }
}

/// Watches the folder of each file (and stops watching folders no file is
/// in any more). A folder that cannot be watched (a missing import's
/// missing folder) is left out: the load reports the real problem.
pub(super) fn watch_folders(
    watcher: &mut impl Watcher,
    dirs: &mut BTreeSet<PathBuf>,
    files: &[PathBuf],
) {
    let wanted: BTreeSet<PathBuf> = files
        .iter()
        .filter_map(|f| f.parent().map(Path::to_path_buf))
        .collect();
    for gone in dirs.difference(&wanted) {
        let _ = watcher.unwatch(gone);
    }
    dirs.retain(|d| wanted.contains(d));
    for d in wanted {
        if !dirs.contains(&d) && watcher.watch(&d, RecursiveMode::NonRecursive).is_ok() {
            dirs.insert(d);
        }
    }
}

/// Blocks until an event touches one of `files`, then until events have
/// stopped for [`QUIET`].
pub(super) fn wait_for_change(
    rx: &Receiver<notify::Result<notify::Event>>,
    files: &[PathBuf],
) -> Result<(), CliError> {
    let relevant = |event: notify::Result<notify::Event>| match event {
        Ok(e) => touches(&e, files),
        Err(e) => {
            eprintln!("warning: file watching: {e}");
            false
        }
    };
    loop {
        let event = rx.recv().map_err(|_| "the file watcher stopped")?;
        if relevant(event) {
            break;
        }
    }
    let mut deadline = Instant::now() + QUIET;
    loop {
        match rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
            Ok(event) => {
                if relevant(event) {
                    deadline = Instant::now() + QUIET;
                }
            }
            Err(RecvTimeoutError::Timeout) => return Ok(()),
            Err(RecvTimeoutError::Disconnected) => return Err("the file watcher stopped".into()),
        }
    }
}

/// Whether `event` may have changed one of `files`: reads and opens do
/// not, anything else (writes, creation, removal, renames) may.
fn touches(event: &notify::Event, files: &[PathBuf]) -> bool {
    let changes = match event.kind {
        EventKind::Access(AccessKind::Close(AccessMode::Write)) => true,
        EventKind::Access(_) => false,
        _ => true,
    };
    changes && event.paths.iter().any(|p| files.contains(p))
}

/// The preview (unless `--preview 1`), then the full image.
fn render_twice(args: &Args, scene: &Scene, in_flight: &Shared) -> Result<(), CliError> {
    let full = args.render.image.size.unwrap_or(scene.render.size);
    let k = args.preview;
    let small = ((full.0 / k).max(1), (full.1 / k).max(1));
    if k > 1 && small != full {
        let mut preview = args.render.clone();
        preview.image.size = Some(small);
        preview.quiet = true;
        (
            preview.depth,
            preview.normals,
            preview.classify,
            preview.stats_json,
        ) = (None, None, None, None);
        render_replacing(&preview, scene, in_flight)?;
        if !args.render.quiet {
            eprintln!(
                "wrote a preview to {} ({}x{})",
                args.render.output.display(),
                small.0,
                small.1
            );
        }
    }
    let mut whole = args.render.clone();
    whole.image.size = Some(full);
    let t = Instant::now();
    render_replacing(&whole, scene, in_flight)?;
    if !args.render.quiet {
        eprintln!(
            "wrote {} ({}x{}) in {:.0} ms",
            args.render.output.display(),
            full.0,
            full.1,
            t.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}

/// Renders `args` with every output going to a temporary file beside it,
/// then renames each over its destination.
fn render_replacing(
    args: &render::Args,
    scene: &Scene,
    in_flight: &Shared,
) -> Result<(), CliError> {
    let mut finals: Vec<PathBuf> = vec![args.output.clone()];
    finals.extend(
        [&args.depth, &args.normals, &args.classify, &args.stats_json]
            .into_iter()
            .flatten()
            .cloned(),
    );
    let mut tmp_args = args.clone();
    tmp_args.output = temp_path(&args.output);
    for p in [
        &mut tmp_args.depth,
        &mut tmp_args.normals,
        &mut tmp_args.classify,
        &mut tmp_args.stats_json,
    ]
    .into_iter()
    .flatten()
    {
        *p = temp_path(p);
    }
    let temps: Vec<PathBuf> = finals.iter().map(|f| temp_path(f)).collect();
    {
        let mut s = in_flight.lock().unwrap_or_else(PoisonError::into_inner);
        if s.stopping {
            return Ok(());
        }
        s.temps.clone_from(&temps);
    }
    let result = render::run_with(&tmp_args, |_| Ok(scene.clone())).and_then(|()| {
        for (t, f) in temps.iter().zip(&finals) {
            std::fs::rename(t, f).map_err(|e| format!("cannot write {}: {e}", f.display()))?;
        }
        Ok(())
    });
    let mut s = in_flight.lock().unwrap_or_else(PoisonError::into_inner);
    for t in s.temps.drain(..) {
        // Left only by a failed render or rename.
        let _ = std::fs::remove_file(t);
    }
    result
}

/// `dir/.stem.ibeam-watch.ext` for `dir/stem.ext`: in the same folder, so
/// the rename is atomic, hidden, and with the destination's extension,
/// which chooses the image format.
fn temp_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let name = match path.extension() {
        Some(ext) => format!(".{stem}.ibeam-watch.{}", ext.to_string_lossy()),
        None => format!(".{stem}.ibeam-watch"),
    };
    path.with_file_name(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use notify::event::{CreateKind, ModifyKind};

    #[test]
    fn temporary_files_sit_beside_their_destination() {
        assert_eq!(
            temp_path(Path::new("out/a.png")),
            PathBuf::from("out/.a.ibeam-watch.png")
        );
        assert_eq!(
            temp_path(Path::new("a.EXR")),
            PathBuf::from(".a.ibeam-watch.EXR")
        );
    }

    #[test]
    fn only_changes_to_the_scene_files_count() {
        let files = vec![PathBuf::from("/s/a.ib"), PathBuf::from("/s/lib/b.ib")];
        let ev = |kind, p: &str| notify::Event::new(kind).add_path(PathBuf::from(p));
        assert!(touches(
            &ev(EventKind::Modify(ModifyKind::Any), "/s/lib/b.ib"),
            &files
        ));
        assert!(touches(
            &ev(EventKind::Create(CreateKind::File), "/s/a.ib"),
            &files
        ));
        assert!(!touches(
            &ev(EventKind::Modify(ModifyKind::Any), "/s/out.png"),
            &files
        ));
        assert!(!touches(
            &ev(EventKind::Access(AccessKind::Read), "/s/a.ib"),
            &files
        ));
        assert!(touches(
            &ev(
                EventKind::Access(AccessKind::Close(AccessMode::Write)),
                "/s/a.ib"
            ),
            &files
        ));
    }
}
