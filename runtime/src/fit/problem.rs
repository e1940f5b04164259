//! The fit: weighted least squares of the output error over a record, minimised by Levenberg–Marquardt
//! ([`super::lm`]) with the Jacobian from forward sensitivities ([`super::sensitivity`]), then the statistics
//! ([`super::stats`]).
//!
//! A parameter marked `log` (a quantity that is positive by its nature: an inertia, a stiffness) is fitted as
//! `ln p`, so it stays positive and its steps are relative. When the statistics find a combination the record
//! does not determine, the quantity that dominates it is held at its starting value and the others are fitted
//! again: the report names the combination and the held quantity instead of an arbitrary value.

use nalgebra::{DMatrix, DVector};

use super::lm::{self, Convergence, LmOptions, Minimum, Residuals, StopReason};
use super::record::{Interp, Record};
use super::sensitivity::{self, FitModel, Fitted, SensitivityError};
use super::stats;
use crate::sim::{Method, SolverOptions};

/// The Gauss–Newton step (in standard errors) within which a fit that did not converge is near enough to its
/// minimum for the statistics to decide what to hold.
const NEAR_MINIMUM_STANDARD_ERRORS: f64 = 1.0;

/// A parameter to fit.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeParam {
    /// Its index among the model's parameters.
    pub index: usize,
    pub name: String,
    /// Fit `ln p` (the start must be positive).
    pub log: bool,
    /// Bounds on the value (`-∞`/`∞` when none).
    pub lower: f64,
    pub upper: f64,
}

impl FreeParam {
    /// An unbounded parameter.
    pub fn new(index: usize, name: &str, log: bool) -> FreeParam {
        FreeParam {
            index,
            name: name.to_string(),
            log,
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
        }
    }
}

/// An initial state to fit.
#[derive(Clone, Debug, PartialEq)]
pub struct FreeState {
    pub index: usize,
    pub name: String,
}

/// What to fit and how.
#[derive(Clone, Debug, PartialEq)]
pub struct FitSpec {
    pub params: Vec<FreeParam>,
    pub x0: Vec<FreeState>,
    /// One weight per measured column of the record (`1/σ²` of its noise gives standard errors in the
    /// record's own scale).
    pub weights: Vec<f64>,
    pub interp: Interp,
    pub solver: SolverOptions,
    pub lm: LmOptions,
}

impl FitSpec {
    /// Parameters `params`, unit weights, zero-order hold, ESDIRK3(4) at `rtol` 1e-8.
    pub fn new(params: Vec<FreeParam>, measured_columns: usize) -> FitSpec {
        FitSpec {
            params,
            x0: Vec::new(),
            weights: vec![1.0; measured_columns],
            interp: Interp::Zoh,
            solver: SolverOptions {
                method: Method::Esdirk34,
                rtol: 1e-8,
                atol: 1e-10,
                max_steps: 1_000_000,
            },
            lm: LmOptions::default(),
        }
    }
}

/// One fitted quantity.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Estimate {
    pub name: String,
    pub value: f64,
    /// `NaN` for a quantity held because the record does not determine it.
    pub std_error: f64,
    pub start: f64,
    pub determined: bool,
}

/// A combination `Π θ^exponent` the record does not determine, and the quantity held at its start because of it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Undetermined {
    pub combination: Vec<(String, f64)>,
    /// The standard error of the logarithm of the combination (infinite: the record does not depend on it).
    pub relative_std_error: f64,
    /// The quantity held at its start because of it; `None` when none could be (the fit did not converge, or
    /// holding it would leave nothing to fit): its dominant quantity is then reported as not determined at the
    /// value the fit reached.
    pub held: Option<String>,
}

/// The answer of a fit.
#[derive(Clone, Debug)]
pub struct FitReport {
    /// The parameters, then the initial states, in the order of the spec.
    pub estimates: Vec<Estimate>,
    /// Correlations among the determined estimates, in the order of `correlated`.
    pub correlation: DMatrix<f64>,
    pub correlated: Vec<String>,
    /// The RMS of the output error (model − measured) of each measured column, in its unit.
    pub rms: Vec<f64>,
    pub residual_variance: f64,
    pub degrees_of_freedom: usize,
    pub iterations: usize,
    pub stop: StopReason,
    /// Whether the last minimisation found a minimum ([`Convergence`]); estimates of a fit that did not are no
    /// identification.
    pub convergence: Convergence,
    /// The Gauss–Newton step from the final point in standard errors ([`lm::Minimum::optimality`]).
    pub optimality: f64,
    pub undetermined: Vec<Undetermined>,
    /// All parameter values and the initial state at the optimum.
    pub params: Vec<f64>,
    pub x0: Vec<f64>,
    /// The fitted outputs at each sample, one per measured column.
    pub fitted: Vec<Vec<f64>>,
}

