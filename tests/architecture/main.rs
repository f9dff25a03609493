//! The module layering of `src/`: which top-level module may use which
//! (see [`ALLOWED`]), read from the source text itself so that a new
//! `use crate::render::...` inside `ir` fails here, not in review. Paths
//! are found outside comments and string literals: `crate::X`,
//! `$crate::X`, grouped `crate::{X, Y::z}`, and `super::` chains that climb
//! to the crate root. The dependency graph found must also have no cycle.

mod layers;
mod lengths;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Each library module and the modules it may use. The binary's modules
/// (`main.rs` and `src/cli/`) may use anything and are not checked.
const ALLOWED: &[(&str, &[&str])] = &[
    ("interval", &[]),
    ("ir", &["interval"]),
    ("scene", &["ir"]),
    ("lang", &["ir", "scene", "interval"]),
    ("eval", &["ir", "interval", "scene"]),
    ("render", &["eval", "ir", "interval", "scene"]),
    (
        "bench",
        &["render", "eval", "lang", "scene", "ir", "interval"],
    ),
];

/// Top-level modules of the binary, which are exempt.
const BINARY: &[&str] = &["main", "cli"];

/// One dependency found: `from` uses `to` in `file`, at `line`.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Use {
    from: String,
    to: String,
    file: String,
    line: usize,
}

/// The source with comments and the contents of string and char literals
/// blanked out (newlines kept, so line numbers stay right).
fn strip(src: &str) -> String {
    let c: Vec<char> = src.chars().collect();
    let mut out = String::with_capacity(src.len());
    let blank = |out: &mut String, ch: char| out.push(if ch == '\n' { '\n' } else { ' ' });
    let mut i = 0;
    while i < c.len() {
        let next = c.get(i + 1).copied();
        if c[i] == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if c[i] == '/' && next == Some('*') {
            // Block comments nest in Rust.
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    blank(&mut out, c[i]);
                    i += 1;
                }
            }
        } else if c[i] == 'r'
            && (next == Some('"') || next == Some('#'))
            && (i == 0 || !is_ident(c[i - 1]))
        {
            // A raw string r"..." or r#"..."#: ends at a quote followed by
            // as many hashes as it opened with.
            let mut j = i + 1;
            let mut hashes = 0;
            while c.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if c.get(j) != Some(&'"') {
                out.push(c[i]);
                i += 1;
                continue;
            }
            j += 1;
            while j < c.len() {
                if c[j] == '"' && (1..=hashes).all(|k| c.get(j + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                blank(&mut out, c[j]);
                j += 1;
            }
            i = j;
        } else if c[i] == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                if c[i] == '\\' {
                    i += 1;
                }
                if i < c.len() {
                    blank(&mut out, c[i]);
                }
                i += 1;
            }
            i += 1;
        } else if c[i] == '\'' {
            // A char literal ('x', '\n', '"'); otherwise a lifetime.
            if next == Some('\\') {
                let mut j = i + 2;
                while j < c.len() && c[j] != '\'' {
                    j += 1;
                }
                i = j + 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                out.push(c[i]);
                i += 1;
            }
        } else {
            out.push(c[i]);
            i += 1;
        }
    }
    out
}

/// Whether `ch` can be part of an identifier.
fn is_ident(ch: char) -> bool {
    ch.is_alphanumeric() || ch == '_'
}

/// The identifier at the start of `s` (after spaces).
fn ident(s: &str) -> &str {
    let s = s.trim_start();
    let end = s.find(|ch: char| !is_ident(ch)).unwrap_or(s.len());
    &s[..end]
}

/// The top-level modules named right after a path to the crate root at
/// the start of `rest`: `X` of `X::...`, or every `X` of `{X, Y::z, ...}`.
fn roots_after(rest: &str) -> Vec<String> {
    let rest = rest.trim_start();
    if let Some(group) = rest.strip_prefix('{') {
        // Split the group at its top-level commas.
        let mut names = Vec::new();
        let (mut depth, mut start) = (0, 0);
        for (k, ch) in group.char_indices() {
            match ch {
                '{' => depth += 1,
                '}' if depth == 0 => {
                    names.push(ident(&group[start..k]).to_string());
                    break;
                }
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    names.push(ident(&group[start..k]).to_string());
                    start = k + 1;
                }
                _ => {}
            }
        }
        names.retain(|n| !n.is_empty() && n != "self");
        names
    } else {
        let name = ident(rest);
        if name.is_empty() {
            Vec::new()
        } else {
            vec![name.to_string()]
        }
    }
}

/// The module path of a file relative to `src/` (`eval/jit/mod.rs` is
/// `[eval, jit]`, `eval/interp.rs` is `[eval, interp]`).
fn module_path(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel.split('/').map(str::to_string).collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" {
        parts.push(stem.to_string());
    }
    parts
}

