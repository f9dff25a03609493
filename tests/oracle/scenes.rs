//! Random scenes for the oracle: solids bounded by domain edges (sqrt,
//! ln, asin, acos, pow, a division's pole), by jumps (floor, mod), thin
//! plates and rods, and unions of many small spheres (long enough to be
//! pruned), over a floor, seen by an orthographic camera from above, lit
//! by one shadow-casting light.

use ibeam::ir::random::Rng;

/// A number as scene text (full precision).
fn n(v: f64) -> String {
    format!("{v:?}")
}

/// A solid whose lower face is a domain edge or a jump: its source.
pub fn edge_solid(rng: &mut Rng, kind: usize) -> String {
    let a = n(rng.range(-0.2, 0.3));
    let w = n(rng.range(0.3, 0.8));
    let clip = format!("abs(x) - {w}, abs(z) - {w}");
    match kind {
        // Thickness b² above the edge y = a.
        0 => format!("max(sqrt(y - {a}) - {}, {clip})", n(rng.range(0.12, 0.3))),
        // ln's edge at y = -a, thickness e^-c.
        1 => format!(
            "max(ln(y + {a}) + {}, sqrt(x*x + z*z) - {w})",
            n(rng.range(1.8, 3.5))
        ),
        // A dome whose inner face is asin's edge.
        2 => format!(
            "max({} - asin({} - sqrt(x*x + y*y + z*z)), -y)",
            n(rng.range(1.2, 1.5)),
            n(rng.range(1.4, 1.8))
        ),
        // acos's edge at y = k - 1.
        3 => {
            let k = rng.range(0.9, 1.3);
            format!("max(acos({} - y) - 0.5, {clip})", n(k))
        }
        // pow's edge, where the derivative stays finite (x^1.5).
        4 => format!(
            "max(pow(y - {a}, 1.5) + 0.5*(y - {a}) - {}, {clip})",
            n(rng.range(0.01, 0.05))
        ),
        // A division's pole at y = a: from +inf below to -inf above.
        5 => format!(
            "max(-1/(y - {a}) - {}, {clip}, y - {a} - {})",
            n(rng.range(2.0, 6.0)),
            n(rng.range(0.03, 0.2))
        ),
        // Stairs: floor jumps.
        6 => format!(
            "max(abs(y - {a} - 0.1*floor(3*x)) - {}, {clip})",
            n(rng.range(0.01, 0.06))
        ),
        // Slats whose faces are mod's jumps.
        _ => format!(
            "max(mod(x, {p}) - {h}, abs(y - {a}) - {}, {clip})",
            n(rng.range(0.01, 0.06)),
            p = n(0.4),
            h = n(rng.range(0.1, 0.3)),
        ),
    }
}

/// Kinds of [`edge_solid`].
pub const EDGE_KINDS: usize = 8;

/// A thin plate or rod.
pub fn thin_solid(rng: &mut Rng) -> String {
    let t = n(rng.range(0.002, 0.01));
    let (a, w) = (n(rng.range(-0.5, 0.6)), n(rng.range(0.2, 0.9)));
    if rng.chance(0.5) {
        format!("max(abs(y - {a}) - {t}, abs(x) - {w}, abs(z) - {w})")
    } else {
        format!("max(sqrt(y*y + (z - {a})*(z - {a})) - {t}, abs(x) - {w})")
    }
}

/// A union of `count` small spheres, written out as one `min`.
pub fn sphere_union(rng: &mut Rng, count: usize) -> String {
    let parts: Vec<String> = (0..count)
        .map(|_| {
            let c = [
                rng.range(-1.2, 1.2),
                rng.range(-0.6, 0.8),
                rng.range(-1.2, 1.2),
            ];
            format!(
                "sqrt((x - {})^2 + (y - {})^2 + (z - {})^2) - {}",
                n(c[0]),
                n(c[1]),
                n(c[2]),
                n(rng.range(0.03, 0.12))
            )
        })
        .collect();
    format!("min({})", parts.join(", "))
}

/// A scene: the objects' sources over a floor, an orthographic camera
/// from above at a random side, one directional light with shadows.
pub fn scene_text(rng: &mut Rng, objects: &[String]) -> String {
    let mut text = String::from("object floor = y + 1;\n");
    for (i, o) in objects.iter().enumerate() {
        text += &format!("object s{i} = {o};\n");
    }
    let th = rng.range(0.0, std::f64::consts::TAU);
    let el = rng.range(0.5, 1.4);
    let eye = [
        4.0 * el.cos() * th.cos(),
        4.0 * el.sin(),
        4.0 * el.cos() * th.sin(),
    ];
    let ld = [rng.range(-0.6, 0.6), -1.0, rng.range(-0.6, 0.6)];
    text += &format!(
        "camera {{ eye = ({}, {}, {}); target = (0, -0.3, 0); up = (0, 1, 0); ortho = 4.5; }}\n\
         bounds = (-2, -1.5, -2) .. (2, 1, 2);\n\
         light {{ direction = ({}, {}, {}); color = (1, 1, 1); shadows = true; }}\n",
        n(eye[0]),
        n(eye[1]),
        n(eye[2]),
        n(ld[0]),
        n(ld[1]),
        n(ld[2])
    );
    text
}
