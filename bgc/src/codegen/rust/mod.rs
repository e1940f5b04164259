//! The Rust module generated for a `.bg` file.
//!
//! [`generate`] prints, for each model of the file (at the top level of the module when the file has one model,
//! in a `pub mod <model>` each otherwise):
//! - sizes and names: `N_STATES` (energy states first, then integrated flows), `N_ENERGY_STATES`, `N_INPUTS`,
//!   `N_OUTPUTS`, `N_PARAMS`, `STATE_NAMES`, `INPUT_NAMES`, `OUTPUT_NAMES`, `PARAM_NAMES`; fixed-size `nalgebra`
//!   aliases `State`, `Inputs`, `Outputs`, `JacX`, `JacU`, `OutJacX`, `OutJacU`;
//! - `ParamError` and `Params` (one documented field per free parameter, `Default` from the file, `validate`,
//!   `get`, `set`; a derived parameter, defined from others in the file, is a method that follows them);
//! - `rhs`/`rhs_into` (`ẋ = f(t, x, u)`), `outputs`/`outputs_into` (`y = h(t, x, u)`) and the Jacobians
//!   `jac_x_into`, `jac_u_into`, `output_jac_x_into`, `output_jac_u_into` from symbolic derivatives; when a
//!   `JacX` takes more than 256 KiB (above 181 states) and no loop corrects it, also the triplets
//!   `JAC_X_NNZ`, `JAC_X_ROWS`, `JAC_X_COLS` and `jac_x_sparse_into`, which need no `N_STATES²` matrix (mass blocks'
//!   rows solved block by block, `sparse_jac.rs`);
//! - the parameter Jacobians `jac_p_into` (`JacP`, `N_STATES × N_PARAMS`) and `output_jac_p_into` (`OutJacP`,
//!   `N_OUTPUTS × N_PARAMS`): full matrices, a column per free parameter in `PARAM_NAMES` order, total through the
//!   derived parameters, with the loops' and mass matrices' contributions as in `jac_x_into`
//!   (`param_jacobians.rs`);
//! - for a linear model `state_space(&Params) -> (A, B, C, D)` whenever `bgc statespace` prints one (above 181
//!   states, where `A` takes more than 256 KiB, `state_space_entries(&Params, &mut dyn FnMut(char, usize, usize,
//!   f64))` instead, which passes each entry that is not identically zero and declares no matrix): in the energy
//!   states (type `EnergyStateSpace`), or, when the outputs or rates read an integrated flow (`var`), in all states,
//!   energy states then integrated flows (type `FullStateSpace`); a linear model whose algebraic loops are solved
//!   numerically has no symbolic one, and its `state_space` (up to 181 states) evaluates the Jacobians at the
//!   origin, which are its `A, B, C, D`; and, when the model declares coordinates,
//!   `state_space_declared` (type `DeclaredStateSpace`, sizes `N_COORDS`, names `COORD_NAMES`);
//! - `stored_energy`, `dissipated_power`, `supplied_power` when every term has a closed form;
//! - for a model with nonlinear algebraic loops, `N_TEARS`, `TEAR_NAMES`, `Tears`, `LoopFailure`, `LoopError` and
//!   `solve_loops(p, t, x, u) -> Result<Tears, LoopError>` (damped Newton's method per block, see
//!   `codegen::loops`); the functions above solve the loops first and give NaN where `solve_loops` fails;
//! - `Model` (the parameters, validated) and, with [`Options::runtime`], its implementations of
//!   `bgc_runtime::model::ContinuousModel`, `Parametric` and `bgc_runtime::fit::generated::ParamJacobians` (the columns
//!   of given parameter indices from `jac_p_into` or `output_jac_p_into`, for `Generated::exact`).
//!
//! Bodies of more than `parts::MAX_PART_STATEMENTS` independent statements are split into private parts (see
//! `parts`), and `validate` checks each distinct (element value, rule) once.
//!
//! # What the code needs
//! The functions of the model take fixed-size values, allocate nothing, never panic (indices are constants within
//! the fixed sizes) and use only `core`, `nalgebra` (which works without its default `std` feature) and the `libm`
//! crate for the elementary functions (see [`crate::symbolic::to_rust`]). With [`Options::runtime`] (the default)
//! `ParamError` is `bgc_runtime::model::ParamError` and `Model` implements the runtime's traits, so the including
//! crate depends on `bgc-runtime` (as `bgc_runtime`) too; without it the module defines its own `ParamError` and
//! builds in a `#![no_std]` crate.
//!
//! # Layout
//! The text is what `rustfmt --edition 2024` makes of it and no line is longer than 100 columns: statements too
//! long for a line bind parts of their expression to `let`s first (`codegen::layout`), comments and documentation
//! are wrapped (`codegen::format`), lists and signatures take `rustfmt`'s layout. Each statement of a body has the
//! equation it computes in a comment above it (and above the `let`s it needs). Two things can make a line longer:
//! the header, which holds the source path as given, and a single name or number wider than a line.
//!
//! # Lints
//! The code passes `clippy -D warnings` in the crate that includes it, whichever of its items that crate uses. An
//! unused argument is named `_x`. Every item carries `#[allow(dead_code)]` (as `prost` and `lalrpop` output do):
//! a binary crate that calls `rhs` but not `stored_energy` would otherwise get a warning for each item it leaves
//! unused, and its `-D warnings` build would fail. Beyond that only two lints are allowed, and only on the items
//! that need it: `non_snake_case` where a local name is the model's and not snake case (`J_m`), and
//! `clippy::approx_constant` where a number of the model (three or more significant digits) could be taken for a
//! rounded `π`, `e`, ...: the number is what the model file says. A comment at the top of the file says so.

