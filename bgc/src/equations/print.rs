//! Readable equations and their printers: text, LaTeX and JSON.
//!
//! The readable form keeps one intermediate per bond variable that the rates and outputs need, except copies (a
//! junction's common effort or flow on its other bonds), which are replaced by the variable they copy. Intermediates
//! are listed in dependency order (depth-first from the rates, then the outputs), so each is defined before use
//! unless an algebraic loop joins them. Output is deterministic: same model, same text.

use super::build::{Built, Def};
use super::naming::UniqueNames;
use super::symbols::{self, Sym, SymExt};
use super::{Equations, Intermediate, StateKind, StateSpec};
use crate::concurrent::map_halves;
use crate::symbolic::{Expr, Symbol, to_latex_with, to_text_with};
use serde_json::{Value, json};
use std::collections::HashMap;

pub(crate) struct Readable {
    pub rates: Vec<Expr>,
    pub intermediates: Vec<Intermediate>,
    /// Per bond variable: the printed name of its representative.
    pub names: Vec<String>,
    rep: Vec<usize>,
    /// Per bond variable: the junction velocity state it equals, when it is one (see `equations::kinematic`).
    velocity: Vec<Option<usize>>,
}

impl Readable {
    /// Replaces copies by the variable they copy (a junction's velocity by its state).
    pub fn alias(&self, e: &Expr) -> Expr {
        // `None` for a variable that stays as it is, so that an unchanged expression is not rebuilt.
        symbols::subst(e, &mut |s| match s {
            Sym::Var(v) => {
                let r = *self.rep.get(v)?;
                match self.velocity.get(r).copied().flatten() {
                    Some(k) => Some(symbols::leaf(Sym::State(k))),
                    None => (r != v).then(|| symbols::leaf(Sym::Var(r))),
                }
            }
            _ => None,
        })
    }
}

/// `taken` holds the names the intermediates must not take (parameters, inputs, outputs, states).
pub(crate) fn readable(
    built: &Built,
    rates: &[Expr],
    outputs: &[Expr],
    mut taken: UniqueNames,
) -> Readable {
    let n = built.defs.len();
    let rep = super::copies::representatives(&built.defs);
    // The flow of a junction with a velocity state is that state (its massless inertia's bond copies it).
    let velocity: Vec<Option<usize>> = built
        .defs
        .iter()
        .map(|d| {
            match d.as_ref().and_then(|d| match d {
                Def::Plain(e) => e.as_sym(),
                Def::Rate(_) => None,
            }) {
                Some(Sym::State(k))
                    if built
                        .states
                        .get(k)
                        .is_some_and(|s| s.kind == StateKind::Velocity && s.port.is_none()) =>
                {
                    Some(k)
                }
                _ => None,
            }
        })
        .collect();
    let mut r = Readable {
        rates: Vec::new(),
        intermediates: Vec::new(),
        names: Vec::new(),
        rep,
        velocity,
    };
    r.rates = rates.iter().map(|e| r.alias(e)).collect();
    let defs: Vec<Option<(Expr, bool)>> = built
        .defs
        .iter()
        .map(|d| match d {
            Some(Def::Plain(e)) => Some((r.alias(e), false)),
            Some(Def::Rate(e)) => Some((r.alias(e), true)),
            None => None,
        })
        .collect();
    // Depth-first post-order from the roots, on an explicit stack.
    let mut seen = vec![false; n];
    let mut order = Vec::new();
    let roots: Vec<Expr> = r
        .rates
        .iter()
        .cloned()
        .chain(outputs.iter().map(|o| r.alias(o)))
        .collect();
    for root in &roots {
        for v in vars_of(root) {
            if seen[v] {
                continue;
            }
            seen[v] = true;
            let mut stack = vec![(
                v,
                vars_of(defs[v].as_ref().map(|d| &d.0).unwrap_or(&Expr::zero())),
                0usize,
            )];
            while let Some((node, deps, i)) = stack.last_mut() {
                if let Some(&w) = deps.get(*i) {
                    *i += 1;
                    if !seen[w] {
                        seen[w] = true;
                        let d = vars_of(defs[w].as_ref().map(|d| &d.0).unwrap_or(&Expr::zero()));
                        stack.push((w, d, 0));
                    }
                } else {
                    order.push(*node);
                    stack.pop();
                }
            }
        }
    }
    // Unique names: a variable whose name is taken gets the first free numeric suffix; the model's own elements
    // claim before those of instances.
    let mut names: Vec<String> = built.names.clone();
    for qualified in [false, true] {
        for &v in &order {
            if built.qualified.get(v).copied().unwrap_or(false) == qualified {
                names[v] = taken.claim(&names[v]);
            }
        }
    }
    r.names = (0..n).map(|v| names[r.rep[v]].clone()).collect();
    for &v in &order {
        if let Some((value, derivative)) = &defs[v] {
            r.intermediates.push(Intermediate {
                name: r.names[v].clone(),
                value: value.clone(),
                derivative: *derivative,
            });
        }
    }
    r
}

