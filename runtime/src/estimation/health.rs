//! Filter health statistics of paper 000 (Table 7 and the three innovation criteria before it): the
//! innovations `ỹ = y − ŷ⁻` should be small, have zero mean and no autocorrelation except at lag zero; the
//! state errors should have about zero mean and mostly stay within the filter's own 1σ bounds.
//!
//! [`FilterHealth`] accumulates, without allocating:
//!
//! - the innovation mean per channel;
//! - the normalised autocorrelation of each innovation channel for lags `1..=NL`,
//!   `ρ(l) = Σ_{k≥l} (e_k − ē)(e_{k−l} − ē) / Σ_k (e_k − ē)²` (the biased estimator of `numpy.correlate` /
//!   MATLAB `autocorr`), and its mean over the lags, which is what we take Table 7's "mean correlation of
//!   residuals" to be (the paper does not define it; its Fig. 12 plots the normalised autocorrelation);
//! - the mean normalised innovation squared `NIS = ỹᵀ S⁻¹ ỹ`, which should be near `NY` for a consistent
//!   filter;
//! - when the true state is known (simulation), the mean state error per state and the fraction of steps on
//!   which `|x − x̂|` exceeded the 1σ bound `√P_ii` (about 32 % for a consistent Gaussian filter; the paper
//!   calls below 30 % good).
//!
//! The lag products are summed as they arrive and centred with the final mean, which is exact because
//! `Σ (a − ē)(b − ē) = Σ ab − ē Σ a − ē Σ b + n ē²` for each lag.

use super::dense::{cholesky_lower, cholesky_solve};
use super::fault::EstimationError;
use nalgebra::{SMatrix, SVector};

/// Health statistics for a filter with `NX` states and `NY` measurements, autocorrelation up to lag `NL`.
#[derive(Clone, Debug)]
pub struct FilterHealth<const NX: usize, const NY: usize, const NL: usize> {
    n_innov: usize,
    sum_e: SVector<f64, NY>,
    sum_e2: SVector<f64, NY>,
    /// Last `NL` innovations, column `(k mod NL)` holding `e_k`.
    history: SMatrix<f64, NY, NL>,
    lag_prod: SMatrix<f64, NY, NL>,
    lag_lead_sum: SMatrix<f64, NY, NL>,
    lag_trail_sum: SMatrix<f64, NY, NL>,
    lag_count: [usize; NL],
    sum_nis: f64,
    n_states: usize,
    sum_err: SVector<f64, NX>,
    outside: SVector<f64, NX>,
}

/// A summary in the layout of Table 7.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HealthReport<const NX: usize, const NY: usize> {
    pub innovation_mean: SVector<f64, NY>,
    pub mean_innovation_autocorrelation: SVector<f64, NY>,
    pub mean_nis: Option<f64>,
    pub state_error_mean: SVector<f64, NX>,
    pub fraction_outside_one_sigma: SVector<f64, NX>,
}

impl<const NX: usize, const NY: usize, const NL: usize> Default for FilterHealth<NX, NY, NL> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const NX: usize, const NY: usize, const NL: usize> FilterHealth<NX, NY, NL> {
    /// An empty accumulator.
    pub fn new() -> Self {
        FilterHealth {
            n_innov: 0,
            sum_e: SVector::zeros(),
            sum_e2: SVector::zeros(),
            history: SMatrix::zeros(),
            lag_prod: SMatrix::zeros(),
            lag_lead_sum: SMatrix::zeros(),
            lag_trail_sum: SMatrix::zeros(),
            lag_count: [0; NL],
            sum_nis: 0.0,
            n_states: 0,
            sum_err: SVector::zeros(),
            outside: SVector::zeros(),
        }
    }

    /// Records an innovation `e` with its covariance `s`. Non-finite values or a singular `s` are refused
    /// (the statistics stay as they were).
    pub fn record_innovation(
        &mut self,
        e: &SVector<f64, NY>,
        s: &SMatrix<f64, NY, NY>,
    ) -> Result<(), EstimationError> {
        if e.iter().any(|v| !v.is_finite()) {
            return Err(EstimationError::NonFiniteValue { what: "innovation" });
        }
        let singular = EstimationError::SingularInnovation {
            filter: "health monitor",
        };
        let ls = cholesky_lower(s).ok_or(singular.clone())?;
        let nis = e.dot(&cholesky_solve(&ls, e).ok_or(singular)?);
        // Accumulate into a copy (no allocation: every field is fixed-size) and keep it only if every sum is
        // still finite, so that one huge innovation cannot turn the statistics into inf or NaN.
        let mut next = self.clone();
        next.accumulate_innovation(e, nis);
        if !next.sums_finite() {
            return Err(EstimationError::NonFiniteValue {
                what: "innovation statistics (an innovation too large to square and sum)",
            });
        }
        *self = next;
        Ok(())
    }