/// Why no fit was made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error("{0}")]
    Spec(String),
    #[error("the model cannot be simulated at the starting values: {0}")]
    Start(SensitivityError),
    #[error("{0}")]
    Model(String),
}

/// Fits `spec`'s quantities of `model` to `record`, starting from the parameter values `params` and the initial
/// state `x0` (both complete; the fitted entries are the starting values).
pub fn fit(
    model: &mut dyn FitModel,
    record: &Record,
    params: &[f64],
    x0: &[f64],
    spec: &FitSpec,
) -> Result<FitReport, FitError> {
    check(model, record, params, x0, spec)?;
    let n = spec.params.len() + spec.x0.len();
    let mut objective = Objective {
        model,
        record,
        spec,
        params: params.to_vec(),
        x0: x0.to_vec(),
        active: (0..n).collect(),
        start: (params.to_vec(), x0.to_vec()),
    };
    let mut undetermined = Vec::new();
    let mut iterations = 0;
    loop {
        let (lower, upper) = objective.bounds();
        let z0 = objective.start_coordinates();
        let min =
            lm::minimise(&mut objective, &z0, &lower, &upper, &spec.lm).map_err(FitError::Model)?;
        iterations += min.iterations;
        objective.set(&min.z);
        let scales = objective.scales();
        let jac_rel = relative(&min.jacobian, &objective, &scales);
        let st = stats::statistics(min.residuals.norm_squared(), &jac_rel, &scales)
            .map_err(FitError::Model)?;
        let found = objective.name_directions(&st.undetermined);
        // Statistics away from a minimum say nothing about what the record determines, and a fit needs at least
        // one quantity: then the combinations are reported without holding anything. A fit that did not converge
        // but ended within a standard error of the Gauss–Newton minimum (an undetermined direction is exactly
        // what makes the iteration crawl) is near enough for its statistics to hold.
        let held: Vec<usize> = found.iter().map(|&(q, _)| q).collect();
        let near_minimum =
            min.convergence.converged() || min.optimality <= NEAR_MINIMUM_STANDARD_ERRORS;
        let holdable = near_minimum && held.len() < objective.active.len();
        if found.is_empty() || !holdable {
            let unheld = found.into_iter().map(|(_, u)| u);
            undetermined.extend(unheld);
            return objective.report(st, &min, iterations, undetermined);
        }
        for (_, mut u) in found {
            u.held = u.combination.first().map(|(n, _)| n.clone());
            undetermined.push(u);
        }
        // Held quantities go back to their starting values; the others are fitted again from where they are.
        for &q in &held {
            objective.restore(q, params, x0);
        }
        objective.active.retain(|q| !held.contains(q));
    }
}