mod calls;
mod chunks;
mod functions;
mod model;
pub(in crate::codegen) use functions::state_space_through_loops;
pub(crate) use model::MAX_CONSTANT_JACOBIAN_BYTES;
mod param_jacobians;
mod params;
mod parts;
mod scopes;
mod sparse_jac;
mod terms;

pub(super) use functions::{Draft, TearValues};

use super::emit::Plan;
use super::format::{self, Wrap};
use super::layout::MAX_WIDTH;
use super::names::{Namer, comment, string_literal};
use super::{CompiledFile, CompiledModel};
use crate::symbolic::{
    Expr, ExprMap, RUST_HELPER_FNS, RUST_HELPER_PREFIX, RustCode, Symbol, rust_helpers_used,
    to_rust_code,
};
use chunks::{AllowDeadCode, Chunks};
use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::fmt::Write;
use std::sync::Arc;

/// The version written into the header of generated files.
pub const BGC_VERSION: &str = env!("CARGO_PKG_VERSION");

/// What a generated module contains besides the model's own functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Implement `bgc_runtime::model::ContinuousModel` and `Parametric` for `Model`, and use the runtime's
    /// `ParamError` (default). Without them the module needs only `core`, `nalgebra` and `libm`.
    pub runtime: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options { runtime: true }
    }
}

/// The first line of a generated file: `// @generated by bgc <version> from <file> (fnv1a64 <hash>)`.
pub fn header(source_name: &str, hash: u64) -> String {
    format!(
        "// @generated by bgc {BGC_VERSION} from {} (fnv1a64 {hash:016x})",
        params::doc_safe(&comment(source_name))
    )
}

/// The Rust module of a compiled file with the default [`Options`]; `source_name` names the file in the header.
pub fn generate(file: &CompiledFile, source_name: &str) -> String {
    generate_with(file, source_name, Options::default())
}

/// The Rust module of a compiled file; `source_name` names the file in the header.
pub fn generate_with(file: &CompiledFile, source_name: &str, options: Options) -> String {
    let mut out = String::new();
    generate_into(file, source_name, options, &mut |text| out.push_str(text));
    out
}

