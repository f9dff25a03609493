//! The lowerer's state and the expression forms: numbers, `-`, `^`,
//! sums and products, with constants folded as they are met.

use super::{Def, MAX_RECURSION, MAX_STEPS, Program};
use crate::ir::semantics::{point_binary, point_powi, point_unary};
use crate::ir::{BinaryOp, Builder, Function, UnaryOp, ValueId, Var};
use crate::lang::ast::{AddOp, Expr, ExprKind, MulOp, Span};
use crate::lang::diag::Diag;
use std::collections::HashMap;
use std::rc::Rc;

/// A lowered value: a number known now, or an IR value.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(in crate::lang) enum Val {
    /// Known while lowering (folded in f64).
    Const(f64),
    /// Depends on x, y or z.
    Node(ValueId),
}

/// What x, y or z currently stands for.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub(in crate::lang) enum Coord {
    /// The input coordinate itself (not emitted until used).
    Var(Var),
    /// A value computed by a transform.
    Node(ValueId),
}

/// What x, y and z stand for where an expression is lowered.
pub(in crate::lang) type Env = [Coord; 3];

/// x, y and z as themselves (no transform applied).
pub(super) const IDENTITY: Env = [Coord::Var(Var::X), Coord::Var(Var::Y), Coord::Var(Var::Z)];

/// A parameter bound to the unevaluated argument of a call.
#[derive(Debug)]
pub(super) struct Thunk<'a> {
    pub(super) id: usize,
    pub(super) expr: &'a Expr,
    pub(super) ctx: Ctx<'a>,
    /// Definitions being expanded where the call was written: the argument
    /// belongs to the caller, so only these count for recursion.
    pub(super) stack_len: usize,
}

/// The parameters visible in a function body.
#[derive(Debug)]
pub(super) struct Scope<'a> {
    pub(super) params: Vec<(&'a str, Rc<Thunk<'a>>)>,
}

/// Where an expression is lowered: its parameter scope and source.
#[derive(Clone, Debug)]
pub(in crate::lang) struct Ctx<'a> {
    pub(super) scope: Option<Rc<Scope<'a>>>,
    pub(super) src: usize,
}

impl<'a> Ctx<'a> {
    /// The context of a top-level expression of source `src`.
    pub(super) fn top(src: usize) -> Ctx<'a> {
        Ctx { scope: None, src }
    }

    /// The argument bound to parameter `name`, if in scope.
    pub(super) fn param(&self, name: &str) -> Option<Rc<Thunk<'a>>> {
        let scope = self.scope.as_ref()?;
        scope
            .params
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| t.clone())
    }

    /// An error at `span` of this context's source.
    pub(in crate::lang) fn diag(&self, span: (usize, usize), message: String) -> Diag {
        Diag::new(self.src, span.0..span.1, message)
    }
}

/// Lowers the expressions of one function; its builder collects the IR.
pub(in crate::lang) struct Lowerer<'p, 'a> {
    pub(super) prog: &'p Program<'a>,
    pub(in crate::lang) b: Builder,
    /// Definitions being expanded, innermost last (for recursion errors).
    pub(super) stack: Vec<&'p Def<'a>>,
    pub(super) def_memo: HashMap<(usize, Env), Val>,
    pub(super) thunk_memo: HashMap<(usize, Env), Val>,
    pub(super) next_thunk: usize,
    pub(super) steps: u64,
    recursion: usize,
}

impl<'p, 'a> Lowerer<'p, 'a> {
    /// A lowerer with an empty builder.
    pub(super) fn new(prog: &'p Program<'a>) -> Lowerer<'p, 'a> {
        Lowerer {
            prog,
            b: Builder::new(),
            stack: Vec::new(),
            def_memo: HashMap::new(),
            thunk_memo: HashMap::new(),
            next_thunk: 0,
            steps: 0,
            recursion: 0,
        }
    }

    /// The function computed so far, returning `root`.
    pub(super) fn finish(self, root: ValueId) -> Function {
        self.b.finish(root)
    }

