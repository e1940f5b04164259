//! `Model`: the parameters of a generated model, validated, and its implementations of the runtime's traits.
//!
//! A Jacobian that depends on the parameters only (every Jacobian of a linear model) is computed once per
//! parameter set, in `Model::new`, `set_params` and `set_param`, and the runtime's `jac_x`, ... copy it: the
//! back-support `jac_x` would otherwise divide by parameters 22 times and fill 100 entries at each call. The cache
//! lives in `Model`, which is `Copy` and on the stack, so it is kept only while its matrices fit in
//! [`MAX_CONSTANT_JACOBIAN_BYTES`]; a larger model computes its Jacobians at each call, as the free functions do.
//! `Model` also holds the parameter terms ([`super::terms`]) that its functions read, computed at the same times.

use super::super::names::comment;
use super::Writer;
use std::fmt::Write;

/// The most bytes of constant Jacobians a `Model` holds (256 KiB: a `JacX` of 181 states).
pub(crate) const MAX_CONSTANT_JACOBIAN_BYTES: usize = 256 * 1024;

/// Whether an `n × n` matrix of `f64` fits in [`MAX_CONSTANT_JACOBIAN_BYTES`] (up to 181 states): the bound of every
/// square matrix generated code declares (`JacX`, the state space's `A`).
pub(in crate::codegen) fn square_fits(n: usize) -> bool {
    n.saturating_mul(n).saturating_mul(8) <= MAX_CONSTANT_JACOBIAN_BYTES
}

/// A Jacobian function whose body reads neither `t`, `x` nor `u`.
#[derive(Clone, Debug)]
pub(in crate::codegen) struct ConstantJacobian {
    /// The free function (`jac_x_into`).
    function: String,
    /// The matrix type (`JacX`).
    ty: String,
}

impl ConstantJacobian {
    /// The field of `ConstantJacobians` and the method of the runtime's trait (`jac_x`).
    fn field(&self) -> &str {
        self.function
            .strip_suffix("_into")
            .unwrap_or(&self.function)
    }
}

/// `Model` and its inherent methods, without constant Jacobians.
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

/// `Model` and its inherent methods when it holds values computed from its parameters (`{fields}`: their
/// declarations, `{values}`: their values in `Model::at`).
const MODEL_WITH_CACHE: &str = "#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model {
    params: Params,
{fields}}

impl Model {
    /// The model with parameters `params`, refused when they are not physical.
    pub fn new(params: Params) -> Result<Model, ParamError> {
        params.validate()?;
        Ok(Model::at(params))
    }

    /// The model at `params` (validated or the defaults), with what it computes from them once.
    fn at(params: Params) -> Model {
        Model {
            params,
{values}        }
    }

    /// The parameters.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Replaces the parameters; non-physical ones are refused and leave the model unchanged.
    pub fn set_params(&mut self, params: Params) -> Result<(), ParamError> {
        params.validate()?;
        *self = Model::at(params);
        Ok(())
    }
}

impl Default for Model {
    fn default() -> Self {
        Model::at(Params::default())
    }
}
";

/// The implementations of `bgc_runtime`'s traits.
const RUNTIME_IMPLS: &str = "
impl bgc_runtime::model::Parametric for Model {
    fn param_names(&self) -> &'static [&'static str] {
        &PARAM_NAMES
    }

    fn param(&self, index: usize) -> Option<f64> {
        self.params.get(index)
    }

    fn set_param(&mut self, index: usize, value: f64) -> Result<(), ParamError> {
        {set_param}
    }
}
";

/// The body of `set_param` when `Model` holds values computed from its parameters.
const SET_PARAM_WITH_CACHE: &str = "self.params.set(index, value)?;
        *self = Model::at(self.params);
        Ok(())";

