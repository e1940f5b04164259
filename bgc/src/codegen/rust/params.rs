//! The sizes, names and types of a generated module, its `ParamError` and its `Params`.

use super::super::format::{self, Wrap};
use super::super::layout::Body;
use super::super::names::{Namer, comment, sanitize, string_literal};
use super::{Writer, output_names, rust_f64};
use crate::ir;
use crate::symbolic::{Expr, ExprMap, Symbol, from_ir, to_rust_code, to_text};
use crate::syntax::ast::ElementKind;
use std::collections::HashMap;
use std::fmt::Write;

/// The rule a parameter-only element value must satisfy.
#[derive(Clone, Copy)]
enum Rule {
    Positive(&'static str),
    NonNegative,
    NonZero,
}

/// The error type of a module without the runtime, with the variants and messages of
/// `bgc_runtime::model::ParamError`, as `rustfmt` lays it out.
const OWN_PARAM_ERROR: &str = "
/// Why parameter values are refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamError {
    /// No parameter has index `index`.
    NoSuchParam { index: usize },
    /// Parameter `name` cannot take `value`, for `reason`.
    NonPhysical {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ParamError::NoSuchParam { index } => write!(f, \"no parameter with index {index}\"),
            ParamError::NonPhysical {
                name,
                value,
                reason,
            } => write!(
                f,
                \"parameter `{name}` = {value:?} is not physical: {reason}\"
            ),
        }
    }
}

impl core::error::Error for ParamError {}
";

