//! Reading files: text that is not UTF-8 is an error at its first bad
//! byte, and input over the size limit is refused before it is read whole.

use super::*;
use ibeam::lang::MAX_SOURCE_BYTES;
use ibeam::lang::input::read_source_limited;

/// A scratch file of its own for each test, holding `bytes`.
fn scratch_file(name: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ibeam-lang-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn non_utf8_scene_names_offset_line_and_column() {
    // Latin-1 'é' (0xE9) on line 3, after "// caf" (two bytes of 'ä' before
    // it on line 2 count as one column there, not here).
    let text = b"let r = 1;\n// \xc3\xa4\nobject s = sphere(r); // caf\xe9\n";
    let p = scratch_file("latin1.ib", text);
    let e = load_scene(&p).unwrap_err();
    let offset = text.iter().position(|&b| b == 0xe9).unwrap();
    assert_eq!(offset, 45);
    assert!(
        e.message
            .contains(&format!("invalid byte 0xE9 at byte offset {offset}")),
        "{e}"
    );
    assert_eq!((e.line, e.col), (3, 29));
    let header = format!("{}:3:29: error: file is not valid UTF-8", p.display());
    assert!(e.rendered.starts_with(&header), "{}", e.rendered);
    // The snippet shows the line up to the bad byte with a caret under it.
    assert!(e.rendered.contains("| object s = sphere(r); // caf"), "{e}");
    assert!(e.rendered.contains('^'), "{e}");
    assert!(e.help.as_deref().is_some_and(|h| h.contains("UTF-8")));
}

#[test]
fn non_utf8_vm_model_is_the_same_error() {
    let p = scratch_file("bad.vm", b"_0 var-x\n_1 \x80neg _0\n");
    let e = load_scene(&p).unwrap_err();
    assert!(e.message.contains("0x80 at byte offset 12"), "{e}");
    assert_eq!((e.line, e.col), (2, 4));
}

#[test]
fn first_bad_byte_wins_and_valid_utf8_loads() {
    // Only the first of several bad bytes is reported.
    let e = err_of_bytes(b"object o = x; \xfe \xff");
    assert!(e.message.contains("0xFE at byte offset 14"), "{e}");
    // An overlong encoding is a bad byte too, not a character.
    let e = err_of_bytes(b"object o = x;\n\xc0\xaf");
    assert!(e.message.contains("0xC0 at byte offset 14"), "{e}");
    assert_eq!((e.line, e.col), (2, 1));
    // Valid multi-byte text (a comment in Greek) still loads.
    let p = scratch_file("greek.ib", "// σφαίρα\nobject s = sphere(1);\n".as_bytes());
    load_scene(&p).unwrap_or_else(|e| panic!("{e}"));
}

/// The error of loading `bytes` from a file.
fn err_of_bytes(bytes: &[u8]) -> LoadError {
    let p = scratch_file("bytes.ib", bytes);
    load_scene(&p).unwrap_err()
}

#[test]
fn size_limit_counts_bytes_exactly() {
    let p = scratch_file("sized.ib", b"object s = sphere(1);\n");
    let n = std::fs::metadata(&p).unwrap().len();
    assert_eq!(read_source_limited(&p, n).unwrap().len() as u64, n);
    let e = read_source_limited(&p, n - 1).unwrap_err();
    assert_eq!(
        e.message,
        format!(
            "`{}` is too large ({n} bytes): scene files are limited to {} bytes ({} B)",
            p.display(),
            n - 1,
            n - 1
        )
    );
    assert_eq!((e.line, e.col), (0, 0));
    assert!(e.rendered.starts_with(&format!("{}: error: ", p.display())));
}

#[test]
fn the_limit_is_256_mib_and_applies_to_load_scene() {
    assert_eq!(MAX_SOURCE_BYTES, 256 * 1024 * 1024);
    // A sparse file one byte over the limit: refused from its length,
    // without reading (or the disk holding) 256 MiB.
    let p = scratch_file("sparse.ib", b"");
    let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
    f.set_len(MAX_SOURCE_BYTES + 1).unwrap();
    drop(f);
    let t = std::time::Instant::now();
    let e = load_scene(&p).unwrap_err();
    assert!(t.elapsed().as_secs() < 2, "{:?}", t.elapsed());
    assert!(e.message.contains("too large (268435457 bytes)"), "{e}");
    assert!(e.message.contains("268435456 bytes (256 MiB)"), "{e}");
    std::fs::remove_file(&p).unwrap();
}

/// A device that never ends reports no length: the read itself stops one
/// byte past the limit.
#[cfg(unix)]
#[test]
fn endless_device_is_refused_by_the_read() {
    let e = read_source_limited(Path::new("/dev/zero"), 4096).unwrap_err();
    assert_eq!(
        e.message,
        "`/dev/zero` is too large: scene files are limited to 4096 bytes (4 KiB)"
    );
    // Within the limit, a device's bytes are read like a file's.
    let e = read_source_limited(Path::new("/dev/null"), 4096).unwrap();
    assert_eq!(e, "");
}
