//! One instance of the model: its parameters, time, states and inputs, the phase of the standard's state
//! machine it is in, and the Co-Simulation integrator. Shared by the FMI 2.0 and 3.0 interfaces, which only
//! translate their calls into these methods and the results into their status codes.

use crate::plant::{self, NU, NX, NY, Params, Var};
use crate::solver::Integrator;

/// The interface an instance was created for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    ModelExchange,
    CoSimulation,
}

/// The phases of the standard's state machine (the FMI 2.0 names; FMI 3.0 has the same ones).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    Instantiated,
    Initialization,
    Event,
    ContinuousTime,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
}

/// What an importer may restore with get/set FMU state.
#[derive(Clone, Debug)]
pub struct Snapshot {
    params: Params,
    t: f64,
    x: Vec<f64>,
    u: Vec<f64>,
    phase: Phase,
    h: f64,
}

pub struct Instance {
    pub name: String,
    pub kind: Kind,
    pub phase: Phase,
    pub logging: bool,
    params: Params,
    t: f64,
    x: Vec<f64>,
    u: Vec<f64>,
    integrator: Integrator,
}

/// The relative tolerance of Co-Simulation steps when the importer gives none.
const DEFAULT_TOLERANCE: f64 = 1e-8;

pub type Outcome<T> = Result<T, String>;

impl Instance {
    pub fn new(name: String, kind: Kind) -> Instance {
        Instance {
            name,
            kind,
            phase: Phase::Instantiated,
            logging: false,
            params: Params::default(),
            t: 0.0,
            x: vec![0.0; NX],
            u: vec![0.0; NU],
            integrator: Integrator::new(DEFAULT_TOLERANCE),
        }
    }

    /// Back to the state right after instantiation (`Reset`).
    pub fn reset(&mut self) {
        let logging = self.logging;
        *self = Instance::new(std::mem::take(&mut self.name), self.kind);
        self.logging = logging;
    }

    /// Refuses a call in a phase the standard does not allow it in.
    pub fn expect(&self, call: &str, allowed: &[Phase]) -> Outcome<()> {
        if allowed.contains(&self.phase) {
            Ok(())
        } else {
            Err(format!(
                "{call} is not allowed in the {:?} phase (allowed in {allowed:?})",
                self.phase
            ))
        }
    }

    pub fn setup(&mut self, tolerance: Option<f64>, start: f64) -> Outcome<()> {
        self.expect("SetupExperiment", &[Phase::Instantiated])?;
        if !start.is_finite() {
            return Err(format!("the start time {start} is not finite"));
        }
        if let Some(tol) = tolerance {
            if !(tol > 0.0 && tol < 1.0) {
                return Err(format!("the tolerance {tol} is not in (0, 1)"));
            }
            self.integrator = Integrator::new(tol);
        }
        self.t = start;
        Ok(())
    }

    pub fn time(&self) -> f64 {
        self.t
    }

    pub fn set_time(&mut self, t: f64) -> Outcome<()> {
        if !t.is_finite() {
            return Err(format!("the time {t} is not finite"));
        }
        self.t = t;
        Ok(())
    }

    pub fn states(&self) -> &[f64] {
        &self.x
    }

    pub fn set_states(&mut self, x: &[f64]) -> Outcome<()> {
        if let Some(k) = x.iter().position(|v| !v.is_finite()) {
            return Err(format!(
                "state {} = {} is not finite",
                plant::Var::State(k).name(),
                x[k]
            ));
        }
        self.x.copy_from_slice(x);
        Ok(())
    }

    pub fn derivatives(&self) -> Outcome<Vec<f64>> {
        let mut dx = vec![0.0; NX];
        plant::rhs(&self.params, self.t, &self.x, &self.u, &mut dx);
        finite(&dx, Var::Derivative, self.t)?;
        Ok(dx)
    }

    fn outputs(&self) -> Outcome<Vec<f64>> {
        let mut y = vec![0.0; NY];
        plant::outputs(&self.params, self.t, &self.x, &self.u, &mut y);
        finite(&y, Var::Output, self.t)?;
        Ok(y)
    }

