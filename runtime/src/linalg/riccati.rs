//! Types, checks and scaling shared by the continuous ([`super::care`]) and discrete ([`super::dare`]) Riccati
//! solvers.
//!
//! Both solvers reduce a cross-weighted problem `(A, B, Q, R, N)` to `Ã = A − B R⁻¹ Nᵀ`, `Q̃ = Q − N R⁻¹ Nᵀ`
//! (the optimal gain is unchanged, `K = R⁻¹(BᵀX + Nᵀ)` resp. `(R + BᵀXB)⁻¹(BᵀXA + Nᵀ)`), then rescale it:
//!
//! - states: `x = D x̃` with `D` a diagonal of powers of two chosen to balance the Hamiltonian (resp. symplectic)
//!   matrix, i.e. `Ã → D⁻¹ Ã D`, `B → D⁻¹ B`, `Q̃ → D Q̃ D`, and the solution `X = D⁻¹ X̃ D⁻¹`;
//! - weights: `Q̃ → Q̃/α`, `R → R/α`, `X → X/α` with `α` (a power of two) equalising `‖Q̃‖` and `‖B R⁻¹ Bᵀ‖`.
//!
//! The Riccati equations are invariant under both, and with weights such as `Q = diag(10⁵ … 5·10¹⁵)`,
//! `R = 10¹²` the scaled problem has entries of comparable size, which the base solvers need.

use nalgebra::{Complex, DMatrix, DVector};

use super::balance::{frobenius, osborne_factor, power_of_two};
use super::check::{self, MatrixError};
use super::lyapunov::LyapunovError;
use super::pbh::{self, Domain, PbhError};
use super::schur::{SchurError, eigenvalues};

/// Relative residual above which a Riccati solution is refused (see [`Riccati::relative_residual`]).
pub const RICCATI_TOLERANCE: f64 = 1e-8;

/// The stabilising solution of a Riccati equation and the optimal gain.
#[derive(Clone, Debug, PartialEq)]
pub struct Riccati {
    /// The symmetric positive semidefinite stabilising solution `X`.
    pub x: DMatrix<f64>,
    /// The optimal state-feedback gain: `u = −K x`.
    pub k: DMatrix<f64>,
    /// The eigenvalues of `A − B K`, all in the open left half plane (continuous) or unit disc (discrete).
    pub closed_loop_eigenvalues: Vec<Complex<f64>>,
    /// `‖Res(X)‖_F` divided by the sum of the Frobenius norms of the terms of the equation.
    pub relative_residual: f64,
    /// Newton–Kleinman (resp. Hewer) steps applied after the base solver.
    pub refinement_steps: usize,
}

