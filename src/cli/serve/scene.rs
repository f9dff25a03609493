//! The scene `ibeam serve` shows: loaded, checked and compiled once per
//! save (every view then renders with the same evaluators), reloaded by
//! `ibeam watch`'s mechanism, with the last good load kept through a
//! broken save.

use std::collections::BTreeSet;
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::sync::mpsc::channel;
use std::sync::{Arc, Mutex, PoisonError};

use super::super::{CliError, build_evaluators, watch};
use super::Args;
use ibeam::eval::Evaluator;
use ibeam::ir::passes::simplify;
use ibeam::ir::print::print;
use ibeam::scene::Scene;

/// A scene that loaded, with what every view of it shares.
pub struct Good {
    /// The scene, its camera as the command line's flags set it.
    pub scene: Scene,
    /// One evaluator per object, compiled once for every view.
    pub evaluators: Vec<Arc<dyn Evaluator>>,
    /// What `ibeam ir FILE` prints for it.
    pub ir: String,
    /// The full image's size.
    pub size: (u32, u32),
}

/// What the page is told about the scene.
#[derive(Default)]
pub struct State {
    /// Bumped by every load, good or not, so the page sees each save.
    pub generation: u64,
    /// The last good load (kept through broken saves).
    pub good: Option<Arc<Good>>,
    /// The last load's error, exactly as the command line prints it.
    pub error: Option<String>,
    /// The scene file's text as last read.
    pub source: String,
}

/// The state, shared by the reloading thread and the request handlers.
pub type Shared = Arc<Mutex<State>>;

/// Locks `shared`; a handler that panicked leaves plain data behind.
pub fn lock(shared: &Shared) -> std::sync::MutexGuard<'_, State> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Largest scene text the page is sent (the file itself may be bigger,
/// a `.vm` model say; the page then shows a note).
const MAX_SHOWN_SOURCE: u64 = 8 << 20;

/// Loads the scene once, into `shared`; returns the files it read.
pub fn reload(args: &Args, shared: &Shared) -> Vec<PathBuf> {
    let loaded = ibeam::lang::load_scene_with_files(&args.file);
    let good = loaded
        .scene
        .map_err(|e| e.to_string())
        .and_then(|scene| inside_folder(&args.file, &loaded.files).map(|()| scene))
        .and_then(|scene| prepare(args, scene).map_err(|e| e.to_string()));
    let source = read_source(&args.file);
    let mut s = lock(shared);
    s.generation += 1;
    s.source = source;
    match good {
        Ok(g) => {
            s.good = Some(Arc::new(g));
            s.error = None;
        }
        Err(e) => {
            if !args.quiet {
                eprintln!("{e}");
            }
            s.error = Some(e);
        }
    }
    loaded.files
}

fn read_source(file: &Path) -> String {
    match std::fs::metadata(file) {
        Ok(m) if m.len() > MAX_SHOWN_SOURCE => {
            format!("({} bytes: too long to show here)", m.len())
        }
        _ => std::fs::read(file)
            .map(|b| String::from_utf8_lossy(&b).into_owned())
            .unwrap_or_default(),
    }
}

/// Refuses a load that read a file outside the scene's own folder: the
/// page serves what the scene makes of its files (the IR), so a scene
/// must not reach the rest of the disk through `import`.
fn inside_folder(file: &Path, files: &[PathBuf]) -> Result<(), String> {
    let main = ibeam::lang::imports::file_identity(file);
    let dir = main.parent().unwrap_or(Path::new("/"));
    match files.iter().find(|f| !f.starts_with(dir)) {
        None => Ok(()),
        Some(outside) => Err(format!(
            "{}: error: import of {} refused: `ibeam serve` reads only files \
             in the scene's folder ({})",
            file.display(),
            outside.display(),
            dir.display()
        )),
    }
}

/// Compiles a loaded scene and sets its camera as the flags ask.
fn prepare(args: &Args, mut scene: Scene) -> Result<Good, CliError> {
    if scene.objects.is_empty() {
        return Err(format!("{}: the scene has no objects", args.file.display()).into());
    }
    let size = args.image.size.unwrap_or(scene.render.size);
    args.image.set_shadows(&mut scene);
    let evaluators = build_evaluators(&scene, args.image.eval)?;
    args.view
        .apply(&args.file, &mut scene, &evaluators, size, true)?;
    let mut ir = String::new();
    for object in &scene.objects {
        // As `ibeam ir` prints it.
        let _ = write!(
            ir,
            "; object {}\n{}",
            object.name,
            print(&simplify(&object.function))
        );
    }
    Ok(Good {
        scene,
        evaluators,
        ir,
        size,
    })
}

/// Loads the scene, calls `ready` once that first load is in `shared`,
/// then reloads it each time it or a file it imports is saved, until the
/// file watcher stops.
pub fn keep_loading(args: &Args, shared: &Shared, ready: impl FnOnce()) -> Result<(), CliError> {
    let (tx, rx) = channel();
    let mut watcher = notify::recommended_watcher(move |event| {
        let _ = tx.send(event);
    })
    .map_err(|e| format!("cannot watch files: {e}"))?;
    // The folder is watched before the first load, as in `ibeam watch`,
    // so a save while it loads is not missed.
    let mut files = vec![ibeam::lang::imports::file_identity(&args.file)];
    let mut dirs = BTreeSet::new();
    watch::watch_folders(&mut watcher, &mut dirs, &files);
    let mut ready = Some(ready);
    loop {
        let read = reload(args, shared);
        // As in `ibeam watch`: a failed load keeps the last good load's
        // files watched, so fixing any of them reloads.
        if lock(shared).error.is_none() {
            files.clear();
        }
        for f in read {
            if !files.contains(&f) {
                files.push(f);
            }
        }
        watch::watch_folders(&mut watcher, &mut dirs, &files);
        if let Some(r) = ready.take() {
            r();
        }
        watch::wait_for_change(&rx, &files)?;
    }
}
