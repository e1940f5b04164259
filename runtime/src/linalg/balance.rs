//! Diagonal balancing by powers of two (Osborne's iteration, as in LAPACK `gebal` without permutation).
//!
//! A similarity `D⁻¹ A D` with `D` diagonal changes no eigenvalue but equalises row and column norms, which makes
//! eigenvalues and rank decisions far less sensitive to the choice of units (radians against newton metres,
//! stiffnesses of 10⁴ against inertias of 10⁻⁴). Powers of two make the scaling exact in floating point.

use nalgebra::{DMatrix, DVector};

/// The diagonal of `D` such that `D⁻¹ A D` has comparable off-diagonal row and column 1-norms: powers of two whose
/// reciprocals are finite, for any `a` (a row or column with a non-finite entry is left unscaled).
pub fn balancing_scales(a: &DMatrix<f64>) -> DVector<f64> {
    balance(a).0
}

/// The scales of [`balancing_scales`] and the balanced `D⁻¹ A D`, as the iteration formed it (no product of an entry
/// with a ratio of scales that could overflow on the way).
fn balance(a: &DMatrix<f64>) -> (DVector<f64>, DMatrix<f64>) {
    let n = a.nrows();
    let mut m = a.clone();
    let mut d = DVector::from_element(n, 1.0);
    for _sweep in 0..100 {
        let mut changed = false;
        for i in 0..n {
            let mut c = 0.0;
            let mut r = 0.0;
            for j in 0..n {
                if j != i {
                    c += m[(j, i)].abs();
                    r += m[(i, j)].abs();
                }
            }
            if c == 0.0 || r == 0.0 || !(c.is_finite() && r.is_finite()) {
                continue;
            }
            let Some(f) = osborne_factor(r, c, d[i]) else {
                continue;
            };
            // Only rescale when it reduces the combined norm noticeably (LAPACK's 0.95 criterion).
            if (c * f + r / f) < 0.95 * (c + r) {
                changed = true;
                d[i] *= f;
                // The diagonal is unchanged: multiplying it by `f` first could overflow before the division.
                for j in (0..n).filter(|&j| j != i) {
                    m[(j, i)] *= f;
                    m[(i, j)] /= f;
                }
            }
        }
        if !changed {
            break;
        }
    }
    (d, m)
}

/// The factor of one step of Osborne's iteration for a state whose scale is `scale`, with off-diagonal row and
/// column norms `r` and `c` (positive and finite): `√(r/c)` to the nearest power of two, taken from the logarithms
/// (`r / c` overflows for r = 1e300, c = 1e-300). `None` when the new scale or its reciprocal would not be a normal
/// number, however many sweeps have multiplied it.
pub fn osborne_factor(r: f64, c: f64, scale: f64) -> Option<f64> {
    let f = 2f64.powi((0.5 * (r.log2() - c.log2())).round().clamp(-1000.0, 1000.0) as i32);
    let scaled = scale * f;
    (scaled.is_normal() && scaled.recip().is_normal()).then_some(f)
}

/// The power of two nearest to `x` (in the logarithmic sense); `x` must be positive and finite.
pub fn power_of_two(x: f64) -> f64 {
    let e = x.log2().round().clamp(-1000.0, 1000.0);
    2f64.powi(e as i32)
}

/// A power of two that brings magnitudes up to `largest` near one: dividing and multiplying by it rounds nothing,
/// so a computation can run on `m / s` and scale its results back by `s`, away from overflow and underflow. 1 for a
/// zero or non-finite `largest`. The scale stays between 2⁻¹⁰²² and 2¹⁰²³, so that its reciprocal is finite too
/// (nalgebra divides a matrix by multiplying with the reciprocal): a subnormal `largest` is brought up as far as
/// that allows, and 1.8e308 gives 2¹⁰²³, not infinity.
pub fn unit_scale(largest: f64) -> f64 {
    if largest > 0.0 && largest.is_finite() {
        2f64.powi(largest.log2().round().clamp(-1022.0, 1023.0) as i32)
    } else {
        1.0
    }
}

