//! Tests of the symbolic engine.

mod dag;
mod derivatives;
mod evaluation;
mod from_ir;
mod linear;
mod printing;
mod properties;
mod reference;
mod simplification;
mod solver;

use super::{Expr, Symbol};

/// A parameter symbol as an expression.
fn p(name: &str) -> Expr {
    Expr::symbol(Symbol::param(name))
}

/// A state symbol as an expression.
fn s(name: &str) -> Expr {
    Expr::symbol(Symbol::state(name))
}

fn c(v: f64) -> Expr {
    Expr::constant(v)
}

/// A small deterministic generator (SplitMix64) for sample points.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }
}
