//! The functions built into the language.
//!
//! [`Builtin::spec`] gives each builtin its name and the form it lowers
//! to, in one line per builtin; its arity follows from the form, so the
//! name lookup, the arity check, the "did you mean" hints, the reserved
//! names and the lowering all read the same table and cannot drift apart.

use crate::ir::{BinaryOp, UnaryOp, ValueId};
use crate::lang::ast::Expr;
use crate::lang::diag::Diag;
use crate::lang::lower::{Coord, Ctx, Env, Lowerer, Val, int_exponent};
use std::fmt;

/// How many arguments a builtin (or a definition) takes.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Arity {
    /// Exactly this many.
    Exactly(usize),
    /// Two or more (the n-ary folds).
    AtLeastTwo,
}

impl Arity {
    /// Whether a call with `n` arguments fits.
    pub fn accepts(self, n: usize) -> bool {
        match self {
            Arity::Exactly(k) => n == k,
            Arity::AtLeastTwo => n >= 2,
        }
    }
}

/// As the diagnostics say it: "1 argument", "at least 2 arguments".
impl fmt::Display for Arity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Arity::Exactly(1) => f.write_str("1 argument"),
            Arity::Exactly(n) => write!(f, "{n} arguments"),
            Arity::AtLeastTwo => f.write_str("at least 2 arguments"),
        }
    }
}

/// A function built into the language.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Builtin {
    /// `sqrt(a)`
    Sqrt,
    /// `abs(a)`
    Abs,
    /// `exp(a)`
    Exp,
    /// `ln(a)`
    Ln,
    /// `sin(a)`
    Sin,
    /// `cos(a)`
    Cos,
    /// `square(a)`
    Square,
    /// `min(a, b, …)`
    Min,
    /// `max(a, b, …)`
    Max,
    /// `pow(a, b)`
    Pow,
    /// `atan2(a, b)`
    Atan2,
    /// `union(a, b, …)`: the minimum.
    Union,
    /// `intersect(a, b, …)`: the maximum.
    Intersect,
    /// `difference(a, b)`: a without b.
    Difference,
    /// `complement(a)`: inside and outside swapped.
    Complement,
    /// `blend(a, b, k)`: a union with a smooth join of radius k.
    Blend,
    /// `translate(s, dx, dy, dz)`
    Translate,
    /// `scale(s, k)`
    Scale,
    /// `rotate_x(s, degrees)`
    RotateX,
    /// `rotate_y(s, degrees)`
    RotateY,
    /// `rotate_z(s, degrees)`
    RotateZ,
}

/// What a builtin lowers to.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Form {
    /// `op a`.
    Unary(UnaryOp),
    /// `a op b`.
    Binary(BinaryOp),
    /// `a op b op c …`, folded left over two or more arguments.
    Fold(BinaryOp),
    /// `a^b`: an integer power when b is a constant integer.
    Pow,
    /// `max(a, -b)`.
    Difference,
    /// A smooth minimum of a and b with a constant radius.
    Blend,
    /// The shape evaluated at the point moved back by (dx, dy, dz).
    Translate,
    /// `k * s(p / k)` for a constant k > 0.
    Scale,
    /// The shape evaluated at the point rotated back, in the plane of the
    /// coordinates with these indices.
    Rotate(usize, usize),
}

impl Form {
    fn arity(self) -> Arity {
        match self {
            Form::Unary(_) => Arity::Exactly(1),
            Form::Binary(_) | Form::Pow | Form::Difference | Form::Scale | Form::Rotate(..) => {
                Arity::Exactly(2)
            }
            Form::Fold(_) => Arity::AtLeastTwo,
            Form::Blend => Arity::Exactly(3),
            Form::Translate => Arity::Exactly(4),
        }
    }
}

impl Builtin {
    /// Every builtin.
    pub const ALL: [Builtin; 21] = [
        Builtin::Sqrt,
        Builtin::Abs,
        Builtin::Exp,
        Builtin::Ln,
        Builtin::Sin,
        Builtin::Cos,
        Builtin::Square,
        Builtin::Min,
        Builtin::Max,
        Builtin::Pow,
        Builtin::Atan2,
        Builtin::Union,
        Builtin::Intersect,
        Builtin::Difference,
        Builtin::Complement,
        Builtin::Blend,
        Builtin::Translate,
        Builtin::Scale,
        Builtin::RotateX,
        Builtin::RotateY,
        Builtin::RotateZ,
    ];

