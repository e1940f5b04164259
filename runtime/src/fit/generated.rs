//! A model of fixed size (a generated model, or any [`ContinuousModel`] with [`Parametric`]) as a [`FitModel`].
//! [`ParamJacobians`] is here with or without the `ode` feature (every generated `Model` implements it);
//! [`Generated`] needs the feature.
//!
//! `∂f/∂x` and `∂h/∂x` come from the model's `jac_x` and `output_jac_x` (symbolic in generated models). The
//! parameter Jacobians come from [`ParamJacobians`] when the model implements it ([`Generated::exact`]; every
//! generated `Model` does, from its symbolic `jac_p_into` and `output_jac_p_into`, which follow the derived
//! parameters and solve the model's loops and mass matrices), else from central differences over
//! [`Parametric::set_param`] ([`Generated::new`], for a hand-written model).
//!
//! [`ContinuousModel`]: crate::model::ContinuousModel
//! [`Parametric`]: crate::model::Parametric
//! [`Parametric::set_param`]: crate::model::Parametric::set_param
//! [`FitModel`]: crate::fit::FitModel

use nalgebra::SVector;

#[cfg(feature = "ode")]
mod adapter;
#[cfg(feature = "ode")]
pub use adapter::Generated;

/// The derivatives of the rates and outputs with respect to chosen parameters.
///
/// Both methods take the parameter indices of all the columns wanted at once: a generated model evaluates its
/// whole parameter Jacobian in one pass (the entries share subexpressions), so a fit with several free
/// parameters pays for one evaluation per rate, not one per parameter.
pub trait ParamJacobians<const NX: usize, const NU: usize, const NY: usize> {
    /// Writes `∂f/∂p_k` for each `k` of `indices` into `columns`, one column of `NX` values after another
    /// (column-major, as an `NX × indices.len()` matrix); false, with `columns` left unspecified, for an index
    /// out of range or `columns.len() != NX * indices.len()`.
    fn jac_p_columns(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        indices: &[usize],
        columns: &mut [f64],
    ) -> bool;

    /// Writes `∂h/∂p_k` for each `k` of `indices` into `columns` likewise (`NY` values per column).
    fn output_jac_p_columns(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        indices: &[usize],
        columns: &mut [f64],
    ) -> bool;
}
