//! Certificates that make the `O(n³)` definiteness test of a Kalman step's covariance unnecessary.
//!
//! The filter keeps its covariance symmetric positive definite: after each step it factorises the result
//! (`dense::positive_definite_in`) and repairs it if that fails. When the noise covariances bound the smallest
//! eigenvalue of the exact result away from zero by more than the rounding error of the computed one, the
//! computed result is positive definite by Weyl's inequality (`|λᵢ(X + E) − λᵢ(X)| ≤ ‖E‖₂` for symmetric `X`,
//! `E`) and the test is skipped; the bounds below cost `O(n m)` per step. Each asks the same margin the test
//! would: the eigenvalue bound must exceed twice the rounding bound. Norms are Frobenius norms (`‖·‖₂ ≤ ‖·‖_F`,
//! submultiplicative), and `‖P‖_F ≤ tr P` for a positive-definite `P`.

use super::super::dense::{symmetric_eigen_in_place, with_square_scratch};
use nalgebra::{SMatrix, SVector};

/// A magnitude whose sums of a few terms, rounded up, stay far below `f64::MAX`: a certificate whose bound on the
/// entries of the result is below it also certifies that every entry is finite.
const NO_OVERFLOW: f64 = f64::MAX / 16.0;

/// `γₖ = k ε / (1 − k ε)` (Higham's bound for a sum of `k` rounded terms), rounded up to `(k + 1) ε`.
fn gamma(k: usize) -> f64 {
    (k as f64 + 1.0) * f64::EPSILON
}

/// The smallest eigenvalue of a symmetric matrix less its own rounding error (`n ε ‖M‖_F`), or `−∞` when
/// the eigenvalues cannot be computed; not positive for a singular matrix. The decomposition works in two
/// scratch matrices (on the heap for a large `N`).
fn smallest_eigenvalue<const N: usize>(m: &SMatrix<f64, N, N>) -> f64 {
    let smallest = with_square_scratch(|a: &mut SMatrix<f64, N, N>| {
        a.copy_from(m);
        with_square_scratch(|v| symmetric_eigen_in_place(a, v))
    });
    smallest.map_or(f64::NEG_INFINITY, |values| values.min()) - N as f64 * f64::EPSILON * m.norm()
}

/// The time update `P⁻ = A P Aᵀ + Q`: `A P Aᵀ ⪰ 0`, so `λ_min(A P Aᵀ + Q) ≥ λ_min(Q)`, and the rounding error
/// `E` of the computed `P⁻` is bounded entrywise by `γ (|A| |P| |A|ᵀ + |Q|)`, `γ = γ_{2n+1}` (two products of
/// length `n` and a sum), so `‖E‖₂ ≤ γ (‖A‖_F² tr P + ‖Q‖_F)`. When `λ_min(Q)` exceeds twice that bound, the
/// computed `P⁻` is positive definite with `λ_min ≥ λ_min(Q) − ‖E‖₂`.
#[derive(Clone, Copy, Debug)]
pub(super) struct DefinitePrediction {
    /// `λ_min(Q)` less its own rounding error; not positive for a singular `Q`.
    q_min: f64,
    a_frobenius_sq: f64,
    q_frobenius: f64,
    gamma: f64,
}

impl DefinitePrediction {
    pub(super) fn of<const NX: usize>(a: &SMatrix<f64, NX, NX>, q: &SMatrix<f64, NX, NX>) -> Self {
        DefinitePrediction {
            q_min: smallest_eigenvalue(q),
            a_frobenius_sq: a.norm_squared(),
            q_frobenius: q.norm(),
            gamma: gamma(2 * NX + 1),
        }
    }

    /// A lower bound on `λ_min(fl(A P Aᵀ + Q))` for every positive-definite `P` with trace `trace_p`, when
    /// it is positive with the margin of the definiteness test; `None` when the test must run. A bound also
    /// means that every entry of the computed `P⁻` is finite: each partial sum of `T = P Aᵀ` is at most about
    /// `‖A‖_F tr P` and each of `A T + Q` about `‖A‖_F² tr P + ‖Q‖_F`, both below
    /// `(‖A‖_F² + 1) tr P + ‖Q‖_F`, which is required to be far below `f64::MAX`.
    pub(super) fn eigenvalue_floor(&self, trace_p: f64) -> Option<f64> {
        let bound = self.gamma * (self.a_frobenius_sq * trace_p + self.q_frobenius);
        let size = (self.a_frobenius_sq + 1.0) * trace_p + self.q_frobenius;
        (size < NO_OVERFLOW && self.q_min > 2.0 * bound).then_some(self.q_min - bound)
    }
}