/// Writes the Rust module of a compiled file (the text of [`generate_with`], byte for byte) to `out` as it is
/// produced, without holding the whole module in memory a second time. A failed write is returned (the first
/// one; nothing is written after it, though the module is still generated to its end).
pub fn write_with(
    file: &CompiledFile,
    source_name: &str,
    options: Options,
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let mut result = Ok(());
    generate_into(file, source_name, options, &mut |text| {
        if result.is_ok() {
            result = out.write_all(text.as_bytes());
        }
    });
    result
}

/// The text of the module, handed to `out` piece by piece in order.
fn generate_into(
    file: &CompiledFile,
    source_name: &str,
    options: Options,
    out: &mut dyn FnMut(&str),
) {
    let mut head = header(source_name, file.hash);
    head.push_str(
        "\n// Do not edit: this file is regenerated from the .bg source when it changes.\n",
    );
    for line in format::comment(
        0,
        "//",
        "Allowed lints: `dead_code` on every item (the including crate may use only some of them), \
         `non_snake_case` where local names are the model's (`J_m`), `clippy::approx_constant` where a number \
         of the model, as written or folded (`2*pi`), looks like one of `core::f64::consts` (the number is the \
         model's).",
        Wrap::Prose,
        MAX_WIDTH,
    ) {
        head.push_str(&line);
        head.push('\n');
    }
    out(&head);
    match file.models.as_slice() {
        [single] => {
            out("\n");
            // The lines joined by `\n`, and one after the last when the code ends with it.
            let mut first = true;
            let ends_with_newline = model_code_into(single, options, 0, &mut |line| {
                if !std::mem::take(&mut first) {
                    out("\n");
                }
                out(line);
            });
            if ends_with_newline {
                out("\n");
            }
        }
        many => {
            let mut namer = Namer::with_reserved();
            for m in many {
                let name = namer.ident(&m.model.name);
                let mut open = format!(
                    "\n/// The generated code of model `{}`.\n",
                    comment(&m.model.name)
                );
                if !format::is_snake_case(&name) {
                    open.push_str("#[allow(non_snake_case)]\n");
                }
                let _ = writeln!(open, "pub mod {name} {{");
                out(&open);
                let mut indented = String::new();
                model_code_into(m, options, 4, &mut |line| {
                    indented.clear();
                    if !line.is_empty() {
                        indented.push_str("    ");
                        indented.push_str(line);
                    }
                    indented.push('\n');
                    out(&indented);
                });
                out("}\n");
            }
        }
    }
}

/// Hands the lines of the code of one model (items at the top level), for lines of `MAX_WIDTH - base_indent`
/// columns, to `line`; returns whether the code ends with a line break.
fn model_code_into(
    m: &CompiledModel,
    options: Options,
    base_indent: usize,
    line: &mut dyn FnMut(&str),
) -> bool {
    let width = MAX_WIDTH - base_indent;
    Writer::new(m, &m.plan, options, width).write_into(line)
}

/// The item keywords that start a line of a model's code at the top level.
pub(in crate::codegen) const ITEM_STARTS: &[&str] = &[
    "pub const ",
    "pub static ",
    "pub type ",
    "pub fn ",
    "pub struct ",
    "pub enum ",
    "const ",
    "static ",
    "type ",
    "fn ",
    "struct ",
    "enum ",
    "impl ",
    "impl<",
];

fn rust_f64(v: f64) -> String {
    if v.is_nan() {
        "f64::NAN".into()
    } else if v.is_infinite() {
        if v > 0.0 {
            "f64::INFINITY"
        } else {
            "f64::NEG_INFINITY"
        }
        .into()
    } else {
        format!("{v:?}")
    }
}

/// An argument of a generated function: its name (prefixed with `_` when the body does not use it) and type.
struct Arg {
    name: &'static str,
    ty: &'static str,
    used: bool,
}

impl Arg {
    fn new(name: &'static str, ty: &'static str, used: bool) -> Arg {
        Arg { name, ty, used }
    }

