//! The generated model (`crate::model`) seen through slices, in the value-reference layout of
//! `modelDescription.xml`: 0 is the time, then the parameters, the inputs, the outputs, the states and the
//! state derivatives, each in the generated module's order.

use crate::model as m;
use nalgebra::SMatrix;

pub const NX: usize = m::N_STATES;
pub const NU: usize = m::N_INPUTS;
pub const NY: usize = m::N_OUTPUTS;
pub const NP: usize = m::N_PARAMS;

pub const VR_TIME: u32 = 0;
pub const VR_PARAMS: u32 = 1;
pub const VR_INPUTS: u32 = VR_PARAMS + NP as u32;
pub const VR_OUTPUTS: u32 = VR_INPUTS + NU as u32;
pub const VR_STATES: u32 = VR_OUTPUTS + NY as u32;
pub const VR_DERIVATIVES: u32 = VR_STATES + NX as u32;
pub const VR_END: u32 = VR_DERIVATIVES + NX as u32;

/// What a value reference names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Var {
    Time,
    Param(usize),
    Input(usize),
    Output(usize),
    State(usize),
    Derivative(usize),
}

impl Var {
    pub fn of(vr: u32) -> Option<Var> {
        let k = |base: u32| (vr - base) as usize;
        Some(match vr {
            VR_TIME => Var::Time,
            v if v < VR_INPUTS => Var::Param(k(VR_PARAMS)),
            v if v < VR_OUTPUTS => Var::Input(k(VR_INPUTS)),
            v if v < VR_STATES => Var::Output(k(VR_OUTPUTS)),
            v if v < VR_DERIVATIVES => Var::State(k(VR_STATES)),
            v if v < VR_END => Var::Derivative(k(VR_DERIVATIVES)),
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Var::Time => "time",
            Var::Param(i) => m::PARAM_NAMES[i],
            Var::Input(i) => m::INPUT_NAMES[i],
            Var::Output(i) => m::OUTPUT_NAMES[i],
            Var::State(i) | Var::Derivative(i) => m::STATE_NAMES[i],
        }
    }
}

pub type Params = m::Params;

/// `ẋ = f(t, x, u)`.
pub fn rhs(p: &Params, t: f64, x: &[f64], u: &[f64], dx: &mut [f64]) {
    let mut out = m::State::zeros();
    m::rhs_into(p, t, &state(x), &inputs(u), &mut out);
    dx.copy_from_slice(out.as_slice());
}

/// `y = h(t, x, u)`.
pub fn outputs(p: &Params, t: f64, x: &[f64], u: &[f64], y: &mut [f64]) {
    let mut out = m::Outputs::zeros();
    m::outputs_into(p, t, &state(x), &inputs(u), &mut out);
    y.copy_from_slice(out.as_slice());
}

/// An `R × C` matrix of zeros on the heap. The Jacobians of a model of a few hundred states do not fit the stack
/// of the importing tool's thread, and `Box::new(SMatrix::zeros())` would build the matrix on the stack first.
pub fn zeroed_matrix<const R: usize, const C: usize>() -> Box<SMatrix<f64, R, C>> {
    // SAFETY: an `SMatrix<f64, R, C>` is an array of `R · C` `f64` (nalgebra's `ArrayStorage` in a `repr(C)`
    // `Matrix`), and all-zero bits are the `f64` 0.0.
    unsafe { Box::<SMatrix<f64, R, C>>::new_zeroed().assume_init() }
}

/// Writes `∂f/∂x` into `jac` (for the solver's LU decomposition).
pub fn jac_x_into(p: &Params, t: f64, x: &[f64], u: &[f64], jac: &mut m::JacX) {
    m::jac_x_into(p, t, &state(x), &inputs(u), jac);
}

/// The Jacobian of `(ẋ, y)` with respect to `(x, u)`: rows ẋ then y, columns x then u, column-major.
pub fn full_jacobian(p: &Params, t: f64, x: &[f64], u: &[f64]) -> Vec<f64> {
    let (xs, us) = (state(x), inputs(u));
    let (mut fx, mut fu) = (zeroed_matrix::<NX, NX>(), zeroed_matrix::<NX, NU>());
    let (mut hx, mut hu) = (zeroed_matrix::<NY, NX>(), zeroed_matrix::<NY, NU>());
    m::jac_x_into(p, t, &xs, &us, &mut fx);
    m::jac_u_into(p, t, &xs, &us, &mut fu);
    m::output_jac_x_into(p, t, &xs, &us, &mut hx);
    m::output_jac_u_into(p, t, &xs, &us, &mut hu);
    let rows = NX + NY;
    let mut jac = vec![0.0; rows * (NX + NU)];
    for c in 0..NX {
        for r in 0..NX {
            jac[c * rows + r] = fx[(r, c)];
        }
        for r in 0..NY {
            jac[c * rows + NX + r] = hx[(r, c)];
        }
    }
    for c in 0..NU {
        for r in 0..NX {
            jac[(NX + c) * rows + r] = fu[(r, c)];
        }
        for r in 0..NY {
            jac[(NX + c) * rows + NX + r] = hu[(r, c)];
        }
    }
    jac
}

fn state(x: &[f64]) -> m::State {
    m::State::from_iterator(x.iter().copied())
}

fn inputs(u: &[f64]) -> m::Inputs {
    m::Inputs::from_iterator(u.iter().copied())
}