/// The measurement update in the Joseph form `J(K) = (I − K C) P (I − K C)ᵀ + K R Kᵀ` for a symmetric `P`
/// with `λ_min(P) ≥ ℓ > 0` (the floor a certified prediction left) and `R` positive definite.
///
/// Exact part: `J(K) = J(K*) + (K − K*) S (K − K*)ᵀ ⪰ J(K*)` for *any* gain `K` (fixed, or the optimal `K*`
/// with rounding errors), and `J(K*) = (P⁻¹ + Cᵀ R⁻¹ C)⁻¹`, whose eigenvalues are at least
/// `μ = 1 / (1/ℓ + ‖C‖_F² / λ_min(R))`.
///
/// Rounding part, following the computation in `products`: `P Cᵀ` is computed with an error `E₁`,
/// `‖E₁‖ ≤ γₙ ‖P‖ ‖C‖`; the mirrored `S` with a symmetric error `F`,
/// `‖F‖ ≤ √2 (‖E₁‖ ‖C‖ + γₙ₊₁ (‖R‖ + ‖P Cᵀ‖ ‖C‖) + ‖R − Rᵀ‖/2)`; `W = P Cᵀ − K S` with `E₃`,
/// `‖E₃‖ ≤ γₘ₊₁ (‖P Cᵀ‖ + ‖K‖ ‖S‖)`; and the triangle of `P − K (P Cᵀ)ᵀ − W Kᵀ` with `E₄`,
/// `‖E₄‖ ≤ γ₂ₘ₊₁ (‖P‖ + ‖K‖ (‖P Cᵀ‖ + ‖W‖))`. Substituting, the computed result is
/// `J(K) − K E₁ᵀ − E₁ Kᵀ + K F Kᵀ + mirror(E₄ − E₃ Kᵀ)`, and mirroring the upper triangle at most multiplies a
/// Frobenius norm by `√2`, so its distance from `J(K)` is at most
/// `2 ‖K‖ ‖E₁‖ + ‖K‖² ‖F‖ + √2 (‖E₃‖ ‖K‖ + ‖E₄‖)`.
#[derive(Clone, Copy, Debug)]
pub(super) struct DefiniteUpdate {
    /// `λ_min(R)` less its rounding error; not positive when `R` is singular (then no certificate).
    r_min: f64,
    c_frobenius: f64,
    /// `‖C‖_F² / λ_min(R)`, the part of `1/μ` that does not change.
    c_sq_over_r_min: f64,
    r_frobenius: f64,
    r_asymmetry: f64,
    /// `γₙ`, `γₙ₊₁`, `γₘ₊₁` and `γ₂ₘ₊₁` for `n = NX`, `m = NY`, fixed by the sizes.
    gamma_n: f64,
    gamma_n1: f64,
    gamma_m1: f64,
    gamma_2m1: f64,
}

/// The norms of the quantities of one update that its rounding bound needs.
pub(super) struct UpdateNorms {
    pub(super) trace_p: f64,
    pub(super) pct: f64,
    pub(super) s: f64,
    pub(super) k: f64,
    pub(super) w: f64,
}

impl DefiniteUpdate {
    pub(super) fn of<const NX: usize, const NY: usize>(
        c: &SMatrix<f64, NY, NX>,
        r: &SMatrix<f64, NY, NY>,
    ) -> Self {
        let r_min = smallest_eigenvalue(r);
        DefiniteUpdate {
            r_min,
            c_frobenius: c.norm(),
            c_sq_over_r_min: c.norm_squared() / r_min,
            r_frobenius: r.norm(),
            r_asymmetry: (r - r.transpose()).norm(),
            gamma_n: gamma(NX),
            gamma_n1: gamma(NX + 1),
            gamma_m1: gamma(NY + 1),
            gamma_2m1: gamma(2 * NY + 1),
        }
    }

