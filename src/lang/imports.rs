//! `import "path";`: finding, reading and parsing the files a scene
//! imports, each once, in an order that lets the definitions of every file
//! be collected as if they were one file.
//!
//! Files are told apart by their canonical path, so `lib.ib`,
//! `./lib.ib` and `../here/lib.ib` are one file, and a diamond (two files
//! importing a third) reads the third once. A file that is still being
//! read when an import names it again closes a cycle, which is an error at
//! that import. Only definitions are taken from an imported file (see
//! `docs/language.md`); its objects, camera, lights, bounds and render
//! settings are for rendering it on its own.

use super::LoadError;
use super::ast::Item;
use super::diag::{Diag, Sources};
use super::input::{self, MAX_SOURCE_BYTES, ReadFailure};
use super::parser;
use std::collections::HashSet;
use std::path::{Component, Path, PathBuf};

/// How many files deep imports may nest (a chain `a` imports `b` imports
/// `c` …). Real libraries nest a few levels; the limit keeps a generated
/// chain of thousands of files from recursing without bound.
pub const MAX_IMPORT_DEPTH: usize = 256;

/// The identity of a file: its canonical path when it exists, else its
/// absolute path (a main file given as text, or a missing import that
/// `ibeam watch` should notice once it is created).
pub fn file_identity(path: &Path) -> PathBuf {
    std::fs::canonicalize(path)
        .or_else(|_| std::path::absolute(path))
        .unwrap_or_else(|_| path.to_path_buf())
}

/// The parsed items of the main file (source `main`, whose name in
/// diagnostics is `main_name`) and of every file it imports, directly or
/// not: each import before the file that imports it, the main file last,
/// so that a clash between files is reported at the later definition.
///
/// `files` gets the identity of every file read or tried, the main file's
/// included when it is not there yet; on failure it holds those up to the
/// error, so a watcher can still watch the file that needs fixing.
pub fn read_all(
    sources: &mut Sources,
    main: usize,
    main_name: &str,
    files: &mut Vec<PathBuf>,
) -> Result<Vec<(usize, Vec<Item>)>, LoadError> {
    let main_path = Path::new(main_name);
    let id = file_identity(main_path);
    if !files.contains(&id) {
        files.push(id.clone());
    }
    let items = parser::parse_file(sources.text(main), main).map_err(|d| sources.render(&d))?;
    let mut walk = Walk {
        sources,
        files,
        seen: HashSet::from([id.clone()]),
        stack: vec![(id, main_name.to_string())],
        parsed: Vec::new(),
    };
    let dir = main_path.parent().unwrap_or(Path::new("")).to_path_buf();
    walk.visit(main, items, &dir)?;
    Ok(walk.parsed)
}

/// The state of one depth-first walk over the import graph.
struct Walk<'s> {
    sources: &'s mut Sources,
    files: &'s mut Vec<PathBuf>,
    /// Every file read or being read.
    seen: HashSet<PathBuf>,
    /// The chain of files being read, main file first: (identity, name).
    stack: Vec<(PathBuf, String)>,
    /// Files whose imports are all read, in that order.
    parsed: Vec<(usize, Vec<Item>)>,
}

