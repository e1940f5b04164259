//! The back-support exoskeleton of Shojaei Barjuei, Caldwell & Ortiz, "Bond Graph Modeling and Kalman Filter
//! Observer Design for an Industrial Back-Support Exoskeleton", Designs 2020, 4, 53, end to end: model check,
//! LQR with integral action, observer, lifting scenario and robustness, as the `back_support` example prints
//! them and its integration test checks them.
//!
//! - [`params`]: the physical parameters;
//! - [`plant`]: the plant (Eq. 3), taken from the model bgc generates from `models/back_support.bg`, and the
//!   6-state design model in angles relative to the trunk;
//! - [`block_diagram`]: Eq. 1, coded independently, and [`model_check`]: Sec. 5.1;
//! - [`lqr`]: Eqs. 10–17; [`observer`]: Eqs. 4–9 with the noise of Sec. 4;
//! - [`scenario`]: the lifting task of Sec. 5.2; [`robustness`]: margins and disturbance rejection;
//! - [`recovery`]: the observer retuned by loop transfer recovery for margins.
//!
//! [`study`] runs all of it.

pub mod block_diagram;
pub mod identification;
pub mod lqr;
pub mod model_check;
pub mod observer;
pub mod params;
pub mod plant;
pub mod recovery;
pub mod robustness;
pub mod scenario;

use std::fmt;

use bgc_runtime::analysis::AnalysisError;
use bgc_runtime::design::DesignError;
use bgc_runtime::estimation::EstimationError;
use bgc_runtime::linalg::{DiscretizeError, PbhError, RiccatiError};
use bgc_runtime::model::ParamError;
use bgc_runtime::sim::SimError;
use bgc_runtime::statespace::StateSpaceError;

/// Why a step of the study failed.
#[derive(Clone, Debug, PartialEq)]
pub enum BackSupportError {
    /// A physical parameter is out of its domain.
    Parameter {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    /// The plant does not leave the rigid rotation with the trunk force-free (relative residual).
    NotRigidInvariant {
        residual: f64,
    },
    /// An inconsistent setting of the study.
    Setup {
        what: &'static str,
    },
    /// The generated model refused the parameters.
    ModelParameter(ParamError),
    StateSpace(StateSpaceError),
    Simulation(SimError),
    Design(DesignError),
    Riccati(RiccatiError),
    Discretize(DiscretizeError),
    Pbh(PbhError),
    Estimation(EstimationError),
    Analysis(AnalysisError),
    Recovery(bgc_runtime::design::LtrError),
}

impl fmt::Display for BackSupportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BackSupportError::Parameter {
                name,
                value,
                reason,
            } => write!(f, "parameter {name} = {value}: {reason}"),
            BackSupportError::NotRigidInvariant { residual } => write!(
                f,
                "the plant is not invariant under a rigid rotation with the trunk (relative residual \
                 {residual:e}); the relative-angle design model does not apply"
            ),
            BackSupportError::Setup { what } => write!(f, "{what}"),
            BackSupportError::ModelParameter(e) => write!(f, "generated model: {e}"),
            BackSupportError::StateSpace(e) => write!(f, "state-space model: {e}"),
            BackSupportError::Simulation(e) => write!(f, "simulation: {e}"),
            BackSupportError::Design(e) => write!(f, "LQR design: {e}"),
            BackSupportError::Riccati(e) => write!(f, "observer design: {e}"),
            BackSupportError::Discretize(e) => write!(f, "discretisation: {e}"),
            BackSupportError::Pbh(e) => write!(f, "observability test: {e}"),
            BackSupportError::Estimation(e) => write!(f, "Kalman filter: {e}"),
            BackSupportError::Analysis(e) => write!(f, "frequency analysis: {e}"),
            BackSupportError::Recovery(e) => write!(f, "loop transfer recovery: {e}"),
        }
    }
}

impl std::error::Error for BackSupportError {}

macro_rules! from_error {
    ($($source:ty => $variant:ident),* $(,)?) => {
        $(impl From<$source> for BackSupportError {
            fn from(e: $source) -> Self {
                BackSupportError::$variant(e)
            }
        })*
    };
}

from_error!(
    ParamError => ModelParameter,
    StateSpaceError => StateSpace,
    SimError => Simulation,
    DesignError => Design,
    RiccatiError => Riccati,
    DiscretizeError => Discretize,
    PbhError => Pbh,
    EstimationError => Estimation,
    AnalysisError => Analysis,
);

/// Everything the example reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    pub params: params::Params,
    pub model_check: model_check::ModelCheck,
    pub lqr: lqr::LqrDesigns,
    pub seven_state: Vec<observer::SevenStateCase>,
    pub observer: observer::ObserverDesign,
    /// The scenario with the double design of Eq. 15.
    pub scenario: scenario::ScenarioResult,
    /// The scenario with the double design with `q_z = 10¹³` ([`lqr::LqrDesigns::double_reproducing`]).
    pub scenario_reproducing: scenario::ScenarioResult,
    pub robustness: robustness::Robustness,
    /// The observer retuned by loop transfer recovery, with its margins and scenario.
    pub recovery: recovery::Recovery,
}

/// Runs the whole study with the paper's parameters and the given scenario settings.
pub fn study(cfg: &scenario::ScenarioConfig) -> Result<Study, BackSupportError> {
    let p = params::Params::paper();
    let plant = plant::plant(&p)?;
    let model = plant::design_model(&plant, &p)?;
    let check = model_check::model_check(&p)?;
    let lqr = lqr::designs(&model)?;
    let seven_state = observer::seven_state_check(&plant, &cfg.noise, cfg.sample_time)?;
    let obs = observer::design(&model, &cfg.noise, cfg.sample_time)?;
    let run = scenario::run(&p, &plant, &model, &lqr.double, &obs, cfg)?;
    let run_reproducing = scenario::run(&p, &plant, &model, &lqr.double_reproducing, &obs, cfg)?;
    let robustness = robustness::analyse(&model, &lqr.double, &obs.continuous.l, &obs)?;
    let recovery = recovery::recover(&p, &plant, &model, &lqr.double, cfg)?;
    Ok(Study {
        params: p,
        model_check: check,
        lqr,
        seven_state,
        observer: obs,
        scenario: run,
        scenario_reproducing: run_reproducing,
        robustness,
        recovery,
    })
}
