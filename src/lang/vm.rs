//! Import of Fidget's `.vm` text format: one SSA op per line,
//! `_id op args…`, `#` comments; the last op is the result.

use super::diag::{Diag, suggest};
use crate::ir::{BinaryOp, Builder, Function, UnaryOp, ValueId, Var};
use std::collections::HashMap;
use std::ops::Range;

/// What a `.vm` opcode lowers to.
#[derive(Copy, Clone, Debug, PartialEq)]
enum VmOp {
    Var(Var),
    Const,
    Unary(UnaryOp),
    Recip,
    Binary(BinaryOp),
    /// -1, 0 or 1 as a < b, a = b, a > b: `sign(a - b)`.
    Compare,
    /// 1 where a = 0, else 0: `1 - |sign(a)|`.
    Not,
    /// a where a = 0, else b: `b·|sign(a)|`.
    And,
    /// a where a ≠ 0, else b: `a + b·(1 - |sign(a)|)`.
    Or,
    /// An op whose meaning depends on state ibeam does not model.
    Unsupported(&'static str),
}

impl VmOp {
    /// How many arguments the opcode takes (a literal for `const`).
    fn arity(self) -> usize {
        match self {
            VmOp::Var(_) => 0,
            VmOp::Const | VmOp::Unary(_) | VmOp::Recip | VmOp::Not => 1,
            VmOp::Binary(_) | VmOp::Compare | VmOp::And | VmOp::Or => 2,
            VmOp::Unsupported(_) => 0,
        }
    }
}

/// The opcodes we read (every one that has an IR equivalent), with what
/// each lowers to; the arity follows from that.
const OPS: &[(&str, VmOp)] = &[
    ("var-x", VmOp::Var(Var::X)),
    ("var-y", VmOp::Var(Var::Y)),
    ("var-z", VmOp::Var(Var::Z)),
    ("const", VmOp::Const),
    ("neg", VmOp::Unary(UnaryOp::Neg)),
    ("abs", VmOp::Unary(UnaryOp::Abs)),
    ("recip", VmOp::Recip),
    ("sqrt", VmOp::Unary(UnaryOp::Sqrt)),
    ("square", VmOp::Unary(UnaryOp::Square)),
    ("exp", VmOp::Unary(UnaryOp::Exp)),
    ("ln", VmOp::Unary(UnaryOp::Ln)),
    ("sin", VmOp::Unary(UnaryOp::Sin)),
    ("cos", VmOp::Unary(UnaryOp::Cos)),
    ("add", VmOp::Binary(BinaryOp::Add)),
    ("sub", VmOp::Binary(BinaryOp::Sub)),
    ("mul", VmOp::Binary(BinaryOp::Mul)),
    ("div", VmOp::Binary(BinaryOp::Div)),
    ("min", VmOp::Binary(BinaryOp::Min)),
    ("max", VmOp::Binary(BinaryOp::Max)),
    ("atan2", VmOp::Binary(BinaryOp::Atan2)),
    ("floor", VmOp::Unary(UnaryOp::Floor)),
    ("ceil", VmOp::Unary(UnaryOp::Ceil)),
    ("round", VmOp::Unary(UnaryOp::Round)),
    ("tan", VmOp::Unary(UnaryOp::Tan)),
    ("asin", VmOp::Unary(UnaryOp::Asin)),
    ("acos", VmOp::Unary(UnaryOp::Acos)),
    ("atan", VmOp::Unary(UnaryOp::Atan)),
    ("mod", VmOp::Binary(BinaryOp::Mod)),
    ("compare", VmOp::Compare),
    ("not", VmOp::Not),
    ("and", VmOp::And),
    ("or", VmOp::Or),
    (
        "rand",
        VmOp::Unsupported("a pseudo-random number has no interval enclosure ibeam could guarantee"),
    ),
    (
        "mix",
        VmOp::Unsupported(
            "Fidget's `mix` draws from a pseudo-random source; use min/max/mul instead",
        ),
    ),
];

fn vm_op(name: &str) -> Option<VmOp> {
    OPS.iter().find(|(n, _)| *n == name).map(|(_, op)| *op)
}

/// Words of a line with their byte offsets in the whole text.
fn words(line: &str, base: usize) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, c) in line.char_indices() {
        match (c.is_whitespace(), start) {
            (true, Some(s)) => {
                out.push((base + s, &line[s..i]));
                start = None;
            }
            (false, None) => start = Some(i),
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((base + s, &line[s..]));
    }
    out
}

/// A word of a line with its byte offset in the whole text.
type Word<'t> = (usize, &'t str);

fn word_span((at, s): Word<'_>) -> Range<usize> {
    at..at + s.len()
}

