//! `Model`: the parameters of a generated model, validated, and its implementations of the runtime's traits.

use super::super::names::comment;
use super::Writer;

/// `Model` and its inherent methods.
const MODEL: &str = "#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Model {
    params: Params,
}

impl Model {
    /// The model with parameters `params`, refused when they are not physical.
    pub fn new(params: Params) -> Result<Model, ParamError> {
        params.validate()?;
        Ok(Model { params })
    }

    /// The parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Replaces the parameters; non-physical ones are refused and leave the model unchanged.
    pub fn set_params(&mut self, params: Params) -> Result<(), ParamError> {
        params.validate()?;
        self.params = params;
        Ok(())
    }
}
";

/// The implementations of `bgc_runtime`'s traits.
const RUNTIME_IMPLS: &str = "
impl bgc_runtime::model::ContinuousModel<N_STATES, N_INPUTS, N_OUTPUTS> for Model {
    fn rhs(&self, t: f64, x: &State, u: &Inputs, dx: &mut State) {
        rhs_into(&self.params, t, x, u, dx);
    }

    fn outputs(&self, t: f64, x: &State, u: &Inputs, y: &mut Outputs) {
        outputs_into(&self.params, t, x, u, y);
    }

    fn jac_x(&self, t: f64, x: &State, u: &Inputs, jac: &mut JacX) {
        jac_x_into(&self.params, t, x, u, jac);
    }

    fn jac_u(&self, t: f64, x: &State, u: &Inputs, jac: &mut JacU) {
        jac_u_into(&self.params, t, x, u, jac);
    }

    fn output_jac_x(&self, t: f64, x: &State, u: &Inputs, jac: &mut OutJacX) {
        output_jac_x_into(&self.params, t, x, u, jac);
    }

    fn output_jac_u(&self, t: f64, x: &State, u: &Inputs, jac: &mut OutJacU) {
        output_jac_u_into(&self.params, t, x, u, jac);
    }
}

impl bgc_runtime::model::Parametric for Model {
    fn param_names(&self) -> &'static [&'static str] {
        &PARAM_NAMES
    }

    fn param(&self, index: usize) -> Option<f64> {
        self.params.get(index)
    }

    fn set_param(&mut self, index: usize, value: f64) -> Result<(), ParamError> {
        self.params.set(index, value)
    }
}
";

impl Writer<'_> {
    pub(super) fn model(&mut self) {
        let model = &self.m.model;
        self.out.push('\n');
        self.doc_lines(0, &model.doc.clone());
        if !model.doc.is_empty() {
            self.doc(0, "");
        }
        let what = if self.options.runtime {
            "a `bgc_runtime::model::ContinuousModel` with symbolic Jacobians and a `Parametric` model."
        } else {
            "the functions of this module at these parameters."
        };
        let name = comment(&self.m.model.name);
        self.doc(0, &format!("Model `{name}` with its parameters: {what}"));
        self.out.push_str(MODEL);
        if self.options.runtime {
            self.out.push_str(RUNTIME_IMPLS);
        }
    }
}
