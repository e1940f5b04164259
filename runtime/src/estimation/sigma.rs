//! Scaled sigma points and weights of Wan and van der Merwe (paper 000, Eqs. 13 and 20), and the unscented
//! transform (Eqs. 17–19, 21–22).
//!
//! For a state of dimension `L` (here `N`), `λ = α²(L + κ) − L` and `γ = √(L + λ)`. The `2L + 1` points are
//! `χ₀ = x̂`, `χᵢ = x̂ + γ Sᵢ`, `χ_{L+i} = x̂ − γ Sᵢ`, where `Sᵢ` is column `i` of the lower Cholesky factor of
//! `P` (the same points as filterpy's `MerweScaledSigmaPoints`, whose rows of the upper factor of `(L+λ)P` are
//! these columns). The weights are `W₀⁽ᵐ⁾ = λ/(L+λ)`, `W₀⁽ᶜ⁾ = λ/(L+λ) + 1 − α² + β` and
//! `Wᵢ⁽ᵐ⁾ = Wᵢ⁽ᶜ⁾ = 1/(2(L+λ))` for `i ≥ 1`.
//!
//! **Paper inconsistency.** Eq. 20 of paper 000 prints `Wᵢ = λ/(2(L+λ))`; with that the mean weights do not
//! sum to one (for `α = 1e-3` they sum to about `−2·10⁶`), so the mean of Eq. 17 would be wrong. We follow
//! Wan and van der Merwe (2000), the paper's reference \[51\], with `1/(2(L+λ))`.
//!
//! Because stable Rust cannot write `2N + 1` as a const generic, the number of points is a second parameter
//! `NS`; [`SigmaPoints::new`] refuses any `NS ≠ 2N + 1` at compile time:
//!
//! ```compile_fail
//! // 3 states need 7 sigma points, not 6: this does not build.
//! let _ = bgc_runtime::estimation::SigmaPoints::<3, 6>::new(1.0, 2.0, 0.0);
//! ```
//!
//! ```
//! let points = bgc_runtime::estimation::SigmaPoints::<3, 7>::new(1.0, 2.0, 0.0).unwrap();
//! // α = 1, κ = 0: λ = 0, so W₀⁽ᵐ⁾ = 0 and the other six weights are 1/6.
//! assert_eq!(points.mean_weights()[0], 0.0);
//! assert!((points.mean_weights().sum() - 1.0).abs() < 1e-15);
//! ```

use super::dense::{cholesky_lower, cholesky_lower_into};
use super::fault::EstimationError;
use nalgebra::{SMatrix, SVector};

/// A user-supplied weighted mean of sigma points (e.g. a circular mean for angles).
pub type MeanFn<const N: usize, const NS: usize> =
    fn(&SMatrix<f64, N, NS>, &SVector<f64, NS>) -> SVector<f64, N>;
/// A user-supplied residual `a − b` (e.g. wrapped to (−π, π] for angles).
pub type ResidualFn<const N: usize> = fn(&SVector<f64, N>, &SVector<f64, N>) -> SVector<f64, N>;

/// The plain weighted mean `Σ Wᵢ χᵢ`.
pub fn weighted_mean<const N: usize, const NS: usize>(
    points: &SMatrix<f64, N, NS>,
    wm: &SVector<f64, NS>,
) -> SVector<f64, N> {
    points * wm
}

/// The plain residual `a − b`.
pub fn subtract<const N: usize>(a: &SVector<f64, N>, b: &SVector<f64, N>) -> SVector<f64, N> {
    a - b
}

/// Merwe scaled sigma points: the parameters and the weights they give.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SigmaPoints<const N: usize, const NS: usize> {
    alpha: f64,
    beta: f64,
    kappa: f64,
    lambda: f64,
    wm: SVector<f64, NS>,
    wc: SVector<f64, NS>,
}

impl<const N: usize, const NS: usize> SigmaPoints<N, NS> {
    const SIZE_CHECK: () = assert!(NS == 2 * N + 1, "NS must equal 2 N + 1");

