//! Deterministic random IR for differential and fuzz-like tests: the same
//! seed gives the same function on every machine and every run.

use super::{BinaryOp, Builder, Function, UnaryOp, ValueId, Var};

/// A small deterministic generator (SplitMix64), so tests need no extra
/// dependency and reproduce from a printed seed.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator started from `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// A uniformly chosen element of a non-empty slice.
    pub fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len())]
    }
}

/// Every one-operand op, for generators and exhaustive tests.
pub const UNARY_OPS: [UnaryOp; 19] = UnaryOp::ALL;

/// Every two-operand op, for generators and exhaustive tests.
pub const BINARY_OPS: [BinaryOp; 9] = BinaryOp::ALL;

/// Constants that exercise edge cases: signed zeros, identities, halves,
/// huge and tiny magnitudes (subnormal included), negatives.
pub const EDGE_CONSTANTS: [f64; 16] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    2.0,
    3.0,
    -2.5,
    0.1,
    std::f64::consts::PI,
    1e300,
    -1e300,
    1e-300,
    5e-324,
    1e10,
    -7.0,
];

/// Most ops a generated function has (the expression stops growing there).
const MAX_OPS: usize = 160;

/// A random valid function over x, y, z using every op kind, of depth at
/// most `max_depth` (about 12 is a good upper value) and at most a few
/// hundred ops. Subexpressions are sometimes shared, so the result is a
/// DAG as real lowered functions are.
pub fn random_function(seed: u64, max_depth: u32) -> Function {
    let mut g = Gen {
        rng: Rng::new(seed ^ 0x5eed_1b3a_u64),
        b: Builder::new(),
        made: Vec::new(),
    };
    let root = g.expr(max_depth);
    g.b.finish(root)
}

struct Gen {
    rng: Rng,
    b: Builder,
    // Values built so far with the depth budget they were built under (a
    // bound on their height), so reuse keeps the depth limit.
    made: Vec<(ValueId, u32)>,
}

impl Gen {
    fn expr(&mut self, depth: u32) -> ValueId {
        let leaf = depth == 0 || self.b.len() >= MAX_OPS || self.rng.chance(0.15);
        let v = if leaf {
            self.leaf()
        } else if let Some(v) = self.reuse(depth) {
            v
        } else {
            match self.rng.below(10) {
                0..=3 => {
                    let op = self.rng.pick(&UNARY_OPS);
                    let a = self.expr(depth - 1);
                    self.b.unary(op, a)
                }
                4..=8 => {
                    let op = self.rng.pick(&BINARY_OPS);
                    let a = self.expr(depth - 1);
                    let c = if self.rng.chance(0.1) {
                        a
                    } else {
                        self.expr(depth - 1)
                    };
                    self.b.binary(op, a, c)
                }
                _ => {
                    let n = self.rng.below(11) as i32 - 4;
                    let a = self.expr(depth - 1);
                    self.b.powi(a, n)
                }
            }
        };
        self.made.push((v, depth));
        v
    }

    // Sometimes an earlier value: shared subexpressions, x*x, x-x, …
    fn reuse(&mut self, depth: u32) -> Option<ValueId> {
        if self.made.is_empty() || !self.rng.chance(0.08) {
            return None;
        }
        let (v, h) = self.rng.pick(&self.made);
        (h <= depth).then_some(v)
    }

    fn leaf(&mut self) -> ValueId {
        match self.rng.below(10) {
            0..=5 => {
                let v = self.rng.pick(&Var::ALL);
                self.b.var(v)
            }
            6..=7 => {
                let c = self.rng.pick(&EDGE_CONSTANTS);
                self.b.constant(c)
            }
            _ => {
                let c = (self.rng.range(-10.0, 10.0) * 8.0).round() / 8.0;
                self.b.constant(c)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ir::{Op, validate::validate};

    #[test]
    fn deterministic_valid_and_varied() {
        let mut kinds = std::collections::HashSet::new();
        for seed in 0..300 {
            let f = random_function(seed, 12);
            assert_eq!(f, random_function(seed, 12));
            validate(&f).unwrap();
            assert!(f.len() <= MAX_OPS + 64);
            for op in &f.ops {
                kinds.insert(op.mnemonic());
                if let Op::Powi(_, n) = op {
                    assert!((-4..=6).contains(n));
                }
            }
        }
        // var, const, powi and every unary and binary op.
        assert_eq!(kinds.len(), 3 + UNARY_OPS.len() + BINARY_OPS.len());
    }
}