    fn sums_finite(&self) -> bool {
        let finite = |m: &[f64]| m.iter().all(|v| v.is_finite());
        finite(self.sum_e.as_slice())
            && finite(self.sum_e2.as_slice())
            && finite(self.lag_prod.as_slice())
            && finite(self.lag_lead_sum.as_slice())
            && finite(self.lag_trail_sum.as_slice())
            && self.sum_nis.is_finite()
            && finite(self.sum_err.as_slice())
    }

    fn accumulate_innovation(&mut self, e: &SVector<f64, NY>, nis: f64) {
        let k = self.n_innov;
        for l in 1..=NL.min(k) {
            let col = (k - l) % NL;
            for c in 0..NY {
                let past = self.history[(c, col)];
                self.lag_prod[(c, l - 1)] += e[c] * past;
                self.lag_lead_sum[(c, l - 1)] += e[c];
                self.lag_trail_sum[(c, l - 1)] += past;
            }
            self.lag_count[l - 1] += 1;
        }
        if NL > 0 {
            self.history.set_column(k % NL, e);
        }
        self.sum_e += e;
        self.sum_e2 += e.component_mul(e);
        self.sum_nis += nis;
        self.n_innov += 1;
    }

    /// Records a state error `x_true − x̂` with the filter's covariance `p`; non-finite values are refused.
    pub fn record_state_error(
        &mut self,
        err: &SVector<f64, NX>,
        p: &SMatrix<f64, NX, NX>,
    ) -> Result<(), EstimationError> {
        if err.iter().chain(p.iter()).any(|v| !v.is_finite()) {
            return Err(EstimationError::NonFiniteValue {
                what: "state error or covariance",
            });
        }
        let sum_err = self.sum_err + err;
        if sum_err.iter().any(|v| !v.is_finite()) {
            return Err(EstimationError::NonFiniteValue {
                what: "state error statistics (a state error too large to sum)",
            });
        }
        self.sum_err = sum_err;
        for i in 0..NX {
            if err[i].abs() > p[(i, i)].max(0.0).sqrt() {
                self.outside[i] += 1.0;
            }
        }
        self.n_states += 1;
        Ok(())
    }

    /// The number of innovations recorded.
    pub fn innovation_count(&self) -> usize {
        self.n_innov
    }

    /// The mean innovation per channel (zero before any is recorded).
    pub fn innovation_mean(&self) -> SVector<f64, NY> {
        if self.n_innov == 0 {
            return SVector::zeros();
        }
        self.sum_e / self.n_innov as f64
    }

    /// The normalised autocorrelation `ρ(lag)` of channel `channel`; `None` for a lag outside `1..=NL`, a
    /// channel out of range, or too few samples.
    pub fn autocorrelation(&self, channel: usize, lag: usize) -> Option<f64> {
        if channel >= NY || lag == 0 || lag > NL || self.lag_count[lag - 1] == 0 {
            return None;
        }
        let n = self.n_innov as f64;
        let mean = self.sum_e[channel] / n;
        let c0 = self.sum_e2[channel] - n * mean * mean;
        if c0 <= 0.0 {
            return None;
        }
        let nl = self.lag_count[lag - 1] as f64;
        let cl = self.lag_prod[(channel, lag - 1)]
            - mean * self.lag_lead_sum[(channel, lag - 1)]
            - mean * self.lag_trail_sum[(channel, lag - 1)]
            + nl * mean * mean;
        Some(cl / c0)
    }

    /// The mean of `ρ(1..=NL)` per channel (zero where undefined).
    pub fn mean_autocorrelation(&self) -> SVector<f64, NY> {
        let mut out = SVector::<f64, NY>::zeros();
        for c in 0..NY {
            let (sum, count) = (1..=NL)
                .filter_map(|l| self.autocorrelation(c, l))
                .fold((0.0, 0usize), |(s, n), r| (s + r, n + 1));
            if count > 0 {
                out[c] = sum / count as f64;
            }
        }
        out
    }