    /// `v` as an IR value (a constant op for a folded number).
    pub(in crate::lang) fn node(&mut self, v: Val) -> ValueId {
        match v {
            Val::Const(c) => self.b.constant(c),
            Val::Node(n) => n,
        }
    }

    /// The IR value a coordinate stands for.
    pub(in crate::lang) fn coord(&mut self, c: Coord) -> ValueId {
        match c {
            Coord::Var(v) => self.b.var(v),
            Coord::Node(n) => n,
        }
    }

    fn folded(&self, c: f64, ctx: &Ctx<'a>, span: (usize, usize)) -> Result<Val, Diag> {
        if c.is_nan() {
            Err(ctx
                .diag(
                    span,
                    "this constant expression is not a number (NaN)".into(),
                )
                .with_help("check for a square root or logarithm of a negative number, or 0/0"))
        } else {
            Ok(Val::Const(c))
        }
    }

    /// `op a`, folded when `a` is a constant.
    pub(in crate::lang) fn unary(
        &mut self,
        op: UnaryOp,
        a: Val,
        ctx: &Ctx<'a>,
        span: (usize, usize),
    ) -> Result<Val, Diag> {
        match a {
            Val::Const(c) => self.folded(point_unary(op, c), ctx, span),
            Val::Node(n) => Ok(Val::Node(self.b.unary(op, n))),
        }
    }

    /// `a op b`, folded when both are constants.
    pub(in crate::lang) fn binary(
        &mut self,
        op: BinaryOp,
        a: Val,
        b: Val,
        ctx: &Ctx<'a>,
        span: (usize, usize),
    ) -> Result<Val, Diag> {
        if let (Val::Const(x), Val::Const(y)) = (a, b) {
            return self.folded(point_binary(op, x, y), ctx, span);
        }
        let (x, y) = (self.node(a), self.node(b));
        Ok(Val::Node(self.b.binary(op, x, y)))
    }

    /// `a^n`, folded when `a` is a constant.
    pub(in crate::lang) fn powi(
        &mut self,
        a: Val,
        n: i32,
        ctx: &Ctx<'a>,
        span: (usize, usize),
    ) -> Result<Val, Diag> {
        match a {
            Val::Const(c) => self.folded(point_powi(c, n), ctx, span),
            Val::Node(v) => Ok(Val::Node(self.b.powi(v, n))),
        }
    }

