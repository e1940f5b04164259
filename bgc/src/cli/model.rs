//! `bgc equations` and `bgc statespace`: the equations stage and the linear state space of one model.

use super::commands::{Loaded, count_line, load_one};
use super::io::{keep_until_exit, stderr, stderrln, stdout, stdoutln};
use super::matrix_text;
use super::params::{Assignment, name_list, param_values, values_or_zero};
use super::quantities::{self, Declared};
use super::sparse;
use super::{Coords, EquationsFormat, ReportFormat, Status};
use bgc::diagnostic::{has_errors, render};
use bgc::equations::symbols::{self, Sym};
use bgc::equations::{self, CoordsError, Equations, Jacobians, LinearError, NumericStateSpace};
use bgc::symbolic::Expr;
use serde_json::{Value, json};
use std::path::Path;

/// A model through the front end, causality and the equations stage.
pub(super) struct Derived {
    pub loaded: Loaded,
    pub eqs: Equations,
}

/// Loads `path`, picks the model and derives its equations. Diagnostics are printed; with `strict`, an error
/// among them ends the command (status 1).
pub(super) fn derive_one(
    path: &Path,
    wanted: Option<&str>,
    color: bool,
    strict: bool,
) -> Result<(Derived, bool), Status> {
    let loaded = load_one(path, wanted, color)?;
    let (causality, mut diags) = bgc::causality::analyse(&loaded.model);
    let (eqs, eq_diags) = equations::derive(&loaded.model, &causality);
    diags.extend(eq_diags);
    bgc::lower::add_instance_context(&loaded.model, &mut diags);
    let mut all = loaded.diags.clone();
    all.extend(diags);
    stderr(&render::to_text(&loaded.sources, &all, color));
    let failed = has_errors(&all);
    if failed {
        stderrln(&count_line(&all));
        if strict {
            return Err(Status::InputErrors);
        }
    }
    Ok((Derived { loaded, eqs }, failed))
}

/// `bgc equations FILE`
pub fn equations(
    path: &Path,
    wanted: Option<&str>,
    format: EquationsFormat,
    color: bool,
) -> Status {
    // The equations are printed even when some could not be derived: the diagnostics say which are missing.
    let (d, failed) = match derive_one(path, wanted, color, false) {
        Ok(x) => x,
        Err(s) => return s,
    };
    match format {
        EquationsFormat::Text => stdout(&equations::to_text(&d.eqs)),
        EquationsFormat::Latex => stdout(&equations::to_latex(&d.eqs)),
        EquationsFormat::Json => stdoutln(
            &serde_json::to_string_pretty(&equations::to_json(&d.eqs))
                .unwrap_or_else(|_| "{}".into()),
        ),
    }
    keep_until_exit(d);
    if failed {
        Status::InputErrors
    } else {
        Status::Ok
    }
}

/// The options of `bgc statespace`.
pub struct StateSpaceArgs<'a> {
    pub params: &'a [Assignment],
    pub coords: Coords,
    pub symbolic: bool,
    pub format: ReportFormat,
    pub at: &'a [Assignment],
    /// Print the effective parameter values and the operating point on standard error.
    pub verbose: bool,
    /// Coordinate triplets of the nonzero entries instead of dense rows.
    pub sparse: bool,
}

/// `bgc statespace FILE`
pub fn statespace(
    path: &Path,
    wanted: Option<&str>,
    args: &StateSpaceArgs<'_>,
    color: bool,
) -> Status {
    let (d, _) = match derive_one(path, wanted, color, true) {
        Ok(x) => x,
        Err(s) => return s,
    };
    let result = state_space(&d, args);
    keep_until_exit(d);
    match result {
        Ok(v) => {
            match (args.format, args.sparse) {
                (ReportFormat::Json, false) => stdout(&json_rows(&v)),
                (ReportFormat::Text, false) => stdout(&text(&v)),
                (ReportFormat::Json, true) => stdout(&sparse::json(&v)),
                (ReportFormat::Text, true) => stdout(&sparse::text(&v)),
            }
            Status::Ok
        }
        Err(msg) => {
            stderrln(&format!("error: {msg}"));
            Status::InputErrors
        }
    }
}

