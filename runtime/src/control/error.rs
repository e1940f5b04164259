//! Errors of the controllers and the gait supervisor.

/// Why a controller could not be built or could not compute a command.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ControlError {
    #[error("impedance gain `{name}` has a non-finite entry at ({row}, {col})")]
    NonFiniteGain {
        name: &'static str,
        row: usize,
        col: usize,
    },
    #[error("the impedance inertia M_r is singular; Eq. (29) needs its inverse")]
    SingularInertiaGain,
    #[error("torque limit of joint {joint} is {value:?}; limits must be finite and non-negative")]
    BadTorqueLimit { joint: usize, value: f64 },
    #[error("controller input `{name}`[{index}] = {value:?} is not finite")]
    NonFiniteInput {
        name: &'static str,
        index: usize,
        value: f64,
    },
    #[error("the manipulator model returned a non-finite {term}")]
    NonFiniteModel { term: &'static str },
    #[error("gait threshold `{name}` = {value:?} is invalid: {reason}")]
    BadThreshold {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
}
