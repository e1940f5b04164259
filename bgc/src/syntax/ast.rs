//! The abstract syntax tree of a `.bg` file.
//!
//! The tree mirrors the source closely (nothing is resolved yet) so that the formatter can print it back and the
//! lowering stage can point at any piece of it. Every node that a diagnostic may name carries a [`Span`].

use crate::span::Span;
use serde::Serialize;

pub use super::short_list::ShortList;

/// A name as written, with its place.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

/// One parsed file.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct File {
    pub items: Vec<Item>,
    /// Ordinary `//` comments (and doc comments that document nothing), in source order, for the formatter.
    pub comments: Vec<Comment>,
    /// Byte offsets of blank lines, so the formatter can keep the author's paragraphs.
    pub blank_lines: Vec<u32>,
}

/// A `//` comment kept for the formatter; it has no meaning.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comment {
    /// The whole comment from its slashes, without the line break or trailing whitespace.
    pub text: String,
    pub span: Span,
    /// Nothing but whitespace precedes it on its line (otherwise it trails code).
    pub own_line: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Item {
    Import(Import),
    /// A `model` or a `component`: the same body, a different role.
    Model(ModelDecl),
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Import {
    /// The path as written, without quotes.
    pub path: String,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum ModelKind {
    Model,
    Component,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelDecl {
    pub kind: ModelKind,
    pub doc: Vec<String>,
    pub name: Ident,
    pub body: Vec<Stmt>,
    /// What the statements that failed to parse declared (their errors are reported): later stages leave
    /// references to these alone rather than call them unknown.
    #[serde(skip_serializing_if = "Unparsed::is_empty")]
    pub unparsed: Unparsed,
    /// From the keyword to the closing brace.
    pub span: Span,
}

/// The declarations of a body whose statements did not parse: the names they declared and whether one was a
/// `domain` statement.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Unparsed {
    pub names: Vec<Ident>,
    pub domain: bool,
    /// The names in `bond` statements that did not parse: the bonds of those nodes are not all known.
    pub bonded: Vec<Ident>,
}

impl Unparsed {
    pub fn is_empty(&self) -> bool {
        self.names.is_empty() && !self.domain && self.bonded.is_empty()
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum Stmt {
    Domain(Box<DomainStmt>),
    Param(Box<ParamDecl>),
    Input(Box<InputDecl>),
    Output(Box<OutputDecl>),
    Var(Box<VarDecl>),
    Coords(Box<CoordsDecl>),
    Element(Box<ElementDecl>),
    Instance(Box<InstanceDecl>),
    Bond(Box<BondStmt>),
    Port(Box<PortDecl>),
    Allow(Box<AllowDecl>),
}

impl Stmt {
    /// From the statement's first token (after its doc comments) to its `;` or closing `}`.
    pub fn span(&self) -> Span {
        match self {
            Stmt::Domain(x) => x.span,
            Stmt::Param(x) => x.span,
            Stmt::Input(x) => x.span,
            Stmt::Output(x) => x.span,
            Stmt::Var(x) => x.span,
            Stmt::Coords(x) => x.span,
            Stmt::Element(x) => x.span,
            Stmt::Instance(x) => x.span,
            Stmt::Bond(x) => x.span,
            Stmt::Port(x) => x.span,
            Stmt::Allow(x) => x.span,
        }
    }
}

impl Item {
    pub fn span(&self) -> Span {
        match self {
            Item::Import(x) => x.span,
            Item::Model(x) => x.span,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DomainStmt {
    pub domain: Ident,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParamDecl {
    pub doc: Vec<String>,
    pub name: Ident,
    pub default: Expr,
    pub unit: UnitExpr,
    pub description: Option<String>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InputDecl {
    pub doc: Vec<String>,
    pub name: Ident,
    pub unit: UnitExpr,
    pub description: Option<String>,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OutputDecl {
    pub doc: Vec<String>,
    pub name: Ident,
    pub unit: UnitExpr,
    pub value: Expr,
    pub description: Option<String>,
    pub span: Span,
}

/// `var theta [rad] = int(f(rotor));`: a named integrated flow.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VarDecl {
    pub doc: Vec<String>,
    pub name: Ident,
    pub unit: UnitExpr,
    /// The flow that is integrated (the argument of `int`).
    pub integrand: Expr,
    pub span: Span,
}

/// `coords [a, f(b), ...];`
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoordsDecl {
    pub coords: Vec<Expr>,
    pub span: Span,
}

/// The kind keyword of an element.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum ElementKind {
    Se,
    Sf,
    MSe,
    MSf,
    C,
    I,
    R,
    TF,
    GY,
    MTF,
    MGY,
    Zero,
    One,
    /// Multiport fields.
    CF,
    RF,
    IF,
}

impl ElementKind {
    /// The keyword as written in source.
    pub fn keyword(self) -> &'static str {
        match self {
            ElementKind::Se => "Se",
            ElementKind::Sf => "Sf",
            ElementKind::MSe => "MSe",
            ElementKind::MSf => "MSf",
            ElementKind::C => "C",
            ElementKind::I => "I",
            ElementKind::R => "R",
            ElementKind::TF => "TF",
            ElementKind::GY => "GY",
            ElementKind::MTF => "MTF",
            ElementKind::MGY => "MGY",
            ElementKind::Zero => "0",
            ElementKind::One => "1",
            ElementKind::CF => "CF",
            ElementKind::RF => "RF",
            ElementKind::IF => "IF",
        }
    }

    /// The keyword with its indefinite article, as it is read aloud: "an `R`", "a `C`", "an `MTF`".
    pub fn with_article(self) -> String {
        let vowel_sound = matches!(
            self,
            ElementKind::Se
                | ElementKind::Sf
                | ElementKind::MSe
                | ElementKind::MSf
                | ElementKind::I
                | ElementKind::R
                | ElementKind::MTF
                | ElementKind::MGY
                | ElementKind::RF
                | ElementKind::IF
        );
        let article = if vowel_sound { "an" } else { "a" };
        format!("{article} `{}`", self.keyword())
    }

    /// Parses a kind keyword.
    pub fn from_keyword(s: &str) -> Option<Self> {
        Some(match s {
            "Se" => ElementKind::Se,
            "Sf" => ElementKind::Sf,
            "MSe" => ElementKind::MSe,
            "MSf" => ElementKind::MSf,
            "C" => ElementKind::C,
            "I" => ElementKind::I,
            "R" => ElementKind::R,
            "TF" => ElementKind::TF,
            "GY" => ElementKind::GY,
            "MTF" => ElementKind::MTF,
            "MGY" => ElementKind::MGY,
            "0" => ElementKind::Zero,
            "1" => ElementKind::One,
            "CF" => ElementKind::CF,
            "RF" => ElementKind::RF,
            "IF" => ElementKind::IF,
            _ => return None,
        })
    }

    pub fn is_field(self) -> bool {
        matches!(self, ElementKind::CF | ElementKind::RF | ElementKind::IF)
    }

    pub fn is_junction(self) -> bool {
        matches!(self, ElementKind::Zero | ElementKind::One)
    }

    pub fn is_two_port(self) -> bool {
        matches!(
            self,
            ElementKind::TF | ElementKind::GY | ElementKind::MTF | ElementKind::MGY
        )
    }
}

/// `KIND NAME[(n)] [: DOMAIN] [= EXPR | { LAW; ... }];`
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ElementDecl {
    pub doc: Vec<String>,
    pub kind: ElementKind,
    pub kind_span: Span,
    pub name: Ident,
    /// The port count of a field, `IF leg(3)`.
    pub ports: Option<(u32, Span)>,
    pub domain: Option<Ident>,
    pub body: ElementBody,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ElementBody {
    /// A junction or an element without a parameter.
    None,
    /// `= EXPR`: the linear parameter, source value or modulus.
    Value(Expr),
    /// `{ LHS = EXPR; ... }`: constitutive laws.
    Laws(Vec<Law>),
}

/// `e = b0*sign(f)`, `e[1] = ...`, `mass[1,2] = ...`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Law {
    /// The variable on the left: `e`, `f`, `p`, `q` or `mass`.
    pub lhs: Ident,
    /// Indices on the left (`e[1]` has one, `mass[1,2]` two), 1-based as written.
    pub indices: Vec<(u32, Span)>,
    pub rhs: Expr,
    pub span: Span,
}

/// `COMPONENT INSTANCE(p = EXPR, ...);`
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InstanceDecl {
    pub doc: Vec<String>,
    pub component: Ident,
    pub name: Ident,
    pub overrides: Vec<(Ident, Expr)>,
    pub span: Span,
}

/// `allow BG0510 gear_in "the gear's input inertia moves with the rotor";`: a finding of the analysis that the
/// model intends, acknowledged at the element it concerns.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AllowDecl {
    /// The diagnostic code (`BG0510`).
    pub code: Ident,
    /// The element (or junction) the finding is located at.
    pub target: NodeRef,
    /// Why it is intended.
    pub reason: Option<String>,
    pub span: Span,
}

/// `port a = j;`
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PortDecl {
    pub name: Ident,
    pub target: NodeRef,
    pub span: Span,
}

/// A reference to a node in a bond: `j1`, `inst.port`, `field[2]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NodeRef {
    /// `inst.port` has two parts; deeper nesting is allowed (`a.b.c`).
    pub path: ShortList<Ident>,
    /// `field[i]`, 1-based as written.
    pub port: Option<(u32, Span)>,
    pub span: Span,
}

/// `bond [NAME:] a -> b -> c, d [stroke[!] NODE];`
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BondStmt {
    pub label: Option<Ident>,
    /// The chain: each entry is joined to the next by an arrow. All but the last have exactly one node.
    pub chain: Vec<ShortList<NodeRef>>,
    pub hint: Option<CausalHint>,
    /// The chain has a fan-out before its end (BG0110, reported): which bonds it meant is unknown, so it makes none.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub malformed: bool,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CausalHint {
    /// Where the causal stroke goes.
    pub at: NodeRef,
    /// `stroke!`: a requirement rather than a preference.
    pub fixed: bool,
    pub span: Span,
}

/// A unit as written: `[N m/rad]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct UnitExpr {
    /// Factors of the numerator, `(symbol, power)`, e.g. `("m", 2)`.
    pub numerator: Vec<(String, i32)>,
    pub denominator: Vec<(String, i32)>,
    pub span: Span,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub enum ExprKind {
    Number(f64),
    /// A bare name: parameter, input, output, var, `pi`, `t`, or (inside laws) `e`, `f`, `p`, `q`.
    Name(String),
    /// `name[i]` inside field laws: `e[1]`, `q[2]`.
    Indexed(String, u32),
    /// `e(x)`, `f(x)`, `p(x)`, `q(x)` and function calls such as `sin(x)`, `atan2(y, x)`, `int(f(x))`.
    /// Arguments of `e`/`f`/`p`/`q` that name nodes are parsed as [`ExprKind::Node`].
    Call(Ident, Vec<Expr>),
    /// A node named as an argument of `e`, `f`, `p` or `q`: `sensor.spring`, `leg[2]`.
    Node(NodeRef),
    Neg(Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
}
