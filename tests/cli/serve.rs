//! `ibeam serve` end to end: the real binary on a scene in a scratch
//! folder, asked over plain HTTP/1.0 (the requests are written by hand so
//! that paths like `/../x` reach the server as they are). Waits poll with
//! a generous timeout; nothing is timed.
#![cfg(unix)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// How long any one wait may take before the test fails.
const PATIENCE: Duration = Duration::from_secs(60);

/// A running `ibeam serve`, stopped when dropped.
struct Serving {
    child: Child,
    addr: String,
}

impl Drop for Serving {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A response: status, headers (lower-case names) and body.
struct Reply {
    status: u16,
    headers: Vec<(String, String)>,
    body: Vec<u8>,
}

impl Reply {
    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|h| h.0 == name)
            .map(|h| h.1.as_str())
    }

    fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
}

impl Serving {
    fn start(scene: &Path) -> Serving {
        let mut child = Command::new(env!("CARGO_BIN_EXE_ibeam"))
            .args(["serve", scene.to_str().unwrap(), "--port", "0"])
            .args(["--size", "64x48", "--eval", "interp", "--threads", "1"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("run ibeam serve");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let url = line
            .split_whitespace()
            .find(|w| w.starts_with("http://"))
            .unwrap_or_else(|| panic!("no URL in {line:?}"));
        let addr = url
            .trim_start_matches("http://")
            .trim_end_matches('/')
            .to_string();
        assert!(addr.starts_with("127.0.0.1:"), "{addr}");
        Serving { child, addr }
    }

    /// Sends `request_line` (e.g. `GET / HTTP/1.0`) with a Host header.
    fn raw(&self, request_line: &str) -> Reply {
        let mut s = TcpStream::connect(&self.addr).unwrap();
        write!(s, "{request_line}\r\nHost: {}\r\n\r\n", self.addr).unwrap();
        let mut bytes = Vec::new();
        s.read_to_end(&mut bytes).unwrap();
        let split = bytes
            .windows(4)
            .position(|w| w == b"\r\n\r\n")
            .expect("a header block");
        let head = String::from_utf8_lossy(&bytes[..split]).into_owned();
        let mut lines = head.lines();
        let status = lines.next().unwrap().split(' ').nth(1).unwrap();
        let headers = lines
            .filter_map(|l| l.split_once(':'))
            .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_string()))
            .collect();
        Reply {
            status: status.parse().unwrap(),
            headers,
            body: bytes[split + 4..].to_vec(),
        }
    }

    fn get(&self, path: &str) -> Reply {
        self.raw(&format!("GET {path} HTTP/1.0"))
    }

