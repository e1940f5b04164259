//! The bond-graph IR: what the lowering stage produces and every later stage reads.
//!
//! A [`Model`] is a flat (components already expanded) directed graph: nodes are elements and junctions, edges are
//! bonds pointing in the direction of positive power. Names are resolved: expressions refer to parameters, inputs and
//! nodes by index. Source places live in a side table ([`SpanTable`]) beside the graph, as naga keeps spans beside
//! its arena, so that stages that do not report errors never see them.
//!
//! Invariants established by lowering (checked by `lower::validate` in debug builds and by tests):
//! - every node has the bond count its kind requires (1-ports one, TF/GY one in and one out, junctions at least two,
//!   an n-port field n, each on a distinct port);
//! - every bond has one resolved domain, and both its ends agree with it;
//! - every expression's names resolve, and its unit is consistent;
//! - `spans` has an entry for every node, bond, parameter, input, output and var.

mod coefficient;

pub use coefficient::{CoefficientFault, coefficient_fault};

use crate::span::Span;
use crate::syntax::ast::{BinOp, ElementKind};
use crate::units::Unit;
use petgraph::graph::{DiGraph, EdgeIndex, NodeIndex};
use serde::Serialize;

pub type ParamId = usize;
pub type InputId = usize;
pub type OutputId = usize;
pub type VarId = usize;

/// An energy domain. See the table in docs/language.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Domain {
    Translational,
    Rotational,
    Electrical,
    Hydraulic,
    Thermal,
}

impl Domain {
    pub const ALL: [Domain; 5] = [
        Domain::Translational,
        Domain::Rotational,
        Domain::Electrical,
        Domain::Hydraulic,
        Domain::Thermal,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Domain::Translational => "translational",
            Domain::Rotational => "rotational",
            Domain::Electrical => "electrical",
            Domain::Hydraulic => "hydraulic",
            Domain::Thermal => "thermal",
        }
    }

    pub fn from_name(s: &str) -> Option<Domain> {
        Domain::ALL.into_iter().find(|d| d.name() == s)
    }
}

/// The functions an expression may call.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    Exp,
    Ln,
    Log10,
    Sqrt,
    Abs,
    Sign,
    Min,
    Max,
    Tanh,
    Sinh,
    Cosh,
}

impl Func {
    pub const ALL: [Func; 18] = [
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Atan2,
        Func::Exp,
        Func::Ln,
        Func::Log10,
        Func::Sqrt,
        Func::Abs,
        Func::Sign,
        Func::Min,
        Func::Max,
        Func::Tanh,
        Func::Sinh,
        Func::Cosh,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Atan2 => "atan2",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Log10 => "log10",
            Func::Sqrt => "sqrt",
            Func::Abs => "abs",
            Func::Sign => "sign",
            Func::Min => "min",
            Func::Max => "max",
            Func::Tanh => "tanh",
            Func::Sinh => "sinh",
            Func::Cosh => "cosh",
        }
    }

    pub fn from_name(s: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == s)
    }

    pub fn arity(self) -> usize {
        match self {
            Func::Atan2 | Func::Min | Func::Max => 2,
            _ => 1,
        }
    }

    /// The function applied to numbers (`None` when an argument is missing). The plain `f64` functions of the
    /// standard library: constant folding of the IR and the equations stage share this one definition.
    pub fn eval(self, a: &[f64]) -> Option<f64> {
        let x = *a.first()?;
        let y = a.get(1).copied();
        Some(match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Asin => x.asin(),
            Func::Acos => x.acos(),
            Func::Atan => x.atan(),
            Func::Atan2 => x.atan2(y?),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Log10 => x.log10(),
            Func::Sqrt => x.sqrt(),
            Func::Abs => x.abs(),
            Func::Sign => {
                if x > 0.0 {
                    1.0
                } else if x < 0.0 {
                    -1.0
                } else {
                    0.0
                }
            }
            Func::Min => x.min(y?),
            Func::Max => x.max(y?),
            Func::Tanh => x.tanh(),
            Func::Sinh => x.sinh(),
            Func::Cosh => x.cosh(),
        })
    }
}

/// What an effort or flow reference points at.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Target {
    /// A 1-port element's own variable, a 0-junction's common effort or a 1-junction's common flow.
    Node(#[serde(serialize_with = "ser_node")] NodeIndex),
    Bond(#[serde(serialize_with = "ser_edge")] EdgeIndex),
}

/// The power and energy variables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PortVar {
    Effort,
    Flow,
    Momentum,
    Displacement,
}

