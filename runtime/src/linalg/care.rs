//! The continuous-time algebraic Riccati equation: [`care`] and [`care_with_cross`] (the equation and the
//! method are in [`care`]'s documentation).

use nalgebra::DMatrix;

use super::balance::{frobenius, unit_scale};
use super::lyapunov::{lyap, symmetrize};
use super::pbh::Domain;
use super::refine::{Evaluated, refine, relative_residual};
use super::riccati::{
    Problem, Riccati, RiccatiError, Scaled, finite_solution, stabilising_solution,
};
use super::sign::hamiltonian_sign;

/// Newton–Kleinman steps at most.
const MAX_NEWTON_STEPS: usize = 30;

/// Solves `AᵀX + XA − XBR⁻¹BᵀX + Q = 0` for the stabilising solution `X = Xᵀ ≥ 0` (all eigenvalues of
/// `A − BK`, `K = R⁻¹BᵀX`, in the open left half plane).
///
/// With a cross weight ([`care_with_cross`]) the equation is `AᵀX + XA − (XB + N) R⁻¹ (BᵀX + Nᵀ) + Q = 0`,
/// `K = R⁻¹(BᵀX + Nᵀ)`.
///
/// Method: validate the inputs and the PBH conditions ((A, B) stabilisable, (Q̃, Ã) detectable), reduce the cross
/// term and balance (see [`crate::linalg::riccati`]), in a unit of time (a power of two) that brings the Hamiltonian
/// to unit size; compute `W = sign(H)` of the Hamiltonian
/// `H = [Ã, −G; −Q̃, −Ãᵀ]` ([`crate::linalg::sign`]), whose stable invariant subspace `[I; X]` is the null space of
/// `W + I`, giving `X` as the least-squares solution of `[W₁₂; W₂₂ + I] X = −[W₁₁ + I; W₂₁]`; then Newton–Kleinman
/// refinement in correction form: `(Ã − GX)ᵀ Δ + Δ (Ã − GX) + Res(X) = 0`, `X ← X + Δ`, until the residual stops
/// decreasing. The final relative residual `‖Res(X)‖ / (‖ÃᵀX‖ + ‖XÃ‖ + ‖XGX‖ + ‖Q̃‖)` (Frobenius norms, original
/// coordinates) must be below [`crate::linalg::riccati::RICCATI_TOLERANCE`] and `A − BK` must be stable, else an
/// error is returned.
///
/// `Q` must be symmetric positive semidefinite, `R` symmetric positive definite.
pub fn care(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<Riccati, RiccatiError> {
    care_with_cross(a, b, q, r, None)
}

/// Solves the CARE with the cross weight `N` of the cost `∫ xᵀQx + 2xᵀNu + uᵀRu dt`; `[Q N; Nᵀ R]` must be
/// positive semidefinite.
pub fn care_with_cross(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    n: Option<&DMatrix<f64>>,
) -> Result<Riccati, RiccatiError> {
    let p = Problem::new(a, b, q, r, n)?;
    p.check_modes(Domain::Continuous)?;
    let s = Scaled::new(&p);
    let first = solve_scaled(&p, &s, a, b);
    // The weight scale balances `Q̃` against `G`, as if `X` were of size √(‖Q‖/‖G‖). A state weight far below
    // what stabilising the unstable modes costs (`Q` of 1e-40 on an unstable plant) leaves `X` of size ‖Ã‖/‖G‖
    // instead, and both of the Hamiltonian's coupling blocks negligible: its stable subspace is then lost. Once
    // more, balanced on the plant's rates.
    match first {
        Err(
            RiccatiError::NoConvergence { .. }
            | RiccatiError::ClosedLoopUnstable { .. }
            | RiccatiError::IllConditioned { .. },
        ) => match s.rebalanced_on_rates() {
            Some(rates) => solve_scaled(&p, &rates, a, b).or(first),
            None => first,
        },
        other => other,
    }
}

/// The CARE of `p` in the scaled coordinates `s`.
fn solve_scaled(
    p: &Problem,
    s: &Scaled,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
) -> Result<Riccati, RiccatiError> {
    let nn = p.n;
    // A change of the unit of time (by a power of two, exactly) divides Ã, G and Q̃ alike and keeps X: it brings
    // the Hamiltonian to unit magnitude, so that rates of 1e200 per second neither overflow its iteration nor the
    // residual's products.
    let largest = [&s.a, &s.g, &s.q]
        .iter()
        .map(|m| m.amax())
        .fold(0.0, f64::max);
    let time_unit = unit_scale(largest);
    let (sa, sg, sq) = (&s.a / time_unit, &s.g / time_unit, &s.q / time_unit);

    let mut h = DMatrix::<f64>::zeros(2 * nn, 2 * nn);
    h.view_mut((0, 0), (nn, nn)).copy_from(&sa);
    h.view_mut((0, nn), (nn, nn)).copy_from(&(-&sg));
    h.view_mut((nn, 0), (nn, nn)).copy_from(&(-&sq));
    h.view_mut((nn, nn), (nn, nn)).copy_from(&(-sa.transpose()));
    let Some((w, sign_iterations)) = hamiltonian_sign(&h) else {
        return Err(match p.diagnose(Domain::Continuous, f64::INFINITY, 0) {
            RiccatiError::NoConvergence { .. } => RiccatiError::IllConditioned {
                what: "the sign function of the Hamiltonian",
            },
            found => found,
        });
    };
    let mut lhs = DMatrix::<f64>::zeros(2 * nn, nn);
    lhs.view_mut((0, 0), (nn, nn))
        .copy_from(&w.view((0, nn), (nn, nn)));
    lhs.view_mut((nn, 0), (nn, nn))
        .copy_from(&(w.view((nn, nn), (nn, nn)) + DMatrix::<f64>::identity(nn, nn)));
    let mut rhs = DMatrix::<f64>::zeros(2 * nn, nn);
    rhs.view_mut((0, 0), (nn, nn))
        .copy_from(&(-(w.view((0, 0), (nn, nn)) + DMatrix::<f64>::identity(nn, nn))));
    rhs.view_mut((nn, 0), (nn, nn))
        .copy_from(&(-w.view((nn, 0), (nn, nn))));
    let qr = lhs.qr();
    let qtb = qr.q().transpose() * rhs;
    let Some(x0) = qr.r().solve_upper_triangular(&qtb) else {
        return Err(p.diagnose(Domain::Continuous, f64::INFINITY, sign_iterations));
    };
    let xs = symmetrize(&x0);
    finite_solution(&xs, sign_iterations)?;

    // Newton–Kleinman refinement in the scaled coordinates: (Ã − GX)ᵀ Δ + Δ (Ã − GX) + Res(X) = 0.
    let evaluate = |x: &DMatrix<f64>| Some(Evaluation::new(&sa, &sg, &sq, x));
    let eval = Evaluation::new(&sa, &sg, &sq, &xs);
    let newton = |x: &DMatrix<f64>, eval: &Evaluation| {
        lyap(&(&sa - &sg * x).transpose(), &eval.residual).ok()
    };
    let (xs, steps) = refine(xs, eval, MAX_NEWTON_STEPS, newton, evaluate);

    let x = s.unscale(&xs);
    finite_solution(&x, sign_iterations + steps)?;
    let g = p.g();
    let rel_orig = Evaluation::new(&p.a, &g, &p.q, &x).relative;
    p.check_residual(Domain::Continuous, rel_orig, sign_iterations + steps)?;
    let k = &p.r_inv * (p.b.transpose() * &x + &p.n_t);
    stabilising_solution(Domain::Continuous, a, b, x, k, rel_orig, steps)
}

/// The CARE residual `AᵀX + XA − XGX + Q` at `X` and its size relative to the terms.
struct Evaluation {
    residual: DMatrix<f64>,
    relative: f64,
}

impl Evaluation {
    fn new(a: &DMatrix<f64>, g: &DMatrix<f64>, q: &DMatrix<f64>, x: &DMatrix<f64>) -> Evaluation {
        let xa = x * a;
        let xgx = x * g * x;
        let residual = symmetrize(&(a.transpose() * x + &xa - &xgx + q));
        // ‖AᵀX‖ = ‖XA‖ for symmetric X.
        let relative = relative_residual(
            &residual,
            2.0 * frobenius(&xa) + frobenius(&xgx) + frobenius(q),
        );
        Evaluation { residual, relative }
    }
}

impl Evaluated for Evaluation {
    fn relative(&self) -> f64 {
        self.relative
    }
}
