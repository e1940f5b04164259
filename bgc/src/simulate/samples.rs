//! Recorded input signals: samples at given times, replayed between them.
//!
//! A measured record gives an input at its sample times only. Between two samples the value is held (zero-order
//! hold, the way a logger records a digitally commanded signal) or interpolated linearly; before the first sample
//! the first value holds, after the last the last. The breakpoints of a held signal are the times at which its
//! value changes, so the integrator restarts there as at a `step`; a linearly interpolated signal only kinks, and
//! its derivative (the slope of each interval, 0 outside the record) is the signal [`Samples::derivative`].

use std::sync::Arc;

/// How a recorded signal is read between its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Replay {
    /// Each sample holds until the next.
    Hold,
    /// Straight lines between samples.
    Linear,
    /// The slope of the straight lines: the derivative of [`Replay::Linear`] (0 before the first sample and from
    /// the last on).
    Slope,
}

/// One signal of a record: strictly increasing finite times and their finite values, shared by its derivative.
#[derive(Clone, Debug, PartialEq)]
pub struct Samples {
    times: Arc<[f64]>,
    values: Arc<[f64]>,
    replay: Replay,
}

/// Why samples were refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SamplesError {
    #[error("a recorded signal needs at least one sample")]
    Empty,
    #[error("{times} sample times and {values} values")]
    Lengths { times: usize, values: usize },
    #[error("sample {index} is not finite")]
    NotFinite { index: usize },
    #[error(
        "sample time {index} does not follow the one before it; times must be strictly increasing"
    )]
    Unsorted { index: usize },
}

impl Samples {
    /// The signal of `values` at `times`, read as `replay` says.
    pub fn new(times: Vec<f64>, values: Vec<f64>, replay: Replay) -> Result<Samples, SamplesError> {
        if times.len() != values.len() {
            return Err(SamplesError::Lengths {
                times: times.len(),
                values: values.len(),
            });
        }
        if times.is_empty() {
            return Err(SamplesError::Empty);
        }
        let bad = |xs: &[f64]| xs.iter().position(|v| !v.is_finite());
        if let Some(index) = bad(&times).or_else(|| bad(&values)) {
            return Err(SamplesError::NotFinite { index });
        }
        if let Some(k) = times.windows(2).position(|w| w[1] <= w[0]) {
            return Err(SamplesError::Unsorted { index: k + 1 });
        }
        Ok(Samples {
            times: times.into(),
            values: values.into(),
            replay,
        })
    }

    /// The value at `t`.
    pub fn eval(&self, t: f64) -> f64 {
        // The sample at or before `t`: before the first, the first value holds.
        let Some(k) = self.times.partition_point(|&s| s <= t).checked_sub(1) else {
            return match self.replay {
                Replay::Slope => 0.0,
                _ => self.values.first().copied().unwrap_or(f64::NAN),
            };
        };
        let (v0, t0) = (self.values[k], self.times[k]);
        // From the last sample on, the last value holds.
        let (Some(&v1), Some(&t1)) = (self.values.get(k + 1), self.times.get(k + 1)) else {
            return match self.replay {
                Replay::Slope => 0.0,
                _ => v0,
            };
        };
        match self.replay {
            Replay::Hold => v0,
            Replay::Linear => {
                // The weighted mean, not `v0 + s (v1 − v0)`: the difference of two finite samples may overflow.
                let s = ((t - t0) / (t1 - t0)).clamp(0.0, 1.0);
                v0 * (1.0 - s) + v1 * s
            }
            Replay::Slope => (v1 - v0) / (t1 - t0),
        }
    }

    /// The time derivative: 0 for a held signal (a jump is no derivative; the integrator accounts for it at the
    /// breakpoint), the slopes for an interpolated one.
    pub fn derivative(&self) -> Option<Samples> {
        (self.replay == Replay::Linear).then(|| Samples {
            replay: Replay::Slope,
            ..self.clone()
        })
    }

    /// The times at which the signal jumps: where a held value changes.
    pub fn breakpoints(&self, out: &mut Vec<f64>) {
        if self.replay == Replay::Hold {
            let changes = self.values.windows(2).zip(&self.times[1..]);
            out.extend(changes.filter(|(v, _)| v[1] != v[0]).map(|(_, &t)| t));
        }
    }

    /// The first and last sample times.
    pub fn span(&self) -> (f64, f64) {
        let first = self.times.first().copied().unwrap_or(f64::NAN);
        (first, self.times.last().copied().unwrap_or(first))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp_then_flat(replay: Replay) -> Samples {
        // 0 until t = 1, up to 2 at t = 2, 2 at t = 3.
        Samples::new(vec![1.0, 2.0, 3.0], vec![0.0, 2.0, 2.0], replay).expect("valid samples")
    }

    #[test]
    fn held_samples_hold_until_the_next_and_jump_there() {
        let s = ramp_then_flat(Replay::Hold);
        let values: Vec<f64> = [0.0, 1.0, 1.999, 2.0, 2.5, 9.0]
            .iter()
            .map(|&t| s.eval(t))
            .collect();
        assert_eq!(values, [0.0, 0.0, 0.0, 2.0, 2.0, 2.0]);
        let mut b = Vec::new();
        s.breakpoints(&mut b);
        assert_eq!(b, [2.0], "only where the value changes");
        assert_eq!(s.derivative(), None);
    }

    #[test]
    fn linear_samples_interpolate_and_their_slope_is_the_derivative() {
        let s = ramp_then_flat(Replay::Linear);
        assert_eq!(s.eval(0.5), 0.0, "the first value holds before the record");
        assert_eq!(s.eval(1.25), 0.5);
        assert_eq!(s.eval(2.5), 2.0);
        assert_eq!(s.eval(7.0), 2.0, "the last value holds after the record");
        let d = s.derivative().expect("an interpolated signal has slopes");
        let slopes: Vec<f64> = [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0]
            .iter()
            .map(|&t| d.eval(t))
            .collect();
        assert_eq!(slopes, [0.0, 2.0, 2.0, 0.0, 0.0, 0.0, 0.0]);
        let mut b = Vec::new();
        s.breakpoints(&mut b);
        assert!(b.is_empty(), "a kink is no jump: {b:?}");
    }

    /// Between samples near the largest `f64` the values lie between them; `v0 + s (v1 − v0)` overflowed to NaN.
    #[test]
    fn samples_near_the_largest_number_interpolate_without_overflow() {
        let s = Samples::new(vec![0.0, 1.0], vec![1e308, -1e308], Replay::Linear)
            .expect("valid samples");
        assert_eq!(s.eval(0.5), 0.0);
        assert_eq!(s.eval(0.25), 5e307);
        assert_eq!(s.eval(1.0), -1e308);
    }

    #[test]
    fn malformed_samples_are_refused_with_the_place() {
        let err = |t: Vec<f64>, v: Vec<f64>| Samples::new(t, v, Replay::Hold).unwrap_err();
        assert_eq!(err(vec![], vec![]), SamplesError::Empty);
        assert_eq!(
            err(vec![0.0, 1.0], vec![1.0]),
            SamplesError::Lengths {
                times: 2,
                values: 1
            }
        );
        assert_eq!(
            err(vec![0.0, 1.0], vec![1.0, f64::NAN]),
            SamplesError::NotFinite { index: 1 }
        );
        assert_eq!(
            err(vec![0.0, 1.0, 1.0], vec![1.0, 2.0, 3.0]),
            SamplesError::Unsorted { index: 2 }
        );
    }
}
