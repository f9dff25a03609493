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
//! that depends on x, y or z is emitted through [`Builder`], whose
//! hash-consing merges repeated sub-expressions. No other simplification
//! happens here.
//!
//! Work is bounded: the parser caps the tree depth, calls may nest at most
//! [`MAX_CALL_DEPTH`] deep, and lowering gives up after [`MAX_STEPS`] steps,
//! so no input makes lowering overflow the stack or run away.

use crate::ir::semantics::{point_binary, point_powi, point_unary};
use crate::ir::{BinaryOp, Builder, Function, Op, UnaryOp, ValueId, Var};
use crate::lang::ast::{AddOp, Expr, ExprKind, Ident, Item, MulOp, Span};
use crate::lang::diag::Diag;
use std::collections::HashMap;
use std::rc::Rc;

/// How deeply definitions may call one another.
pub const MAX_CALL_DEPTH: usize = 128;

/// Lowering steps (expression nodes visited) allowed per object.
pub const MAX_STEPS: u64 = 5_000_000;

/// How deeply lowering may recurse (expression levels plus inlined
/// bodies); with the loader's stack this leaves a wide margin.
pub const MAX_RECURSION: usize = 16_384;

/// The functions built into the language, with their argument counts
/// (`None`: two or more).
pub const BUILTINS: &[(&str, Option<usize>)] = &[
    ("sqrt", Some(1)),
    ("abs", Some(1)),
    ("exp", Some(1)),
    ("ln", Some(1)),
    ("sin", Some(1)),
    ("cos", Some(1)),
    ("square", Some(1)),
    ("min", None),
    ("max", None),
    ("pow", Some(2)),
    ("atan2", Some(2)),
    ("union", None),
    ("intersect", None),
    ("difference", Some(2)),
    ("complement", Some(1)),
    ("blend", Some(3)),
    ("translate", Some(4)),
    ("scale", Some(2)),
    ("rotate_x", Some(2)),
    ("rotate_y", Some(2)),
    ("rotate_z", Some(2)),
];

/// The coordinate names.
const COORDS: [(&str, Var); 3] = [("x", Var::X), ("y", Var::Y), ("z", Var::Z)];

fn builtin_arity(name: &str) -> Option<Option<usize>> {
    BUILTINS.iter().find(|(n, _)| *n == name).map(|(_, a)| *a)
}

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
}

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
        Ok(Program { defs })
    }

    /// Lowers `body` (from source `src`) to a function of x, y, z.
    pub fn lower(&self, body: &Expr, src: usize) -> Result<Function, Diag> {
        let mut l = Lowerer::new(self);
        let ctx = Ctx { scope: None, src };
        let v = l.lower(body, &ctx, IDENTITY)?;
        match v {
            Val::Node(root) => Ok(l.b.finish(root)),
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
        let ctx = Ctx { scope: None, src };
        let v = l.lower(body, &ctx, IDENTITY)?;
        let root = l.node(v);
        Ok(l.b.finish(root))
    }

    /// Evaluates `e` (from source `src`) as a constant; `what` names the
    /// value in the error when it depends on x, y or z.
    pub fn constant(&self, e: &Expr, src: usize, what: &str) -> Result<f64, Diag> {
        let mut l = Lowerer::new(self);
        let ctx = Ctx { scope: None, src };
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
            .chain(BUILTINS.iter().map(|(n, _)| (*n, true)))
            .chain(COORDS.iter().map(|(n, _)| (*n, false)))
    }
}

fn check_definable(src: usize, name: &Ident, what: &str) -> Result<(), Diag> {
    let reserved = if coord(&name.name).is_some() {
        Some("a coordinate")
    } else if builtin_arity(&name.name).is_some() {
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

/// The closest known name to `name`, if any is close enough to be a likely
/// typo.
pub fn suggest<'n>(name: &str, candidates: impl Iterator<Item = &'n str>) -> Option<&'n str> {
    let limit = (name.chars().count() / 3).max(1);
    let mut best: Option<(usize, &str)> = None;
    for c in candidates {
        let d = strsim::damerau_levenshtein(name, c);
        let better = match best {
            None => true,
            Some((bd, bn)) => d < bd || (d == bd && c < bn),
        };
        if d <= limit && better {
            best = Some((d, c));
        }
    }
    best.map(|(_, c)| c)
}

/// A lowered value: a number known now, or an IR value.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Val {
    Const(f64),
    Node(ValueId),
}

