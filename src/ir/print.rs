//! The stable text form of the IR: one op per line, `v7 = mul v3 v5`.

use super::{Function, Op};
use std::fmt::Write;

/// Prints `f` as text, one op per line, ending with `return vN`.
///
/// Constants print with Rust's shortest round-trip formatting, so the text
/// names the exact f64.
pub fn print(f: &Function) -> String {
    let mut out = String::new();
    for (i, op) in f.ops.iter().enumerate() {
        let _ = write!(out, "v{i} = {}", op.mnemonic());
        match *op {
            Op::Var(v) => {
                let _ = write!(out, " {}", v.name());
            }
            Op::Const(c) => {
                let _ = write!(out, " {c:?}");
            }
            Op::Powi(a, n) => {
                let _ = write!(out, " {a} {n}");
            }
            Op::Unary(_, a) => {
                let _ = write!(out, " {a}");
            }
            Op::Binary(_, a, b) => {
                let _ = write!(out, " {a} {b}");
            }
        }
        out.push('\n');
    }
    let _ = writeln!(out, "return {}", f.root);
    out
}

/// Op counts per mnemonic, sorted by mnemonic, then the total.
pub fn op_counts(f: &Function) -> (Vec<(&'static str, usize)>, usize) {
    let mut counts: std::collections::BTreeMap<&'static str, usize> = Default::default();
    for op in &f.ops {
        *counts.entry(op.mnemonic()).or_default() += 1;
    }
    (counts.into_iter().collect(), f.ops.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::{BinaryOp, Builder, Var};

    #[test]
    fn prints_one_op_per_line() {
        let mut b = Builder::new();
        let x = b.var(Var::X);
        let c = b.constant(-1.5);
        let s = b.binary(BinaryOp::Mul, x, c);
        let p = b.powi(s, -2);
        let f = b.finish(p);
        assert_eq!(
            print(&f),
            "v0 = var x\nv1 = const -1.5\nv2 = mul v0 v1\nv3 = powi v2 -2\nreturn v3\n"
        );
    }
}