    fn text(&self) -> String {
        let underscore = if self.used { "" } else { "_" };
        format!("{underscore}{}: {}", self.name, self.ty)
    }
}

/// A generated function: documentation, signature and body (lines indented by four spaces).
struct Function {
    doc: String,
    name: String,
    args: Vec<Arg>,
    /// ` -> Type`, or nothing.
    ret: String,
    body: String,
    /// The local names the body binds (for `non_snake_case`).
    locals: Vec<String>,
    /// Marked `#[inline]`: the functions behind `Model`'s methods, so that a caller in another crate (the
    /// runtime's integrators and filters are generic over the model) can inline the model into its loop.
    inline: bool,
}

/// Which of the model function's arguments a body uses.
#[derive(Clone, Copy, Debug, Default)]
pub(in crate::codegen) struct Uses {
    pub(in crate::codegen) p: bool,
    pub(in crate::codegen) t: bool,
    pub(in crate::codegen) x: bool,
    pub(in crate::codegen) u: bool,
}

pub(in crate::codegen) struct Writer<'a> {
    m: &'a CompiledModel,
    pub(in crate::codegen) plan: &'a Plan,
    options: Options,
    /// Rust text of each symbol inside a model function (`p.J_m`, `p_rotor`, `t`); shared with [`Writer::fork`]s.
    names: Arc<HashMap<Symbol, String>>,
    /// Where each state and input is read from: `(0, i)` for `x[i]`, `(1, i)` for `u[i]`.
    positions: Arc<HashMap<Symbol, (u8, usize)>>,
    /// Every local name of the model functions taken (states, inputs, intermediates); cloned for each function.
    namer: Namer,
    /// Field names of the free parameters, in parameter order (the fields of `Params`).
    fields: Vec<String>,
    /// Indices (in the model's parameter list) of the free parameters, matching `fields`.
    free: Vec<usize>,
    /// Rust name of every parameter (a field, or the method of a derived parameter), in parameter order.
    all_fields: Vec<String>,
    /// The columns of a line.
    pub(in crate::codegen) width: usize,
    /// The Jacobians whose bodies read neither `t`, `x` nor `u` (those of a linear model): `Model` computes them
    /// once per parameter set.
    constant_jacobians: Vec<model::ConstantJacobian>,
    /// The parameter-only subexpressions of the bodies that take `c: &ParamTerms` ([`terms`]), found while
    /// they are written.
    terms: RefCell<terms::ParamTerms>,
    /// The functions written as `{name}_with(p, c, ...)` and a `{name}` that computes `c` (`rhs_into`).
    with_terms: Vec<String>,
    /// Whether the bodies read parameter terms: not when there would be more than `MAX_LETS` of them (a large
    /// model), which `ParamTerms::at` could not bind.
    terms_enabled: bool,
    /// Printed forms of expressions met before: a large model's Jacobians repeat a few entries thousands of times.
    printed: RefCell<Printed>,
    pub(in crate::codegen) out: Chunks,
}

/// The largest expression, in nodes written out as a tree (shared parts counted each time), that a comment in
/// the generated code shows: a rate from the symbolic elimination of derivative causality, or from loops solved
/// in closed form one inside another, can take tens of kilobytes written out (a tree can be far larger than the
/// shared form the code computes), and a comment that long helps no reader.
const MAX_COMMENT_NODES: usize = 2_000;

/// Memo of [`Writer::code`] and the text of equation comments, keyed by expression (a node, so lookups are by
/// identity). Both are pure functions of the expression for one writer. Cleared when full, to bound its memory.
#[derive(Default)]
struct Printed {
    code: ExprMap<RustCode>,
    text: ExprMap<String>,
}

impl Printed {
    const CAPACITY: usize = 4096;

    fn get_or<T: Clone>(map: &mut ExprMap<T>, e: &Expr, make: impl FnOnce() -> T) -> T {
        if let Some(v) = map.get(e) {
            return v.clone();
        }
        let v = make();
        if map.len() >= Self::CAPACITY {
            map.clear();
        }
        map.insert(e.clone(), v.clone());
        v
    }
}

