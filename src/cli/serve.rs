//! `ibeam serve`: a live view of a scene in the browser. One page, which
//! asks for images of the views it wants (camera and switches in the
//! query string), polls the scene's state, and shows the render's stats,
//! the IR, the scene text and the located error of a broken save.
//!
//! Requests are matched against a fixed list of paths; none is ever
//! joined to a folder, so no request reaches a file. Each request gets a
//! thread of its own (up to [`MAX_REQUESTS`] at once, the rest a 503),
//! so that a newer view can cancel the render of an older one
//! ([`draw::Slot`]): a burst of requests leaves one render running.

mod draw;
mod query;
mod scene;

use std::io::Write;
use std::net::IpAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use tiny_http::{Header, Method, Request, Response};

use super::CliError;
use super::image::ImageArgs;
use super::view::ViewArgs;
use draw::{Drawn, Encoding, Failed, Slot};
use ibeam::render::Aa;
use scene::{Shared, lock};

/// Requests handled at once; more get a 503 straight away.
const MAX_REQUESTS: usize = 32;

/// The page, with its script (no build step).
const PAGE: &str = include_str!("serve/page.html");

/// Arguments of `ibeam serve`: where to listen, and the render flags that
/// make sense for a view.
#[derive(clap::Args, Clone, Debug)]
#[group(id = "serve_args")]
pub struct Args {
    /// Scene file (`.ib`) or Fidget model (`.vm`).
    pub file: PathBuf,
    /// Port to listen on (0: any free port; the URL printed says which).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// Address to listen on; the default lets only this machine connect.
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: IpAddr,
    /// Camera overrides and framing, as for `ibeam render`: the view the
    /// page starts from.
    #[command(flatten)]
    pub view: Box<ViewArgs>,
    /// How each image is traced (the page can switch the method, the
    /// anti-aliasing, the shadows and the size; previews have no
    /// anti-aliasing).
    #[command(flatten)]
    pub image: ImageArgs,
    /// Print nothing but the URL (no load errors on stderr).
    #[arg(long)]
    pub quiet: bool,
}

/// Everything the request handlers share.
struct Server {
    args: Args,
    state: Shared,
    slot: Slot,
    /// The last full image's stats and camera, for `/stats.json`.
    last: Mutex<Option<String>>,
    busy: AtomicUsize,
}

/// Runs `ibeam serve` until the process is stopped.
pub fn run(args: &Args) -> Result<(), CliError> {
    let args = args.clone();
    let http = tiny_http::Server::http((args.bind, args.port))
        .map_err(|e| format!("cannot listen on {}:{}: {e}", args.bind, args.port))?;
    let addr = http
        .server_addr()
        .to_ip()
        .ok_or("the server has no IP address")?;
    let server = Arc::new(Server {
        args,
        state: Shared::default(),
        slot: Slot::default(),
        last: Mutex::new(None),
        busy: AtomicUsize::new(0),
    });
    let (ready_tx, ready_rx) = std::sync::mpsc::channel();
    let loader = Arc::clone(&server);
    std::thread::spawn(move || {
        let ready = move || {
            let _ = ready_tx.send(());
        };
        if let Err(e) = scene::keep_loading(&loader.args, &loader.state, ready) {
            eprintln!("ibeam serve: reloading stopped: {e}");
        }
    });
    ready_rx
        .recv()
        .map_err(|_| "the scene loader stopped before the first load")?;
    let host = match addr.ip() {
        IpAddr::V6(ip) => format!("[{ip}]"),
        IpAddr::V4(ip) => ip.to_string(),
    };
    println!(
        "serving {} at http://{host}:{}/",
        server.args.file.display(),
        addr.port()
    );
    std::io::stdout().flush()?;
    for request in http.incoming_requests() {
        if server.busy.fetch_add(1, Ordering::SeqCst) >= MAX_REQUESTS {
            server.busy.fetch_sub(1, Ordering::SeqCst);
            let _ = request.respond(text(503, "too many requests at once"));
            continue;
        }
        let s = Arc::clone(&server);
        std::thread::spawn(move || {
            handle(&s, request);
            s.busy.fetch_sub(1, Ordering::SeqCst);
        });
    }
    Ok(())
}

type Reply = Response<std::io::Cursor<Vec<u8>>>;

/// `response` with a header added; a value `tiny_http` refuses (one
/// with a line break) is left out rather than sent.
fn with(response: Reply, name: &str, value: &str) -> Reply {
    match Header::from_bytes(name.as_bytes(), value.as_bytes()) {
        Ok(h) => response.with_header(h),
        Err(()) => response,
    }
}

fn reply(status: u16, content_type: &str, body: Vec<u8>) -> Reply {
    let r = Response::from_data(body).with_status_code(status);
    let r = with(r, "Content-Type", content_type);
    let r = with(r, "Cache-Control", "no-store");
    with(r, "X-Content-Type-Options", "nosniff")
}

