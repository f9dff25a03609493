//! How much wider than the true range an enclosure is (issue 40): the
//! interval and the affine enclosures of a few surfaces over small cubes,
//! against reference ranges sampled at 200 bits with mpmath
//! (`tests/data/enclosure.py` writes `tests/data/enclosure.txt`).
//!
//! A box's overestimation is the enclosure's width over the reference
//! range's width. Where f is identically zero (`(x−1)¹⁰` minus its
//! expansion: the reference ranges are 200-bit rounding, 1e-60 wide), a
//! ratio says nothing, and the absolute width is reported instead.

use crate::eval::Single;
use crate::eval::affine::AffineEvaluator;
use crate::eval::interp::Interpreter;
use crate::eval::tape::Tape;
use crate::interval::Interval;
use crate::ir::passes::simplify;
use std::fmt::Write;

/// One box and the range of f sampled in it.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RefBox {
    /// The box `[X, Y, Z]`.
    pub b: [Interval; 3],
    /// The least and greatest sampled value of f.
    pub range: Interval,
}

/// A surface of the reference file.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    /// Its name.
    pub name: String,
    /// f in ibeam's expression syntax.
    pub formula: String,
    /// The boxes and their reference ranges.
    pub boxes: Vec<RefBox>,
}

/// The reference file of this checkout.
pub const DEFAULT_DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/enclosure.txt");

/// Reads the reference file's text (see the module doc).
pub fn parse(text: &str) -> Result<Vec<Surface>, String> {
    let mut out: Vec<Surface> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if let Some(name) = line.strip_prefix("surface ") {
            out.push(Surface {
                name: name.trim().to_string(),
                formula: String::new(),
                boxes: Vec::new(),
            });
            continue;
        }
        let Some(s) = out.last_mut() else {
            return Err(format!("line {}: data before the first `surface`", n + 1));
        };
        if let Some(formula) = line.strip_prefix("formula ") {
            s.formula = formula.trim().to_string();
            continue;
        }
        let v: Vec<f64> = line
            .split_whitespace()
            .map(str::parse)
            .collect::<Result<_, _>>()
            .map_err(|e| format!("line {}: {e}", n + 1))?;
        if v.len() != 8
            || v.chunks(2)
                .any(|p| p[0].partial_cmp(&p[1]).is_none_or(|o| o.is_gt()))
        {
            return Err(format!("line {}: expected 4 ordered pairs", n + 1));
        }
        let iv = |i: usize| Interval::new(v[2 * i], v[2 * i + 1]);
        s.boxes.push(RefBox {
            b: [iv(0), iv(1), iv(2)],
            range: iv(3),
        });
    }
    Ok(out)
}

/// The two enclosures of f over one box.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Enclosures {
    /// The reference box.
    pub reference: RefBox,
    /// The interval rules' enclosure (as `ibeam eval --box`).
    pub interval: Interval,
    /// The affine enclosure (`--enclosure affine`).
    pub affine: Interval,
}

impl Enclosures {
    /// Whether both contain the reference range.
    pub fn contained(&self) -> bool {
        let r = self.reference.range;
        [self.interval, self.affine]
            .iter()
            .all(|e| e.lo <= r.lo && r.hi <= e.hi)
    }
}

/// Both enclosures of the surface's f (simplified, as renders evaluate
/// it) over each of its boxes: the interpreter's intervals, a tape's
/// affine forms (batched).
pub fn measure(s: &Surface) -> Result<Vec<Enclosures>, String> {
    let source = format!("object f = {};", s.formula);
    let scene = crate::lang::load_scene_source("enclosure.ib", &source)
        .map_err(|e| format!("{}: {e}", s.name))?;
    let f = simplify(&scene.objects[0].function);
    let interp = Interpreter::new(f.clone());
    let boxes: Vec<[Interval; 3]> = s.boxes.iter().map(|r| r.b).collect();
    let mut affine = vec![Interval::EMPTY; boxes.len()];
    Tape::new(&f).affine_batch(&boxes, &mut affine);
    Ok(s.boxes
        .iter()
        .zip(affine)
        .map(|(r, a)| Enclosures {
            reference: *r,
            interval: interp.interval(r.b),
            affine: a,
        })
        .collect())
}

/// Lower quartile, median and upper quartile (nearest rank).
pub fn quartiles(mut v: Vec<f64>) -> [f64; 3] {
    if v.is_empty() {
        return [f64::NAN; 3];
    }
    v.sort_by(f64::total_cmp);
    let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
    [at(0.25), at(0.5), at(0.75)]
}

/// The figures of one surface.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Summary {
    /// Whether f is identically zero there (absolute widths, not ratios).
    pub absolute: bool,
    /// Quartiles of the interval enclosures' overestimation.
    pub interval: [f64; 3],
    /// Quartiles of the affine enclosures' overestimation.
    pub affine: [f64; 3],
    /// Median over boxes of interval width over affine width.
    pub gain: f64,
    /// Boxes whose reference range an enclosure misses (must be 0).
    pub missed: usize,
}

/// Sums up a surface's enclosures.
pub fn summarise(es: &[Enclosures]) -> Summary {
    let absolute = es.iter().all(|e| e.reference.range.width() < 1e-30);
    let over = |w: Interval, r: Interval| {
        if absolute {
            w.width()
        } else {
            w.width() / r.width()
        }
    };
    let col = |pick: fn(&Enclosures) -> Interval| {
        quartiles(
            es.iter()
                .map(|e| over(pick(e), e.reference.range))
                .collect(),
        )
    };
    Summary {
        absolute,
        interval: col(|e| e.interval),
        affine: col(|e| e.affine),
        gain: quartiles(
            es.iter()
                .map(|e| e.interval.width() / e.affine.width())
                .collect(),
        )[1],
        missed: es.iter().filter(|e| !e.contained()).count(),
    }
}

/// The table `ibeam bench enclosure` prints, one row per surface.
pub fn table(rows: &[(String, Summary)]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "{:<34} {:>8} {:>30} {:>30} {:>10} {:>6}",
        "surface",
        "measure",
        "interval q1 / median / q3",
        "affine q1 / median / q3",
        "gain",
        "missed"
    );
    let q = |v: [f64; 3]| format!("{:.3e} / {:.3e} / {:.3e}", v[0], v[1], v[2]);
    for (name, s) in rows {
        let _ = writeln!(
            out,
            "{:<34} {:>8} {:>30} {:>30} {:>10.3e} {:>6}",
            name,
            if s.absolute { "width" } else { "ratio" },
            q(s.interval),
            q(s.affine),
            s.gain,
            s.missed
        );
    }
    out
}