    /// The mean NIS, `None` before any innovation.
    pub fn mean_nis(&self) -> Option<f64> {
        (self.n_innov > 0).then(|| self.sum_nis / self.n_innov as f64)
    }

    /// The mean state error per state.
    pub fn state_error_mean(&self) -> SVector<f64, NX> {
        if self.n_states == 0 {
            return SVector::zeros();
        }
        self.sum_err / self.n_states as f64
    }

    /// The fraction of recorded steps on which `|error_i| > √P_ii`, per state.
    pub fn fraction_outside_one_sigma(&self) -> SVector<f64, NX> {
        if self.n_states == 0 {
            return SVector::zeros();
        }
        self.outside / self.n_states as f64
    }

    /// All statistics in the layout of Table 7.
    pub fn report(&self) -> HealthReport<NX, NY> {
        HealthReport {
            innovation_mean: self.innovation_mean(),
            mean_innovation_autocorrelation: self.mean_autocorrelation(),
            mean_nis: self.mean_nis(),
            state_error_mean: self.state_error_mean(),
            fraction_outside_one_sigma: self.fraction_outside_one_sigma(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix1, Matrix2, Vector1, Vector2};

    /// Reference from numpy:
    /// ```python
    /// import numpy as np
    /// e = np.array([0.3, -1.2, 0.8, 0.1, -0.4, 1.5, -0.9, 0.2])
    /// d = e - e.mean(); c0 = d @ d
    /// [float((d[l:] @ d[:-l]) / c0) for l in (1, 2, 3)]
    /// # [-0.628690036900369, 0.09317343173431734, 0.2855166051660517]
    /// ```
    #[test]
    fn autocorrelation_matches_numpy() {
        let e = [0.3, -1.2, 0.8, 0.1, -0.4, 1.5, -0.9, 0.2];
        let numpy = [-0.628690036900369, 0.09317343173431734, 0.2855166051660517];
        let rho = |l: usize| numpy[l - 1];
        let mut h = FilterHealth::<1, 1, 3>::new();
        for v in e {
            h.record_innovation(&Vector1::new(v), &Matrix1::new(0.5))
                .unwrap();
        }
        for l in 1..=3 {
            let got = h.autocorrelation(0, l).unwrap();
            assert!((got - rho(l)).abs() < 1e-12, "lag {l}: {got} vs {}", rho(l));
        }
        assert!((h.innovation_mean()[0] - 0.05).abs() < 1e-15);
        // NIS = e²/0.5 averaged: Σe² = 5.44 → 5.44 / 0.5 / 8 = 1.36.
        assert!((h.mean_nis().unwrap() - 1.36).abs() < 1e-12);
        let mean_rho = (rho(1) + rho(2) + rho(3)) / 3.0;
        assert!((h.mean_autocorrelation()[0] - mean_rho).abs() < 1e-12);
        assert_eq!(h.autocorrelation(0, 4), None);
        assert_eq!(h.autocorrelation(1, 1), None);
    }

    #[test]
    fn state_error_statistics_and_refusals() {
        let mut h = FilterHealth::<2, 1, 2>::new();
        let p = Matrix2::new(1.0, 0.0, 0.0, 0.25);
        for e in [
            Vector2::new(0.5, 0.6),  // second outside 0.5
            Vector2::new(-1.5, 0.1), // first outside 1
            Vector2::new(0.1, -0.1),
            Vector2::new(0.3, 0.2),
        ] {
            h.record_state_error(&e, &p).unwrap();
        }
        assert!(
            h.record_state_error(&Vector2::new(f64::NAN, 0.0), &p)
                .is_err()
        );
        assert!((h.state_error_mean() - Vector2::new(-0.15, 0.2)).norm() < 1e-15);
        assert_eq!(h.fraction_outside_one_sigma(), Vector2::new(0.25, 0.25));
        assert!(
            h.record_innovation(&Vector1::new(f64::NAN), &Matrix1::new(1.0))
                .is_err()
        );
        assert!(
            h.record_innovation(&Vector1::new(1.0), &Matrix1::new(0.0))
                .is_err()
        );
        assert_eq!(h.innovation_count(), 0);
    }
}
