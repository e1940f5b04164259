//! Open-loop simulation with dense output at requested times.

use nalgebra::SVector;

use super::check_initial;
use super::error::SimError;
use super::integrate::{Segment, SolverOptions, integrate_segment};
use crate::model::ContinuousModel;

/// States, inputs and outputs of a run at the requested times.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory<const NX: usize, const NU: usize, const NY: usize> {
    pub times: Vec<f64>,
    pub states: Vec<SVector<f64, NX>>,
    /// `u(t)` at each time.
    pub inputs: Vec<SVector<f64, NU>>,
    /// `h(t, x(t), u(t))` at each time.
    pub outputs: Vec<SVector<f64, NY>>,
}

impl<const NX: usize, const NU: usize, const NY: usize> Trajectory<NX, NU, NY> {
    /// Number of recorded times.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }
}

/// Simulates `ẋ = f(t, x, u(t))` from `x(t0) = x0` and reports the trajectory at `times`.
///
/// `times` must be finite, strictly increasing and not before `t0`; a time equal to `t0` reports `x0`. The
/// run is one solver segment, so the input should be smooth after `t0` (a step applied at `t0` is fine);
/// for inputs that jump later, use [`super::simulate_sampled_loop`] or run segments back to back.
pub fn simulate_open_loop<Mdl, U, const NX: usize, const NU: usize, const NY: usize>(
    model: &Mdl,
    t0: f64,
    x0: &SVector<f64, NX>,
    input: U,
    times: &[f64],
    opts: &SolverOptions,
) -> Result<Trajectory<NX, NU, NY>, SimError>
where
    Mdl: ContinuousModel<NX, NU, NY>,
    U: Fn(f64) -> SVector<f64, NU>,
{
    opts.check()?;
    check_initial(t0, x0)?;
    let mut prev = t0;
    for (i, &t) in times.iter().enumerate() {
        let increasing = if i == 0 { t >= prev } else { t > prev };
        if !(t.is_finite() && increasing) {
            return Err(SimError::BadSetting {
                name: "times",
                value: t,
                reason: "output times must be finite, strictly increasing and not before t0",
            });
        }
        prev = t;
    }
    let mut states = Vec::with_capacity(times.len());
    let inner: &[f64] = match times.first() {
        Some(&t) if t == t0 => {
            states.push(*x0);
            &times[1..]
        }
        _ => times,
    };
    if let Some(&t_end) = inner.last() {
        let zero = SVector::<f64, NX>::zeros();
        let seg = Segment {
            t0,
            t_end,
            x0,
            disturbance: &zero,
            output_times: inner,
        };
        integrate_segment::<Mdl, _, NX, NU, NY>(model, &input, &seg, opts, &mut states)?;
    }
    let inputs: Vec<SVector<f64, NU>> = times.iter().map(|&t| input(t)).collect();
    let outputs = times
        .iter()
        .zip(states.iter().zip(&inputs))
        .map(|(&t, (x, u))| {
            let mut y = SVector::<f64, NY>::zeros();
            model.outputs(t, x, u, &mut y);
            match y.iter().position(|v| !v.is_finite()) {
                Some(index) => Err(SimError::NonFiniteOutput { time: t, index }),
                None => Ok(y),
            }
        })
        .collect::<Result<_, _>>()?;
    Ok(Trajectory {
        times: times.to_vec(),
        states,
        inputs,
        outputs,
    })
}