fn check(
    model: &dyn FitModel,
    record: &Record,
    params: &[f64],
    x0: &[f64],
    spec: &FitSpec,
) -> Result<(), FitError> {
    let bad = |s: String| Err(FitError::Spec(s));
    if params.len() != model.param_count() || x0.len() != model.state_count() {
        return bad(format!(
            "expected {} parameter values and {} initial states, got {} and {}",
            model.param_count(),
            model.state_count(),
            params.len(),
            x0.len()
        ));
    }
    // Every row, not only the first: the record's fields are public, and a short row would be copied into the
    // model's input buffer.
    let n = record.times.len();
    if record.inputs.len() != n
        || record.measured.len() != n
        || record.inputs.iter().any(|u| u.len() != model.input_count())
        || record
            .measured
            .iter()
            .any(|y| y.len() != record.outputs.len())
        || record.outputs.iter().any(|&o| o >= model.output_count())
    {
        return bad("the record's inputs or outputs do not match the model".into());
    }
    if let Some(k) = params.iter().position(|v| !v.is_finite()) {
        return bad(format!(
            "parameter {k} is {:?}; every parameter must be finite",
            params[k]
        ));
    }
    if let Some(k) = x0.iter().position(|v| !v.is_finite()) {
        return bad(format!(
            "initial state {k} is {:?}; every initial state must be finite",
            x0[k]
        ));
    }
    spec.lm.check().map_err(FitError::Spec)?;
    if spec.weights.len() != record.outputs.len()
        || spec.weights.iter().any(|w| !(w.is_finite() && *w > 0.0))
    {
        return bad(format!(
            "expected {} finite positive weights (one per measured column), got {:?}",
            record.outputs.len(),
            spec.weights
        ));
    }
    if spec.params.is_empty() && spec.x0.is_empty() {
        return bad("nothing to fit: name at least one parameter or initial state".into());
    }
    if let Some(p) = first_repeat(spec.params.iter().map(|p| p.index)).map(|k| &spec.params[k]) {
        return bad(format!(
            "parameter `{}` (index {}) is named twice",
            p.name, p.index
        ));
    }
    for p in &spec.params {
        let Some(&v) = params.get(p.index) else {
            return bad(format!("parameter `{}` has no index {}", p.name, p.index));
        };
        if p.lower >= p.upper || p.lower.is_nan() || p.upper.is_nan() {
            return bad(format!(
                "the bounds of `{}` are empty: [{:?}, {:?}]",
                p.name, p.lower, p.upper
            ));
        }
        if !(v >= p.lower && v <= p.upper && v.is_finite()) {
            return bad(format!(
                "the start of `{}`, {v:?}, is not within its bounds [{:?}, {:?}]",
                p.name, p.lower, p.upper
            ));
        }
        if p.log && v <= 0.0 {
            return bad(format!(
                "`{}` is fitted in log space (a positive quantity) but starts at {v:?}; give a positive start",
                p.name
            ));
        }
    }
    if let Some(s) = spec.x0.iter().find(|s| s.index >= x0.len()) {
        return bad(format!(
            "initial state `{}` has no index {}",
            s.name, s.index
        ));
    }
    if let Some(s) = first_repeat(spec.x0.iter().map(|s| s.index)).map(|k| &spec.x0[k]) {
        return bad(format!(
            "initial state `{}` (index {}) is named twice",
            s.name, s.index
        ));
    }
    let measured = record.sample_count();
    let fitted = spec.params.len() + spec.x0.len();
    if measured <= fitted {
        return bad(format!(
            "the record has {measured} measured values for {fitted} fitted quantities; it needs more values than \
             quantities"
        ));
    }
    Ok(())
}

/// The Jacobian in optimiser coordinates turned into the relative one of [`stats`].
fn relative(jac_z: &DMatrix<f64>, o: &Objective<'_>, scales: &[f64]) -> DMatrix<f64> {
    let mut j = jac_z.clone();
    for (c, &q) in o.active.iter().enumerate() {
        // ∂r/∂θ · c = ∂r/∂z / (dθ/dz) · c.
        let factor = scales[c] / o.dtheta_dz(q);
        j.column_mut(c).scale_mut(factor);
    }
    j
}

/// The least-squares objective over the active quantities (indices into params then x0 of the spec).
struct Objective<'a> {
    model: &'a mut dyn FitModel,
    record: &'a Record,
    spec: &'a FitSpec,
    params: Vec<f64>,
    x0: Vec<f64>,
    active: Vec<usize>,
    /// The starting parameter values and initial state.
    start: (Vec<f64>, Vec<f64>),
}