/// Parses `.vm` text (source number `src`) into a function whose root is
/// the last op.
pub fn parse_vm(text: &str, src: usize) -> Result<Function, Diag> {
    // A line is about an op: room for them all up front (growing as it
    // went was a third of parsing prospero).
    let lines = text.bytes().filter(|&c| c == b'\n').count() + 1;
    let mut b = Builder::with_capacity(lines);
    let mut ids: HashMap<&str, (ValueId, usize)> = HashMap::with_capacity(lines);
    let mut last = None;
    let mut base = 0;
    for line in text.split_inclusive('\n') {
        let line_base = base;
        base += line.len();
        let content = line.split('#').next().unwrap_or("");
        let w = words(content, line_base);
        if w.is_empty() {
            continue;
        }
        let v = parse_line(&mut b, &ids, &w, src)?;
        if let Some((_, first)) = ids.get(w[0].1) {
            return Err(Diag::new(
                src,
                word_span(w[0]),
                format!("`{}` is defined twice", w[0].1),
            )
            .with_secondary(src, *first..*first + w[0].1.len(), "first defined here"));
        }
        ids.insert(w[0].1, (v, w[0].0));
        last = Some(v);
    }
    match last {
        Some(root) => Ok(b.finish(root)),
        None => Err(Diag::new(src, 0..0, "the file has no ops".into())
            .with_help("each line is `_id op args…`, e.g. `_0 var-x`")),
    }
}

/// Emits the op of one line's words `w` (at least one), whose operands
/// `ids` defines.
// long-fn: one match arm per `.vm` opcode, as the format lists them.
fn parse_line(
    b: &mut Builder,
    ids: &HashMap<&str, (ValueId, usize)>,
    w: &[Word<'_>],
    src: usize,
) -> Result<ValueId, Diag> {
    let Some(&op_word) = w.get(1) else {
        return Err(
            Diag::new(src, word_span(w[0]), format!("`{}` has no op", w[0].1))
                .with_help("each line is `_id op args…`, e.g. `_3 add _1 _2`"),
        );
    };
    let op = vm_op(op_word.1).ok_or_else(|| unknown_op(op_word, src))?;
    if let VmOp::Unsupported(why) = op {
        return Err(Diag::new(
            src,
            word_span(op_word),
            format!("op `{}` is not supported: {why}", op_word.1),
        ));
    }
    let arity = op.arity();
    let args = &w[2..];
    if args.len() != arity {
        let at = args.get(arity).copied().unwrap_or(op_word);
        return Err(Diag::new(
            src,
            word_span(at),
            format!(
                "`{}` takes {arity} argument{}, but {} {} given",
                op_word.1,
                if arity == 1 { "" } else { "s" },
                args.len(),
                if args.len() == 1 { "was" } else { "were" }
            ),
        ));
    }
    let operand = |i: usize| -> Result<ValueId, Diag> {
        let a = args[i];
        ids.get(a.1).map(|(v, _)| *v).ok_or_else(|| {
            Diag::new(
                src,
                word_span(a),
                format!("`{}` is not defined before this line", a.1),
            )
        })
    };
    Ok(match op {
        VmOp::Var(v) => b.var(v),
        VmOp::Const => {
            let a = args[0];
            match a.1.parse::<f64>() {
                Ok(c) if c.is_finite() => b.constant(c),
                _ => {
                    return Err(Diag::new(
                        src,
                        word_span(a),
                        format!("bad number literal `{}`", a.1),
                    ));
                }
            }
        }
        VmOp::Unary(u) => {
            let a = operand(0)?;
            b.unary(u, a)
        }
        VmOp::Recip => {
            let a = operand(0)?;
            let one = b.constant(1.0);
            b.binary(BinaryOp::Div, one, a)
        }
        VmOp::Binary(o) => {
            let (x, y) = (operand(0)?, operand(1)?);
            b.binary(o, x, y)
        }
        VmOp::Compare => {
            let (x, y) = (operand(0)?, operand(1)?);
            let d = b.binary(BinaryOp::Sub, x, y);
            b.unary(UnaryOp::Sign, d)
        }
        VmOp::Not => {
            let nz = nonzero(b, operand(0)?);
            let one = b.constant(1.0);
            b.binary(BinaryOp::Sub, one, nz)
        }
        VmOp::And => {
            let (x, y) = (operand(0)?, operand(1)?);
            let nz = nonzero(b, x);
            b.binary(BinaryOp::Mul, y, nz)
        }
        VmOp::Or => {
            let (x, y) = (operand(0)?, operand(1)?);
            let nz = nonzero(b, x);
            let one = b.constant(1.0);
            let z = b.binary(BinaryOp::Sub, one, nz);
            let t = b.binary(BinaryOp::Mul, y, z);
            b.binary(BinaryOp::Add, x, t)
        }
        VmOp::Unsupported(_) => unreachable!("rejected above"),
    })
}

/// `|sign(a)|`: 1 where a ≠ 0, 0 where a = 0 (NaN for NaN).
fn nonzero(b: &mut Builder, a: ValueId) -> ValueId {
    let s = b.unary(UnaryOp::Sign, a);
    b.unary(UnaryOp::Abs, s)
}

/// "unknown op", with the closest opcode or the list of them as a hint.
fn unknown_op(op_word: Word<'_>, src: usize) -> Diag {
    let d = Diag::new(
        src,
        word_span(op_word),
        format!("unknown op `{}`", op_word.1),
    );
    let supported = || {
        OPS.iter()
            .filter(|(_, op)| !matches!(op, VmOp::Unsupported(_)))
            .map(|(n, _)| *n)
    };
    match suggest(op_word.1, supported()) {
        Some(s) => d.with_help(format!("did you mean `{s}`?")),
        None => {
            let names: Vec<&str> = supported().collect();
            d.with_help(format!("supported ops: {}", names.join(" ")))
        }
    }
}
