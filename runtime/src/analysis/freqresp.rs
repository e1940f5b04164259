//! Frequency response of a state-space model.
//!
//! For a continuous model the response at `ω` is `G(jω) = C (jωI − A)⁻¹ B + D`; for a discrete model with
//! sample time `T` it is `G(e^{jωT}) = C (e^{jωT} I − A)⁻¹ B + D`, defined for `0 ≤ ω ≤ π/T`. The points are
//! evaluated by a [`Resolvent`] (one Hessenberg reduction of `A`, then a solve per point), and the residual
//! of each solve is checked so that a frequency sitting on (or numerically on) a pole is reported rather
//! than returned as a meaningless number.

use nalgebra::{Complex, DMatrix};

use super::error::AnalysisError;
pub use super::resolvent::Resolvent;
use crate::statespace::StateSpace;

/// A complex number in double precision.
pub type C64 = Complex<f64>;

/// Relative residual above which a resolvent solve is refused.
pub(super) const RESIDUAL_LIMIT: f64 = 1e-8;

/// The most points [`logspace`] builds (80 MB of frequencies), so that a mistyped length is an error rather
/// than an allocation failure that aborts the process.
pub const MAX_GRID_POINTS: usize = 10_000_000;

/// The point of the complex plane at which frequency `omega` (rad/s) is evaluated: `jω`, or `e^{jωT}`.
pub fn evaluation_point(sys: &StateSpace, omega: f64) -> Result<C64, AnalysisError> {
    point_of(sys.dt(), omega)
}

/// [`evaluation_point`] for a model of sample time `dt` (`None`: continuous).
pub(super) fn point_of(dt: Option<f64>, omega: f64) -> Result<C64, AnalysisError> {
    if !omega.is_finite() || omega < 0.0 {
        return Err(AnalysisError::BadFrequency {
            omega,
            reason: "frequencies must be finite and non-negative",
        });
    }
    match dt {
        None => Ok(C64::new(0.0, omega)),
        Some(dt) => {
            let nyquist = std::f64::consts::PI / dt;
            if omega > nyquist * (1.0 + 1e-12) {
                return Err(AnalysisError::AboveNyquist { omega, nyquist });
            }
            Ok(C64::from_polar(1.0, omega * dt))
        }
    }
}

/// `C (pI − A)⁻¹ B + D` at a point `p` of the complex plane; `omega` only names the point in errors.
pub fn transfer_at(sys: &StateSpace, p: C64, omega: f64) -> Result<DMatrix<C64>, AnalysisError> {
    Resolvent::new(sys).transfer_at(p, omega)
}

/// The frequency response matrix (outputs × inputs) at each frequency of `omegas` (rad/s).
pub fn frequency_response(
    sys: &StateSpace,
    omegas: &[f64],
) -> Result<Vec<DMatrix<C64>>, AnalysisError> {
    let resolvent = Resolvent::new(sys);
    omegas.iter().map(|&w| resolvent.response(w)).collect()
}

/// The response of a SISO model at one frequency.
pub fn siso_response(sys: &StateSpace, omega: f64) -> Result<C64, AnalysisError> {
    check_siso(sys, "siso_response")?;
    Resolvent::new(sys).siso(omega)
}

/// The steady-state gain `G(0)` (continuous) or `G(1)` (discrete).
///
/// A pole at `s = 0` (or `z = 1`) gives [`AnalysisError::InfiniteDcGain`].
pub fn dc_gain(sys: &StateSpace) -> Result<DMatrix<f64>, AnalysisError> {
    let p = match sys.dt() {
        None => C64::new(0.0, 0.0),
        Some(_) => C64::new(1.0, 0.0),
    };
    match transfer_at(sys, p, 0.0) {
        Ok(g) => Ok(g.map(|v| v.re)),
        Err(AnalysisError::PoleOnContour { .. }) | Err(AnalysisError::IllConditioned { .. }) => {
            Err(AnalysisError::InfiniteDcGain)
        }
        Err(e) => Err(e),
    }
}

