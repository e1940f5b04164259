//! The settings of the ODE solver behind the nonlinear simulations and fits: plain data, present with or without
//! the `ode` feature, so that configurations (such as [`super::SampledLoopConfig`]) keep one shape.

use super::error::SimError;

/// The integration method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Variable-order variable-step BDF (orders 1–5): for stiff models. The default.
    #[default]
    Bdf,
    /// Singly diagonally implicit Runge–Kutta ESDIRK3(4): stiff, one-step (cheap restarts).
    Esdirk34,
    /// TR-BDF2 (an ESDIRK of order 2): stiff, robust, low order.
    TrBdf2,
    /// Tsitouras 5(4) explicit Runge–Kutta: for non-stiff models.
    Tsit45,
}

/// Solver settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverOptions {
    pub method: Method,
    /// Relative tolerance of the local error test.
    pub rtol: f64,
    /// Absolute tolerance of the local error test (all states).
    pub atol: f64,
    /// Upper bound on internal steps within one segment (one sample interval or one open-loop run).
    pub max_steps: usize,
}

impl Default for SolverOptions {
    fn default() -> Self {
        SolverOptions {
            method: Method::Bdf,
            rtol: 1e-8,
            atol: 1e-10,
            max_steps: 1_000_000,
        }
    }
}

impl SolverOptions {
    pub(crate) fn check(&self) -> Result<(), SimError> {
        for (name, value) in [("rtol", self.rtol), ("atol", self.atol)] {
            if !(value.is_finite() && value > 0.0) {
                return Err(SimError::BadSetting {
                    name,
                    value,
                    reason: "tolerances must be finite and positive",
                });
            }
        }
        if self.max_steps == 0 {
            return Err(SimError::BadSetting {
                name: "max_steps",
                value: 0.0,
                reason: "at least one step must be allowed",
            });
        }
        Ok(())
    }
}
