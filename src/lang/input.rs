//! Reading a scene file's bytes: the size limit and the UTF-8 check, in
//! one place so that every way of loading a file (the main file, and each
//! file it imports) is bounded the same way.

use super::LoadError;
use super::diag::{self, Diag, Sources};
use std::fs::File;
use std::io::Read;
use std::path::Path;

/// Largest scene or `.vm` file the loader reads, in bytes (256 MiB).
///
/// Bigger input is refused before it is read whole, so a mistaken path
/// (`/dev/zero`, a pipe, a huge binary, a file that keeps growing) costs
/// at most this much memory instead of exhausting it; the largest real
/// models (Fidget's prospero.vm is a few MiB) are far below it.
pub const MAX_SOURCE_BYTES: u64 = 256 << 20;

/// The text of the scene file at `path`, refused with a diagnostic when it
/// is over [`MAX_SOURCE_BYTES`] or not UTF-8.
pub fn read_source(path: &Path) -> Result<String, LoadError> {
    read_source_limited(path, MAX_SOURCE_BYTES)
}

/// [`read_source`] with the size limit as a parameter, so that tests can
/// exercise the limit with a tiny one instead of a 256 MiB file.
pub fn read_source_limited(path: &Path, limit: u64) -> Result<String, LoadError> {
    let name = path.display().to_string();
    let bytes = read_bytes(path, limit)
        .map_err(|f| diag::error_without_position(&name, f.message(&name)))?;
    decode_source(&name, bytes)
}

/// Why a file's bytes could not be had; an import reports it at the
/// `import` statement, a main file without a position.
#[derive(Debug)]
pub(crate) enum ReadFailure {
    /// Opening or reading failed (missing file, a folder, permissions).
    Io(std::io::Error),
    /// Over the limit: (size when known, the limit).
    TooLarge(Option<u64>, u64),
}

impl ReadFailure {
    /// The one-line message, naming the file `name`.
    pub(crate) fn message(&self, name: &str) -> String {
        match self {
            ReadFailure::Io(e) => format!("cannot read `{name}`: {e}"),
            ReadFailure::TooLarge(size, limit) => too_large(name, *size, *limit),
        }
    }
}

/// The bytes of `path`, at most `limit` of them.
pub(crate) fn read_bytes(path: &Path, limit: u64) -> Result<Vec<u8>, ReadFailure> {
    let file = File::open(path).map_err(ReadFailure::Io)?;
    // The length up front refuses a big regular file without reading it;
    // devices and pipes report 0 here and are caught by `take` below.
    if let Ok(meta) = file.metadata()
        && meta.is_file()
        && meta.len() > limit
    {
        return Err(ReadFailure::TooLarge(Some(meta.len()), limit));
    }
    let mut bytes = Vec::new();
    // One byte past the limit tells "exactly at the limit" from "over
    // it" without ever reading further.
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(ReadFailure::Io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadFailure::TooLarge(None, limit));
    }
    Ok(bytes)
}

/// `bytes` as text, or a diagnostic at the first byte that is not UTF-8.
pub fn decode_source(name: &str, bytes: Vec<u8>) -> Result<String, LoadError> {
    match String::from_utf8(bytes) {
        Ok(text) => Ok(text),
        Err(e) => Err(not_utf8(name, e.as_bytes(), e.utf8_error())),
    }
}

/// The size-limit message; `size` is known for a regular file only.
fn too_large(name: &str, size: Option<u64>, limit: u64) -> String {
    let size = match size {
        Some(s) => format!(" ({s} bytes)"),
        None => String::new(),
    };
    format!(
        "`{name}` is too large{size}: scene files are limited to {limit} bytes ({})",
        human_bytes(limit)
    )
}

/// `n` bytes in the largest binary unit that divides it, for messages.
fn human_bytes(n: u64) -> String {
    for (shift, unit) in [(30, "GiB"), (20, "MiB"), (10, "KiB")] {
        if n >= 1 << shift && n.is_multiple_of(1 << shift) {
            return format!("{} {unit}", n >> shift);
        }
    }
    format!("{n} B")
}

/// The UTF-8 error rendered like any other diagnostic: the line up to the
/// bad byte is shown (the bad bytes as U+FFFD) with a caret under it, and
/// line and column count the valid text before it.
fn not_utf8(name: &str, bytes: &[u8], e: std::str::Utf8Error) -> LoadError {
    let offset = e.valid_up_to();
    let what = match e.error_len() {
        Some(n) => {
            let bad: Vec<String> = bytes[offset..offset + n]
                .iter()
                .map(|b| format!("0x{b:02X}"))
                .collect();
            format!("invalid byte {} at byte offset {offset}", bad.join(" "))
        }
        None => format!("incomplete character at the end of the file, byte offset {offset}"),
    };
    // Only the bad byte's line is needed for the snippet; the rest of a
    // possibly huge file is not copied.
    let line_end = bytes[offset..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| offset + i);
    let shown = String::from_utf8_lossy(&bytes[..line_end]);
    let mut sources = Sources::default();
    let src = sources.add(name, &shown);
    // The valid prefix is unchanged by the lossy copy, so `offset` is the
    // replacement character's position in `shown`.
    let end = offset + shown[offset..].chars().next().map_or(0, char::len_utf8);
    let d = Diag::new(src, offset..end, format!("file is not valid UTF-8: {what}"))
        .with_help("scene files must be UTF-8 text; convert it, e.g. with `iconv -t UTF-8`");
    sources.render(&d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_in_messages() {
        assert_eq!(human_bytes(MAX_SOURCE_BYTES), "256 MiB");
        assert_eq!(human_bytes(3 << 10), "3 KiB");
        assert_eq!(human_bytes(1000), "1000 B");
    }

    #[test]
    fn first_bad_byte_has_offset_line_and_column() {
        let e = decode_source("t.ib", b"let a = 1;\nlet \xc3\xa9b = \xff;\n".to_vec()).unwrap_err();
        // 'é' is one column: columns count characters.
        assert_eq!((e.line, e.col), (2, 10));
        assert!(e.message.contains("0xFF at byte offset 21"), "{e}");
        assert!(
            e.rendered
                .starts_with("t.ib:2:10: error: file is not valid UTF-8")
        );
        assert!(e.rendered.contains('^'), "{e}");
    }

    #[test]
    fn truncated_character_at_the_end() {
        let e = decode_source("t.ib", b"ab\xe2\x82".to_vec()).unwrap_err();
        assert_eq!((e.line, e.col), (1, 3));
        assert!(e.message.contains("incomplete character"), "{e}");
        assert!(e.message.contains("byte offset 2"), "{e}");
    }
}
