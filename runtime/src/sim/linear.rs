//! Linear plants in sampled-data loops: the exact zero-order-hold step.
//!
//! For `ẋ = A x + B u + w` with `u` and the process disturbance `w` held over `[t_k, t_k + T)`,
//!
//! `x_{k+1} = A_d x_k + B_d u_k + E_d w_k`, `[A_d B_d E_d] = [I 0 0] exp([A B I; 0 0 0] T)`
//!
//! (Van Loan's block exponential, as [`crate::linalg::c2d_zoh`] with the disturbance as an extra input). One
//! matrix exponential per run replaces an ODE solve per sample, and the step is exact up to rounding instead
//! of up to the solver's tolerance.

use nalgebra::{DMatrix, SMatrix, SVector};

use super::error::SimError;
use crate::linalg::expm;
use crate::model::ContinuousModel;

/// A linear time-invariant plant `ẋ = A x + B u`, `y = C x + D u`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearPlant<const NX: usize, const NU: usize, const NY: usize> {
    pub a: SMatrix<f64, NX, NX>,
    pub b: SMatrix<f64, NX, NU>,
    pub c: SMatrix<f64, NY, NX>,
    pub d: SMatrix<f64, NY, NU>,
}

impl<const NX: usize, const NU: usize, const NY: usize> ContinuousModel<NX, NU, NY>
    for LinearPlant<NX, NU, NY>
{
    fn rhs(&self, _t: f64, x: &SVector<f64, NX>, u: &SVector<f64, NU>, dx: &mut SVector<f64, NX>) {
        *dx = self.a * x + self.b * u;
    }

    fn outputs(
        &self,
        _t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        y: &mut SVector<f64, NY>,
    ) {
        *y = self.c * x + self.d * u;
    }

    fn jac_x(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NX>,
    ) {
        *jac = self.a;
    }

    fn jac_u(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NU>,
    ) {
        *jac = self.b;
    }

    fn output_jac_x(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NX>,
    ) {
        *jac = self.c;
    }

    fn output_jac_u(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NU>,
    ) {
        *jac = self.d;
    }
}

/// The exact one-sample step of a [`LinearPlant`] under zero-order hold (see the module docs).
pub(crate) struct ZohStep<const NX: usize, const NU: usize> {
    ad: SMatrix<f64, NX, NX>,
    bd: SMatrix<f64, NX, NU>,
    ed: SMatrix<f64, NX, NX>,
}

impl<const NX: usize, const NU: usize> ZohStep<NX, NU> {
    /// Discretises `plant` with sample time `t`; refuses non-finite plant matrices and a failed exponential.
    pub fn new<const NY: usize>(plant: &LinearPlant<NX, NU, NY>, t: f64) -> Result<Self, SimError> {
        let entries = plant.a.iter().chain(plant.b.iter());
        let entries = entries.chain(plant.c.iter()).chain(plant.d.iter());
        if let Some(&v) = entries.clone().find(|v| !v.is_finite()) {
            return Err(SimError::BadSetting {
                name: "linear plant matrix",
                value: v,
                reason: "the matrices A, B, C, D of a linear plant must be finite",
            });
        }
        let size = 2 * NX + NU;
        let mut big = DMatrix::<f64>::zeros(size, size);
        for i in 0..NX {
            for j in 0..NX {
                big[(i, j)] = plant.a[(i, j)] * t;
            }
            for j in 0..NU {
                big[(i, NX + j)] = plant.b[(i, j)] * t;
            }
            big[(i, NX + NU + i)] = t;
        }
        let e = expm(&big).map_err(|e| SimError::Discretisation {
            message: e.to_string(),
        })?;
        Ok(ZohStep {
            ad: SMatrix::from_fn(|i, j| e[(i, j)]),
            bd: SMatrix::from_fn(|i, j| e[(i, NX + j)]),
            ed: SMatrix::from_fn(|i, j| e[(i, NX + NU + j)]),
        })
    }

    /// `A_d x + B_d u + E_d w`.
    pub fn advance(
        &self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NX>,
    ) -> SVector<f64, NX> {
        self.ad * x + self.bd * u + self.ed * w
    }
}