fn text(status: u16, body: &str) -> Reply {
    reply(
        status,
        "text/plain; charset=utf-8",
        body.as_bytes().to_vec(),
    )
}

fn handle(server: &Server, request: Request) {
    let response = respond(server, &request);
    // A client that went away (a superseded image) is not an error.
    let _ = request.respond(response);
}

fn respond(server: &Server, request: &Request) -> Reply {
    if !matches!(request.method(), Method::Get | Method::Head) {
        return text(405, "only GET and HEAD");
    }
    if !host_allowed(server, request) {
        return text(403, "unexpected Host header");
    }
    let (path, query) = request.url().split_once('?').unwrap_or((request.url(), ""));
    match (path, query.is_empty()) {
        ("/", true) => reply(200, "text/html; charset=utf-8", PAGE.as_bytes().to_vec()),
        ("/state.json", true) => state(server),
        ("/source.txt", true) => text(200, &lock(&server.state).source),
        ("/ir.txt", true) => match lock(&server.state).good.as_ref() {
            Some(g) => text(200, &g.ir),
            None => text(503, "the scene has not loaded yet"),
        },
        ("/stats.json", true) => match &*server.last.lock().unwrap_or_else(PoisonError::into_inner)
        {
            Some(json) => reply(200, "application/json", json.clone().into_bytes()),
            None => text(404, "nothing rendered yet"),
        },
        ("/image.png", _) => image(server, query, Encoding::Png),
        ("/image.exr", _) => image(server, query, Encoding::Exr),
        (_, false) if KNOWN.contains(&path) => text(400, "this page takes no query"),
        _ => text(404, "not found"),
    }
}

/// The paths served besides the images.
const KNOWN: [&str; 5] = ["/", "/state.json", "/source.txt", "/ir.txt", "/stats.json"];

/// Whether the Host header names the address listened on, or localhost:
/// a page from elsewhere that resolves its own name to 127.0.0.1 (DNS
/// rebinding) must not read the scene.
fn host_allowed(server: &Server, request: &Request) -> bool {
    if !server.args.bind.is_loopback() {
        return true;
    }
    let host = request
        .headers()
        .iter()
        .find(|h| h.field.equiv("Host"))
        .map(|h| h.value.as_str().to_ascii_lowercase());
    let Some(host) = host else { return true };
    let name = match host.rsplit_once(':') {
        Some((n, port)) if port.bytes().all(|b| b.is_ascii_digit()) => n,
        _ => host.as_str(),
    };
    ["localhost", "127.0.0.1", "[::1]"].contains(&name)
}

fn state(server: &Server) -> Reply {
    let s = lock(&server.state);
    let args = &server.args;
    let view = s.good.as_ref().map(|g| {
        serde_json::json!({
            "camera": draw::camera_flags(&g.scene.camera),
            "eye": g.scene.camera.eye,
            "target": g.scene.camera.target,
            "up": g.scene.camera.up,
            "projection": match g.scene.camera.projection {
                ibeam::scene::Projection::Perspective { fov_deg } => serde_json::json!({"fov": fov_deg}),
                ibeam::scene::Projection::Orthographic { width } => serde_json::json!({"ortho": width}),
            },
            "size": [g.size.0, g.size.1],
        })
    });
    let json = serde_json::json!({
        "file": args.file.display().to_string(),
        "generation": s.generation,
        "error": s.error,
        "view": view,
        "method": args.image.method.to_string(),
        "aa": aa_text(args.image.aa),
        "preview": draw::PREVIEW,
    });
    reply(200, "application/json", json.to_string().into_bytes())
}

fn aa_text(aa: Aa) -> String {
    match aa {
        Aa::None => "none".into(),
        Aa::Iaa { .. } => "iaa".into(),
        Aa::Grid(n) => format!("grid:{n}"),
    }
}

fn image(server: &Server, query: &str, encoding: Encoding) -> Reply {
    let q = match query::parse(query) {
        Ok(q) => q,
        Err(e) => return text(400, &e),
    };
    let good = lock(&server.state).good.clone();
    let Some(good) = good else {
        return text(503, "the scene has not loaded yet");
    };
    match server.slot.draw(&server.args, &good, &q, encoding) {
        Err(Failed::Superseded) => text(409, "superseded by a newer view"),
        Err(Failed::Bad(e)) => text(422, &e),
        Ok(Drawn {
            bytes,
            stats,
            camera_flags,
        }) => {
            let stats = serde_json::json!({"stats": stats.to_json(), "camera": camera_flags});
            let stats = stats.to_string();
            if q.preview != Some(true) {
                *server.last.lock().unwrap_or_else(PoisonError::into_inner) = Some(stats.clone());
            }
            let kind = match encoding {
                Encoding::Png => "image/png",
                Encoding::Exr => "image/x-exr",
            };
            let r = with(reply(200, kind, bytes), "X-Ibeam-Stats", &stats);
            with(r, "X-Ibeam-Camera", &camera_flags)
        }
    }
}