impl Writer<'_> {
    pub(in crate::codegen) fn name_array(
        &mut self,
        konst: &str,
        size: &str,
        what: &str,
        names: &[String],
    ) {
        let list: Vec<String> = names.iter().map(|n| string_literal(n)).collect();
        self.out.push('\n');
        self.doc(0, &format!("The names of the {what}, in vector order."));
        let head = format!("pub const {konst}: [&str; {size}] = ");
        self.out
            .push_str(&format::array(&head, &list, ";", 0, self.width));
        self.out.push('\n');
    }

    pub(super) fn sizes(&mut self) {
        let eqs = &self.m.equations;
        let consts = [
            (
                "N_STATES",
                "The number of states: the energy variables of the storages (`p` of inertias, `q` of \
                 compliances), then the integrated flows (`var`s).",
                eqs.states.len(),
            ),
            (
                "N_ENERGY_STATES",
                "The number of energy states (the first `N_ENERGY_STATES` entries of the state vector).",
                eqs.energy_states,
            ),
            ("N_INPUTS", "The number of inputs.", eqs.inputs.len()),
            ("N_OUTPUTS", "The number of outputs.", eqs.outputs.len()),
            (
                "N_PARAMS",
                "The number of free parameters (the fields of `Params`).",
                self.free.len(),
            ),
        ];
        self.out.push('\n');
        for (name, doc, value) in consts {
            self.doc(0, doc);
            let _ = writeln!(self.out, "pub const {name}: usize = {value};");
        }
        let states: Vec<String> = eqs.states.iter().map(|s| s.name.clone()).collect();
        let inputs = eqs.inputs.clone();
        let outputs = output_names(eqs);
        let params: Vec<String> = self
            .free
            .iter()
            .filter_map(|&k| eqs.params.get(k).map(|p| p.0.clone()))
            .collect();
        self.name_array("STATE_NAMES", "N_STATES", "states", &states);
        self.name_array("INPUT_NAMES", "N_INPUTS", "inputs", &inputs);
        self.name_array("OUTPUT_NAMES", "N_OUTPUTS", "outputs", &outputs);
        self.name_array("PARAM_NAMES", "N_PARAMS", "parameters", &params);
        self.out.push_str(
            "
/// The state vector.
pub type State = SVector<f64, N_STATES>;
/// The input vector.
pub type Inputs = SVector<f64, N_INPUTS>;
/// The output vector.
pub type Outputs = SVector<f64, N_OUTPUTS>;
/// `∂f/∂x`.
pub type JacX = SMatrix<f64, N_STATES, N_STATES>;
/// `∂f/∂u`.
pub type JacU = SMatrix<f64, N_STATES, N_INPUTS>;
/// `∂h/∂x`.
pub type OutJacX = SMatrix<f64, N_OUTPUTS, N_STATES>;
/// `∂h/∂u`.
pub type OutJacU = SMatrix<f64, N_OUTPUTS, N_INPUTS>;
",
        );
    }

    pub(super) fn params(&mut self) {
        if self.options.runtime {
            self.out.push('\n');
            self.doc(
                0,
                "Why parameter values are refused: the runtime's error, which its traits return.",
            );
            self.out
                .push_str("pub use bgc_runtime::model::ParamError;\n");
        } else {
            self.out.push_str(OWN_PARAM_ERROR);
        }
        let model = &self.m.model;
        let free: Vec<&ir::Param> = self
            .free
            .iter()
            .filter_map(|&k| model.params.get(k))
            .collect();
        self.out.push('\n');
        self.doc(
            0,
            &format!(
                "The parameters of `{}`, in SI units. A parameter the file defines from others is a method: it \
                 follows the fields it uses.",
                comment(&model.name)
            ),
        );
        // `Default` derived when every default is +0 (clippy's `derivable_impls`), written out otherwise.
        let derive_default = free.iter().all(|p| p.default.to_bits() == 0);
        let _ = writeln!(
            self.out,
            "#[derive(Clone, Copy, Debug, {}PartialEq)]",
            if derive_default { "Default, " } else { "" }
        );
        if self.fields.iter().any(|f| !format::is_snake_case(f)) {
            self.out.push_str("#[allow(non_snake_case)]\n");
        }
        if free.is_empty() {
            self.out.push_str("pub struct Params {}\n");
        } else {
            self.out.push_str("pub struct Params {\n");
            for (p, field) in free.iter().zip(self.fields.clone()) {
                let desc = p.description.as_deref().unwrap_or("(no description)");
                self.doc(4, desc);
                if !p.doc.is_empty() {
                    self.doc(4, "");
                    self.doc_lines(4, &p.doc);
                }
                self.doc(4, "");
                self.doc(
                    4,
                    &format!(
                        "Declared unit `[{}]`; the value is in SI units. Default: {}.",
                        comment(&p.unit_text),
                        rust_f64(p.default)
                    ),
                );
                let _ = writeln!(self.out, "    pub {field}: f64,");
            }
            self.out.push_str("}\n");
        }
        if !derive_default {
            let values: Vec<(String, String)> = free
                .iter()
                .zip(self.fields.clone())
                .map(|(p, f)| (f, rust_f64(p.default)))
                .collect();
            let literal = format::struct_literal("Params", &values, "", 8, self.width);
            let allow = if format::may_look_like_a_constant(&literal) {
                "    #[allow(clippy::approx_constant)]\n"
            } else {
                ""
            };
            let _ = write!(
                self.out,
                "\nimpl Default for Params {{\n    /// The defaults of the `.bg` file.\n{allow}    fn default() -> Self {{\n{literal}\n    }}\n}}\n"
            );
        }
        self.out.push_str("\nimpl Params {\n");
        self.derived_methods();
        self.validate();
        self.get_set();
        self.out.push_str("}\n");
    }

    /// One method per derived parameter, in terms of the fields and the methods before it.
    fn derived_methods(&mut self) {
        let model = &self.m.model;
        let eqs = &self.m.equations;
        for (k, p) in model.params.iter().enumerate() {
            let Some(Some(e)) = eqs.derived.get(k) else {
                continue;
            };
            let Ok(value) = super::super::adapter::to_symbolic(eqs, e) else {
                continue;
            };
            let code = to_rust_code(&value, &|s| self.param_access(s.name()));
            let name = self.all_fields.get(k).cloned().unwrap_or_default();
            let desc = p.description.as_deref().unwrap_or("A derived parameter.");
            self.doc(4, desc);
            self.doc(4, "");
            self.doc(
                4,
                &format!(
                    "Declared unit `[{}]`, in SI units: `{}`.",
                    comment(&p.unit_text),
                    to_text(&value)
                ),
            );
            let mut namer = Namer::with_reserved();
            let mut body = Body::new(&mut namer, 8, self.width);
            body.statement("", &code, "");
            let text = body.finish();
            let mut lints = Vec::new();
            if !format::is_snake_case(&name) {
                lints.push("non_snake_case");
            }
            if format::may_look_like_a_constant(&text) {
                lints.push("clippy::approx_constant");
            }
            if !lints.is_empty() {
                let _ = writeln!(self.out, "    #[allow({})]", lints.join(", "));
            }
            let _ = write!(
                self.out,
                "    pub fn {name}(&self) -> f64 {{\n{text}    }}\n\n"
            );
        }
    }

    /// How code inside `impl Params` reads parameter `name`: `self.field`, or `self.method()` when derived.
    fn param_access(&self, name: &str) -> String {
        let eqs = &self.m.equations;
        let Some(k) = eqs.params.iter().position(|p| p.0 == name) else {
            return "f64::NAN".into();
        };
        let field = self.all_fields.get(k).cloned().unwrap_or_default();
        if eqs.derived.get(k).is_some_and(Option::is_some) {
            format!("self.{field}()")
        } else {
            format!("self.{field}")
        }
    }

    /// `get` and `set` by index.
    fn get_set(&mut self) {
        self.out.push('\n');
        self.doc(
            4,
            "The parameter with index `index` (in `PARAM_NAMES` order).",
        );
        if self.fields.is_empty() {
            self.out.push_str(
                "    pub fn get(&self, _index: usize) -> Option<f64> {\n        None\n    }\n",
            );
        } else {
            self.out.push_str(
                "    pub fn get(&self, index: usize) -> Option<f64> {\n        match index {\n",
            );
            for (k, field) in self.fields.iter().enumerate() {
                let _ = writeln!(self.out, "            {k} => Some(self.{field}),");
            }
            self.out
                .push_str("            _ => None,\n        }\n    }\n");
        }
        self.out.push('\n');
        self.doc(
            4,
            "Sets the parameter with index `index`; a value that makes the parameters non-physical is refused \
             and leaves them unchanged.",
        );
        if self.fields.is_empty() {
            self.out.push_str(
                "    pub fn set(&mut self, index: usize, _value: f64) -> Result<(), ParamError> {\n        \
                 Err(ParamError::NoSuchParam { index })\n    }\n",
            );
            return;
        }
        self.out.push_str(
            "    pub fn set(&mut self, index: usize, value: f64) -> Result<(), ParamError> {\n        \
             let mut next = *self;\n        match index {\n",
        );
        for (k, field) in self.fields.iter().enumerate() {
            let _ = writeln!(self.out, "            {k} => next.{field} = value,");
        }
        self.out.push_str(
            "            _ => return Err(ParamError::NoSuchParam { index }),\n        }\n        \
             next.validate()?;\n        *self = next;\n        Ok(())\n    }\n",
        );
    }

    /// `validate`: every parameter finite; each inertia and compliance positive, each resistance non-negative and
    /// each transformer or gyrator modulus non-zero, where the element's value depends on parameters only.
    fn validate(&mut self) {
        let model = &self.m.model;
        let mut namer = Namer::with_reserved();
        let mut body = Body::new(&mut namer, 8, self.width);
        let values: Vec<String> = self.fields.iter().map(|f| format!("self.{f}")).collect();
        body.lines(
            format::array(
                "        let values: [f64; N_PARAMS] = ",
                &values,
                ";",
                8,
                self.width,
            )
            .lines()
            .map(str::to_string),
        );
        body.lines(
            "        for (name, value) in PARAM_NAMES.into_iter().zip(values) {
            if !value.is_finite() {
                return Err(ParamError::NonPhysical {
                    name,
                    value,
                    reason: \"not a finite number\",
                });
            }
        }"
            .lines()
            .map(str::to_string),
        );
        let field_of: HashMap<String, String> = model
            .params
            .iter()
            .map(|p| (p.name.clone(), self.param_access(&p.name)))
            .collect();
        let checks = self.element_checks(&field_of);
        let divisors = self.divisor_checks(&checks);
        for check in checks {
            let (cond, what) = match check.rule {
                Rule::Positive(what) => ("!v.is_finite() || v <= 0.0", (what, "positive")),
                Rule::NonNegative => ("!v.is_finite() || v < 0.0", ("resistance", "non-negative")),
                Rule::NonZero => ("!v.is_finite() || v == 0.0", ("modulus", "non-zero")),
            };
            let text = &check.text;
            let (elements, of) = match check.others {
                0 => (
                    check.element.clone(),
                    format!("`{}` ({text})", check.element),
                ),
                n => (
                    format!("{} and {n} {}", check.element, others(n)),
                    format!(
                        "`{}` ({text}) and of {n} {} with the same value",
                        check.element,
                        others(n)
                    ),
                ),
            };
            let reason = format!("the {} of {of} must be {} and finite", what.0, what.1);
            body.lines(format::comment(
                8,
                "//",
                &format!("{elements}: {text}"),
                Wrap::Equation,
                self.width,
            ));
            body.statement("let v = ", &check.code, ";");
            let reason_head = "                reason: ";
            let reason = format::string_literal(&reason, reason_head.len(), 1, 16, self.width);
            body.lines(
                format!(
                    "        if {cond} {{
            return Err(ParamError::NonPhysical {{
                name: {},
                value: {},
{reason_head}{reason},
            }});
        }}",
                    string_literal(&check.param),
                    check.field,
                )
                .lines()
                .map(str::to_string),
            );
        }
        for (name, access) in divisors {
            let reason = "the equations divide by it, and its reciprocal is not finite";
            body.lines(
                format!(
                    "        // The equations divide by {name}.
        if !(1.0 / {access}).is_finite() {{
            return Err(ParamError::NonPhysical {{
                name: {},
                value: {access},
                reason: {},
            }});
        }}",
                    string_literal(&name),
                    string_literal(reason),
                )
                .lines()
                .map(str::to_string),
            );
        }
        body.line("Ok(())");
        let text = body.finish();
        self.doc(
            4,
            "Checks that the parameters are physical: all finite, inertias and compliances positive, resistances \
             non-negative, transformer and gyrator moduli non-zero, and each parameter the equations divide by \
             with a finite reciprocal.",
        );
        if format::may_look_like_a_constant(&text) {
            self.out.push_str("    #[allow(clippy::approx_constant)]\n");
        }
        self.out
            .push_str("    pub fn validate(&self) -> Result<(), ParamError> {\n");
        self.out.push_str(&text);
        self.out.push_str("    }\n");
    }
}

