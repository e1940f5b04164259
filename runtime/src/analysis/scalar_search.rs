//! Scalar root bracketing (Brent's method) and minimisation (golden section) used to refine crossings found
//! on a frequency grid.
//!
//! Both work on a fallible function: an evaluation error aborts the search and is passed up.

/// Finds `x` in `[a, b]` with `f(x) = 0`, given that `f(a)` and `f(b)` have opposite signs (or one is zero).
///
/// Brent's method (Brent 1973, `zeroin`): inverse quadratic interpolation or secant steps, falling back to
/// bisection, so that it converges superlinearly on smooth functions and never slower than bisection. Stops
/// when the bracket is narrower than a few ulps of `x`.
pub(crate) fn brent_root<E>(
    mut f: impl FnMut(f64) -> Result<f64, E>,
    a0: f64,
    b0: f64,
    fa0: f64,
    fb0: f64,
) -> Result<f64, E> {
    let (mut a, mut b, mut fa, mut fb) = (a0, b0, fa0, fb0);
    if fa == 0.0 {
        return Ok(a);
    }
    if fb == 0.0 {
        return Ok(b);
    }
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..200 {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs() + 1e-300;
        let m = 0.5 * (c - b);
        if m.abs() <= tol || fb == 0.0 {
            return Ok(b);
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * m * s;
                q = 1.0 - s;
            } else {
                let qa = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * m * qa * (qa - r) - (b - a) * (r - 1.0));
                q = (qa - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * m * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = m;
                e = m;
            }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(m) };
        fb = f(b)?;
    }
    Ok(b)
}

/// Minimises a unimodal `f` on `[a, b]` by golden-section search; returns `(x, f(x))`.
pub(crate) fn golden_min<E>(
    mut f: impl FnMut(f64) -> Result<f64, E>,
    a0: f64,
    b0: f64,
) -> Result<(f64, f64), E> {
    let inv_phi = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (a0, b0);
    let mut x1 = b - inv_phi * (b - a);
    let mut x2 = a + inv_phi * (b - a);
    let mut f1 = f(x1)?;
    let mut f2 = f(x2)?;
    for _ in 0..200 {
        if (b - a).abs() <= 1e-12 * (a.abs() + b.abs()) {
            break;
        }
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - inv_phi * (b - a);
            f1 = f(x1)?;
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + inv_phi * (b - a);
            f2 = f(x2)?;
        }
    }
    Ok(if f1 < f2 { (x1, f1) } else { (x2, f2) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_cube_root_of_two() {
        let f = |x: f64| -> Result<f64, ()> { Ok(x * x * x - 2.0) };
        let r = brent_root(f, 0.0, 2.0, -2.0, 6.0).unwrap_or(f64::NAN);
        assert!((r - 2f64.cbrt()).abs() < 1e-15, "{r}");
    }

    #[test]
    fn golden_finds_parabola_minimum() {
        let f = |x: f64| -> Result<f64, ()> { Ok((x - 0.3).powi(2) + 1.0) };
        let (x, fx) = golden_min(f, -1.0, 2.0).unwrap_or((f64::NAN, f64::NAN));
        assert!((x - 0.3).abs() < 1e-7, "{x}");
        assert!((fx - 1.0).abs() < 1e-14);
    }
}
