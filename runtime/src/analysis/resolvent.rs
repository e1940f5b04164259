//! `C (pI − A)⁻¹ B + D` at many points `p` of one model.
//!
//! `A` is reduced once to upper Hessenberg form `H = Qᵀ A Q` by an orthogonal similarity, which leaves the
//! transfer function unchanged: `C (pI − A)⁻¹ B = (CQ) (pI − H)⁻¹ (QᵀB)`. A Hessenberg system is solved by
//! Gaussian elimination with partial pivoting in `O(n²)` per input instead of the `O(n³)` of a dense
//! factorisation (the reduction SLICOT's TB05AD makes for python-control's frequency responses). A margin or
//! bandwidth search evaluates a loop at thousands of frequencies, so this is what its cost is made of.
//!
//! The residual of every solve is checked, as for a dense solve: orthogonal transformations keep the norms
//! of the residual, the matrix and the solution, so a point on (or numerically on) a pole is refused by the
//! same test.

use nalgebra::DMatrix;
use nalgebra::linalg::Hessenberg;

use super::error::AnalysisError;
use super::freqresp::{C64, RESIDUAL_LIMIT, check_siso_shape, point_of};
use crate::statespace::StateSpace;

/// A model prepared for evaluating its transfer matrix at many points.
#[derive(Clone, Debug)]
pub struct Resolvent {
    /// `QᵀAQ`, zero below its first subdiagonal.
    h: DMatrix<f64>,
    /// `QᵀB`.
    b: DMatrix<f64>,
    /// `CQ`.
    c: DMatrix<f64>,
    d: DMatrix<f64>,
    dt: Option<f64>,
    /// The reduction overflowed (entries near `f64::MAX` whose squares are not finite): no point can be trusted.
    overflowed: bool,
    /// `‖H‖` (Frobenius), the scale of the rounding in forming `pI − H`.
    h_norm: f64,
}

impl Resolvent {
    /// Reduces the state matrix of `sys` to Hessenberg form.
    pub fn new(sys: &StateSpace) -> Self {
        let (h, b, c) = if sys.n_states() == 0 {
            (sys.a().clone(), sys.b().clone(), sys.c().clone())
        } else {
            let (q, h) = Hessenberg::new(sys.a().clone()).unpack();
            (h, q.tr_mul(sys.b()), sys.c() * q)
        };
        let overflowed = [&h, &b, &c]
            .iter()
            .any(|m| m.iter().any(|v| !v.is_finite()));
        let h_norm = h.norm();
        Self {
            h,
            b,
            c,
            d: sys.d().clone(),
            dt: sys.dt(),
            overflowed,
            h_norm,
        }
    }

    /// The response matrix (outputs × inputs) at frequency `omega` (rad/s): at `jω`, or at `e^{jωT}`.
    pub fn response(&self, omega: f64) -> Result<DMatrix<C64>, AnalysisError> {
        self.transfer_at(point_of(self.dt, omega)?, omega)
    }

    /// The response of a SISO model at frequency `omega` (rad/s).
    pub fn siso(&self, omega: f64) -> Result<C64, AnalysisError> {
        let (outputs, inputs) = self.d.shape();
        check_siso_shape("Resolvent::siso", outputs, inputs)?;
        Ok(self.response(omega)?[(0, 0)])
    }

    /// `C (pI − A)⁻¹ B + D` at a point `p` of the complex plane; `omega` only names the point in errors.
    pub fn transfer_at(&self, p: C64, omega: f64) -> Result<DMatrix<C64>, AnalysisError> {
        let (outputs, inputs) = self.d.shape();
        let n = self.h.nrows();
        let x = self.solve(p, omega)?;
        let g = DMatrix::from_fn(outputs, inputs, |r, k| {
            let column = &x[k * n..(k + 1) * n];
            let mut sum = real(self.d[(r, k)]);
            for (j, &xj) in column.iter().enumerate() {
                sum = add(sum, times(self.c[(r, j)], xj));
            }
            sum
        });
        if g.iter().any(|v| !is_finite(*v)) {
            return Err(AnalysisError::Overflow { omega });
        }
        Ok(g)
    }

