//! Hover: what a name is, in Markdown.
//!
//! A parameter shows its declaration, description and value in SI units; an input or output its unit; an element
//! its kind and law, its domain, its causality and the equations derived for it (when the model got that far); an
//! instance its component's parameters; a unit its SI form; an element kind keyword what the kind means.

use super::analysis::{Analysis, ModelFacts};
use super::index::{Hit, Symbol, SymbolKind};
use crate::causality::StorageForm;
use crate::equations::expr_text;
use crate::span::{FileId, Span};
use crate::syntax::ast::{ElementKind, UnitExpr};
use petgraph::graph::NodeIndex;
use petgraph::visit::EdgeRef;

/// The hover text at a byte offset of a file and the span it is about.
pub fn hover(analysis: &Analysis, file: FileId, offset: usize) -> Option<(String, Span)> {
    match analysis.index.at(file, offset)? {
        Hit::Symbol(id, span) => Some((symbol(analysis, id), span)),
        Hit::Unit(u) => Some((unit(u), u.span)),
        Hit::Kind(span, kind) => Some((
            format!("`{}`: {}", kind.keyword(), kind_meaning(kind)),
            span,
        )),
    }
}

fn symbol(analysis: &Analysis, id: usize) -> String {
    let index = &analysis.index;
    let Some(s) = index.symbols.get(id) else {
        return String::new();
    };
    let mut out = format!("```bg\n{}\n```\n\n", signature(analysis, s));
    let owner = s
        .parent
        .and_then(|p| index.symbols.get(p))
        .map(|p| format!(" of {} `{}`", p.kind.noun(), p.name))
        .unwrap_or_default();
    out.push_str(&format!("{} `{}`{owner}", s.kind.noun(), s.name));
    if let Some(d) = &s.description {
        out.push_str(&format!(": {d}"));
    }
    out.push('\n');
    if !s.doc.is_empty() {
        out.push_str(&format!("\n{}\n", s.doc.join("\n")));
    }
    let facts = match s.kind {
        SymbolKind::Param => param_facts(analysis, s),
        SymbolKind::Input | SymbolKind::Output => signal_facts(analysis, s),
        SymbolKind::Element => element_facts(analysis, s),
        SymbolKind::Instance => instance_facts(analysis, s),
        SymbolKind::Model | SymbolKind::Component => model_facts(analysis, id, s),
        SymbolKind::Var => var_facts(analysis, s),
        SymbolKind::Port => Vec::new(),
    };
    if !facts.is_empty() {
        out.push('\n');
        for f in facts {
            out.push_str(&format!("- {f}\n"));
        }
    }
    out
}

/// The declaration as written, on one line (at most 200 characters).
fn signature(analysis: &Analysis, s: &Symbol) -> String {
    if matches!(s.kind, SymbolKind::Model | SymbolKind::Component) {
        return format!("{} {}", s.kind.noun(), s.name);
    }
    let text = analysis.sources.snippet(s.decl_span);
    let one_line: Vec<&str> = text.split_whitespace().collect();
    let line = one_line.join(" ");
    match line.char_indices().nth(200) {
        Some((cut, _)) => format!("{} …", &line[..cut]),
        None => line,
    }
}

fn contains(outer: Span, inner: Span) -> bool {
    outer.file == inner.file && outer.start <= inner.start && inner.end <= outer.end
}

fn param_facts(analysis: &Analysis, s: &Symbol) -> Vec<String> {
    let mut out = Vec::new();
    for m in &analysis.models {
        for (p, span) in m.model.params.iter().zip(&m.model.spans.params) {
            if !contains(*span, s.name_span) {
                continue;
            }
            let value = if p.derived.is_some() {
                format!(
                    "{} (derived from other parameters)",
                    crate::syntax::format_number(p.default)
                )
            } else {
                crate::syntax::format_number(p.default)
            };
            out.push(format!(
                "`{}` = {value} {} (SI; declared in [{}])",
                p.name, p.unit.dim, p.unit_text
            ));
        }
    }
    out
}

