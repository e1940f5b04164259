//! A hand-written implementation of Eq. (3) of Shojaei Barjuei et al. (Designs 2020): the back-support
//! exoskeleton's linear model in the coordinates `x = [θ_m, ω_m, θ_sint, ω_sint, θ_sext, ω_sext, θ_h]` and inputs
//! `u = [τ_m, ω_h]`, written from Newton's law for each body (motor and gearbox input `J_m + J_g` merged, the gearbox
//! ratio `r_g` between motor and gearbox output):
//!
//! ```text
//! (J_m + J_g) ω̇_m = τ_m − (b_f + b_g/r_g²) ω_m − (k_g/r_g)(θ_m/r_g − θ_sint) − (d_g/r_g)(ω_m/r_g − ω_sint)
//! J_sint ω̇_sint  = k_g(θ_m/r_g − θ_sint) + d_g(ω_m/r_g − ω_sint) − k_s(θ_sint − θ_sext) − d_s(ω_sint − ω_sext)
//! J_sext ω̇_sext  = k_s(θ_sint − θ_sext) + d_s(ω_sint − ω_sext) − k_eh(θ_sext − θ_h) − d_eh(ω_sext − ω_h)
//! θ̇_m = ω_m, θ̇_sint = ω_sint, θ̇_sext = ω_sext, θ̇_h = ω_h
//! ```

use nalgebra::{SMatrix, SVector};

/// The parameters, in the order of `back_support.bg`.
#[derive(Clone, Copy, Debug)]
pub struct Eq3Params {
    pub j_m: f64,
    pub j_g: f64,
    pub b_f: f64,
    pub r_g: f64,
    pub b_g: f64,
    pub k_g: f64,
    pub d_g: f64,
    pub j_sint: f64,
    pub k_s: f64,
    pub d_s: f64,
    pub j_sext: f64,
    pub k_eh: f64,
    pub d_eh: f64,
}

impl Eq3Params {
    /// The same values as the generated model's parameters.
    pub fn of(p: &bgc_models::back_support::Params) -> Eq3Params {
        Eq3Params {
            j_m: p.J_m,
            j_g: p.J_g,
            b_f: p.b_f,
            r_g: p.r_g,
            b_g: p.b_g,
            k_g: p.k_g,
            d_g: p.d_g,
            j_sint: p.J_sint,
            k_s: p.k_s,
            d_s: p.d_s,
            j_sext: p.J_sext,
            k_eh: p.k_eh,
            d_eh: p.d_eh,
        }
    }
}

/// `ẋ = A x + B u` with `A` and `B` formed once.
pub struct Eq3 {
    pub a: SMatrix<f64, 7, 7>,
    pub b: SMatrix<f64, 7, 2>,
}

impl Eq3 {
    pub fn new(p: &Eq3Params) -> Eq3 {
        let mut a = SMatrix::<f64, 7, 7>::zeros();
        let mut b = SMatrix::<f64, 7, 2>::zeros();
        let jm = p.j_m + p.j_g;
        a[(0, 1)] = 1.0;
        a[(1, 0)] = -p.k_g / (p.r_g * p.r_g * jm);
        a[(1, 1)] = -(p.b_f + p.b_g / (p.r_g * p.r_g) + p.d_g / (p.r_g * p.r_g)) / jm;
        a[(1, 2)] = p.k_g / (p.r_g * jm);
        a[(1, 3)] = p.d_g / (p.r_g * jm);
        b[(1, 0)] = 1.0 / jm;
        a[(2, 3)] = 1.0;
        a[(3, 0)] = p.k_g / (p.r_g * p.j_sint);
        a[(3, 1)] = p.d_g / (p.r_g * p.j_sint);
        a[(3, 2)] = -(p.k_g + p.k_s) / p.j_sint;
        a[(3, 3)] = -(p.d_g + p.d_s) / p.j_sint;
        a[(3, 4)] = p.k_s / p.j_sint;
        a[(3, 5)] = p.d_s / p.j_sint;
        a[(4, 5)] = 1.0;
        a[(5, 2)] = p.k_s / p.j_sext;
        a[(5, 3)] = p.d_s / p.j_sext;
        a[(5, 4)] = -(p.k_s + p.k_eh) / p.j_sext;
        a[(5, 5)] = -(p.d_s + p.d_eh) / p.j_sext;
        a[(5, 6)] = p.k_eh / p.j_sext;
        b[(5, 1)] = p.d_eh / p.j_sext;
        b[(6, 1)] = 1.0;
        Eq3 { a, b }
    }

    #[inline]
    pub fn rhs(&self, x: &SVector<f64, 7>, u: &SVector<f64, 2>, dx: &mut SVector<f64, 7>) {
        *dx = self.a * x + self.b * u;
    }
}
