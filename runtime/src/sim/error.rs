//! Errors of simulation.

/// Why a simulation stopped or could not start. Every runtime failure carries the simulated time at which
/// it happened.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// The ODE solver failed (step size underflow, Newton failure, ...).
    #[error("the ODE solver failed at t = {time:?}: {message}")]
    Solver { time: f64, message: String },
    /// The state became NaN or infinite: the model diverged or left its domain.
    #[error("the state became non-finite at t = {time:?} (state index {index})")]
    NonFiniteState { time: f64, index: usize },
    /// The model's right-hand side returned a non-finite derivative and the solver could not continue.
    #[error("the model returned a non-finite derivative at t = {time:?} (state index {index})")]
    NonFiniteDerivative { time: f64, index: usize },
    /// The model's outputs were non-finite at a sample instant.
    #[error("the model output {index} is non-finite at t = {time:?}")]
    NonFiniteOutput { time: f64, index: usize },
    /// The controller returned a non-finite input.
    #[error("the controller returned a non-finite input {index} at t = {time:?}")]
    NonFiniteInput { time: f64, index: usize },
    /// The solver took more internal steps than allowed within one segment.
    #[error(
        "more than {max_steps} solver steps between t = {from:?} and t = {to:?}; stopped at t = {time:?}"
    )]
    TooManySteps {
        from: f64,
        to: f64,
        time: f64,
        max_steps: usize,
    },
    /// A setting is out of range (sample time, tolerances, output times, noise levels, initial state).
    #[error("invalid simulation setting `{name}` = {value:?}: {reason}")]
    BadSetting {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// The exact discretisation of a linear plant failed (its matrix exponential overflowed).
    #[error("the zero-order-hold discretisation of the linear plant failed: {message}")]
    Discretisation { message: String },
    /// A linear plant built from a state-space model whose matrices do not have the plant's sizes.
    #[error("the linear plant does not match the state-space model: {message}")]
    PlantShape { message: String },
}
