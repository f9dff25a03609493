//! `ibeam watch` end to end: the real binary on a scene in a scratch
//! folder, edited the ways people edit (in place, and by an editor's
//! write-and-rename), broken and fixed, then stopped with SIGINT. Waits
//! poll with a generous timeout; nothing is timed. Unix only: the test
//! stops the watcher with `kill -INT`.
#![cfg(unix)]

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// How long any one wait may take before the test fails: far above a
/// 32×32 render, for a loaded machine.
const PATIENCE: Duration = Duration::from_secs(60);

/// The size the test renders at (the preview is a quarter of it per side).
const SIZE: (u32, u32) = (32, 32);

/// Polls `ok` until it holds, failing after [`PATIENCE`] with `what`.
fn wait_until(what: &str, watching: &mut Watching, mut ok: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ok() {
        if let Ok(Some(status)) = watching.child.try_wait() {
            panic!(
                "ibeam watch exited ({status}) while waiting for {what}; stderr:\n{}",
                watching.stderr()
            );
        }
        assert!(
            start.elapsed() < PATIENCE,
            "timed out waiting for {what}; stderr:\n{}",
            watching.stderr()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The bytes of the PNG at `path` when it is a whole image of [`SIZE`]
/// (not the preview, not missing).
fn full_image(path: &Path) -> Option<Vec<u8>> {
    let bytes = std::fs::read(path).ok()?;
    let img = image::load_from_memory(&bytes).ok()?;
    ((img.width(), img.height()) == SIZE).then_some(bytes)
}

/// A running `ibeam watch` and everything it has written to stderr.
struct Watching {
    child: Child,
    err: Arc<Mutex<String>>,
}

impl Watching {
    fn start(scene: &Path, out: &Path) -> Watching {
        let size = format!("{}x{}", SIZE.0, SIZE.1);
        let mut child = Command::new(env!("CARGO_BIN_EXE_ibeam"))
            .args([
                "watch",
                scene.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ])
            .args(["--size", &size, "--eval", "interp", "--threads", "1"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run ibeam watch");
        let err = Arc::new(Mutex::new(String::new()));
        let mut pipe = child.stderr.take().unwrap();
        let sink = Arc::clone(&err);
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = pipe.read(&mut buf) {
                if n == 0 {
                    break;
                }
                sink.lock()
                    .unwrap()
                    .push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        Watching { child, err }
    }

    fn stderr(&self) -> String {
        self.err.lock().unwrap().clone()
    }
}

impl Drop for Watching {
    fn drop(&mut self) {
        // Only a failed test gets here with the process running.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Saves `text` to `path` as many editors do: a new file renamed over it.
fn save_by_rename(path: &Path, text: &str) {
    let tmp = path.with_extension("ib.swp");
    std::fs::write(&tmp, text).unwrap();
    std::fs::rename(&tmp, path).unwrap();
}

#[test]
fn watch_rerenders_on_save_keeps_going_after_errors_and_stops_on_sigint() {
    let dir: PathBuf = super::scratch("watch");
    let (scene, lib, out) = (
        dir.join("scene.ib"),
        dir.join("lib/shapes.ib"),
        dir.join("out.png"),
    );
    std::fs::create_dir_all(lib.parent().unwrap()).unwrap();
    std::fs::write(&lib, "fn ball(r) = sphere(r);\n").unwrap();
    let scene_with = |call: &str| format!("import \"lib/shapes.ib\";\nobject o = {call};\n");
    std::fs::write(&scene, scene_with("ball(0.8)")).unwrap();

    let mut w = Watching::start(&scene, &out);
    let mut last = Vec::new();
    wait_until("the first image", &mut w, || {
        full_image(&out).is_some_and(|b| {
            last = b;
            true
        })
    });

    let mut changed = |what: &str, w: &mut Watching| {
        let before = last.clone();
        wait_until(what, w, || {
            full_image(&out).is_some_and(|b| {
                let differs = b != before;
                last = b;
                differs
            })
        });
    };

    // Each image is preceded by a preview a quarter of its size.
    let err = Arc::clone(&w.err);
    wait_until("the preview's message", &mut w, || {
        err.lock().unwrap().contains("wrote a preview to")
    });
    assert!(w.stderr().contains("(8x8)"), "{}", w.stderr());

    // Saved in place: the main file.
    std::fs::write(&scene, scene_with("ball(0.5)")).unwrap();
    changed("the image after editing the scene", &mut w);

    // Saved by rename: the imported file.
    save_by_rename(&lib, "fn ball(r) = sphere(1.5 * r);\n");
    changed("the image after editing the import", &mut w);

    // A broken edit: its located error, and the watch goes on.
    std::fs::write(&scene, scene_with("bal(0.5)")).unwrap();
    let header = format!("{}:2:12: error: ", scene.display());
    wait_until("the error of the broken edit", &mut w, || {
        err.lock().unwrap().contains(&header)
    });
    assert!(w.child.try_wait().unwrap().is_none(), "{}", w.stderr());
    assert!(w.stderr().contains("^^^"), "{}", w.stderr());

    // Fixed again: renders again.
    std::fs::write(&scene, scene_with("ball(0.3)")).unwrap();
    changed("the image after fixing the scene", &mut w);

    let kill = Command::new("kill")
        .args(["-INT", &w.child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(kill.success());
    let start = Instant::now();
    let status = loop {
        if let Some(s) = w.child.try_wait().unwrap() {
            break s;
        }
        assert!(start.elapsed() < PATIENCE, "ibeam watch ignored SIGINT");
        std::thread::sleep(Duration::from_millis(50));
    };
    assert_eq!(status.code(), Some(0), "stderr:\n{}", w.stderr());
    let leftovers: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("ibeam-watch"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    assert!(full_image(&out).is_some());
    drop(w);
    let _ = std::fs::remove_dir_all(&dir);
}