/// Every top-level module that the file at `rel` (relative to `src/`)
/// uses, with the line of each use.
fn uses_in(rel: &str, src: &str) -> Vec<Use> {
    let path = module_path(rel);
    let Some(from) = path.first().cloned() else {
        return Vec::new();
    };
    let text = strip(src);
    let mut found = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut push = |to: String| {
            found.push(Use {
                from: from.clone(),
                to,
                file: rel.to_string(),
                line: n + 1,
            })
        };
        for (k, _) in line.match_indices("crate") {
            let before = line[..k].chars().next_back();
            // `$crate` counts; `my_crate` or `ibeam_crate` do not.
            if before.is_some_and(is_ident) {
                continue;
            }
            let after = &line[k + "crate".len()..];
            if let Some(rest) = after.trim_start().strip_prefix("::") {
                roots_after(rest).into_iter().for_each(&mut push);
            }
        }
        for (k, _) in line.match_indices("super") {
            if line[..k].chars().next_back().is_some_and(is_ident)
                || line[..k].trim_end().ends_with("::")
            {
                continue; // Counted from the first `super` of the chain.
            }
            let mut rest = &line[k..];
            let mut depth = 0;
            while let Some(r) = rest.strip_prefix("super") {
                let Some(r) = r.trim_start().strip_prefix("::") else {
                    break;
                };
                depth += 1;
                rest = r.trim_start();
            }
            // A chain that climbs to the crate root names a top-level
            // module next.
            if depth > 0 && depth == path.len() {
                roots_after(rest).into_iter().for_each(&mut push);
            }
        }
    }
    found
}

/// The violations of `allowed` among `uses` (self-uses aside), as messages.
fn violations(uses: &[Use], allowed: &[(&str, &[&str])], exempt: &[&str]) -> Vec<String> {
    let table: BTreeMap<&str, &[&str]> = allowed.iter().copied().collect();
    let mut bad = Vec::new();
    for u in uses {
        if u.from == u.to || exempt.contains(&u.from.as_str()) {
            continue;
        }
        match table.get(u.from.as_str()) {
            None => bad.push(format!(
                "{}:{}: module `{}` is not in the dependency table",
                u.file, u.line, u.from
            )),
            Some(ok) if !ok.contains(&u.to.as_str()) => bad.push(format!(
                "{}:{}: `{}` must not use `{}` (it may use {:?})",
                u.file, u.line, u.from, u.to, ok
            )),
            Some(_) => {}
        }
    }
    bad
}

/// A cycle in the graph of `uses` (self-uses aside), as the modules along
/// it, if there is one.
fn find_cycle(uses: &[Use]) -> Option<Vec<String>> {
    let mut graph: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    for u in uses.iter().filter(|u| u.from != u.to) {
        graph.entry(&u.from).or_default().insert(&u.to);
    }
    /// Depth-first search from `node`; `stack` is the current path.
    fn visit<'a>(
        node: &'a str,
        graph: &BTreeMap<&'a str, BTreeSet<&'a str>>,
        stack: &mut Vec<&'a str>,
        done: &mut BTreeSet<&'a str>,
    ) -> Option<Vec<String>> {
        if let Some(at) = stack.iter().position(|&n| n == node) {
            let mut cycle: Vec<String> = stack[at..].iter().map(|s| s.to_string()).collect();
            cycle.push(node.to_string());
            return Some(cycle);
        }
        if !done.insert(node) {
            return None;
        }
        stack.push(node);
        for &next in graph.get(node).into_iter().flatten() {
            if let Some(c) = visit(next, graph, stack, done) {
                return Some(c);
            }
        }
        stack.pop();
        None
    }
    let mut done = BTreeSet::new();
    for &start in graph.keys() {
        if let Some(c) = visit(start, &graph, &mut Vec::new(), &mut done) {
            return Some(c);
        }
    }
    None
}

/// Every `.rs` file under `dir`, as (path relative to `root`, text).
fn read_tree(root: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("readable entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            read_tree(root, &p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            let rel = p.strip_prefix(root).expect("under root");
            let rel = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect::<Vec<_>>()
                .join("/");
            let text = std::fs::read_to_string(&p).expect("readable source");
            out.push((rel, text));
        }
    }
}

/// Every use between top-level modules in the given files (`lib.rs`, which
/// only declares the modules, aside).
fn all_uses(files: &[(String, String)]) -> Vec<Use> {
    files
        .iter()
        .filter(|(rel, _)| rel != "lib.rs")
        .flat_map(|(rel, src)| uses_in(rel, src))
        .collect()
}