fn state_space(d: &Derived, args: &StateSpaceArgs<'_>) -> Result<Value, String> {
    let eqs = &d.eqs;
    let params = param_values(&d.loaded.model, &d.eqs, args.params)?;
    if args.verbose {
        stderr(&quantities::describe_params(
            &d.loaded.model,
            eqs,
            &params,
            args.params,
        ));
    }
    match args.coords {
        Coords::Energy => energy_coords(&d.loaded.model, eqs, &params, args),
        Coords::Declared => {
            if !args.at.is_empty() {
                return Err("--at applies to the energy coordinates only; the declared coordinates are defined for linear models".into());
            }
            let declared = |e: CoordsError| match e {
                CoordsError::Linear(
                    l @ (LinearError::NotLinear { .. }
                    | LinearError::TimeVarying { .. }
                    | LinearError::Affine { .. }),
                ) => format!(
                    "the state space in declared coordinates needs a linear model: {l}; use --coords energy with --at"
                ),
                other => format!("no state space in declared coordinates: {other}"),
            };
            if args.symbolic {
                let j = equations::declared_state_space_symbolic(eqs).map_err(declared)?;
                symbolic_json(eqs, &j, &fixed_params(eqs, args.params, &params))
            } else {
                // The exact elimination, evaluated at the parameters, keeps structural zeros exactly zero; the
                // numeric path (null spaces by floating-point elimination) leaves rounding residue such as 5e-11
                // in them, so it serves only when the symbolic form is refused.
                let exact = equations::declared_state_space_symbolic(eqs)
                    .ok()
                    .and_then(|j| {
                        let (x0, u0) = (vec![0.0; j.states.len()], vec![0.0; eqs.inputs.len()]);
                        equations::evaluate_at(eqs, &j, &params, &x0, &u0, 0.0).ok()
                    });
                let ss = match exact {
                    Some(ss) => ss,
                    None => equations::declared_state_space(eqs, &params).map_err(declared)?,
                };
                Ok(numeric_json(&ss))
            }
        }
    }
}