impl Writer<'_> {
    /// The checks of the elements whose value is an expression of parameters, each distinct (value, rule)
    /// once, in the order of the first element that needs it: a chain of 10,000 masses of inertia `m` checks `m`
    /// once, not 10,000 times, and the message names the first mass and counts the others.
    fn element_checks(&self, field_of: &HashMap<String, String>) -> Vec<ElementCheck> {
        let model = &self.m.model;
        let mut checks: Vec<ElementCheck> = Vec::new();
        let mut index: HashMap<(String, &'static str), usize> = HashMap::new();
        let mut printed: ExprMap<Option<CheckCode>> = ExprMap::default();
        for node in model.graph.node_weights() {
            let (expr, rule) = match (&node.kind, &node.relation) {
                (ElementKind::I, ir::Relation::Linear(e)) => (e, Rule::Positive("inertia")),
                (ElementKind::C, ir::Relation::Linear(e)) => (e, Rule::Positive("compliance")),
                (ElementKind::R, ir::Relation::Linear(e)) => (e, Rule::NonNegative),
                (ElementKind::TF | ElementKind::GY, ir::Relation::Modulus(e)) => (e, Rule::NonZero),
                _ => continue,
            };
            let leaf = |l: &ir::Expr| match l {
                ir::Expr::Param(i) => model
                    .params
                    .get(*i)
                    .map(|p| Expr::symbol(Symbol::param(p.name.as_str()))),
                _ => None,
            };
            let Ok(value) = from_ir(expr, &leaf) else {
                continue;
            };
            // Elements of one value share its node: its code and key are made once (a chain of 100,000 masses
            // has one inertia `m`).
            let made = match printed.get(&value) {
                Some(made) => made.clone(),
                None => {
                    let made = check_code(&value, field_of);
                    printed.insert(value.clone(), made.clone());
                    made
                }
            };
            let Some((first, first_field, code, code_key)) = made else {
                continue;
            };
            let key = (code_key, rule.key());
            if let Some(&k) = index.get(&key) {
                if let Some(check) = checks.get_mut(k) {
                    check.others += 1;
                }
                continue;
            }
            index.insert(key, checks.len());
            checks.push(ElementCheck {
                element: node.name.clone(),
                others: 0,
                text: to_text(&value),
                code,
                rule,
                param: first,
                field: first_field,
            });
        }
        checks
    }
}

