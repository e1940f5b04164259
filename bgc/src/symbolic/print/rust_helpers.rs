/// `sign(x)` with `sign(0) = 0` (unlike `f64::signum`) and `sign(NaN) = NaN`.
#[inline]
#[allow(dead_code)]
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
#[allow(dead_code)]
fn bgc_min(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() { f64::NAN } else { a.min(b) }
}

/// The larger of `a` and `b`, NaN if either is NaN (unlike `f64::max`).
#[inline]
#[allow(dead_code)]
fn bgc_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() { f64::NAN } else { a.max(b) }
}
