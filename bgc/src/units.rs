//! Physical units and dimension checking.

use serde::Serialize;

/// Exponents of the SI base dimensions, in the order m, kg, s, A, K, mol, cd.
/// The radian and steradian are dimensionless, as in SI.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct Dim(pub [i8; 7]);

/// A unit: a dimension and the factor that converts a value in this unit to SI base units
/// (`mm` is `Dim(m)` with scale 1e-3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Unit {
    pub dim: Dim,
    pub scale: f64,
}