impl Writer<'_> {
    /// The parameters the equations divide by that no element check already keeps away from zero (an inertia
    /// `m` or a compliance `1/k` must be positive, a modulus non-zero; a resistance may be 0), with how
    /// `validate` reads each.
    fn divisor_checks(&self, checks: &[ElementCheck]) -> Vec<(String, String)> {
        let eqs = &self.m.equations;
        let covered = |name: &str| {
            checks.iter().any(|c| {
                !matches!(c.rule, Rule::NonNegative)
                    && (c.text == name || c.text == format!("1/{name}"))
            })
        };
        eqs.divisor_params()
            .into_iter()
            .filter_map(|i| eqs.params.get(i).map(|(name, _)| name.clone()))
            .filter(|name| !covered(name))
            .map(|name| {
                let access = self.param_access(&name);
                (name, access)
            })
            .collect()
    }
}

/// A checked value's first parameter, that parameter's field, the value's code and the text that identifies it.
type CheckCode = (String, String, crate::symbolic::RustCode, String);

/// The [`CheckCode`] of `value`, read through `field_of`; `None` for a value without a parameter.
fn check_code(value: &Expr, field_of: &HashMap<String, String>) -> Option<CheckCode> {
    let first = value.free_symbols().into_iter().next()?;
    let first_field = field_of.get(first.name())?.clone();
    let code = to_rust_code(value, &|s| {
        field_of
            .get(s.name())
            .cloned()
            .unwrap_or_else(|| "f64::NAN".into())
    });
    let key = format!("{code:?}");
    Some((first.name().to_string(), first_field, code, key))
}