/// What x, y or z currently stands for.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
enum Coord {
    /// The input coordinate itself (not emitted until used).
    Var(Var),
    /// A value computed by a transform.
    Node(ValueId),
}

type Env = [Coord; 3];

const IDENTITY: Env = [Coord::Var(Var::X), Coord::Var(Var::Y), Coord::Var(Var::Z)];

/// A parameter bound to the unevaluated argument of a call.
#[derive(Debug)]
struct Thunk<'a> {
    id: usize,
    expr: &'a Expr,
    ctx: Ctx<'a>,
    /// Definitions being expanded where the call was written: the argument
    /// belongs to the caller, so only these count for recursion.
    stack_len: usize,
}

/// The parameters visible in a function body.
#[derive(Debug)]
struct Scope<'a> {
    params: Vec<(&'a str, Rc<Thunk<'a>>)>,
}

/// Where an expression is lowered: its parameter scope and source.
#[derive(Clone, Debug)]
struct Ctx<'a> {
    scope: Option<Rc<Scope<'a>>>,
    src: usize,
}

impl<'a> Ctx<'a> {
    fn param(&self, name: &str) -> Option<Rc<Thunk<'a>>> {
        let scope = self.scope.as_ref()?;
        scope
            .params
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| t.clone())
    }

    fn diag(&self, span: (usize, usize), message: String) -> Diag {
        Diag::new(self.src, span.0..span.1, message)
    }
}

struct Lowerer<'p, 'a> {
    prog: &'p Program<'a>,
    b: Builder,
    /// Definitions being expanded, innermost last (for recursion errors).
    stack: Vec<&'p Def<'a>>,
    def_memo: HashMap<(usize, Env), Val>,
    thunk_memo: HashMap<(usize, Env), Val>,
    next_thunk: usize,
    steps: u64,
    recursion: usize,
}

fn plural(n: usize) -> &'static str {
    if n == 1 { "" } else { "s" }
}

