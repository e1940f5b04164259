//! The Jacobians of the rates and outputs at a point with respect to the states and to chosen parameters, for
//! the forward sensitivities of `bgc fit`.
//!
//! They are taken numerically, by central differences of [`Equations::rates_at`] and [`Equations::outputs_at`],
//! so they cover every model those evaluate (mass-matrix rows, algebraic loops) with one rule. A parameter is
//! perturbed through [`Equations::param_values`], so the derived parameters that depend on it move with it.
//! The step `∛ε · |v|` (`∛ε · max(|x|, 1)` for a state) balances truncation against rounding (relative error about 1e-10).

use super::Equations;
use super::linear::LinearError;

/// `∂f/∂x`, `∂f/∂p`, `∂h/∂x`, `∂h/∂p` at a point, row-major (`fx[i][j] = ∂f_i/∂x_j`); the parameter columns are
/// those asked for, in that order.
#[derive(Clone, Debug, PartialEq)]
pub struct PointJacobians {
    pub fx: Vec<Vec<f64>>,
    pub fp: Vec<Vec<f64>>,
    pub hx: Vec<Vec<f64>>,
    pub hp: Vec<Vec<f64>>,
}

/// ∛ε: the relative step of a central difference.
const STEP: f64 = 6.0554544523933395e-6;

impl Equations {
    /// The Jacobians at state `x`, input `u`, time `t`, with the parameter values that follow from `given`
    /// ([`Equations::param_values`]), differentiated with respect to the parameters `free` (indices into
    /// [`Equations::params`]).
    pub fn param_jacobian_at(
        &self,
        given: &[Option<f64>],
        x: &[f64],
        u: &[f64],
        t: f64,
        free: &[usize],
    ) -> Result<PointJacobians, LinearError> {
        self.jacobians_at(given, (x, u, t), free, true)
    }

    /// [`Equations::param_jacobian_at`] without the outputs (`hx`, `hp` are left empty): half the evaluations,
    /// for an integrator that needs only the rates' Jacobians.
    pub fn rate_param_jacobian_at(
        &self,
        given: &[Option<f64>],
        x: &[f64],
        u: &[f64],
        t: f64,
        free: &[usize],
    ) -> Result<PointJacobians, LinearError> {
        self.jacobians_at(given, (x, u, t), free, false)
    }

    fn jacobians_at(
        &self,
        given: &[Option<f64>],
        (x, u, t): (&[f64], &[f64], f64),
        free: &[usize],
        outputs: bool,
    ) -> Result<PointJacobians, LinearError> {
        let params = self.param_values(given);
        let (nx, ny) = (x.len(), if outputs { self.outputs.len() } else { 0 });
        let mut out = PointJacobians {
            fx: vec![vec![0.0; nx]; nx],
            fp: vec![vec![0.0; free.len()]; nx],
            hx: vec![vec![0.0; nx]; ny],
            hp: vec![vec![0.0; free.len()]; ny],
        };
        let mut xs = x.to_vec();
        for j in 0..nx {
            let h = STEP * x[j].abs().max(1.0);
            xs[j] = x[j] + h;
            let plus = self.point(&params, &xs, u, t, outputs)?;
            xs[j] = x[j] - h;
            let minus = self.point(&params, &xs, u, t, outputs)?;
            xs[j] = x[j];
            column(&mut out.fx, &mut out.hx, j, &plus, &minus, h);
        }
        let mut perturbed = given.to_vec();
        perturbed.resize(self.params.len(), None);
        for (c, &k) in free.iter().enumerate() {
            let Some(&v) = params.get(k) else {
                return Err(LinearError::Dimension {
                    what: "parameter",
                    expected: self.params.len(),
                    got: k + 1,
                });
            };
            // Relative to the value: a tiny positive inertia is stepped in proportion, never across zero.
            let h = STEP * if v == 0.0 { 1.0 } else { v.abs() };
            perturbed[k] = Some(v + h);
            let plus = self.point(&self.param_values(&perturbed), x, u, t, outputs)?;
            perturbed[k] = Some(v - h);
            let minus = self.point(&self.param_values(&perturbed), x, u, t, outputs)?;
            perturbed[k] = given.get(k).copied().flatten();
            column(&mut out.fp, &mut out.hp, c, &plus, &minus, h);
        }
        Ok(out)
    }

    /// The rates and the outputs at a point.
    fn point(
        &self,
        params: &[f64],
        x: &[f64],
        u: &[f64],
        t: f64,
        outputs: bool,
    ) -> Result<(Vec<f64>, Vec<f64>), LinearError> {
        let y = if outputs {
            self.outputs_at(params, x, u, t)?
        } else {
            Vec::new()
        };
        Ok((self.rates_at(params, x, u, t)?, y))
    }
}

/// Writes column `c` of the rate and output Jacobians from the two perturbed points.
fn column(
    f: &mut [Vec<f64>],
    h: &mut [Vec<f64>],
    c: usize,
    plus: &(Vec<f64>, Vec<f64>),
    minus: &(Vec<f64>, Vec<f64>),
    step: f64,
) {
    for (row, (a, b)) in f.iter_mut().zip(plus.0.iter().zip(&minus.0)) {
        row[c] = (a - b) / (2.0 * step);
    }
    for (row, (a, b)) in h.iter_mut().zip(plus.1.iter().zip(&minus.1)) {
        row[c] = (a - b) / (2.0 * step);
    }
}
