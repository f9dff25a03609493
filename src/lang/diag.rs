//! Diagnostics: an error with a span in one source (of the several a scene
//! and its imports are read from), and its rendering as
//! `file:line:col: error: message` followed by a codespan snippet.

use super::LoadError;
use codespan_reporting::diagnostic::{Diagnostic, Label};
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term::{self, Chars, Config};
use std::ops::Range;

/// An error found while lexing, parsing or lowering, before rendering.
#[derive(Clone, Debug, PartialEq)]
pub struct Diag {
    /// Index of the source (see [`Sources`]).
    pub src: usize,
    /// Byte range of the offending text.
    pub span: Range<usize>,
    /// One-line description.
    pub message: String,
    /// A hint shown as `help: …`.
    pub help: Option<String>,
    /// Related places, e.g. a first definition.
    pub secondary: Vec<(usize, Range<usize>, String)>,
}

impl Diag {
    /// An error at `span` of source `src`.
    pub fn new(src: usize, span: Range<usize>, message: String) -> Diag {
        Diag {
            src,
            span,
            message,
            help: None,
            secondary: Vec::new(),
        }
    }

    /// Adds a `help:` hint.
    pub fn with_help(mut self, help: impl Into<String>) -> Diag {
        self.help = Some(help.into());
        self
    }

    /// Points at a related place.
    pub fn with_secondary(
        mut self,
        src: usize,
        span: Range<usize>,
        what: impl Into<String>,
    ) -> Diag {
        self.secondary.push((src, span, what.into()));
        self
    }
}

/// The texts a scene is read from: index 0 is the prelude, 1 the user's
/// file, then each file it imports, in the order read (for a
/// single-source load, whatever was registered). A diagnostic names the
/// file of its own source, so an error inside an import names the import.
#[derive(Default)]
pub struct Sources {
    files: SimpleFiles<String, String>,
    names: Vec<String>,
}

impl Sources {
    /// Registers a source and returns its index.
    pub fn add(&mut self, name: &str, text: &str) -> usize {
        self.names.push(name.to_string());
        self.files.add(name.to_string(), text.to_string())
    }

    /// The text of source `src`.
    pub fn text(&self, src: usize) -> &str {
        self.files
            .get(src)
            .map(|f| f.source().as_str())
            .unwrap_or("")
    }

    /// Renders `d` into a [`LoadError`].
    pub fn render(&self, d: &Diag) -> LoadError {
        let text = self.text(d.src);
        let start = d.span.start.min(text.len());
        let end = d.span.end.clamp(start, text.len());
        let (line, col) = line_col(text, start);
        let name = self
            .names
            .get(d.src)
            .map(String::as_str)
            .unwrap_or("<input>");
        let mut rendered = format!("{name}:{line}:{col}: error: {}\n", d.message);
        let mut labels = vec![Label::primary(d.src, start..end)];
        for (src, span, what) in &d.secondary {
            let t = self.text(*src);
            let s = span.start.min(t.len());
            let e = span.end.clamp(s, t.len());
            labels.push(Label::secondary(*src, s..e).with_message(what.clone()));
        }
        let mut diagnostic = Diagnostic::error()
            .with_message(d.message.clone())
            .with_labels(labels);
        if let Some(h) = &d.help {
            diagnostic = diagnostic.with_notes(vec![format!("help: {h}")]);
        }
        let config = Config {
            chars: Chars::ascii(),
            ..Config::default()
        };
        if let Ok(snippet) = term::emit_into_string(&config, &self.files, &diagnostic) {
            // codespan's own first two lines repeat the message and the
            // location, which the header above already gives, and its
            // third is an empty gutter; the source line comes right after
            // the header instead.
            let mut lines = snippet.lines().skip(2).peekable();
            if lines.peek().is_some_and(|l| l.trim() == "|") {
                lines.next();
            }
            for l in lines {
                rendered.push_str(l.trim_end());
                rendered.push('\n');
            }
        } else if let Some(h) = &d.help {
            rendered.push_str(&format!("help: {h}\n"));
        }
        rendered.truncate(rendered.trim_end().len());
        rendered.push('\n');
        LoadError {
            message: d.message.clone(),
            line,
            col,
            help: d.help.clone(),
            file: name.to_string(),
            rendered,
        }
    }
}

/// 1-based line and column (in characters) of byte `offset`.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let col = text[line_start..offset].chars().count() + 1;
    (line, col)
}

/// The closest known name to `name`, if any is close enough to be a likely
/// typo.
pub fn suggest<'n>(name: &str, candidates: impl Iterator<Item = &'n str>) -> Option<&'n str> {
    let limit = (name.chars().count() / 3).max(1);
    let mut best: Option<(usize, &str)> = None;
    for c in candidates {
        let d = strsim::damerau_levenshtein(name, c);
        let better = match best {
            None => true,
            Some((bd, bn)) => d < bd || (d == bd && c < bn),
        };
        if d <= limit && better {
            best = Some((d, c));
        }
    }
    best.map(|(_, c)| c)
}

/// A LoadError without a source position (e.g. an unreadable file).
pub fn error_without_position(file: &str, message: String) -> LoadError {
    LoadError {
        rendered: format!("{file}: error: {message}\n"),
        message,
        line: 0,
        col: 0,
        help: None,
        file: file.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions_only_for_close_names() {
        let names = ["sphere", "box", "torus"];
        assert_eq!(suggest("sphre", names.iter().copied()), Some("sphere"));
        assert_eq!(suggest("bx", names.iter().copied()), Some("box"));
        assert_eq!(suggest("cylinder", names.iter().copied()), None);
    }

    #[test]
    fn line_and_column_are_one_based_in_characters() {
        let t = "ab\nçd\n";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 2), (1, 3));
        assert_eq!(line_col(t, 3), (2, 1));
        assert_eq!(line_col(t, 5), (2, 2));
        assert_eq!(line_col(t, 99), (3, 1));
    }

    #[test]
    fn rendering_has_header_snippet_and_help() {
        let mut s = Sources::default();
        let src = s.add("a.ib", "let a = 1;\nobject o = b;\n");
        let e = s.render(
            &Diag::new(src, 22..23, "unknown variable `b`".into()).with_help("did you mean `a`?"),
        );
        assert_eq!((e.line, e.col), (2, 12));
        let lines: Vec<&str> = e.rendered.lines().collect();
        assert_eq!(lines[0], "a.ib:2:12: error: unknown variable `b`");
        assert!(lines.iter().any(|l| l.ends_with("| object o = b;")));
        assert!(
            lines
                .iter()
                .any(|l| l.trim_end().ends_with("|            ^"))
        );
        assert!(lines.last().unwrap().ends_with("= help: did you mean `a`?"));
    }
}
