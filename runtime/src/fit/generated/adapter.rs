//! [`Generated`]: the adapter of a fixed-size model to [`FitModel`] (needs the `ode` feature, as the fit does).

use nalgebra::{DMatrix, SMatrix, SVector};

use super::ParamJacobians;
use crate::fit::sensitivity::FitModel;
use crate::model::{ContinuousModel, Parametric};

/// A [`ParamJacobians`] method: the columns of the given parameter indices, column-major.
type Columns<M, const NX: usize, const NU: usize> =
    fn(&M, f64, &SVector<f64, NX>, &SVector<f64, NU>, &[usize], &mut [f64]) -> bool;

/// A fixed-size model adapted to [`FitModel`].
pub struct Generated<M, const NX: usize, const NU: usize, const NY: usize> {
    model: M,
    exact: Option<(Columns<M, NX, NU>, Columns<M, NX, NU>)>,
    linear: bool,
}

impl<M, const NX: usize, const NU: usize, const NY: usize> Generated<M, NX, NU, NY>
where
    M: ContinuousModel<NX, NU, NY> + Parametric + Clone,
{
    /// Parameter Jacobians by central differences.
    pub fn new(model: M) -> Self {
        Generated {
            model,
            exact: None,
            linear: false,
        }
    }

    /// Parameter Jacobians from the model's own derivatives.
    pub fn exact(model: M) -> Self
    where
        M: ParamJacobians<NX, NU, NY>,
    {
        Generated {
            model,
            exact: Some((M::jac_p_columns, M::output_jac_p_columns)),
            linear: false,
        }
    }

    /// Declares the model linear time-invariant (a generated model with a `state_space` function is): fits with
    /// held inputs then use the exact discretisation of [`crate::fit::linear`] (checked at a probe point).
    pub fn declared_linear(mut self) -> Self {
        self.linear = true;
        self
    }

    /// The model with its current parameters.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// Column `index` of `(∂f/∂p, ∂h/∂p)` by central differences.
    fn difference(
        &self,
        t: f64,
        x: &SVector<f64, NX>,
        u: &SVector<f64, NU>,
        index: usize,
    ) -> Result<(SVector<f64, NX>, SVector<f64, NY>), String> {
        let p = self
            .model
            .param(index)
            .ok_or_else(|| format!("no parameter {index}"))?;
        // ∛ε relative to the value (a tiny positive inertia is stepped in proportion, never across zero).
        let h = 6.0554544523933395e-6 * if p == 0.0 { 1.0 } else { p.abs() };
        let eval = |v: f64| -> Result<(SVector<f64, NX>, SVector<f64, NY>), String> {
            let mut m = self.model.clone();
            m.set_param(index, v).map_err(|e| e.to_string())?;
            let mut f = SVector::zeros();
            let mut y = SVector::zeros();
            m.rhs(t, x, u, &mut f);
            m.outputs(t, x, u, &mut y);
            Ok((f, y))
        };
        // A bound of the parameter's physical range (a positive inertia at a tiny value) falls back to one side.
        match (eval(p + h), eval(p - h)) {
            (Ok(a), Ok(b)) => Ok(((a.0 - b.0) / (2.0 * h), (a.1 - b.1) / (2.0 * h))),
            (Ok(a), Err(_)) => {
                let c = eval(p)?;
                Ok(((a.0 - c.0) / h, (a.1 - c.1) / h))
            }
            (Err(e), _) => Err(e),
        }
    }

    /// The columns of `∂f/∂p` (of `∂h/∂p` for `output`) of the parameters `free`: all from one call of the
    /// model's exact columns when it has them (`false` there means an index that is no parameter), else column
    /// by column by central differences.
    fn param_matrix(
        &self,
        (t, x, u): (f64, &SVector<f64, NX>, &SVector<f64, NU>),
        free: &[usize],
        output: bool,
    ) -> Result<DMatrix<f64>, String> {
        let mut m = DMatrix::zeros(if output { NY } else { NX }, free.len());
        if free.is_empty() {
            return Ok(m);
        }
        match self.exact {
            Some((rate, out)) => {
                let columns = if output { out } else { rate };
                if !columns(&self.model, t, x, u, free, m.as_mut_slice()) {
                    return Err(format!("no parameter among {free:?}"));
                }
            }
            None => {
                for (c, &k) in free.iter().enumerate() {
                    let (f, h) = self.difference(t, x, u, k)?;
                    let column = if output { h.as_slice() } else { f.as_slice() };
                    m.column_mut(c).copy_from_slice(column);
                }
            }
        }
        Ok(m)
    }
}

fn fixed<const N: usize>(v: &[f64]) -> SVector<f64, N> {
    SVector::from_fn(|i, _| v[i])
}

impl<M, const NX: usize, const NU: usize, const NY: usize> FitModel for Generated<M, NX, NU, NY>
where
    M: ContinuousModel<NX, NU, NY> + Parametric + Clone,
{
    fn state_count(&self) -> usize {
        NX
    }
    fn input_count(&self) -> usize {
        NU
    }
    fn output_count(&self) -> usize {
        NY
    }
    fn param_count(&self) -> usize {
        self.model.param_names().len()
    }

    fn is_linear(&self) -> bool {
        self.linear
    }

    fn set_params(&mut self, p: &[f64]) -> Result<(), String> {
        for (k, &v) in p.iter().enumerate() {
            if self.model.param(k) != Some(v) {
                self.model.set_param(k, v).map_err(|e| e.to_string())?;
            }
        }
        Ok(())
    }

    fn rhs(&self, t: f64, x: &[f64], u: &[f64], dx: &mut [f64]) -> Result<(), String> {
        let mut d = SVector::<f64, NX>::zeros();
        self.model.rhs(t, &fixed(x), &fixed(u), &mut d);
        dx.copy_from_slice(d.as_slice());
        Ok(())
    }

    fn outputs(&self, t: f64, x: &[f64], u: &[f64], y: &mut [f64]) -> Result<(), String> {
        let mut o = SVector::<f64, NY>::zeros();
        self.model.outputs(t, &fixed(x), &fixed(u), &mut o);
        y.copy_from_slice(o.as_slice());
        Ok(())
    }

    fn rate_jacobians(
        &self,
        t: f64,
        x: &[f64],
        u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        let (x, u) = (fixed::<NX>(x), fixed::<NU>(u));
        // On the heap, written there: an `NX × NX` matrix takes 8 MB at 1,000 states.
        let mut a: Box<SMatrix<f64, NX, NX>> = bytemuck::zeroed_box();
        self.model.jac_x(t, &x, &u, &mut a);
        let fp = self.param_matrix((t, &x, &u), free, false)?;
        Ok((DMatrix::from_column_slice(NX, NX, a.as_slice()), fp))
    }

    fn output_jacobians(
        &self,
        t: f64,
        x: &[f64],
        u: &[f64],
        free: &[usize],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), String> {
        let (x, u) = (fixed::<NX>(x), fixed::<NU>(u));
        let mut c_mat: Box<SMatrix<f64, NY, NX>> = bytemuck::zeroed_box();
        self.model.output_jac_x(t, &x, &u, &mut c_mat);
        let hp = self.param_matrix((t, &x, &u), free, true)?;
        Ok((DMatrix::from_column_slice(NY, NX, c_mat.as_slice()), hp))
    }
}
