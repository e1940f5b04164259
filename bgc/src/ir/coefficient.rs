//! The one rule for the value of a linear element's coefficient, shared by BG0401 (the defaults, in `lower`) and
//! by the commands that take parameter values (`--param`), which word it each in their own way.

use crate::syntax::ast::ElementKind;

/// What makes a coefficient's value non-physical.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CoefficientFault {
    /// Infinite or NaN.
    NotFinite,
    /// An inertia or a compliance that is zero or negative: the stored energy would not be positive definite.
    NotPositive,
    /// A negative resistance: it would create energy.
    Negative,
    /// A TF or GY modulus of zero: it would cut the graph in two.
    Zero,
    /// Finite and of the right sign, but its reciprocal overflows (`1e-320`): the equations divide by it
    /// (`f = p/m`, `e = q/C`, a modulus in one causality) and would be infinite far from where the error shows.
    ReciprocalNotFinite,
}

/// The fault of the value `v` for the coefficient of an `I`, `C`, `R`, `TF` or `GY`, checked in the order of
/// [`CoefficientFault`]'s variants; `None` when it is physical or the element has no such coefficient.
pub fn coefficient_fault(kind: ElementKind, v: f64) -> Option<CoefficientFault> {
    use ElementKind as K;
    if !matches!(kind, K::I | K::C | K::R | K::TF | K::GY) {
        return None;
    }
    if !v.is_finite() {
        return Some(CoefficientFault::NotFinite);
    }
    match kind {
        K::I | K::C if v <= 0.0 => Some(CoefficientFault::NotPositive),
        K::R if v < 0.0 => Some(CoefficientFault::Negative),
        K::TF | K::GY if v == 0.0 => Some(CoefficientFault::Zero),
        K::R => None,
        _ if !(1.0 / v).is_finite() => Some(CoefficientFault::ReciprocalNotFinite),
        _ => None,
    }
}
