//! The discrete-time algebraic Riccati equation: [`dare`] and [`dare_with_cross`] (the equation and the
//! method are in [`dare`]'s documentation).

use nalgebra::DMatrix;

use super::balance::frobenius;
use super::lyapunov::{dlyap, symmetrize};
use super::pbh::Domain;
use super::refine::{Evaluated, refine, relative_residual};
use super::riccati::{
    Problem, Riccati, RiccatiError, Scaled, finite_solution, overflowed, stabilising_solution,
};

/// Doubling steps at most (each squares the convergence factor).
const MAX_DOUBLING_STEPS: usize = 100;
/// Hewer steps at most.
const MAX_HEWER_STEPS: usize = 30;
/// `‖G̃‖ δ` of the heavier state weight `Q̃ + δI` whose doubling starts the refinement when the doubling of `Q̃` fails.
const REGULARISATION: f64 = 1e-8;

/// Solves `AᵀXA − X − AᵀXB(R + BᵀXB)⁻¹BᵀXA + Q = 0` for the stabilising solution `X = Xᵀ ≥ 0` (all eigenvalues
/// of `A − BK`, `K = (R + BᵀXB)⁻¹BᵀXA`, inside the unit circle).
///
/// With a cross weight ([`dare_with_cross`]) the equation is
/// `AᵀXA − X − (AᵀXB + N)(R + BᵀXB)⁻¹(BᵀXA + Nᵀ) + Q = 0`, `K = (R + BᵀXB)⁻¹(BᵀXA + Nᵀ)`.
///
/// Method: validate the inputs and the PBH conditions, reduce the cross term and balance (see
/// [`crate::linalg::riccati`]); the structure-preserving doubling algorithm (SDA, Chu, Fan, Lin & Wang 2004) on the
/// symplectic pencil, which needs no inverse of `A`:
///
/// `A₀ = Ã, G₀ = BR⁻¹Bᵀ, H₀ = Q̃`; with `W = I + GₖHₖ`:
/// `Aₖ₊₁ = Aₖ W⁻¹ Aₖ`, `Gₖ₊₁ = Gₖ + Aₖ W⁻¹ Gₖ Aₖᵀ`, `Hₖ₊₁ = Hₖ + Aₖᵀ Hₖ W⁻¹ Aₖ`,
///
/// where `Hₖ → X` quadratically (when the iterates leave f64 for a state weight far below the plant's rates, the
/// doubling of `Q̃ + δI` gives the start instead, `‖G‖ δ = 1e-8`); then Hewer's (Newton's) refinement in correction
/// form `(Ã − BK)ᵀ Δ (Ã − BK) − Δ + Res(X) = 0`, `X ← X + Δ`, while the residual decreases. The relative residual
/// `‖Res(X)‖ / (‖ÃᵀXÃ‖ + ‖X‖ + ‖ÃᵀXB(R + BᵀXB)⁻¹BᵀXÃ‖ + ‖Q̃‖)` must be below
/// [`crate::linalg::riccati::RICCATI_TOLERANCE`] and `A − BK` stable, else an error is returned.
pub fn dare(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<Riccati, RiccatiError> {
    dare_with_cross(a, b, q, r, None)
}

/// Solves the DARE with the cross weight `N` of the cost `Σ xᵀQx + 2xᵀNu + uᵀRu`.
pub fn dare_with_cross(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
) -> Result<Riccati, RiccatiError> {
    let p = Problem::new(a, b, q, r, n)?;
    p.check_modes(Domain::Discrete)?;
    let s = Scaled::new(&p);
    let out_of_range =
        |doubling| overflowed(&p, Domain::Discrete, "the doubling iterates", doubling);
    let (xs, doubling, identity_lost) = match sda(&p, &s, &s.q) {
        Ok(found) => found,
        // A state weight far below the plant's rates (Q/R of 1e-16 on an unstable plant): the iterates grow as
        // Ã^(2^k) before the weak coupling GₖHₖ acts, and leave f64. The doubling of a slightly heavier weight gives
        // a stabilising start, and Hewer's refinement below, on the true weight, converges from any stabilising
        // start.
        Err(
            first @ (RiccatiError::OutOfRange { .. }
            | RiccatiError::NoConvergence { .. }
            | RiccatiError::IllConditioned { .. }),
        ) => {
            let nn = p.n;
            let heavier = &s.q
                + DMatrix::<f64>::identity(nn, nn)
                    * (REGULARISATION / frobenius(&s.g).max(f64::MIN_POSITIVE));
            sda(&p, &s, &heavier).map_err(|_| first)?
        }
        Err(e) => return Err(e),
    };
    finite_solution(&xs, doubling)?;

    // Hewer refinement in the scaled coordinates: (Ã − BK)ᵀ Δ (Ã − BK) − Δ + Res(X) = 0.
    let evaluate = |x: &DMatrix<f64>| Evaluation::new(&s.a, &s.b, &s.q, &s.r, x);
    let Some(eval) = evaluate(&xs) else {
        return Err(p.diagnose(Domain::Discrete, f64::INFINITY, doubling));
    };
    let hewer = |_: &DMatrix<f64>, eval: &Evaluation| {
        dlyap(&(&s.a - &s.b * &eval.gain).transpose(), &eval.residual).ok()
    };
    let (xs, steps) = refine(xs, eval, MAX_HEWER_STEPS, hewer, evaluate);

    let x = s.unscale(&xs);
    finite_solution(&x, doubling + steps)?;
    let Some(orig) = Evaluation::new(&p.a, &p.b, &p.q, &p.r, &x) else {
        return Err(RiccatiError::Singular { what: "R + BᵀXB" });
    };
    p.check_residual(Domain::Discrete, orig.relative, doubling + steps)
        .map_err(|e| match e {
            RiccatiError::NoConvergence { .. } if identity_lost => out_of_range(doubling + steps),
            e => e,
        })?;
    // K for the original (cross-weighted) problem: (R + BᵀXB)⁻¹(BᵀXA + Nᵀ).
    let k = gain(&p.b, &p.r, &x, a, Some(&p.n_t))
        .ok_or(RiccatiError::Singular { what: "R + BᵀXB" })?;
    stabilising_solution(Domain::Discrete, a, b, x, k, orig.relative, steps)
}

/// The structure-preserving doubling from `H₀ = q` in the scaled coordinates `s`: `X`, the number of doubling
/// steps, and whether some `I + GₖHₖ` lost its identity to rounding.
fn sda(
    p: &Problem,
    s: &Scaled,
    q: &DMatrix<f64>,
) -> Result<(DMatrix<f64>, usize, bool), RiccatiError> {
    let nn = p.n;
    let identity = DMatrix::<f64>::identity(nn, nn);
    let (mut ak, mut gk, mut hk) = (s.a.clone(), s.g.clone(), q.clone());
    let mut doubling = 0;
    let mut converged = false;
    // Whether some `I + GₖHₖ` had entries beyond 1/ε: its identity was lost to rounding, so a solution that then
    // fails its residual check failed for range, not for a property of the data.
    let mut identity_lost = false;
    let out_of_range =
        |doubling| overflowed(p, Domain::Discrete, "the doubling iterates", doubling);
    while doubling < MAX_DOUBLING_STEPS {
        doubling += 1;
        let pivot = &identity + &gk * &hk;
        if !pivot.iter().chain(ak.iter()).all(|v| v.is_finite()) {
            return Err(out_of_range(doubling));
        }
        // `I + GₖHₖ` with entries beyond 1/ε has lost its identity to rounding: singular for range, not data.
        let lost_identity = pivot.amax() > 1.0 / f64::EPSILON;
        identity_lost |= lost_identity;
        let lu = pivot.lu();
        let (Some(w_a), Some(w_g)) = (lu.solve(&ak), lu.solve(&gk)) else {
            return Err(if lost_identity {
                out_of_range(doubling)
            } else {
                p.diagnose(Domain::Discrete, f64::INFINITY, doubling)
            });
        };
        let h_next = symmetrize(&(&hk + ak.transpose() * &hk * &w_a));
        let g_next = symmetrize(&(&gk + &ak * w_g * ak.transpose()));
        let a_next = &ak * w_a;
        if !h_next.iter().all(|v| v.is_finite()) {
            return Err(out_of_range(doubling));
        }
        let change = (&h_next - &hk).norm() / h_next.norm().max(f64::MIN_POSITIVE);
        hk = h_next;
        gk = g_next;
        ak = a_next;
        if change <= 1e-14 {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(if identity_lost {
            out_of_range(doubling)
        } else {
            p.diagnose(Domain::Discrete, f64::INFINITY, doubling)
        });
    }
    Ok((hk, doubling, identity_lost))
}

/// `K = (R + BᵀXB)⁻¹(BᵀXA + Nᵀ)`, multiplied as `(((R + BᵀXB)⁻¹Bᵀ)X)A`: the solve first, then two products of
/// `O(m n²)` as for `BᵀXA`. `BᵀXA` first underflowed: with weights of 1e-150 it is `(R + BᵀXB)·K`, below the range
/// of f64 for a gain of 1e-301, while the solve gives a result of order 0.1 there and the products after it are of
/// the order of `K A⁻¹` and `K`.
fn gain(
    b: &DMatrix<f64>,
    r: &DMatrix<f64>,
    x: &DMatrix<f64>,
    a: &DMatrix<f64>,
    n_t: Option<&DMatrix<f64>>,
) -> Option<DMatrix<f64>> {
    let lu = (r + b.transpose() * x * b).lu();
    let left = lu.solve(&b.transpose())?;
    let mut k = (left * x) * a;
    if let Some(n_t) = n_t {
        k += lu.solve(n_t)?;
    }
    Some(k)
}

/// The DARE residual at `X` with the gain `K = (R + BᵀXB)⁻¹BᵀXA` of the problem without cross term.
struct Evaluation {
    residual: DMatrix<f64>,
    relative: f64,
    gain: DMatrix<f64>,
}

impl Evaluation {
    fn new(
        a: &DMatrix<f64>,
        b: &DMatrix<f64>,
        q: &DMatrix<f64>,
        r: &DMatrix<f64>,
        x: &DMatrix<f64>,
    ) -> Option<Evaluation> {
        let gain = gain(b, r, x, a, None)?;
        let atxa = a.transpose() * x * a;
        let correction = symmetrize(&((b.transpose() * x * a).transpose() * &gain));
        let residual = symmetrize(&(&atxa - x - &correction + q));
        let relative = relative_residual(
            &residual,
            frobenius(&atxa) + frobenius(x) + frobenius(&correction) + frobenius(q),
        );
        Some(Evaluation {
            residual,
            relative,
            gain,
        })
    }
}

impl Evaluated for Evaluation {
    fn relative(&self) -> f64 {
        self.relative
    }
}
