//! Lowering of the shape operators and functions that are more than one
//! op: smooth joins, transforms (coordinates replaced before the shape is
//! lowered), and the composed functions (`clamp`, `mix`, `smoothstep`).

use crate::ir::{BinaryOp, UnaryOp, ValueId};
use crate::lang::ast::Expr;
use crate::lang::diag::Diag;
use crate::lang::lower::{Coord, Ctx, Env, Lowerer, Val};

impl<'a> Lowerer<'_, 'a> {
    /// A constant argument that must be positive and finite (`what` names
    /// it in the error, `help` says what to do instead).
    pub(in crate::lang) fn positive_arg(
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
    pub(in crate::lang) fn blend(
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
        let c = self.blend_term(a, b, k, ctx, span)?;
        let mn = self.binary(BinaryOp::Min, a, b, ctx, span)?;
        self.binary(BinaryOp::Sub, mn, c, ctx, span)
    }

    /// The polynomial term of the smooth joins, `h²·k/4` with
    /// `h = max(k - |a - b|, 0) / k`: `blend` subtracts it from the
    /// minimum, `blend_intersect` adds it to the maximum.
    fn blend_term(
        &mut self,
        a: Val,
        b: Val,
        k: f64,
        ctx: &Ctx<'a>,
        span: (usize, usize),
    ) -> Result<Val, Diag> {
        let d = self.binary(BinaryOp::Sub, a, b, ctx, span)?;
        let ad = self.unary(UnaryOp::Abs, d, ctx, span)?;
        let t = self.binary(BinaryOp::Sub, Val::Const(k), ad, ctx, span)?;
        let m = self.binary(BinaryOp::Max, t, Val::Const(0.0), ctx, span)?;
        let h = self.binary(BinaryOp::Div, m, Val::Const(k), ctx, span)?;
        let h2 = self.unary(UnaryOp::Square, h, ctx, span)?;
        let c = self.binary(BinaryOp::Mul, h2, Val::Const(k / 4.0), ctx, span)?;
        Ok(c)
    }

    /// `translate(s, dx, dy, dz)`.
    pub(in crate::lang) fn translate(
        &mut self,
        args: &'a [Expr],
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
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
    pub(in crate::lang) fn scale(
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
    pub(in crate::lang) fn rotate(
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

    /// `blend_intersect(a, b, k)` (or `blend_difference` with b negated):
    /// `max(a, b) + h²·k/4`, the mirror image of `blend`'s polynomial, so
    /// it never falls below `max(a, b)` and exceeds it by at most `k/4`.
    pub(in crate::lang) fn blend_max(
        &mut self,
        negate_b: bool,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let k = self.positive_arg(
            &args[2],
            (ctx, env),
            "the blend radius",
            "use `intersect(a, b)` or `difference(a, b)` for a sharp join",
        )?;
        let a = self.lower(&args[0], ctx, env)?;
        let b = self.lower(&args[1], ctx, env)?;
        let b = if negate_b {
            self.unary(UnaryOp::Neg, b, ctx, span)?
        } else {
            b
        };
        let c = self.blend_term(a, b, k, ctx, span)?;
        let mx = self.binary(BinaryOp::Max, a, b, ctx, span)?;
        self.binary(BinaryOp::Add, mx, c, ctx, span)
    }

    /// `clamp(a, lo, hi)` = `min(max(a, lo), hi)`.
    pub(in crate::lang) fn clamp(
        &mut self,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let [a, lo, hi] = self.three(args, ctx, env)?;
        let m = self.binary(BinaryOp::Max, a, lo, ctx, span)?;
        self.binary(BinaryOp::Min, m, hi, ctx, span)
    }

    /// `mix(a, b, t)` = `a + (b - a)·t`.
    pub(in crate::lang) fn mix(
        &mut self,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let [a, b, t] = self.three(args, ctx, env)?;
        let d = self.binary(BinaryOp::Sub, b, a, ctx, span)?;
        let dt = self.binary(BinaryOp::Mul, d, t, ctx, span)?;
        self.binary(BinaryOp::Add, a, dt, ctx, span)
    }

    /// `smoothstep(e0, e1, a)`: `t²(3 - 2t)` with
    /// `t = clamp((a - e0) / (e1 - e0), 0, 1)`.
    pub(in crate::lang) fn smoothstep(
        &mut self,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let [e0, e1, a] = self.three(args, ctx, env)?;
        if let (Val::Const(lo), Val::Const(hi)) = (e0, e1)
            && lo == hi
        {
            return Err(ctx
                .diag(args[1].span, format!("smoothstep's edges are both {lo}"))
                .with_help("the edges must differ: the step rises from the first to the second"));
        }
        let n = self.binary(BinaryOp::Sub, a, e0, ctx, span)?;
        let w = self.binary(BinaryOp::Sub, e1, e0, ctx, span)?;
        let q = self.binary(BinaryOp::Div, n, w, ctx, span)?;
        let m = self.binary(BinaryOp::Max, q, Val::Const(0.0), ctx, span)?;
        let t = self.binary(BinaryOp::Min, m, Val::Const(1.0), ctx, span)?;
        let t2 = self.unary(UnaryOp::Square, t, ctx, span)?;
        let tt = self.binary(BinaryOp::Mul, Val::Const(2.0), t, ctx, span)?;
        let r = self.binary(BinaryOp::Sub, Val::Const(3.0), tt, ctx, span)?;
        self.binary(BinaryOp::Mul, t2, r, ctx, span)
    }

    /// The first three arguments, lowered.
    fn three(&mut self, args: &'a [Expr], ctx: &Ctx<'a>, env: Env) -> Result<[Val; 3], Diag> {
        Ok([
            self.lower(&args[0], ctx, env)?,
            self.lower(&args[1], ctx, env)?,
            self.lower(&args[2], ctx, env)?,
        ])
    }

    /// `mirror_*(s)`: s with coordinate `axis` replaced by its magnitude.
    pub(in crate::lang) fn mirror(
        &mut self,
        axis: usize,
        args: &'a [Expr],
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let c = self.coord(env[axis]);
        let mut new_env = env;
        new_env[axis] = Coord::Node(self.b.unary(UnaryOp::Abs, c));
        self.lower(&args[0], ctx, new_env)
    }

    /// `repeat(s, px, py, pz)`: each coordinate with a period p > 0
    /// becomes `mod(c + p/2, p) - p/2`, the offset from the centre of its
    /// cell; a period of 0 leaves the coordinate alone.
    pub(in crate::lang) fn repeat(
        &mut self,
        args: &'a [Expr],
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let mut new_env = env;
        for (i, slot) in new_env.iter_mut().enumerate() {
            let p = self.constant_arg(&args[i + 1], ctx, env, "the repetition period")?;
            if !(p >= 0.0 && p.is_finite()) {
                return Err(ctx
                    .diag(
                        args[i + 1].span,
                        format!("the repetition period must be 0 or positive, but it is {p}"),
                    )
                    .with_help("use 0 for an axis that does not repeat"));
            }
            if p == 0.0 {
                continue;
            }
            let c = self.coord(env[i]);
            let half = self.b.constant(p / 2.0);
            let period = self.b.constant(p);
            let shifted = self.b.binary(BinaryOp::Add, c, half);
            let m = self.b.binary(BinaryOp::Mod, shifted, period);
            *slot = Coord::Node(self.b.binary(BinaryOp::Sub, m, half));
        }
        self.lower(&args[0], ctx, new_env)
    }

    /// `rotate(s, ax, ay, az, deg)`: s evaluated at the point turned by
    /// -deg about the axis (ax, ay, az) through the origin (right-handed,
    /// like `rotate_x`, `rotate_y` and `rotate_z`, which it equals on the
    /// coordinate axes).
    pub(in crate::lang) fn rotate_axis(
        &mut self,
        args: &'a [Expr],
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let mut axis = [0.0; 3];
        for (k, a) in axis.iter_mut().enumerate() {
            *a = self.constant_arg(&args[k + 1], ctx, env, "the rotation axis")?;
        }
        // Scaled by the largest component first, so that huge components
        // do not overflow the length.
        let big = axis.iter().fold(0.0f64, |m, a| m.max(a.abs()));
        let axis = axis.map(|a| a / big);
        let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        if !(big > 0.0 && big.is_finite() && len > 0.0 && len.is_finite()) {
            return Err(ctx
                .diag(
                    args[1].span,
                    "the rotation axis must be a non-zero vector".into(),
                )
                .with_help("for example `rotate(s, 0, 0, 1, 30)` turns s about z"));
        }
        let deg = self.constant_arg(&args[4], ctx, env, "the rotation angle")?;
        if !deg.is_finite() {
            return Err(ctx.diag(args[4].span, "the rotation angle must be finite".into()));
        }
        let u = axis.map(|a| a / len);
        // Rodrigues' formula for the inverse rotation (angle -deg).
        let (c, s) = cos_sin_deg(deg);
        let s = -s;
        let t = 1.0 - c;
        let m = [
            [
                c + u[0] * u[0] * t,
                u[0] * u[1] * t - u[2] * s,
                u[0] * u[2] * t + u[1] * s,
            ],
            [
                u[1] * u[0] * t + u[2] * s,
                c + u[1] * u[1] * t,
                u[1] * u[2] * t - u[0] * s,
            ],
            [
                u[2] * u[0] * t - u[1] * s,
                u[2] * u[1] * t + u[0] * s,
                c + u[2] * u[2] * t,
            ],
        ];
        let p = [0, 1, 2].map(|k| self.coord(env[k]));
        let mut new_env = env;
        for (i, slot) in new_env.iter_mut().enumerate() {
            *slot = Coord::Node(self.lin3(m[i], p));
        }
        self.lower(&args[0], ctx, new_env)
    }

    /// `scale_xyz(s, kx, ky, kz)`: `min(k)·s(x/kx, y/ky, z/kz)`. Scaling
    /// stretches distances by at most `max(k)` and shrinks them by at
    /// least `min(k)`, so multiplying by `min(k)` keeps a distance bound a
    /// bound (it is exact only for uniform k).
    pub(in crate::lang) fn scale_xyz(
        &mut self,
        args: &'a [Expr],
        span: (usize, usize),
        ctx: &Ctx<'a>,
        env: Env,
    ) -> Result<Val, Diag> {
        let mut k = [0.0; 3];
        for (i, ki) in k.iter_mut().enumerate() {
            *ki = self.positive_arg(
                &args[i + 1],
                (ctx, env),
                "a scale factor",
                "mirroring is not supported; use mirror_x, mirror_y or mirror_z",
            )?;
        }
        let mut new_env = env;
        for (i, slot) in new_env.iter_mut().enumerate() {
            if k[i] != 1.0 {
                let c = self.coord(env[i]);
                let kk = self.b.constant(k[i]);
                *slot = Coord::Node(self.b.binary(BinaryOp::Div, c, kk));
            }
        }
        let s = self.lower(&args[0], ctx, new_env)?;
        let kmin = k[0].min(k[1]).min(k[2]);
        self.binary(BinaryOp::Mul, Val::Const(kmin), s, ctx, span)
    }

    /// `c·v` summed over three terms, skipping zero terms and unit factors.
    fn lin3(&mut self, c: [f64; 3], v: [ValueId; 3]) -> ValueId {
        let ab = self.lin(c[0], v[0], c[1], v[1]);
        if c[2] == 0.0 {
            return ab;
        }
        let z = self.lin(c[2], v[2], 0.0, v[2]);
        if c[0] == 0.0 && c[1] == 0.0 {
            return z;
        }
        self.b.binary(BinaryOp::Add, ab, z)
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
    fn right_angles_are_exact() {
        assert_eq!(cos_sin_deg(90.0), (0.0, 1.0));
        assert_eq!(cos_sin_deg(-90.0), (0.0, -1.0));
        assert_eq!(cos_sin_deg(540.0), (-1.0, 0.0));
        let (c, s) = cos_sin_deg(30.0);
        assert!((c - 0.75f64.sqrt()).abs() < 1e-15 && (s - 0.5).abs() < 1e-15);
    }
}
