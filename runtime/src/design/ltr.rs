//! Loop transfer recovery (Doyle & Stein 1979) at the plant input: the observer of an observer-based
//! state-feedback loop is designed with fictitious process noise `q · B Bᵀ` at the plant input added to the
//! real noise model, and `q` is swept.
//!
//! With the full state measured, the LQR loop broken at the plant input is `L_lqr = K (sI − A)⁻¹ B`, with its
//! guaranteed margins (return difference `|1 + L_lqr| ≥ 1`: phase margin ≥ 60°, gain increase unbounded).
//! Putting an observer in the loop can erode them badly. For a plant `(A, B, C)` that is minimum phase (no
//! transmission zero in the closed right half-plane) with at least as many outputs as inputs, the Kalman gain
//! designed with `G Q_n Gᵀ + q B Bᵀ` makes the observer-based loop at the plant input tend to `L_lqr`
//! pointwise in frequency as `q → ∞`: the observer's estimate stops depending on the controller's own input.
//! The price is a faster, noisier estimate, so a design picks the smallest `q` whose margins are enough. For a
//! non-minimum-phase plant the recovery is only partial; the sweep reports what each `q` achieves either way.
//!
//! The same recovery holds when the controller has dynamics of its own driven by the estimate (integrators of
//! an estimated output, as in an LQI): [`recovery_sweep_with`] takes the controller as a function of the
//! observer gain, and [`recovery_sweep`] builds the plain `u = −K x̂` controller
//! ([`crate::analysis::observer_controller`]).
//!
//! Conventions: `q` has the units of `Q_n`'s entries per plant input (an intensity for the continuous `lqe`);
//! margins follow [`crate::analysis::stability_margins`] (python-control's `stability_margins`).

use nalgebra::DMatrix;

use super::kalman::{Kalman, lqe};
use crate::analysis::{
    AnalysisError, StabilityMargins, loop_at_plant_input, observer_controller, stability_margins,
};
use crate::linalg::RiccatiError;
use crate::statespace::StateSpace;

/// The real noise model of the observer: `ẋ = A x + B u + G w`, `y = C x + v`, `E[wwᵀ] = Q_n δ`,
/// `E[vvᵀ] = R_n δ` (as [`lqe`] takes it).
#[derive(Clone, Copy, Debug)]
pub struct ObserverNoise<'a> {
    pub g: &'a DMatrix<f64>,
    pub qn: &'a DMatrix<f64>,
    pub rn: &'a DMatrix<f64>,
}

/// Why a recovery design failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LtrError {
    /// A recovery weight was negative or not finite.
    #[error("recovery weight q = {q:?} is not a finite number ≥ 0")]
    BadWeight { q: f64 },
    /// The plant is discrete; the recovery here designs the continuous observer of [`lqe`].
    #[error("loop transfer recovery needs a continuous-time plant (got sample time {dt:?} s)")]
    Discrete { dt: f64 },
    /// The Kalman design at this `q` failed.
    #[error("Kalman design with recovery weight q = {q:?}: {source}")]
    Kalman { q: f64, source: RiccatiError },
    /// The loop or its margins at this `q` could not be computed.
    #[error("loop at the plant input with recovery weight q = {q:?}: {source}")]
    Analysis { q: f64, source: AnalysisError },
}

/// One point of a recovery sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct RecoveryPoint {
    /// The recovery weight.
    pub q: f64,
    /// The Kalman gain designed with `G Q_n Gᵀ + q B Bᵀ`.
    pub observer: Kalman,
    /// The margins of the observer-based loop broken at the plant input.
    pub margins: StabilityMargins,
}

/// The Kalman gain of `plant` for the noise `noise` plus fictitious noise of intensity `q` on every plant
/// input: `lqe(A, [G B], C, diag(Q_n, q I), R_n)`.
pub fn recovery_lqe(
    plant: &StateSpace,
    noise: ObserverNoise<'_>,
    q: f64,
) -> Result<Kalman, LtrError> {
    check_weight(plant, q)?;
    let (n, w, m) = (plant.n_states(), noise.g.ncols(), plant.n_inputs());
    // A G with the wrong row count is reported by lqe; build [G B] only when the rows agree.
    if noise.g.nrows() != n || noise.qn.shape() != (w, w) {
        return lqe(plant.a(), noise.g, plant.c(), noise.qn, noise.rn)
            .map_err(|source| LtrError::Kalman { q, source });
    }
    let mut g = DMatrix::zeros(n, w + m);
    g.view_mut((0, 0), (n, w)).copy_from(noise.g);
    g.view_mut((0, w), (n, m)).copy_from(plant.b());
    let mut qn = DMatrix::zeros(w + m, w + m);
    qn.view_mut((0, 0), (w, w)).copy_from(noise.qn);
    for i in 0..m {
        qn[(w + i, w + i)] = q;
    }
    lqe(plant.a(), &g, plant.c(), &qn, noise.rn).map_err(|source| LtrError::Kalman { q, source })
}

/// The recovery sweep of the plain observer-based loop `u = −K x̂` (module docs), one point per entry of
/// `weights`, in the given order. `plant` must be SISO at the plant input for margins: one input.
pub fn recovery_sweep(
    plant: &StateSpace,
    gain: &DMatrix<f64>,
    noise: ObserverNoise<'_>,
    weights: &[f64],
) -> Result<Vec<RecoveryPoint>, LtrError> {
    recovery_sweep_with(plant, noise, weights, |kalman, q| {
        observer_controller(plant, gain, &kalman.l)
            .map_err(|source| LtrError::Analysis { q, source })
    })
}

/// The recovery sweep of any controller built from the observer: `controller(kalman, q)` returns the
/// controller from the plant outputs to the plant inputs, feedback sign included (as
/// [`observer_controller`] does), for the Kalman design at `q`.
pub fn recovery_sweep_with<E, F>(
    plant: &StateSpace,
    noise: ObserverNoise<'_>,
    weights: &[f64],
    mut controller: F,
) -> Result<Vec<RecoveryPoint>, E>
where
    E: From<LtrError>,
    F: FnMut(&Kalman, f64) -> Result<StateSpace, E>,
{
    weights
        .iter()
        .map(|&q| {
            let observer = recovery_lqe(plant, noise, q)?;
            let ctl = controller(&observer, q)?;
            let margins = loop_at_plant_input(plant, &ctl)
                .and_then(|l| stability_margins(&l))
                .map_err(|source| LtrError::Analysis { q, source })?;
            Ok(RecoveryPoint {
                q,
                observer,
                margins,
            })
        })
        .collect()
}

/// The margins of the full-state loop `K (sI − A)⁻¹ B` at the plant input: what the recovery tends to.
pub fn state_feedback_margins(
    plant: &StateSpace,
    gain: &DMatrix<f64>,
) -> Result<StabilityMargins, LtrError> {
    let analysis = |source| LtrError::Analysis {
        q: f64::INFINITY,
        source,
    };
    let d = DMatrix::zeros(gain.nrows(), plant.n_inputs());
    let target = StateSpace::new(plant.a().clone(), plant.b().clone(), gain.clone(), d)
        .map_err(|e| analysis(AnalysisError::from(e)))?;
    stability_margins(&target).map_err(analysis)
}

fn check_weight(plant: &StateSpace, q: f64) -> Result<(), LtrError> {
    if let Some(dt) = plant.dt() {
        return Err(LtrError::Discrete { dt });
    }
    if q.is_finite() && q >= 0.0 {
        Ok(())
    } else {
        Err(LtrError::BadWeight { q })
    }
}
