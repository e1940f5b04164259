//! Classical stability margins of a SISO loop transfer `L`, and closed-loop bandwidth.
//!
//! With the loop closed by negative feedback (`u = −L u`), the margins are read where the Nyquist curve
//! `L(jω)` meets the unit circle and the negative real axis:
//!
//! - phase crossover `ω_pc`: `L(jω_pc)` real and negative; gain margin `GM = 1 / |L(jω_pc)|`. A loop can have
//!   several; as python-control's `stability_margins` does, the reported one is the crossing whose `GM` is
//!   closest to 1 in the logarithmic sense, `min |ln GM|`. A `GM < 1` is a gain-*reduction* margin (the loop
//!   is conditionally stable and loses stability when the gain drops by that factor); the smallest `GM > 1`
//!   and the largest `GM < 1` are also returned separately.
//! - gain crossover `ω_gc`: `|L(jω_gc)| = 1`; phase margin `PM = (arg L mod 360°) − 180°`, the reported one
//!   being the smallest in magnitude (python-control's rule).
//! - delay margin: the smallest pure delay that brings a gain crossover onto −1,
//!   `DM = PM_rad / ω_gc` with `PM` taken in `[0°, 360°)` (a negative phase margin already means an unstable
//!   loop; the delay then needed to go round once more is reported, as MATLAB's `allmargin` does). For a
//!   discrete loop the delay margin is given in seconds, not samples.
//! - stability margin: the smallest distance `min |1 + L(jω)|` from the Nyquist curve to −1 over the grid
//!   (python-control's polynomial method looks only for stationary points and reports infinity when it finds
//!   none, e.g. for a monotone `|1 + L|`; here the minimum is always reported).
//!
//! The crossings are found on a dense logarithmic grid (200 points per decade, spanning three decades beyond
//! the slowest and fastest poles, widened until the loop gain is small at the top, with the pole frequencies
//! themselves inserted) and refined by Brent's method on `ln |L|` and on `arg(−L)`; the distance to −1 is
//! refined by golden-section search. A static crossing at `ω = 0` is included when `L(0)` is finite and
//! negative, as python-control does.
//!
//! The back-support exoskeleton paper (Shojaei Barjuei et al. 2020, Sec. 5.2) reads a delay margin of 0.007 s
//! as "a minimum sampling frequency of 143 Hz", i.e. `1 / DM`. That is the bound for a controller whose
//! output is one whole sample late; a zero-order hold alone delays by `T/2` on average, which would allow
//! `T < 2 DM`. Either reading can be applied to [`StabilityMargins::delay_margin`]; this module reports
//! the delay itself.

use super::error::AnalysisError;
use super::freqresp::{C64, Resolvent, check_siso, dc_gain};
use super::scalar_search::{brent_root, golden_min};
use crate::statespace::StateSpace;

/// Points per decade of the search grid.
const POINTS_PER_DECADE: f64 = 200.0;

/// The margins of a loop transfer function.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityMargins {
    /// The gain margin python-control reports (closest to 1 in log scale); `f64::INFINITY` without a phase
    /// crossover.
    pub gain_margin: f64,
    /// The phase crossover frequency of `gain_margin` (rad/s).
    pub phase_crossover: Option<f64>,
    /// The phase margin in degrees of smallest magnitude; `f64::INFINITY` without a gain crossover.
    pub phase_margin: f64,
    /// The gain crossover frequency of `phase_margin` (rad/s).
    pub gain_crossover: Option<f64>,
    /// The smallest delay margin over all gain crossovers (s); `f64::INFINITY` without a gain crossover.
    pub delay_margin: f64,
    /// `min |1 + L(jω)|` over the grid, refined.
    pub stability_margin: f64,
    /// The frequency of `stability_margin` (rad/s).
    pub stability_margin_frequency: Option<f64>,
    /// The smallest gain margin above 1 (the allowed gain increase), if any.
    pub gain_increase_margin: Option<f64>,
    /// The largest gain margin below 1 (the allowed gain reduction of a conditionally stable loop), if any.
    pub gain_reduction_margin: Option<f64>,
    /// Every phase crossover as `(frequency, gain margin)`, by increasing frequency.
    pub all_gain_margins: Vec<(f64, f64)>,
    /// Every gain crossover as `(frequency, phase margin in degrees)`, by increasing frequency.
    pub all_phase_margins: Vec<(f64, f64)>,
}