/// A resolved expression.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Expr {
    Const(f64),
    /// Time `t`.
    Time,
    Param(ParamId),
    Input(InputId),
    Output(OutputId),
    Var(VarId),
    Effort(Target),
    Flow(Target),
    /// `p(x)` of an inertia.
    Momentum(#[serde(serialize_with = "ser_node")] NodeIndex),
    /// `q(x)` of a compliance.
    Displacement(#[serde(serialize_with = "ser_node")] NodeIndex),
    /// A port variable of a multiport field inside its laws: `e[2]` of node `node` is
    /// `FieldPort { node, var: Effort, port: 1 }` (0-based port). Outside the laws, `q(leg[2])` (the integral of
    /// the flow on port 2) is `FieldPort { var: Displacement, .. }`; `e(leg[2])` and `f(leg[2])` are the effort and
    /// flow of the bond on that port (`Target::Bond`).
    FieldPort {
        #[serde(serialize_with = "ser_node")]
        node: NodeIndex,
        var: PortVar,
        port: u32,
    },
    Neg(Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    Call(Func, Vec<Expr>),
}

/// One constitutive law of an element: `lhs = rhs`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Law {
    /// The variable on the left.
    pub lhs: PortVar,
    /// The port (0-based) for fields; 0 for 1-ports.
    pub port: u32,
    pub rhs: Expr,
}

/// How an element relates its port variables.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Relation {
    /// Junctions.
    Junction,
    /// `Se`/`MSe`: `e = value`; `Sf`/`MSf`: `f = value`.
    Source(Expr),
    /// `C`: `q = value * e`; `I`: `p = value * f`; `R`: `e = value * f`.
    Linear(Expr),
    /// `TF`/`MTF`/`GY`/`MGY` modulus (conventions in docs/language.md).
    Modulus(Expr),
    /// Nonlinear laws of C, I, R and of CF, RF.
    Laws(Vec<Law>),
    /// `IF`: the inertia matrix `M(q)`, full and symmetric, row-major, `n × n`.
    MassMatrix { n: u32, entries: Vec<Expr> },
}

/// A node of the bond graph.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Node {
    /// The qualified name: `sensor.spring` for the element `spring` of instance `sensor`.
    pub name: String,
    pub kind: ElementKind,
    pub relation: Relation,
    /// Number of ports: 1 for 1-ports, 2 for TF/GY, n for fields, 0 for junctions (any number of bonds).
    pub ports: u32,
    pub doc: Vec<String>,
}

/// A causality hint attached to a bond.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Hint {
    /// True when the stroke is at the bond's `to` end.
    pub stroke_at_to: bool,
    pub fixed: bool,
}

/// A bond: power flows from its source node to its target node.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bond {
    /// The user's label, if the bond is named.
    pub name: Option<String>,
    /// The port of the `from` node this bond attaches to (0-based; 0 for 1-ports and junctions; for TF/GY the
    /// output port is 1).
    pub from_port: u32,
    /// The port of the `to` node (for TF/GY the input port is 0).
    pub to_port: u32,
    pub domain: Domain,
    pub hint: Option<Hint>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Param {
    pub name: String,
    /// The default value in SI base units (a default written as a plain number in `[rpm]` is converted:
    /// `unit.scale` times the written value).
    pub default: f64,
    /// The declared unit; `unit.scale` converts a value in it to SI.
    pub unit: Unit,
    /// The unit as the user wrote it, for messages and generated docs.
    pub unit_text: String,
    pub description: Option<String>,
    pub doc: Vec<String>,
    /// For a parameter whose default (or instance override) refers to other parameters: that expression, in SI
    /// units. Such a parameter is derived: its value follows the parameters it refers to (see
    /// `Equations::param_values`).
    pub derived: Option<Expr>,
}

/// An input. Its values are in its declared unit; expressions use it as `Const(unit.scale) * Input(id)`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Input {
    pub name: String,
    pub unit: Unit,
    pub unit_text: String,
    pub description: Option<String>,
}

/// An output, in its declared unit: `value` is the SI expression divided by `unit.scale`, and an expression that
/// uses the output multiplies it back.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Output {
    pub name: String,
    pub unit: Unit,
    pub unit_text: String,
    pub value: Expr,
    pub description: Option<String>,
}

/// A named integrated flow: `var theta = int(f(x))`. Its state is in its declared unit (`integrand` is the flow
/// divided by `unit.scale`); an expression that uses it multiplies it back.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Var {
    pub name: String,
    pub unit: Unit,
    pub unit_text: String,
    /// A flow expression, in the declared unit per second.
    pub integrand: Expr,
}

/// Source places of everything in a [`Model`], indexed like the model's vectors and graph.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SpanTable {
    /// The declaration of each node (by `NodeIndex::index()`).
    pub nodes: Vec<Span>,
    /// The name of each node in its declaration.
    pub node_names: Vec<Span>,
    /// The parameter or law expression of each node, when it has one.
    pub node_relations: Vec<Option<Span>>,
    /// The arrow of each bond (by `EdgeIndex::index()`), from its tail name to its head name.
    pub bonds: Vec<Span>,
    pub params: Vec<Span>,
    pub inputs: Vec<Span>,
    pub outputs: Vec<Span>,
    pub vars: Vec<Span>,
    pub coords: Vec<Span>,
    /// For nodes that come from a component instance: the instance declaration.
    pub node_instances: Vec<Option<Span>>,
    pub model: Span,
    /// The findings the model acknowledges as intended (`allow CODE NODE;`); the analyses leave them out.
    pub allowed: Vec<Allowance>,
}

