//! The model traits that estimators, controllers and the simulator are written against.
//!
//! Generated model modules (the `models` crate, via `bgc::build`) implement these traits, and so do the
//! hand-written models of tests. Sizes are const generics so that a control loop works on stack-allocated
//! `SVector`/`SMatrix` values and allocates nothing.

use nalgebra::{SMatrix, SVector};

/// A continuous-time model `ẋ = f(t, x, u)`, `y = h(t, x, u)` with `NX` states, `NU` inputs and `NY` outputs.
///
/// Implementations must not allocate or panic in any method; values outside the model's domain give non-finite
/// results that callers check.
pub trait ContinuousModel<const NX: usize, const NU: usize, const NY: usize> {
    /// Writes `f(t, x, u)` into `dx`.
    fn rhs(&self, t: f64, x: &SVector<f64, NX>, u: &SVector<f64, NU>, dx: &mut SVector<f64, NX>);

    /// Writes `h(t, x, u)` into `y`.
    fn outputs(&self, t: f64, x: &SVector<f64, NX>, u: &SVector<f64, NU>, y: &mut SVector<f64, NY>);

    /// Writes `∂f/∂x` into `jac`. The default is a central finite difference; generated models override it
    /// with their symbolic Jacobian.
    fn jac_x(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NX>,
    ) {
        let mut xp = *x;
        let mut fp = SVector::<f64, NX>::zeros();
        let mut fm = SVector::<f64, NX>::zeros();
        for j in 0..NX {
            let h = fd_step(x[j]);
            xp[j] = x[j] + h;
            self.rhs(t, &xp, u, &mut fp);
            xp[j] = x[j] - h;
            self.rhs(t, &xp, u, &mut fm);
            xp[j] = x[j];
            jac.set_column(j, &((fp - fm) / (2.0 * h)));
        }
    }

    /// Writes `∂f/∂u` into `jac` (default: central finite difference).
    fn jac_u(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NU>,
    ) {
        let mut up = *u;
        let mut fp = SVector::<f64, NX>::zeros();
        let mut fm = SVector::<f64, NX>::zeros();
        for j in 0..NU {
            let h = fd_step(u[j]);
            up[j] = u[j] + h;
            self.rhs(t, x, &up, &mut fp);
            up[j] = u[j] - h;
            self.rhs(t, x, &up, &mut fm);
            up[j] = u[j];
            jac.set_column(j, &((fp - fm) / (2.0 * h)));
        }
    }

    /// Writes `∂h/∂x` into `jac` (default: central finite difference).
    fn output_jac_x(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NX>,
    ) {
        let mut xp = *x;
        let mut yp = SVector::<f64, NY>::zeros();
        let mut ym = SVector::<f64, NY>::zeros();
        for j in 0..NX {
            let h = fd_step(x[j]);
            xp[j] = x[j] + h;
            self.outputs(t, &xp, u, &mut yp);
            xp[j] = x[j] - h;
            self.outputs(t, &xp, u, &mut ym);
            xp[j] = x[j];
            jac.set_column(j, &((yp - ym) / (2.0 * h)));
        }
    }

    /// Writes `∂h/∂u` into `jac` (default: central finite difference).
    fn output_jac_u(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NU>,
    ) {
        let mut up = *u;
        let mut yp = SVector::<f64, NY>::zeros();
        let mut ym = SVector::<f64, NY>::zeros();
        for j in 0..NU {
            let h = fd_step(u[j]);
            up[j] = u[j] + h;
            self.outputs(t, x, &up, &mut yp);
            up[j] = u[j] - h;
            self.outputs(t, x, &up, &mut ym);
            up[j] = u[j];
            jac.set_column(j, &((yp - ym) / (2.0 * h)));
        }
    }
}

/// A model whose parameters can be read and changed at run time by index (for parameter estimation).
pub trait Parametric {
    /// Parameter names in index order.
    fn param_names(&self) -> &'static [&'static str];
    fn param(&self, index: usize) -> Option<f64>;
    /// Sets a parameter; a non-physical value (or an index out of range) is refused with a reason.
    fn set_param(&mut self, index: usize, value: f64) -> Result<(), ParamError>;
}

/// Why a parameter value was refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    #[error("no parameter with index {index}")]
    NoSuchParam { index: usize },
    #[error("parameter `{name}` = {value:?} is not physical: {reason}")]
    NonPhysical {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
}

/// A discrete-time model `x[k+1] = F(x[k], u[k])`, `y[k] = H(x[k], u[k])`.
pub trait DiscreteModel<const NX: usize, const NU: usize, const NY: usize> {
    fn step(&self, x: &SVector<f64, NX>, u: &SVector<f64, NU>, next: &mut SVector<f64, NX>);
    fn outputs(&self, x: &SVector<f64, NX>, u: &SVector<f64, NU>, y: &mut SVector<f64, NY>);
}

/// A step for central differences that balances truncation and rounding error.
fn fd_step(x: f64) -> f64 {
    6.0554544523933395e-6 * x.abs().max(1.0) // cbrt(f64::EPSILON)
}
