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

/// The derivatives of the rates and outputs with respect to one parameter.
pub trait ParamJacobians<const NX: usize, const NU: usize, const NY: usize> {
    /// Writes `∂f/∂p_index` into `col`; false for an index out of range.
    fn jac_p(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        index: usize,
        col: &mut SVector<f64, NX>,
    ) -> bool;

    /// Writes `∂h/∂p_index` into `col`; false for an index out of range.
    fn output_jac_p(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        index: usize,
        col: &mut SVector<f64, NY>,
    ) -> bool;
}