fn signal_facts(analysis: &Analysis, s: &Symbol) -> Vec<String> {
    let mut out = Vec::new();
    for m in &analysis.models {
        let model = &m.model;
        let inputs = model
            .inputs
            .iter()
            .zip(&model.spans.inputs)
            .map(|(i, sp)| (&i.unit_text, i.unit, sp));
        let outputs = model
            .outputs
            .iter()
            .zip(&model.spans.outputs)
            .map(|(o, sp)| (&o.unit_text, o.unit, sp));
        for (text, unit, span) in inputs.chain(outputs) {
            if contains(*span, s.name_span) {
                out.push(format!("unit [{text}] = {unit} in SI"));
            }
        }
    }
    out.dedup();
    out
}

/// An integrated flow: its unit and the rate of its state.
fn var_facts(analysis: &Analysis, s: &Symbol) -> Vec<String> {
    let mut out = Vec::new();
    for m in &analysis.models {
        for (i, (var, span)) in m.model.vars.iter().zip(&m.model.spans.vars).enumerate() {
            if !contains(*span, s.name_span) {
                continue;
            }
            out.push(format!("unit [{}] = {} in SI", var.unit_text, var.unit));
            let Some(eqs) = &m.equations else { continue };
            for (spec, rate) in eqs.states.iter().zip(&eqs.rates) {
                if spec.var == Some(i) {
                    out.push(format!("`d/dt {} = {}`", spec.name, expr_text(eqs, rate)));
                }
            }
        }
    }
    out
}

fn element_facts(analysis: &Analysis, s: &Symbol) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(kind) = ElementKind::from_keyword(&s.detail) {
        out.push(format!("{}: {}", kind.keyword(), kind_meaning(kind)));
    }
    for m in &analysis.models {
        let model = &m.model;
        for (i, span) in model.spans.node_names.iter().enumerate() {
            if *span != s.name_span {
                continue;
            }
            let node = NodeIndex::new(i);
            let name = &model.graph[node].name;
            if let Some(domain) = model
                .graph
                .edges(node)
                .next()
                .map(|e| e.weight().domain)
                .or_else(|| {
                    model
                        .graph
                        .edges_directed(node, petgraph::Direction::Incoming)
                        .next()
                        .map(|e| e.weight().domain)
                })
            {
                out.push(format!(
                    "`{name}` in model `{}`: {} domain",
                    model.name,
                    domain.name()
                ));
            }
            out.extend(causality_lines(m, node));
            out.extend(equation_lines(m, node));
        }
    }
    out
}

/// Which end sets the effort on each bond of the node, and the causality of its storage ports.
fn causality_lines(m: &ModelFacts, node: NodeIndex) -> Vec<String> {
    let Some(c) = &m.causality else {
        return Vec::new();
    };
    let model = &m.model;
    let mut out: Vec<String> = c
        .storage
        .iter()
        .filter(|s| s.node == node)
        .map(|s| {
            let form = match s.causality {
                StorageForm::Integral => "integral causality (its energy variable is a state)",
                StorageForm::Derivative => "derivative causality (no state of its own)",
            };
            if model.graph[node].ports > 1 {
                format!("port {}: {form}", s.port + 1)
            } else {
                form.to_string()
            }
        })
        .collect();
    let name = &model.graph[node].name;
    let bonds = model
        .graph
        .edges_directed(node, petgraph::Direction::Outgoing)
        .chain(
            model
                .graph
                .edges_directed(node, petgraph::Direction::Incoming),
        );
    for e in bonds.take(8) {
        let what = if c.sets_effort(model, node, e.id()) {
            "effort"
        } else {
            "flow"
        };
        out.push(format!(
            "`{name}` sets the {what} on bond `{}`",
            model.bond_name(e.id())
        ));
    }
    out
}

