//! The layers inside `src/render`: each folder may use only the folders
//! below it in [`LAYERS`], never one above, so that a maintainer reads the
//! tracer bottom up and no two layers import each other. Paths into
//! render are found as the crate-level check finds paths into the crate:
//! `crate::render::X`, grouped `crate::render::{X, Y}`, and `super::`
//! chains that climb to `render`. A path naming something in render's
//! root that is not a layer must name an item the root defines itself
//! (shared options and results), not a module it re-exports for users:
//! inside render, a layer is named by its folder.

use std::path::Path;

use super::{module_path, read_tree, roots_after, strip};

/// Render's layers, lowest first.
pub const LAYERS: &[&str] = &[
    "view", "context", "enclose", "prune", "trace", "light", "aa", "tile", "frame",
];

/// Items render's root (`render/mod.rs`) defines, which every layer may use.
fn root_items(root_src: &str) -> Vec<String> {
    let text = strip(root_src);
    let mut items = Vec::new();
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        if !words.first().is_some_and(|w| w.starts_with("pub")) {
            continue;
        }
        for kind in ["const", "enum", "struct", "fn", "type"] {
            if let Some(k) = words.iter().position(|w| *w == kind) {
                if let Some(name) = words.get(k + 1) {
                    let name = super::ident(name);
                    if !name.is_empty() {
                        items.push(name.to_string());
                    }
                }
                break;
            }
        }
    }
    items
}

/// The names right after every path into render's root in the file at
/// `rel` (relative to `src/`), with their lines.
fn render_paths(rel: &str, src: &str) -> Vec<(String, usize)> {
    let path = module_path(rel);
    let text = strip(src);
    let mut found = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for (k, _) in line.match_indices("crate::render::") {
            if line[..k].chars().next_back().is_some_and(super::is_ident) {
                continue;
            }
            let rest = &line[k + "crate::render::".len()..];
            for name in roots_after(rest) {
                found.push((name, n + 1));
            }
        }
        for (k, _) in line.match_indices("super::") {
            if line[..k].chars().next_back().is_some_and(super::is_ident)
                || line[..k].ends_with("::")
            {
                continue;
            }
            let mut rest = &line[k..];
            let mut depth = 0;
            while let Some(r) = rest.strip_prefix("super::") {
                depth += 1;
                rest = r;
            }
            // `render/L/f.rs` is [render, L, f]: two `super`s reach render.
            if depth + 1 == path.len() {
                for name in roots_after(rest) {
                    found.push((name, n + 1));
                }
            }
        }
    }
    found
}

/// The breaches of the layer rule among `files` (path relative to `src/`,
/// text); `root_src` is `render/mod.rs`.
pub fn breaches(files: &[(String, String)], root_src: &str) -> Vec<String> {
    let items = root_items(root_src);
    let mut bad = Vec::new();
    for (rel, src) in files {
        let path = module_path(rel);
        if path.first().map(String::as_str) != Some("render") || path.len() < 2 {
            continue;
        }
        let Some(from) = LAYERS.iter().position(|l| *l == path[1]) else {
            bad.push(format!(
                "{rel}: `{}` is not one of render's layers",
                path[1]
            ));
            continue;
        };
        for (name, line) in render_paths(rel, src) {
            match LAYERS.iter().position(|l| *l == name) {
                Some(to) if to > from => bad.push(format!(
                    "{rel}:{line}: layer `{}` must not use `{name}`, a layer above it",
                    LAYERS[from]
                )),
                Some(_) => {}
                None if items.contains(&name) => {}
                None => bad.push(format!(
                    "{rel}:{line}: `{name}` is not a layer or an item of render's root; name its layer"
                )),
            }
        }
    }
    bad
}

#[test]
fn render_follows_its_layers() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    read_tree(&root, &root, &mut files);
    let root_src = &files
        .iter()
        .find(|(rel, _)| rel == "render/mod.rs")
        .expect("render/mod.rs")
        .1;
    let in_layers = files
        .iter()
        .filter(|(rel, _)| rel.starts_with("render/") && rel.matches('/').count() >= 2)
        .count();
    assert!(in_layers > 20, "only {in_layers} files in render's layers");
    let bad = breaches(&files, root_src);
    assert!(
        bad.is_empty(),
        "render layering broken:\n{}",
        bad.join("\n")
    );
}

#[test]
fn a_use_of_a_higher_layer_or_a_reexport_fails() {
    let root = "pub const TILE: u32 = 32;\npub use view::camera;\npub enum Method {}\n";
    let file = |rel: &str, src: &str| vec![(rel.to_string(), src.to_string())];
    // Down is fine, as are the root's own items.
    let ok = "use crate::render::view::camera::PixelRay;\nuse crate::render::{TILE, Method};\n";
    assert!(breaches(&file("render/trace/ray.rs", ok), root).is_empty());
    // Up fails, by either path form.
    let up = "use crate::render::{tile::TileOut, TILE};\n";
    let bad = breaches(&file("render/trace/ray.rs", up), root);
    assert_eq!(bad.len(), 1, "{bad:?}");
    assert!(bad[0].starts_with("render/trace/ray.rs:1: layer `trace` must not use `tile`"));
    let bad = breaches(
        &file("render/view/camera.rs", "use super::super::frame::x;\n"),
        root,
    );
    assert_eq!(bad.len(), 1, "{bad:?}");
    let bad = breaches(
        &file("render/light/mod.rs", "use super::aa::Classified;\n"),
        root,
    );
    assert_eq!(bad.len(), 1, "{bad:?}");
    // A sibling in the same layer, through one `super`, is no path to render.
    let sib = "use super::refine::refine;\n";
    assert!(breaches(&file("render/trace/ray.rs", sib), root).is_empty());
    // A re-export for users is not a layer's name.
    let reexport = "use crate::render::camera::RayCamera;\n";
    let bad = breaches(&file("render/trace/ray.rs", reexport), root);
    assert!(bad[0].contains("`camera` is not a layer"), "{bad:?}");
    // A file outside any layer fails.
    let bad = breaches(&file("render/misc/x.rs", ""), root);
    assert!(bad[0].contains("not one of render's layers"), "{bad:?}");
}