/// Why a Riccati equation was not solved.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RiccatiError {
    #[error(transparent)]
    Input(#[from] MatrixError),
    #[error(
        "not stabilisable: the mode with eigenvalue {eigenvalue} is not stable and cannot be moved by the input (for an estimator: is not excited by the process noise){}",
        format_direction(.direction)
    )]
    NotStabilizable {
        eigenvalue: Complex<f64>,
        /// For systems of at most [`DIRECTION_MAX_ORDER`] states: the left eigenvector `w`, `wᴴB = 0`.
        direction: Option<DVector<Complex<f64>>>,
    },
    #[error(
        "not detectable: the mode with eigenvalue {eigenvalue} is not stable and is invisible to the state weight Q (for an estimator: to the measurements C){}",
        format_direction(.direction)
    )]
    NotDetectable {
        eigenvalue: Complex<f64>,
        /// For systems of at most [`DIRECTION_MAX_ORDER`] states: the right eigenvector `v`, `Qv = 0`.
        direction: Option<DVector<Complex<f64>>>,
    },
    #[error(
        "the solver did not converge: relative residual {residual:e} after {iterations} iterations"
    )]
    NoConvergence { residual: f64, iterations: usize },
    /// `what` left the range where f64 can carry it: entries that overflow, or so large that the identity added
    /// to them is lost in rounding. The data are too far out of scale for the solver: a discrete open loop that
    /// grows by many orders of magnitude per step, or a solution beyond 1.8e308.
    #[error(
        "{what} left the range of f64 after {iterations} iterations: the data are too far out of scale for the solver; rescale the states, the inputs or the weights"
    )]
    OutOfRange {
        what: &'static str,
        iterations: usize,
    },
    /// The solution meets the equation (its residual was checked) and the modes passed the PBH tests, yet
    /// `A − BK` is not stable: the gain is too sensitive to the rounding of `X` at this scaling, as near a deadbeat
    /// gain of a fast open loop.
    #[error(
        "the closed loop A − BK is not stable: eigenvalue {eigenvalue}, although X meets the equation (its residual is within the tolerance); the gain is too sensitive to rounding at this scaling (the problem is ill-conditioned); rescale the states and inputs"
    )]
    ClosedLoopUnstable { eigenvalue: Complex<f64> },
    /// The base solver could not separate the stable from the unstable modes, although every mode passed the PBH
    /// tests: eigenvalues of the Hamiltonian lie at the imaginary axis to working precision, as when the
    /// closed-loop poles would spread over more orders of magnitude than f64 resolves.
    #[error(
        "{what} did not converge although every mode passed the PBH tests: the Hamiltonian has eigenvalues at the imaginary axis to working precision, as when the closed-loop poles would spread over more orders of magnitude than f64 resolves (control far cheaper or dearer than the plant's own rates); rescale the weights Q and R, or the inputs"
    )]
    IllConditioned { what: &'static str },
    #[error("{what} is singular")]
    Singular { what: &'static str },
    #[error(transparent)]
    Schur(#[from] SchurError),
    #[error("a singular value decomposition did not converge")]
    Svd,
    #[error(transparent)]
    Lyapunov(#[from] LyapunovError),
}

/// `"; state direction [a, b, …]"` with real entries when the direction is real up to a common phase, else
/// complex entries; empty without a direction.
fn format_direction(direction: &Option<DVector<Complex<f64>>>) -> String {
    let Some(d) = direction else {
        return String::new();
    };
    // Rotate so that the largest entry is real and positive, then print real parts if that makes it real.
    let pivot = d
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()));
    let phase = match pivot {
        Some(p) if p.norm() > 0.0 => p.conj() / p.norm(),
        _ => Complex::new(1.0, 0.0),
    };
    let rotated: Vec<Complex<f64>> = d.iter().map(|z| z * phase).collect();
    let real = rotated.iter().all(|z| z.im.abs() <= 1e-12);
    let entries: Vec<String> = rotated
        .iter()
        .map(|z| {
            if real {
                format!("{:.4e}", z.re)
            } else {
                format!("{:.4e}{:+.4e}i", z.re, z.im)
            }
        })
        .collect();
    format!("; state direction [{}]", entries.join(", "))
}

/// Systems up to this order get the state direction of an offending mode in the errors.
pub const DIRECTION_MAX_ORDER: usize = 20;

impl From<PbhError> for RiccatiError {
    fn from(e: PbhError) -> Self {
        match e {
            PbhError::Input(m) => RiccatiError::Input(m),
            PbhError::Schur(s) => RiccatiError::Schur(s),
            PbhError::Svd { .. } => RiccatiError::Svd,
        }
    }
}

/// A validated Riccati problem, reduced to no cross term.
pub(crate) struct Problem {
    pub n: usize,
    /// `Ã = A − B R⁻¹ Nᵀ`
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    /// `Q̃ = Q − N R⁻¹ Nᵀ`
    pub q: DMatrix<f64>,
    pub r: DMatrix<f64>,
    /// `R⁻¹`, symmetrised.
    pub r_inv: DMatrix<f64>,
    /// `Nᵀ` (zero without a cross term).
    pub n_t: DMatrix<f64>,
}

impl Problem {
    /// Checks shapes, finiteness, symmetry, `R > 0` and `[Q N; Nᵀ R] ≥ 0`, then reduces the cross term.
    pub fn new(
        a: &DMatrix<f64>,
        b: &DMatrix<f64>,
        q: &DMatrix<f64>,
        r: &DMatrix<f64>,
        cross: Option<&DMatrix<f64>>,
    ) -> Result<Self, RiccatiError> {
        let n = check::square("A", a)?;
        let m = b.ncols();
        check::shape("B", b, n, m)?;
        check::shape("Q", q, n, n)?;
        check::shape("R", r, m, m)?;
        check::positive_definite("R", r)?;
        let r_sym = (r + r.transpose()) * 0.5;
        let r_inv = r_sym
            .clone()
            .cholesky()
            .map(|c| c.inverse())
            .ok_or(RiccatiError::Input(MatrixError::NotPositiveDefinite {
                name: "R",
                min_eigenvalue: 0.0,
            }))?;
        let r_inv = (&r_inv + r_inv.transpose()) * 0.5;
        let (a_red, q_red, n_t) = match cross {
            None => {
                check::positive_semidefinite("Q", q)?;
                (a.clone(), (q + q.transpose()) * 0.5, DMatrix::zeros(m, n))
            }
            Some(nm) => {
                check::shape("N", nm, n, m)?;
                check::symmetric("Q", q)?;
                let q_red = q - nm * &r_inv * nm.transpose();
                let q_red = (&q_red + q_red.transpose()) * 0.5;
                // [Q N; Nᵀ R] ≥ 0 with R > 0 is equivalent to the Schur complement Q − N R⁻¹ Nᵀ ≥ 0.
                check::positive_semidefinite("Q - N R⁻¹ Nᵀ", &q_red)?;
                (a - b * &r_inv * nm.transpose(), q_red, nm.transpose())
            }
        };
        Ok(Problem {
            n,
            a: a_red,
            b: b.clone(),
            q: q_red,
            r: r_sym,
            r_inv,
            n_t,
        })
    }

    /// `G = B R⁻¹ Bᵀ`.
    pub fn g(&self) -> DMatrix<f64> {
        let g = &self.b * &self.r_inv * self.b.transpose();
        (&g + g.transpose()) * 0.5
    }

    /// Refuses a problem with an uncontrollable mode that is not stable, or an unobservable mode of `(Q̃, Ã)`
    /// that is not stable, by the PBH tests.
    pub fn check_modes(&self, domain: Domain) -> Result<(), RiccatiError> {
        if let Some(mode) = pbh::unstabilizable_mode(&self.a, &self.b, domain)? {
            return Err(RiccatiError::NotStabilizable {
                eigenvalue: mode.eigenvalue,
                direction: self.small(mode.direction),
            });
        }
        if let Some(mode) = pbh::undetectable_mode(&self.a, &self.q, domain)? {
            return Err(RiccatiError::NotDetectable {
                eigenvalue: mode.eigenvalue,
                direction: self.small(mode.direction),
            });
        }
        Ok(())
    }

    fn small(&self, v: DVector<Complex<f64>>) -> Option<DVector<Complex<f64>>> {
        (self.n <= DIRECTION_MAX_ORDER).then_some(v)
    }

    /// Refuses a solution whose relative residual in the original coordinates is NaN or above
    /// [`RICCATI_TOLERANCE`], with the diagnosis of [`Self::diagnose`].
    pub fn check_residual(
        &self,
        domain: Domain,
        relative_residual: f64,
        iterations: usize,
    ) -> Result<(), RiccatiError> {
        if relative_residual.is_nan() || relative_residual > RICCATI_TOLERANCE {
            return Err(self.diagnose(domain, relative_residual, iterations));
        }
        Ok(())
    }

    /// After a failed solve: names the least controllable or least observable mode on or near the stability
    /// boundary (within `10⁴` times the margin of the precondition check, as a defective eigenvalue is only
    /// computed to about `√ε`) when it is nearly rank deficient (PBH margin below `1e-6`), else reports
    /// non-convergence.
    pub fn diagnose(&self, domain: Domain, residual: f64, iterations: usize) -> RiccatiError {
        let scale = 1e4 * pbh::stability_scale(&self.a, domain);
        let worst = |modes: Result<Vec<pbh::Mode>, PbhError>| {
            modes.ok().and_then(|ms| {
                ms.into_iter()
                    .find(|m| !domain.is_stable(m.eigenvalue, scale))
            })
        };
        let ctrl = worst(pbh::controllability_margins(&self.a, &self.b));
        let obs = worst(pbh::observability_margins(&self.a, &self.q));
        let c_margin = ctrl.as_ref().map_or(f64::INFINITY, |m| m.margin);
        let o_margin = obs.as_ref().map_or(f64::INFINITY, |m| m.margin);
        match (ctrl, obs) {
            (Some(m), _) if c_margin <= o_margin && c_margin < 1e-6 => {
                RiccatiError::NotStabilizable {
                    eigenvalue: m.eigenvalue,
                    direction: self.small(m.direction),
                }
            }
            (_, Some(m)) if o_margin < 1e-6 => RiccatiError::NotDetectable {
                eigenvalue: m.eigenvalue,
                direction: self.small(m.direction),
            },
            _ => RiccatiError::NoConvergence {
                residual,
                iterations,
            },
        }
    }
}

/// A Riccati problem in balanced coordinates: `X = α D⁻¹ X̃ D⁻¹`.
pub(crate) struct Scaled {
    pub a: DMatrix<f64>,
    pub b: DMatrix<f64>,
    pub q: DMatrix<f64>,
    pub r: DMatrix<f64>,
    pub g: DMatrix<f64>,
    pub d: DVector<f64>,
    pub alpha: f64,
}

impl Scaled {
    pub fn new(p: &Problem) -> Scaled {
        let n = p.n;
        let g0 = p.g();
        let alpha0 = weight_scale(&p.q, &g0);
        let d = hamiltonian_scales(&p.a, &(&g0 * alpha0), &(&p.q / alpha0));
        let mut a = p.a.clone();
        let mut q = p.q.clone();
        let mut b = p.b.clone();
        for j in 0..n {
            for i in 0..n {
                a[(i, j)] *= d[j] / d[i];
                q[(i, j)] *= d[i] * d[j];
            }
        }
        for i in 0..n {
            for j in 0..b.ncols() {
                b[(i, j)] /= d[i];
            }
        }
        let g_unit = {
            let g = &b * &p.r_inv * b.transpose();
            (&g + g.transpose()) * 0.5
        };
        let alpha = weight_scale(&q, &g_unit);
        Scaled {
            q: q / alpha,
            r: &p.r / alpha,
            g: g_unit * alpha,
            a,
            b,
            d,
            alpha,
        }
    }

    /// The same coordinates with the weight scale `α = ‖Ã‖/‖G‖` (a power of two), when that is larger than the
    /// one that balances `Q̃` against `G`: the size of `X` where stabilising the unstable modes dominates the
    /// state weight. `None` otherwise.
    pub fn rebalanced_on_rates(&self) -> Option<Scaled> {
        let g_unit = &self.g / self.alpha;
        let (an, gn) = (frobenius(&self.a), frobenius(&g_unit));
        if !(an > 0.0 && gn > 0.0 && an.is_finite() && gn.is_finite()) {
            return None;
        }
        let alpha = power_of_two(an / gn);
        (alpha > self.alpha).then(|| Scaled {
            q: &self.q * (self.alpha / alpha),
            r: &self.r * (self.alpha / alpha),
            g: g_unit * alpha,
            a: self.a.clone(),
            b: self.b.clone(),
            d: self.d.clone(),
            alpha,
        })
    }

    /// `X = α D⁻¹ X̃ D⁻¹`.
    pub fn unscale(&self, xs: &DMatrix<f64>) -> DMatrix<f64> {
        let n = xs.nrows();
        DMatrix::from_fn(n, n, |i, j| {
            self.alpha * xs[(i, j)] / (self.d[i] * self.d[j])
        })
    }
}

/// `α` (a power of two) with `‖Q‖/α = α‖G‖`; 1 when either is zero.
fn weight_scale(q: &DMatrix<f64>, g: &DMatrix<f64>) -> f64 {
    let (qn, gn) = (frobenius(q), frobenius(g));
    if qn > 0.0 && gn > 0.0 && qn.is_finite() && gn.is_finite() {
        power_of_two((qn / gn).sqrt())
    } else {
        1.0
    }
}

/// Symplectic diagonal balancing of `[A, −G; −Q, −Aᵀ]` by `diag(D⁻¹, D)`: scaling state `i` by `f` multiplies
/// column `i` of `A` and row/column `i` of `Q` by `f` and divides row `i` of `A` and row/column `i` of `G` by `f`;
/// Osborne's iteration equalises the two groups.
fn hamiltonian_scales(a: &DMatrix<f64>, g: &DMatrix<f64>, q: &DMatrix<f64>) -> DVector<f64> {
    let n = a.nrows();
    let (mut a, mut g, mut q) = (a.clone(), g.clone(), q.clone());
    let mut d = DVector::from_element(n, 1.0);
    for _sweep in 0..100 {
        let mut changed = false;
        for i in 0..n {
            let mut c = 0.0;
            let mut r = 0.0;
            for j in 0..n {
                if j != i {
                    c += a[(j, i)].abs();
                    r += a[(i, j)].abs();
                }
                c += q[(i, j)].abs();
                r += g[(i, j)].abs();
            }
            if c == 0.0 || r == 0.0 || !(c.is_finite() && r.is_finite()) {
                continue;
            }
            let Some(f) = osborne_factor(r, c, d[i]) else {
                continue;
            };
            if c * f + r / f < 0.95 * (c + r) {
                changed = true;
                d[i] *= f;
                for j in 0..n {
                    // `A`'s diagonal is unchanged (scaled up first, it could overflow before the division).
                    if j != i {
                        a[(j, i)] *= f;
                        a[(i, j)] /= f;
                    }
                    q[(j, i)] *= f;
                    q[(i, j)] *= f;
                    g[(j, i)] /= f;
                    g[(i, j)] /= f;
                }
            }
        }
        if !changed {
            break;
        }
    }
    d
}

/// The solution `x` with gain `k` as a [`Riccati`], once every eigenvalue of `A − BK` is stable in `domain`.
pub(crate) fn stabilising_solution(
    domain: Domain,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    x: DMatrix<f64>,
    k: DMatrix<f64>,
    relative_residual: f64,
    refinement_steps: usize,
) -> Result<Riccati, RiccatiError> {
    let closed_loop = a - b * &k;
    let closed_loop_eigenvalues = eigenvalues(&closed_loop)?;
    // A stabilising X puts the closed loop clearly inside; only rounding-level margins (relative to the closed
    // loop's own scale) are tolerated here.
    let scale = pbh::stability_scale(&closed_loop, domain);
    if let Some(&eigenvalue) = closed_loop_eigenvalues
        .iter()
        .find(|l| !domain.is_stable(**l, scale))
    {
        return Err(RiccatiError::ClosedLoopUnstable { eigenvalue });
    }
    Ok(Riccati {
        x,
        k,
        closed_loop_eigenvalues,
        relative_residual,
        refinement_steps,
    })
}

/// Refuses a solution with non-finite entries: out of range when some entry is infinite, else (NaN) a failure
/// to converge.
pub(crate) fn finite_solution(x: &DMatrix<f64>, iterations: usize) -> Result<(), RiccatiError> {
    if x.iter().all(|v| v.is_finite()) {
        Ok(())
    } else if x.iter().any(|v| v.is_infinite()) {
        Err(RiccatiError::OutOfRange {
            what: "the solution X",
            iterations,
        })
    } else {
        Err(RiccatiError::NoConvergence {
            residual: f64::INFINITY,
            iterations,
        })
    }
}

/// The error for iterates that left the range of f64: what [`Problem::diagnose`] finds in the data (a mode that
/// cannot be stabilised or detected) or, failing that, [`RiccatiError::OutOfRange`].
pub(crate) fn overflowed(
    p: &Problem,
    domain: Domain,
    what: &'static str,
    iterations: usize,
) -> RiccatiError {
    match p.diagnose(domain, f64::INFINITY, iterations) {
        RiccatiError::NoConvergence { .. } => RiccatiError::OutOfRange { what, iterations },
        found => found,
    }
}
