//! The causal equations of every node: each bond variable gets exactly one defining equation, written by the node
//! at the end of the bond that computes it (the effort by the end that sets it, the flow by the other end).
//!
//! Sign convention (docs/language.md, "Effort and flow of an element"): a 1-port element's own effort is its bond's
//! effort; its own flow is its bond's flow counted in the element's standard direction, into a C, I or R and out of
//! a source: `own f = s · f_bond` with `s = +1` when the bond is drawn that way and `-1` otherwise. So `e·f` is the
//! power a C, I or R absorbs and the power a source delivers, whichever way the bond is drawn, and a source's value
//! is its own variable (`Sf x = v` gives `f(x) = v`). Junction sums use `+` for bonds pointing in and `-` for bonds
//! pointing out.
//!
//! | node | causality | definitions |
//! |---|---|---|
//! | `Se` | sets e | `e = value` |
//! | `Sf` | sets f | `f = s · value` |
//! | `C` | integral | `e = q/C` or `e = g(q)` (or `q = g(e)` inverted when affine in `e`) |
//! | `C` | derivative | `f = s · d/dt(C·e)` (or `d/dt(g(e))`) |
//! | `I` | integral | `f = s · p/I` or `f = g(p)` (or `p = g(f)` inverted) |
//! | `I` | derivative | `e = d/dt(I·f)` (or `d/dt(g(f))`) |
//! | `R` | resistance | `e = R·f` or `e = g(f)` (or `f = g(e)` inverted) |
//! | `R` | conductance | `f = s·e/R` or `f = g(e)` (or `e = g(f)` inverted) |
//! | `TF n` | effort in | `e_out = n·e_in`, `f_in = n·f_out` |
//! | `TF n` | flow in | `e_in = e_out/n`, `f_out = f_in/n` |
//! | `GY m` | sets efforts | `e_in = m·f_out`, `e_out = m·f_in` |
//! | `GY m` | sets flows | `f_out = e_in/m`, `f_in = e_out/m` |
//! | `0` | strong bond k | `e_b = e_k`, `f_k = -s_k Σ_{b≠k} s_b f_b` |
//! | `1` | strong bond k | `f_b = f_k`, `e_k = -s_k Σ_{b≠k} s_b e_b` |
//!
//! A nonlinear law is inverted only when it is affine in the unknown (`BG0601` otherwise).

use super::symbols::{self, Sym, add, div, mul, neg};
use super::{StateKind, StateSpec, codes};
use crate::causality::{Causality, StorageForm};
use crate::diagnostic::Diagnostic;
use crate::ir::{Expr as IrExpr, Law, Model, PortVar, Relation, Target};
use crate::symbolic::Expr;
use crate::syntax::ast::{BinOp, ElementKind};
use petgraph::Direction;
use petgraph::graph::{EdgeIndex, NodeIndex};
use std::collections::HashMap;

/// The definition of one bond variable.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Def {
    /// `v = expr`.
    Plain(Expr),
    /// `v = d/dt(expr)`: the output of a storage in derivative causality.
    Rate(Expr),
}

/// Index of the effort variable of a bond.
pub(crate) fn effort_var(b: EdgeIndex) -> usize {
    2 * b.index()
}

/// Index of the flow variable of a bond.
pub(crate) fn flow_var(b: EdgeIndex) -> usize {
    2 * b.index() + 1
}

/// Everything the later steps need from the graph.
pub(crate) struct Built {
    /// Per bond variable (`2·bond + {0: effort, 1: flow}`): its definition.
    pub defs: Vec<Option<Def>>,
    /// Per bond variable: the node that defines it.
    pub definer: Vec<Option<NodeIndex>>,
    /// Per bond variable: its readable name.
    pub names: Vec<String>,
    /// Per bond variable: true when its name comes from an instance's element (a qualified name), which yields a
    /// shared name to the model's own elements ([`super::naming`]).
    pub qualified: Vec<bool>,
    /// The states: integral storages, then integrated flows.
    pub states: Vec<StateSpec>,
    /// Per state: its rate in terms of bond variables (`ṗ = e`, `q̇ = s·f`, `θ̇ = integrand`); for the flow states
    /// of an I-field, the generalised force of its mass-matrix row.
    pub rates: Vec<Expr>,
    /// The inertia matrices of the I-fields.
    pub mass: Vec<super::field::MassBlock>,
    /// Per state: true when its rate equation is the implicit `0 = rates[i]` (the effort balance of a velocity
    /// state's junction, see [`super::kinematic`]).
    pub implicit_rows: Vec<bool>,
}

