//! The workloads both renderers draw: the two shared models and unions of
//! random spheres, with the view every workload is seen from.

use std::fmt::Write as _;

/// Radius of every random sphere.
pub const SPHERE_RADIUS: f64 = 0.04;
/// Sphere centres are uniform in [-CENTRE_EXTENT, CENTRE_EXTENT]³, so every
/// sphere lies inside the [-1, 1]³ cube both renderers look at.
pub const CENTRE_EXTENT: f64 = 0.9;

/// One thing to render.
#[derive(Clone, Debug, PartialEq)]
pub enum Workload {
    /// prospero.vm, a 2D model, as a mask.
    Prospero,
    /// colonnade.vm, a 3D model, with depth and normals.
    Colonnade,
    /// A union of this many random spheres, with depth and normals.
    Spheres(usize),
}

impl Workload {
    /// The name in the table and in file names (`spheres-100`).
    pub fn name(&self) -> String {
        match self {
            Workload::Prospero => "prospero".into(),
            Workload::Colonnade => "colonnade".into(),
            Workload::Spheres(n) => format!("spheres-{n}"),
        }
    }

    /// Parses [`Workload::name`] back.
    pub fn parse(s: &str) -> Option<Workload> {
        match s {
            "prospero" => Some(Workload::Prospero),
            "colonnade" => Some(Workload::Colonnade),
            _ => s
                .strip_prefix("spheres-")
                .and_then(|n| n.parse().ok())
                .filter(|&n: &usize| n >= 1)
                .map(Workload::Spheres),
        }
    }

    /// The model file of a `.vm` workload.
    pub fn vm_file(&self) -> Option<&'static str> {
        match self {
            Workload::Prospero => Some("prospero.vm"),
            Workload::Colonnade => Some("colonnade.vm"),
            Workload::Spheres(_) => None,
        }
    }

    /// Whether the workload is a 2D image (no depth, no normals).
    pub fn is_2d(&self) -> bool {
        matches!(self, Workload::Prospero)
    }
}

/// `n` sphere centres from `seed`, each coordinate rounded to 6 decimals
/// so that the scene text holds exactly the numbers Fidget is given.
pub fn sphere_centres(n: usize, seed: u64) -> Vec<[f64; 3]> {
    // ibeam's SplitMix64: the same seed gives the same spheres on every
    // machine and for both renderers.
    let mut rng = ibeam::ir::random::Rng::new(seed);
    let mut coord = || {
        let v = (2.0 * rng.unit() - 1.0) * CENTRE_EXTENT;
        (v * 1e6).round() / 1e6
    };
    (0..n).map(|_| [coord(), coord(), coord()]).collect()
}

/// The ibeam scene of a sphere union: one object, orthographic view down
/// -z over [-1, 1]² (Fidget's default view), no shadows.
pub fn spheres_scene(centres: &[[f64; 3]]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "// {} spheres of radius {SPHERE_RADIUS}", centres.len());
    let ball = |c: &[f64; 3]| {
        format!(
            "translate(sphere({SPHERE_RADIUS}), {:.6}, {:.6}, {:.6})",
            c[0], c[1], c[2]
        )
    };
    if centres.len() == 1 {
        let _ = writeln!(s, "object spheres = {};", ball(&centres[0]));
    } else {
        s.push_str("object spheres = union(\n");
        for (i, c) in centres.iter().enumerate() {
            let sep = if i + 1 == centres.len() { ");" } else { "," };
            let _ = writeln!(s, "    {}{sep}", ball(c));
        }
    }
    s.push_str(
        "camera { eye = (0, 0, 3); target = (0, 0, 0); up = (0, 1, 0); ortho = 2; }\n\
         light { direction = (-0.4, -1, -0.6); shadows = false; }\n\
         bounds = (-1, -1, -1) .. (1, 1, 1);\n",
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for w in [
            Workload::Prospero,
            Workload::Colonnade,
            Workload::Spheres(30),
        ] {
            assert_eq!(Workload::parse(&w.name()), Some(w));
        }
        assert_eq!(Workload::parse("spheres-0"), None);
    }

    #[test]
    fn centres_are_deterministic_and_inside() {
        let a = sphere_centres(100, 7);
        assert_eq!(a, sphere_centres(100, 7));
        assert_ne!(a, sphere_centres(100, 8));
        assert!(a.iter().flatten().all(|v| v.abs() <= CENTRE_EXTENT));
    }
}
