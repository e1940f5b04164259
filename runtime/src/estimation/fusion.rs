//! Minimum-variance weighted fusion of `N` unbiased, independent sensors of one quantity (paper 001,
//! Eqs. 22–28).
//!
//! Each sensor reads `Z_j = Z + n_j` with noise variance `σ_j²` (Eqs. 22, 23). The fused estimate
//! `Ẑ = Σ W_j Z_j` with `Σ W_j = 1` (Eq. 24) has variance `σ² = Σ W_j² σ_j²` (Eq. 25); minimising it with a
//! Lagrange multiplier (Eq. 26) gives
//!
//! `W_j = 1 / (σ_j² Σᵢ 1/σᵢ²)` (Eq. 27), and then `σ² = 1 / Σᵢ 1/σᵢ²`, below every `σ_j²`.
//!
//! The variances come from a test rig that knows the true signal: Eq. 28 estimates each sensor's variance as
//! `E = Σ (angle_n − standard_n)² / (n₂ − n₁)` over samples `n₁..=n₂`, i.e. the sum of `n₂ − n₁ + 1` squared
//! errors divided by one less than their number. [`ErrorVariance`] follows the paper (divisor `count − 1`).
//!
//! When a sensor's reading is NaN or infinite, [`WeightedFusion::fuse`] leaves it out and renormalises Eq. 27
//! over the remaining sensors (the minimum-variance weights of that subset) and reports how many were left out.
//!
//! Eq. 27 is evaluated as `W_j = (σ²_min / σ_j²) / Σᵢ (σ²_min / σᵢ²)`, which is the same number but has every
//! ratio in `(0, 1]` and the sum in `[1, N]`: the reciprocals `1/σ²` of tiny variances would overflow, and
//! the sum `Σ Z_j / σ_j²` of large readings would too. The fused value `Σ W_j Z_j` is a convex combination, so
//! it lies between the readings and cannot overflow. Variances must be normal positive numbers (subnormal
//! ones, below `f64::MIN_POSITIVE` ≈ 2.2e-308, keep too few digits to weigh with).

use super::fault::EstimationError;
use nalgebra::SVector;

/// The minimum-variance weights of Eq. 27 for sensor variances `variances` (each positive and finite).
pub fn minimum_variance_weights<const N: usize>(
    variances: &SVector<f64, N>,
) -> Result<SVector<f64, N>, EstimationError> {
    check_variances(variances)?;
    let smallest = variances.min();
    let ratio_sum: f64 = variances.iter().map(|v| smallest / v).sum();
    Ok(variances.map(|v| (smallest / v) / ratio_sum))
}

/// The variance `Σ W_j² σ_j²` of a weighted fusion (Eq. 25).
pub fn fused_variance<const N: usize>(
    weights: &SVector<f64, N>,
    variances: &SVector<f64, N>,
) -> f64 {
    weights
        .iter()
        .zip(variances.iter())
        .map(|(w, v)| w * w * v)
        .sum()
}

fn check_variances<const N: usize>(variances: &SVector<f64, N>) -> Result<(), EstimationError> {
    if N == 0 {
        return Err(EstimationError::NoFiniteMeasurement { sensors: 0 });
    }
    for &v in variances.iter() {
        if !(v >= f64::MIN_POSITIVE && v.is_finite()) {
            return Err(EstimationError::InvalidSetting {
                name: "sensor variance",
                value: v,
                reason: "a sensor variance must be a positive, finite, normal number (at least 2.2e-308)",
            });
        }
    }
    Ok(())
}

/// A fused reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fused {
    /// `Ẑ = Σ W_j Z_j` over the sensors used.
    pub value: f64,
    /// Its variance `1 / Σ 1/σ_j²` over the sensors used.
    pub variance: f64,
    /// How many sensors were left out because their reading was not finite.
    pub excluded: usize,
}

/// Fusion of `N` sensors with fixed noise variances.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedFusion<const N: usize> {
    variances: SVector<f64, N>,
    weights: SVector<f64, N>,
}

impl<const N: usize> WeightedFusion<N> {
    /// Fusion for sensors with noise variances `variances`.
    pub fn new(variances: SVector<f64, N>) -> Result<Self, EstimationError> {
        let weights = minimum_variance_weights(&variances)?;
        Ok(WeightedFusion { variances, weights })
    }

    /// The weights of Eq. 27 when every sensor reads.
    pub fn weights(&self) -> &SVector<f64, N> {
        &self.weights
    }

    /// The fused variance when every sensor reads.
    pub fn variance(&self) -> f64 {
        fused_variance(&self.weights, &self.variances)
    }

    /// Fuses one reading per sensor; non-finite readings are left out. An error when none is finite.
    pub fn fuse(&self, readings: &SVector<f64, N>) -> Result<Fused, EstimationError> {
        let used = || {
            readings
                .iter()
                .zip(self.variances.iter())
                .filter(|(z, _)| z.is_finite())
        };
        let excluded = N - used().count();
        let Some(smallest) = used().map(|(_, &v)| v).reduce(f64::min) else {
            return Err(EstimationError::NoFiniteMeasurement { sensors: N });
        };
        let ratio_sum: f64 = used().map(|(_, v)| smallest / v).sum();
        let value: f64 = used().map(|(z, v)| (smallest / v) / ratio_sum * z).sum();
        if !value.is_finite() {
            // Only possible for readings within rounding of f64::MAX.
            return Err(EstimationError::Overflow {
                filter: "weighted fusion",
                quantity: "fused value",
            });
        }
        Ok(Fused {
            value,
            variance: smallest / ratio_sum,
            excluded,
        })
    }
}