/// The state space in the energy variables: exact for a linear model, the linearisation at `--at` otherwise. When
/// the rates need an integrated flow (an angle in a modulated transformer), the integrated flows join the state.
fn energy_coords(
    model: &bgc::ir::Model,
    eqs: &Equations,
    params: &[f64],
    args: &StateSpaceArgs<'_>,
) -> Result<Value, String> {
    // The rates and outputs converted once; a large model (or one whose outputs, inlined, would be huge trees) is
    // differentiated and evaluated sparse, a small one by the dense path as always.
    let rows = equations::ModelRows::new(eqs);
    let selection = equations::state_selection(eqs, &rows);
    let n = eqs.state_count(selection);
    let state_names: Vec<String> = (0..n).map(|i| eqs.sym_name(Sym::State(i))).collect();
    let (x0, u0) = operating_point(model, eqs, &state_names, args.at, args.verbose)?;
    if !args.sparse || args.symbolic {
        dense_fits(n, args.symbolic)?;
    }
    let linear = match equations::sparse_linear_state_space(eqs, &rows, selection) {
        Ok(j) => Ok(j),
        Err(
            e @ (LinearError::NotLinear { .. }
            | LinearError::TimeVarying { .. }
            | LinearError::Affine { .. }
            | LinearError::MassMatrix { .. }),
        ) => Err(e),
        Err(e) => return Err(format!("no state space: {e}")),
    };
    // Without a point: a signal of time on numerically solved loops is refused as it is in a rate, and a linear
    // model whose loops are solved numerically is linearised at the origin, exactly its state space.
    if let Err(why) = &linear
        && args.at.is_empty()
    {
        if let Some(e) = equations::time_in_loops(eqs) {
            return Err(format!("no state space: {e}"));
        }
        if !equations::linear_through_loops(eqs, selection) {
            let names = format!(
                "states: {}; inputs: {}; those not given are 0",
                name_list(&state_names),
                name_list(&eqs.inputs)
            );
            return Err(match why {
                LinearError::TimeVarying { .. } => {
                    format!("no state space: {why} (--at NAME=VALUE,...; {names})")
                }
                _ => format!(
                    "the model is not linear ({why}): give an operating point with --at NAME=VALUE,... ({names})"
                ),
            });
        }
    }
    let fixed = fixed_params(eqs, args.params, params);
    if args.symbolic {
        if let Err(e @ LinearError::MassMatrix { .. }) = &linear {
            return Err(format!("no symbolic state space: {e}"));
        }
        let j = match linear {
            Ok(_) => equations::linear_state_space(eqs, selection).map_err(|e| e.to_string())?,
            Err(_) => {
                let j = equations::jacobians(eqs, selection).map_err(|e| e.to_string())?;
                at_point(&j, &x0, &u0)
            }
        };
        return symbolic_json(eqs, &j, &fixed);
    }
    let no_state_space = |e: LinearError| format!("no state space: {e}");
    // A large model is linearised sparse, its mass-matrix rows and algebraic loops included.
    if !equations::dense_is_cheap(eqs, &rows) {
        let ss = match linear {
            Ok(j) => equations::evaluate_sparse(eqs, &j, params, &x0, &u0, 0.0),
            Err(_) => equations::linearise_sparse(eqs, &rows, selection, (params, &x0, &u0, 0.0)),
        }
        .map_err(no_state_space)?;
        return Ok(if args.sparse {
            sparse::numeric_triplets(&ss)
        } else {
            numeric_json(&ss.to_dense())
        });
    }
    let ss = match linear {
        Ok(_) => equations::linear_state_space(eqs, selection)
            .and_then(|j| equations::evaluate_at(eqs, &j, params, &x0, &u0, 0.0)),
        Err(_) => equations::linearise(eqs, selection, params, &x0, &u0, 0.0),
    }
    .map_err(no_state_space)?;
    Ok(numeric_json(&ss))
}

/// The most states a dense state space is printed for: `A` then has 16 million entries (some 300 MB of JSON), and
/// a larger one would exhaust memory before it is printed.
const MAX_DENSE_STATES: usize = 4_000;

/// Refuses dense matrices for a model too large for them, before any are formed.
fn dense_fits(states: usize, symbolic: bool) -> Result<(), String> {
    if states <= MAX_DENSE_STATES {
        return Ok(());
    }
    let entries = states as f64 * states as f64;
    Err(if symbolic {
        format!(
            "the model has {states} states: its symbolic A would have {entries:.1e} entries, more than the \
             {MAX_DENSE_STATES}² printed densely; use --sparse without --symbolic for the non-zero entries at the \
             parameters' values"
        )
    } else {
        format!(
            "the model has {states} states: its dense A would have {entries:.1e} entries, more than the \
             {MAX_DENSE_STATES}² printed densely; use --sparse for the non-zero entries as coordinate triplets"
        )
    })
}

/// The operating point from `--at`: state values and input values by name (each in its unit: see
/// [`super::quantities`]), 0 for those not given.
fn operating_point(
    model: &bgc::ir::Model,
    eqs: &Equations,
    state_names: &[String],
    at: &[Assignment],
    verbose: bool,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let all_states = quantities::states(model, eqs);
    // By name, so that a model of many states is not searched once per state.
    let by_name: std::collections::HashMap<&str, &Declared> =
        all_states.iter().map(|d| (d.name.as_str(), d)).collect();
    let mut declared: Vec<Declared> = state_names
        .iter()
        .map(|n| {
            by_name
                .get(n.as_str())
                .map(|d| (*d).clone())
                .unwrap_or(Declared {
                    name: n.clone(),
                    unit: bgc::units::Unit::ONE,
                    text: "1".into(),
                })
        })
        .collect();
    declared.extend(quantities::inputs(model));
    if let Some(a) = at
        .iter()
        .find(|a| by_name.contains_key(a.name.as_str()) && !state_names.contains(&a.name))
    {
        return Err(format!(
            "`{}` is an integrated flow (`var`) that neither the rates nor the outputs read, so it is no state \
             of this state space and the linearisation does not depend on it: leave it out of --at",
            a.name
        ));
    }
    let values = values_or_zero("state or input", "--at", &declared, at)?;
    if verbose {
        stderr(&quantities::describe_values(
            "operating point",
            &declared,
            &values,
            at,
        ));
    }
    let (xs, us) = values.split_at(state_names.len().min(values.len()));
    Ok((xs.to_vec(), us.to_vec()))
}

