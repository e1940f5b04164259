//! Linearisation of a nonlinear model at an operating point, for the linear designs of [`crate::design`].
//!
//! [`linearize`] evaluates `A = ∂f/∂x`, `B = ∂f/∂u`, `C = ∂h/∂x`, `D = ∂h/∂u` at `(x₀, u₀)` through the
//! [`ContinuousModel`] methods `jac_x`, `jac_u`, `output_jac_x`, `output_jac_u`: a generated model implements
//! them with its symbolic Jacobians (exact, including the mass-matrix solve of an I-field and the implicit
//! derivatives of a nonlinear algebraic loop), a hand-written model gets the traits' central differences unless
//! it overrides them.
//!
//! The result describes deviations `δx = x − x₀`, `δu = u − u₀`, `δy = y − h(x₀, u₀)`:
//! `δẋ = A δx + B δu + f(x₀, u₀)`. Linear designs assume `f(x₀, u₀) = 0` (an equilibrium); [`linearize`] does not
//! require it (a linearisation along a trajectory is legitimate), so check `rhs` at the point when the design
//! needs an equilibrium.
//!
//! # Large models
//!
//! An `NX × NX` matrix takes `8 NX²` bytes: 2 MiB (a spawned thread's default stack) at 512 states, 8 MB at
//! 1,000. [`linearize`], [`linearize_at`] and [`boxed_jacobians_at`] allocate each Jacobian on the heap,
//! zeroed, and let the model write into it there, so they run at any size on any thread. [`jacobians_at`]
//! returns the matrices by value, on the caller's stack: for a control loop or filter of a small model.

use crate::matrix::{FixedStateSpace, dynamic};
use crate::model::ContinuousModel;
use crate::statespace::{StateSpace, StateSpaceError};
use nalgebra::{SMatrix, SVector};

/// Why a linearisation failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LinearizeError {
    #[error("the operating point is not finite: {what}[{index}] = {value:?}")]
    NonFinitePoint {
        what: &'static str,
        index: usize,
        value: f64,
    },
    /// A Jacobian entry is NaN or infinite at the point (outside the model's domain, a singular mass matrix or
    /// an algebraic loop without a solution there).
    #[error(
        "{name}[({row}, {col})] = {value:?} at the operating point: the model has no linearisation there"
    )]
    NonFiniteJacobian {
        name: &'static str,
        row: usize,
        col: usize,
        value: f64,
    },
    #[error(transparent)]
    StateSpace(#[from] StateSpaceError),
}

/// The linearisation `(A, B, C, D)` of a time-invariant `model` at the operating point `(x0, u0)` (at `t = 0`;
/// see [`linearize_at`] for a model that depends on time), ready for `lqr`, `lqi`, `lqe` or `c2d_zoh`.
pub fn linearize<M, const NX: usize, const NU: usize, const NY: usize>(
    model: &M,
    x0: &SVector<f64, NX>,
    u0: &SVector<f64, NU>,
) -> Result<StateSpace, LinearizeError>
where
    M: ContinuousModel<NX, NU, NY>,
{
    linearize_at(model, 0.0, x0, u0)
}

/// The linearisation `(A, B, C, D)` of `model` at time `t` and the operating point `(x0, u0)`.
pub fn linearize_at<M, const NX: usize, const NU: usize, const NY: usize>(
    model: &M,
    t: f64,
    x0: &SVector<f64, NX>,
    u0: &SVector<f64, NU>,
) -> Result<StateSpace, LinearizeError>
where
    M: ContinuousModel<NX, NU, NY>,
{
    let j = boxed_jacobians_at(model, t, x0, u0)?;
    Ok(StateSpace::new(
        dynamic(&j.a),
        dynamic(&j.b),
        dynamic(&j.c),
        dynamic(&j.d),
    )?)
}