/// The stability margins of the SISO loop transfer `loop_tf` (negative feedback convention).
pub fn stability_margins(loop_tf: &StateSpace) -> Result<StabilityMargins, AnalysisError> {
    check_siso(loop_tf, "stability_margins")?;
    let resolvent = Resolvent::new(loop_tf);
    let response = |w| resolvent.siso(w);
    let grid = grid_of(loop_tf, &resolvent)?;
    let samples: Vec<Option<C64>> = grid
        .iter()
        .map(|&w| sample(&resolvent, w))
        .collect::<Result<_, _>>()?;
    if samples.iter().all(Option::is_none) {
        // Not one point of the grid could be evaluated: report why instead of a loop without crossings.
        response(grid[0])?;
    }

    let mut phase_crossings = Vec::new();
    if let Ok(l0) = dc_gain(loop_tf)
        && l0[(0, 0)] < 0.0
    {
        phase_crossings.push((0.0, 1.0 / l0[(0, 0)].abs()));
    }
    let mut gain_crossings = Vec::new();
    for i in 0..grid.len().saturating_sub(1) {
        let (Some(l_lo), Some(l_hi)) = (samples[i], samples[i + 1]) else {
            continue;
        };
        let (w_lo, w_hi) = (grid[i], grid[i + 1]);

        // |L| = 1 crossing, refined on ln|L| (well scaled across decades).
        let (g_lo, g_hi) = (l_lo.norm().ln(), l_hi.norm().ln());
        if g_lo.is_finite() && g_hi.is_finite() && ((g_lo > 0.0) != (g_hi > 0.0)) {
            let w = brent_root(
                |w| Ok::<f64, AnalysisError>(response(w)?.norm().ln()),
                w_lo,
                w_hi,
                g_lo,
                g_hi,
            )?;
            let l = response(w)?;
            let pm = l.arg().to_degrees().rem_euclid(360.0) - 180.0;
            gain_crossings.push((w, pm));
        }

        // Negative real axis crossing: arg(−L) changes sign where Re L < 0.
        let (a_lo, a_hi) = ((-l_lo).arg(), (-l_hi).arg());
        if (a_lo > 0.0) != (a_hi > 0.0) && (l_lo.re <= 0.0 || l_hi.re <= 0.0) {
            let w = brent_root(
                |w| Ok::<f64, AnalysisError>((-response(w)?).arg()),
                w_lo,
                w_hi,
                a_lo,
                a_hi,
            )?;
            let l = response(w)?;
            // A jump of arg(−L) from π to −π (the positive real axis) also changes sign; keep true crossings.
            if l.re < 0.0 && l.im.abs() <= 1e-6 * l.norm() {
                phase_crossings.push((w, 1.0 / l.norm()));
            }
        }
    }
    gain_crossings.dedup_by(|a, b| (a.0 - b.0).abs() <= 1e-12 * b.0);
    phase_crossings.dedup_by(|a, b| (a.0 - b.0).abs() <= 1e-12 * b.0.max(1e-300));

    let best_gm = phase_crossings
        .iter()
        .copied()
        .min_by(|a, b| a.1.ln().abs().total_cmp(&b.1.ln().abs()));
    let best_pm = gain_crossings
        .iter()
        .copied()
        .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()));
    let delay_margin = gain_crossings
        .iter()
        .map(|&(w, pm)| pm.rem_euclid(360.0).to_radians() / w)
        .fold(f64::INFINITY, f64::min);
    let (stability_margin, stability_margin_frequency) =
        nearest_approach(&resolvent, &grid, &samples)?;

    Ok(StabilityMargins {
        gain_margin: best_gm.map_or(f64::INFINITY, |c| c.1),
        phase_crossover: best_gm.map(|c| c.0),
        phase_margin: best_pm.map_or(f64::INFINITY, |c| c.1),
        gain_crossover: best_pm.map(|c| c.0),
        delay_margin,
        stability_margin,
        stability_margin_frequency,
        gain_increase_margin: phase_crossings
            .iter()
            .map(|c| c.1)
            .filter(|&g| g > 1.0)
            .reduce(f64::min),
        gain_reduction_margin: phase_crossings
            .iter()
            .map(|c| c.1)
            .filter(|&g| g < 1.0)
            .reduce(f64::max),
        all_gain_margins: phase_crossings,
        all_phase_margins: gain_crossings,
    })
}