    /// The weights for spread `alpha` (> 0), prior knowledge `beta` (2 for Gaussians) and secondary scaling
    /// `kappa`; `L + λ = α²(L + κ)` must be positive.
    pub fn new(alpha: f64, beta: f64, kappa: f64) -> Result<Self, EstimationError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SIZE_CHECK;
        if !(alpha > 0.0 && alpha.is_finite()) {
            return Err(EstimationError::InvalidSetting {
                name: "alpha",
                value: alpha,
                reason: "alpha must be positive and finite",
            });
        }
        if !beta.is_finite() {
            return Err(EstimationError::InvalidSetting {
                name: "beta",
                value: beta,
                reason: "beta must be finite",
            });
        }
        let n = N as f64;
        let lambda = alpha * alpha * (n + kappa) - n;
        let spread = n + lambda;
        if !(spread > 0.0 && spread.is_finite()) {
            return Err(EstimationError::InvalidSetting {
                name: "kappa",
                value: kappa,
                reason: "L + lambda = alpha^2 (L + kappa) must be positive",
            });
        }
        let c = 0.5 / spread;
        let mut wm = SVector::<f64, NS>::repeat(c);
        let mut wc = wm;
        wm[0] = lambda / spread;
        wc[0] = lambda / spread + (1.0 - alpha * alpha + beta);
        let amplification: f64 = wm.iter().map(|w| w.abs()).sum();
        let mean_rounding = NS as f64 * f64::EPSILON * amplification;
        if mean_rounding >= 1.0 || mean_rounding.is_nan() {
            return Err(EstimationError::InvalidSetting {
                name: "alpha",
                value: alpha,
                reason: "the mean weights cancel so strongly (sum of |W| times NS eps >= 1) that the \
                         sigma-point mean has no correct digit; increase alpha or kappa",
            });
        }
        Ok(SigmaPoints {
            alpha,
            beta,
            kappa,
            lambda,
            wm,
            wc,
        })
    }

    /// The mean weights `W⁽ᵐ⁾`.
    pub fn mean_weights(&self) -> &SVector<f64, NS> {
        &self.wm
    }

    /// The covariance weights `W⁽ᶜ⁾`.
    pub fn covariance_weights(&self) -> &SVector<f64, NS> {
        &self.wc
    }

    /// `Σ |W⁽ᵐ⁾ᵢ|`, the factor by which the weights' cancellation amplifies the rounding of a weighted mean
    /// (1 for `α² (L + κ) ≥ L`, about `2/α²` for small `α` and `κ = 0`). The filters estimate from it the
    /// rounding error of every covariance they form and refuse a step that would keep fewer than four significant
    /// digits ([`EstimationError::PrecisionLoss`]); weights with `NS · ε · Σ|W| ≥ 1` are refused here.
    pub fn rounding_amplification(&self) -> f64 {
        self.wm.iter().map(|w| w.abs()).sum()
    }

    /// `λ = α²(L + κ) − L`.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }

    /// `γ = √(L + λ)`, the scale of the sigma-point spread.
    pub fn gamma(&self) -> f64 {
        (N as f64 + self.lambda).sqrt()
    }

    /// `(α, β, κ)`.
    pub fn parameters(&self) -> (f64, f64, f64) {
        (self.alpha, self.beta, self.kappa)
    }

    /// The sigma points (columns) of mean `x` and covariance `p`; an error when `p` is not positive definite.
    pub fn generate(
        &self,
        x: &SVector<f64, N>,
        p: &SMatrix<f64, N, N>,
    ) -> Result<SMatrix<f64, N, NS>, EstimationError> {
        let s = cholesky_lower(p).ok_or(EstimationError::NotPositiveDefinite {
            name: "covariance for the sigma points",
            kind: "definite",
        })?;
        Ok(self.generate_from_factor(x, &s))
    }

    /// [`Self::generate`] written into `chi`, with the Cholesky factor of `p` in `factor` (any contents;
    /// overwritten): no `N × N` or `N × NS` value on the stack, for a filter that keeps them on the heap.
    pub(crate) fn generate_into(
        &self,
        x: &SVector<f64, N>,
        p: &SMatrix<f64, N, N>,
        factor: &mut SMatrix<f64, N, N>,
        chi: &mut SMatrix<f64, N, NS>,
    ) -> Result<(), EstimationError> {
        // The factorisation writes the lower triangle only; the points read whole columns.
        factor.fill(0.0);
        if !cholesky_lower_into(p, factor) {
            return Err(EstimationError::NotPositiveDefinite {
                name: "covariance for the sigma points",
                kind: "definite",
            });
        }
        self.generate_from_factor_into(x, factor, chi);
        Ok(())
    }

    /// The sigma points from a square-root factor `s` with `s sᵀ = P`.
    pub fn generate_from_factor(
        &self,
        x: &SVector<f64, N>,
        s: &SMatrix<f64, N, N>,
    ) -> SMatrix<f64, N, NS> {
        let mut chi = SMatrix::<f64, N, NS>::zeros();
        self.generate_from_factor_into(x, s, &mut chi);
        chi
    }

    /// [`Self::generate_from_factor`] written into `chi`.
    pub(crate) fn generate_from_factor_into(
        &self,
        x: &SVector<f64, N>,
        s: &SMatrix<f64, N, N>,
        chi: &mut SMatrix<f64, N, NS>,
    ) {
        let g = self.gamma();
        chi.set_column(0, x);
        for i in 0..N {
            let d = s.column(i) * g;
            chi.set_column(1 + i, &(x + d));
            chi.set_column(1 + N + i, &(x - d));
        }
    }
}