    /// `(pI − H)⁻¹ QᵀB` (column-major), refused when its relative residual, or the size of the solution against
    /// the rounding of `pI − H`, shows that `p` is (numerically) a pole.
    fn solve(&self, p: C64, omega: f64) -> Result<Vec<C64>, AnalysisError> {
        let n = self.h.nrows();
        if n == 0 {
            return Ok(Vec::new());
        }
        if self.overflowed {
            return Err(AnalysisError::Overflow { omega });
        }
        let b: Vec<C64> = self.b.iter().map(|&v| real(v)).collect();
        let shifted = self.shifted(p);
        let mut u = shifted.clone();
        let mut x = b.clone();
        eliminate_subdiagonal(n, &mut u, &mut x);
        back_substitute(n, &u, &mut x).ok_or(AnalysisError::PoleOnContour { omega })?;
        if x.iter().any(|v| !is_finite(*v)) {
            return Err(AnalysisError::PoleOnContour { omega });
        }
        let residual = residual_norm(n, &shifted, &x, &b);
        let scale = frobenius(&shifted) * frobenius(&x) + frobenius(&b);
        if !(residual.is_finite() && scale.is_finite()) {
            // The entries are finite but their products are not: no residual, and no response, can be trusted.
            return Err(AnalysisError::Overflow { omega });
        }
        let relative = if scale > 0.0 { residual / scale } else { 0.0 };
        if relative > RESIDUAL_LIMIT {
            return Err(AnalysisError::IllConditioned {
                omega,
                residual: relative,
            });
        }
        if self.within_rounding_of_a_pole(p, &x, &b) {
            return Err(AnalysisError::PoleOnContour { omega });
        }
        Ok(x)
    }

    /// Whether `pI − H` is singular to within the rounding of its own entries. A backward-stable solve keeps the
    /// residual small even there, so the residual cannot tell; but `‖b‖ / ‖x‖` bounds the smallest singular value
    /// of `pI − H` from above, and when that is below the error of forming `pI − H` (`n ε (|p| + ‖H‖)`, with a
    /// factor 16 of margin) some matrix within rounding of it is singular: `p` is a pole as far as `f64` can tell
    /// (`z = e^{jπ}` of a discrete pole at −1 is `−1 + 1.2e−16 j`, and its "response" was `4e15`).
    fn within_rounding_of_a_pole(&self, p: C64, x: &[C64], b: &[C64]) -> bool {
        let n = self.h.nrows();
        let size = p.norm() + self.h_norm;
        let floor = 16.0 * n as f64 * f64::EPSILON * size;
        x.chunks(n).zip(b.chunks(n)).any(|(xj, bj)| {
            let (x_norm, b_norm) = (frobenius(xj), frobenius(bj));
            b_norm > 0.0 && b_norm < floor * x_norm
        })
    }

    /// `pI − H`, column-major.
    fn shifted(&self, p: C64) -> Vec<C64> {
        let n = self.h.nrows();
        let mut m: Vec<C64> = self.h.iter().map(|&v| real(-v)).collect();
        for i in 0..n {
            m[i * n + i] = add(m[i * n + i], p);
        }
        m
    }
}

// Complex arithmetic written out on `f64`. In lightly optimised builds (the test profile) the generic
// operators of `Complex` stay function calls, and these loops are the whole cost of a margin search.

const ZERO: C64 = C64 { re: 0.0, im: 0.0 };

#[inline(always)]
fn real(v: f64) -> C64 {
    C64 { re: v, im: 0.0 }
}

#[inline(always)]
fn add(a: C64, b: C64) -> C64 {
    C64 {
        re: a.re + b.re,
        im: a.im + b.im,
    }
}

#[inline(always)]
fn sub(a: C64, b: C64) -> C64 {
    C64 {
        re: a.re - b.re,
        im: a.im - b.im,
    }
}

#[inline(always)]
fn mul(a: C64, b: C64) -> C64 {
    C64 {
        re: a.re * b.re - a.im * b.im,
        im: a.re * b.im + a.im * b.re,
    }
}

#[inline(always)]
fn times(s: f64, a: C64) -> C64 {
    C64 {
        re: s * a.re,
        im: s * a.im,
    }
}

#[inline(always)]
fn abs2(a: C64) -> f64 {
    a.re * a.re + a.im * a.im
}

#[inline(always)]
fn div(a: C64, b: C64) -> C64 {
    let d = abs2(b);
    C64 {
        re: (a.re * b.re + a.im * b.im) / d,
        im: (a.im * b.re - a.re * b.im) / d,
    }
}