/// The conversion context of IR expressions.
pub(crate) struct Ctx<'a> {
    pub model: &'a Model,
    /// Per node: its single bond and the sign of its own flow (into a C, I or R, out of a source), for 1-port
    /// elements.
    pub port: Vec<Option<(EdgeIndex, f64)>>,
    /// Per node: the state of its energy variable when in integral causality.
    pub node_state: Vec<Option<usize>>,
    /// Per node: the energy variable of a storage in derivative causality, in bond variables.
    pub energy_expr: Vec<Option<Expr>>,
    /// Per `var`: its state.
    pub var_state: Vec<usize>,
    /// Per multiport field with states: the displacement state of each port.
    pub field_q: HashMap<NodeIndex, Vec<usize>>,
    /// Per I-field with states: the flow state of each port.
    pub field_f: HashMap<NodeIndex, Vec<usize>>,
    /// Per multiport field with states: the bond and own-flow sign of each port.
    pub field_ports: HashMap<NodeIndex, Vec<(EdgeIndex, f64)>>,
    /// Per node: true for the massless inertia that makes its junction's flow a velocity state
    /// ([`super::kinematic`]).
    pub velocity: Vec<bool>,
}

/// Why an IR expression could not be converted.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum ConvertError {
    /// A reference the equations stage cannot express (with what it is).
    Unsupported(String),
}