/// One check of `validate`: the value of `element` (and of `others` more elements with the same value and rule)
/// must satisfy `rule`; a failure names parameter `param` (read as `field`).
struct ElementCheck {
    element: String,
    others: usize,
    text: String,
    code: crate::symbolic::RustCode,
    rule: Rule,
    param: String,
    field: String,
}

impl Rule {
    /// What tells two rules apart, for finding equal checks.
    fn key(self) -> &'static str {
        match self {
            Rule::Positive(what) => what,
            Rule::NonNegative => "non-negative",
            Rule::NonZero => "non-zero",
        }
    }
}

/// "other element" or "other elements".
fn others(n: usize) -> &'static str {
    if n == 1 {
        "other element"
    } else {
        "other elements"
    }
}

/// The methods of the generated `Params`, its own and those of the traits it derives: a derived parameter is a
/// method too, so one of these names would clash (E0592) or shadow the trait's method.
pub(super) const PARAMS_METHODS: &[&str] = &[
    "get",
    "set",
    "validate",
    "default",
    "clone",
    "clone_from",
    "fmt",
    "eq",
    "ne",
];

/// The Rust name of parameter `name` in `Params` (a field when free, a method when derived), unique in `namer`.
pub(super) fn field_name(namer: &mut Namer, name: &str, derived: bool) -> String {
    if derived && PARAMS_METHODS.contains(&sanitize(name).as_str()) {
        // As a keyword gets a `_` suffix, so does a name the generated methods use.
        namer.ident(&format!("{name}_"))
    } else {
        namer.ident(name)
    }
}

/// Text from the model file made inert in a comment: the code points rustc refuses in comments (the deny-by-default
/// `text_direction_codepoint_in_comment` lint: bidirectional overrides and isolates) and other invisible controls
/// are written as `\u{…}`; a run of three backticks or tildes (which rustdoc would read as a code fence, and then
/// as a doctest) and a leading indent (an indented code block) are escaped.
pub(in crate::codegen) fn doc_safe(text: &str) -> String {
    let visible = visible(text.trim_start());
    let chars: Vec<char> = visible.chars().collect();
    let mut out = String::with_capacity(visible.len());
    let mut i = 0;
    while let Some(&c) = chars.get(i) {
        let mut j = i + 1;
        if c == '`' || c == '~' {
            while chars.get(j) == Some(&c) {
                j += 1;
            }
        }
        for _ in i..j {
            if j - i >= 3 {
                out.push('\\');
            }
            out.push(c);
        }
        i = j;
    }
    out
}