/// The Jacobians with the operating point put in for the states, inputs and time.
fn at_point(j: &Jacobians, x0: &[f64], u0: &[f64]) -> Jacobians {
    let put = |m: &[Vec<Expr>]| -> Vec<Vec<Expr>> {
        m.iter()
            .map(|row| {
                row.iter()
                    .map(|e| {
                        symbols::subst(e, &mut |s| match s {
                            Sym::State(i) => x0.get(i).map(|v| symbols::num(*v)),
                            Sym::Input(i) => u0.get(i).map(|v| symbols::num(*v)),
                            Sym::Time => Some(Expr::zero()),
                            _ => None,
                        })
                    })
                    .collect()
            })
            .collect()
    };
    Jacobians {
        states: j.states.clone(),
        inputs: j.inputs.clone(),
        outputs: j.outputs.clone(),
        dfdx: put(&j.dfdx),
        dfdu: put(&j.dfdu),
        dhdx: put(&j.dhdx),
        dhdu: put(&j.dhdu),
    }
}

/// The parameters given with `--param`, to put into symbolic entries as numbers.
fn fixed_params(eqs: &Equations, given: &[Assignment], values: &[f64]) -> Vec<Option<f64>> {
    eqs.params
        .iter()
        .enumerate()
        .map(|(i, (name, _))| {
            given
                .iter()
                .any(|a| a.name == *name)
                .then(|| values.get(i).copied())
                .flatten()
        })
        .collect()
}

/// `e` in the free parameters: those given with `--param` as numbers, and each derived parameter replaced by its
/// expression, so that an instance parameter set by an override (`dc_motor mot(R_a = R)`) reads as the user's `R`,
/// not as `mot.R_a`.
fn in_free_params(eqs: &Equations, e: &Expr, fixed: &[Option<f64>]) -> Expr {
    // Derived parameters refer only to earlier ones, so the substitution ends; the bound guards a malformed table.
    let mut e = e.clone();
    for _ in 0..=eqs.params.len() {
        let mut changed = false;
        e = symbols::subst(&e, &mut |s| match s {
            Sym::Param(i) => match (fixed.get(i).copied().flatten(), eqs.derived.get(i)) {
                (Some(v), _) => {
                    changed = true;
                    Some(symbols::num(v))
                }
                (None, Some(Some(d))) => {
                    changed = true;
                    Some(d.clone())
                }
                _ => None,
            },
            _ => None,
        });
        if !changed {
            break;
        }
    }
    e
}

/// The symbolic state space as text. An entry holding a number that is not finite (parameters given with `--param`
/// whose product overflows, `1e308 / 1e-308`, or a division by an expression that is zero by structure) is
/// refused: printed, `-inf` would read as a coefficient.
fn symbolic_json(eqs: &Equations, j: &Jacobians, fixed: &[Option<f64>]) -> Result<Value, String> {
    let render = |name: &str, m: &[Vec<Expr>]| -> Result<Vec<Vec<String>>, String> {
        let entries: Vec<Expr> = m
            .iter()
            .flatten()
            .map(|e| in_free_params(eqs, e, fixed))
            .collect();
        let mut held = Expr::non_finite_constants(&entries).into_iter();
        for (r, row) in m.iter().enumerate() {
            for (c, v) in held.by_ref().take(row.len()).enumerate() {
                if let Some(v) = v {
                    return Err(format!(
                        "no symbolic state space: {name}[{r}][{c}] holds the number {v}, which is not finite (with \
                         the values given by --param, or a division by zero in the model)"
                    ));
                }
            }
        }
        let mut texts = entries.iter().map(|e| equations::expr_text(eqs, e));
        Ok(m.iter()
            .map(|row| texts.by_ref().take(row.len()).collect())
            .collect())
    };
    Ok(json!({
        "states": j.states,
        "inputs": j.inputs,
        "outputs": j.outputs,
        "A": render("A", &j.dfdx)?,
        "B": render("B", &j.dfdu)?,
        "C": render("C", &j.dhdx)?,
        "D": render("D", &j.dhdu)?,
    }))
}

