//! Linear plants in sampled-data loops: the exact zero-order-hold step.
//!
//! For `ẋ = A x + B u + w` with `u` and the process disturbance `w` held over `[t_k, t_k + T)`,
//!
//! `x_{k+1} = A_d x_k + B_d u_k + E_d w_k`, `[A_d B_d E_d] = [I 0 0] exp([A B I; 0 0 0] T)`
//!
//! (Van Loan's block exponential, as [`crate::linalg::c2d_zoh`] with the disturbance as an extra input). One
//! matrix exponential per run replaces an ODE solve per sample, and the step is exact up to rounding instead
//! of up to the solver's tolerance.
//!
//! The plant's matrices and the step's `A_d`, `B_d`, `E_d` are kept on the heap, and a step writes into
//! vectors only: a plant of any size runs on any thread (an `NX × NX` matrix exceeds a spawned thread's 2 MiB
//! stack at 512 states).

use nalgebra::{DMatrix, SMatrix, SVector};

use super::error::SimError;
use crate::linalg::{DiscretizeError, zoh_blocks};
use crate::linearize::BoxedJacobians;
use crate::matrix::{boxed_copy, boxed_fixed, dynamic, product_sum, zeroed_box};
use crate::model::ContinuousModel;
use crate::statespace::StateSpace;

/// A linear time-invariant plant `ẋ = A x + B u`, `y = C x + D u`, its matrices on the heap.
///
/// [`LinearPlant::new`] takes the matrices by value (a small plant); [`LinearPlant::from_state_space`] and
/// [`LinearPlant::from_jacobians`] build a plant of any size without a matrix on the stack.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearPlant<const NX: usize, const NU: usize, const NY: usize> {
    pub a: Box<SMatrix<f64, NX, NX>>,
    pub b: Box<SMatrix<f64, NX, NU>>,
    pub c: Box<SMatrix<f64, NY, NX>>,
    pub d: Box<SMatrix<f64, NY, NU>>,
}

impl<const NX: usize, const NU: usize, const NY: usize> LinearPlant<NX, NU, NY> {
    /// The plant of the given matrices (each moved to the heap; for a plant whose matrices fit the stack).
    pub fn new(
        a: SMatrix<f64, NX, NX>,
        b: SMatrix<f64, NX, NU>,
        c: SMatrix<f64, NY, NX>,
        d: SMatrix<f64, NY, NU>,
    ) -> Self {
        LinearPlant {
            a: boxed_copy(&a),
            b: boxed_copy(&b),
            c: boxed_copy(&c),
            d: boxed_copy(&d),
        }
    }

    /// The plant of a continuous-time [`StateSpace`] (a linearisation, a design model), copied to the heap
    /// entry by entry; an error naming the matrix whose shape is not `NX`, `NU`, `NY`'s, or when `ss` is
    /// discrete.
    pub fn from_state_space(ss: &StateSpace) -> Result<Self, SimError> {
        if let Some(dt) = ss.dt() {
            return Err(SimError::BadSetting {
                name: "linear plant sample time",
                value: dt,
                reason: "a linear plant is continuous-time; discretisation is the loop's",
            });
        }
        let shape = |e: crate::linalg::MatrixError| SimError::PlantShape {
            message: e.to_string(),
        };
        Ok(LinearPlant {
            a: boxed_fixed("A", ss.a()).map_err(shape)?,
            b: boxed_fixed("B", ss.b()).map_err(shape)?,
            c: boxed_fixed("C", ss.c()).map_err(shape)?,
            d: boxed_fixed("D", ss.d()).map_err(shape)?,
        })
    }

    /// The plant of a linearisation's Jacobians ([`crate::linearize::boxed_jacobians_at`]), without a copy.
    pub fn from_jacobians(j: BoxedJacobians<NX, NU, NY>) -> Self {
        LinearPlant {
            a: j.a,
            b: j.b,
            c: j.c,
            d: j.d,
        }
    }
}