    /// The values of `vrs`, computing outputs and derivatives only when asked for.
    pub fn get_real(&self, vrs: &[u32], values: &mut [f64]) -> Outcome<()> {
        let mut y = None;
        let mut dx = None;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            *value = match Var::of(*vr).ok_or_else(|| unknown(*vr))? {
                Var::Time => self.t,
                Var::Param(i) => self.params.get(i).ok_or_else(|| unknown(*vr))?,
                Var::Input(i) => self.u[i],
                Var::State(i) => self.x[i],
                Var::Output(i) => {
                    if y.is_none() {
                        y = Some(self.outputs()?);
                    }
                    y.as_ref().map_or(f64::NAN, |y| y[i])
                }
                Var::Derivative(i) => {
                    if dx.is_none() {
                        dx = Some(self.derivatives()?);
                    }
                    dx.as_ref().map_or(f64::NAN, |d| d[i])
                }
            };
        }
        Ok(())
    }

    /// Sets `vrs`: parameters and state start values before initialisation ends, inputs at any time.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Outcome<()> {
        let before_init = matches!(self.phase, Phase::Instantiated | Phase::Initialization);
        for (vr, &value) in vrs.iter().zip(values) {
            let var = Var::of(*vr).ok_or_else(|| unknown(*vr))?;
            if !value.is_finite() {
                return Err(format!("`{}` = {value} is not finite", var.name()));
            }
            match var {
                Var::Param(i) if before_init => self
                    .params
                    .set(i, value)
                    .map_err(|e| e.to_string())?,
                Var::State(i) if before_init => self.x[i] = value,
                Var::Input(i) => self.u[i] = value,
                Var::Param(_) | Var::State(_) => {
                    return Err(format!(
                        "`{}` can be set only before initialisation ends (now in the {:?} phase)",
                        var.name(),
                        self.phase
                    ));
                }
                Var::Time | Var::Output(_) | Var::Derivative(_) => {
                    return Err(format!("`{}` cannot be set", var.name()));
                }
            }
        }
        Ok(())
    }

    /// `Σ ∂unknown/∂known · seed` for each unknown (derivatives or outputs) over the knowns (states or inputs).
    pub fn directional_derivative(
        &self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> Outcome<()> {
        let jac = plant::full_jacobian(&self.params, self.t, &self.x, &self.u);
        let rows = NX + NY;
        let mut cols = Vec::with_capacity(knowns.len());
        for vr in knowns {
            cols.push(match Var::of(*vr).ok_or_else(|| unknown(*vr))? {
                Var::State(i) => i,
                Var::Input(i) => NX + i,
                other => {
                    return Err(format!(
                        "directional derivatives are taken with respect to states and inputs, not `{}`",
                        other.name()
                    ));
                }
            });
        }
        for (vr, o) in unknowns.iter().zip(out.iter_mut()) {
            let row = match Var::of(*vr).ok_or_else(|| unknown(*vr))? {
                Var::Derivative(i) => i,
                Var::Output(i) => NX + i,
                other => {
                    return Err(format!(
                        "directional derivatives are taken of state derivatives and outputs, not `{}`",
                        other.name()
                    ));
                }
            };
            *o = cols
                .iter()
                .zip(seed)
                .map(|(&c, s)| jac[c * rows + row] * s)
                .sum();
        }
        finite(out, |_| Var::Time, self.t)
            .map_err(|_| format!("a directional derivative is not finite at t = {}", self.t))
    }

    /// `Σ seed · ∂unknown/∂known` for each known: the transposed Jacobian times the seed (FMI 3.0's adjoint).
    pub fn adjoint_derivative(
        &self,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> Outcome<()> {
        let mut column = vec![0.0; unknowns.len()];
        for (known, o) in knowns.iter().zip(out.iter_mut()) {
            self.directional_derivative(
                unknowns,
                std::slice::from_ref(known),
                &[1.0],
                &mut column,
            )?;
            *o = column.iter().zip(seed).map(|(j, s)| j * s).sum();
        }
        Ok(())
    }

    /// Co-Simulation: integrates over `[t, t + h]` with the inputs held; on failure the state is unchanged.
    pub fn do_step(&mut self, t: f64, h: f64) -> Outcome<()> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(format!("the communication step {h} is not positive"));
        }
        if (t - self.t).abs() > 1e-9 * t.abs().max(1.0) {
            return Err(format!(
                "the communication point {t} is not the instance's time {}",
                self.t
            ));
        }
        let mut x = self.x.clone();
        self.integrator
            .advance(&self.params, self.t, self.t + h, &mut x, &self.u)
            .map_err(|f| f.0)?;
        self.x = x;
        self.t += h;
        Ok(())
    }

    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            params: self.params,
            t: self.t,
            x: self.x.clone(),
            u: self.u.clone(),
            phase: self.phase,
            h: self.integrator.h,
        }
    }

    pub fn restore(&mut self, s: &Snapshot) {
        self.params = s.params;
        self.t = s.t;
        self.x.clone_from(&s.x);
        self.u.clone_from(&s.u);
        self.phase = s.phase;
        self.integrator.h = s.h;
    }
}

/// Every value finite, or the message naming the first that is not.
fn finite(values: &[f64], var: impl Fn(usize) -> Var, t: f64) -> Outcome<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(k) => Err(format!(
            "`{}` is {} at t = {t} (an algebraic loop without solution, or a state outside the model's domain)",
            var(k).name(),
            values[k]
        )),
    }
}

fn unknown(vr: u32) -> String {
    format!("no variable has the value reference {vr}")
}