fn numeric_json(ss: &NumericStateSpace) -> Value {
    // A zero is a zero: `-0.0` (the product of a zero coefficient and a negative one) would print as `-0.0`.
    let positive_zero = |m: &[Vec<f64>]| -> Vec<Vec<f64>> {
        m.iter()
            .map(|r| r.iter().map(|x| if *x == 0.0 { 0.0 } else { *x }).collect())
            .collect()
    };
    json!({
        "states": ss.states,
        "inputs": ss.inputs,
        "outputs": ss.outputs,
        "A": positive_zero(&ss.a),
        "B": positive_zero(&ss.b),
        "C": positive_zero(&ss.c),
        "D": positive_zero(&ss.d),
    })
}

/// The JSON form with the keys in reading order and one matrix row per line.
fn json_rows(v: &Value) -> String {
    let compact = |x: Option<&Value>| {
        x.and_then(|x| serde_json::to_string(x).ok())
            .unwrap_or_else(|| "null".into())
    };
    let mut out = String::from("{\n");
    for k in ["states", "inputs", "outputs"] {
        out.push_str(&format!("  \"{k}\": {},\n", compact(v.get(k))));
    }
    let matrices = ["A", "B", "C", "D"];
    for (i, m) in matrices.iter().enumerate() {
        let rows: Vec<String> = v
            .get(*m)
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .map(|r| format!("    {}", compact(Some(r))))
            .collect();
        let sep = if i + 1 == matrices.len() { "" } else { "," };
        if rows.is_empty() {
            out.push_str(&format!("  \"{m}\": []{sep}\n"));
        } else {
            out.push_str(&format!("  \"{m}\": [\n{}\n  ]{sep}\n", rows.join(",\n")));
        }
    }
    out.push_str("}\n");
    out
}

/// The head of the text forms: the states, inputs and outputs of a state-space value, one line each.
pub(super) fn names_text(v: &Value) -> String {
    let names = |k: &str| {
        let list: Vec<&str> = v
            .get(k)
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(Value::as_str)
            .collect();
        if list.is_empty() {
            "(none)".to_string()
        } else {
            list.join(", ")
        }
    };
    format!(
        "states: {}\ninputs: {}\noutputs: {}\n",
        names("states"),
        names("inputs"),
        names("outputs")
    )
}

/// The text form: the names, then each matrix with one row per line.
fn text(v: &Value) -> String {
    let mut out = names_text(v);
    for m in ["A", "B", "C", "D"] {
        out.push_str(&format!("\n{m} =\n"));
        let rows: Vec<&Vec<Value>> = v
            .get(m)
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(Value::as_array)
            .collect();
        let numbers: Option<Vec<Vec<f64>>> = rows
            .iter()
            .map(|r| r.iter().map(Value::as_f64).collect())
            .collect();
        let cells = match numbers {
            Some(numbers) => matrix_text::format_matrix(&numbers),
            None => rows
                .iter()
                .map(|r| {
                    r.iter()
                        .map(|c| match c {
                            Value::String(s) => format!("[{s}]"),
                            other => other.to_string(),
                        })
                        .collect()
                })
                .collect(),
        };
        out.push_str(&matrix_text::layout(&cells));
    }
    out
}