/// The unscented transform: mean (via `mean`) and covariance `Σ W⁽ᶜ⁾ rᵢ rᵢᵀ` of the points, with residuals
/// `rᵢ = residual(χᵢ, mean)`.
pub(crate) fn unscented_transform<const N: usize, const NS: usize>(
    points: &SMatrix<f64, N, NS>,
    wm: &SVector<f64, NS>,
    wc: &SVector<f64, NS>,
    mean: MeanFn<N, NS>,
    residual: ResidualFn<N>,
) -> (SVector<f64, N>, SMatrix<f64, N, N>) {
    let mut cov = SMatrix::<f64, N, N>::zeros();
    let m = unscented_transform_into(points, wm, wc, mean, residual, &mut cov);
    (m, cov)
}

/// [`unscented_transform`] with the covariance written into `cov` (any contents; overwritten) and the mean
/// returned: each term `(rₐ r_b) W⁽ᶜ⁾ᵢ` added in place, without the `N × N` products `rᵢ rᵢᵀ`.
pub(crate) fn unscented_transform_into<const N: usize, const NS: usize>(
    points: &SMatrix<f64, N, NS>,
    wm: &SVector<f64, NS>,
    wc: &SVector<f64, NS>,
    mean: MeanFn<N, NS>,
    residual: ResidualFn<N>,
    cov: &mut SMatrix<f64, N, N>,
) -> SVector<f64, N> {
    let m = mean(points, wm);
    cov.fill(0.0);
    for i in 0..NS {
        let r = residual(&points.column(i).into_owned(), &m);
        for b in 0..N {
            for a in 0..N {
                cov[(a, b)] += r[a] * r[b] * wc[i];
            }
        }
    }
    m
}

/// The estimated rounding error of each diagonal entry of `Σ W⁽ᶜ⁾ rᵢ rᵢᵀ`, `rᵢ = residual(pointsᵢ, mean)`.
///
/// The weighted mean of entry `j` is known to `δⱼ = NS ε Σ |W⁽ᵐ⁾ᵢ| |Zⱼᵢ|` (the rounding bound of a dot
/// product; the weights' cancellation is the factor `Σ |W⁽ᵐ⁾|`). An error `δ` common to all residuals changes
/// the covariance by `−2 δ Σ W⁽ᶜ⁾ᵢ rⱼᵢ + δ² Σ W⁽ᶜ⁾ᵢ`, and the weighted sum itself is known to
/// `NS ε Σ |W⁽ᶜ⁾ᵢ| rⱼᵢ²`; the estimate is the sum of their magnitudes.
pub(crate) fn rounding_floor<const N: usize, const NS: usize>(
    points: &SMatrix<f64, N, NS>,
    mean: &SVector<f64, N>,
    wm: &SVector<f64, NS>,
    wc: &SVector<f64, NS>,
    residual: ResidualFn<N>,
) -> SVector<f64, N> {
    let eps = NS as f64 * f64::EPSILON;
    let wc_sum: f64 = wc.sum();
    let mut floor = SVector::<f64, N>::zeros();
    let (mut weighted_residual, mut sum_error) = (SVector::<f64, N>::zeros(), floor);
    let mut delta = floor;
    for i in 0..NS {
        let r = residual(&points.column(i).into_owned(), mean);
        for j in 0..N {
            delta[j] += eps * (wm[i] * points[(j, i)]).abs();
            weighted_residual[j] += wc[i] * r[j];
            sum_error[j] += eps * (wc[i] * r[j] * r[j]).abs();
        }
    }
    for j in 0..N {
        floor[j] = 2.0 * (weighted_residual[j] * delta[j]).abs()
            + (wc_sum * delta[j] * delta[j]).abs()
            + sum_error[j];
    }
    floor
}

/// The cross covariance `Σ W⁽ᶜ⁾ (χᵢ − x)(Yᵢ − y)ᵀ`.
pub(crate) fn cross_covariance<const N: usize, const M: usize, const NS: usize>(
    xs: &SMatrix<f64, N, NS>,
    x: &SVector<f64, N>,
    ys: &SMatrix<f64, M, NS>,
    y: &SVector<f64, M>,
    wc: &SVector<f64, NS>,
    residual_x: ResidualFn<N>,
    residual_y: ResidualFn<M>,
) -> SMatrix<f64, N, M> {
    let mut c = SMatrix::<f64, N, M>::zeros();
    for i in 0..NS {
        let dx = residual_x(&xs.column(i).into_owned(), x);
        let dy = residual_y(&ys.column(i).into_owned(), y);
        c += dx * dy.transpose() * wc[i];
    }
    c
}

/// Index of the first column with a non-finite entry.
pub(crate) fn first_bad_column<const N: usize, const NS: usize>(
    m: &SMatrix<f64, N, NS>,
) -> Option<usize> {
    (0..NS).find(|&j| m.column(j).iter().any(|v| !v.is_finite()))
}