/// The runtime's Jacobian methods, in trait order: method, free function, matrix type.
const JACOBIANS: [(&str, &str, &str); 4] = [
    ("jac_x", "jac_x_into", "JacX"),
    ("jac_u", "jac_u_into", "JacU"),
    ("output_jac_x", "output_jac_x_into", "OutJacX"),
    ("output_jac_u", "output_jac_u_into", "OutJacU"),
];

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
        let constants = self.cached_jacobians();
        // Without the runtime's traits nothing would read the parameter terms from `Model`.
        let terms = self.options.runtime && !self.with_terms.is_empty();
        let mut fields = String::new();
        let mut values = String::new();
        if terms {
            fields.push_str("    terms: ParamTerms,\n");
            values.push_str("            terms: ParamTerms::at(&params),\n");
        }
        if !constants.is_empty() {
            fields.push_str("    constant: ConstantJacobians,\n");
            values.push_str("            constant: ConstantJacobians::at(&params),\n");
        }
        let cached = !fields.is_empty();
        if cached {
            self.out.push_str(
                &MODEL_WITH_CACHE
                    .replace("{fields}", &fields)
                    .replace("{values}", &values),
            );
        } else {
            self.out.push_str(MODEL);
        }
        if self.options.runtime {
            self.continuous_model(&constants);
            let set_param = if cached {
                SET_PARAM_WITH_CACHE
            } else {
                "self.params.set(index, value)"
            };
            self.out
                .push_str(&RUNTIME_IMPLS.replace("{set_param}", set_param));
            self.param_jacobians_impl();
        }
        if !constants.is_empty() {
            self.constant_jacobians_struct(&constants);
        }
    }

    /// Records that the Jacobian function `function` (with argument type `&mut JacX`, ...) is constant.
    pub(super) fn constant_jacobian(&mut self, function: &str, arg_ty: &str) {
        self.constant_jacobians.push(ConstantJacobian {
            function: function.to_string(),
            ty: arg_ty.trim_start_matches("&mut ").to_string(),
        });
    }

    /// The constant Jacobians `Model` holds: none without the runtime's traits (nothing would read them) or when
    /// they take more than [`MAX_CONSTANT_JACOBIAN_BYTES`].
    fn cached_jacobians(&self) -> Vec<ConstantJacobian> {
        let (nx, nu, ny) = (
            self.plan.states.len(),
            self.plan.inputs.len(),
            self.m.equations.outputs.len(),
        );
        let bytes = |ty: &str| {
            let (r, c) = match ty {
                "JacX" => (nx, nx),
                "JacU" => (nx, nu),
                "OutJacX" => (ny, nx),
                _ => (ny, nu),
            };
            r.saturating_mul(c).saturating_mul(8)
        };
        let total: usize = self.constant_jacobians.iter().map(|j| bytes(&j.ty)).sum();
        if !self.options.runtime || total > MAX_CONSTANT_JACOBIAN_BYTES {
            return Vec::new();
        }
        self.constant_jacobians.clone()
    }

    /// The call of the model function `function` from a method of `Model`: with the parameter terms it holds
    /// when the function reads any.
    fn model_call(&self, function: &str, out: &str) -> String {
        if self.with_terms.iter().any(|f| f == function) {
            let with = super::functions::with_terms_name(function);
            format!("{with}(&self.params, &self.terms, t, x, u, {out});")
        } else {
            format!("{function}(&self.params, t, x, u, {out});")
        }
    }

    /// `ContinuousModel` for `Model`: a constant Jacobian is copied, the others are computed.
    fn continuous_model(&mut self, constants: &[ConstantJacobian]) {
        let mut text = String::from(
            "
impl bgc_runtime::model::ContinuousModel<N_STATES, N_INPUTS, N_OUTPUTS> for Model {
    #[inline]
    fn rhs(&self, t: f64, x: &State, u: &Inputs, dx: &mut State) {
        {rhs}
    }

    #[inline]
    fn outputs(&self, t: f64, x: &State, u: &Inputs, y: &mut Outputs) {
        {outputs}
    }
",
        )
        .replace("{rhs}", &self.model_call("rhs_into", "dx"))
        .replace("{outputs}", &self.model_call("outputs_into", "y"));
        for (method, function, ty) in JACOBIANS {
            if constants.iter().any(|c| c.function == function) {
                let _ = write!(
                    text,
                    "
    #[inline]
    fn {method}(&self, _t: f64, _x: &State, _u: &Inputs, jac: &mut {ty}) {{
        *jac = self.constant.{method};
    }}
"
                );
            } else {
                let call = self.model_call(function, "jac");
                let _ = write!(
                    text,
                    "
    #[inline]
    fn {method}(&self, t: f64, x: &State, u: &Inputs, jac: &mut {ty}) {{
        {call}
    }}
"
                );
            }
        }
        text.push_str(
            "}
",
        );
        self.out.push_str(&text);
    }

    /// `ConstantJacobians`: the Jacobians that depend on the parameters only, and `at(p)`.
    fn constant_jacobians_struct(&mut self, constants: &[ConstantJacobian]) {
        let mut text = String::from(
            "
/// The Jacobians that depend on the parameters only, computed once for them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct ConstantJacobians {
",
        );
        for c in constants {
            let _ = writeln!(text, "    {}: {},", c.field(), c.ty);
        }
        text.push_str(
            "}

impl ConstantJacobians {
    /// The Jacobians at the parameters `p` (at any `t`, `x`, `u`: they read none).
    fn at(p: &Params) -> ConstantJacobians {
        let (x, u) = (State::zeros(), Inputs::zeros());
",
        );
        for c in constants {
            let _ = write!(
                text,
                "        let mut {field} = {ty}::zeros();\n        {function}(p, 0.0, &x, &u, &mut {field});\n",
                field = c.field(),
                ty = c.ty,
                function = c.function,
            );
        }
        let fields: Vec<&str> = constants.iter().map(|c| c.field()).collect();
        let list = fields.join(", ");
        // rustfmt keeps a struct literal on one line while its fields take at most 18 columns.
        if list.len() <= 18 {
            let _ = writeln!(text, "        ConstantJacobians {{ {list} }}");
        } else {
            text.push_str("        ConstantJacobians {\n");
            for f in fields {
                let _ = writeln!(text, "            {f},");
            }
            text.push_str("        }\n");
        }
        text.push_str("    }\n}\n");
        self.out.push_str(&text);
    }
}
