//! The continuous-time (Luenberger/Kalman–Bucy) observer `x̂' = A x̂ + B u + L (y − C x̂ − D u)`.
//!
//! The gain `L` comes from outside (e.g. `L = P Cᵀ R⁻¹` from the continuous Riccati equation, Eq. 9 of
//! paper 004, or pole placement). [`ContinuousObserver::rhs`] is the right-hand side a simulator integrates
//! together with the plant; the estimation error `e = x − x̂` obeys `e' = (A − L C) e`, whose matrix
//! [`ContinuousObserver::error_dynamics`] returns.
//!
//! The observer keeps its matrices on the heap and its right-hand side declares vectors only, so an observer
//! of any size runs on any thread (an `NX × NX` matrix exceeds a spawned thread's 2 MiB stack at 512 states);
//! [`ContinuousObserver::from_refs`] builds one from matrices held on the heap.

use super::fault::{EstimationError, check_finite};
use crate::matrix::{boxed_copy, product_sum};
use nalgebra::{SMatrix, SVector};

/// A continuous-time observer with `NX` states, `NU` inputs and `NY` measurements.
#[derive(Clone, Debug, PartialEq)]
pub struct ContinuousObserver<const NX: usize, const NU: usize, const NY: usize> {
    a: Box<SMatrix<f64, NX, NX>>,
    b: Box<SMatrix<f64, NX, NU>>,
    c: Box<SMatrix<f64, NY, NX>>,
    d: Box<SMatrix<f64, NY, NU>>,
    l: Box<SMatrix<f64, NX, NY>>,
}

impl<const NX: usize, const NU: usize, const NY: usize> ContinuousObserver<NX, NU, NY> {
    /// An observer for `ẋ = A x + B u`, `y = C x + D u` with gain `l`; all entries must be finite. The matrices
    /// are taken by value, on the caller's stack; [`Self::from_refs`] borrows them.
    pub fn new(
        a: SMatrix<f64, NX, NX>,
        b: SMatrix<f64, NX, NU>,
        c: SMatrix<f64, NY, NX>,
        d: SMatrix<f64, NY, NU>,
        l: SMatrix<f64, NX, NY>,
    ) -> Result<Self, EstimationError> {
        Self::from_refs(&a, &b, &c, &d, &l)
    }

    /// [`Self::new`] from borrowed matrices, which the observer copies to the heap (for a model whose
    /// matrices do not fit the stack).
    pub fn from_refs(
        a: &SMatrix<f64, NX, NX>,
        b: &SMatrix<f64, NX, NU>,
        c: &SMatrix<f64, NY, NX>,
        d: &SMatrix<f64, NY, NU>,
        l: &SMatrix<f64, NX, NY>,
    ) -> Result<Self, EstimationError> {
        check_finite("A", a)?;
        check_finite("B", b)?;
        check_finite("C", c)?;
        check_finite("D", d)?;
        check_finite("L", l)?;
        Ok(ContinuousObserver {
            a: boxed_copy(a),
            b: boxed_copy(b),
            c: boxed_copy(c),
            d: boxed_copy(d),
            l: boxed_copy(l),
        })
    }

    /// `x̂' = A x̂ + B u + L (y − C x̂ − D u)`. Non-finite inputs give a non-finite derivative, which the
    /// integrator reports.
    pub fn rhs(
        &self,
        x_hat: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
    ) -> SVector<f64, NX> {
        let innovation = y - self.output(x_hat, u);
        let l = &*self.l;
        product_sum(&self.a, x_hat, &self.b, u) + l * innovation
    }

    /// Writes [`Self::rhs`] into `dx` (the form of [`crate::model::ContinuousModel::rhs`]).
    pub fn rhs_into(
        &self,
        x_hat: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        y: &SVector<f64, NY>,
        dx: &mut SVector<f64, NX>,
    ) {
        *dx = self.rhs(x_hat, u, y);
    }

    /// The estimated output `C x̂ + D u`.
    pub fn output(&self, x_hat: &SVector<f64, NX>, u: &SVector<f64, NU>) -> SVector<f64, NY> {
        product_sum(&self.c, x_hat, &self.d, u)
    }

    /// `A − L C`, the matrix of the error dynamics `e' = (A − L C) e`, on the heap.
    pub fn error_dynamics(&self) -> Box<SMatrix<f64, NX, NX>> {
        let mut out = boxed_copy(&self.a);
        out.gemm(-1.0, &self.l, &self.c, 1.0);
        out
    }

    /// The gain `L`.
    pub fn gain(&self) -> &SMatrix<f64, NX, NY> {
        &self.l
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix1, Matrix1x2, Matrix2, Matrix2x1, Vector1, Vector2};

    /// Double integrator with position measured and L = [2ζω, ω²] (ω = 3, ζ = 1): A − L C has the double
    /// eigenvalue −3, so trace −6 and determinant 9; the rhs equals the hand-expanded formula.
    #[test]
    fn rhs_and_error_dynamics_match_hand_computation() {
        let a = Matrix2::new(0.0, 1.0, 0.0, 0.0);
        let b = Matrix2x1::new(0.0, 1.0);
        let c = Matrix1x2::new(1.0, 0.0);
        let l = Matrix2x1::new(6.0, 9.0);
        let obs = ContinuousObserver::new(a, b, c, Matrix1::zeros(), l).unwrap();
        let ald = obs.error_dynamics();
        assert!((ald.trace() + 6.0).abs() < 1e-15);
        assert!((ald.determinant() - 9.0).abs() < 1e-12);
        let xh = Vector2::new(0.5, -1.0);
        let dx = obs.rhs(&xh, &Vector1::new(2.0), &Vector1::new(0.7));
        // x̂1' = x̂2 + 6 (y − x̂1) = −1 + 1.2; x̂2' = u + 9 (y − x̂1) = 2 + 1.8.
        assert!((dx - Vector2::new(0.2, 3.8)).norm() < 1e-14);
        let bad = ContinuousObserver::new(a, b, c, Matrix1::zeros(), Matrix2x1::new(f64::NAN, 0.0));
        assert!(matches!(
            bad,
            Err(EstimationError::NonFiniteMatrix { name: "L", .. })
        ));
    }
}
