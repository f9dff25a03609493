//! Camera flags shared by the commands that draw a scene: overrides of
//! the scene's own camera, orbiting and zooming about its target, and
//! framing the solid itself (`--fit`, the default for `.vm` models, which
//! carry no camera).

use std::path::Path;
use std::sync::Arc;

use glam::DVec3;

use super::{CliError, parse_numbers};
use ibeam::eval::Evaluator;
use ibeam::render::camera::RayCamera;
use ibeam::render::fit::{FIT_DEPTH, frame_box, solid_box};
use ibeam::scene::{Camera, Projection, Scene};

/// Camera flags (`#[command(flatten)]` them into a command's arguments).
#[derive(clap::Args, Clone, Debug, Default, PartialEq)]
pub struct ViewArgs {
    /// Eye position, overriding the scene's camera.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<[f64; 3]>,
    /// Point looked at, overriding the scene's camera.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<[f64; 3]>,
    /// Up direction, overriding the scene's camera.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<[f64; 3]>,
    /// Perspective view with this vertical field of view, degrees in
    /// (0, 180).
    #[arg(long, value_name = "DEG", value_parser = parse_fov, conflicts_with = "ortho", allow_hyphen_values = true)]
    pub fov: Option<f64>,
    /// Orthographic view this wide in world units (> 0).
    #[arg(long, value_name = "WIDTH", value_parser = parse_positive, allow_hyphen_values = true)]
    pub ortho: Option<f64>,
    /// Turns the eye about the target: YAW degrees about the up axis
    /// (counter-clockwise seen from above), then PITCH degrees towards up.
    #[arg(long, value_name = "YAW,PITCH", value_parser = parse_vec2, allow_hyphen_values = true)]
    pub orbit: Option<[f64; 2]>,
    /// Brings the eye K times closer to the target (K > 1 zooms in); an
    /// orthographic view gets K times narrower instead.
    #[arg(long, value_name = "K", value_parser = parse_positive, allow_hyphen_values = true)]
    pub zoom: Option<f64>,
    /// Aims the camera at the solid itself and frames it to fill about 80%
    /// of the image, keeping the view direction: a box that contains every
    /// point where f ≤ 0 is found by interval subdivision of the bounds
    /// (256 cells a side at most; cheap next to the render). The default
    /// for `.vm` models unless a camera flag is given.
    #[arg(long, conflicts_with = "no_fit")]
    pub fit: bool,
    /// Keeps the scene's (or a `.vm` model's default) camera unframed.
    #[arg(long)]
    pub no_fit: bool,
}

fn parse_vec3(s: &str) -> Result<[f64; 3], CliError> {
    let v = parse_numbers(s, 3, "X,Y,Z")?;
    Ok([v[0], v[1], v[2]])
}

fn parse_vec2(s: &str) -> Result<[f64; 2], CliError> {
    let v = parse_numbers(s, 2, "YAW,PITCH")?;
    Ok([v[0], v[1]])
}

fn parse_fov(s: &str) -> Result<f64, CliError> {
    let v = parse_numbers(s, 1, "field of view")?[0];
    if v > 0.0 && v < 180.0 {
        Ok(v)
    } else {
        Err(format!("field of view {v} must be between 0 and 180 degrees").into())
    }
}

fn parse_positive(s: &str) -> Result<f64, CliError> {
    let v = parse_numbers(s, 1, "value")?[0];
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} must be positive").into())
    }
}

impl ViewArgs {
    /// Whether any flag sets the camera outright (so a `.vm` model keeps
    /// it rather than being framed by default).
    fn sets_camera(&self) -> bool {
        self.eye.is_some()
            || self.target.is_some()
            || self.up.is_some()
            || self.fov.is_some()
            || self.ortho.is_some()
    }

    /// Whether the solid is framed for the scene file `file`.
    pub fn fits(&self, file: &Path) -> bool {
        let vm = file
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("vm"));
        self.fit || (vm && !self.no_fit && !self.sets_camera())
    }

    /// Sets `scene.camera` as the flags ask for a `width × height` image:
    /// the overrides, then the orbit, then the framing, then the zoom.
    /// Each step's camera is checked, so a degenerate view is an error
    /// that names it, never a panic.
    pub fn apply(
        &self,
        file: &Path,
        scene: &mut Scene,
        evaluators: &[Arc<dyn Evaluator>],
        (width, height): (u32, u32),
        quiet: bool,
    ) -> Result<(), CliError> {
        let check = |cam: &Camera, after: &str| -> Result<(), CliError> {
            RayCamera::new(cam, width, height)
                .map(|_| ())
                .map_err(|e| format!("{}: bad camera{after}: {e}", file.display()).into())
        };
        let mut cam = scene.camera;
        cam.eye = self.eye.unwrap_or(cam.eye);
        cam.target = self.target.unwrap_or(cam.target);
        cam.up = self.up.unwrap_or(cam.up);
        if let Some(fov_deg) = self.fov {
            cam.projection = Projection::Perspective { fov_deg };
        }
        if let Some(width) = self.ortho {
            cam.projection = Projection::Orthographic { width };
        }
        check(
            &cam,
            if self.sets_camera() {
                " (after --eye, --target, --up, --fov, --ortho)"
            } else {
                ""
            },
        )?;
        if let Some([yaw, pitch]) = self.orbit {
            cam = orbit(cam, yaw, pitch);
            check(&cam, " after --orbit")?;
        }
        if self.fits(file) {
            match solid_box(scene, evaluators, FIT_DEPTH) {
                Some(b) => {
                    cam = frame_box(&cam, &b, width, height).unwrap_or(cam);
                    check(&cam, " after --fit")?;
                }
                None if !quiet => eprintln!(
                    "{}: nothing to frame (no point of the bounds is inside a solid); \
                     keeping the camera",
                    file.display()
                ),
                None => {}
            }
        }
        if let Some(k) = self.zoom {
            cam = zoom(cam, k);
            check(&cam, " after --zoom")?;
        }
        scene.camera = cam;
        Ok(())
    }
}