impl Ctx<'_> {
    fn node_name(&self, n: NodeIndex) -> String {
        self.model
            .graph
            .node_weight(n)
            .map(|w| w.name.clone())
            .unwrap_or_else(|| format!("node#{}", n.index()))
    }

    /// The effort variable of a target.
    fn effort_of(&self, t: Target) -> Result<Expr, ConvertError> {
        match t {
            Target::Bond(b) => Ok(symbols::leaf(Sym::Var(effort_var(b)))),
            Target::Node(n) => {
                if let Some((b, _)) = self.port.get(n.index()).copied().flatten() {
                    return Ok(symbols::leaf(Sym::Var(effort_var(b))));
                }
                let kind = self.model.graph.node_weight(n).map(|w| w.kind);
                match kind {
                    Some(ElementKind::Zero) => self
                        .model
                        .graph
                        .edges_directed(n, Direction::Incoming)
                        .chain(self.model.graph.edges_directed(n, Direction::Outgoing))
                        .next()
                        .map(|e| {
                            symbols::leaf(Sym::Var(effort_var(petgraph::visit::EdgeRef::id(&e))))
                        })
                        .ok_or_else(|| {
                            ConvertError::Unsupported(format!(
                                "e({}) of a junction without bonds",
                                self.node_name(n)
                            ))
                        }),
                    _ => Err(ConvertError::Unsupported(format!(
                        "e({}): the effort of a 1-junction, transformer or gyrator is not one variable; name a bond",
                        self.node_name(n)
                    ))),
                }
            }
        }
    }

    /// The flow variable of a target (a 1-port element's flow into it).
    fn flow_of(&self, t: Target) -> Result<Expr, ConvertError> {
        match t {
            Target::Bond(b) => Ok(symbols::leaf(Sym::Var(flow_var(b)))),
            Target::Node(n) => {
                if let Some((b, s)) = self.port.get(n.index()).copied().flatten() {
                    return Ok(mul(vec![
                        symbols::num(s),
                        symbols::leaf(Sym::Var(flow_var(b))),
                    ]));
                }
                let kind = self.model.graph.node_weight(n).map(|w| w.kind);
                match kind {
                    Some(ElementKind::One) => self
                        .model
                        .graph
                        .edges_directed(n, Direction::Incoming)
                        .chain(self.model.graph.edges_directed(n, Direction::Outgoing))
                        .next()
                        .map(|e| {
                            symbols::leaf(Sym::Var(flow_var(petgraph::visit::EdgeRef::id(&e))))
                        })
                        .ok_or_else(|| {
                            ConvertError::Unsupported(format!(
                                "f({}) of a junction without bonds",
                                self.node_name(n)
                            ))
                        }),
                    _ => Err(ConvertError::Unsupported(format!(
                        "f({}): the flow of a 0-junction, transformer or gyrator is not one variable; name a bond",
                        self.node_name(n)
                    ))),
                }
            }
        }
    }

    fn energy_of(&self, n: NodeIndex, what: &str) -> Result<Expr, ConvertError> {
        if let Some(s) = self.node_state.get(n.index()).copied().flatten() {
            return Ok(symbols::leaf(Sym::State(s)));
        }
        if let Some(e) = self.energy_expr.get(n.index()).cloned().flatten() {
            return Ok(e);
        }
        Err(ConvertError::Unsupported(format!(
            "{what}({}) is not the energy variable of a storage element",
            self.node_name(n)
        )))
    }

    /// A port variable of a multiport field: its displacement or (I-field) flow state, or its bond's variable.
    fn field_port(&self, node: NodeIndex, var: PortVar, port: u32) -> Result<Expr, ConvertError> {
        let k = port as usize;
        let state =
            |m: &HashMap<NodeIndex, Vec<usize>>| m.get(&node).and_then(|v| v.get(k)).copied();
        let bond = super::field::ports(self.model, node).and_then(|b| b.get(k).copied());
        let missing = || {
            ConvertError::Unsupported(format!(
                "{}[{}] of the multiport field {} has no value in this causality",
                match var {
                    PortVar::Effort => "e",
                    PortVar::Flow => "f",
                    PortVar::Momentum => "p",
                    PortVar::Displacement => "q",
                },
                k + 1,
                self.node_name(node)
            ))
        };
        match var {
            PortVar::Displacement => state(&self.field_q)
                .map(|s| symbols::leaf(Sym::State(s)))
                .ok_or_else(missing),
            PortVar::Flow => match state(&self.field_f) {
                Some(s) => Ok(symbols::leaf(Sym::State(s))),
                None => bond
                    .map(|(b, s)| mul(vec![symbols::num(s), symbols::leaf(Sym::Var(flow_var(b)))]))
                    .ok_or_else(missing),
            },
            PortVar::Effort => bond
                .map(|(b, _)| symbols::leaf(Sym::Var(effort_var(b))))
                .ok_or_else(missing),
            PortVar::Momentum => Err(missing()),
        }
    }

    /// Converts an IR expression; `outputs_seen` guards against outputs defined through each other.
    pub fn convert(&self, e: &IrExpr) -> Result<Expr, ConvertError> {
        self.convert_guarded(e, &mut Vec::new(), 0)
    }

    /// Converts the value of output `k`: earlier outputs stay references ([`Sym::Output`]), evaluated once before
    /// it, so that a chain of outputs defined through each other is shared, not copied into every use.
    pub fn convert_output(&self, e: &IrExpr, k: usize) -> Result<Expr, ConvertError> {
        self.convert_guarded(e, &mut vec![k], k)
    }

    /// `shared_below`: outputs with a smaller index are kept as references.
    fn convert_guarded(
        &self,
        e: &IrExpr,
        outputs_seen: &mut Vec<usize>,
        shared_below: usize,
    ) -> Result<Expr, ConvertError> {
        Ok(match e {
            IrExpr::Const(v) => symbols::num(*v),
            IrExpr::Time => symbols::leaf(Sym::Time),
            IrExpr::Param(p) => symbols::leaf(Sym::Param(*p)),
            IrExpr::Input(i) => symbols::leaf(Sym::Input(*i)),
            IrExpr::Output(o) if *o < shared_below => symbols::leaf(Sym::Output(*o)),
            IrExpr::Output(o) => {
                if outputs_seen.contains(o) {
                    return Err(ConvertError::Unsupported(
                        "an output defined through itself".into(),
                    ));
                }
                let out = self
                    .model
                    .outputs
                    .get(*o)
                    .ok_or_else(|| ConvertError::Unsupported(format!("output #{o}")))?;
                outputs_seen.push(*o);
                let v = self.convert_guarded(&out.value, outputs_seen, shared_below)?;
                outputs_seen.pop();
                v
            }
            IrExpr::Var(v) => symbols::leaf(Sym::State(
                *self
                    .var_state
                    .get(*v)
                    .ok_or_else(|| ConvertError::Unsupported(format!("var #{v}")))?,
            )),
            IrExpr::Effort(t) => self.effort_of(*t)?,
            IrExpr::Flow(t) => self.flow_of(*t)?,
            IrExpr::Momentum(n) => self.energy_of(*n, "p")?,
            IrExpr::Displacement(n) => self.energy_of(*n, "q")?,
            IrExpr::FieldPort { node, var, port } => self.field_port(*node, *var, *port)?,
            IrExpr::Neg(a) => neg(self.convert_guarded(a, outputs_seen, shared_below)?),
            IrExpr::Binary(op, a, b) => {
                let a = self.convert_guarded(a, outputs_seen, shared_below)?;
                let b = self.convert_guarded(b, outputs_seen, shared_below)?;
                match op {
                    BinOp::Add => add(vec![a, b]),
                    BinOp::Sub => symbols::sub(a, b),
                    BinOp::Mul => mul(vec![a, b]),
                    BinOp::Div => div(a, b),
                    BinOp::Pow => symbols::pow(a, b),
                }
            }
            IrExpr::Call(f, args) => symbols::call(
                *f,
                args.iter()
                    .map(|a| self.convert_guarded(a, outputs_seen, shared_below))
                    .collect::<Result<_, _>>()?,
            ),
        })
    }
}