/// The bond variables of an expression, in first-use order.
fn vars_of(e: &Expr) -> Vec<usize> {
    let mut out = Vec::new();
    e.for_each_sym(&mut |s| {
        if let Sym::Var(v) = s
            && !out.contains(&v)
        {
            out.push(v);
        }
    });
    out
}

/// The output style of [`expr`].
#[derive(Clone, Copy, PartialEq)]
enum Style {
    Text,
    Latex,
}

/// A symbol name in LaTeX (`J_sint` → `J_{sint}`, `tau_m` → `\\tau_{m}`, `e_hd_spring` → `e_{hd\\_spring}`):
/// the engine's typesetting, so that a name reads the same in every equation.
fn latex_name(name: &str) -> String {
    crate::symbolic::latex_symbol(name)
}

/// The time derivative of a symbol in LaTeX, the dot on the main symbol alone: `\\dot{p}_{leg\\_1}`.
fn latex_dot(name: &str) -> String {
    match crate::symbolic::latex_symbol_parts(name) {
        (head, None) => format!("\\dot{{{head}}}"),
        (head, Some(sub)) => format!("\\dot{{{head}}}_{{{sub}}}"),
    }
}

/// An element's name as the subscript of a quantity of it (`E_{leg\\_1}`, `M_{leg}`): as written, like the
/// subscripts of its state names.
fn latex_element(name: &str) -> String {
    crate::symbolic::latex_subscript(name)
}

fn name_of(eqs: &Equations, s: Sym, style: Style) -> String {
    match (style, s) {
        (Style::Latex, Sym::StateDot(i)) => latex_dot(&eqs.sym_name(Sym::State(i))),
        (Style::Latex, Sym::InputDot(i)) => latex_dot(&eqs.sym_name(Sym::Input(i))),
        (Style::Latex, _) => latex_name(&eqs.sym_name(s)),
        (Style::Text, _) => eqs.sym_name(s),
    }
}

/// Prints `e` with the engine's printers, each symbol named by `eqs`.
fn expr(eqs: &Equations, e: &Expr, style: Style) -> String {
    expr_named(eqs, e, style, &HashMap::new())
}

/// [`expr`] with the definitions of shared subexpressions (`extra`) named as it says.
fn expr_named(eqs: &Equations, e: &Expr, style: Style, extra: &HashMap<Symbol, String>) -> String {
    let name = |s: &Symbol| match (Sym::of(s), extra.get(s)) {
        (_, Some(n)) if style == Style::Latex => latex_name(n),
        (_, Some(n)) => n.clone(),
        (Some(t), None) => name_of(eqs, t, style),
        (None, None) => s.name().to_string(),
    };
    match style {
        Style::Text => to_text_with(e, &name),
        Style::Latex => to_latex_with(e, &name),
    }
}

/// An expression as text, with the symbol names of `eqs`.
pub fn expr_text(eqs: &Equations, e: &Expr) -> String {
    expr(eqs, e, Style::Text)
}

/// An expression in LaTeX.
pub fn expr_latex(eqs: &Equations, e: &Expr) -> String {
    expr(eqs, e, Style::Latex)
}

/// The mass block and row of state `i`, when its rate is a row of an I-field's mass-matrix form.
fn mass_row(eqs: &Equations, i: usize) -> Option<(&super::MassBlock, usize)> {
    eqs.mass
        .iter()
        .find_map(|b| b.states.iter().position(|&j| j == i).map(|k| (b, k)))
}

