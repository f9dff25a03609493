//! A validated scene: the objects' surface functions and everything the
//! renderer needs to draw them, with defaults filled in.
//!
//! Colours are linear RGB in [0, 1]; the renderer encodes sRGB on output.

use crate::ir::Function;

/// A scene ready to render.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The objects, in source order (at least one).
    pub objects: Vec<Object>,
    /// The view.
    pub camera: Camera,
    /// Light sources (a default light when the file names none).
    pub lights: Vec<Light>,
    /// The region rays are clipped to; no surface outside it is drawn.
    pub bounds: Bounds,
    /// Image settings.
    pub render: RenderSettings,
}

/// One named shape with its material.
#[derive(Clone, Debug)]
pub struct Object {
    /// The name after `object`.
    pub name: String,
    /// f(x, y, z), lowered but not yet simplified.
    pub function: Function,
    /// Diffuse colour, linear RGB.
    pub color: [f64; 3],
}

/// How screen positions map to rays.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole camera with this vertical field of view in degrees.
    Perspective {
        /// Vertical field of view, degrees, in (0, 180).
        fov_deg: f64,
    },
    /// Parallel rays; the view is this wide in world units.
    Orthographic {
        /// Width of the view in world units.
        width: f64,
    },
}

/// The camera.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at (differs from `eye`).
    pub target: [f64; 3],
    /// Approximate up direction (not parallel to target - eye).
    pub up: [f64; 3],
    /// Perspective or orthographic.
    pub projection: Projection,
}

/// Where light comes from.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum LightKind {
    /// A point light at this position.
    Point([f64; 3]),
    /// A light at infinity shining along this direction.
    Directional([f64; 3]),
}

/// A light source.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Light {
    /// Position or direction.
    pub kind: LightKind,
    /// Intensity per channel, linear RGB.
    pub color: [f64; 3],
    /// Whether this light casts (guaranteed) shadows.
    pub shadows: bool,
}

/// An axis-aligned box.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Bounds {
    /// Minimum corner.
    pub min: [f64; 3],
    /// Maximum corner.
    pub max: [f64; 3],
}

/// Image settings from the `render { }` block.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Background colour, linear RGB.
    pub background: [f64; 3],
}

impl Default for Camera {
    fn default() -> Camera {
        Camera {
            eye: [3.0, 2.5, 4.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            projection: Projection::Perspective { fov_deg: 40.0 },
        }
    }
}

impl Default for Bounds {
    fn default() -> Bounds {
        Bounds {
            min: [-2.0; 3],
            max: [2.0; 3],
        }
    }
}

impl Default for RenderSettings {
    fn default() -> RenderSettings {
        RenderSettings {
            size: (512, 512),
            background: [0.05, 0.05, 0.08],
        }
    }
}

impl Light {
    /// The light used when a scene names none: white, from upper front
    /// left, with shadows.
    pub fn default_light() -> Light {
        Light {
            kind: LightKind::Directional([-0.4, -1.0, -0.6]),
            color: [1.0, 1.0, 1.0],
            shadows: true,
        }
    }
}
