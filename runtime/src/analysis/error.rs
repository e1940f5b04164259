//! Errors of frequency-domain analysis and interconnection.

use crate::statespace::StateSpaceError;

/// Why a frequency response, a margin or an interconnection could not be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum AnalysisError {
    /// `s I − A` (or `z I − A`) is singular at this frequency: the model has a pole on the evaluation contour.
    #[error(
        "the model has a pole at (or numerically at) frequency {omega:?} rad/s: sI - A is singular there"
    )]
    PoleOnContour { omega: f64 },
    /// The linear solve at this frequency left a residual too large to trust the result.
    #[error(
        "frequency response at {omega:?} rad/s is ill-conditioned (relative residual {residual:e})"
    )]
    IllConditioned { omega: f64, residual: f64 },
    /// The response at this frequency exceeds the range of `f64` (the model's entries are finite but their
    /// products overflow).
    #[error(
        "the frequency response at {omega:?} rad/s overflows f64: the model's entries are too large for its products to be represented"
    )]
    Overflow { omega: f64 },
    /// A frequency was negative, zero where not allowed, or non-finite.
    #[error("frequency {omega:?} is not a valid evaluation frequency: {reason}")]
    BadFrequency { omega: f64, reason: &'static str },
    /// A discrete-time model was evaluated above its Nyquist frequency `π / dt`.
    #[error(
        "frequency {omega:?} rad/s is above the Nyquist frequency {nyquist:?} rad/s of the discrete model"
    )]
    AboveNyquist { omega: f64, nyquist: f64 },
    /// A frequency grid was asked with invalid bounds or length.
    #[error("frequency grid from {low} to {high} with {points} points is invalid: {reason}")]
    BadGrid {
        low: f64,
        high: f64,
        points: usize,
        reason: &'static str,
    },
    /// The analysis needs a single-input single-output model.
    #[error("{what} needs a SISO model, got {inputs} inputs and {outputs} outputs")]
    NotSiso {
        what: &'static str,
        inputs: usize,
        outputs: usize,
    },
    /// An input or output index is outside the model.
    #[error(
        "channel (output {output}, input {input}) does not exist in a model with {outputs} outputs and {inputs} inputs"
    )]
    NoSuchChannel {
        output: usize,
        input: usize,
        outputs: usize,
        inputs: usize,
    },
    /// Two models in an interconnection have incompatible sizes.
    #[error("{operation}: {detail} ({left} vs {right})")]
    SizeMismatch {
        operation: &'static str,
        detail: &'static str,
        left: usize,
        right: usize,
    },
    /// Two models in an interconnection have different time domains or sample times.
    #[error("{operation}: models have different sample times ({left:?} vs {right:?})")]
    TimebaseMismatch {
        operation: &'static str,
        left: Option<f64>,
        right: Option<f64>,
    },
    /// The feedback interconnection has an algebraic loop `I ∓ D1 D2` that is singular.
    #[error(
        "feedback: the algebraic loop I - sign*D1*D2 is singular; the interconnection is ill-posed"
    )]
    IllPosedFeedback,
    /// The DC gain is infinite (a pole at s = 0 or z = 1), so a bandwidth relative to it does not exist.
    #[error("the DC gain is infinite (pole at s = 0 or z = 1)")]
    InfiniteDcGain,
    /// The DC gain is zero, so no drop relative to it can be measured.
    #[error("the DC gain is zero; a bandwidth relative to it is undefined")]
    ZeroDcGain,
    /// A gain, sign or drop parameter is not acceptable.
    #[error("parameter `{name}` = {value} is invalid: {reason}")]
    BadParameter {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// Building the resulting state-space model failed (non-finite entries).
    #[error("the interconnection produced an invalid model: {0}")]
    Model(#[from] StateSpaceError),
}