/// The Frobenius norm of the balanced `D⁻¹ A D`: the magnitude that eigenvalue errors scale with, free of the
/// units chosen for the states.
pub fn balanced_norm(a: &DMatrix<f64>) -> f64 {
    frobenius(&balance(a).1)
}

/// The Frobenius norm of `m` without overflow or underflow of the squares: entries beyond about 1e154 (or below
/// 1e-154) are squared after scaling by the largest one, so the norm is finite whenever it is representable.
pub fn frobenius<C: nalgebra::ComplexField<RealField = f64>>(m: &DMatrix<C>) -> f64 {
    let largest = m.iter().map(|v| v.clone().abs()).fold(0.0, f64::max);
    if largest == 0.0 || !largest.is_finite() {
        return m.norm();
    }
    let scale = unit_scale(largest);
    let sum: f64 = m.iter().map(|v| (v.clone().abs() / scale).powi(2)).sum();
    scale * sum.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A two-state model in mismatched units (10⁸ against 10⁻⁴ couplings): balancing makes the off-diagonal
    /// entries comparable, uses only powers of two and keeps the eigenvalues (trace and determinant).
    #[test]
    fn balancing_equalises_couplings_exactly() {
        let a = DMatrix::from_row_slice(2, 2, &[-1.0, 1e8, -1e-4, -2.0]);
        let d = balancing_scales(&a);
        for s in d.iter() {
            assert_eq!(s.log2().fract(), 0.0, "scale {s} is not a power of two");
        }
        let b = DMatrix::from_fn(2, 2, |i, j| a[(i, j)] * d[j] / d[i]);
        let ratio = (b[(0, 1)] / b[(1, 0)]).abs();
        assert!((0.25..=4.0).contains(&ratio), "off-diagonal ratio {ratio}");
        assert_eq!(b.trace(), a.trace());
        assert!((b.determinant() - a.determinant()).abs() < 1e-12 * a.determinant().abs());
        assert!(balanced_norm(&a) < 1e3);
    }

    /// Couplings at the ends of the f64 range (1e300 against 5e-324, found by a fuzzer): every scale and its
    /// reciprocal stay finite (the ratio of the row and column norms overflowed, and a scale became infinite).
    #[test]
    fn balancing_extreme_couplings_keeps_scales_finite() {
        let a = DMatrix::from_column_slice(
            3,
            3,
            &[
                5e-324, 1e-300, 1e300, 0.0, 1e-300, 5e-324, 0.0, 1e160, 5e-324,
            ],
        );
        let d = balancing_scales(&a);
        assert!(
            d.iter().all(|s| s.is_normal() && s.recip().is_normal()),
            "{d:?}"
        );
        assert!(balanced_norm(&a).is_finite());
        // A diagonal near the largest f64 in a row that is scaled up: it was multiplied before the division and
        // overflowed, so the balanced norm of a finite matrix was infinite.
        let a = DMatrix::from_row_slice(2, 2, &[1e300, 1e10, 1e-10, 0.0]);
        let norm = balanced_norm(&a);
        assert!((norm - 1e300).abs() <= 1e-12 * 1e300, "{norm}");
    }

    /// The scale and its reciprocal are finite powers of two for every positive finite magnitude.
    #[test]
    fn unit_scale_stays_where_its_reciprocal_is_finite() {
        assert_eq!(unit_scale(3.0), 4.0);
        assert_eq!(unit_scale(0.3), 0.25);
        assert_eq!(unit_scale(f64::MAX), 2f64.powi(1023));
        assert_eq!(unit_scale(1e-310), 2f64.powi(-1022));
        for bad in [0.0, f64::NAN, f64::INFINITY] {
            assert_eq!(unit_scale(bad), 1.0);
        }
        for x in [f64::MAX, 1e-310, 5e-324] {
            assert!((1.0 / unit_scale(x)).is_finite(), "{x:e}");
        }
    }

    #[test]
    fn power_of_two_rounds_in_log_scale() {
        assert_eq!(power_of_two(1.0), 1.0);
        assert_eq!(power_of_two(3.0), 4.0);
        assert_eq!(power_of_two(0.3), 0.25);
    }
}