/// The Jacobians `(A, B, C, D)` of `model` at `(t, x0, u0)` as fixed-size matrices (for a control loop or a
/// filter that works on `SMatrix` directly); every entry is checked to be finite. They are returned on the
/// stack; for a model of a few hundred states or more use [`boxed_jacobians_at`] (see the module docs).
pub fn jacobians_at<M, const NX: usize, const NU: usize, const NY: usize>(
    model: &M,
    t: f64,
    x0: &SVector<f64, NX>,
    u0: &SVector<f64, NU>,
) -> Result<FixedStateSpace<NX, NU, NY>, LinearizeError>
where
    M: ContinuousModel<NX, NU, NY>,
{
    check_point("t", std::slice::from_ref(&t))?;
    check_point("x", x0.as_slice())?;
    check_point("u", u0.as_slice())?;
    let mut a = SMatrix::<f64, NX, NX>::zeros();
    let mut b = SMatrix::<f64, NX, NU>::zeros();
    let mut c = SMatrix::<f64, NY, NX>::zeros();
    let mut d = SMatrix::<f64, NY, NU>::zeros();
    evaluate(model, t, x0, u0, (&mut a, &mut b, &mut c, &mut d))?;
    Ok((a, b, c, d))
}

/// The Jacobians `A = ∂f/∂x`, `B = ∂f/∂u`, `C = ∂h/∂x`, `D = ∂h/∂u` of a model at a point, each on the heap.
#[derive(Debug, PartialEq)]
pub struct BoxedJacobians<const NX: usize, const NU: usize, const NY: usize> {
    pub a: Box<SMatrix<f64, NX, NX>>,
    pub b: Box<SMatrix<f64, NX, NU>>,
    pub c: Box<SMatrix<f64, NY, NX>>,
    pub d: Box<SMatrix<f64, NY, NU>>,
}

/// [`jacobians_at`] for a model of any size: each matrix is allocated on the heap, zeroed, and written there by
/// the model, so nothing of size `NX²` is ever on the stack.
pub fn boxed_jacobians_at<M, const NX: usize, const NU: usize, const NY: usize>(
    model: &M,
    t: f64,
    x0: &SVector<f64, NX>,
    u0: &SVector<f64, NU>,
) -> Result<BoxedJacobians<NX, NU, NY>, LinearizeError>
where
    M: ContinuousModel<NX, NU, NY>,
{
    check_point("t", std::slice::from_ref(&t))?;
    check_point("x", x0.as_slice())?;
    check_point("u", u0.as_slice())?;
    let mut j = BoxedJacobians {
        a: bytemuck::zeroed_box(),
        b: bytemuck::zeroed_box(),
        c: bytemuck::zeroed_box(),
        d: bytemuck::zeroed_box(),
    };
    evaluate(model, t, x0, u0, (&mut j.a, &mut j.b, &mut j.c, &mut j.d))?;
    Ok(j)
}

/// The four matrices a linearisation writes.
type JacobiansMut<'a, const NX: usize, const NU: usize, const NY: usize> = (
    &'a mut SMatrix<f64, NX, NX>,
    &'a mut SMatrix<f64, NX, NU>,
    &'a mut SMatrix<f64, NY, NX>,
    &'a mut SMatrix<f64, NY, NU>,
);

/// Writes the model's Jacobians at `(t, x0, u0)` into `(a, b, c, d)` and checks that every entry is finite.
fn evaluate<M, const NX: usize, const NU: usize, const NY: usize>(
    model: &M,
    t: f64,
    x0: &SVector<f64, NX>,
    u0: &SVector<f64, NU>,
    (a, b, c, d): JacobiansMut<'_, NX, NU, NY>,
) -> Result<(), LinearizeError>
where
    M: ContinuousModel<NX, NU, NY>,
{
    model.jac_x(t, x0, u0, a);
    model.jac_u(t, x0, u0, b);
    model.output_jac_x(t, x0, u0, c);
    model.output_jac_u(t, x0, u0, d);
    check_jacobian("A", a)?;
    check_jacobian("B", b)?;
    check_jacobian("C", c)?;
    check_jacobian("D", d)
}

fn check_jacobian<const R: usize, const C: usize>(
    name: &'static str,
    m: &SMatrix<f64, R, C>,
) -> Result<(), LinearizeError> {
    for row in 0..R {
        for col in 0..C {
            let value = m[(row, col)];
            if !value.is_finite() {
                return Err(LinearizeError::NonFiniteJacobian {
                    name,
                    row,
                    col,
                    value,
                });
            }
        }
    }
    Ok(())
}