fn is_finite(v: C64) -> bool {
    v.re.is_finite() && v.im.is_finite()
}

fn frobenius(m: &[C64]) -> f64 {
    m.iter().map(|&v| abs2(v)).sum::<f64>().sqrt()
}

/// Reduces the `n × n` upper Hessenberg `u` (column-major) to upper triangular form, applying the same row
/// operations to the columns of `x`. Only rows `k` and `k + 1` meet at step `k`, so the partial pivoting
/// chooses between those two.
fn eliminate_subdiagonal(n: usize, u: &mut [C64], x: &mut [C64]) {
    for k in 0..n.saturating_sub(1) {
        let (diag, below) = (k * n + k, k * n + k + 1);
        if abs2(u[below]) > abs2(u[diag]) {
            // Columns before k are zero in both rows.
            for j in k..n {
                u.swap(j * n + k, j * n + k + 1);
            }
            for column in x.chunks_mut(n) {
                column.swap(k, k + 1);
            }
        }
        if u[below] == ZERO || u[diag] == ZERO {
            // Nothing to eliminate; a zero pivot with a zero below it is caught by the back substitution.
            continue;
        }
        let f = div(u[below], u[diag]);
        u[below] = ZERO;
        for j in k + 1..n {
            u[j * n + k + 1] = sub(u[j * n + k + 1], mul(f, u[j * n + k]));
        }
        for column in x.chunks_mut(n) {
            column[k + 1] = sub(column[k + 1], mul(f, column[k]));
        }
    }
}

/// Solves the `n × n` upper triangular `u` (column-major) in place of the columns of `x`; `None` on a zero
/// pivot (a singular matrix).
fn back_substitute(n: usize, u: &[C64], x: &mut [C64]) -> Option<()> {
    for column in x.chunks_mut(n) {
        for i in (0..n).rev() {
            let pivot = u[i * n + i];
            if pivot == ZERO {
                return None;
            }
            column[i] = div(column[i], pivot);
            let xi = column[i];
            // Column-oriented: subtract x_i times column i of u from the rows above.
            for (r, &uri) in u[i * n..i * n + i].iter().enumerate() {
                column[r] = sub(column[r], mul(uri, xi));
            }
        }
    }
    Some(())
}

