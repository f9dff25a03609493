//! Export to Fidget's `.vm` text format, so that Fidget's meshers and
//! viewers can use ibeam models.
//!
//! Ops Fidget has are written as they are; the others are rewritten into
//! ones it has: `powi` into squares and products (a reciprocal as
//! `div 1 a`), `pow(a, b)` into `exp(b·ln a)`, `sign(a)` into
//! `compare a 0`, and `sinh`, `cosh`, `tanh` into exponentials. Importing
//! the text back gives the same values: bit for bit where no op was
//! rewritten, within the rounding of the rewritten forms otherwise.

use crate::ir::{BinaryOp, Function, Op, UnaryOp, ValueId, Var};
use std::fmt::Write;

/// Writes the union (`min`) of `functions` as `.vm` text (no ops for an
/// empty list, which Fidget and ibeam then refuse to load).
pub fn to_vm(functions: &[Function]) -> String {
    let mut w = VmWriter::default();
    let _ = writeln!(w.out, "# written by ibeam {}", env!("CARGO_PKG_VERSION"));
    let roots: Vec<String> = functions
        .iter()
        .enumerate()
        .map(|(k, f)| w.function(k, f))
        .collect();
    let mut roots = roots.into_iter();
    if let Some(mut acc) = roots.next() {
        for r in roots {
            acc = w.emit(format!("min {acc} {r}"));
        }
    }
    w.out
}

/// The text so far and the next fresh id.
#[derive(Default)]
struct VmWriter {
    out: String,
    next: usize,
}

impl VmWriter {
    /// Writes one line `_N body` and returns its id.
    fn emit(&mut self, body: String) -> String {
        let id = format!("_{:x}", self.next);
        self.next += 1;
        let _ = writeln!(self.out, "{id} {body}");
        id
    }

    fn konst(&mut self, c: f64) -> String {
        self.emit(format!("const {c:?}"))
    }

    /// Writes function number `k` and returns the id of its root.
    fn function(&mut self, k: usize, f: &Function) -> String {
        let _ = writeln!(self.out, "# object {k}");
        let mut ids: Vec<String> = Vec::with_capacity(f.ops.len());
        for op in &f.ops {
            let id = |v: ValueId| ids[v.index()].clone();
            let line = match *op {
                Op::Var(v) => self.emit(
                    match v {
                        Var::X => "var-x",
                        Var::Y => "var-y",
                        Var::Z => "var-z",
                    }
                    .into(),
                ),
                Op::Const(c) => self.konst(c),
                Op::Unary(u, a) => self.unary(u, id(a)),
                Op::Binary(o, a, b) => self.binary(o, id(a), id(b)),
                Op::Powi(a, n) => self.powi(id(a), n),
            };
            ids.push(line);
        }
        ids[f.root.index()].clone()
    }

    fn unary(&mut self, u: UnaryOp, a: String) -> String {
        match u {
            UnaryOp::Sign => {
                let z = self.konst(0.0);
                self.emit(format!("compare {a} {z}"))
            }
            UnaryOp::Sinh | UnaryOp::Cosh => {
                // (e^a ∓ e^-a) / 2
                let ea = self.emit(format!("exp {a}"));
                let na = self.emit(format!("neg {a}"));
                let en = self.emit(format!("exp {na}"));
                let op = if u == UnaryOp::Sinh { "sub" } else { "add" };
                let s = self.emit(format!("{op} {ea} {en}"));
                let half = self.konst(0.5);
                self.emit(format!("mul {s} {half}"))
            }
            UnaryOp::Tanh => {
                // 1 - 2 / (e^2a + 1)
                let a2 = self.emit(format!("add {a} {a}"));
                let e = self.emit(format!("exp {a2}"));
                let one = self.konst(1.0);
                let d = self.emit(format!("add {e} {one}"));
                let two = self.konst(2.0);
                let q = self.emit(format!("div {two} {d}"));
                self.emit(format!("sub {one} {q}"))
            }
            _ => self.emit(format!("{} {a}", u.name())),
        }
    }

    fn binary(&mut self, o: BinaryOp, a: String, b: String) -> String {
        match o {
            BinaryOp::Pow => {
                let l = self.emit(format!("ln {a}"));
                let m = self.emit(format!("mul {b} {l}"));
                self.emit(format!("exp {m}"))
            }
            _ => self.emit(format!("{} {a} {b}", o.name())),
        }
    }

    /// `a^n` by squaring, a negative power as `1 / a^|n|`.
    fn powi(&mut self, a: String, n: i32) -> String {
        if n == 0 {
            return self.konst(1.0);
        }
        let mut m = n.unsigned_abs();
        let (mut base, mut acc): (String, Option<String>) = (a, None);
        loop {
            if m & 1 == 1 {
                acc = Some(match acc {
                    None => base.clone(),
                    Some(p) => self.emit(format!("mul {p} {base}")),
                });
            }
            m >>= 1;
            if m == 0 {
                break;
            }
            base = self.emit(format!("square {base}"));
        }
        let p = acc.unwrap_or(base);
        if n < 0 {
            let one = self.konst(1.0);
            self.emit(format!("div {one} {p}"))
        } else {
            p
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::random::{Rng, random_function};
    use crate::ir::semantics::run_point;
    use crate::lang::vm::parse_vm;

    fn value(f: &Function, p: [f64; 3]) -> f64 {
        let mut v = Vec::new();
        run_point(&f.ops, p, &mut v);
        v[f.root.index()]
    }

    fn rewritten(f: &Function) -> bool {
        f.ops.iter().any(|op| match op {
            Op::Unary(u, _) => matches!(u, UnaryOp::Sinh | UnaryOp::Cosh | UnaryOp::Tanh),
            Op::Binary(o, ..) => *o == BinaryOp::Pow,
            Op::Powi(_, n) => !matches!(n, 1 | 2),
            _ => false,
        })
    }

    // Export then import gives the same values: bit for bit where nothing
    // was rewritten, within rounding where something was.
    #[test]
    fn round_trip_keeps_values() {
        let mut rng = Rng::new(5);
        let (mut exact, mut close) = (0, 0);
        for seed in 0..200 {
            let f = random_function(seed, 6);
            let back = parse_vm(&to_vm(std::slice::from_ref(&f)), 0).expect("parses");
            for _ in 0..20 {
                let p = [0, 1, 2].map(|_| rng.range(-2.0, 2.0));
                let (a, b) = (value(&f, p), value(&back, p));
                if rewritten(&f) {
                    let ok = (a.is_nan() && b.is_nan())
                        || a == b
                        || (a - b).abs() <= 1e-9 * a.abs().max(1.0)
                        || !a.is_finite()
                        || !b.is_finite();
                    assert!(ok, "seed {seed} at {p:?}: {a:e} vs {b:e}");
                    close += 1;
                } else {
                    assert!(
                        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                        "seed {seed} at {p:?}: {a:e} vs {b:e}"
                    );
                    exact += 1;
                }
            }
        }
        assert!(exact > 500 && close > 500, "{exact} exact, {close} close");
    }

    #[test]
    fn several_objects_become_their_union() {
        let one = parse_vm("_0 var-x\n_1 const 1\n_2 sub _0 _1\n", 0).unwrap();
        let two = parse_vm("_0 var-y\n", 0).unwrap();
        let text = to_vm(&[one, two]);
        assert!(text.lines().last().unwrap().contains("min"));
        let back = parse_vm(&text, 0).unwrap();
        assert_eq!(value(&back, [3.0, 0.5, 0.0]), 0.5);
        assert_eq!(value(&back, [0.0, 5.0, 0.0]), -1.0);
    }
}
