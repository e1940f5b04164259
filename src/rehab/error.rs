//! Errors of the measurement-system simulation.

use bgc_runtime::estimation::EstimationError;
use bgc_runtime::sim::SimError;
use std::fmt;

/// Why a run of the measurement-system simulation could not give its figures.
#[derive(Clone, Debug, PartialEq)]
pub enum RehabError {
    /// Simulating a plant model failed.
    Simulation {
        model: &'static str,
        source: SimError,
    },
    /// An estimator refused its settings or failed.
    Estimation {
        stage: &'static str,
        source: EstimationError,
    },
    /// A setting is out of its domain.
    BadSetting {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// Too few finite samples to compute a figure.
    TooFewSamples { what: &'static str, count: usize },
    /// A generated model lacks a state or output the study reads (the `.bg` file renamed or removed it).
    ModelLayout {
        model: &'static str,
        kind: &'static str,
        name: &'static str,
    },
}

impl fmt::Display for RehabError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RehabError::Simulation { model, source } => {
                write!(f, "simulating the {model} model failed: {source}")
            }
            RehabError::Estimation { stage, source } => write!(f, "{stage} failed: {source}"),
            RehabError::BadSetting {
                name,
                value,
                reason,
            } => write!(f, "invalid setting `{name}` = {value}: {reason}"),
            RehabError::TooFewSamples { what, count } => {
                write!(f, "too few finite samples for {what} ({count})")
            }
            RehabError::ModelLayout { model, kind, name } => {
                write!(
                    f,
                    "the generated {model} model has no {kind} named `{name}`"
                )
            }
        }
    }
}

impl std::error::Error for RehabError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            RehabError::Simulation { source, .. } => Some(source),
            RehabError::Estimation { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Checks that a setting is finite and positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64, RehabError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(RehabError::BadSetting {
            name,
            value,
            reason: "must be finite and positive",
        })
    }
}

/// Checks that a setting is finite and not negative.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64, RehabError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(RehabError::BadSetting {
            name,
            value,
            reason: "must be finite and not negative",
        })
    }
}
