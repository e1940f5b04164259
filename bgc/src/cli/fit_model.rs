//! The derived equations of a model as a [`FitModel`] for `bgc fit`: rates and outputs by
//! [`Equations::rates_at`] and [`Equations::outputs_at`], Jacobians by the symbolic derivatives of
//! [`Equations::sensitivity`] (built once, evaluated at every step).

use bgc::equations::{self, Equations, PointJacobians, Rows, Sensitivity, StateSelection};
use bgc_runtime::fit::FitModel;
use nalgebra::DMatrix;

/// The equations with the parameter values as given: the fitted ones set by the fit, the derived ones recomputed
/// from them.
pub struct Interpreted<'a> {
    eqs: &'a Equations,
    given: Vec<Option<f64>>,
    values: Vec<f64>,
    free: Vec<usize>,
    /// The rates and outputs are linear in the states and inputs (a symbolic state space exists): fits with held
    /// inputs take the exact discretisation path.
    linear: bool,
    /// The symbolic Jacobians, or why they could not be formed (reported when they are asked for).
    sensitivity: Result<Sensitivity<'a>, String>,
}

impl<'a> Interpreted<'a> {
    /// `given`: the values set on the command line (the rest follow from the defaults); `free`: the fitted ones.
    pub fn new(eqs: &'a Equations, given: Vec<Option<f64>>, free: Vec<usize>) -> Interpreted<'a> {
        let values = eqs.param_values(&given);
        let linear = equations::linear_state_space(eqs, StateSelection::All).is_ok();
        let sensitivity = eqs.sensitivity(&given, &free).map_err(|e| e.to_string());
        Interpreted {
            eqs,
            given,
            values,
            free,
            linear,
            sensitivity,
        }
    }

    /// The Jacobians at a point, with the parameter columns `free`: picked from the prepared ones when the model
    /// was made with them, else formed for this call.
    fn jacobians(
        &self,
        (t, x, u): (f64, &[f64], &[f64]),
        free: &[usize],
        rows: Rows,
    ) -> Result<PointJacobians, String> {
        let picked: Option<Vec<usize>> = free
            .iter()
            .map(|k| self.free.iter().position(|f| f == k))
            .collect();
        let Some(picked) = picked else {
            return self
                .eqs
                .sensitivity(&self.given, free)
                .and_then(|s| s.at(&self.values, (x, u, t), rows))
                .map_err(|e| e.to_string());
        };
        let sensitivity = self.sensitivity.as_ref().map_err(Clone::clone)?;
        let mut j = sensitivity
            .at(&self.values, (x, u, t), rows)
            .map_err(|e| e.to_string())?;
        if picked.len() != self.free.len() || picked.iter().enumerate().any(|(c, &k)| c != k) {
            let pick = |rows: &mut Vec<Vec<f64>>| {
                for row in rows.iter_mut() {
                    *row = picked.iter().map(|&k| row[k]).collect();
                }
            };
            pick(&mut j.fp);
            pick(&mut j.hp);
        }
        Ok(j)
    }
}

fn matrix(rows: &[Vec<f64>], ncols: usize) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), ncols, |i, j| rows[i][j])
}

impl FitModel for Interpreted<'_> {
    fn is_linear(&self) -> bool {
        self.linear
    }

    fn state_count(&self) -> usize {
        self.eqs.states.len()
    }
    fn input_count(&self) -> usize {
        self.eqs.inputs.len()
    }
    fn output_count(&self) -> usize {
        self.eqs.outputs.len()
    }
    fn param_count(&self) -> usize {
        self.eqs.params.len()
    }

    fn set_params(&mut self, p: &[f64]) -> Result<(), String> {
        for &k in &self.free {
            let v = p.get(k).copied().ok_or("too few parameter values")?;
            self.given[k] = Some(v);
        }
        self.values = self.eqs.param_values(&self.given);
        Ok(())
    }

    fn rhs(&self, t: f64, x: &[f64], u: &[f64], dx: &mut [f64]) -> Result<(), String> {
        let rates = self
            .eqs
            .rates_at(&self.values, x, u, t)
            .map_err(|e| e.to_string())?;
        dx.copy_from_slice(&rates);
        Ok(())
    }

    fn outputs(&self, t: f64, x: &[f64], u: &[f64], y: &mut [f64]) -> Result<(), String> {
        let out = self
            .eqs
            .outputs_at(&self.values, x, u, t)
            .map_err(|e| e.to_string())?;
        y.copy_from_slice(&out);
        Ok(())
    }

    fn rate_jacobians(
        &self,
        t: f64,
        x: &[f64],
        u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        let j = self.jacobians((t, x, u), free, Rows::Rates)?;
        Ok((matrix(&j.fx, x.len()), matrix(&j.fp, free.len())))
    }

    fn output_jacobians(
        &self,
        t: f64,
        x: &[f64],
        u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        let j = self.jacobians((t, x, u), free, Rows::Outputs)?;
        Ok((matrix(&j.hx, x.len()), matrix(&j.hp, free.len())))
    }
}
