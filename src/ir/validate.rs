//! Checks the IR contract (see [`crate::ir`]) as a separate pass.

use super::{Function, Op};
use std::fmt;

/// A broken IR invariant, with the op where it was found.
#[derive(Debug, Clone, PartialEq)]
pub struct InvalidIr {
    /// Index of the offending op (or of the root when it is out of range).
    pub at: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for InvalidIr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid IR at v{}: {}", self.at, self.message)
    }
}

impl std::error::Error for InvalidIr {}

/// Checks that every operand is defined before use, that the root exists,
/// and that no constant is NaN.
pub fn validate(f: &Function) -> Result<(), InvalidIr> {
    if f.root.index() >= f.ops.len() {
        return Err(InvalidIr {
            at: f.root.index(),
            message: format!("root {} is not defined ({} ops)", f.root, f.ops.len()),
        });
    }
    for (i, op) in f.ops.iter().enumerate() {
        for a in op.operands() {
            if a.index() >= i {
                return Err(InvalidIr {
                    at: i,
                    message: format!("operand {a} is used before it is defined"),
                });
            }
        }
        if let Op::Const(c) = op
            && c.is_nan()
        {
            return Err(InvalidIr {
                at: i,
                message: "constant is NaN".into(),
            });
        }
    }
    Ok(())
}

/// Panics with the broken invariant in debug builds; free in release.
pub fn debug_validate(f: &Function, after: &str) {
    if cfg!(debug_assertions)
        && let Err(e) = validate(f)
    {
        panic!("after {after}: {e}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::{BinaryOp, ValueId, Var};

    #[test]
    fn rejects_use_before_definition() {
        let f = Function {
            ops: vec![
                Op::Binary(BinaryOp::Add, ValueId(1), ValueId(1)),
                Op::Var(Var::X),
            ],
            root: ValueId(0),
        };
        assert_eq!(validate(&f).unwrap_err().at, 0);
    }

    #[test]
    fn rejects_missing_root() {
        let f = Function {
            ops: vec![Op::Var(Var::X)],
            root: ValueId(3),
        };
        assert!(validate(&f).is_err());
    }
}
