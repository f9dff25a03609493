//! Rendering one view: the scene's shared evaluators, the page's camera
//! and switches, and a cancel flag that a newer view sets, so at most one
//! render runs and a stale one stops within a row of tiles.

use std::io::Cursor;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};

use super::Args;
use super::query::{Query, Switch};
use super::scene::Good;
use ibeam::render::{Aa, FloatLayers, Frame, RenderError, RenderOptions, RenderStats};
use ibeam::scene::{Camera, Projection};
use image::{ImageBuffer, ImageFormat, Rgb};

/// Each side of a preview is this many times smaller than the image's.
pub const PREVIEW: u32 = 4;

/// The encoding asked for.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// 8-bit sRGB PNG.
    Png,
    /// 32-bit float linear OpenEXR.
    Exr,
}

/// A finished render.
pub struct Drawn {
    /// The encoded image.
    pub bytes: Vec<u8>,
    /// Its counters.
    pub stats: RenderStats,
    /// The flags that give this camera on the command line.
    pub camera_flags: String,
}

/// Why a view was not drawn.
pub enum Failed {
    /// A newer view was asked for first.
    Superseded,
    /// The view cannot be rendered (a degenerate camera, say).
    Bad(String),
}

/// The one render slot: the newest view's cancel flag, and a lock held
/// while a render runs.
#[derive(Default)]
pub struct Slot {
    newest: Mutex<Arc<AtomicBool>>,
    running: Mutex<()>,
}

impl Slot {
    /// Cancels the view in progress (if any) and renders `query`, unless a
    /// newer view cancels this one first.
    pub fn draw(
        &self,
        args: &Args,
        good: &Good,
        query: &Query,
        encoding: Encoding,
    ) -> Result<Drawn, Failed> {
        let mine = Arc::new(AtomicBool::new(false));
        {
            let mut newest = self.newest.lock().unwrap_or_else(PoisonError::into_inner);
            newest.store(true, Ordering::Relaxed);
            *newest = Arc::clone(&mine);
        }
        let _running = self.running.lock().unwrap_or_else(PoisonError::into_inner);
        if mine.load(Ordering::Relaxed) {
            return Err(Failed::Superseded);
        }
        render(args, good, query, encoding, mine)
    }
}

fn render(
    args: &Args,
    good: &Good,
    query: &Query,
    encoding: Encoding,
    cancel: Arc<AtomicBool>,
) -> Result<Drawn, Failed> {
    let bad = |e: &dyn std::fmt::Display| Failed::Bad(e.to_string());
    let mut scene = good.scene.clone();
    let full = query.size.unwrap_or(good.size);
    let preview = query.preview == Some(true);
    let (w, h) = if preview {
        ((full.0 / PREVIEW).max(1), (full.1 / PREVIEW).max(1))
    } else {
        full
    };
    query
        .view
        .apply(&args.file, &mut scene, &good.evaluators, (w, h), true)
        .map_err(|e| bad(&e))?;
    if let Some(s) = query.shadows {
        for light in &mut scene.lights {
            light.shadows = s == Switch::On;
        }
    }
    let image = &args.image;
    let method = query.method.unwrap_or(image.method).method(image.steps);
    let aa = match query.aa.unwrap_or(image.aa) {
        _ if preview => Aa::None,
        aa => image.aa_with(aa),
    };
    let opts = RenderOptions {
        threads: image.threads.map(|n| n as usize),
        method,
        want_buffers: false,
        prune: !image.no_prune,
        ..RenderOptions::new(w, h)
    };
    let frame = Frame::new(&scene, &good.evaluators, &opts, aa)
        .map_err(|e| bad(&e))?
        .with_cancel(cancel)
        .with_float_layers(FloatLayers {
            color: encoding == Encoding::Exr,
            ..FloatLayers::default()
        });
    let mut color: Vec<u8> = Vec::with_capacity(w as usize * h as usize * 3);
    let mut linear: Vec<f32> = Vec::new();
    let stats = frame
        .stream(|band| {
            color.extend_from_slice(&band.color);
            if let Some(l) = &band.linear {
                linear.extend(l.iter().flatten());
            }
            Ok::<(), RenderError>(())
        })
        .map_err(|e| match e {
            RenderError::Cancelled => Failed::Superseded,
            e => bad(&e),
        })?;
    let bytes = encode(encoding, (w, h), color, linear).map_err(|e| bad(&e))?;
    Ok(Drawn {
        bytes,
        stats,
        camera_flags: camera_flags(&scene.camera),
    })
}

fn encode(
    encoding: Encoding,
    (w, h): (u32, u32),
    color: Vec<u8>,
    linear: Vec<f32>,
) -> Result<Vec<u8>, String> {
    let mut out = Cursor::new(Vec::new());
    let size_err = || "image size mismatch".to_string();
    match encoding {
        Encoding::Png => ImageBuffer::<Rgb<u8>, _>::from_raw(w, h, color)
            .ok_or_else(size_err)?
            .write_to(&mut out, ImageFormat::Png),
        Encoding::Exr => ImageBuffer::<Rgb<f32>, _>::from_raw(w, h, linear)
            .ok_or_else(size_err)?
            .write_to(&mut out, ImageFormat::OpenExr),
    }
    .map_err(|e| format!("cannot encode the image: {e}"))?;
    Ok(out.into_inner())
}

/// `--eye … --target … --up … --fov …` (or `--ortho …`) for `cam`: f64's
/// shortest round-trip digits, so the command line gets this very camera.
pub fn camera_flags(cam: &Camera) -> String {
    let v = |a: [f64; 3]| format!("{},{},{}", a[0], a[1], a[2]);
    let projection = match cam.projection {
        Projection::Perspective { fov_deg } => format!("--fov {fov_deg}"),
        Projection::Orthographic { width } => format!("--ortho {width}"),
    };
    format!(
        "--eye {} --target {} --up {} {projection}",
        v(cam.eye),
        v(cam.target),
        v(cam.up)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_flags_round_trip() {
        let cam = Camera {
            eye: [0.1, -2.0, 1e-3],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Perspective { fov_deg: 35.5 },
        };
        assert_eq!(
            camera_flags(&cam),
            "--eye 0.1,-2,0.001 --target 0,0,0 --up 0,1,0 --fov 35.5"
        );
    }
}
