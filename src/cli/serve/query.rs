//! A view the page asks for, from a request's query string: the camera
//! flags of `ibeam render` and the page's switches, parsed by the same
//! clap definitions as the command line, so a value the CLI refuses is
//! refused here too; unknown or repeated keys are refused as well.

use clap::Parser;

use super::super::image::{MethodArg, parse_aa, parse_size};
use super::super::view::ViewArgs;
use ibeam::render::Aa;

/// Largest side the page may ask for: a browser view, not a print.
pub const MAX_SIDE: u32 = 4096;

/// The keys a query may have.
const KEYS: [&str; 12] = [
    "eye", "target", "up", "fov", "ortho", "orbit", "zoom", "size", "method", "aa", "shadows",
    "preview",
];

/// On or off, for a switch the scene also sets.
#[derive(Copy, Clone, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    /// Every light casts shadows.
    On,
    /// No light does.
    Off,
}

/// A view asked for by the page.
#[derive(Parser, Debug, Default)]
#[command(
    no_binary_name = true,
    disable_help_flag = true,
    disable_version_flag = true
)]
pub struct Query {
    /// The camera, on top of the scene's (as set by the command line).
    #[command(flatten)]
    pub view: ViewArgs,
    /// The full image's size (a preview is a quarter of it per side).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// The visibility method.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// Anti-aliasing.
    #[arg(long, value_parser = parse_aa)]
    pub aa: Option<Aa>,
    /// Shadows on or off, whatever the scene says.
    #[arg(long, value_enum)]
    pub shadows: Option<Switch>,
    /// A quick preview (a quarter of the size, no anti-aliasing) while
    /// the camera moves.
    #[arg(long)]
    pub preview: Option<bool>,
}

/// Parses a query string (`a=1&b=2`, percent-encoded).
pub fn parse(query: &str) -> Result<Query, String> {
    let mut argv: Vec<String> = Vec::new();
    let mut seen: Vec<&str> = Vec::new();
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        let (key, value) = pair
            .split_once('=')
            .ok_or_else(|| format!("`{}`: expected key=value", shorten(pair)))?;
        let key = KEYS
            .iter()
            .find(|k| **k == key)
            .ok_or_else(|| format!("unknown parameter `{}`", shorten(key)))?;
        if seen.contains(key) {
            return Err(format!("parameter `{key}` given twice"));
        }
        seen.push(key);
        argv.push(format!("--{key}={}", decode(value)?));
    }
    let mut q = Query::try_parse_from(&argv).map_err(|e| {
        // clap's message, without its usage lines about a command line.
        let text = e.to_string();
        text.lines().next().unwrap_or("bad query").to_string()
    })?;
    if let Some((w, h)) = q.size
        && (w > MAX_SIDE || h > MAX_SIDE)
    {
        return Err(format!(
            "size {w}x{h}: each side must be at most {MAX_SIDE}"
        ));
    }
    // The scene's camera is already framed; a view never reframes it.
    q.view.no_fit = true;
    Ok(q)
}

/// The first 40 characters of untrusted text, for an error message.
fn shorten(s: &str) -> String {
    s.chars().take(40).collect()
}

/// Decodes `%XX` escapes and `+` (a space); the result must be UTF-8.
fn decode(s: &str) -> Result<String, String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'%' => {
                let hex = bytes
                    .get(i + 1..i + 3)
                    .and_then(|h| std::str::from_utf8(h).ok())
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
                    .ok_or("bad percent escape in the query")?;
                out.push(hex);
                i += 3;
            }
            b'+' => {
                out.push(b' ');
                i += 1;
            }
            b => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8(out).map_err(|_| "the query is not UTF-8".to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_parse_strictly() {
        let q = parse("eye=1%2C2%2C3&target=0,0,0&fov=40&size=64x48&preview=true").unwrap();
        assert_eq!(q.view.eye, Some([1.0, 2.0, 3.0]));
        assert_eq!(q.view.fov, Some(40.0));
        assert_eq!((q.size, q.preview), (Some((64, 48)), Some(true)));
        assert!(q.view.no_fit);
        let q = parse("eye=-1,-2,-3&aa=grid:2&method=pixel&shadows=off").unwrap();
        assert_eq!(q.view.eye, Some([-1.0, -2.0, -3.0]));
        assert_eq!((q.aa, q.shadows), (Some(Aa::Grid(2)), Some(Switch::Off)));
        assert!(parse("").unwrap().view.eye.is_none());
        for bad in [
            "eye=1,2",
            "eye=1,2,nan",
            "eye=1,2,3&eye=1,2,3",
            "fov=180",
            "fov=40&ortho=2",
            "zoom=0",
            "size=5000x10",
            "size=0x10",
            "method=magic",
            "help=1",
            "fit=true",
            "eye",
            "eye=%zz",
            "eye=%ff,1,1",
            "preview=maybe",
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }
}
