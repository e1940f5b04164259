//! Conversions between the fixed-size matrices of generated models, filters and controllers (`SMatrix`) and the
//! dynamically sized ones of design ([`crate::design`], [`crate::linalg`]: `DMatrix`).
//!
//! A generated model's `state_space(&params)` gives `SMatrix` values; [`state_space`] turns them into the
//! [`StateSpace`] that `lqr`, `lqi`, `lqe` and `c2d_zoh` take. Gains and covariances come back as `DMatrix`;
//! [`fixed`] copies one into the `SMatrix` a `KalmanFilter` or a control loop needs, checking its shape, and
//! [`dynamic`] goes the other way (weights written as fixed-size literals, for instance).

use crate::linalg::MatrixError;
use crate::statespace::{StateSpace, StateSpaceError};
use nalgebra::{DMatrix, SMatrix};

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
    if m.nrows() != R || m.ncols() != C {
        return Err(MatrixError::Shape {
            name,
            rows: m.nrows(),
            cols: m.ncols(),
            expected_rows: R,
            expected_cols: C,
        });
    }
    Ok(SMatrix::from_fn(|i, j| m[(i, j)]))
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