/// `cam` with its eye turned about the target: `yaw` degrees about the up
/// axis, then `pitch` degrees towards up. A camera without a view
/// direction or up axis is returned as it is (the caller's check names
/// it).
pub fn orbit(cam: Camera, yaw: f64, pitch: f64) -> Camera {
    let target = DVec3::from_array(cam.target);
    let up = DVec3::from_array(cam.up).normalize_or_zero();
    let mut offset = DVec3::from_array(cam.eye) - target;
    if up == DVec3::ZERO {
        return cam;
    }
    offset = rotate(offset, up, yaw.to_radians());
    let side = offset.cross(up).normalize_or_zero();
    if side != DVec3::ZERO {
        offset = rotate(offset, side, pitch.to_radians());
    }
    Camera {
        eye: (target + offset).to_array(),
        ..cam
    }
}

// `v` turned by `angle` radians about the unit `axis` (Rodrigues).
fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
}

/// `cam` zoomed `k` times: the eye `k` times closer to the target, or an
/// orthographic view `k` times narrower (moving its eye would not change
/// the image, and could put it inside the solid).
pub fn zoom(cam: Camera, k: f64) -> Camera {
    match cam.projection {
        Projection::Orthographic { width } => Camera {
            projection: Projection::Orthographic { width: width / k },
            ..cam
        },
        Projection::Perspective { .. } => {
            let target = DVec3::from_array(cam.target);
            let eye = target + (DVec3::from_array(cam.eye) - target) / k;
            Camera {
                eye: eye.to_array(),
                ..cam
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|i| (a[i] - b[i]).abs() < 1e-12)
    }

    #[test]
    fn orbit_turns_about_up_then_towards_it() {
        let cam = Camera {
            eye: [0.0, 0.0, 5.0],
            target: [0.0; 3],
            up: [0.0, 1.0, 0.0],
            ..Camera::default()
        };
        // Yaw 90° about +y takes +z to +x.
        assert!(
            close(orbit(cam, 90.0, 0.0).eye, [5.0, 0.0, 0.0]),
            "{:?}",
            orbit(cam, 90.0, 0.0)
        );
        // Pitch 90° takes the eye straight up.
        assert!(close(orbit(cam, 0.0, 90.0).eye, [0.0, 5.0, 0.0]));
        let c = orbit(cam, 30.0, 20.0);
        let d = DVec3::from_array(c.eye).length();
        assert!((d - 5.0).abs() < 1e-12);
    }

    #[test]
    fn zoom_divides_the_distance_or_the_width() {
        let cam = Camera {
            eye: [0.0, 0.0, 4.0],
            target: [0.0, 0.0, 1.0],
            ..Camera::default()
        };
        assert!(close(zoom(cam, 3.0).eye, [0.0, 0.0, 2.0]));
        let o = Camera {
            projection: Projection::Orthographic { width: 2.0 },
            ..cam
        };
        let z = zoom(o, 4.0);
        assert_eq!(
            (z.eye, z.projection),
            (o.eye, Projection::Orthographic { width: 0.5 })
        );
    }

    #[test]
    fn flags_parse_and_reject_bad_values() {
        use clap::Parser;
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            view: ViewArgs,
        }
        let p = |v: &[&str]| Cli::try_parse_from([&["x"], v].concat()).map(|c| c.view);
        let v = p(&["--eye", "-3,2,1e1", "--orbit", "-30,10", "--zoom", "2"]).unwrap();
        assert_eq!(v.eye, Some([-3.0, 2.0, 10.0]));
        assert_eq!(v.orbit, Some([-30.0, 10.0]));
        assert!(p(&["--fov", "180"]).is_err());
        assert!(p(&["--fov", "0"]).is_err());
        assert!(p(&["--ortho", "-1"]).is_err());
        assert!(p(&["--zoom", "0"]).is_err());
        assert!(p(&["--eye", "1,2"]).is_err());
        assert!(p(&["--fov", "40", "--ortho", "2"]).is_err());
        assert!(p(&["--fit", "--no-fit"]).is_err());
        let none = p(&[]).unwrap();
        assert!(none.fits(Path::new("m.VM")) && !none.fits(Path::new("s.ib")));
        assert!(!v.fits(Path::new("m.vm")));
        assert!(!p(&["--eye", "0,0,3"]).unwrap().fits(Path::new("m.vm")));
        assert!(!p(&["--no-fit"]).unwrap().fits(Path::new("m.vm")));
        assert!(p(&["--fit"]).unwrap().fits(Path::new("s.ib")));
    }
}