/// The rate of the node's state and the intermediates named after it.
fn equation_lines(m: &ModelFacts, node: NodeIndex) -> Vec<String> {
    let Some(eqs) = &m.equations else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (spec, rate) in eqs.states.iter().zip(&eqs.rates) {
        if spec.node == Some(node) {
            out.push(format!("`d/dt {} = {}`", spec.name, expr_text(eqs, rate)));
        }
    }
    let graph = &m.model.graph;
    let base = graph[node].name.replace('.', "_");
    // A transformer or gyrator `T` names the variables of its ports `T_in` and `T_out`; an element whose own name
    // is one of those would be confused with them, so it is shown none.
    let bases: Vec<String> = if graph[node].kind.is_two_port() {
        vec![format!("{base}_in"), format!("{base}_out")]
    } else if graph.node_weights().any(|n| {
        n.kind.is_two_port() && {
            let t = n.name.replace('.', "_");
            base == format!("{t}_in") || base == format!("{t}_out")
        }
    }) {
        Vec::new()
    } else {
        vec![base]
    };
    let named_after = |n: &str| {
        ["e_", "f_"].iter().any(|p| {
            n.strip_prefix(p).is_some_and(|rest| {
                bases.iter().any(|base| {
                    rest == base
                        || rest
                            .strip_prefix(base.as_str())
                            .and_then(|r| r.strip_prefix('_'))
                            .is_some_and(|r| r.parse::<u32>().is_ok())
                })
            })
        })
    };
    for i in eqs.intermediates.iter().filter(|i| named_after(&i.name)) {
        let d = if i.derivative { "d/dt " } else { "" };
        out.push(format!("`{} = {d}{}`", i.name, expr_text(eqs, &i.value)));
    }
    out
}

fn instance_facts(analysis: &Analysis, s: &Symbol) -> Vec<String> {
    let index = &analysis.index;
    let Some(component) = index.global(&s.detail) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    if let Some(c) = index.symbols.get(component)
        && let Some(first) = c.doc.first()
    {
        out.push(format!("`{}`: {first}", c.name));
    }
    for (_, p) in index
        .members(component)
        .filter(|(_, p)| p.kind == SymbolKind::Param)
    {
        out.push(format!("`{}`", signature(analysis, p)));
    }
    out
}

fn model_facts(analysis: &Analysis, id: usize, s: &Symbol) -> Vec<String> {
    let mut out = Vec::new();
    for m in analysis.models.iter().filter(|m| {
        m.model.spans.model == s.decl_span || m.model.name == s.name && s.kind == SymbolKind::Model
    }) {
        out.push(m.model.size_in_words());
        if let Some(eqs) = &m.equations {
            let names: Vec<&str> = eqs.states.iter().map(|s| s.name.as_str()).collect();
            out.push(format!("{} states: {}", names.len(), names.join(", ")));
        }
    }
    let members = analysis.index.members(id).count();
    if out.is_empty() {
        out.push(format!("{members} declarations"));
    }
    out
}

fn unit(u: &UnitExpr) -> String {
    let written = crate::syntax::format_unit(u);
    match crate::units::parse_unit(u) {
        Ok(unit) if unit.scale == 1.0 => format!("unit `{written}` = {} (SI)", unit.dim),
        Ok(unit) => format!(
            "unit `{written}` = {} {} (SI): a value in `{written}` is {} times the value in SI",
            crate::syntax::format_number(unit.scale),
            unit.dim,
            crate::syntax::format_number(unit.scale)
        ),
        Err(e) => format!("unit `{written}`: {e}"),
    }
}

/// What an element kind is, as docs/language.md describes it.
pub fn kind_meaning(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Se => "effort source (`e = value`)",
        ElementKind::Sf => "flow source (`f = value`)",
        ElementKind::MSe => {
            "modulated effort source (`e = value`, an expression of inputs and states)"
        }
        ElementKind::MSf => {
            "modulated flow source (`f = value`, an expression of inputs and states)"
        }
        ElementKind::C => {
            "compliance, stores potential energy (`q = C e`, or a law `e = ...` of `q`)"
        }
        ElementKind::I => "inertia, stores kinetic energy (`p = I f`, or a law `f = ...` of `p`)",
        ElementKind::R => "resistance, dissipates power (`e = R f`, or a law of `e` and `f`)",
        ElementKind::TF => "transformer (`f_in = ratio f_out`, `e_out = ratio e_in`)",
        ElementKind::GY => "gyrator (`e_out = r f_in`, `e_in = r f_out`)",
        ElementKind::MTF => "modulated transformer (the ratio an expression)",
        ElementKind::MGY => "modulated gyrator (the modulus an expression)",
        ElementKind::Zero => "0-junction: common effort, flows sum to zero",
        ElementKind::One => "1-junction: common flow, efforts sum to zero",
        ElementKind::CF => "multiport compliance field (laws `e[i] = ...` of the `q[j]`)",
        ElementKind::RF => "multiport resistance field (laws `e[i] = ...` of the `f[j]`)",
        ElementKind::IF => "multiport inertia field (`mass[i,j] = ...`: the inertia matrix M(q))",
    }
}
