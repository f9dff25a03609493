//! Names and calls: parameters, coordinates, definitions (inlined at each
//! use, with recursion and depth checks) and built-in functions.

use super::expr::{Scope, Thunk};
use super::{Ctx, Def, Env, Lowerer, MAX_CALL_DEPTH, Val, coord};
use crate::lang::ast::Expr;
use crate::lang::builtins::{Arity, Builtin};
use crate::lang::diag::{Diag, suggest};
use std::rc::Rc;

/// "`name` takes 2 arguments, but 1 was given".
fn takes(name: &str, expected: Arity, given: usize) -> String {
    let verb = if given == 1 { "was" } else { "were" };
    format!("`{name}` takes {expected}, but {given} {verb} given")
}

impl<'p, 'a> Lowerer<'p, 'a> {
    /// "unknown function `f`", with the closest known name as a hint.
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

    /// Pushes `def` on the expansion stack, unless that recurses or nests
    /// too deeply.
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

    /// Lowers a name: a parameter, a coordinate or a `let`.
    pub(super) fn name(
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
        if Builtin::from_name(n).is_some() {
            return Err(ctx
                .diag(span, format!("`{n}` is a built-in function, not a value"))
                .with_help(format!("call it with arguments: `{n}(...)`")));
        }
        Err(self.unknown(n, span, ctx, false))
    }

    /// Inlines a `let` or `fn` with the given (unevaluated) arguments.
    pub(super) fn expand(
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
                let body_ctx = Ctx::top(def.src);
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

    /// Lowers `name(args)`.
    pub(super) fn call(
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
        if let Some(builtin) = Builtin::from_name(name) {
            if !builtin.arity().accepts(args.len()) {
                return Err(ctx.diag(span, takes(name, builtin.arity(), args.len())));
            }
            return builtin.lower(self, args, span, ctx, env);
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
                    .diag(span, takes(name, Arity::Exactly(params.len()), args.len()))
                    .with_secondary(def.src, def.name.span.0..def.name.span.1, "defined here")
                    .with_help(format!("call it as `{name}({})`", names.join(", "))));
            }
            return self.expand(def, args, span, ctx, env);
        }
        Err(self.unknown(name, name_span, ctx, true))
    }
}
