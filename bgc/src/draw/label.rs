//! Element labels in the usual bond-graph style: `I:J_m`, `C:1/k_g`, `TF:r_g`, with the element's own name
//! underneath when it differs from the parameter expression.

use crate::ir::{Expr, Model, Node, Relation, Target};
use crate::syntax::ast::BinOp;
use petgraph::graph::{EdgeIndex, NodeIndex};

/// Expressions longer than this are replaced by the element's name in the label.
const MAX_EXPR: usize = 18;

/// The text lines of a node's label: the main line and an optional caption.
pub struct NodeLabel {
    pub main: String,
    pub caption: Option<String>,
}

/// The label of a node.
pub fn node_label(model: &Model, node: &Node) -> NodeLabel {
    if node.kind.is_junction() {
        return NodeLabel {
            main: node.kind.keyword().to_string(),
            caption: Some(node.name.clone()),
        };
    }
    let expr = match &node.relation {
        Relation::Source(e) | Relation::Linear(e) | Relation::Modulus(e) => {
            Some(expr_text(model, e, 0))
        }
        _ => None,
    };
    match expr {
        Some(text) if text.chars().count() <= MAX_EXPR => NodeLabel {
            main: format!("{}:{text}", node.kind.keyword()),
            caption: (text != node.name).then(|| node.name.clone()),
        },
        _ => NodeLabel {
            main: format!("{}:{}", node.kind.keyword(), node.name),
            caption: None,
        },
    }
}

fn binding(op: BinOp) -> u8 {
    match op {
        BinOp::Add | BinOp::Sub => 1,
        BinOp::Mul | BinOp::Div => 2,
        BinOp::Pow => 4,
    }
}

fn node_name(model: &Model, n: NodeIndex) -> String {
    model
        .graph
        .node_weight(n)
        .map_or_else(|| "?".to_string(), |w| w.name.clone())
}

fn target_name(model: &Model, t: &Target) -> String {
    match t {
        Target::Node(n) => node_name(model, *n),
        Target::Bond(e) => model.bond_name(EdgeIndex::new(e.index())),
    }
}

/// An expression as source-like text; `outer` is the binding strength of the context (to place parentheses).
pub fn expr_text(model: &Model, e: &Expr, outer: u8) -> String {
    let name = |v: Option<&String>| v.cloned().unwrap_or_else(|| "?".to_string());
    match e {
        Expr::Const(c) => format!("{c}"),
        Expr::Time => "t".to_string(),
        Expr::Param(i) => name(model.params.get(*i).map(|p| &p.name)),
        Expr::Input(i) => name(model.inputs.get(*i).map(|p| &p.name)),
        Expr::Output(i) => name(model.outputs.get(*i).map(|p| &p.name)),
        Expr::Var(i) => name(model.vars.get(*i).map(|p| &p.name)),
        Expr::Effort(t) => format!("e({})", target_name(model, t)),
        Expr::Flow(t) => format!("f({})", target_name(model, t)),
        Expr::Momentum(n) => format!("p({})", node_name(model, *n)),
        Expr::Displacement(n) => format!("q({})", node_name(model, *n)),
        Expr::FieldPort { node, var, port } => {
            let v = match var {
                crate::ir::PortVar::Effort => "e",
                crate::ir::PortVar::Flow => "f",
                crate::ir::PortVar::Momentum => "p",
                crate::ir::PortVar::Displacement => "q",
            };
            format!("{v}({})[{}]", node_name(model, *node), port + 1)
        }
        Expr::Neg(inner) => {
            // `-a*b` reads the same either way; only a power or a right operand needs the parentheses.
            let s = format!("-{}", expr_text(model, inner, 3));
            if outer > 2 { format!("({s})") } else { s }
        }
        Expr::Binary(op, a, b) => {
            let p = binding(*op);
            let sym = match op {
                BinOp::Add => "+",
                BinOp::Sub => "-",
                BinOp::Mul => "*",
                BinOp::Div => "/",
                BinOp::Pow => "^",
            };
            // Left-associative operators need parentheses on the right at equal strength; `^` on the left.
            let (lp, rp) = if *op == BinOp::Pow {
                (p + 1, p)
            } else {
                (p, p + 1)
            };
            let s = format!(
                "{}{sym}{}",
                expr_text(model, a, lp),
                expr_text(model, b, rp)
            );
            if p < outer { format!("({s})") } else { s }
        }
        Expr::Call(f, args) => {
            let a: Vec<String> = args.iter().map(|x| expr_text(model, x, 0)).collect();
            format!("{}({})", f.name(), a.join(", "))
        }
    }
}