/// `text` with the code points rustc refuses in comments, and other invisible controls, written as `\\u{…}`.
pub(in crate::codegen) fn visible(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if invisible(c) {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        } else {
            out.push(c);
        }
    }
    out
}

/// A code fence of a model file's documentation as rustdoc should read it: an opening fence that rustdoc would take
/// for Rust (no language, `rust`, or only rustdoc's attributes such as `no_run`) becomes ```` ```text ````, so that
/// no example of the model file becomes a doctest of the user's crate; other languages (`bg`, `python`) stay.
pub(in crate::codegen) fn rustdoc_fence(line: &str, opening: bool) -> String {
    let (indent, fence) = line.split_at(line.len() - line.trim_start().len());
    let marks = fence.chars().take_while(|&c| c == '`').count();
    let info = fence[marks..].trim();
    const RUSTDOC: [&str; 8] = [
        "rust",
        "ignore",
        "no_run",
        "should_panic",
        "compile_fail",
        "test_harness",
        "standalone_crate",
        "allow_fail",
    ];
    let rust_like = info
        .split([',', ' '])
        .filter(|t| !t.is_empty())
        .all(|t| RUSTDOC.contains(&t) || t.starts_with("edition"));
    if opening && rust_like {
        format!("{indent}{}text", &fence[..marks])
    } else {
        visible(line)
    }
}

/// Prose from the model file made literal for rustdoc (after [`doc_safe`]): outside inline code, a `[`…`]` that is
/// not an inline link `[text](url)` and a `<` that does not open an autolink (`<https://…>`) are escaped, so that
/// `Mass [kg]` is not an unresolved intra-doc link and `<m>` not an unclosed HTML tag (both warnings, errors under
/// `RUSTDOCFLAGS=-D warnings`).
pub(in crate::codegen) fn rustdoc_literal(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len() + 8);
    let mut code_run = 0usize;
    let mut link_close = None;
    let mut i = 0;
    while let Some(&c) = chars.get(i) {
        match c {
            '\\' => {
                out.push(c);
                if let Some(&next) = chars.get(i + 1) {
                    out.push(next);
                    i += 1;
                }
            }
            '`' => {
                let run = chars[i..].iter().take_while(|&&b| b == '`').count();
                code_run = match code_run {
                    // A run that nothing closes is literal backticks, as in Markdown.
                    0 if closes_later(&chars[i + run..], run) => run,
                    0 => 0,
                    open if open == run => 0,
                    open => open,
                };
                out.extend(std::iter::repeat_n('`', run));
                i += run;
                continue;
            }
            _ if code_run > 0 => out.push(c),
            '[' => match inline_link_close(&chars, i) {
                Some(close) => {
                    link_close = Some(close);
                    out.push(c);
                }
                None => out.push_str("\\["),
            },
            ']' if link_close == Some(i) => {
                link_close = None;
                out.push(c);
            }
            ']' => out.push_str("\\]"),
            '<' if !opens_autolink(&chars[i + 1..]) => out.push_str("\\<"),
            _ => out.push(c),
        }
        i += 1;
    }
    out
}

/// Whether `rest` holds a run of exactly `run` backticks, which closes a code span opened by one.
fn closes_later(rest: &[char], run: usize) -> bool {
    rest.split(|&c| c != '`').any(|r| r.len() == run)
}

/// The index of the `]` that closes the `[` at `open` when the two make an inline link `[text](url)`.
fn inline_link_close(chars: &[char], open: usize) -> Option<usize> {
    let close = open
        + 1
        + chars[open + 1..]
            .iter()
            .position(|&c| c == ']' || c == '[')?;
    (chars[close] == ']' && chars.get(close + 1) == Some(&'(')).then_some(close)
}

/// Whether the text after a `<` is an autolink's scheme (`https://`, `mailto:`), which rustdoc renders as a link.
fn opens_autolink(rest: &[char]) -> bool {
    let head: String = rest.iter().take(8).collect();
    ["http://", "https://", "mailto:"]
        .iter()
        .any(|s| head.starts_with(s))
}

/// A code point that changes how text around it reads without showing itself.
fn invisible(c: char) -> bool {
    c.is_control() && c != ' '
        || matches!(
            c,
            '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}' | '\u{200E}' | '\u{200F}' | '\u{061C}' | '\u{2028}' | '\u{2029}'
        )
}