impl Objective<'_> {
    fn np(&self) -> usize {
        self.spec.params.len()
    }

    fn name(&self, q: usize) -> &str {
        match self.spec.params.get(q) {
            Some(p) => &p.name,
            None => &self.spec.x0[q - self.np()].name,
        }
    }

    fn value(&self, q: usize) -> f64 {
        match self.spec.params.get(q) {
            Some(p) => self.params[p.index],
            None => self.x0[self.spec.x0[q - self.np()].index],
        }
    }

    fn restore(&mut self, q: usize, params: &[f64], x0: &[f64]) {
        match self.spec.params.get(q) {
            Some(p) => self.params[p.index] = params[p.index],
            None => {
                let i = self.spec.x0[q - self.np()].index;
                self.x0[i] = x0[i];
            }
        }
    }

    fn is_log(&self, q: usize) -> bool {
        self.spec.params.get(q).is_some_and(|p| p.log)
    }

    /// `dθ/dz` at the current value.
    fn dtheta_dz(&self, q: usize) -> f64 {
        if self.is_log(q) { self.value(q) } else { 1.0 }
    }

    /// The size `c` of each active quantity for relative statistics. A log-space parameter's is its value (the
    /// statistics are then those of `ln θ`); a linear-space parameter's is the larger of its value and its start,
    /// so a parameter that wandered towards zero is judged against the size it was expected to have; an initial
    /// state's is its value. 1 (one SI unit) when that is zero.
    fn scales(&self) -> Vec<f64> {
        self.active
            .iter()
            .map(|&q| {
                let size = match self.spec.params.get(q) {
                    Some(p) if !p.log => self.value(q).abs().max(self.start.0[p.index].abs()),
                    _ => self.value(q).abs(),
                };
                if size > 0.0 { size } else { 1.0 }
            })
            .collect()
    }

    /// The undetermined directions named, each with its dominant active quantity (one direction per quantity).
    fn name_directions(&self, directions: &[stats::Direction]) -> Vec<(usize, Undetermined)> {
        let mut out: Vec<(usize, Undetermined)> = Vec::new();
        for d in directions {
            let Some(&(k, _)) = d.combination.first() else {
                continue;
            };
            let q = self.active[k];
            if out.iter().any(|(held, _)| *held == q) {
                continue;
            }
            let combination = d
                .combination
                .iter()
                .map(|&(k, e)| (self.name(self.active[k]).to_string(), e))
                .collect();
            out.push((
                q,
                Undetermined {
                    combination,
                    relative_std_error: d.relative_std_error,
                    held: None,
                },
            ));
        }
        out
    }

    fn start_coordinates(&self) -> Vec<f64> {
        self.active
            .iter()
            .map(|&q| {
                let v = self.value(q);
                if self.is_log(q) { v.ln() } else { v }
            })
            .collect()
    }

    fn bounds(&self) -> (Vec<f64>, Vec<f64>) {
        self.active
            .iter()
            .map(|&q| match self.spec.params.get(q) {
                Some(p) if p.log => (p.lower.max(0.0).ln(), p.upper.ln()),
                Some(p) => (p.lower, p.upper),
                None => (f64::NEG_INFINITY, f64::INFINITY),
            })
            .unzip()
    }

    /// Sets the active quantities from optimiser coordinates.
    fn set(&mut self, z: &[f64]) {
        for (k, &q) in self.active.clone().iter().enumerate() {
            let v = if self.is_log(q) { z[k].exp() } else { z[k] };
            match self.spec.params.get(q) {
                Some(p) => self.params[p.index] = v,
                None => {
                    let i = self.spec.x0[q - self.np()].index;
                    self.x0[i] = v;
                }
            }
        }
    }

    fn simulate(&mut self) -> Result<sensitivity::Simulated, SensitivityError> {
        self.model
            .set_params(&self.params)
            .map_err(|message| SensitivityError::Model { time: 0.0, message })?;
        let np = self.np();
        let free_params: Vec<usize> = self
            .active
            .iter()
            .filter(|&&q| q < np)
            .map(|&q| self.spec.params[q].index)
            .collect();
        let free_x0: Vec<usize> = self
            .active
            .iter()
            .filter(|&&q| q >= np)
            .map(|&q| self.spec.x0[q - np].index)
            .collect();
        // Active quantities are listed parameters first, as the sensitivities order their columns.
        let scale: Vec<f64> = self.active.iter().map(|&q| self.dtheta_dz(q)).collect();
        let fitted = Fitted {
            params: &free_params,
            x0: &free_x0,
            scale: &scale,
        };
        if self.spec.interp == Interp::Zoh && self.model.is_linear() {
            return super::linear::simulate(&*self.model, self.record, &self.x0, &fitted);
        }
        sensitivity::simulate(
            &*self.model,
            self.record,
            self.spec.interp,
            &self.x0,
            &fitted,
            &self.spec.solver,
        )
    }

    fn report(
        &mut self,
        st: stats::Statistics,
        min: &Minimum,
        iterations: usize,
        undetermined: Vec<Undetermined>,
    ) -> Result<FitReport, FitError> {
        let sim = self
            .simulate()
            .map_err(|e| FitError::Model(e.to_string()))?;
        let n = self.spec.params.len() + self.spec.x0.len();
        let mut estimates = Vec::with_capacity(n);
        for q in 0..n {
            let start = match self.spec.params.get(q) {
                Some(p) => self.start.0[p.index],
                None => self.start.1[self.spec.x0[q - self.np()].index],
            };
            let active = self.active.iter().position(|&a| a == q);
            let name = self.name(q).to_string();
            // Not determined: held at its start, or the dominant quantity of a combination left free.
            let dominates = undetermined.iter().any(|u| {
                u.held.is_none() && u.combination.first().is_some_and(|(n, _)| *n == name)
            });
            estimates.push(Estimate {
                value: self.value(q),
                std_error: active.map_or(f64::NAN, |k| st.std_errors[k]),
                start,
                determined: active.is_some() && !dominates,
                name,
            });
        }
        let columns = self.record.outputs.len();
        let mut fitted = vec![Vec::with_capacity(sim.outputs.len()); columns];
        let mut sums = vec![(0.0, 0usize); columns];
        for (y, meas) in sim.outputs.iter().zip(&self.record.measured) {
            for (c, &o) in self.record.outputs.iter().enumerate() {
                fitted[c].push(y[o]);
                if !meas[c].is_nan() {
                    sums[c].0 += (y[o] - meas[c]).powi(2);
                    sums[c].1 += 1;
                }
            }
        }
        Ok(FitReport {
            estimates,
            correlation: st.correlation,
            correlated: self
                .active
                .iter()
                .map(|&q| self.name(q).to_string())
                .collect(),
            rms: sums
                .iter()
                .map(|&(s, k)| {
                    if k > 0 {
                        (s / k as f64).sqrt()
                    } else {
                        f64::NAN
                    }
                })
                .collect(),
            residual_variance: st.residual_variance,
            degrees_of_freedom: st.degrees_of_freedom,
            iterations,
            stop: min.stop,
            convergence: min.convergence,
            optimality: min.optimality,
            undetermined,
            params: self.params.clone(),
            x0: self.x0.clone(),
            fitted,
        })
    }
}