/// `‖m x − b‖` (Frobenius) for the `n × n` upper Hessenberg `m`, skipping its zeros below the subdiagonal.
fn residual_norm(n: usize, m: &[C64], x: &[C64], b: &[C64]) -> f64 {
    let mut sum = 0.0;
    for (xc, bc) in x.chunks(n).zip(b.chunks(n)) {
        let mut r: Vec<C64> = bc.iter().map(|&v| times(-1.0, v)).collect();
        for (j, &xj) in xc.iter().enumerate() {
            let rows = (j + 2).min(n);
            for (ri, &mij) in r[..rows].iter_mut().zip(&m[j * n..j * n + rows]) {
                *ri = add(*ri, mul(mij, xj));
            }
        }
        sum += r.iter().map(|&v| abs2(v)).sum::<f64>();
    }
    sum.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense reference: `C (pI − A)⁻¹ B + D` by a complex LU of the full resolvent.
    fn dense(sys: &StateSpace, p: C64) -> DMatrix<C64> {
        let n = sys.n_states();
        let mut m = sys.a().map(|v| C64::new(-v, 0.0));
        for i in 0..n {
            m[(i, i)] += p;
        }
        let x = m
            .lu()
            .solve(&sys.b().map(|v| C64::new(v, 0.0)))
            .expect("not a pole");
        sys.c().map(|v| C64::new(v, 0.0)) * x + sys.d().map(|v| C64::new(v, 0.0))
    }

    fn model() -> StateSpace {
        // A dense 5-state, 2-input, 3-output model with poles spread over two decades.
        let a = DMatrix::from_fn(5, 5, |i, j| {
            let v = ((3 * i + 7 * j) % 11) as f64 - 5.0;
            if i == j { v - 12.0 * (i + 1) as f64 } else { v }
        });
        let b = DMatrix::from_fn(5, 2, |i, j| ((i + 2 * j) % 3) as f64 - 1.0);
        let c = DMatrix::from_fn(3, 5, |i, j| ((2 * i + j) % 4) as f64 * 0.5);
        let d = DMatrix::from_fn(3, 2, |i, j| (i as f64) - (j as f64));
        StateSpace::new(a, b, c, d).expect("a valid model")
    }

    #[test]
    fn the_hessenberg_response_equals_the_dense_solve() {
        let sys = model();
        let r = Resolvent::new(&sys);
        for p in [
            C64::new(0.0, 0.1),
            C64::new(0.0, 7.0),
            C64::new(0.0, 300.0),
            C64::new(-3.0, 2.0),
        ] {
            let got = r.transfer_at(p, p.im).expect("evaluates");
            let want = dense(&sys, p);
            assert!(
                (&got - &want).norm() <= 1e-12 * want.norm(),
                "at {p}: {got} against {want}"
            );
        }
    }

    #[test]
    fn an_eigenvalue_of_a_is_refused() {
        // Poles at 0 and ±2j: a point on each is a pole on the contour, not a number.
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, -2.0, 0.0]);
        let sys = StateSpace::new(
            a,
            DMatrix::from_element(3, 1, 1.0),
            DMatrix::from_element(1, 3, 1.0),
            DMatrix::zeros(1, 1),
        )
        .expect("a valid model");
        let r = Resolvent::new(&sys);
        for omega in [0.0, 2.0] {
            let e = r.response(omega).expect_err("a pole");
            assert!(
                matches!(
                    e,
                    AnalysisError::PoleOnContour { .. } | AnalysisError::IllConditioned { .. }
                ),
                "{e:?}"
            );
        }
        assert!(r.response(1.0).is_ok());
    }

    #[test]
    fn a_point_within_rounding_of_a_pole_is_refused() {
        // A discrete pole at −1 (T = 0.1 s): at ω = π/T the point e^{jπ} is −1 + 1.2e−16 j, a non-zero pivot with
        // a tiny residual, and the "response" was −4e15 j.
        let sys = StateSpace::new_discrete(
            DMatrix::from_element(1, 1, -1.0),
            DMatrix::from_element(1, 1, 1.0),
            DMatrix::from_element(1, 1, 0.5),
            DMatrix::zeros(1, 1),
            0.1,
        )
        .expect("a valid model");
        let r = Resolvent::new(&sys);
        let nyquist = std::f64::consts::PI / 0.1;
        assert!(
            matches!(
                r.response(nyquist),
                Err(AnalysisError::PoleOnContour { .. })
            ),
            "{:?}",
            r.response(nyquist)
        );
        // Near it, where the pole is 1e-6 away, the response is a number: 0.5 / |e^{jωT} + 1|.
        let near = nyquist * (1.0 - 1e-6 / std::f64::consts::PI);
        let g = r.response(near).expect("not a pole")[(0, 0)];
        assert!((g.norm() / (0.5 / 1e-6) - 1.0).abs() < 1e-6, "{g}");
        // A continuous lightly damped pair (ζ = 1e−9 at 1 rad/s) is not mistaken for a pole at its peak.
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -1.0, -2e-9]);
        let lightly = StateSpace::new(
            a,
            DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
            DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
            DMatrix::zeros(1, 1),
        )
        .expect("a valid model");
        let peak = Resolvent::new(&lightly).response(1.0).expect("a number")[(0, 0)];
        assert!((peak.norm() / 5e8 - 1.0).abs() < 1e-6, "{peak}");
    }

    #[test]
    fn a_static_gain_is_its_d() {
        let d = DMatrix::from_row_slice(2, 1, &[3.0, -0.5]);
        let sys = StateSpace::new(
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, 1),
            DMatrix::zeros(2, 0),
            d,
        )
        .expect("a valid model");
        let g = Resolvent::new(&sys).response(10.0).expect("evaluates");
        assert_eq!(
            g,
            DMatrix::from_row_slice(2, 1, &[C64::new(3.0, 0.0), C64::new(-0.5, 0.0)])
        );
    }

    #[test]
    fn entries_whose_squares_overflow_are_an_overflow_not_a_number() {
        let a = DMatrix::from_fn(4, 4, |i, j| if i == j { -1e300 } else { 1e300 });
        let sys = StateSpace::new(
            a,
            DMatrix::from_element(4, 1, 1.0),
            DMatrix::from_element(1, 4, 1.0),
            DMatrix::zeros(1, 1),
        )
        .expect("a valid model");
        let e = Resolvent::new(&sys).response(1.0).expect_err("overflows");
        assert!(matches!(e, AnalysisError::Overflow { .. }), "{e:?}");
    }
}