/// Builds the conversion context: 1-port bonds and signs, states.
pub(crate) fn context<'a>(
    model: &'a Model,
    causality: &Causality,
    velocities: &[NodeIndex],
) -> (Ctx<'a>, Vec<StateSpec>) {
    let n = model.graph.node_count();
    let mut velocity = vec![false; n];
    for v in velocities {
        if let Some(slot) = velocity.get_mut(v.index()) {
            *slot = true;
        }
    }
    let mut port = vec![None; n];
    for node in model.graph.node_indices() {
        let w = &model.graph[node];
        if w.kind.is_junction() || w.kind.is_two_port() || w.kind.is_field() {
            continue;
        }
        let incoming = model.graph.edges_directed(node, Direction::Incoming).next();
        let outgoing = model.graph.edges_directed(node, Direction::Outgoing).next();
        // The standard direction: into a storage or a resistor, out of a source.
        let source = matches!(
            w.kind,
            ElementKind::Se | ElementKind::Sf | ElementKind::MSe | ElementKind::MSf
        );
        let inward = if source { -1.0 } else { 1.0 };
        port[node.index()] = match (incoming, outgoing) {
            (Some(e), _) => Some((petgraph::visit::EdgeRef::id(&e), inward)),
            (None, Some(e)) => Some((petgraph::visit::EdgeRef::id(&e), -inward)),
            (None, None) => None,
        };
    }
    let mut states = Vec::new();
    let mut node_state = vec![None; n];
    for s in &causality.storage {
        if s.causality != StorageForm::Integral {
            continue;
        }
        let Some(w) = model.graph.node_weight(s.node) else {
            continue;
        };
        if w.kind.is_field() {
            continue;
        }
        let kind = match w.kind {
            _ if velocity[s.node.index()] => StateKind::Velocity,
            ElementKind::I => StateKind::Momentum,
            _ => StateKind::Displacement,
        };
        let prefix = match kind {
            StateKind::Momentum => "p",
            StateKind::Velocity => "f",
            _ => "q",
        };
        // A velocity state belongs to its junction (the massless inertia is not the user's element).
        let owner = match kind {
            StateKind::Velocity => super::kinematic::junction_of(model, s.node),
            _ => Some(s.node),
        };
        node_state[s.node.index()] = Some(states.len());
        states.push(StateSpec {
            name: format!("{prefix}_{}", sanitize(&w.name)),
            kind,
            node: owner,
            var: None,
            port: None,
        });
    }
    let mut ctx = Ctx {
        model,
        port,
        node_state,
        energy_expr: vec![None; n],
        var_state: Vec::new(),
        field_q: HashMap::new(),
        field_f: HashMap::new(),
        field_ports: HashMap::new(),
        velocity,
    };
    super::field::add_states(&mut ctx, causality, &mut states);
    for (i, v) in model.vars.iter().enumerate() {
        ctx.var_state.push(states.len());
        states.push(StateSpec {
            name: sanitize(&v.name),
            kind: StateKind::Integrated,
            node: None,
            var: Some(i),
            port: None,
        });
    }
    super::naming::unique_states(model, &mut states);
    (ctx, states)
}

