//! The two views every 3D workload is seen from: Fidget's default view from
//! above (parallel rays down -z over [-1, 1]²), and a perspective view from
//! a corner. The corner view is defined once, as Fidget's `world_to_model`
//! matrix, and ibeam's pinhole camera is derived from that same matrix, so
//! both renderers look from the same eye, along the same axis, with the
//! same field of view and up direction.

use ibeam::scene::{Camera, Projection};
use nalgebra::{Matrix4, Rotation3, Vector3, Vector4};

/// Where a workload is seen from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Parallel rays down -z over [-1, 1]² (Fidget's identity view).
    Top,
    /// Perspective from a corner ([`corner_matrix`]).
    Corner,
}

impl View {
    /// The name in the table, in file names and on the worker's command line.
    pub fn name(self) -> &'static str {
        match self {
            View::Top => "top",
            View::Corner => "corner",
        }
    }

    /// Parses [`View::name`] back.
    pub fn parse(s: &str) -> Option<View> {
        match s {
            "top" => Some(View::Top),
            "corner" => Some(View::Corner),
            _ => None,
        }
    }
}

/// Roll about z, degrees.
const ROLL_DEG: f32 = 30.0;
/// Pitch about x, degrees.
const PITCH_DEG: f32 = 60.0;
/// The model is shown at this scale (world = 0.7 × model).
const SCALE: f32 = 0.7;
/// Fidget's projective term, the matrix entry (3, 2): w = 1 + 0.3 z, so the
/// voxel columns converge on one eye point and near things look larger.
const PERSPECTIVE: f32 = 0.3;

/// Fidget's `world_to_model` of the corner view: roll × pitch × scale ×
/// perspective, applied to Fidget's world cube [-1, 1]³ (the screen, its
/// z pointing at the viewer).
pub fn corner_matrix() -> Matrix4<f32> {
    let roll = Rotation3::from_axis_angle(&Vector3::z_axis(), ROLL_DEG.to_radians());
    let pitch = Rotation3::from_axis_angle(&Vector3::x_axis(), PITCH_DEG.to_radians());
    let mut perspective = Matrix4::identity();
    perspective[(3, 2)] = PERSPECTIVE;
    roll.to_homogeneous() * pitch.to_homogeneous() * Matrix4::new_scaling(1.0 / SCALE) * perspective
}

/// A homogeneous point or direction of Fidget's world in model space.
fn to_model(m: &Matrix4<f32>, v: [f32; 4]) -> Vector4<f64> {
    (m * Vector4::from(v)).cast::<f64>()
}

fn point(v: Vector4<f64>) -> Vector3<f64> {
    v.xyz() / v.w
}

/// ibeam's camera equal to [`corner_matrix`]: every world column (fixed
/// screen x, y; z from the viewer into the screen) maps to a line in
/// model space through one point, the eye, which is the image of the
/// world's point at infinity along z. The target is the image of the
/// world's origin, up the image of world +y, and the field of view the
/// angle the screen's half-height subtends from the eye at the target.
pub fn corner_camera() -> Camera {
    let m = corner_matrix();
    let eye = point(to_model(&m, [0.0, 0.0, 1.0, 0.0]));
    let target = point(to_model(&m, [0.0, 0.0, 0.0, 1.0]));
    let top = point(to_model(&m, [0.0, 1.0, 0.0, 1.0]));
    let up = to_model(&m, [0.0, 1.0, 0.0, 0.0]).xyz();
    let half = (top - eye).angle(&(target - eye));
    Camera {
        eye: eye.into(),
        target: target.into(),
        up: up.into(),
        projection: Projection::Perspective {
            fov_deg: 2.0 * half.to_degrees(),
        },
    }
}

/// Fidget's default 3D view: parallel rays down -z over [-1, 1]².
pub fn top_camera() -> Camera {
    Camera {
        eye: [0.0, 0.0, 3.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Orthographic { width: 2.0 },
    }
}

/// The camera ibeam renders `view` with.
pub fn camera(view: View) -> Camera {
    match view {
        View::Top => top_camera(),
        View::Corner => corner_camera(),
    }
}

/// The camera as `ibeam render` flags (`--eye`, `--target`, `--up`, and
/// `--fov` or `--ortho`), which also keep a `.vm` model from being framed.
pub fn camera_flags(view: View) -> Vec<String> {
    let cam = camera(view);
    let v = |a: [f64; 3]| format!("{},{},{}", a[0], a[1], a[2]);
    let mut flags = vec![
        "--eye".into(),
        v(cam.eye),
        "--target".into(),
        v(cam.target),
        "--up".into(),
        v(cam.up),
    ];
    match cam.projection {
        Projection::Perspective { fov_deg } => flags.extend(["--fov".into(), fov_deg.to_string()]),
        Projection::Orthographic { width } => flags.extend(["--ortho".into(), width.to_string()]),
    }
    flags
}

/// Fidget's `world_to_model` for `view`.
pub fn fidget_matrix(view: View) -> Matrix4<f32> {
    match view {
        View::Top => Matrix4::identity(),
        View::Corner => corner_matrix(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_camera_matches_the_matrix() {
        let cam = corner_camera();
        let eye = Vector3::from(cam.eye);
        // The eye lies 1 / (0.3 × 0.7) from the origin, the fov is
        // 2 atan(0.3) whatever the scale.
        assert!((eye.norm() - 1.0 / (0.3 * 0.7)).abs() < 1e-4);
        let Projection::Perspective { fov_deg } = cam.projection else {
            panic!("perspective")
        };
        assert!((fov_deg - 2.0 * 0.3f64.atan().to_degrees()).abs() < 1e-3);
        // A world point off the axis lies on the ray from the eye through
        // its screen position, at any depth.
        let m = corner_matrix();
        let a = point(to_model(&m, [0.5, -0.25, 0.8, 1.0]));
        let b = point(to_model(&m, [0.5, -0.25, -0.6, 1.0]));
        let cos = (a - eye).normalize().dot(&(b - eye).normalize());
        assert!(cos > 1.0 - 1e-6, "{cos}");
    }
}
