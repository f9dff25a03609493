//! The scene language: lexer, parser glue, AST, diagnostics, the prelude of
//! primitives, `import` between scene files, and the importer for
//! Fidget's `.vm` format.
//!
//! See `docs/language.md` for the language reference. Entry points:
//! [`load_scene`], [`load_scene_with_files`] (which also tells the files
//! read, for `ibeam watch`), [`load_scene_source`] and
//! [`function_from_formula`].

pub mod ast;
pub mod builtins;
pub mod diag;
pub mod imports;
pub mod input;
pub mod lexer;
pub mod lower;
pub mod parser;
pub mod scene;
pub mod vm;
pub mod vm_export;

use crate::ir::Function;
use crate::lang::lower::Program;
use crate::scene::Scene;
use diag::Sources;
pub use input::{MAX_SOURCE_BYTES, read_source};
use std::fmt;
use std::path::{Path, PathBuf};

/// The prelude's source text.
pub const PRELUDE: &str = include_str!("prelude.ib");

/// Stack for the loader thread: the parser caps the tree depth and
/// lowering caps the call depth, and this leaves room for both limits at
/// once whatever thread calls us.
const LOADER_STACK_BYTES: usize = 256 << 20;

/// A load failure, already rendered as `file:line:col: error: message`
/// followed by the source line, a caret and any hint.
#[derive(Debug, Clone)]
pub struct LoadError {
    /// The full rendered diagnostic text.
    pub rendered: String,
    /// The one-line message (without location).
    pub message: String,
    /// 1-based line of the error (0 when the error has no position).
    pub line: usize,
    /// 1-based column, in characters (0 when the error has no position).
    pub col: usize,
    /// The hint shown as `help: …`, if any.
    pub help: Option<String>,
    /// The name of the file the position refers to.
    pub file: String,
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.rendered.trim_end())
    }
}

impl std::error::Error for LoadError {}

/// Reads and lowers a scene file: `*.vm` is read as Fidget's SSA format,
/// anything else as an ibeam scene (with its imports). Files over
/// [`MAX_SOURCE_BYTES`] or not UTF-8 are refused (see [`read_source`]).
pub fn load_scene(path: &Path) -> Result<Scene, LoadError> {
    load_scene_with_files(path).scene
}

/// A scene load, with the files it read.
#[derive(Debug)]
pub struct Loaded {
    /// The scene, or the first error.
    pub scene: Result<Scene, LoadError>,
    /// Every file read, as canonical paths (absolute where a file is
    /// missing): the main file first, then each import once, in the order
    /// found. After a failure, the files read or tried up to the error, so
    /// that a watcher also watches the one to fix.
    pub files: Vec<PathBuf>,
}

/// [`load_scene`], also telling which files the scene was read from.
pub fn load_scene_with_files(path: &Path) -> Loaded {
    let mut files = vec![imports::file_identity(path)];
    let scene = read_source(path)
        .and_then(|text| load_tracked(&path.display().to_string(), &text, &mut files));
    Loaded { scene, files }
}

/// Lowers scene text; `file_name` picks the format by its extension (as
/// in [`load_scene`]), names the file in diagnostics, and is the place
/// its imports are found from.
pub fn load_scene_source(file_name: &str, source: &str) -> Result<Scene, LoadError> {
    load_tracked(file_name, source, &mut Vec::new())
}

/// [`load_scene_source`], adding the files read to `files`.
fn load_tracked(
    file_name: &str,
    source: &str,
    files: &mut Vec<PathBuf>,
) -> Result<Scene, LoadError> {
    let is_vm = Path::new(file_name)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vm"));
    on_big_stack(|| {
        let mut sources = Sources::default();
        if is_vm {
            let src = sources.add(file_name, source);
            let stem = Path::new(file_name)
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "model".into());
            vm::parse_vm(source, src)
                .and_then(|f| scene::vm_scene(stem, f, src))
                .map_err(|d| sources.render(&d))
        } else {
            let prelude = sources.add("prelude.ib", PRELUDE);
            let src = sources.add(file_name, source);
            load_ib(prelude, src, file_name, &mut sources, files)
        }
    })
}

/// Loads source `src` (named `file_name`) with its imports and the
/// prelude.
fn load_ib(
    prelude: usize,
    src: usize,
    file_name: &str,
    sources: &mut Sources,
    files: &mut Vec<PathBuf>,
) -> Result<Scene, LoadError> {
    let prelude_items = parser::parse_file(PRELUDE, prelude).map_err(|d| sources.render(&d))?;
    let parsed = imports::read_all(sources, src, file_name, files)?;
    let sources = &*sources;
    let mut all = vec![(prelude, prelude_items.as_slice())];
    all.extend(parsed.iter().map(|(s, items)| (*s, items.as_slice())));
    let prog = Program::new(&all).map_err(|d| sources.render(&d))?;
    // The walk records the main file last.
    let items = parsed.last().map_or(&[][..], |(_, items)| items.as_slice());
    scene::build(&prog, items, src, sources.text(src).len()).map_err(|d| sources.render(&d))
}

/// Lowers one expression over x, y, z (the prelude is available) to an
/// unsimplified IR function. Unlike an object, the expression may be a
/// constant.
pub fn function_from_formula(formula: &str) -> Result<Function, LoadError> {
    on_big_stack(|| {
        let mut sources = Sources::default();
        let prelude = sources.add("prelude.ib", PRELUDE);
        let src = sources.add("<formula>", formula);
        let lower = || -> Result<Function, diag::Diag> {
            let prelude_items = parser::parse_file(PRELUDE, prelude)?;
            let e = parser::parse_expr(formula, src)?;
            let prog = Program::new(&[(prelude, &prelude_items)])?;
            prog.lower_any(&e, src)
        };
        lower().map_err(|d| sources.render(&d))
    })
}

/// Runs `f` on a thread with a large stack, so that the bounded recursion
/// of dropping and lowering deep (but accepted) trees never overflows the
/// caller's stack, whatever its size.
fn on_big_stack<T: Send>(f: impl FnOnce() -> Result<T, LoadError> + Send) -> Result<T, LoadError> {
    std::thread::scope(|s| {
        let handle = std::thread::Builder::new()
            .name("ibeam-loader".into())
            .stack_size(LOADER_STACK_BYTES)
            .spawn_scoped(s, f)
            .map_err(|e| {
                diag::error_without_position(
                    "<loader>",
                    format!("cannot start the loader thread: {e}"),
                )
            })?;
        handle.join().unwrap_or_else(|_| {
            Err(diag::error_without_position(
                "<loader>",
                "internal error: the scene loader panicked".into(),
            ))
        })
    })
}