    /// The builtin's name in the language and the form it lowers to.
    fn spec(self) -> (&'static str, Form) {
        use Builtin as B;
        match self {
            B::Sqrt => ("sqrt", Form::Unary(UnaryOp::Sqrt)),
            B::Abs => ("abs", Form::Unary(UnaryOp::Abs)),
            B::Exp => ("exp", Form::Unary(UnaryOp::Exp)),
            B::Ln => ("ln", Form::Unary(UnaryOp::Ln)),
            B::Sin => ("sin", Form::Unary(UnaryOp::Sin)),
            B::Cos => ("cos", Form::Unary(UnaryOp::Cos)),
            B::Square => ("square", Form::Unary(UnaryOp::Square)),
            B::Min => ("min", Form::Fold(BinaryOp::Min)),
            B::Max => ("max", Form::Fold(BinaryOp::Max)),
            B::Pow => ("pow", Form::Pow),
            B::Atan2 => ("atan2", Form::Binary(BinaryOp::Atan2)),
            B::Union => ("union", Form::Fold(BinaryOp::Min)),
            B::Intersect => ("intersect", Form::Fold(BinaryOp::Max)),
            B::Difference => ("difference", Form::Difference),
            B::Complement => ("complement", Form::Unary(UnaryOp::Neg)),
            B::Blend => ("blend", Form::Blend),
            B::Translate => ("translate", Form::Translate),
            B::Scale => ("scale", Form::Scale),
            // The indices of the two coordinates each rotation mixes.
            B::RotateX => ("rotate_x", Form::Rotate(1, 2)),
            B::RotateY => ("rotate_y", Form::Rotate(2, 0)),
            B::RotateZ => ("rotate_z", Form::Rotate(0, 1)),
        }
    }

    /// The builtin called `name`, if any.
    pub fn from_name(name: &str) -> Option<Builtin> {
        Builtin::ALL.into_iter().find(|b| b.name() == name)
    }

    /// Its name in the language.
    pub fn name(self) -> &'static str {
        self.spec().0
    }

    /// How many arguments it takes.
    pub fn arity(self) -> Arity {
        self.spec().1.arity()
    }

    /// Lowers a call whose argument count [`Builtin::arity`] accepts.
    pub(in crate::lang) fn lower<'a>(
        self,
        l: &mut Lowerer<'_, 'a>,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        match self.spec().1 {
            Form::Unary(op) => {
                let a = l.lower(&args[0], ctx, env)?;
                l.unary(op, a, ctx, span)
            }
            Form::Binary(op) => {
                let a = l.lower(&args[0], ctx, env)?;
                let b = l.lower(&args[1], ctx, env)?;
                l.binary(op, a, b, ctx, span)
            }
            Form::Fold(op) => {
                let vals = l.args(args, ctx, env)?;
                l.fold_all(op, vals, ctx, span)
            }
            Form::Pow => {
                let a = l.lower(&args[0], ctx, env)?;
                let b = l.lower(&args[1], ctx, env)?;
                match b {
                    Val::Const(c) if int_exponent(c).is_some() => {
                        let k = int_exponent(c).unwrap_or(1);
                        l.powi(a, k, ctx, span)
                    }
                    _ => l.binary(BinaryOp::Pow, a, b, ctx, span),
                }
            }
            Form::Difference => {
                let a = l.lower(&args[0], ctx, env)?;
                let b = l.lower(&args[1], ctx, env)?;
                let nb = l.unary(UnaryOp::Neg, b, ctx, span)?;
                l.binary(BinaryOp::Max, a, nb, ctx, span)
            }
            Form::Blend => l.blend(args, span, ctx, env),
            Form::Translate => l.translate(args, ctx, env),
            Form::Scale => l.scale(args, span, ctx, env),
            Form::Rotate(iu, iv) => l.rotate(iu, iv, args, ctx, env),
        }
    }
}