    /// Whether the computed Joseph-form result is positive definite with the margin of the test, given the
    /// eigenvalue floor `ell` of `P` (not positive: unknown) and the norms of the step.
    #[inline(always)]
    pub(super) fn holds(&self, ell: f64, n: &UpdateNorms) -> bool {
        if !(ell > 0.0 && self.r_min > 0.0) {
            return false;
        }
        let c = self.c_frobenius;
        let sqrt2 = std::f64::consts::SQRT_2;
        let e1 = self.gamma_n * n.trace_p * c;
        let f = sqrt2
            * (e1 * c + self.gamma_n1 * (self.r_frobenius + n.pct * c) + 0.5 * self.r_asymmetry);
        let e3 = self.gamma_m1 * (n.pct + n.k * n.s);
        let e4 = self.gamma_2m1 * (n.trace_p + n.k * (n.pct + n.w));
        let bound = 2.0 * n.k * e1 + n.k * n.k * f + sqrt2 * (e3 * n.k + e4);
        // Every partial sum of an entry of the result is at most `tr P + ‖K‖ (‖P Cᵀ‖ + ‖W‖)` (Cauchy–Schwarz
        // over the measurements), so below `NO_OVERFLOW` every entry is finite. NaN norms (a non-finite
        // quantity) fail both comparisons: the test then runs and reports them.
        let size = n.trace_p + n.k * (n.pct + n.w);
        // `μ > 2 bound` with `μ = 1 / (1/ℓ + ‖C‖²/λ_min(R))`, multiplied out by the positive `1/μ` and `ℓ` so
        // that a step divides by nothing.
        size < NO_OVERFLOW && ell > 2.0 * bound * (1.0 + ell * self.c_sq_over_r_min)
    }
}

/// The floor of the innovation covariance's Cholesky pivots, `NX ε (|C| |P| |C|ᵀ)ⱼⱼ + ε |Rⱼⱼ|` (the rounding
/// error with which `diag(C P Cᵀ + R)` is known: a pivot at or below it means `S` is singular to working
/// accuracy). Its `O(NX² NY)` sum is needed only for a pivot near it: for a positive-semidefinite `P`,
/// `|pₐ_b| ≤ √(pₐₐ p_bb) ≤ (pₐₐ + p_bb)/2`, so `(|C| |P| |C|ᵀ)ⱼⱼ ≤ (Σₐ |cⱼₐ| pₐₐ) (Σ_b |cⱼ_b|)`, an
/// `O(NX NY)` bound, and `Σₐ |cⱼₐ| pₐₐ ≤ maxₐ |cⱼₐ| tr P`, an `O(NY)` one given `tr P`; a pivot above twice
/// either bound is above the floor, and the tighter bound is computed only when the looser one is not enough.
#[derive(Clone, Copy, Debug)]
pub(super) struct InnovationFloor<const NY: usize> {
    /// `Σ_b |cⱼ_b|` for each measurement `j`.
    c_abs_row_sums: [f64; NY],
    /// `maxₐ |cⱼₐ| Σ_b |cⱼ_b|` for each measurement `j`.
    c_abs_row_max_sums: [f64; NY],
}

impl<const NY: usize> InnovationFloor<NY> {
    pub(super) fn of<const NX: usize>(c: &SMatrix<f64, NY, NX>) -> Self {
        let c_abs_row_sums = std::array::from_fn(|j| c.row(j).iter().map(|v| v.abs()).sum());
        InnovationFloor {
            c_abs_row_sums,
            c_abs_row_max_sums: std::array::from_fn(|j| {
                c.row(j).iter().fold(0.0_f64, |m, v| m.max(v.abs())) * c_abs_row_sums[j]
            }),
        }
    }

    /// Whether every pivot `pivots[j]` (`l_jj²` of the factor of `S`) lies above its floor; `ct` is `Cᵀ`, whose
    /// column `j` is row `j` of `C`, contiguous, and `trace_p` is `tr P`.
    #[inline(always)]
    pub(super) fn pivots_clear<const NX: usize>(
        &self,
        pivots: &SVector<f64, NY>,
        ct: &SMatrix<f64, NX, NY>,
        p: &SMatrix<f64, NX, NX>,
        trace_p: f64,
        r: &SMatrix<f64, NY, NY>,
    ) -> bool {
        let n = NX.max(1) as f64;
        let above =
            |j: usize, spread: f64| pivots[j] > 2.0 * f64::EPSILON * (n * spread + r[(j, j)].abs());
        (0..NY).all(|j| {
            above(j, self.c_abs_row_max_sums[j] * trace_p) || {
                let mut weighted_diagonal = 0.0;
                for (a, c) in ct.data.0[j].iter().enumerate() {
                    weighted_diagonal += c.abs() * p.data.0[a][a];
                }
                above(j, weighted_diagonal * self.c_abs_row_sums[j])
                    || pivots[j] > exact_floor(j, ct, p, r)
            }
        })
    }
}