/// The loop response at `w`, or `None` on (or, for an overflowing response, next to) a pole of the loop
/// (such points break brackets).
fn sample(resolvent: &Resolvent, w: f64) -> Result<Option<C64>, AnalysisError> {
    match resolvent.siso(w) {
        Ok(l) => Ok(Some(l)),
        Err(AnalysisError::PoleOnContour { .. })
        | Err(AnalysisError::IllConditioned { .. })
        | Err(AnalysisError::Overflow { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Smallest `|1 + L|` on the grid, refined around each local minimum.
fn nearest_approach(
    resolvent: &Resolvent,
    grid: &[f64],
    samples: &[Option<C64>],
) -> Result<(f64, Option<f64>), AnalysisError> {
    let dist: Vec<f64> = samples
        .iter()
        .map(|l| l.map_or(f64::INFINITY, |l| (l + 1.0).norm()))
        .collect();
    let mut best = (f64::INFINITY, None);
    for i in 0..dist.len() {
        let left = if i > 0 { dist[i - 1] } else { f64::INFINITY };
        let right = dist.get(i + 1).copied().unwrap_or(f64::INFINITY);
        if !(dist[i].is_finite() && dist[i] <= left && dist[i] <= right) {
            continue;
        }
        let lo = if i > 0 { grid[i - 1] } else { grid[i] };
        let hi = grid.get(i + 1).copied().unwrap_or(grid[i]);
        let (w, d) = if hi > lo {
            golden_min(
                |w| Ok::<f64, AnalysisError>((resolvent.siso(w)? + 1.0).norm()),
                lo,
                hi,
            )?
        } else {
            (grid[i], dist[i])
        };
        if d < best.0 {
            best = (d, Some(w));
        }
    }
    Ok(best)
}

/// The frequency grid on which crossings are searched (see the module documentation).
pub fn search_grid(sys: &StateSpace) -> Result<Vec<f64>, AnalysisError> {
    grid_of(sys, &Resolvent::new(sys))
}

/// [`search_grid`] with the model's responses from `resolvent`.
pub(super) fn grid_of(sys: &StateSpace, resolvent: &Resolvent) -> Result<Vec<f64>, AnalysisError> {
    let corners = pole_frequencies(sys);
    let (slow, fast) = corners
        .iter()
        .filter(|&&w| w > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &w| {
            (lo.min(w), hi.max(w))
        });
    let (slow, fast) = if slow.is_finite() {
        (slow, fast)
    } else {
        (1.0, 1.0)
    };
    let low = slow * 1e-3;
    let mut high = fast * 1e3;
    match sys.dt() {
        Some(dt) => high = std::f64::consts::PI / dt,
        None => {
            // Widen until the loop gain has fallen well below 1 (or stopped falling: a biproper loop).
            for _ in 0..6 {
                match largest_gain(resolvent, high) {
                    Some(g) if g > 0.5 => high *= 100.0,
                    _ => break,
                }
            }
        }
    }
    let low = low.min(high * 1e-6);
    let decades = (high / low).log10();
    let points = ((decades * POINTS_PER_DECADE).ceil() as usize).max(2);
    let mut grid = super::freqresp::logspace(low, high, points)?;
    grid.extend(corners.iter().copied().filter(|&w| w > low && w < high));
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    Ok(grid)
}

/// The largest gain of the continuous model at `w`, if it can be evaluated.
fn largest_gain(resolvent: &Resolvent, w: f64) -> Option<f64> {
    resolvent
        .response(w)
        .ok()
        .map(|g| g.iter().map(|v| v.norm()).fold(0.0, f64::max))
}

/// Natural frequencies of the poles: `|λ|` in continuous time, `|ln z| / T` in discrete time. Empty if the
/// eigenvalues cannot be computed (the grid then falls back to a default range).
fn pole_frequencies(sys: &StateSpace) -> Vec<f64> {
    if sys.n_states() == 0 {
        return Vec::new();
    }
    let Some(schur) = sys.a().clone().try_schur(f64::EPSILON, 10_000) else {
        return Vec::new();
    };
    schur
        .complex_eigenvalues()
        .iter()
        .filter_map(|z| match sys.dt() {
            None => Some(z.norm()),
            Some(dt) => {
                let s = z.ln() / dt;
                (z.norm() > 0.0).then_some(s.norm())
            }
        })
        .filter(|w| w.is_finite())
        .collect()
}
