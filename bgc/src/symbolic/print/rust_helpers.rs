/// `sign(x)` with `sign(0) = 0` (unlike `f64::signum`) and `sign(NaN) = NaN`.
#[inline]
fn bgc_sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        x * 0.0
    }
}

/// The smaller of `a` and `b`, NaN if either is NaN (unlike `f64::min`).
#[inline]
fn bgc_min(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.min(b)
    }
}

/// The larger of `a` and `b`, NaN if either is NaN (unlike `f64::max`).
#[inline]
fn bgc_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// `x^n` by binary powering (`1 / x^-n` for `n < 0`): the same multiplications in the same
/// order on every platform (`f64::powi` is not in `core` and leaves their order to the
/// compiler).
#[inline]
fn bgc_powi(x: f64, n: i32) -> f64 {
    let mut base = x;
    let mut k = n.unsigned_abs();
    let mut acc = 1.0;
    loop {
        if k & 1 == 1 {
            acc *= base;
        }
        k >>= 1;
        if k == 0 {
            break;
        }
        base *= base;
    }
    if n < 0 { 1.0 / acc } else { acc }
}