/// `NX ε (|C| |P| |C|ᵀ)ⱼⱼ + ε |Rⱼⱼ|` by its `O(NX²)` sum, from `ct = Cᵀ`.
fn exact_floor<const NX: usize, const NY: usize>(
    j: usize,
    ct: &SMatrix<f64, NX, NY>,
    p: &SMatrix<f64, NX, NX>,
    r: &SMatrix<f64, NY, NY>,
) -> f64 {
    let mut spread = 0.0;
    for a in 0..NX {
        let mut row = 0.0;
        for b in 0..NX {
            row += p[(a, b)].abs() * ct[(b, j)].abs();
        }
        spread += ct[(a, j)].abs() * row;
    }
    f64::EPSILON * (NX.max(1) as f64 * spread + r[(j, j)].abs())
}

#[cfg(test)]
mod tests {
    use super::super::isa::Separate;
    use super::super::products::{
        InnovationFactor, covariance_times_ct, innovation_covariance, joseph,
    };
    use super::*;
    use crate::estimation::dense::{cholesky_lower, positive_definite, symmetric_eigen};

    /// Uniform numbers in `[−1, 1)` from a fixed seed (xorshift64*), so that every run sees the same cases.
    struct Numbers(u64);

    impl Numbers {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
            bits as f64 / (1u64 << 52) as f64 - 1.0
        }

        fn matrix<const R: usize, const C: usize>(&mut self, scale: f64) -> SMatrix<f64, R, C> {
            SMatrix::from_fn(|_, _| scale * self.next())
        }

