//! The `.vm` importer (Fidget's SSA text format: `_id op args…` per line)
//! on text built from the fuzz bytes: mostly well-formed lines whose
//! operands name earlier ops, so that most inputs load and reach the
//! evaluators, with some damage mixed in (unknown ops, wrong argument
//! counts, undefined or repeated names, comments, blank lines, odd
//! constants) to reach the importer's diagnostics.
//!
//! Checked: loading returns a scene or a diagnostic, never an "internal
//! error" (the loader's name for a panic); where it loads, the JIT and
//! the reference interpreter, each built by `build_evaluators` over the
//! same simplified function, give the same point value bits (NaN equal to
//! NaN) and the same interval over boxes around those points, as
//! `tests/random_scenes.rs` requires of them.

#![no_main]

use ibeam::eval::{EvalKind, build_evaluators};
use ibeam::interval::Interval;
use libfuzzer_sys::fuzz_target;

/// Choices read from the fuzz bytes; zeros once they run out.
struct Choices<'a>(&'a [u8]);

impl Choices<'_> {
    fn byte(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }

    fn below(&mut self, n: usize) -> usize {
        usize::from(self.byte()) % n
    }

    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

/// Every opcode the importer reads, with its argument count.
const OPS: &[(&str, usize)] = &[
    ("var-x", 0),
    ("var-y", 0),
    ("var-z", 0),
    ("const", 1),
    ("neg", 1),
    ("abs", 1),
    ("recip", 1),
    ("sqrt", 1),
    ("square", 1),
    ("exp", 1),
    ("ln", 1),
    ("sin", 1),
    ("cos", 1),
    ("add", 2),
    ("sub", 2),
    ("mul", 2),
    ("div", 2),
    ("min", 2),
    ("max", 2),
    ("atan2", 2),
];

/// Constant texts: ordinary numbers, and the forms a number parser gets
/// wrong (signs, exponents, infinities, NaN, garbage).
const CONSTS: &[&str] = &[
    "0", "1", "-1", "0.5", "2.95", "-3.675", "1e-3", "1e300", "-0", "inf", "-inf", "NaN", "1e400",
    "0x10", "+2", ".5", "5.", "abc", "",
];

/// The `.vm` text for the bytes: up to 64 lines, ids in Fidget's `_hex`
/// style.
fn vm_text(c: &mut Choices) -> String {
    let mut text = String::new();
    // Names defined so far (the ones operands may refer to).
    let mut names: Vec<String> = Vec::new();
    for i in 0..64 {
        if c.is_empty() && i > 0 {
            break;
        }
        let kind = c.byte();
        // One line in 16 is damaged in some way.
        if kind >= 240 {
            match kind & 7 {
                0 => text += "# a comment line\n",
                1 => text += "\n   \t\n",
                2 => text += &format!("_{i:x} frobnicate _0\n"),
                3 => text += &format!("_{i:x}\n"),
                4 => text += &format!("_{i:x} add _0\n"),
                5 => text += &format!("_{i:x} neg _nope\n"),
                6 => {
                    // A repeated name: redefines (or is refused).
                    let name = names.first().cloned().unwrap_or_else(|| "_0".into());
                    text += &format!("{name} var-x\n");
                }
                _ => text += &format!("_{i:x} sqrt _{:x} # trailing comment\n", i + 5),
            }
            continue;
        }
        let (op, arity) = OPS[usize::from(kind) % OPS.len()];
        let name = format!("_{i:x}");
        let mut line = format!("{name} {op}");
        if op == "const" {
            line += " ";
            line += CONSTS[c.below(CONSTS.len())];
        } else {
            for _ in 0..arity {
                // An earlier name, or (with none yet) one that is not.
                let arg = if names.is_empty() {
                    "_0".to_string()
                } else {
                    names[c.below(names.len())].clone()
                };
                line += " ";
                line += &arg;
            }
        }
        text += &line;
        text.push('\n');
        names.push(name);
    }
    text
}

/// A coordinate in [-4, 4] from a byte.
fn coord(b: u8) -> f64 {
    f64::from(b) / 255.0 * 8.0 - 4.0
}

fuzz_target!(|data: &[u8]| {
    let mut c = Choices(data);
    let text = vm_text(&mut c);
    let scene = match ibeam::lang::load_scene_source("fuzz.vm", &text) {
        Ok(s) => s,
        Err(e) => {
            assert!(
                !e.message.contains("internal error"),
                "importer panicked: {e}\n{text}"
            );
            return;
        }
    };
    let jit = build_evaluators(&scene, EvalKind::Jit).expect("JIT accepts valid IR");
    let interp = build_evaluators(&scene, EvalKind::Interp).expect("valid IR");
    // A few points: the origin, then any left over bytes.
    let mut points = vec![[0.0; 3], [0.5, -0.25, 1.0]];
    let rest = c.0;
    points.extend(
        rest.chunks_exact(3)
            .take(8)
            .map(|p| [coord(p[0]), coord(p[1]), coord(p[2])]),
    );
    for (j, i) in jit.iter().zip(&interp) {
        for &p in &points {
            let (a, b) = (j.point(p), i.point(p));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "at {p:?}: JIT {a}, interpreter {b}\n{text}"
            );
            let bx: [Interval; 3] = p.map(|v| Interval::new(v - 0.25, v + 0.25));
            let (ja, ib) = (j.interval(bx), i.interval(bx));
            assert!(
                ja == ib || (ja.is_empty() && ib.is_empty()),
                "over {bx:?}: JIT {ja:?}, interpreter {ib:?}\n{text}"
            );
        }
    }
});
