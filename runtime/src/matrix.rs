//! Conversions between the fixed-size matrices of generated models, filters and controllers (`SMatrix`) and the
//! dynamically sized ones of design ([`crate::design`], [`crate::linalg`]: `DMatrix`).
//!
//! A generated model's `state_space(&params)` gives `SMatrix` values; [`state_space`] turns them into the
//! [`StateSpace`] that `lqr`, `lqi`, `lqe` and `c2d_zoh` take. Gains and covariances come back as `DMatrix`;
//! [`fixed`] copies one into the `SMatrix` a `KalmanFilter` or a control loop needs, checking its shape, and
//! [`dynamic`] goes the other way (weights written as fixed-size literals, for instance).
//!
//! # Large models
//!
//! An `R × C` `SMatrix` takes `8 R C` bytes wherever it is declared: an `NX × NX` one exceeds a spawned thread's
//! 2 MiB stack at 512 states. [`zeroed_box`], [`boxed_copy`], [`boxed_fixed`] and [`boxed_identity`] build one
//! on the heap without building it on the stack first (`Box::new(SMatrix::zeros())` does), for the
//! constructors of filters, observers and plants that take their matrices by reference.

use crate::linalg::MatrixError;
use crate::statespace::{StateSpace, StateSpaceError};
use nalgebra::{DMatrix, SMatrix, SVector};

/// `(A, B, C, D)` of `ẋ = A x + B u`, `y = C x + D u` in fixed sizes, as generated models' `state_space` and
/// [`crate::linearize::jacobians_at`] give them.
pub type FixedStateSpace<const NX: usize, const NU: usize, const NY: usize> = (
    SMatrix<f64, NX, NX>,
    SMatrix<f64, NX, NU>,
    SMatrix<f64, NY, NX>,
    SMatrix<f64, NY, NU>,
);

/// The `DMatrix` with the entries of `m`.
pub fn dynamic<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_fn(R, C, |i, j| m[(i, j)])
}

/// The `R × C` matrix with the entries of `m`; an error naming `name` when `m` has another shape.
pub fn fixed<const R: usize, const C: usize>(
    name: &'static str,
    m: &DMatrix<f64>,
) -> Result<SMatrix<f64, R, C>, MatrixError> {
    check_shape::<R, C>(name, m)?;
    Ok(SMatrix::from_fn(|i, j| m[(i, j)]))
}

/// An error naming `name` unless `m` is `R × C`.
fn check_shape<const R: usize, const C: usize>(
    name: &'static str,
    m: &DMatrix<f64>,
) -> Result<(), MatrixError> {
    if m.nrows() != R || m.ncols() != C {
        return Err(MatrixError::Shape {
            name,
            rows: m.nrows(),
            cols: m.ncols(),
            expected_rows: R,
            expected_cols: C,
        });
    }
    Ok(())
}

/// An `R × C` matrix of zeros on the heap, never on the stack (`bytemuck::zeroed_box`).
pub fn zeroed_box<const R: usize, const C: usize>() -> Box<SMatrix<f64, R, C>> {
    bytemuck::zeroed_box()
}

/// A copy of `m` on the heap, written there entry by entry.
pub fn boxed_copy<const R: usize, const C: usize>(
    m: &SMatrix<f64, R, C>,
) -> Box<SMatrix<f64, R, C>> {
    let mut out = zeroed_box::<R, C>();
    out.copy_from(m);
    out
}

/// `s I` on the heap.
pub fn boxed_identity<const N: usize>(s: f64) -> Box<SMatrix<f64, N, N>> {
    let mut out = zeroed_box::<N, N>();
    out.fill_diagonal(s);
    out
}

/// [`fixed`] on the heap: the `R × C` matrix with the entries of `m`, for a size that does not fit the stack.
pub fn boxed_fixed<const R: usize, const C: usize>(
    name: &'static str,
    m: &DMatrix<f64>,
) -> Result<Box<SMatrix<f64, R, C>>, MatrixError> {
    check_shape::<R, C>(name, m)?;
    let mut out = zeroed_box::<R, C>();
    out.copy_from(m);
    Ok(out)
}

/// `M₁ v₁ + M₂ v₂` with the matrices read where they are: `model.a * x`, a matrix value, may copy the matrix
/// to the stack first (an unoptimised build does), where a reference times a vector does not.
pub(crate) fn product_sum<const R: usize, const C1: usize, const C2: usize>(
    m1: &SMatrix<f64, R, C1>,
    v1: &SVector<f64, C1>,
    m2: &SMatrix<f64, R, C2>,
    v2: &SVector<f64, C2>,
) -> SVector<f64, R> {
    m1 * v1 + m2 * v2
}

/// The continuous-time [`StateSpace`] `ẋ = A x + B u`, `y = C x + D u` of fixed-size matrices, as a generated
/// model's `state_space(&params)` returns them (`let ss = state_space(&drive::state_space(&p))?;`). Refused when
/// an entry is not finite.
pub fn state_space<const NX: usize, const NU: usize, const NY: usize>(
    (a, b, c, d): &FixedStateSpace<NX, NU, NY>,
) -> Result<StateSpace, StateSpaceError> {
    StateSpace::new(dynamic(a), dynamic(b), dynamic(c), dynamic(d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2x3, Vector2};

    #[test]
    fn round_trip_keeps_every_entry_in_place() {
        let m = Matrix2x3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0);
        let d = dynamic(&m);
        assert_eq!((d.nrows(), d.ncols()), (2, 3));
        assert_eq!(d[(0, 2)], 3.0);
        assert_eq!(d[(1, 0)], 4.0);
        let back: Matrix2x3<f64> = fixed("M", &d).unwrap();
        assert_eq!(back, m);
    }

    #[test]
    fn a_wrong_shape_is_named() {
        let d = DMatrix::<f64>::zeros(3, 2);
        let err = fixed::<2, 3>("K", &d).unwrap_err();
        assert_eq!(
            err,
            MatrixError::Shape {
                name: "K",
                rows: 3,
                cols: 2,
                expected_rows: 2,
                expected_cols: 3
            }
        );
    }

    #[test]
    fn state_space_of_fixed_matrices() {
        // A double integrator with position output.
        let a = SMatrix::<f64, 2, 2>::new(0.0, 1.0, 0.0, 0.0);
        let b = Vector2::new(0.0, 1.0);
        let c = SMatrix::<f64, 1, 2>::new(1.0, 0.0);
        let d = SMatrix::<f64, 1, 1>::zeros();
        let ss = state_space(&(a, b, c, d)).unwrap();
        assert_eq!((ss.n_states(), ss.n_inputs(), ss.n_outputs()), (2, 1, 1));
        let bad = SMatrix::<f64, 1, 2>::new(f64::NAN, 0.0);
        assert!(matches!(
            state_space(&(a, b, bad, d)),
            Err(StateSpaceError::NonFinite {
                name: "C",
                row: 0,
                col: 0
            })
        ));
    }
}