/// `points` frequencies spaced evenly in logarithm from `low` to `high` (both included, both > 0).
pub fn logspace(low: f64, high: f64, points: usize) -> Result<Vec<f64>, AnalysisError> {
    let bad = |reason| AnalysisError::BadGrid {
        low,
        high,
        points,
        reason,
    };
    if !(low.is_finite() && high.is_finite() && low > 0.0 && high > low) {
        return Err(bad("bounds must be finite with 0 < low < high"));
    }
    if points < 2 {
        return Err(bad("a grid needs at least two points"));
    }
    if points > MAX_GRID_POINTS {
        return Err(bad("a grid may have at most 10,000,000 points"));
    }
    let (l0, l1) = (low.log10(), high.log10());
    let step = (l1 - l0) / (points - 1) as f64;
    let mut grid: Vec<f64> = (0..points)
        .map(|i| 10f64.powf(l0 + step * i as f64))
        .collect();
    // Pin the ends exactly so that callers can rely on them.
    grid[0] = low;
    grid[points - 1] = high;
    Ok(grid)
}

/// Bode data of one channel: magnitude in dB and phase in degrees, unwrapped along the grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Bode {
    /// Frequencies in rad/s.
    pub omega: Vec<f64>,
    /// `20 log10 |G(jω)|`.
    pub magnitude_db: Vec<f64>,
    /// `arg G(jω)` in degrees, unwrapped so that consecutive points differ by less than 180°.
    pub phase_deg: Vec<f64>,
}

/// Bode data of the channel from `input` to `output` at the given frequencies.
pub fn bode(
    sys: &StateSpace,
    output: usize,
    input: usize,
    omegas: &[f64],
) -> Result<Bode, AnalysisError> {
    if output >= sys.n_outputs() || input >= sys.n_inputs() {
        return Err(AnalysisError::NoSuchChannel {
            output,
            input,
            outputs: sys.n_outputs(),
            inputs: sys.n_inputs(),
        });
    }
    let responses = frequency_response(sys, omegas)?;
    let values: Vec<C64> = responses.iter().map(|g| g[(output, input)]).collect();
    let magnitude_db = values.iter().map(|g| 20.0 * g.norm().log10()).collect();
    let wrapped: Vec<f64> = values.iter().map(|g| g.arg().to_degrees()).collect();
    Ok(Bode {
        omega: omegas.to_vec(),
        magnitude_db,
        phase_deg: unwrap_degrees(&wrapped),
    })
}

/// Removes jumps of more than 180° between consecutive phases by adding multiples of 360°.
///
/// The multiple is computed in one step (`round(jump / 360)`), so any finite input takes one pass; a
/// non-finite phase is copied as it is and does not change the offset of the phases after it.
pub fn unwrap_degrees(phase: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(phase.len());
    let mut offset = 0.0;
    let mut prev: Option<f64> = None;
    for &p in phase {
        if !p.is_finite() {
            out.push(p);
            continue;
        }
        if let Some(prev) = prev {
            let jump = p + offset - prev;
            // Round half towards zero so that a jump of exactly ±180° is kept, as the loop it replaces did.
            let turns = (jump.abs() / 360.0 - 0.5).ceil().max(0.0).copysign(jump);
            offset -= 360.0 * turns;
        }
        let unwrapped = p + offset;
        out.push(unwrapped);
        prev = Some(unwrapped);
    }
    out
}

pub(crate) fn check_siso(sys: &StateSpace, what: &'static str) -> Result<(), AnalysisError> {
    check_siso_shape(what, sys.n_outputs(), sys.n_inputs())
}

/// [`check_siso`] for a model of `outputs` outputs and `inputs` inputs.
pub(super) fn check_siso_shape(
    what: &'static str,
    outputs: usize,
    inputs: usize,
) -> Result<(), AnalysisError> {
    if (outputs, inputs) != (1, 1) {
        return Err(AnalysisError::NotSiso {
            what,
            inputs,
            outputs,
        });
    }
    Ok(())
}
