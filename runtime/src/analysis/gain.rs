//! Gain-based figures of a SISO model: the bandwidth relative to the DC gain, the first crossing of an
//! absolute level, and the peak gain.
//!
//! All three scan the grid of [`search_grid`](super::margins::search_grid) (dense logarithmic, pole frequencies
//! inserted) and refine by Brent's method (crossings) or golden-section search (the peak). Frequencies are in
//! rad/s; divide by `2π` for Hz (the back-support paper quotes its disturbance-rejection bandwidth, 52 Hz, in Hz).

use super::error::AnalysisError;
use super::freqresp::{Resolvent, check_siso, dc_gain};
use super::margins::grid_of;
use super::scalar_search::{brent_root, golden_min};
use crate::statespace::StateSpace;

/// The closed-loop bandwidth: the first frequency (rad/s) at which `|G|` falls `drop_db` below its DC value
/// (`drop_db = -3.0` for the usual −3 dB bandwidth), or `None` if it never does on the search grid.
///
/// This is python-control's `bandwidth(sys, dbdrop)`; the back-support exoskeleton paper uses the same
/// definition ("the first frequency in which the gain descends to below −3 dB of its DC value").
pub fn bandwidth(sys: &StateSpace, drop_db: f64) -> Result<Option<f64>, AnalysisError> {
    check_siso(sys, "bandwidth")?;
    if !(drop_db.is_finite() && drop_db < 0.0) {
        return Err(AnalysisError::BadParameter {
            name: "drop_db",
            value: drop_db,
            reason: "the drop must be a finite negative number of dB",
        });
    }
    let g0 = dc_gain(sys)?[(0, 0)].abs();
    if g0 == 0.0 {
        return Err(AnalysisError::ZeroDcGain);
    }
    let resolvent = Resolvent::new(sys);
    let level = |w: f64| -> Result<f64, AnalysisError> {
        Ok(20.0 * (resolvent.siso(w)?.norm() / g0).log10() - drop_db)
    };
    let grid = grid_of(sys, &resolvent)?;
    let (mut w_prev, mut f_prev) = (0.0, -drop_db);
    for &w in &grid {
        let f = match level(w) {
            Ok(f) => f,
            Err(AnalysisError::PoleOnContour { .. }) => continue,
            Err(e) => return Err(e),
        };
        if f < 0.0 {
            return brent_root(level, w_prev, w, f_prev, f).map(Some);
        }
        (w_prev, f_prev) = (w, f);
    }
    Ok(None)
}

/// The first crossing of an absolute gain level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelCrossing {
    /// Frequency of the crossing (rad/s).
    pub frequency: f64,
    /// `true` if the gain rises through the level, `false` if it falls.
    pub rising: bool,
}

/// The lowest frequency at which `20 log10 |G(jω)|` crosses `level_db`, or `None` if it never does on the
/// search grid.
///
/// For a disturbance-rejection bandwidth whose DC gain is zero (integral action rejects constant
/// disturbances, so [`bandwidth`] has no reference level), apply it to the sensitivity or disturbance
/// transfer with `level_db = -3.0`: the frequency where `|S|` first rises through `1/√2` (Skogestad and
/// Postlethwaite, *Multivariable Feedback Control*, Sec. 2.4.5).
pub fn first_level_crossing(
    sys: &StateSpace,
    level_db: f64,
) -> Result<Option<LevelCrossing>, AnalysisError> {
    check_siso(sys, "first_level_crossing")?;
    if !level_db.is_finite() {
        return Err(AnalysisError::BadParameter {
            name: "level_db",
            value: level_db,
            reason: "the level must be a finite number of dB",
        });
    }
    let resolvent = Resolvent::new(sys);
    let level = |w: f64| -> Result<f64, AnalysisError> {
        Ok(20.0 * resolvent.siso(w)?.norm().log10() - level_db)
    };
    let mut prev: Option<(f64, f64)> = None;
    for &w in &grid_of(sys, &resolvent)? {
        let f = match level(w) {
            Ok(f) if f.is_finite() => f,
            Ok(_) | Err(AnalysisError::PoleOnContour { .. }) => {
                prev = None;
                continue;
            }
            Err(e) => return Err(e),
        };
        if let Some((w_prev, f_prev)) = prev
            && (f_prev < 0.0) != (f < 0.0)
        {
            let frequency = brent_root(level, w_prev, w, f_prev, f)?;
            return Ok(Some(LevelCrossing {
                frequency,
                rising: f > f_prev,
            }));
        }
        prev = Some((w, f));
    }
    Ok(None)
}

/// The largest gain `max |G(jω)|` over the search grid and `ω = 0`, refined; returns `(gain, frequency)`. A
/// pole on the imaginary axis (the unit circle), including one at `s = 0` (`z = 1`), makes the peak infinite:
/// [`AnalysisError::PoleOnContour`].
pub fn peak_gain(sys: &StateSpace) -> Result<(f64, f64), AnalysisError> {
    check_siso(sys, "peak_gain")?;
    let resolvent = Resolvent::new(sys);
    let grid = grid_of(sys, &resolvent)?;
    let gains: Vec<f64> = grid
        .iter()
        .map(|&w| match resolvent.siso(w) {
            Ok(g) => Ok(g.norm()),
            Err(AnalysisError::PoleOnContour { .. }) => Ok(f64::INFINITY),
            Err(e) => Err(e),
        })
        .collect::<Result<_, _>>()?;
    let Some((i, &g_max)) = gains.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) else {
        return Ok((0.0, 0.0));
    };
    if !g_max.is_finite() {
        return Err(AnalysisError::PoleOnContour { omega: grid[i] });
    }
    let mut best = (g_max, grid[i]);
    if i > 0 && i + 1 < grid.len() {
        let (w, neg) = golden_min(
            |w| Ok::<f64, AnalysisError>(-resolvent.siso(w)?.norm()),
            grid[i - 1],
            grid[i + 1],
        )?;
        if -neg > best.0 {
            best = (-neg, w);
        }
    }
    // A pole at s = 0 (z = 1) makes the peak infinite, below the grid's lowest frequency; ignoring it reported
    // the gain at the bottom of the grid as the peak.
    let g0 = match dc_gain(sys) {
        Err(AnalysisError::InfiniteDcGain) => {
            return Err(AnalysisError::PoleOnContour { omega: 0.0 });
        }
        g0 => g0?[(0, 0)].abs(),
    };
    if g0 > best.0 {
        best = (g0, 0.0);
    }
    Ok(best)
}
