//! The two length rules of `docs/architecture.md`, as checks that fail: no
//! file in `src/` over [`MAX_FILE_LINES`] lines, and no function over
//! [`MAX_FN_LINES`] lines unless a comment line starting with
//! [`LONG_FN_MARK`], among the comments and attributes right above it,
//! says why.

use std::path::Path;

use super::{read_tree, strip};

/// Longest source file allowed, in lines.
pub const MAX_FILE_LINES: usize = 600;
/// Longest function allowed without a reason, in lines (from its `fn`
/// line to its closing brace).
pub const MAX_FN_LINES: usize = 80;
/// What a comment giving the reason for a long function starts with.
pub const LONG_FN_MARK: &str = "// long-fn:";

/// One function found: its name, first line (1-based) and length.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FnSpan {
    pub name: String,
    pub line: usize,
    pub lines: usize,
}

/// Every function with a body in `src`, found in the text with comments
/// and literals blanked (so a `fn` in a string or a comment is no
/// function), and its length in lines.
pub fn functions(src: &str) -> Vec<FnSpan> {
    let text: Vec<char> = strip(src).chars().collect();
    let mut found = Vec::new();
    let mut i = 0;
    while i + 2 < text.len() {
        let is_fn = text[i] == 'f'
            && text[i + 1] == 'n'
            && text[i + 2].is_whitespace()
            && (i == 0 || !is_ident(text[i - 1]));
        if !is_fn {
            i += 1;
            continue;
        }
        let mut j = i + 2;
        while j < text.len() && text[j].is_whitespace() {
            j += 1;
        }
        let name: String = text[j..].iter().take_while(|&&c| is_ident(c)).collect();
        if name.is_empty() {
            i += 2; // `fn (`: a function pointer type.
            continue;
        }
        let Some(open) = body_start(&text, j) else {
            i = j;
            continue; // A declaration without a body (trait, extern).
        };
        let close = matching_brace(&text, open);
        let line_of = |k: usize| text[..k].iter().filter(|&&c| c == '\n').count() + 1;
        found.push(FnSpan {
            name,
            line: line_of(i),
            lines: line_of(close) - line_of(i) + 1,
        });
        // Nested functions are found on their own: go on inside the body.
        i = open + 1;
    }
    found
}

/// The index of the `{` that opens the body of the function whose
/// signature starts at `from`, or `None` when a `;` ends it first.
fn body_start(text: &[char], from: usize) -> Option<usize> {
    let mut depth = 0i32;
    for (k, &c) in text.iter().enumerate().skip(from) {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            '{' if depth == 0 => return Some(k),
            ';' if depth == 0 => return None,
            _ => {}
        }
    }
    None
}

/// The index of the `}` that closes the `{` at `open` (the end of the
/// text when unbalanced).
fn matching_brace(text: &[char], open: usize) -> usize {
    let mut depth = 0i32;
    for (k, &c) in text.iter().enumerate().skip(open) {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return k;
                }
            }
            _ => {}
        }
    }
    text.len().saturating_sub(1)
}

/// Whether `ch` can be part of an identifier.
fn is_ident(ch: char) -> bool {
    ch.is_alphanumeric() || ch == '_'
}

/// Whether the comments and attributes right above line `line` (1-based)
/// of `src` hold a [`LONG_FN_MARK`] line.
fn has_reason(src: &str, line: usize) -> bool {
    let lines: Vec<&str> = src.lines().collect();
    lines[..line - 1]
        .iter()
        .rev()
        .map(|l| l.trim())
        .take_while(|l| l.starts_with("//") || l.starts_with("#[") || l.starts_with("#!["))
        .any(|l| l.starts_with(LONG_FN_MARK))
}

/// The breaches of both rules in `files` (path relative to `src/`, text).
pub fn breaches(files: &[(String, String)]) -> Vec<String> {
    let mut bad = Vec::new();
    for (rel, src) in files {
        let n = src.lines().count();
        if n > MAX_FILE_LINES {
            bad.push(format!("{rel}: {n} lines (at most {MAX_FILE_LINES})"));
        }
        for f in functions(src) {
            if f.lines > MAX_FN_LINES && !has_reason(src, f.line) {
                bad.push(format!(
                    "{rel}:{}: fn {} is {} lines (at most {MAX_FN_LINES} without a `{LONG_FN_MARK}` comment saying why)",
                    f.line, f.name, f.lines
                ));
            }
        }
    }
    bad
}

#[test]
fn src_keeps_the_length_rules() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&root, &root, &mut files);
    let fns: usize = files.iter().map(|(_, s)| functions(s).len()).sum();
    assert!(
        fns > 500,
        "only {fns} functions found: the reader is broken"
    );
    let bad = breaches(&files);
    assert!(bad.is_empty(), "length rules broken:\n{}", bad.join("\n"));
}

/// A function of `n` body lines named `name`.
fn long_fn(name: &str, n: usize) -> String {
    let body: String = (0..n).map(|k| format!("    let _a{k} = {k};\n")).collect();
    format!("fn {name}() {{\n{body}}}\n")
}

#[test]
fn functions_are_measured_from_fn_to_closing_brace() {
    let src = "/// doc\npub(crate) fn short<T: Fn(u8) -> u8>(f: T) -> u8 {\n    f(1)\n}\n\
               trait T { fn decl(&self); fn with_default(&self) { let s = \"fn x() {\"; } }\n\
               const P: fn(f64) -> f64 = f64::abs;\n\
               // fn in_a_comment() { }\n";
    let fns = functions(src);
    let names: Vec<(&str, usize, usize)> = fns
        .iter()
        .map(|f| (f.name.as_str(), f.line, f.lines))
        .collect();
    assert_eq!(names, [("short", 2, 3), ("with_default", 5, 1)]);
}

#[test]
fn a_planted_long_function_or_file_fails() {
    let long = long_fn("too_long", MAX_FN_LINES);
    let bad = breaches(&[("eval/x.rs".into(), long.clone())]);
    assert_eq!(bad.len(), 1, "{bad:?}");
    assert!(bad[0].starts_with("eval/x.rs:1: fn too_long is 82 lines"));
    // One line shorter is within the rule.
    let ok = long_fn("just_fits", MAX_FN_LINES - 2);
    assert!(breaches(&[("a.rs".into(), ok)]).is_empty());
    // A marked reason lets a long function pass; a plain comment does not.
    let marked = format!("/// Doc.\n{LONG_FN_MARK} one match over every op.\n#[inline]\n{long}");
    assert!(breaches(&[("a.rs".into(), marked)]).is_empty());
    let unmarked = format!("// long, but why?\n{long}");
    assert_eq!(breaches(&[("a.rs".into(), unmarked)]).len(), 1);
    // A long file fails whatever its functions.
    let file = "const X: u8 = 0;\n".repeat(MAX_FILE_LINES + 1);
    let bad = breaches(&[("big.rs".into(), file)]);
    assert_eq!(
        bad,
        [format!("big.rs: 601 lines (at most {MAX_FILE_LINES})")]
    );
}