impl Walk<'_> {
    /// Reads the imports of `items` (source `src`, in folder `dir`), then
    /// records `items`.
    fn visit(&mut self, src: usize, items: Vec<Item>, dir: &Path) -> Result<(), LoadError> {
        for item in &items {
            let Item::Import {
                path,
                span,
                path_span,
            } = item
            else {
                continue;
            };
            let at_path = |message: String| Diag::new(src, path_span.0..path_span.1, message);
            if path.trim().is_empty() {
                return Err(self.render(
                    at_path("an import needs a file name".into())
                        .with_help("e.g. `import \"lib/shapes.ib\";`"),
                ));
            }
            let shown = clean(&dir.join(path));
            let name = shown.display().to_string();
            if shown
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("vm"))
            {
                return Err(self.render(
                    at_path(format!(
                        "cannot import `{name}`: a `.vm` model has no definitions"
                    ))
                    .with_help(
                        "import reads `let` and `fn` definitions from `.ib` files; \
                             render a model on its own",
                    ),
                ));
            }
            let id = match std::fs::canonicalize(&shown) {
                Ok(id) => id,
                Err(e) => {
                    // Watched anyway, so that creating it re-renders.
                    self.files.push(file_identity(&shown));
                    return Err(self.render(at_path(ReadFailure::Io(e).message(&name))));
                }
            };
            if let Some(pos) = self.stack.iter().position(|(p, _)| *p == id) {
                let d = Diag::new(src, span.0..span.1, cycle_message(&self.stack[pos..]))
                    .with_help("a file may not import itself, directly or through others");
                return Err(self.render(d));
            }
            if !self.seen.insert(id.clone()) {
                continue;
            }
            self.files.push(id.clone());
            // Opening a FIFO blocks until a writer comes, and a device may
            // never end: only plain files are read.
            if !std::fs::metadata(&id).is_ok_and(|m| m.is_file()) {
                return Err(
                    self.render(at_path(format!("cannot import `{name}`: it is not a file")))
                );
            }
            if self.stack.len() >= MAX_IMPORT_DEPTH {
                return Err(self.render(Diag::new(
                    src,
                    span.0..span.1,
                    format!("imports nest too deeply (more than {MAX_IMPORT_DEPTH} files)"),
                )));
            }
            let bytes = input::read_bytes(&shown, MAX_SOURCE_BYTES)
                .map_err(|f| self.render(at_path(f.message(&name))))?;
            let text = input::decode_source(&name, bytes)?;
            let child = self.sources.add(&name, &text);
            drop(text);
            let child_items = parser::parse_file(self.sources.text(child), child)
                .map_err(|d| self.sources.render(&d))?;
            self.stack.push((id, name));
            let child_dir = shown.parent().unwrap_or(Path::new("")).to_path_buf();
            self.visit(child, child_items, &child_dir)?;
            self.stack.pop();
        }
        self.parsed.push((src, items));
        Ok(())
    }

    fn render(&self, d: Diag) -> LoadError {
        self.sources.render(&d)
    }
}

/// `chain` is the files from the one imported again to the one importing
/// it: "`a.ib` imports `b.ib`, which imports `a.ib`".
fn cycle_message(chain: &[(PathBuf, String)]) -> String {
    let first = &chain[0].1;
    if chain.len() == 1 {
        return format!("import cycle: `{first}` imports itself");
    }
    let mut m = format!("import cycle: `{first}` imports `{}`", chain[1].1);
    for (_, name) in &chain[2..] {
        m.push_str(&format!(", which imports `{name}`"));
    }
    m.push_str(&format!(", which imports `{first}`"));
    m
}

/// `p` without `.` components, so diagnostics name `dir/lib.ib`, not
/// `dir/./lib.ib`. `..` is kept: removing it is only right without links.
fn clean(p: &Path) -> PathBuf {
    p.components()
        .filter(|c| !matches!(c, Component::CurDir))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(names: &[&str]) -> Vec<(PathBuf, String)> {
        names
            .iter()
            .map(|n| (PathBuf::from(n), (*n).to_string()))
            .collect()
    }

    #[test]
    fn cycle_messages_name_every_file() {
        assert_eq!(
            cycle_message(&chain(&["a.ib"])),
            "import cycle: `a.ib` imports itself"
        );
        assert_eq!(
            cycle_message(&chain(&["a.ib", "b.ib", "c.ib"])),
            "import cycle: `a.ib` imports `b.ib`, which imports `c.ib`, which imports `a.ib`"
        );
    }

    #[test]
    fn current_folder_components_are_dropped() {
        assert_eq!(clean(Path::new("./a/./b.ib")), PathBuf::from("a/b.ib"));
        assert_eq!(clean(Path::new("a/../b.ib")), PathBuf::from("a/../b.ib"));
    }
}