    /// A flat chain `t0 op1 t1 op2 t2 …` (n-ary sums and products, kept
    /// flat by the parser so a million terms never nest), folded left.
    fn lower_chain(
        &mut self,
        terms: impl Iterator<Item = (BinaryOp, &'a Expr)>,
        span: Span,
        what: &str,
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let mut acc: Option<Val> = None;
        for (op, t) in terms {
            let v = self.lower(t, ctx, env)?;
            acc = Some(match acc {
                None => v,
                Some(a) => self.binary(op, a, v, ctx, (span.0, t.span.1))?,
            });
        }
        acc.ok_or_else(|| ctx.diag(span, format!("empty {what}")))
    }

    /// Lowers `e` where x, y, z stand for `env`.
    pub(in crate::lang) fn lower(
        &mut self,
        e: &'a Expr,
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        if self.recursion >= MAX_RECURSION {
            return Err(ctx
                .diag(
                    e.span,
                    format!(
                        "definitions nested too deeply (over {MAX_RECURSION} levels when inlined)"
                    ),
                )
                .with_help("split the scene into fewer nested definitions"));
        }
        self.recursion += 1;
        let r = self.lower_node(e, ctx, env);
        self.recursion -= 1;
        r
    }

    fn lower_node(&mut self, e: &'a Expr, ctx: &Ctx<'a>, env: Env) -> Result<Val, Diag> {
        self.steps += 1;
        if self.steps > MAX_STEPS {
            return Err(ctx
                .diag(e.span, format!("this is too large to lower (over {MAX_STEPS} steps)"))
                .with_help("definitions are inlined at every use; share work through fewer, larger definitions"));
        }
        match &e.kind {
            ExprKind::Num(v) => Ok(Val::Const(*v)),
            ExprKind::Name(n) => self.name(n, e.span, ctx, env),
            ExprKind::Neg(a) => {
                let a = self.lower(a, ctx, env)?;
                self.unary(UnaryOp::Neg, a, ctx, e.span)
            }
            ExprKind::Pow(a, n) => {
                let base = self.lower(a, ctx, env)?;
                let exp = self.lower(n, ctx, env)?;
                let hint = "use `pow(a, b)` for a real exponent";
                match exp {
                    Val::Const(c) => match int_exponent(c) {
                        Some(k) => self.powi(base, k, ctx, e.span),
                        None if c.fract() == 0.0 => Err(ctx.diag(
                            n.span,
                            format!("the exponent of `^` is too large ({c}; at most 2^31 - 1 in size)"),
                        )),
                        None => Err(ctx
                            .diag(n.span, format!("the exponent of `^` must be an integer, but it is {c}"))
                            .with_help(hint)),
                    },
                    Val::Node(_) => Err(ctx
                        .diag(n.span, "the exponent of `^` must be a constant integer, but this depends on x, y or z".into())
                        .with_help(hint)),
                }
            }
            ExprKind::Sum(terms) => {
                let terms = terms.iter().map(|(op, t)| {
                    let op = match op {
                        AddOp::Add => BinaryOp::Add,
                        AddOp::Sub => BinaryOp::Sub,
                    };
                    (op, t)
                });
                self.lower_chain(terms, e.span, "sum", ctx, env)
            }
            ExprKind::Product(terms) => {
                let terms = terms.iter().map(|(op, t)| {
                    let op = match op {
                        MulOp::Mul => BinaryOp::Mul,
                        MulOp::Div => BinaryOp::Div,
                    };
                    (op, t)
                });
                self.lower_chain(terms, e.span, "product", ctx, env)
            }
            ExprKind::Call {
                name,
                name_span,
                args,
            } => self.call(name, *name_span, args, e.span, ctx, env),
        }
    }

    /// Lowers every argument.
    pub(in crate::lang) fn args(
        &mut self,
        args: &'a [Expr],
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Vec<Val>, Diag> {
        args.iter().map(|a| self.lower(a, ctx, env)).collect()
    }

    /// Lowers an argument that must be a constant; `what` names it in the
    /// error.
    pub(in crate::lang) fn constant_arg(
        &mut self,
        a: &'a Expr,
        ctx: &Ctx<'a>,
        env: Env,
        what: &str,
    ) -> Result<f64, Diag> {
        match self.lower(a, ctx, env)? {
            Val::Const(c) => Ok(c),
            Val::Node(_) => Err(ctx.diag(
                a.span,
                format!("{what} must be a constant, but this depends on x, y or z"),
            )),
        }
    }

    /// `v0 op v1 op v2 …`, folded left.
    pub(in crate::lang) fn fold_all(
        &mut self,
        op: BinaryOp,
        vals: Vec<Val>,
        ctx: &Ctx<'a>,
        span: (usize, usize),
    ) -> Result<Val, Diag> {
        let mut it = vals.into_iter();
        let mut acc = it
            .next()
            .ok_or_else(|| ctx.diag(span, "missing arguments".into()))?;
        for v in it {
            acc = self.binary(op, acc, v, ctx, span)?;
        }
        Ok(acc)
    }
}

/// `c` as an `i32` exponent, when it is an integer in range.
pub(in crate::lang) fn int_exponent(c: f64) -> Option<i32> {
    if c.fract() == 0.0 && c.abs() <= f64::from(i32::MAX) {
        Some(c as i32)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_exponents() {
        assert_eq!(int_exponent(3.0), Some(3));
        assert_eq!(int_exponent(-2.0), Some(-2));
        assert_eq!(int_exponent(0.5), None);
        assert_eq!(int_exponent(1e10), None);
    }
}