/// The error variance of a sensor against a known reference signal (Eq. 28).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorVariance {
    sum_sq: f64,
    count: usize,
}

impl ErrorVariance {
    /// An empty accumulator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds a sample; a pair with a non-finite value, or whose squared error would overflow the sum, is
    /// skipped and `false` returned.
    pub fn push(&mut self, measured: f64, reference: f64) -> bool {
        let e = measured - reference;
        let sum_sq = self.sum_sq + e * e;
        if !sum_sq.is_finite() {
            return false;
        }
        self.sum_sq = sum_sq;
        self.count += 1;
        true
    }

    /// The number of samples used.
    pub fn count(&self) -> usize {
        self.count
    }

    /// `Σ e² / (count − 1)` as in Eq. 28; `None` with fewer than two samples.
    pub fn variance(&self) -> Option<f64> {
        (self.count >= 2).then(|| self.sum_sq / (self.count - 1) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    /// Eq. 27 by hand for σ² = (1, 4, 0.25): Σ 1/σ² = 1 + 0.25 + 4 = 5.25, so W = (1/5.25, 0.25/5.25, 4/5.25)
    /// = (0.19047619…, 0.04761904…, 0.76190476…), and the fused variance 1/5.25 = 0.19047619….
    #[test]
    fn weights_match_hand_computation_of_eq_27() {
        let var = Vector3::new(1.0, 4.0, 0.25);
        let w = minimum_variance_weights(&var).unwrap();
        let expected = Vector3::new(4.0 / 21.0, 1.0 / 21.0, 16.0 / 21.0);
        assert!((w - expected).amax() < 1e-15, "{w}");
        assert!((w.sum() - 1.0).abs() < 1e-15);
        // Eq. 25 at the optimum equals 1/Σ(1/σ²) and is below the best sensor's variance.
        let fv = fused_variance(&w, &var);
        assert!((fv - 4.0 / 21.0).abs() < 1e-15);
        assert!(fv < 0.25);
        // Any other weights summing to one give a larger Eq. 25 variance.
        let other = Vector3::new(0.2, 0.05, 0.75);
        assert!(fused_variance(&other, &var) > fv);
    }

    #[test]
    fn fusing_two_sensors_and_dropping_a_nan_reading() {
        // σ² = (0.01, 0.04): W = (0.8, 0.2); readings 1.0 and 2.0 fuse to 1.2 with variance 0.008.
        let f = WeightedFusion::new(Vector2::new(0.01, 0.04)).unwrap();
        let r = f.fuse(&Vector2::new(1.0, 2.0)).unwrap();
        assert!((r.value - 1.2).abs() < 1e-15 && (r.variance - 0.008).abs() < 1e-15);
        assert_eq!(r.excluded, 0);
        let r = f.fuse(&Vector2::new(f64::NAN, 2.0)).unwrap();
        assert_eq!((r.value, r.variance, r.excluded), (2.0, 0.04, 1));
        assert!(matches!(
            f.fuse(&Vector2::new(f64::NAN, f64::INFINITY)),
            Err(EstimationError::NoFiniteMeasurement { sensors: 2 })
        ));
        assert!(WeightedFusion::new(Vector2::new(0.0, 1.0)).is_err());
        assert!(WeightedFusion::new(Vector2::new(f64::NAN, 1.0)).is_err());
    }

    /// Monte Carlo check of the whole chain: variances estimated with Eq. 28 from a known signal, weights from
    /// Eq. 27, and the fused error variance below both sensors' (the paper's E_fusion < E_IMU, E_vision).
    #[test]
    fn estimated_variances_give_a_fusion_better_than_each_sensor() {
        let mut rng = crate::noise::Rng::new(5);
        let (s1, s2) = (0.02, 0.05);
        let mut ev = [ErrorVariance::new(), ErrorVariance::new()];
        for n in 0..4000 {
            let truth = (n as f64 * 0.01).sin();
            ev[0].push(truth + rng.gaussian(0.0, s1), truth);
            ev[1].push(truth + rng.gaussian(0.0, s2), truth);
        }
        let v = Vector2::new(ev[0].variance().unwrap(), ev[1].variance().unwrap());
        // Sample variances within 5 % of the truth (standard error √(2/4000) ≈ 2.2 %).
        assert!((v[0] / (s1 * s1) - 1.0).abs() < 0.05 && (v[1] / (s2 * s2) - 1.0).abs() < 0.05);
        let f = WeightedFusion::new(v).unwrap();
        let mut fused = ErrorVariance::new();
        for n in 0..4000 {
            let truth = (n as f64 * 0.013).cos();
            let z = Vector2::new(truth + rng.gaussian(0.0, s1), truth + rng.gaussian(0.0, s2));
            fused.push(f.fuse(&z).unwrap().value, truth);
        }
        let e = fused.variance().unwrap();
        // Theory: 1/(1/0.0004 + 1/0.0025) = 3.448e-4.
        assert!((e / 3.448e-4 - 1.0).abs() < 0.06, "{e}");
        assert!(e < s1 * s1);
    }

    #[test]
    fn eq_28_divides_by_count_minus_one() {
        let mut ev = ErrorVariance::new();
        assert_eq!(ev.variance(), None);
        for (m, r) in [(1.0, 0.0), (0.0, 2.0), (3.0, 3.0)] {
            ev.push(m, r);
        }
        assert!(!ev.push(f64::NAN, 0.0));
        // (1 + 4 + 0) / (3 − 1) = 2.5
        assert_eq!(ev.variance(), Some(2.5));
    }
}
