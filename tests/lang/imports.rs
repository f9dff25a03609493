//! `import "path";`: definitions from other files, paths relative to the
//! importing file, each file read once, cycles, errors located in the file
//! they are in, and the list of files read.

use super::*;
use ibeam::lang::load_scene_with_files;

/// A fresh folder holding `files` (path relative to it, text).
fn tree(test: &str, files: &[(&str, &str)]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ibeam-imports-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for (path, text) in files {
        let p = dir.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
    }
    dir
}

/// The load error of `dir/main.ib`, which must fail.
fn load_err(dir: &Path) -> LoadError {
    match load_scene(&dir.join("main.ib")) {
        Ok(_) => panic!("{} loads", dir.display()),
        Err(e) => e,
    }
}

/// `name` in `dir`, as diagnostics show it.
fn shown(dir: &Path, name: &str) -> String {
    dir.join(name).display().to_string()
}

#[test]
fn import_brings_in_lets_and_fns() {
    let dir = tree(
        "basic",
        &[
            ("lib.ib", "let r = 0.5;\nfn ball(s) = sphere(s);\n"),
            ("main.ib", "import \"lib.ib\";\nobject o = ball(r);\n"),
        ],
    );
    let s = load_scene(&dir.join("main.ib")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.objects.len(), 1);
    assert_close(eval(&s.objects[0].function, [0.0; 3]), -0.5);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn paths_are_relative_to_the_importing_file() {
    let dir = tree(
        "relative",
        &[
            (
                "scenes/main.ib",
                "import \"../lib/a.ib\";\nobject o = sphere(k);\n",
            ),
            // From lib/, "./sub/b.ib" is lib/sub/b.ib, and "../c.ib" is c.ib.
            ("lib/a.ib", "import \"./sub/b.ib\";\n"),
            ("lib/sub/b.ib", "import \"../../c.ib\";\n"),
            ("c.ib", "let k = 2;\n"),
        ],
    );
    let loaded = load_scene_with_files(&dir.join("scenes/main.ib"));
    let s = loaded.scene.unwrap_or_else(|e| panic!("{e}"));
    assert_close(eval(&s.objects[0].function, [0.0; 3]), -2.0);
    let canon = |p: &str| std::fs::canonicalize(dir.join(p)).unwrap();
    assert_eq!(
        loaded.files,
        ["scenes/main.ib", "lib/a.ib", "lib/sub/b.ib", "c.ib"].map(canon)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_diamond_reads_the_shared_file_once() {
    let dir = tree(
        "diamond",
        &[
            (
                "main.ib",
                "import \"a.ib\";\nimport \"b.ib\";\nimport \"./a.ib\";\nobject o = sphere(ka + kb + k);\n",
            ),
            ("a.ib", "import \"c.ib\";\nlet ka = k;\n"),
            ("b.ib", "import \"c.ib\";\nlet kb = k;\n"),
            ("c.ib", "let k = 0.25;\n"),
        ],
    );
    let loaded = load_scene_with_files(&dir.join("main.ib"));
    let s = loaded.scene.unwrap_or_else(|e| panic!("{e}"));
    assert_close(eval(&s.objects[0].function, [0.0; 3]), -0.75);
    let canon = |p: &str| std::fs::canonicalize(dir.join(p)).unwrap();
    assert_eq!(loaded.files, ["main.ib", "a.ib", "c.ib", "b.ib"].map(canon));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_cycle_is_an_error_at_the_import_that_closes_it() {
    let dir = tree(
        "cycle",
        &[
            ("main.ib", "import \"a.ib\";\nobject o = sphere(1);\n"),
            ("a.ib", "import \"b.ib\";\n"),
            ("b.ib", "let k = 1;\n  import \"a.ib\";\n"),
        ],
    );
    let e = load_err(&dir);
    let (a, b) = (shown(&dir, "a.ib"), shown(&dir, "b.ib"));
    assert_eq!(
        e.message,
        format!("import cycle: `{a}` imports `{b}`, which imports `{a}`")
    );
    assert_eq!((e.file.as_str(), e.line, e.col), (b.as_str(), 2, 3));
    assert!(
        e.rendered
            .starts_with(&format!("{b}:2:3: error: import cycle"))
    );
    assert!(e.rendered.contains("^^^^^^^^^^^^^"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_file_importing_itself_is_a_cycle() {
    let dir = tree(
        "self",
        &[("main.ib", "import \"main.ib\";\nobject o = sphere(1);\n")],
    );
    let e = load_err(&dir);
    assert!(e.message.ends_with("main.ib` imports itself"), "{e}");
    assert_eq!((e.line, e.col), (1, 1));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn errors_inside_an_imported_file_name_that_file() {
    let dir = tree(
        "inner",
        &[
            (
                "main.ib",
                "import \"lib/shapes.ib\";\nobject o = wobble(1);\n",
            ),
            ("lib/shapes.ib", "// shapes\n\nfn wobble(r) = sphre(r);\n"),
        ],
    );
    let e = load_err(&dir);
    let lib = shown(&dir, "lib/shapes.ib");
    assert_eq!((e.file.as_str(), e.line, e.col), (lib.as_str(), 3, 16));
    assert!(e.message.contains("sphre"), "{e}");
    assert!(
        e.rendered.starts_with(&format!("{lib}:3:16: error: ")),
        "{e}"
    );
    assert!(e.rendered.contains("| fn wobble(r) = sphre(r);"), "{e}");

    // A syntax error is found in the imported file too.
    std::fs::write(dir.join("lib/shapes.ib"), "fn wobble(r) = sphere(r)\n").unwrap();
    let e = load_err(&dir);
    assert_eq!((e.file.as_str(), e.line), (lib.as_str(), 1));
    assert!(e.message.contains("end of input"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_missing_import_is_an_error_at_the_import() {
    let dir = tree(
        "missing",
        &[(
            "main.ib",
            "object o = sphere(1);\n\nimport \"lib/nope.ib\";\n",
        )],
    );
    let e = load_err(&dir);
    let main = shown(&dir, "main.ib");
    let nope = shown(&dir, "lib/nope.ib");
    assert_eq!((e.file.as_str(), e.line, e.col), (main.as_str(), 3, 8));
    assert!(
        e.message.starts_with(&format!("cannot read `{nope}`")),
        "{e}"
    );
    // The missing file is in the list, so `ibeam watch` notices its creation.
    let loaded = load_scene_with_files(&dir.join("main.ib"));
    assert!(loaded.scene.is_err());
    assert_eq!(loaded.files.last(), Some(&dir.join("lib/nope.ib")));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn only_plain_files_are_imported() {
    let dir = tree(
        "folder",
        &[
            ("main.ib", "import \"lib\";\nobject o = sphere(1);\n"),
            ("lib/a.ib", "let a = 1;\n"),
        ],
    );
    let e = load_err(&dir);
    assert_eq!((e.line, e.col), (1, 8));
    assert!(e.message.ends_with("it is not a file"), "{e}");
    #[cfg(unix)]
    {
        // A device would be read forever (or block, like a FIFO).
        std::fs::write(dir.join("main.ib"), "import \"/dev/zero\";\n").unwrap();
        let e = load_err(&dir);
        assert!(e.message.ends_with("it is not a file"), "{e}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn importing_a_vm_model_is_an_error() {
    let dir = tree(
        "vm",
        &[
            ("main.ib", "import \"m.vm\";\nobject o = sphere(1);\n"),
            ("m.vm", "_0 var-x\n"),
        ],
    );
    let e = load_err(&dir);
    assert_eq!((e.line, e.col), (1, 8));
    assert!(
        e.message.contains("a `.vm` model has no definitions"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_clash_between_files_is_reported_at_the_later_definition() {
    let dir = tree(
        "clash",
        &[
            (
                "main.ib",
                "import \"lib.ib\";\nlet r = 2;\nobject o = sphere(r);\n",
            ),
            ("lib.ib", "let r = 1;\n"),
        ],
    );
    let e = load_err(&dir);
    let main = shown(&dir, "main.ib");
    assert_eq!(e.message, "`r` is defined twice");
    assert_eq!((e.file.as_str(), e.line, e.col), (main.as_str(), 2, 5));
    // The first definition is shown in its own file.
    assert!(e.rendered.contains(&shown(&dir, "lib.ib")), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn imported_objects_and_settings_are_left_out() {
    let dir = tree(
        "items",
        &[
            ("main.ib", "import \"lib.ib\";\nobject o = ball;\n"),
            (
                "lib.ib",
                "let ball = sphere(1);\nobject demo = ball;\ncamera { eye = (9, 9, 9); }\n\
                 light { direction = (0, -1, 0); }\nbounds = (-1, -1, -1) .. (1, 1, 1);\n\
                 render { size = (7, 7); }\n",
            ),
        ],
    );
    let s = load_scene(&dir.join("main.ib")).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = s.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["o"]);
    let defaults = scene("object o = sphere(1);");
    assert_eq!(s.camera.eye, defaults.camera.eye);
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.render.size, defaults.render.size);
    assert_eq!(s.bounds.min, defaults.bounds.min);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn import_syntax_errors() {
    assert_err("import lib;", "unexpected name `lib`", 1, 8);
    assert_err("import \"lib.ib\"", "unexpected end of input", 1, 16);
    assert_err("import \"lib.ib;\nlet a = 1;", "unterminated string", 1, 8);
    assert_err(
        "import \"\";\nobject o = sphere(1);",
        "needs a file name",
        1,
        8,
    );
    assert_err("let a = \"x\";", "unexpected string", 1, 9);
}

#[test]
fn imports_nest_a_bounded_number_of_files_deep() {
    use ibeam::lang::imports::MAX_IMPORT_DEPTH;
    let n = MAX_IMPORT_DEPTH + 10;
    let texts: Vec<(String, String)> = (0..n)
        .map(|i| (format!("f{i}.ib"), format!("import \"f{}.ib\";\n", i + 1)))
        .chain([(format!("f{n}.ib"), "let k = 1;\n".to_string())])
        .chain([(
            "main.ib".to_string(),
            "import \"f0.ib\";\nobject o = sphere(k);\n".to_string(),
        )])
        .collect();
    let files: Vec<(&str, &str)> = texts
        .iter()
        .map(|(p, t)| (p.as_str(), t.as_str()))
        .collect();
    let dir = tree("deep", &files);
    let e = load_err(&dir);
    assert!(e.message.starts_with("imports nest too deeply"), "{e}");
    assert_eq!(e.line, 1);
    let _ = std::fs::remove_dir_all(&dir);
}
