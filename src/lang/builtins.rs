//! The functions built into the language.
//!
//! [`Builtin::spec`] gives each builtin its name and the form it lowers
//! to, in one line per builtin; its arity follows from the form, so the
//! name lookup, the arity check, the "did you mean" hints, the reserved
//! names and the lowering all read the same table and cannot drift apart.

use crate::ir::{BinaryOp, UnaryOp};
use crate::lang::ast::Expr;
use crate::lang::diag::Diag;
use crate::lang::lower::{Ctx, Env, Lowerer, Val, int_exponent};
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
    /// `tan(a)`
    Tan,
    /// `asin(a)`
    Asin,
    /// `acos(a)`
    Acos,
    /// `atan(a)`
    Atan,
    /// `sinh(a)`
    Sinh,
    /// `cosh(a)`
    Cosh,
    /// `tanh(a)`
    Tanh,
    /// `floor(a)`
    Floor,
    /// `ceil(a)`
    Ceil,
    /// `round(a)`: halves away from zero.
    Round,
    /// `fract(a)` = a - floor(a).
    Fract,
    /// `sign(a)`
    Sign,
    /// `mod(a, b)`: the least non-negative remainder.
    Mod,
    /// `clamp(a, lo, hi)`
    Clamp,
    /// `mix(a, b, t)` = a + (b - a)·t.
    Mix,
    /// `smoothstep(e0, e1, a)`
    Smoothstep,
    /// `blend_intersect(a, b, k)`: a smooth intersection.
    BlendIntersect,
    /// `blend_difference(a, b, k)`: a smooth difference.
    BlendDifference,
    /// `shell(s, t)` = |s| - t.
    Shell,
    /// `offset(s, r)` = s - r.
    Offset,
    /// `mirror_x(s)`: s at (|x|, y, z).
    MirrorX,
    /// `mirror_y(s)`
    MirrorY,
    /// `mirror_z(s)`
    MirrorZ,
    /// `repeat(s, px, py, pz)`: infinite domain repetition.
    Repeat,
    /// `rotate(s, ax, ay, az, degrees)`: about any axis through the origin.
    Rotate,
    /// `scale_xyz(s, kx, ky, kz)`: non-uniform scaling.
    ScaleXyz,
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
    /// `a - floor(a)`, as `mod(a, 1)` (the same bits, a tighter interval).
    Fract,
    /// `min(max(a, lo), hi)`.
    Clamp,
    /// `a + (b - a)·t`.
    Mix,
    /// The cubic Hermite step between two edges.
    Smoothstep,
    /// A smooth maximum of a and b (of a and -b when the flag is set).
    BlendMax(bool),
    /// `|s| - t`.
    Shell,
    /// The shape evaluated with this coordinate replaced by its magnitude.
    Mirror(usize),
    /// The shape evaluated in the cell of a periodic lattice.
    Repeat,
    /// The shape evaluated at the point rotated back about an axis.
    RotateAxis,
    /// `min(k)·s(x/kx, y/ky, z/kz)`.
    ScaleXyz,
}

impl Form {
    fn arity(self) -> Arity {
        match self {
            Form::Unary(_) | Form::Fract | Form::Mirror(_) => Arity::Exactly(1),
            Form::Binary(_)
            | Form::Pow
            | Form::Difference
            | Form::Scale
            | Form::Rotate(..)
            | Form::Shell => Arity::Exactly(2),
            Form::Fold(_) => Arity::AtLeastTwo,
            Form::Blend | Form::BlendMax(_) | Form::Clamp | Form::Mix | Form::Smoothstep => {
                Arity::Exactly(3)
            }
            Form::Translate | Form::Repeat | Form::ScaleXyz => Arity::Exactly(4),
            Form::RotateAxis => Arity::Exactly(5),
        }
    }
}

impl Builtin {
    /// Every builtin.
    pub const ALL: [Builtin; 47] = [
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
        Builtin::Tan,
        Builtin::Asin,
        Builtin::Acos,
        Builtin::Atan,
        Builtin::Sinh,
        Builtin::Cosh,
        Builtin::Tanh,
        Builtin::Floor,
        Builtin::Ceil,
        Builtin::Round,
        Builtin::Fract,
        Builtin::Sign,
        Builtin::Mod,
        Builtin::Clamp,
        Builtin::Mix,
        Builtin::Smoothstep,
        Builtin::BlendIntersect,
        Builtin::BlendDifference,
        Builtin::Shell,
        Builtin::Offset,
        Builtin::MirrorX,
        Builtin::MirrorY,
        Builtin::MirrorZ,
        Builtin::Repeat,
        Builtin::Rotate,
        Builtin::ScaleXyz,
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
            B::Tan => ("tan", Form::Unary(UnaryOp::Tan)),
            B::Asin => ("asin", Form::Unary(UnaryOp::Asin)),
            B::Acos => ("acos", Form::Unary(UnaryOp::Acos)),
            B::Atan => ("atan", Form::Unary(UnaryOp::Atan)),
            B::Sinh => ("sinh", Form::Unary(UnaryOp::Sinh)),
            B::Cosh => ("cosh", Form::Unary(UnaryOp::Cosh)),
            B::Tanh => ("tanh", Form::Unary(UnaryOp::Tanh)),
            B::Floor => ("floor", Form::Unary(UnaryOp::Floor)),
            B::Ceil => ("ceil", Form::Unary(UnaryOp::Ceil)),
            B::Round => ("round", Form::Unary(UnaryOp::Round)),
            B::Fract => ("fract", Form::Fract),
            B::Sign => ("sign", Form::Unary(UnaryOp::Sign)),
            B::Mod => ("mod", Form::Binary(BinaryOp::Mod)),
            B::Clamp => ("clamp", Form::Clamp),
            B::Mix => ("mix", Form::Mix),
            B::Smoothstep => ("smoothstep", Form::Smoothstep),
            B::BlendIntersect => ("blend_intersect", Form::BlendMax(false)),
            B::BlendDifference => ("blend_difference", Form::BlendMax(true)),
            B::Shell => ("shell", Form::Shell),
            B::Offset => ("offset", Form::Binary(BinaryOp::Sub)),
            B::MirrorX => ("mirror_x", Form::Mirror(0)),
            B::MirrorY => ("mirror_y", Form::Mirror(1)),
            B::MirrorZ => ("mirror_z", Form::Mirror(2)),
            B::Repeat => ("repeat", Form::Repeat),
            B::Rotate => ("rotate", Form::RotateAxis),
            B::ScaleXyz => ("scale_xyz", Form::ScaleXyz),
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
            Form::Fract => {
                let a = l.lower(&args[0], ctx, env)?;
                l.binary(BinaryOp::Mod, a, Val::Const(1.0), ctx, span)
            }
            Form::Clamp => l.clamp(args, span, ctx, env),
            Form::Mix => l.mix(args, span, ctx, env),
            Form::Smoothstep => l.smoothstep(args, span, ctx, env),
            Form::BlendMax(negate_b) => l.blend_max(negate_b, args, span, ctx, env),
            Form::Shell => {
                let s = l.lower(&args[0], ctx, env)?;
                let t = l.lower(&args[1], ctx, env)?;
                let a = l.unary(UnaryOp::Abs, s, ctx, span)?;
                l.binary(BinaryOp::Sub, a, t, ctx, span)
            }
            Form::Mirror(axis) => l.mirror(axis, args, ctx, env),
            Form::Repeat => l.repeat(args, ctx, env),
            Form::RotateAxis => l.rotate_axis(args, ctx, env),
            Form::ScaleXyz => l.scale_xyz(args, span, ctx, env),
        }
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
}