        /// `G Gᵀ + floor I` with `G` of `N` rows, `K` columns and entries up to `spread`: symmetric, smallest
        /// eigenvalue at least `floor`, and about `floor` when `K < N`.
        fn definite<const N: usize, const K: usize>(
            &mut self,
            spread: f64,
            floor: f64,
        ) -> SMatrix<f64, N, N> {
            let g = self.matrix::<N, K>(spread);
            let mut m = g * g.transpose() + SMatrix::<f64, N, N>::identity() * floor;
            crate::estimation::dense::symmetrise(&mut m);
            m
        }
    }

    fn min_eigenvalue<const N: usize>(m: &SMatrix<f64, N, N>) -> f64 {
        symmetric_eigen(m).expect("finite").0.min()
    }

    /// The exact part of the update certificate: for random `P ⪰ ℓ I`, `R`, `C` and gains `K` that are far from
    /// optimal (random) or optimal, the Joseph covariance's smallest eigenvalue (by Jacobi, independently of
    /// the bound) is at least `μ = 1 / (1/ℓ + ‖C‖_F² / λ_min(R))`.
    #[test]
    fn the_joseph_covariance_of_any_gain_stays_above_the_bound() {
        let mut rng = Numbers(0x9e37_79b9_7f4a_7c15);
        for case in 0..300 {
            let p = rng.definite::<5, 3>(1.0, 10f64.powi(-(case % 7)));
            let r = rng.definite::<2, 2>(0.5, 1e-3);
            let c = rng.matrix::<2, 5>(2.0);
            let ell = min_eigenvalue(&p);
            let r_min = min_eigenvalue(&r);
            let mu = 1.0 / (1.0 / ell + c.norm_squared() / r_min);
            let pct = covariance_times_ct::<Separate, _, _>(&p, &c.transpose());
            let s = innovation_covariance::<Separate, _, _>(&pct, &c.transpose(), &r);
            let optimal =
                InnovationFactor::new(cholesky_lower(&s).unwrap()).gain::<Separate, _>(&pct);
            for k in [
                optimal,
                rng.matrix::<5, 2>(3.0),
                optimal + rng.matrix::<5, 2>(1e-3),
            ] {
                let mut out = SMatrix::zeros();
                joseph::<Separate, _, _>(&p, &k, &pct, &s, &mut out);
                let lowest = min_eigenvalue(&out);
                // Rounding of the Jacobi sweep and of the product: a few ε of the largest entry.
                let slack = 1e-12 * out.amax();
                assert!(
                    lowest >= mu - slack,
                    "case {case}: λ_min {lowest:e} < μ {mu:e}"
                );
            }
        }
    }

    /// The whole certificate: whenever it holds, the computed Joseph covariance passes the definiteness test
    /// and its smallest eigenvalue is above the rounding bound; it holds for well-conditioned cases and is
    /// refused without a floor for `P` or with a singular `R`.
    #[test]
    fn a_certified_update_is_definite_and_the_certificate_needs_a_floor_and_a_definite_r() {
        let mut rng = Numbers(0x2545_f491_4f6c_dd1d);
        let (mut certified, mut refused_indefinite) = (0, 0);
        for case in 0..400 {
            // From well conditioned to a smallest eigenvalue near the rounding of the largest.
            let floor = 10f64.powi(-(case % 17));
            let p = rng.definite::<6, 3>(1.0, floor);
            let r = rng.definite::<2, 1>(0.3, floor);
            let c = rng.matrix::<2, 6>(1.0);
            let ct = c.transpose();
            let pct = covariance_times_ct::<Separate, _, _>(&p, &ct);
            let s = innovation_covariance::<Separate, _, _>(&pct, &ct, &r);
            let Some(l) = cholesky_lower(&s) else {
                continue;
            };
            let k = InnovationFactor::new(l).gain::<Separate, _>(&pct);
            let mut out = SMatrix::zeros();
            let w = joseph::<Separate, _, _>(&p, &k, &pct, &s, &mut out);
            let norms = UpdateNorms {
                trace_p: p.trace(),
                pct: pct.norm(),
                s: s.norm(),
                k: k.norm(),
                w: w.norm(),
            };
            let certificate = DefiniteUpdate::of(&c, &r);
            // A lower bound on λ_min(P) as a certified prediction would leave it.
            let ell = min_eigenvalue(&p) * (1.0 - 1e-9);
            assert!(
                !certificate.holds(0.0, &norms),
                "case {case}: no floor, no certificate"
            );
            if certificate.holds(ell, &norms) {
                certified += 1;
                assert!(positive_definite(&out), "case {case}");
                assert!(min_eigenvalue(&out) > 0.0, "case {case}");
            } else if !positive_definite(&out) {
                refused_indefinite += 1;
            }
        }
        // Most cases are certified; near the rounding floor some are not, among them results that the
        // definiteness test refuses (so the cases reach the boundary the certificate must respect).
        assert!(certified > 250, "only {certified} of 400 certified");
        assert!(refused_indefinite > 0);
        let c = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
        let singular_r = DefiniteUpdate::of(&c, &SMatrix::<f64, 1, 1>::zeros());
        let norms = UpdateNorms {
            trace_p: 2.0,
            pct: 1.0,
            s: 1.0,
            k: 1.0,
            w: 1.0,
        };
        assert!(!singular_r.holds(1.0, &norms));
    }

    /// The innovation floor's `O(NX NY)` shortcut never changes a verdict: for pivots from far below to far
    /// above the exact floor, `pivots_clear` agrees with the comparison against the exact `O(NX² NY)` floor.
    #[test]
    fn the_innovation_floor_shortcut_gives_the_exact_verdict() {
        let mut rng = Numbers(0x1234_5678_9abc_def1);
        for case in 0..200 {
            let p = rng.definite::<4, 4>(10f64.powi(case % 5), 1e-6);
            let c = rng.matrix::<2, 4>(3.0);
            let r = rng.definite::<2, 2>(0.1, 1e-8);
            let floor = InnovationFloor::of(&c);
            let ct = c.transpose();
            let exact = [exact_floor(0, &ct, &p, &r), exact_floor(1, &ct, &p, &r)];
            for factor in [0.5, 0.999, 1.0, 1.001, 2.0, 10.0, 1e6] {
                let pivots = SVector::<f64, 2>::new(exact[0] * factor, 1.0);
                let expected = pivots[0] > exact[0] && pivots[1] > exact[1];
                assert_eq!(
                    floor.pivots_clear(&pivots, &ct, &p, p.trace(), &r),
                    expected,
                    "case {case}, factor {factor}"
                );
            }
        }
    }
}