impl<'p, 'a> Lowerer<'p, 'a> {
    fn new(prog: &'p Program<'a>) -> Lowerer<'p, 'a> {
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

    fn node(&mut self, v: Val) -> ValueId {
        match v {
            Val::Const(c) => self.b.constant(c),
            Val::Node(n) => n,
        }
    }

    fn coord(&mut self, c: Coord) -> ValueId {
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

    fn unary(
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

    fn binary(
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

    fn powi(&mut self, a: Val, n: i32, ctx: &Ctx<'a>, span: (usize, usize)) -> Result<Val, Diag> {
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

    fn lower(&mut self, e: &'a Expr, ctx: &Ctx<'a>, env: Env) -> Result<Val, Diag> {
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

    fn unknown(&self, name: &str, span: (usize, usize), ctx: &Ctx<'a>, want_fn: bool) -> Diag {
        let params: Vec<&str> = ctx
            .scope
            .as_ref()
            .map(|s| s.params.iter().map(|(n, _)| *n).collect())
            .unwrap_or_default();
        let known = self
            .prog
            .known_names()
            .filter(|(_, is_fn)| *is_fn == want_fn)
            .map(|(n, _)| n)
            .chain(params.iter().copied().filter(|_| !want_fn));
        let kind = if want_fn { "function" } else { "variable" };
        let d = ctx.diag(span, format!("unknown {kind} `{name}`"));
        match suggest(name, known) {
            Some(s) => d.with_help(format!("did you mean `{s}`?")),
            None => d,
        }
    }

    fn enter(&mut self, def: &'p Def<'a>, span: (usize, usize), ctx: &Ctx<'a>) -> Result<(), Diag> {
        if let Some(pos) = self.stack.iter().position(|d| d.id == def.id) {
            let mut chain: Vec<&str> = self.stack[pos..]
                .iter()
                .map(|d| d.name.name.as_str())
                .collect();
            chain.push(&def.name.name);
            let what = if chain.len() == 2 {
                "recursive"
            } else {
                "mutually recursive"
            };
            return Err(ctx
                .diag(span, format!("{what} use of `{}` ({})", def.name.name, chain.join(" -> ")))
                .with_secondary(def.src, def.name.span.0..def.name.span.1, "defined here")
                .with_help("definitions are inlined where they are used, so they cannot refer to themselves"));
        }
        if self.stack.len() >= MAX_CALL_DEPTH {
            return Err(ctx.diag(
                span,
                format!("definitions nested too deeply (more than {MAX_CALL_DEPTH} calls inside one another)"),
            ));
        }
        self.stack.push(def);
        Ok(())
    }

    fn name(
        &mut self,
        n: &str,
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        if let Some(t) = ctx.param(n) {
            if let Some(v) = self.thunk_memo.get(&(t.id, env)) {
                return Ok(*v);
            }
            let inner = self.stack.split_off(t.stack_len.min(self.stack.len()));
            let v = self.lower(t.expr, &t.ctx, env);
            self.stack.extend(inner);
            let v = v?;
            self.thunk_memo.insert((t.id, env), v);
            return Ok(v);
        }
        if let Some(v) = coord(n) {
            return Ok(Val::Node(self.coord(env[v.index()])));
        }
        let prog = self.prog;
        if let Some(def) = prog.defs.get(n) {
            if def.params.is_some() {
                return Err(ctx
                    .diag(span, format!("`{n}` is a function, not a value"))
                    .with_help(format!("call it with arguments: `{n}(...)`")));
            }
            return self.expand(def, &[], span, ctx, env);
        }
        if builtin_arity(n).is_some() {
            return Err(ctx
                .diag(span, format!("`{n}` is a built-in function, not a value"))
                .with_help(format!("call it with arguments: `{n}(...)`")));
        }
        Err(self.unknown(n, span, ctx, false))
    }

    /// Inlines a `let` or `fn` with the given (unevaluated) arguments.
    fn expand(
        &mut self,
        def: &'p Def<'a>,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let stack_len = self.stack.len();
        self.enter(def, span, ctx)?;
        let memo_key = (def.id, env);
        let result = if args.is_empty() {
            if let Some(v) = self.def_memo.get(&memo_key) {
                Ok(*v)
            } else {
                let body_ctx = Ctx {
                    scope: None,
                    src: def.src,
                };
                let v = self.lower(def.body, &body_ctx, env);
                if let Ok(v) = v {
                    self.def_memo.insert(memo_key, v);
                }
                v
            }
        } else {
            let params = def.params.unwrap_or(&[]);
            let mut scope = Scope {
                params: Vec::with_capacity(args.len()),
            };
            for (p, a) in params.iter().zip(args) {
                let id = self.next_thunk;
                self.next_thunk += 1;
                scope.params.push((
                    p.name.as_str(),
                    Rc::new(Thunk {
                        id,
                        expr: a,
                        ctx: ctx.clone(),
                        stack_len,
                    }),
                ));
            }
            let body_ctx = Ctx {
                scope: Some(Rc::new(scope)),
                src: def.src,
            };
            self.lower(def.body, &body_ctx, env)
        };
        self.stack.pop();
        result
    }

    fn args(&mut self, args: &'a [Expr], ctx: &Ctx<'a>, env: Env) -> Result<Vec<Val>, Diag> {
        args.iter().map(|a| self.lower(a, ctx, env)).collect()
    }

    fn call(
        &mut self,
        name: &str,
        name_span: (usize, usize),
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        if ctx.param(name).is_some() {
            return Err(ctx.diag(
                name_span,
                format!("`{name}` is a parameter, not a function"),
            ));
        }
        if coord(name).is_some() {
            return Err(ctx
                .diag(
                    name_span,
                    format!("`{name}` is a coordinate, not a function"),
                )
                .with_help(format!("write `{name} * (...)` to multiply")));
        }
        if let Some(arity) = builtin_arity(name) {
            let ok = match arity {
                Some(n) => args.len() == n,
                None => args.len() >= 2,
            };
            if !ok {
                let expected = match arity {
                    Some(n) => format!("{n} argument{}", plural(n)),
                    None => "at least 2 arguments".to_string(),
                };
                return Err(ctx.diag(
                    span,
                    format!(
                        "`{name}` takes {expected}, but {} {} given",
                        args.len(),
                        if args.len() == 1 { "was" } else { "were" }
                    ),
                ));
            }
            return self.builtin(name, args, span, ctx, env);
        }
        let prog = self.prog;
        if let Some(def) = prog.defs.get(name) {
            let Some(params) = def.params else {
                return Err(ctx
                    .diag(name_span, format!("`{name}` is a value, not a function"))
                    .with_help(format!("use it without arguments: `{name}`")));
            };
            if params.len() != args.len() {
                let names: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
                return Err(ctx
                    .diag(
                        span,
                        format!(
                            "`{name}` takes {} argument{}, but {} {} given",
                            params.len(),
                            plural(params.len()),
                            args.len(),
                            if args.len() == 1 { "was" } else { "were" }
                        ),
                    )
                    .with_secondary(def.src, def.name.span.0..def.name.span.1, "defined here")
                    .with_help(format!("call it as `{name}({})`", names.join(", "))));
            }
            return self.expand(def, args, span, ctx, env);
        }
        Err(self.unknown(name, name_span, ctx, true))
    }

    fn constant_arg(
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

    fn fold_all(
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

    /// `lhs = c1*a + c2*b` for constant coefficients, skipping zero terms
    /// and unit factors (rotations by multiples of 90° stay exact).
    fn lin(&mut self, c1: f64, a: ValueId, c2: f64, b: ValueId) -> ValueId {
        let term = |l: &mut Self, c: f64, v: ValueId| -> Option<ValueId> {
            if c == 0.0 {
                None
            } else if c == 1.0 {
                Some(v)
            } else {
                let k = l.b.constant(c);
                Some(l.b.binary(BinaryOp::Mul, k, v))
            }
        };
        match (term(self, c1, a), term(self, c2, b)) {
            (Some(p), Some(q)) => self.b.binary(BinaryOp::Add, p, q),
            (Some(p), None) | (None, Some(p)) => p,
            (None, None) => self.b.constant(0.0),
        }
    }

    fn builtin(
        &mut self,
        name: &str,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let unary = |n: &str| match n {
            "sqrt" => Some(UnaryOp::Sqrt),
            "abs" => Some(UnaryOp::Abs),
            "exp" => Some(UnaryOp::Exp),
            "ln" => Some(UnaryOp::Ln),
            "sin" => Some(UnaryOp::Sin),
            "cos" => Some(UnaryOp::Cos),
            "square" => Some(UnaryOp::Square),
            _ => None,
        };
        if let Some(op) = unary(name) {
            let a = self.lower(&args[0], ctx, env)?;
            return self.unary(op, a, ctx, span);
        }
        match name {
            "min" | "union" => {
                let vals = self.args(args, ctx, env)?;
                self.fold_all(BinaryOp::Min, vals, ctx, span)
            }
            "max" | "intersect" => {
                let vals = self.args(args, ctx, env)?;
                self.fold_all(BinaryOp::Max, vals, ctx, span)
            }
            "atan2" => {
                let a = self.lower(&args[0], ctx, env)?;
                let b = self.lower(&args[1], ctx, env)?;
                self.binary(BinaryOp::Atan2, a, b, ctx, span)
            }
            "pow" => {
                let a = self.lower(&args[0], ctx, env)?;
                let b = self.lower(&args[1], ctx, env)?;
                match b {
                    Val::Const(c) if int_exponent(c).is_some() => {
                        let k = int_exponent(c).unwrap_or(1);
                        self.powi(a, k, ctx, span)
                    }
                    _ => self.binary(BinaryOp::Pow, a, b, ctx, span),
                }
            }
            "difference" => {
                let a = self.lower(&args[0], ctx, env)?;
                let b = self.lower(&args[1], ctx, env)?;
                let nb = self.unary(UnaryOp::Neg, b, ctx, span)?;
                self.binary(BinaryOp::Max, a, nb, ctx, span)
            }
            "complement" => {
                let a = self.lower(&args[0], ctx, env)?;
                self.unary(UnaryOp::Neg, a, ctx, span)
            }
            "blend" => {
                let k = self.constant_arg(&args[2], ctx, env, "the blend radius")?;
                if !(k > 0.0 && k.is_finite()) {
                    return Err(ctx
                        .diag(
                            args[2].span,
                            format!("the blend radius must be positive, but it is {k}"),
                        )
                        .with_help("use `union(a, b)` for a sharp join"));
                }
                let a = self.lower(&args[0], ctx, env)?;
                let b = self.lower(&args[1], ctx, env)?;
                // h = max(k - |a - b|, 0) / k;  min(a, b) - h² k/4
                let d = self.binary(BinaryOp::Sub, a, b, ctx, span)?;
                let ad = self.unary(UnaryOp::Abs, d, ctx, span)?;
                let t = self.binary(BinaryOp::Sub, Val::Const(k), ad, ctx, span)?;
                let m = self.binary(BinaryOp::Max, t, Val::Const(0.0), ctx, span)?;
                let h = self.binary(BinaryOp::Div, m, Val::Const(k), ctx, span)?;
                let h2 = self.unary(UnaryOp::Square, h, ctx, span)?;
                let c = self.binary(BinaryOp::Mul, h2, Val::Const(k / 4.0), ctx, span)?;
                let mn = self.binary(BinaryOp::Min, a, b, ctx, span)?;
                self.binary(BinaryOp::Sub, mn, c, ctx, span)
            }
            "translate" => {
                let mut new_env = env;
                for (i, slot) in new_env.iter_mut().enumerate() {
                    let d = self.lower(&args[i + 1], ctx, env)?;
                    let c = self.coord(env[i]);
                    let d = self.node(d);
                    *slot = Coord::Node(self.b.binary(BinaryOp::Sub, c, d));
                }
                self.lower(&args[0], ctx, new_env)
            }
            "scale" => {
                let k = self.constant_arg(&args[1], ctx, env, "the scale factor")?;
                if !(k > 0.0 && k.is_finite()) {
                    return Err(ctx
                        .diag(
                            args[1].span,
                            format!("the scale factor must be positive, but it is {k}"),
                        )
                        .with_help("mirroring is not supported; scale by a positive number"));
                }
                let mut new_env = env;
                for slot in new_env.iter_mut() {
                    let c = self.coord(*slot);
                    let kk = self.b.constant(k);
                    *slot = Coord::Node(self.b.binary(BinaryOp::Div, c, kk));
                }
                let s = self.lower(&args[0], ctx, new_env)?;
                self.binary(BinaryOp::Mul, Val::Const(k), s, ctx, span)
            }
            "rotate_x" | "rotate_y" | "rotate_z" => {
                let deg = self.constant_arg(&args[1], ctx, env, "the rotation angle")?;
                if !deg.is_finite() {
                    return Err(ctx.diag(args[1].span, "the rotation angle must be finite".into()));
                }
                let (c, s) = cos_sin_deg(deg);
                // Evaluate at the point rotated by -deg: for a rotation in
                // the (u, v) plane, u' = c u + s v and v' = -s u + c v.
                let (iu, iv) = match name {
                    "rotate_x" => (1, 2),
                    "rotate_y" => (2, 0),
                    _ => (0, 1),
                };
                let u = self.coord(env[iu]);
                let v = self.coord(env[iv]);
                let nu = self.lin(c, u, s, v);
                let nv = self.lin(-s, u, c, v);
                let mut new_env = env;
                new_env[iu] = Coord::Node(nu);
                new_env[iv] = Coord::Node(nv);
                self.lower(&args[0], ctx, new_env)
            }
            _ => Err(ctx.diag(span, format!("`{name}` is not implemented"))),
        }
    }
}

/// `c` as an `i32` exponent, when it is an integer in range.
fn int_exponent(c: f64) -> Option<i32> {
    if c.fract() == 0.0 && c.abs() <= f64::from(i32::MAX) {
        Some(c as i32)
    } else {
        None
    }
}

/// cos and sin of an angle in degrees, exact at multiples of 90°.
fn cos_sin_deg(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    if r == 0.0 {
        (1.0, 0.0)
    } else if r == 90.0 {
        (0.0, 1.0)
    } else if r == 180.0 {
        (-1.0, 0.0)
    } else if r == 270.0 {
        (0.0, -1.0)
    } else {
        let t = deg.to_radians();
        (t.cos(), t.sin())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggestions_only_for_close_names() {
        let names = ["sphere", "box", "torus"];
        assert_eq!(suggest("sphre", names.iter().copied()), Some("sphere"));
        assert_eq!(suggest("bx", names.iter().copied()), Some("box"));
        assert_eq!(suggest("cylinder", names.iter().copied()), None);
    }

    #[test]
    fn right_angles_are_exact() {
        assert_eq!(cos_sin_deg(90.0), (0.0, 1.0));
        assert_eq!(cos_sin_deg(-90.0), (0.0, -1.0));
        assert_eq!(cos_sin_deg(540.0), (-1.0, 0.0));
        let (c, s) = cos_sin_deg(30.0);
        assert!((c - 0.75f64.sqrt()).abs() < 1e-15 && (s - 0.5).abs() < 1e-15);
    }

    #[test]
    fn integer_exponents() {
        assert_eq!(int_exponent(3.0), Some(3));
        assert_eq!(int_exponent(-2.0), Some(-2));
        assert_eq!(int_exponent(0.5), None);
        assert_eq!(int_exponent(1e10), None);
    }
}