/// The equations as text: one equation per line, grouped into states, intermediates and outputs.
pub fn to_text(eqs: &Equations) -> String {
    let mut out = format!("model {}\n", eqs.model);
    out.push_str("states:\n");
    // The lines of a large model's long lists are formatted on two threads (see `map_halves`).
    let rows: Vec<(usize, (&StateSpec, &Expr))> =
        eqs.states.iter().zip(&eqs.rates).enumerate().collect();
    let lines = map_halves(&rows, |&(i, (s, r))| {
        let lhs = match mass_row(eqs, i) {
            Some((b, k)) => format!("[M_{} d/dt f_{}]_{}", b.element, b.element, k + 1),
            None => format!("d/dt {}", s.name),
        };
        format!("  {lhs} = {}\n", expr_text(eqs, r))
    });
    lines.iter().for_each(|l| out.push_str(l));
    for b in &eqs.mass {
        out.push_str(&format!(
            "mass matrix M_{} (symmetric), f_{} = [{}]:\n",
            b.element,
            b.element,
            b.states
                .iter()
                .map(|&j| eqs.sym_name(Sym::State(j)))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        for (i, row) in b.matrix.iter().enumerate() {
            for (j, m) in row.iter().enumerate().skip(i) {
                out.push_str(&format!(
                    "  M_{}[{},{}] = {}\n",
                    b.element,
                    i + 1,
                    j + 1,
                    expr_text(eqs, m)
                ));
            }
        }
    }
    out.push_str("intermediates:\n");
    let lines = map_halves(&eqs.intermediates, |i| {
        let v = expr_text(eqs, &i.value);
        if i.derivative {
            format!("  {} = d/dt({v})\n", i.name)
        } else {
            format!("  {} = {v}\n", i.name)
        }
    });
    lines.iter().for_each(|l| out.push_str(l));
    if !eqs.loops.is_empty() {
        out.push_str(&format!(
            "  (algebraic loop, solved exactly for: {})\n",
            eqs.loops.join(", ")
        ));
    }
    if !eqs.tear_blocks.is_empty() {
        out.push_str("algebraic loops, solved numerically (Newton's method):\n");
        for b in &eqs.tear_blocks {
            let residuals: Vec<String> = b.residuals.iter().map(|r| expr_text(eqs, r)).collect();
            match residuals.as_slice() {
                [one] => out.push_str(&format!("  solve for {}: 0 = {one}\n", b.names.join(", "))),
                _ => {
                    out.push_str(&format!("  solve for {}:\n", b.names.join(", ")));
                    for r in residuals {
                        out.push_str(&format!("    0 = {r}\n"));
                    }
                }
            }
        }
    }
    out.push_str("outputs:\n");
    for o in &eqs.outputs {
        out.push_str(&format!("  {} = {}\n", o.name, expr_text(eqs, &o.value)));
    }
    if !eqs.energy.is_empty() {
        out.push_str("energy (stored energy, dissipated and supplied power):\n");
        let (definitions, values, names) = energy_values(eqs);
        for (name, value) in &definitions {
            let value = expr_named(eqs, value, Style::Text, &names);
            out.push_str(&format!("  where {name} = {value}\n"));
        }
        let terms: Vec<_> = eqs.energy.iter().zip(&values).collect();
        let lines = map_halves(&terms, |(t, value)| {
            let value = value.as_ref().map_or_else(
                || NOT_COMPUTED.to_string(),
                |v| expr_named(eqs, v, Style::Text, &names),
            );
            format!("  {} {} = {value}\n", t.kind.name(), t.element)
        });
        lines.iter().for_each(|l| out.push_str(l));
    }
    out
}

/// The definitions of shared subexpressions, the energy terms' values over them and their names (see
/// [`super::shared`]); no definitions and the values as they are for terms that do not repeat much.
type EnergyValues = (
    Vec<(String, Expr)>,
    Vec<Option<Expr>>,
    HashMap<Symbol, String>,
);

fn energy_values(eqs: &Equations) -> EnergyValues {
    match super::shared::shared_energy(eqs) {
        Some(s) => (s.definitions, s.values, s.names),
        None => (
            Vec::new(),
            eqs.energy.iter().map(|t| t.value.clone()).collect(),
            HashMap::new(),
        ),
    }
}

/// What an energy term without a closed form prints (a warning, BG0607, says why).
const NOT_COMPUTED: &str = "not computed (see warning BG0607)";

/// The left-hand side of an energy term in LaTeX: `E_{x}` stored, `P^{diss}_{x}`, `P^{sup}_{x}`.
fn energy_latex(t: &super::EnergyTerm) -> String {
    let name = latex_element(&t.element);
    match t.kind {
        super::EnergyKind::Stored => format!("E_{{{name}}}"),
        super::EnergyKind::Dissipated => format!("P^{{\\mathrm{{diss}}}}_{{{name}}}"),
        super::EnergyKind::Supplied => format!("P^{{\\mathrm{{sup}}}}_{{{name}}}"),
    }
}

/// The equations in LaTeX: one `aligned` environment per group.
pub fn to_latex(eqs: &Equations) -> String {
    let mut out = String::new();
    let mut group = |title: &str, lines: Vec<(String, String)>| {
        out.push_str(&format!("% {title}\n\\begin{{aligned}}\n"));
        for (l, r) in lines {
            out.push_str(&format!("  {l} &= {r} \\\\\n"));
        }
        out.push_str("\\end{aligned}\n");
    };
    group(
        "states",
        eqs.states
            .iter()
            .zip(&eqs.rates)
            .enumerate()
            .map(|(i, (s, r))| {
                let lhs = match mass_row(eqs, i) {
                    Some((b, k)) => format!(
                        "\\left[M_{{{}}} \\dot{{f}}_{{{}}}\\right]_{{{}}}",
                        latex_element(&b.element),
                        latex_element(&b.element),
                        k + 1
                    ),
                    None => latex_dot(&s.name),
                };
                (lhs, expr_latex(eqs, r))
            })
            .collect(),
    );
    for b in &eqs.mass {
        let mut lines = Vec::new();
        for (i, row) in b.matrix.iter().enumerate() {
            for (j, m) in row.iter().enumerate().skip(i) {
                lines.push((
                    format!("M_{{{},{}{}}}", latex_element(&b.element), i + 1, j + 1),
                    expr_latex(eqs, m),
                ));
            }
        }
        group(&format!("mass matrix of {}", b.element), lines);
    }
    group(
        "intermediates",
        eqs.intermediates
            .iter()
            .map(|i| {
                let v = expr_latex(eqs, &i.value);
                let v = if i.derivative {
                    format!("\\frac{{d}}{{dt}}\\left({v}\\right)")
                } else {
                    v
                };
                (latex_name(&i.name), v)
            })
            .collect(),
    );
    for b in &eqs.tear_blocks {
        group(
            &format!(
                "algebraic loop, solved numerically for {}",
                b.names.join(", ")
            ),
            b.residuals
                .iter()
                .map(|r| ("0".to_string(), expr_latex(eqs, r)))
                .collect(),
        );
    }
    group(
        "outputs",
        eqs.outputs
            .iter()
            .map(|o| (latex_name(&o.name), expr_latex(eqs, &o.value)))
            .collect(),
    );
    if !eqs.energy.is_empty() {
        let (definitions, values, names) = energy_values(eqs);
        let shared = definitions.iter().map(|(name, value)| {
            (
                latex_name(name),
                expr_named(eqs, value, Style::Latex, &names),
            )
        });
        let terms = eqs.energy.iter().zip(&values).map(|(t, value)| {
            let value = value.as_ref().map_or_else(
                || format!("\\text{{{NOT_COMPUTED}}}"),
                |v| expr_named(eqs, v, Style::Latex, &names),
            );
            (energy_latex(t), value)
        });
        group(
            "energy: stored energy E, dissipated and supplied power P",
            shared.chain(terms).collect(),
        );
    }
    out
}

/// The equations as JSON: readable and explicit forms of every rate and output, as text.
pub fn to_json(eqs: &Equations) -> Value {
    let text = |e: &Option<Expr>| e.as_ref().map(|e| expr_text(eqs, e));
    let (definitions, values, names) = energy_values(eqs);
    let energy: Vec<_> = eqs.energy.iter().zip(values).collect();
    json!({
        "model": eqs.model,
        "params": eqs.params.iter().map(|(n, v)| json!({"name": n, "default": v})).collect::<Vec<_>>(),
        "inputs": eqs.inputs,
        "states": eqs.states.iter().enumerate().map(|(i, s)| json!({
            "name": s.name,
            "kind": match s.kind {
                StateKind::Momentum => "momentum",
                StateKind::Displacement => "displacement",
                StateKind::Integrated => "integrated",
                StateKind::Velocity => "velocity",
            },
            "rate": eqs.rates.get(i).map(|r| expr_text(eqs, r)),
            "explicit": text(eqs.f.get(i).unwrap_or(&None)),
        })).collect::<Vec<_>>(),
        "intermediates": eqs.intermediates.iter().map(|i| json!({
            "name": i.name,
            "value": expr_text(eqs, &i.value),
            "derivative": i.derivative,
        })).collect::<Vec<_>>(),
        "outputs": eqs.outputs.iter().map(|o| json!({
            "name": o.name,
            "value": expr_text(eqs, &o.value),
            "explicit": text(&o.explicit),
        })).collect::<Vec<_>>(),
        "coords": eqs.coords.as_ref().map(|c| c.iter().map(|(n, e)| json!({"name": n, "value": expr_text(eqs, e)})).collect::<Vec<_>>()),
        "loops": eqs.loops,
        "mass": eqs.mass.iter().map(|b| json!({
            "element": b.element,
            "states": b.states.iter().map(|&j| eqs.sym_name(Sym::State(j))).collect::<Vec<_>>(),
            "matrix": b.matrix.iter().map(|row| row.iter().map(|m| expr_text(eqs, m)).collect::<Vec<_>>()).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "tear_blocks": eqs.tear_blocks.iter().map(|b| json!({
            "tears": b.names,
            "residuals": b.residuals.iter().map(|r| expr_text(eqs, r)).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "energy": energy.iter().map(|(t, value)| json!({
            "element": t.element,
            "kind": t.kind.name(),
            "value": value.as_ref().map(|v| expr_named(eqs, v, Style::Text, &names)),
        })).collect::<Vec<_>>(),
        "energy_shared": definitions.iter().map(|(name, value)| json!({
            "name": name,
            "value": expr_named(eqs, value, Style::Text, &names),
        })).collect::<Vec<_>>(),
    })
}