fn check_point(what: &'static str, values: &[f64]) -> Result<(), LinearizeError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(LinearizeError::NonFinitePoint {
            what,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector1, Vector2};

    /// A pendulum `θ̈ = −(g/l) sin θ − c θ̇ + u/(m l²)`, outputs `θ` and `u θ̇`, with hand-written `rhs` and
    /// `outputs` only: the Jacobians come from the trait's central differences.
    struct Pendulum;

    const G_OVER_L: f64 = 9.81;
    const DAMPING: f64 = 0.5;
    const INV_ML2: f64 = 2.0;

    impl ContinuousModel<2, 1, 2> for Pendulum {
        fn rhs(&self, _t: f64, x: &SVector<f64, 2>, u: &SVector<f64, 1>, dx: &mut SVector<f64, 2>) {
            dx[0] = x[1];
            dx[1] = -G_OVER_L * x[0].sin() - DAMPING * x[1] + INV_ML2 * u[0];
        }

        fn outputs(
            &self,
            _t: f64,
            x: &SVector<f64, 2>,
            u: &SVector<f64, 1>,
            y: &mut SVector<f64, 2>,
        ) {
            y[0] = x[0];
            y[1] = u[0] * x[1];
        }
    }

    #[test]
    fn jacobians_at_the_operating_point_match_the_hand_derivation() {
        // Hand derivation at θ = π/3, θ̇ = 0.4, u = 1.5:
        // A = [[0, 1], [−(g/l) cos θ, −c]], B = [[0], [1/(m l²)]], C = [[1, 0], [0, u]], D = [[0], [θ̇]].
        let theta = std::f64::consts::FRAC_PI_3;
        let x0 = Vector2::new(theta, 0.4);
        let u0 = Vector1::new(1.5);
        let (a, b, c, d) = jacobians_at(&Pendulum, 0.0, &x0, &u0).unwrap();
        let expected_a = [[0.0, 1.0], [-G_OVER_L * theta.cos(), -DAMPING]];
        let expected_c = [[1.0, 0.0], [0.0, 1.5]];
        for i in 0..2 {
            for j in 0..2 {
                assert!(
                    (a[(i, j)] - expected_a[i][j]).abs() < 1e-8,
                    "A[{i},{j}] = {}",
                    a[(i, j)]
                );
                assert!(
                    (c[(i, j)] - expected_c[i][j]).abs() < 1e-8,
                    "C[{i},{j}] = {}",
                    c[(i, j)]
                );
            }
        }
        assert!((b[(0, 0)]).abs() < 1e-8 && (b[(1, 0)] - INV_ML2).abs() < 1e-8);
        assert!((d[(0, 0)]).abs() < 1e-8 && (d[(1, 0)] - 0.4).abs() < 1e-8);
        let ss = linearize(&Pendulum, &x0, &u0).unwrap();
        assert_eq!((ss.n_states(), ss.n_inputs(), ss.n_outputs()), (2, 1, 2));
    }

    #[test]
    fn a_non_finite_point_is_refused_by_name() {
        let x0 = Vector2::new(0.0, f64::NAN);
        let err = linearize(&Pendulum, &x0, &Vector1::new(0.0)).unwrap_err();
        assert!(matches!(
            err,
            LinearizeError::NonFinitePoint {
                what: "x",
                index: 1,
                ..
            }
        ));
    }

    /// `ẋ = 1/x`: the Jacobian at `x = 0` is infinite.
    struct Reciprocal;

    impl ContinuousModel<1, 1, 1> for Reciprocal {
        fn rhs(&self, _t: f64, x: &SVector<f64, 1>, u: &SVector<f64, 1>, dx: &mut SVector<f64, 1>) {
            dx[0] = 1.0 / x[0] + u[0];
        }

        fn outputs(
            &self,
            _t: f64,
            x: &SVector<f64, 1>,
            _u: &SVector<f64, 1>,
            y: &mut SVector<f64, 1>,
        ) {
            y[0] = x[0];
        }

        fn jac_x(
            &self,
            _t: f64,
            x: &SVector<f64, 1>,
            _u: &SVector<f64, 1>,
            jac: &mut SMatrix<f64, 1, 1>,
        ) {
            jac[(0, 0)] = -1.0 / (x[0] * x[0]);
        }
    }

    #[test]
    fn a_non_finite_jacobian_is_an_error_not_a_model() {
        let err = linearize(&Reciprocal, &Vector1::new(0.0), &Vector1::new(0.0)).unwrap_err();
        assert!(matches!(
            err,
            LinearizeError::NonFiniteJacobian {
                name: "A",
                row: 0,
                col: 0,
                ..
            }
        ));
    }
}