impl Expr {
    /// The value of an expression of constants and parameters, with the parameters' values from `param`; `None`
    /// when it uses anything else (a state, an input, `t`) or a parameter without a value.
    pub fn eval_const(&self, param: &dyn Fn(ParamId) -> Option<f64>) -> Option<f64> {
        Some(match self {
            Expr::Const(v) => *v,
            Expr::Param(id) => param(*id)?,
            Expr::Neg(a) => -a.eval_const(param)?,
            Expr::Binary(op, a, b) => {
                let (a, b) = (a.eval_const(param)?, b.eval_const(param)?);
                match op {
                    BinOp::Add => a + b,
                    BinOp::Sub => a - b,
                    BinOp::Mul => a * b,
                    BinOp::Div => a / b,
                    BinOp::Pow => a.powf(b),
                }
            }
            Expr::Call(f, args) => {
                let vals = args
                    .iter()
                    .map(|a| a.eval_const(param))
                    .collect::<Option<Vec<_>>>()?;
                f.eval(&vals)?
            }
            _ => return None,
        })
    }
}

/// A lowered, checked model. Parameter defaults and the constants of expressions are in SI base units; a declared
/// unit's `scale` converts a value written in that unit to SI. Inputs, outputs and vars are in their declared
/// units (the conversions are in the expressions).
#[derive(Clone, Debug, Serialize)]
pub struct Model {
    pub name: String,
    pub doc: Vec<String>,
    #[serde(serialize_with = "ser_graph")]
    pub graph: DiGraph<Node, Bond>,
    pub params: Vec<Param>,
    pub inputs: Vec<Input>,
    pub outputs: Vec<Output>,
    pub vars: Vec<Var>,
    /// Declared state coordinates, if any.
    pub coords: Option<Vec<Expr>>,
    pub spans: SpanTable,
}

/// `allow CODE NODE;`: the finding `code` located at node `node` (by `NodeIndex::index()`) is intended.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Allowance {
    pub code: String,
    pub node: usize,
    /// The `allow` statement.
    pub span: Span,
}

impl Model {
    /// Its size in words, as `check` and the editor's hover say it: "5 elements and junctions, 4 bonds, 3
    /// parameters" (in the singular for one).
    pub fn size_in_words(&self) -> String {
        let counted =
            |n: usize, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        format!(
            "{}, {}, {}",
            counted(
                self.graph.node_count(),
                "element or junction",
                "elements and junctions"
            ),
            counted(self.graph.edge_count(), "bond", "bonds"),
            counted(self.params.len(), "parameter", "parameters")
        )
    }

    /// The node with this qualified name.
    pub fn node_by_name(&self, name: &str) -> Option<NodeIndex> {
        self.graph
            .node_indices()
            .find(|&i| self.graph[i].name == name)
    }

    pub fn param_by_name(&self, name: &str) -> Option<ParamId> {
        self.params.iter().position(|p| p.name == name)
    }

    pub fn input_by_name(&self, name: &str) -> Option<InputId> {
        self.inputs.iter().position(|p| p.name == name)
    }

    /// A readable name for a bond: its label, or `from->to`.
    pub fn bond_name(&self, e: EdgeIndex) -> String {
        let Some((a, b)) = self.graph.edge_endpoints(e) else {
            return format!("bond#{}", e.index());
        };
        match &self.graph[e].name {
            Some(n) => n.clone(),
            None => format!("{}->{}", self.graph[a].name, self.graph[b].name),
        }
    }
}

fn ser_node<S: serde::Serializer>(n: &NodeIndex, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(n.index() as u64)
}

fn ser_edge<S: serde::Serializer>(e: &EdgeIndex, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_u64(e.index() as u64)
}

fn ser_graph<S: serde::Serializer>(g: &DiGraph<Node, Bond>, s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    #[derive(Serialize)]
    struct Edge<'a> {
        from: usize,
        to: usize,
        bond: &'a Bond,
    }
    let nodes: Vec<&Node> = g.node_weights().collect();
    let edges: Vec<Edge> = g
        .edge_indices()
        .filter_map(|e| {
            let (a, b) = g.edge_endpoints(e)?;
            Some(Edge {
                from: a.index(),
                to: b.index(),
                bond: &g[e],
            })
        })
        .collect();
    let mut st = s.serialize_struct("Graph", 2)?;
    st.serialize_field("nodes", &nodes)?;
    st.serialize_field("bonds", &edges)?;
    st.end()
}