/// A name usable in every printer: qualified names `a.b` become `a_b`.
pub(crate) fn sanitize(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Readable names of the bond variables, qualified (`e_s.spring`) as the elements are.
fn names(model: &Model) -> Vec<String> {
    let mut names = vec![String::new(); 2 * model.graph.edge_count()];
    for b in model.graph.edge_indices() {
        let Some((a, z)) = model.graph.edge_endpoints(b) else {
            continue;
        };
        let (wa, wz) = (&model.graph[a], &model.graph[z]);
        let one_port = |k: ElementKind| !k.is_junction() && !k.is_two_port() && !k.is_field();
        let (e, f) = if one_port(wz.kind) {
            (format!("e_{}", wz.name), format!("f_{}", wz.name))
        } else if one_port(wa.kind) {
            (format!("e_{}", wa.name), format!("f_{}", wa.name))
        } else if let Some(label) = &model.graph[b].name {
            (format!("e_{label}"), format!("f_{label}"))
        } else if wa.kind.is_two_port() {
            (format!("e_{}_out", wa.name), format!("f_{}_out", wa.name))
        } else if wz.kind.is_two_port() {
            (format!("e_{}_in", wz.name), format!("f_{}_in", wz.name))
        } else {
            let e = match (wa.kind, wz.kind) {
                (ElementKind::Zero, _) => format!("e_{}", wa.name),
                (_, ElementKind::Zero) => format!("e_{}", wz.name),
                _ => format!("e_{}_{}", wa.name, wz.name),
            };
            let f = match (wa.kind, wz.kind) {
                (ElementKind::One, _) => format!("f_{}", wa.name),
                (_, ElementKind::One) => format!("f_{}", wz.name),
                _ => format!("f_{}_{}", wa.name, wz.name),
            };
            (e, f)
        };
        names[effort_var(b)] = e;
        names[flow_var(b)] = f;
    }
    names
}

fn node_error(model: &Model, n: NodeIndex, code: &'static str, msg: String) -> Diagnostic {
    let d = Diagnostic::error(code, msg);
    match model.spans.nodes.get(n.index()) {
        Some(span) => d.with_primary(*span, "this element"),
        None => d,
    }
}

/// The law of an element with a given left-hand side.
fn law(laws: &[Law], lhs: PortVar) -> Option<&Law> {
    laws.iter().find(|l| l.lhs == lhs)
}

/// Solves `known = g(unknown)` for `unknown` when `g` is affine in it.
fn invert(known: Expr, g: &Expr, unknown: Sym) -> Option<Expr> {
    let (a, b) = symbols::affine_in(g, unknown)?;
    if a.is_zero() {
        return None;
    }
    Some(div(symbols::sub(known, b), a))
}

/// Writes the definitions of every bond variable. Storages in derivative causality also record their energy
/// variable in `ctx.energy_expr` (done first, so that other laws may refer to it).
pub(crate) fn build(
    model: &Model,
    causality: &Causality,
    ctx: &mut Ctx,
    states: Vec<StateSpec>,
    diags: &mut Vec<Diagnostic>,
) -> Built {
    let nvars = 2 * model.graph.edge_count();
    let mut defs: Vec<Option<Def>> = vec![None; nvars];
    let mut definer = vec![None; nvars];
    // Energy variables of derivative storages.
    for s in causality.derivative() {
        let Some(w) = model.graph.node_weight(s.node) else {
            continue;
        };
        let Some((b, sign)) = ctx.port.get(s.node.index()).copied().flatten() else {
            continue;
        };
        let own_e = symbols::leaf(Sym::Var(effort_var(b)));
        let own_f = mul(vec![
            symbols::num(sign),
            symbols::leaf(Sym::Var(flow_var(b))),
        ]);
        let energy = match (&w.kind, &w.relation) {
            (ElementKind::I, Relation::Linear(i)) => {
                ctx.convert(i).map(|i| Some(mul(vec![i, own_f])))
            }
            (ElementKind::C, Relation::Linear(c)) => {
                ctx.convert(c).map(|c| Some(mul(vec![c, own_e])))
            }
            (ElementKind::I, Relation::Laws(laws)) => derivative_law(
                ctx,
                laws,
                PortVar::Momentum,
                PortVar::Flow,
                s.node,
                Sym::Var(flow_var(b)),
                sign,
            ),
            (ElementKind::C, Relation::Laws(laws)) => derivative_law(
                ctx,
                laws,
                PortVar::Displacement,
                PortVar::Effort,
                s.node,
                Sym::Var(effort_var(b)),
                1.0,
            ),
            _ => Ok(None),
        };
        match energy {
            Ok(Some(e)) => ctx.energy_expr[s.node.index()] = Some(e),
            Ok(None) => diags.push(node_error(
                model,
                s.node,
                codes::NOT_INVERTIBLE,
                format!(
                    "the law of `{}` cannot be written in derivative causality: its energy variable must be given as an explicit function of its {} (or by a law affine in it)",
                    w.name,
                    if w.kind == ElementKind::I { "flow" } else { "effort" }
                ),
            )),
            Err(ConvertError::Unsupported(what)) => diags.push(node_error(model, s.node, codes::UNSUPPORTED, format!("cannot write the equations of `{}`: {what}", w.name))),
        }
    }
    let nodes: Vec<NodeIndex> = model.graph.node_indices().collect();
    let shared: &Ctx = ctx;
    let results =
        crate::concurrent::map_halves(&nodes, |&node| node_defs(model, causality, shared, node));
    for (&node, result) in nodes.iter().zip(results) {
        match result {
            Ok(list) => {
                for (var, def) in list {
                    if let Some(slot) = defs.get_mut(var) {
                        *slot = Some(def);
                        definer[var] = Some(node);
                    }
                }
            }
            Err(d) => diags.push(d),
        }
    }
    let mut rates = Vec::new();
    let mut implicit_rows = vec![false; states.len()];
    for (i, st) in states.iter().enumerate() {
        if st.kind == StateKind::Velocity && st.port.is_none() {
            // The junction's effort balance: the massless inertia's effort, which must vanish.
            let bond = (0..ctx.node_state.len())
                .find(|&n| ctx.velocity[n] && ctx.node_state[n] == Some(i))
                .and_then(|n| ctx.port.get(n).copied().flatten());
            if let Some((b, _)) = bond {
                implicit_rows[i] = true;
                rates.push(symbols::leaf(Sym::Var(effort_var(b))));
                continue;
            }
        }
        let rate = match (st.kind, st.node, st.var) {
            (StateKind::Momentum, Some(n), _) => ctx
                .port
                .get(n.index())
                .copied()
                .flatten()
                .map(|(b, _)| symbols::leaf(Sym::Var(effort_var(b)))),
            (StateKind::Displacement, Some(n), _) => ctx
                .port
                .get(n.index())
                .copied()
                .flatten()
                .map(|(b, s)| mul(vec![symbols::num(s), symbols::leaf(Sym::Var(flow_var(b)))])),
            (StateKind::Integrated, _, Some(v)) => {
                match model.vars.get(v).map(|var| ctx.convert(&var.integrand)) {
                    Some(Ok(e)) => Some(e),
                    Some(Err(ConvertError::Unsupported(what))) => {
                        let d = Diagnostic::error(
                            codes::UNSUPPORTED,
                            format!("cannot integrate `{}`: {what}", st.name),
                        );
                        diags.push(match model.spans.vars.get(v) {
                            Some(span) => d.with_primary(*span, "this integrated flow"),
                            None => d,
                        });
                        None
                    }
                    None => None,
                }
            }
            _ => None,
        };
        rates.push(rate.unwrap_or(Expr::zero()));
    }
    let raw_names = names(model);
    let mut mass = Vec::new();
    for node in model.graph.node_indices() {
        if let Some(block) = super::field::rates(model, ctx, node, &mut rates, diags) {
            mass.push(block);
        }
    }
    Built {
        defs,
        definer,
        qualified: raw_names.iter().map(|n| n.contains('.')).collect(),
        names: raw_names.iter().map(|n| sanitize(n)).collect(),
        states,
        rates,
        mass,
        implicit_rows,
    }
}

/// The energy variable of a storage in derivative causality from its law: `energy = g(input)` directly, or the
/// other form inverted when affine.
fn derivative_law(
    ctx: &Ctx,
    laws: &[Law],
    energy: PortVar,
    input: PortVar,
    node: NodeIndex,
    own_input: Sym,
    sign: f64,
) -> Result<Option<Expr>, ConvertError> {
    if let Some(l) = law(laws, energy) {
        return ctx.convert(&l.rhs).map(Some);
    }
    let Some(l) = law(laws, input) else {
        return Ok(None);
    };
    // input = g(energy): the energy variable appears as a placeholder symbol while inverting.
    let placeholder = Sym::Tear(symbols::PLACEHOLDER);
    let mut c = Ctx {
        model: ctx.model,
        port: ctx.port.clone(),
        node_state: ctx.node_state.clone(),
        energy_expr: ctx.energy_expr.clone(),
        var_state: ctx.var_state.clone(),
        field_q: ctx.field_q.clone(),
        field_f: ctx.field_f.clone(),
        field_ports: ctx.field_ports.clone(),
        velocity: ctx.velocity.clone(),
    };
    c.energy_expr[node.index()] = Some(symbols::leaf(placeholder));
    let g = c.convert(&l.rhs)?;
    let known = mul(vec![symbols::num(sign), symbols::leaf(own_input)]);
    Ok(invert(known, &g, placeholder))
}

type DefList = Vec<(usize, Def)>;

/// The effort or the flow variable of a bond.
type VarOf = fn(EdgeIndex) -> usize;

/// The definitions one node writes.
fn node_defs(
    model: &Model,
    causality: &Causality,
    ctx: &Ctx,
    node: NodeIndex,
) -> Result<DefList, Diagnostic> {
    let w = &model.graph[node];
    let unsupported = |what: String| {
        node_error(
            model,
            node,
            codes::UNSUPPORTED,
            format!("cannot write the equations of `{}`: {what}", w.name),
        )
    };
    let conv = |e: &IrExpr| {
        ctx.convert(e)
            .map_err(|ConvertError::Unsupported(what)| unsupported(what))
    };
    let sets = |b: EdgeIndex| causality.sets_effort(model, node, b);
    let incident: Vec<(EdgeIndex, f64)> = model
        .graph
        .edges_directed(node, Direction::Incoming)
        .map(|e| (petgraph::visit::EdgeRef::id(&e), 1.0))
        .chain(
            model
                .graph
                .edges_directed(node, Direction::Outgoing)
                .map(|e| (petgraph::visit::EdgeRef::id(&e), -1.0)),
        )
        .collect();
    let e = |b: EdgeIndex| symbols::leaf(Sym::Var(effort_var(b)));
    let f = |b: EdgeIndex| symbols::leaf(Sym::Var(flow_var(b)));
    let mut out: DefList = Vec::new();
    match w.kind {
        ElementKind::Zero | ElementKind::One => {
            let zero = w.kind == ElementKind::Zero;
            // The strong bond of a 0-junction is the one it does not set the effort on; of a 1-junction the one it
            // sets the effort on.
            let strong: Vec<(EdgeIndex, f64)> = incident
                .iter()
                .copied()
                .filter(|&(b, _)| sets(b) != zero)
                .collect();
            let [(k, sk)] = strong[..] else {
                return Err(unsupported(format!(
                    "{} bonds determine its {}; exactly one must",
                    strong.len(),
                    if zero { "effort" } else { "flow" }
                )));
            };
            let (common, summed): (VarOf, VarOf) = if zero {
                (effort_var, flow_var)
            } else {
                (flow_var, effort_var)
            };
            let mut sum = Vec::new();
            for &(b, sb) in incident.iter().filter(|(b, _)| *b != k) {
                out.push((common(b), Def::Plain(symbols::leaf(Sym::Var(common(k))))));
                sum.push(mul(vec![
                    symbols::num(-sk * sb),
                    symbols::leaf(Sym::Var(summed(b))),
                ]));
            }
            out.push((summed(k), Def::Plain(add(sum))));
        }
        ElementKind::Se | ElementKind::MSe | ElementKind::Sf | ElementKind::MSf => {
            let Relation::Source(v) = &w.relation else {
                return Err(unsupported("a source without a value".into()));
            };
            let Some((b, s)) = ctx.port.get(node.index()).copied().flatten() else {
                return Err(unsupported("no bond".into()));
            };
            // The value is the source's own variable: its effort, or its flow out of it.
            let def = if matches!(w.kind, ElementKind::Se | ElementKind::MSe) {
                (effort_var(b), conv(v)?)
            } else {
                (flow_var(b), mul(vec![symbols::num(s), conv(v)?]))
            };
            out.push((def.0, Def::Plain(def.1)));
        }
        ElementKind::C | ElementKind::I | ElementKind::R => {
            let Some((b, s)) = ctx.port.get(node.index()).copied().flatten() else {
                return Err(unsupported("no bond".into()));
            };
            let sets_e = sets(b);
            let own_e = e(b);
            let own_f = mul(vec![symbols::num(s), f(b)]);
            match (w.kind, sets_e) {
                (ElementKind::C, true) => {
                    let q = ctx
                        .energy_of(node, "q")
                        .map_err(|ConvertError::Unsupported(what)| unsupported(what))?;
                    let def = match &w.relation {
                        Relation::Linear(c) => div(q, conv(c)?),
                        Relation::Laws(laws) => {
                            if let Some(l) = law(laws, PortVar::Effort) {
                                conv(&l.rhs)?
                            } else if let Some(l) = law(laws, PortVar::Displacement) {
                                invert(q, &conv(&l.rhs)?, Sym::Var(effort_var(b)))
                                    .ok_or_else(|| not_invertible(model, node, "q = g(e)", "e"))?
                            } else {
                                return Err(unsupported("no law for its effort".into()));
                            }
                        }
                        _ => {
                            return Err(unsupported("a storage without a constitutive law".into()));
                        }
                    };
                    out.push((effort_var(b), Def::Plain(def)));
                }
                (ElementKind::C, false) => {
                    let q = ctx
                        .energy_expr
                        .get(node.index())
                        .cloned()
                        .flatten()
                        .ok_or_else(|| unsupported("no energy variable".into()))?;
                    out.push((flow_var(b), Def::Rate(mul(vec![symbols::num(s), q]))));
                }
                (ElementKind::I, false) => {
                    let p = ctx
                        .energy_of(node, "p")
                        .map_err(|ConvertError::Unsupported(what)| unsupported(what))?;
                    if ctx.velocity.get(node.index()).copied().unwrap_or(false) {
                        // A velocity state: the state is the flow itself.
                        out.push((flow_var(b), Def::Plain(mul(vec![symbols::num(s), p]))));
                        return Ok(out);
                    }
                    let def = match &w.relation {
                        Relation::Linear(i) => div(p, conv(i)?),
                        Relation::Laws(laws) => {
                            if let Some(l) = law(laws, PortVar::Flow) {
                                conv(&l.rhs)?
                            } else if let Some(l) = law(laws, PortVar::Momentum) {
                                // p = g(f) with f = s·f_b: solve for s·f_b.
                                let g = conv(&l.rhs)?;
                                let fb = Sym::Var(flow_var(b));
                                let inv = invert(p, &g, fb)
                                    .ok_or_else(|| not_invertible(model, node, "p = g(f)", "f"))?;
                                // g was written in terms of s·f_b; inverting in f_b gives f_b itself.
                                out.push((flow_var(b), Def::Plain(inv)));
                                return Ok(out);
                            } else {
                                return Err(unsupported("no law for its flow".into()));
                            }
                        }
                        _ => {
                            return Err(unsupported("a storage without a constitutive law".into()));
                        }
                    };
                    out.push((flow_var(b), Def::Plain(mul(vec![symbols::num(s), def]))));
                }
                (ElementKind::I, true) => {
                    let p = ctx
                        .energy_expr
                        .get(node.index())
                        .cloned()
                        .flatten()
                        .ok_or_else(|| unsupported("no energy variable".into()))?;
                    out.push((effort_var(b), Def::Rate(p)));
                }
                (_, true) => {
                    // Resistance form: e = R f.
                    let def = match &w.relation {
                        Relation::Linear(r) => mul(vec![conv(r)?, own_f]),
                        Relation::Laws(laws) => {
                            if let Some(l) = law(laws, PortVar::Effort) {
                                conv(&l.rhs)?
                            } else if let Some(l) = law(laws, PortVar::Flow) {
                                let g = conv(&l.rhs)?;
                                invert(own_f, &g, Sym::Var(effort_var(b)))
                                    .ok_or_else(|| not_invertible(model, node, "f = g(e)", "e"))?
                            } else {
                                return Err(unsupported("no law".into()));
                            }
                        }
                        _ => return Err(unsupported("a resistor without a law".into())),
                    };
                    out.push((effort_var(b), Def::Plain(def)));
                }
                (_, false) => {
                    // Conductance form: f = e / R.
                    let def = match &w.relation {
                        Relation::Linear(r) => div(own_e, conv(r)?),
                        Relation::Laws(laws) => {
                            if let Some(l) = law(laws, PortVar::Flow) {
                                conv(&l.rhs)?
                            } else if let Some(l) = law(laws, PortVar::Effort) {
                                let g = conv(&l.rhs)?;
                                let fb = Sym::Var(flow_var(b));
                                // g is written in s·f_b; inverting in f_b gives f_b directly.
                                let inv = invert(own_e, &g, fb)
                                    .ok_or_else(|| not_invertible(model, node, "e = g(f)", "f"))?;
                                out.push((flow_var(b), Def::Plain(inv)));
                                return Ok(out);
                            } else {
                                return Err(unsupported("no law".into()));
                            }
                        }
                        _ => return Err(unsupported("a resistor without a law".into())),
                    };
                    out.push((flow_var(b), Def::Plain(mul(vec![symbols::num(s), def]))));
                }
            }
        }
        ElementKind::TF | ElementKind::MTF | ElementKind::GY | ElementKind::MGY => {
            let Relation::Modulus(m) = &w.relation else {
                return Err(unsupported("no modulus".into()));
            };
            let m = conv(m)?;
            let input = incident.iter().find(|(_, s)| *s > 0.0).map(|(b, _)| *b);
            let output = incident.iter().find(|(_, s)| *s < 0.0).map(|(b, _)| *b);
            let (Some(i), Some(o)) = (input, output) else {
                return Err(unsupported(
                    "a two-port needs one bond in and one bond out".into(),
                ));
            };
            let transformer = matches!(w.kind, ElementKind::TF | ElementKind::MTF);
            match (transformer, sets(o), sets(i)) {
                (true, true, false) => {
                    out.push((effort_var(o), Def::Plain(mul(vec![m.clone(), e(i)]))));
                    out.push((flow_var(i), Def::Plain(mul(vec![m, f(o)]))));
                }
                (true, false, true) => {
                    out.push((effort_var(i), Def::Plain(div(e(o), m.clone()))));
                    out.push((flow_var(o), Def::Plain(div(f(i), m))));
                }
                (false, true, true) => {
                    out.push((effort_var(i), Def::Plain(mul(vec![m.clone(), f(o)]))));
                    out.push((effort_var(o), Def::Plain(mul(vec![m, f(i)]))));
                }
                (false, false, false) => {
                    out.push((flow_var(o), Def::Plain(div(e(i), m.clone()))));
                    out.push((flow_var(i), Def::Plain(div(e(o), m))));
                }
                _ => {
                    return Err(unsupported(
                        "its two bonds have incompatible causalities".into(),
                    ));
                }
            }
        }
        ElementKind::CF | ElementKind::RF | ElementKind::IF => {
            return super::field::defs(model, causality, ctx, node);
        }
    }
    Ok(out)
}

fn not_invertible(model: &Model, node: NodeIndex, form: &str, unknown: &str) -> Diagnostic {
    let name = model
        .graph
        .node_weight(node)
        .map(|w| w.name.as_str())
        .unwrap_or("?");
    node_error(
        model,
        node,
        codes::NOT_INVERTIBLE,
        format!("the law `{form}` of `{name}` must be solved for {unknown} in this causality, and it is not affine in {unknown}"),
    )
    .with_help(format!("write the law of `{name}` in the other form, or give it a causality hint that matches its law"))
}