impl<'a> Writer<'a> {
    fn new(m: &'a CompiledModel, plan: &'a Plan, options: Options, width: usize) -> Writer<'a> {
        let eqs = &m.equations;
        let derived = |k: usize| eqs.derived.get(k).is_some_and(Option::is_some);
        let mut field_namer = Namer::default();
        let all_fields: Vec<String> = eqs
            .params
            .iter()
            .enumerate()
            .map(|(k, p)| params::field_name(&mut field_namer, &p.0, derived(k)))
            .collect();
        let free: Vec<usize> = (0..eqs.params.len()).filter(|&k| !derived(k)).collect();
        let fields: Vec<String> = free
            .iter()
            .filter_map(|&k| all_fields.get(k).cloned())
            .collect();
        let mut names = HashMap::new();
        let derived_symbols: HashSet<Symbol> = (0..eqs.params.len())
            .filter(|&k| derived(k))
            .filter_map(|k| eqs.params.get(k).map(|p| Symbol::param(p.0.as_str())))
            .collect();
        for (k, (p, field)) in eqs.params.iter().zip(&all_fields).enumerate() {
            let access = if derived(k) {
                format!("p.{field}()")
            } else {
                format!("p.{field}")
            };
            names.insert(Symbol::param(p.0.as_str()), access);
        }
        let mut namer = Namer::with_reserved();
        for s in plan.states.iter().chain(&plan.inputs) {
            names.insert(s.clone(), namer.ident(s.name()));
        }
        for i in &eqs.intermediates {
            names.insert(Symbol::intermediate(i.name.as_str()), namer.ident(&i.name));
        }
        for s in plan.loops.iter().flat_map(|l| &l.tears) {
            names.insert(s.clone(), namer.ident(s.name()));
        }
        for (s, _) in plan.shared.values().flatten() {
            names.insert(s.clone(), namer.ident(s.name()));
        }
        // An output that reads an earlier one (in the readable outputs) reads it from `y`, written before.
        for (k, o) in eqs.outputs.iter().enumerate() {
            names.insert(Symbol::output(o.name.as_str()), format!("y[{k}]"));
        }
        names.insert(Symbol::time(), "t".into());
        let namer = namer.frozen();
        let positions: HashMap<Symbol, (u8, usize)> = (plan
            .states
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), (0, i))))
        .chain(
            plan.inputs
                .iter()
                .enumerate()
                .map(|(i, s)| (s.clone(), (1, i))),
        )
        .collect();
        Writer {
            positions: Arc::new(positions),
            m,
            plan,
            options,
            names: Arc::new(names),
            namer,
            fields,
            free,
            all_fields,
            width,
            constant_jacobians: Vec::new(),
            terms: RefCell::new(terms::ParamTerms::new(derived_symbols)),
            with_terms: Vec::new(),
            terms_enabled: false,
            printed: RefCell::default(),
            out: Chunks::default(),
        }
    }

    /// A writer of the same model with its own text, caches and records, for drafting bodies on another thread:
    /// it reads parameter terms from `terms` (which must rewrite every expression it drafts to what `self` would).
    fn fork(&self, terms: terms::ParamTerms) -> Writer<'a> {
        Writer {
            m: self.m,
            plan: self.plan,
            options: self.options,
            names: Arc::clone(&self.names),
            positions: Arc::clone(&self.positions),
            namer: self.namer.clone(),
            fields: self.fields.clone(),
            free: self.free.clone(),
            all_fields: self.all_fields.clone(),
            width: self.width,
            constant_jacobians: Vec::new(),
            terms: RefCell::new(terms),
            with_terms: Vec::new(),
            terms_enabled: self.terms_enabled,
            printed: RefCell::default(),
            out: Chunks::default(),
        }
    }

    /// The name of `s` inside a model function.
    pub(in crate::codegen) fn name(&self, s: &Symbol) -> String {
        if let Some(field) = terms::term_field(s) {
            return format!("c.{field}");
        }
        self.names.get(s).cloned().unwrap_or_else(|| {
            format!(
                "compile_error!({})",
                string_literal(&format!("bgc: no name for `{}`", s.name()))
            )
        })
    }

    fn code(&self, e: &Expr) -> RustCode {
        let mut printed = self.printed.borrow_mut();
        Printed::get_or(&mut printed.code, e, || to_rust_code(e, &|s| self.name(s)))
    }

    /// Wrapped documentation lines `{indent}/// text`; the text is made inert for rustdoc and rustc
    /// ([`params::doc_safe`], [`params::rustdoc_literal`]).
    pub(in crate::codegen) fn doc(&mut self, indent: usize, text: &str) {
        let text = params::rustdoc_literal(&params::doc_safe(text));
        for line in format::comment(indent, "///", &text, Wrap::Prose, self.width) {
            self.out.push_str(&line);
            self.out.push('\n');
        }
    }

    /// Documentation lines of the model file (of the model or of a parameter), as wrapped paragraphs.
    fn doc_lines(&mut self, indent: usize, lines: &[String]) {
        let mut in_code = false;
        for (text, verbatim) in format::paragraphs(lines) {
            if verbatim {
                let text = if text.trim_start().starts_with("```") {
                    in_code = !in_code;
                    params::rustdoc_fence(&text, in_code)
                } else {
                    params::visible(&text)
                };
                let pad = " ".repeat(indent);
                let space = if text.is_empty() { "" } else { " " };
                let _ = writeln!(self.out, "{pad}///{space}{text}");
            } else {
                self.doc(indent, &text);
            }
        }
    }

    /// Wrapped comment lines `{indent}// text`.
    fn note(&mut self, indent: usize, text: &str) {
        let text = params::doc_safe(text);
        for line in format::comment(indent, "//", &text, Wrap::Prose, self.width) {
            self.out.push_str(&line);
            self.out.push('\n');
        }
    }

    /// The equation `{label}{e}` (`d/dt x = ...`) as comment lines above a statement of a function body; an
    /// expression of more than [`MAX_COMMENT_NODES`] nodes written out is named by its size instead.
    fn equation(&self, indent: usize, label: &str, e: &Expr) -> Vec<String> {
        let nodes = e.node_count();
        if nodes > MAX_COMMENT_NODES {
            let size = if nodes == usize::MAX {
                "too many".to_string()
            } else {
                nodes.to_string()
            };
            let text = format!(
                "{label}(an expression of {size} nodes when written out, not repeated here: `bgc equations` \
                 prints it with named intermediates)"
            );
            return format::comment(indent, "//", &text, Wrap::Prose, self.width);
        }
        let text = {
            let mut printed = self.printed.borrow_mut();
            Printed::get_or(&mut printed.text, e, || crate::symbolic::to_text(e))
        };
        let text = format!("{label}{text}");
        format::comment(indent, "//", &text, Wrap::Equation, self.width)
    }

    /// The allow attribute `code` needs (see the module docs), or nothing.
    fn allows(locals: &[String], code: &str) -> Option<String> {
        let mut lints = Vec::new();
        if locals.iter().any(|l| !format::is_snake_case(l)) {
            lints.push("non_snake_case");
        }
        if format::may_look_like_a_constant(code) {
            lints.push("clippy::approx_constant");
        }
        (!lints.is_empty()).then(|| format!("#[allow({})]", lints.join(", ")))
    }

    fn function(&mut self, f: Function) {
        let inline = if f.inline { Some("#[inline]") } else { None };
        self.write_function(f, inline, "pub fn");
    }

    /// Writes `f` with the attribute `inline` (instead of `f.inline`'s) as `{keyword} name(...)`.
    fn write_function(&mut self, f: Function, inline: Option<&str>, keyword: &str) {
        self.out.push('\n');
        self.doc(0, &f.doc);
        if let Some(attr) = Self::allows(&f.locals, &f.body) {
            self.out.push_str(&attr);
            self.out.push('\n');
        }
        if let Some(inline) = inline {
            self.out.push_str(inline);
            self.out.push('\n');
        }
        let args: Vec<String> = f.args.iter().map(Arg::text).collect();
        let sig = format::signature(
            0,
            &format!("{keyword} {}", f.name),
            &args,
            &f.ret,
            f.body.is_empty(),
            self.width,
        );
        self.out.push_str(&sig);
        self.out.push('\n');
        if !f.body.is_empty() {
            self.out
                .push_str(&scopes::flatten_lets(&f.body, "    ", self.width));
            self.out.push_str("}\n");
        }
    }

    /// Writes the model's items and hands their lines to `out`, each item allowed `dead_code`, the prelude (imports
    /// and the helper functions it calls) first; returns whether the text ends with a line break.
    fn write_into(mut self, out: &mut dyn FnMut(&str)) -> bool {
        self.sizes();
        self.params();
        self.functions();
        self.param_terms_struct();
        self.model();
        let mut solvers = String::new();
        let helpers = rust_helpers_used(&self.helper_calls());
        if !helpers.is_empty() {
            solvers.push('\n');
            solvers.push_str(helpers.trim_end());
            solvers.push('\n');
        }
        if !self.plan.mass.is_empty() || self.plan.loops.is_some() {
            solvers.push_str(super::mass::SOLVE_FN);
        }
        if !self.plan.mass.is_empty() {
            solvers.push_str(super::mass::SOLVE_ROWS_FN);
        }
        if self.plan.loops.is_some() {
            solvers.push_str(super::loops::NEWTON_FN);
            solvers.push_str(super::loops_dogleg::DOGLEG_FN);
        }
        // With the runtime, its re-exports: the user's crate then needs neither nalgebra nor libm, nor to match
        // their versions (a second nalgebra makes every signature "a different `Matrix`").
        let mut prelude = String::new();
        if self.options.runtime {
            if calls_libm(solvers.lines()) || calls_libm(self.out.lines()) {
                prelude.push_str("use bgc_runtime::libm;\n");
            }
            prelude.push_str("use bgc_runtime::nalgebra::{SMatrix, SVector};\n");
        } else {
            prelude.push_str("use nalgebra::{SMatrix, SVector};\n");
        }
        prelude.push_str(&solvers);
        // Every piece of the prelude ends its last line, so its lines and the items' lines are those of the two
        // texts joined.
        let ends_with_newline =
            self.out.ends_with('\n') || (self.out.is_empty() && prelude.ends_with('\n'));
        let items = std::mem::take(&mut self.out);
        // The writer's tables go before the items are handed on: only the text is still needed.
        drop(self);
        let mut lines = AllowDeadCode::new(out);
        prelude.lines().for_each(|l| lines.line(l));
        items.into_lines(&mut |l| lines.line(l));
        lines.finish();
        ends_with_newline
    }

    /// The lines of code (not comments or documentation, which quote the model's text) that may call a helper.
    fn helper_calls(&self) -> String {
        let mut code = String::new();
        for line in self.out.lines().filter(|l| {
            l.contains(RUST_HELPER_PREFIX)
                && RUST_HELPER_FNS.iter().any(|h| l.contains(h))
                && !l.trim_start().starts_with("//")
        }) {
            code.push_str(line);
            code.push('\n');
        }
        code
    }
}

/// The outputs' names, in output order.
fn output_names(eqs: &crate::equations::Equations) -> Vec<String> {
    eqs.outputs.iter().map(|o| o.name.clone()).collect()
}

/// Whether a line of code (not a comment, which may quote anything) of `lines` calls `libm`.
fn calls_libm<'a>(mut lines: impl Iterator<Item = &'a str>) -> bool {
    lines.any(|l| l.contains("libm::") && !l.trim_start().starts_with("//"))
}