    /// The state's JSON once `ok` holds for it.
    fn wait_state(&self, what: &str, ok: impl Fn(&serde_json::Value) -> bool) -> serde_json::Value {
        let start = Instant::now();
        loop {
            let s: serde_json::Value =
                serde_json::from_slice(&self.get("/state.json").body).unwrap();
            if ok(&s) {
                return s;
            }
            assert!(
                start.elapsed() < PATIENCE,
                "timed out waiting for {what}: {s}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

fn scratch(test: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("ibeam-serve-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const SPHERE: &str = "object s = x^2 + y^2 + z^2 - 1 { color = (0.8, 0.3, 0.2); }\n\
camera { eye = (0, 0, 4); target = (0, 0, 0); up = (0, 1, 0); fov = 40; }\n\
light { direction = (-0.5, -1, -0.7); }\n\
bounds = (-2, -2, -2) .. (2, 2, 2);\n";

/// A PNG's size and pixels.
fn png(r: &Reply) -> image::RgbImage {
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.header("content-type"), Some("image/png"));
    image::load_from_memory(&r.body).expect("a PNG").to_rgb8()
}

#[test]
fn page_images_edits_and_errors() {
    let dir = scratch("edits");
    let file = dir.join("scene.ib");
    std::fs::write(&file, SPHERE).unwrap();
    let srv = Serving::start(&file);

    let page = srv.get("/");
    assert_eq!(page.status, 200);
    assert!(page.text().contains("<img id=\"view\""));
    assert_eq!(srv.get("/source.txt").text(), SPHERE);
    let ir = srv.get("/ir.txt").text();
    assert!(
        ir.starts_with("; object s\n") && ir.contains("var x"),
        "{ir}"
    );

    let full = png(&srv.get("/image.png"));
    assert_eq!(full.dimensions(), (64, 48));
    assert_eq!(
        png(&srv.get("/image.png?preview=true")).dimensions(),
        (16, 12)
    );
    assert_eq!(
        png(&srv.get("/image.png?size=40x30")).dimensions(),
        (40, 30)
    );
    // The sphere fills the middle, not the corner.
    assert_ne!(full.get_pixel(32, 24), full.get_pixel(0, 0));
    let turned = srv.get("/image.png?eye=4,0,0.5&target=0,0,0&up=0,1,0&fov=40");
    assert_eq!(
        turned.header("x-ibeam-camera"),
        Some("--eye 4,0,0.5 --target 0,0,0 --up 0,1,0 --fov 40")
    );
    let stats: serde_json::Value =
        serde_json::from_str(turned.header("x-ibeam-stats").unwrap()).unwrap();
    assert!(stats["stats"]["rays"].as_u64().unwrap() > 0, "{stats}");
    let last: serde_json::Value = serde_json::from_slice(&srv.get("/stats.json").body).unwrap();
    assert_eq!(last, stats);
    let exr = srv.get("/image.exr");
    assert_eq!(exr.status, 200);
    assert_eq!(&exr.body[..4], &[0x76, 0x2f, 0x31, 0x01], "OpenEXR magic");

    // An edit (a smaller sphere) re-renders.
    let g = srv.wait_state("the first load", |s| s["generation"] == 1)["generation"].clone();
    std::fs::write(&file, SPHERE.replace("- 1 {", "- 0.25 {")).unwrap();
    srv.wait_state("the edit", |s| s["generation"] != g && s["error"].is_null());
    let small = png(&srv.get("/image.png"));
    assert_ne!(small, full);

    // A broken edit: the located error, and the last good image.
    std::fs::write(&file, "object s = x^2 + ;\n").unwrap();
    let s = srv.wait_state("the error", |s| s["error"].is_string());
    let e = s["error"].as_str().unwrap();
    assert!(e.contains("scene.ib:1:18: error: unexpected `;`"), "{e}");
    assert_eq!(png(&srv.get("/image.png")), small);
    // The next good save clears it.
    std::fs::write(&file, SPHERE).unwrap();
    srv.wait_state("the fix", |s| {
        s["error"].is_null() && s["generation"].as_u64() > Some(3)
    });
    assert_eq!(png(&srv.get("/image.png")), full);
}

#[test]
fn bad_requests_get_4xx_and_no_path_reaches_a_file() {
    let dir = scratch("bad");
    let file = dir.join("scene.ib");
    std::fs::write(&file, SPHERE).unwrap();
    std::fs::write(dir.join("secret.txt"), "do not serve").unwrap();
    let srv = Serving::start(&file);
    for (path, status) in [
        ("/image.png?eye=1,2", 400),
        ("/image.png?eye=1,2,3&eye=1,2,3", 400),
        ("/image.png?fov=200", 400),
        ("/image.png?size=100000x10", 400),
        ("/image.png?bogus=1", 400),
        ("/image.png?help=", 400),
        ("/image.png?eye=%zz", 400),
        ("/image.png?eye=0,0,0&target=0,0,0", 422),
        ("/state.json?x=1", 400),
        ("/secret.txt", 404),
        ("/scene.ib", 404),
        ("/../secret.txt", 404),
        ("/%2e%2e/secret.txt", 404),
        ("/source.txt/../secret.txt", 404),
        ("//etc/passwd", 404),
        ("/image.png/../../secret.txt", 404),
    ] {
        let r = srv.get(path);
        assert_eq!(r.status, status, "{path}: {}", r.text());
        assert!(!r.text().contains("do not serve"), "{path}");
    }
    assert_eq!(srv.raw("POST /image.png HTTP/1.0").status, 405);
    assert_eq!(srv.raw("DELETE / HTTP/1.0").status, 405);
    let mut s = TcpStream::connect(&srv.addr).unwrap();
    write!(
        s,
        "GET /state.json HTTP/1.0\r\nHost: attacker.example\r\n\r\n"
    )
    .unwrap();
    let mut reply = String::new();
    s.read_to_string(&mut reply).unwrap();
    assert!(
        reply.starts_with("HTTP/1.0 403") || reply.starts_with("HTTP/1.1 403"),
        "{reply}"
    );
    // Garbage on the wire is answered (or dropped), and the server lives on.
    let mut s = TcpStream::connect(&srv.addr).unwrap();
    let _ = s.write_all(b"\x00\xff garbage\r\n\r\n");
    let mut sink = Vec::new();
    let _ = s.read_to_end(&mut sink);
    assert_eq!(srv.get("/").status, 200);

    // An import from outside the scene's folder is refused.
    let outside = scratch("bad-outside");
    std::fs::write(outside.join("lib.ib"), "let k = 1;\n").unwrap();
    let import = format!("import \"{}\";\n{SPHERE}", outside.join("lib.ib").display());
    std::fs::write(&file, import).unwrap();
    let s = srv.wait_state("the refusal", |s| s["error"].is_string());
    let e = s["error"].as_str().unwrap();
    assert!(e.contains("refused") && e.contains("lib.ib"), "{e}");
}

#[test]
fn a_burst_of_views_leaves_one_render() {
    let dir = scratch("burst");
    let file = dir.join("scene.ib");
    std::fs::write(&file, SPHERE).unwrap();
    let srv = Serving::start(&file);
    let addr = srv.addr.clone();
    let threads: Vec<_> = (0..12)
        .map(|i| {
            let a = addr.clone();
            std::thread::spawn(move || {
                let mut s = TcpStream::connect(&a).unwrap();
                let q = format!("eye=4,{i},1&size=400x400");
                write!(s, "GET /image.png?{q} HTTP/1.0\r\nHost: {a}\r\n\r\n").unwrap();
                let mut bytes = Vec::new();
                s.read_to_end(&mut bytes).unwrap();
                String::from_utf8_lossy(&bytes[..12]).into_owned()
            })
        })
        .collect();
    let statuses: Vec<String> = threads.into_iter().map(|t| t.join().unwrap()).collect();
    // Each is a finished image or superseded; never an error or a crash.
    assert!(
        statuses
            .iter()
            .all(|s| s.ends_with(" 200") || s.ends_with(" 409")),
        "{statuses:?}"
    );
    assert!(statuses.iter().any(|s| s.ends_with(" 200")), "{statuses:?}");
    assert_eq!(srv.get("/").status, 200);
}
