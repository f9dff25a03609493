//! Lowering from the scene AST to SSA IR.
//!
//! Definitions are inlined: `let NAME = e;` and `fn NAME(a, b) = e;` are
//! expanded at each use. Arguments are passed by name (substituted, not
//! evaluated first), and x, y, z inside a body are the coordinates where it
//! is used; so a transform applied to a call, or inside a function to one of
//! its parameters, moves the shape the argument describes. The coordinate
//! environment maps x, y, z to values and is rewritten by the transforms.
//!
//! Constant sub-expressions are evaluated in f64 while lowering (so that
//! exponents, scale factors and blend radii are known numbers); everything
//! that depends on x, y or z is emitted through
//! [`Builder`](crate::ir::Builder), whose hash-consing merges repeated
//! sub-expressions. No other simplification happens here.
//!
//! Work is bounded: the parser caps the tree depth, calls may nest at most
//! [`MAX_CALL_DEPTH`] deep, and lowering gives up after [`MAX_STEPS`] steps,
//! so no input makes lowering overflow the stack or run away.
//!
//! The lowerer itself and the expression forms are in `expr`, names, calls
//! and the inlining of definitions in `calls`; the built-in functions are
//! [`Builtin`].

mod calls;
mod expr;
mod shapes;

pub(in crate::lang) use expr::{Coord, Ctx, Env, Lowerer, Val, int_exponent};

use crate::ir::{Function, Op, Var};
use crate::lang::ast::{Expr, ExprKind, Ident, Item};
use crate::lang::builtins::Builtin;
use crate::lang::diag::Diag;
use expr::IDENTITY;
use std::collections::HashMap;

/// How deeply definitions may call one another.
pub const MAX_CALL_DEPTH: usize = 128;

/// Lowering steps (expression nodes visited) allowed per object.
pub const MAX_STEPS: u64 = 5_000_000;

/// How deeply lowering may recurse (expression levels plus inlined
/// bodies); with the loader's stack this leaves a wide margin.
pub const MAX_RECURSION: usize = 16_384;

/// The coordinate names.
const COORDS: [(&str, Var); 3] = [("x", Var::X), ("y", Var::Y), ("z", Var::Z)];

fn coord(name: &str) -> Option<Var> {
    COORDS.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
}

/// A `let` or `fn` definition.
#[derive(Clone, Debug)]
struct Def<'a> {
    id: usize,
    src: usize,
    name: &'a Ident,
    /// `None` for a `let`.
    params: Option<&'a [Ident]>,
    body: &'a Expr,
}

/// All global definitions of a scene (prelude included), checked for
/// duplicates and reserved names.
#[derive(Debug)]
pub struct Program<'a> {
    defs: HashMap<&'a str, Def<'a>>,
    /// The `let`s another `let` reads, in source order, when there are more
    /// than [`CHAIN_PREWARM`] of them (see [`Program::prewarm`]).
    chain: Vec<&'a str>,
}

/// Chains of `let`s longer than this are lowered in source order before an
/// object, so that a use deep in the chain finds its operands already
/// lowered instead of inlining thousands of definitions inside one another.
/// Shorter chains are lowered where used, as written (which keeps the op
/// order of ordinary scenes).
pub const CHAIN_PREWARM: usize = 64;