#[test]
fn src_follows_the_dependency_table() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&root, &root, &mut files);
    let uses = all_uses(&files);
    // The reader must see the real tree: eval uses ir, render uses eval.
    for (from, to) in [("eval", "ir"), ("render", "eval"), ("lang", "ir")] {
        assert!(
            uses.iter().any(|u| u.from == from && u.to == to),
            "no use of {to} found in {from}: the checker reads nothing"
        );
    }
    let bad = violations(&uses, ALLOWED, BINARY);
    assert!(bad.is_empty(), "layering violations:\n{}", bad.join("\n"));
    let library: Vec<Use> = uses
        .into_iter()
        .filter(|u| !BINARY.contains(&u.from.as_str()))
        .collect();
    assert_eq!(find_cycle(&library), None, "dependency cycle");
}

#[test]
fn the_table_itself_has_no_cycle() {
    let uses: Vec<Use> = ALLOWED
        .iter()
        .flat_map(|(from, tos)| {
            tos.iter().map(|to| Use {
                from: from.to_string(),
                to: to.to_string(),
                file: "ALLOWED".into(),
                line: 0,
            })
        })
        .collect();
    assert_eq!(find_cycle(&uses), None);
}

/// Runs the checker on in-memory files.
fn check(files: &[(&str, &str)]) -> (Vec<String>, Option<Vec<String>>) {
    let files: Vec<(String, String)> = files
        .iter()
        .map(|(p, s)| (p.to_string(), s.to_string()))
        .collect();
    let uses = all_uses(&files);
    (violations(&uses, ALLOWED, BINARY), find_cycle(&uses))
}

#[test]
fn a_planted_violation_fails() {
    let (bad, _) = check(&[
        ("ir/mod.rs", "use crate::interval::Interval;\n"),
        (
            "ir/prune.rs",
            "//! docs\nfn f() {}\nuse crate::eval::{Bulk, Evaluator, Single, Specialise};\n",
        ),
    ]);
    assert_eq!(bad.len(), 1, "{bad:?}");
    assert!(
        bad[0].starts_with("ir/prune.rs:3: `ir` must not use `eval`"),
        "{bad:?}"
    );
}

#[test]
fn every_path_form_is_found() {
    let src = r#"
use crate::{interval::Interval, render::{camera, shade}};
fn f() { let _ = crate :: lang::parse("x"); }
use super::super::bench::run;
macro_rules! m { () => { $crate::cli::go() } }
"#;
    let (bad, _) = check(&[("ir/passes.rs", src)]);
    for needle in ["use `render`", "use `lang`", "use `bench`", "use `cli`"] {
        assert!(bad.iter().any(|b| b.contains(needle)), "{needle}: {bad:?}");
    }
    assert_eq!(bad.len(), 4, "{bad:?}");
    // `super::` from a folder's mod.rs climbs to the root at once; from a
    // nested file it stays inside the module.
    let (bad, _) = check(&[
        ("ir/mod.rs", "use super::render::x;\n"),
        ("eval/jit/lower.rs", "use super::super::interp::y;\n"),
    ]);
    assert_eq!(bad.len(), 1, "{bad:?}");
}

#[test]
fn comments_and_strings_are_not_uses() {
    let src = r##"
// use crate::render::Foo;
/* crate::eval /* nested crate::lang */ crate::bench */
/// See [`crate::render::beam`].
const S: &str = "crate::render::x";
const R: &str = r#"crate::eval "quoted" x"#;
const Q: char = '"';
fn g<'a>(x: &'a str) -> &'a str { x }
use crate::interval::Interval;
"##;
    let (bad, _) = check(&[("ir/print.rs", src)]);
    assert!(bad.is_empty(), "{bad:?}");
    let uses = uses_in("ir/print.rs", src);
    assert_eq!(uses.len(), 1, "{uses:?}");
    assert_eq!((uses[0].to.as_str(), uses[0].line), ("interval", 9));
}

#[test]
fn unknown_modules_and_cycles_fail() {
    let (bad, _) = check(&[("gpu/mod.rs", "use crate::ir::Op;\n")]);
    assert!(
        bad[0].contains("`gpu` is not in the dependency table"),
        "{bad:?}"
    );
    let (_, cycle) = check(&[
        ("scene/mod.rs", "use crate::ir::Function;\n"),
        (
            "ir/mod.rs",
            "use crate::interval::I;\nuse crate::scene::S;\n",
        ),
    ]);
    assert_eq!(
        cycle,
        Some(vec![
            "ir".to_string(),
            "scene".to_string(),
            "ir".to_string()
        ])
    );
    // The binary may use anything, and is no part of the library's graph.
    let (bad, _) = check(&[("cli/render.rs", "use crate::cli::x; use ibeam::render;\n")]);
    assert!(bad.is_empty(), "{bad:?}");
}