impl Residuals for Objective<'_> {
    fn step_limits(&self) -> Vec<f64> {
        self.active
            .iter()
            .map(|&q| {
                if self.is_log(q) {
                    self.spec.lm.max_log_step
                } else {
                    f64::INFINITY
                }
            })
            .collect()
    }

    /// A thousand units in the last place of the weighted measured values (their root sum of squares): the
    /// model's predictions are computed to about that.
    fn rounding_floor(&self) -> f64 {
        let weighted = || {
            self.record.measured.iter().flat_map(|meas| {
                meas.iter()
                    .enumerate()
                    .filter(|(_, v)| !v.is_nan())
                    .map(|(c, v)| self.spec.weights[c].sqrt() * v.abs())
            })
        };
        // Scaled by the largest value, so that the sum of squares of values near the limits of f64 neither
        // overflows (an infinite floor would call any fit exact) nor underflows.
        let largest = weighted().fold(0.0, f64::max);
        if !(largest > 0.0 && largest.is_finite()) {
            return 0.0;
        }
        let sum: f64 = weighted().map(|v| (v / largest).powi(2)).sum();
        ROUNDING_ULPS * f64::EPSILON * largest * sum.sqrt()
    }

    fn evaluate(&mut self, z: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>), String> {
        self.set(z);
        let sim = self.simulate().map_err(|e| e.to_string())?;
        let m = self.record.sample_count();
        let n = self.active.len();
        let mut r = DVector::zeros(m);
        let mut j = DMatrix::zeros(m, n);
        let mut row = 0;
        for ((y, dy), meas) in sim
            .outputs
            .iter()
            .zip(&sim.jacobians)
            .zip(&self.record.measured)
        {
            for (c, &o) in self.record.outputs.iter().enumerate() {
                if meas[c].is_nan() {
                    continue;
                }
                let w = self.spec.weights[c].sqrt();
                r[row] = w * (y[o] - meas[c]);
                for k in 0..n {
                    j[(row, k)] = w * dy[(o, k)];
                }
                row += 1;
            }
        }
        Ok((r, j))
    }
}

/// The rounding error of a prediction, in units in the last place of the measured values, below which a fit is
/// exact ([`Residuals::rounding_floor`]).
const ROUNDING_ULPS: f64 = 1e3;

/// The position of the first index that an earlier one repeats.
fn first_repeat(indices: impl Iterator<Item = usize>) -> Option<usize> {
    let mut seen = std::collections::HashSet::new();
    indices
        .enumerate()
        .find_map(|(k, i)| (!seen.insert(i)).then_some(k))
}