impl<'a> Program<'a> {
    /// Collects the `let` and `fn` items of each `(source, items)` pair.
    pub fn new(files: &[(usize, &'a [Item])]) -> Result<Program<'a>, Diag> {
        let mut defs: HashMap<&'a str, Def<'a>> = HashMap::new();
        for &(src, items) in files {
            for item in items {
                let (name, params, body) = match item {
                    Item::Let { name, body } => (name, None, body),
                    Item::Fn { name, params, body } => (name, Some(params.as_slice()), body),
                    _ => continue,
                };
                check_definable(src, name, "define")?;
                if let Some(prev) = defs.get(name.name.as_str()) {
                    return Err(Diag::new(
                        src,
                        name.span.0..name.span.1,
                        format!("`{}` is defined twice", name.name),
                    )
                    .with_secondary(
                        prev.src,
                        prev.name.span.0..prev.name.span.1,
                        "first defined here",
                    )
                    .with_help("rename one of the definitions"));
                }
                if let Some(ps) = params {
                    for (i, p) in ps.iter().enumerate() {
                        check_definable(src, p, "use as a parameter")?;
                        if let Some(q) = ps[..i].iter().find(|q| q.name == p.name) {
                            return Err(Diag::new(
                                src,
                                p.span.0..p.span.1,
                                format!("parameter `{}` is defined twice", p.name),
                            )
                            .with_secondary(
                                src,
                                q.span.0..q.span.1,
                                "first defined here",
                            ));
                        }
                    }
                }
                let id = defs.len();
                defs.insert(
                    &name.name,
                    Def {
                        id,
                        src,
                        name,
                        params,
                        body,
                    },
                );
            }
        }
        let chain = let_chain(&defs);
        Ok(Program { defs, chain })
    }

    /// Lowers the long `let` chain (if any) in source order, so each `let`
    /// reads memoised values of the ones before it. SSA exports write
    /// `let v1 = …; let v2 = v1 + …;` thousands deep, which inlining where
    /// used would nest past [`MAX_CALL_DEPTH`]. Errors are left for the
    /// use that needs the value to report; the steps spent here do not
    /// count against the object (each expansion still stops at
    /// [`MAX_STEPS`]).
    fn prewarm<'p>(&'p self, l: &mut Lowerer<'p, 'a>) {
        let steps = l.steps;
        for name in &self.chain {
            let def = &self.defs[name];
            let _ = l.expand(def, &[], def.name.span, &Ctx::top(def.src), IDENTITY);
        }
        l.steps = steps;
    }

    /// Lowers `body` (from source `src`) to a function of x, y, z.
    pub fn lower(&self, body: &Expr, src: usize) -> Result<Function, Diag> {
        let mut l = Lowerer::new(self);
        self.prewarm(&mut l);
        let ctx = Ctx::top(src);
        let v = l.lower(body, &ctx, IDENTITY)?;
        match v {
            Val::Node(root) => Ok(l.finish(root)),
            Val::Const(c) => Err(Diag::new(
                src,
                body.span.0..body.span.1,
                format!(
                    "this is not a shape: it does not depend on x, y or z (it is the constant {c})"
                ),
            )
            .with_help("a shape is an expression over x, y, z, e.g. `sphere(1)`")),
        }
    }

    /// Lowers `body` like [`Program::lower`], but also accepts an
    /// expression that does not depend on x, y or z (its function is one
    /// constant op).
    pub fn lower_any(&self, body: &Expr, src: usize) -> Result<Function, Diag> {
        let mut l = Lowerer::new(self);
        self.prewarm(&mut l);
        let ctx = Ctx::top(src);
        let v = l.lower(body, &ctx, IDENTITY)?;
        let root = l.node(v);
        Ok(l.finish(root))
    }

    /// Evaluates `e` (from source `src`) as a constant; `what` names the
    /// value in the error when it depends on x, y or z.
    pub fn constant(&self, e: &Expr, src: usize, what: &str) -> Result<f64, Diag> {
        let mut l = Lowerer::new(self);
        let ctx = Ctx::top(src);
        match l.lower(e, &ctx, IDENTITY)? {
            Val::Const(c) => Ok(c),
            Val::Node(_) => Err(Diag::new(
                src,
                e.span.0..e.span.1,
                format!("{what} must be a constant, but this depends on x, y or z"),
            )),
        }
    }

    /// Names a scene may use, for "did you mean" hints: (name, is a function).
    fn known_names(&self) -> impl Iterator<Item = (&str, bool)> {
        self.defs
            .values()
            .map(|d| (d.name.name.as_str(), d.params.is_some()))
            .chain(Builtin::ALL.iter().map(|b| (b.name(), true)))
            .chain(COORDS.iter().map(|(n, _)| (*n, false)))
    }
}

/// The parameterless `let`s named in the body of another parameterless
/// `let`, in source order, when there are more than [`CHAIN_PREWARM`].
fn let_chain<'a>(defs: &HashMap<&'a str, Def<'a>>) -> Vec<&'a str> {
    let mut read: Vec<&Def<'a>> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for def in defs.values().filter(|d| d.params.is_none()) {
        let mut stack = vec![def.body];
        while let Some(e) = stack.pop() {
            match &e.kind {
                ExprKind::Name(n) => {
                    if let Some(d) = defs.get(n.as_str())
                        && d.params.is_none()
                        && seen.insert(d.id)
                    {
                        read.push(d);
                    }
                }
                ExprKind::Num(_) => {}
                ExprKind::Call { args, .. } => stack.extend(args),
                ExprKind::Neg(a) => stack.push(a),
                ExprKind::Pow(a, b) => stack.extend([a.as_ref(), b.as_ref()]),
                ExprKind::Sum(ts) => stack.extend(ts.iter().map(|(_, t)| t)),
                ExprKind::Product(fs) => stack.extend(fs.iter().map(|(_, f)| f)),
            }
        }
    }
    if read.len() <= CHAIN_PREWARM {
        return Vec::new();
    }
    read.sort_by_key(|d| d.id);
    read.iter().map(|d| d.name.name.as_str()).collect()
}

fn check_definable(src: usize, name: &Ident, what: &str) -> Result<(), Diag> {
    let reserved = if coord(&name.name).is_some() {
        Some("a coordinate")
    } else if Builtin::from_name(&name.name).is_some() {
        Some("a built-in function")
    } else {
        None
    };
    match reserved {
        Some(kind) => Err(Diag::new(
            src,
            name.span.0..name.span.1,
            format!("cannot {what} `{}`: it is {kind}", name.name),
        )
        .with_help("choose another name")),
        None => Ok(()),
    }
}

/// Whether `root` reads x, y or z.
pub fn depends_on_coords(f: &Function) -> bool {
    let mut live = vec![false; f.ops.len()];
    if let Some(l) = live.get_mut(f.root.index()) {
        *l = true;
    }
    for i in (0..f.ops.len()).rev() {
        if !live[i] {
            continue;
        }
        if let Op::Var(_) = f.ops[i] {
            return true;
        }
        for a in f.ops[i].operands() {
            live[a.index()] = true;
        }
    }
    false
}