impl<'a> Lowerer<'_, 'a> {
    /// A constant argument that must be positive and finite (`what` names
    /// it in the error, `help` says what to do instead).
    fn positive_arg(
        &mut self,
        arg: &'a Expr,
        (ctx, env): (&Ctx<'a>, Env),
        what: &str,
        help: &str,
    ) -> Result<f64, Diag> {
        let k = self.constant_arg(arg, ctx, env, what)?;
        if !(k > 0.0 && k.is_finite()) {
            return Err(ctx
                .diag(arg.span, format!("{what} must be positive, but it is {k}"))
                .with_help(help));
        }
        Ok(k)
    }

    /// `blend(a, b, k)`.
    fn blend(
        &mut self,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let k = self.positive_arg(
            &args[2],
            (ctx, env),
            "the blend radius",
            "use `union(a, b)` for a sharp join",
        )?;
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

    /// `translate(s, dx, dy, dz)`.
    fn translate(&mut self, args: &'a [Expr], ctx: &Ctx<'a>, env: Env) -> Result<Val, Diag> {
        let mut new_env = env;
        for (i, slot) in new_env.iter_mut().enumerate() {
            let d = self.lower(&args[i + 1], ctx, env)?;
            let c = self.coord(env[i]);
            let d = self.node(d);
            *slot = Coord::Node(self.b.binary(BinaryOp::Sub, c, d));
        }
        self.lower(&args[0], ctx, new_env)
    }

    /// `scale(s, k)`.
    fn scale(
        &mut self,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let k = self.positive_arg(
            &args[1],
            (ctx, env),
            "the scale factor",
            "mirroring is not supported; scale by a positive number",
        )?;
        let mut new_env = env;
        for slot in new_env.iter_mut() {
            let c = self.coord(*slot);
            let kk = self.b.constant(k);
            *slot = Coord::Node(self.b.binary(BinaryOp::Div, c, kk));
        }
        let s = self.lower(&args[0], ctx, new_env)?;
        self.binary(BinaryOp::Mul, Val::Const(k), s, ctx, span)
    }

    /// `rotate_*(s, degrees)`, in the plane of coordinates `iu` and `iv`.
    fn rotate(
        &mut self,
        iu: usize,
        iv: usize,
        args: &'a [Expr],
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let deg = self.constant_arg(&args[1], ctx, env, "the rotation angle")?;
        if !deg.is_finite() {
            return Err(ctx.diag(args[1].span, "the rotation angle must be finite".into()));
        }
        let (c, s) = cos_sin_deg(deg);
        // Evaluate at the point rotated by -deg: for a rotation in the
        // (u, v) plane, u' = c u + s v and v' = -s u + c v.
        let u = self.coord(env[iu]);
        let v = self.coord(env[iv]);
        let nu = self.lin(c, u, s, v);
        let nv = self.lin(-s, u, c, v);
        let mut new_env = env;
        new_env[iu] = Coord::Node(nu);
        new_env[iv] = Coord::Node(nv);
        self.lower(&args[0], ctx, new_env)
    }

    /// `c1*a + c2*b` for constant coefficients, skipping zero terms and
    /// unit factors (rotations by multiples of 90° stay exact).
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_distinct_and_found() {
        for (i, b) in Builtin::ALL.iter().enumerate() {
            assert_eq!(Builtin::from_name(b.name()), Some(*b));
            assert!(Builtin::ALL[..i].iter().all(|a| a.name() != b.name()));
        }
        assert_eq!(Builtin::from_name("sphere"), None);
    }

    #[test]
    fn arities_read_as_in_diagnostics() {
        assert_eq!(Builtin::Sqrt.arity().to_string(), "1 argument");
        assert_eq!(Builtin::Translate.arity().to_string(), "4 arguments");
        assert_eq!(Builtin::Union.arity().to_string(), "at least 2 arguments");
        assert!(Builtin::Min.arity().accepts(5) && !Builtin::Min.arity().accepts(1));
        assert_eq!(Arity::Exactly(0).to_string(), "0 arguments");
    }

    #[test]
    fn right_angles_are_exact() {
        assert_eq!(cos_sin_deg(90.0), (0.0, 1.0));
        assert_eq!(cos_sin_deg(-90.0), (0.0, -1.0));
        assert_eq!(cos_sin_deg(540.0), (-1.0, 0.0));
        let (c, s) = cos_sin_deg(30.0);
        assert!((c - 0.75f64.sqrt()).abs() < 1e-15 && (s - 0.5).abs() < 1e-15);
    }
}