impl<const NX: usize, const NU: usize, const NY: usize> ContinuousModel<NX, NU, NY>
    for LinearPlant<NX, NU, NY>
{
    fn rhs(&self, _t: f64, x: &SVector<f64, NX>, u: &SVector<f64, NU>, dx: &mut SVector<f64, NX>) {
        *dx = product_sum(&self.a, x, &self.b, u);
    }

    fn outputs(
        &self,
        _t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        y: &mut SVector<f64, NY>,
    ) {
        *y = product_sum(&self.c, x, &self.d, u);
    }

    fn jac_x(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NX>,
    ) {
        jac.copy_from(&self.a);
    }

    fn jac_u(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NX, NU>,
    ) {
        jac.copy_from(&self.b);
    }

    fn output_jac_x(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NX>,
    ) {
        jac.copy_from(&self.c);
    }

    fn output_jac_u(
        &self,
        _t: f64,
        _x: &SVector<f64, NX>,
        _u: &SVector<f64, NU>,
        jac: &mut SMatrix<f64, NY, NU>,
    ) {
        jac.copy_from(&self.d);
    }
}

/// The exact one-sample step of a [`LinearPlant`] under zero-order hold (see the module docs).
pub(crate) struct ZohStep<const NX: usize, const NU: usize> {
    ad: Box<SMatrix<f64, NX, NX>>,
    bd: Box<SMatrix<f64, NX, NU>>,
    ed: Box<SMatrix<f64, NX, NX>>,
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
        // The disturbance enters as a second input of identity gain: `E_d` is the last block of `B_d`.
        let mut b = DMatrix::<f64>::zeros(NX, NU + NX);
        b.columns_mut(0, NU).copy_from(&*plant.b);
        b.columns_mut(NU, NX).fill_with_identity();
        let (ad, bd) = zoh_blocks(&dynamic(&plant.a), &b, t).map_err(|e| SimError::Discretisation {
            message: match e {
                // Finite matrices whose product with T left f64: not a non-finite entry of the caller's A.
                DiscretizeError::Overflow { .. } => format!(
                    "the sample time of {t:?} s is too long for the plant's rates: A T or B T overflows f64"
                ),
                other => other.to_string(),
            },
        })?;
        let mut step = ZohStep {
            ad: zeroed_box::<NX, NX>(),
            bd: zeroed_box::<NX, NU>(),
            ed: zeroed_box::<NX, NX>(),
        };
        step.ad.copy_from(&ad);
        step.bd.copy_from(&bd.columns(0, NU));
        step.ed.copy_from(&bd.columns(NU, NX));
        Ok(step)
    }

    /// `A_d x + B_d u + E_d w`.
    pub fn advance(
        &self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        w: &SVector<f64, NX>,
    ) -> SVector<f64, NX> {
        let (ad, bd, ed) = (&*self.ad, &*self.bd, &*self.ed);
        ad * x + bd * u + ed * w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::SMatrix;

    /// A plant whose rates times the sample time overflow is refused for its sample time (it was reported as a
    /// non-finite entry of `A`, which the caller's `A` does not have).
    #[test]
    fn a_sample_time_too_long_for_the_rates_is_named() {
        let plant = LinearPlant::new(
            SMatrix::<f64, 1, 1>::new(-1e300),
            SMatrix::<f64, 1, 1>::new(1.0),
            SMatrix::<f64, 1, 1>::new(1.0),
            SMatrix::<f64, 1, 1>::zeros(),
        );
        match ZohStep::new(&plant, 1e10) {
            Err(SimError::Discretisation { message }) => {
                assert!(
                    message.contains("is too long for the plant's rates"),
                    "{message}"
                )
            }
            Err(other) => panic!("expected a discretisation error, got {other:?}"),
            Ok(_) => panic!("expected a discretisation error"),
        }
    }
}
