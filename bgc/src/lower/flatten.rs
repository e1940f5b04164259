//! Flattening: a model and, recursively, its component instances become one list of parameters, inputs, nodes and
//! bonds with qualified names (`sensor.spring`, `sensor.k`).
//!
//! Each body is read in passes so that declarations may come in any order: first the domain, parameters (in order:
//! a default may use earlier parameters), inputs, outputs and vars; then elements and instances; then bonds; then
//! ports and coordinates. Component parameters become model parameters named `instance.param` whose default is the
//! instance's override (an expression of the enclosing scope's parameters, evaluated now) or the declared default.

use super::builder::{Builder, NodeInfo, ParamInfo};
use super::consteval::eval;
use super::exprs::{Allow, Cx, Q};
use super::scope::{Entity, Scope, duplicate};
use crate::diagnostic::Diagnostic;
use crate::diagnostic::suggest::closest;
use crate::ir::{self, Domain};
use crate::syntax::ast::{self, ElementKind, Ident, InstanceDecl, ModelDecl, ModelKind, Stmt};
use crate::units::{Unit, parse_unit, unit_text};

/// How deep components may nest. Real models nest a handful of levels; the bound keeps the recursive flattening
/// (and every later walk over qualified names) far from the end of the stack.
pub(crate) const MAX_NESTING: usize = 100;
/// How many component instances one model may expand to. Two instances per level double the model at each level,
/// so a short file could otherwise ask for billions of elements.
pub(crate) const MAX_INSTANCES: usize = 100_000;

/// The most ports a field may have. An I-field's mass matrix has a symbolic entry per pair of ports, and every
/// port needs its own bond, so a larger count is a typing mistake, not a model.
pub(crate) const MAX_FIELD_PORTS: usize = 1000;

/// The overrides of an instance, to be evaluated in the enclosing scope.
pub(crate) struct Overrides<'a> {
    pub instance: &'a InstanceDecl,
    pub parent: usize,
}

impl<'a> Builder<'a> {
    /// Flattens `decl` into the model under construction; returns the index of its scope.
    pub fn instantiate(
        &mut self,
        decl: &'a ModelDecl,
        prefix: String,
        overrides: Option<Overrides<'a>>,
    ) -> usize {
        let instance_span = overrides.as_ref().map(|o| {
            // The outermost instance is what the model's author sees.
            self.scopes
                .get(o.parent)
                .and_then(|s| s.instance_span)
                .unwrap_or(o.instance.span)
        });
        let component = match decl.kind {
            ModelKind::Component => Some((decl.name.name.clone(), decl.name.span)),
            ModelKind::Model => None,
        };
        self.scopes.push(Scope {
            prefix,
            component,
            instance_span,
            own_instance: overrides.as_ref().map(|o| o.instance.span),
            ..Default::default()
        });
        let sid = self.scopes.len() - 1;
        let scope = &mut self.scopes[sid];
        scope
            .unparsed
            .extend(decl.unparsed.names.iter().map(|n| (n.name.as_str(), ())));
        self.domain_reported |= decl.unparsed.domain;
        // A parameter used only by a statement that did not parse is not "unused".
        self.unmatched_name |= !decl.unparsed.names.is_empty();
        // One table of the right size rather than one that rehashes its way up to a hundred thousand names.
        let declared = decl.body.iter().filter(|s| declares_name(s)).count();
        self.scopes[sid].names.reserve(declared);
        if let Some(o) = &overrides {
            self.check_override_names(decl, o.instance);
        }
        // Pass 1: domain, parameters, inputs, outputs, vars.
        for stmt in &decl.body {
            match stmt {
                Stmt::Domain(d) => self.domain_stmt(sid, d),
                Stmt::Param(p) => self.param(sid, p, overrides.as_ref()),
                Stmt::Input(i) => {
                    let (unit, text) = self.unit(&i.unit);
                    let id = self.model.inputs.len();
                    let _ = self.declare(sid, &i.name, Entity::Input(id));
                    if !self.last_unit_ok {
                        self.bad_units.push(Entity::Input(id));
                    }
                    self.model.inputs.push(ir::Input {
                        name: self.qualified(sid, &i.name.name),
                        unit,
                        unit_text: text,
                        description: i.description.clone(),
                    });
                    self.model.spans.inputs.push(i.span);
                }
                Stmt::Output(o) => {
                    let (unit, text) = self.unit(&o.unit);
                    let id = self.model.outputs.len();
                    let _ = self.declare(sid, &o.name, Entity::Output(id));
                    if !self.last_unit_ok {
                        self.bad_units.push(Entity::Output(id));
                    }
                    self.model.outputs.push(ir::Output {
                        name: self.qualified(sid, &o.name.name),
                        unit,
                        unit_text: text,
                        value: ir::Expr::Const(0.0),
                        description: o.description.clone(),
                    });
                    self.model.spans.outputs.push(o.span);
                    self.pending_outputs.push((id, sid, o));
                }
                Stmt::Var(v) => {
                    let (unit, text) = self.unit(&v.unit);
                    let id = self.model.vars.len();
                    let _ = self.declare(sid, &v.name, Entity::Var(id));
                    if !self.last_unit_ok {
                        self.bad_units.push(Entity::Var(id));
                    }
                    self.model.vars.push(ir::Var {
                        name: self.qualified(sid, &v.name.name),
                        unit,
                        unit_text: text,
                        integrand: ir::Expr::Const(0.0),
                    });
                    self.model.spans.vars.push(v.span);
                    self.pending_vars.push((id, sid, v));
                }
                _ => {}
            }
        }
        // Pass 2: elements and instances.
        for stmt in &decl.body {
            match stmt {
                Stmt::Element(e) => self.element(sid, e),
                Stmt::Instance(i) => self.instance(sid, i),
                _ => {}
            }
        }
        // Pass 3: bonds.
        for stmt in &decl.body {
            if let Stmt::Bond(b) = stmt {
                self.bond_stmt(sid, b);
            }
        }
        // The nodes of bond statements that did not parse lack those bonds: their counts follow from that error.
        for name in &decl.unparsed.bonded {
            match self.scopes[sid].get(&name.name) {
                Some(Entity::Node(n)) => {
                    self.suspect_nodes.insert(n);
                }
                Some(Entity::Instance(child)) => self.scopes[child].connected = true,
                _ => {}
            }
        }
        // Pass 4: ports and coordinates.
        for stmt in &decl.body {
            match stmt {
                Stmt::Port(p) => {
                    if decl.kind == ModelKind::Model {
                        self.diags.push(
                            Diagnostic::error("BG0313", "a model has no ports")
                                .with_primary(p.span, "a port in a model")
                                .with_help("ports belong to components; write `component` to make this reusable"),
                        );
                        continue;
                    }
                    let Some(end) = self.resolve_end(sid, &p.target) else {
                        continue;
                    };
                    let scope = &mut self.scopes[sid];
                    if let Some((_, first)) = scope.ports.get(&p.name.name) {
                        let d = duplicate(&p.name.name, p.name.span, *first);
                        self.diags.push(d);
                    } else {
                        scope.ports.insert(p.name.name.clone(), (end, p.name.span));
                        scope.port_order.push(p.name.name.clone());
                    }
                }
                Stmt::Allow(a) => self.allow(sid, a),
                Stmt::Coords(c) => {
                    if decl.kind == ModelKind::Component {
                        self.diags.push(
                            Diagnostic::error(
                                "BG0313",
                                "a component cannot declare state coordinates",
                            )
                            .with_primary(c.span, "coordinates in a component")
                            .with_help("declare `coords` in the model that uses the component"),
                        );
                    } else if let Some((_, first)) = self.pending_coords {
                        self.diags.push(
                            Diagnostic::error("BG0202", "state coordinates are declared twice")
                                .with_primary(c.span, "declared again here")
                                .with_secondary(first.span, "first declared here")
                                .with_help("keep one `coords` list"),
                        );
                    } else {
                        self.pending_coords = Some((sid, c));
                    }
                }
                _ => {}
            }
        }
        sid
    }

    pub fn qualified(&self, sid: usize, name: &str) -> String {
        match self.scopes.get(sid) {
            Some(s) => {
                // Called for every declaration: joined by hand, without the formatting machinery.
                let mut q = String::with_capacity(s.prefix.len() + name.len());
                q.push_str(&s.prefix);
                q.push_str(name);
                q
            }
            None => name.to_string(),
        }
    }

    /// Declares a name in a scope; false (with BG0202 reported) when it is already taken.
    pub(super) fn declare(&mut self, sid: usize, name: &'a Ident, entity: Entity) -> bool {
        if let Some(scope) = self.scopes.get_mut(sid)
            && let Err(d) = scope.declare(&name.name, name.span, entity)
        {
            self.diags.push(d);
            return false;
        }
        true
    }

    /// Parses a unit, reporting an unknown symbol (BG0312); a bad unit reads as `[1]` afterwards.
    pub fn unit(&mut self, u: &ast::UnitExpr) -> (Unit, String) {
        let text = unit_text(u);
        match parse_unit(u) {
            Ok(unit) => {
                self.last_unit_ok = true;
                (unit, text)
            }
            // A symbol with letters outside ASCII (`[kΩ]`) is already an error of its own (BG0104, with the ASCII
            // spelling).
            Err(crate::units::UnitError::UnknownSymbol { symbol })
                if crate::syntax::foreign::reported_by_lexer(&symbol) =>
            {
                self.last_unit_ok = false;
                (Unit::ONE, text)
            }
            Err(err) => {
                let mut d = Diagnostic::error("BG0312", format!("{err} in `[{text}]`"))
                    .with_primary(u.span, err.to_string());
                if let crate::units::UnitError::UnknownSymbol { symbol } = &err {
                    d = d.with_help(crate::units::unknown_symbol_help(symbol));
                }
                self.diags.push(d);
                self.last_unit_ok = false;
                (Unit::ONE, text)
            }
        }
    }

    fn domain_stmt(&mut self, sid: usize, d: &ast::DomainStmt) {
        let Some(domain) = self.domain_name(&d.domain) else {
            return;
        };
        let scope = &mut self.scopes[sid];
        if let Some((_, first)) = scope.default_domain {
            self.diags.push(
                Diagnostic::error("BG0202", "the default domain is set twice")
                    .with_primary(d.span, "set again here")
                    .with_secondary(first, "first set here")
                    .with_help(
                        "keep one `domain` statement; give other elements their own `: DOMAIN`",
                    ),
            );
        } else {
            scope.default_domain = Some((domain, d.span));
        }
    }

    /// A domain name, or BG0201 with a suggestion.
    pub fn domain_name(&mut self, name: &Ident) -> Option<Domain> {
        let found = Domain::from_name(&name.name);
        if found.is_none() {
            let names = Domain::ALL.map(Domain::name);
            let help = match closest(&name.name, names.into_iter()) {
                Some(c) => format!("did you mean `{c}`?"),
                None => format!("the domains are {}", names.join(", ")),
            };
            self.domain_reported = true;
            self.diags.push(
                Diagnostic::error("BG0201", format!("unknown domain `{}`", name.name))
                    .with_primary(name.span, "not a domain")
                    .with_help(help),
            );
        }
        found
    }

    fn check_override_names(&mut self, decl: &ModelDecl, inst: &InstanceDecl) {
        let params: Vec<&str> = decl
            .body
            .iter()
            .filter_map(|s| match s {
                Stmt::Param(p) => Some(p.name.name.as_str()),
                _ => None,
            })
            .collect();
        for (i, (name, _)) in inst.overrides.iter().enumerate() {
            if let Some((first, _)) = inst.overrides[..i]
                .iter()
                .find(|(n, _)| n.name == name.name)
            {
                self.diags
                    .push(duplicate(&name.name, name.span, first.span));
                continue;
            }
            if params.contains(&name.name.as_str()) {
                continue;
            }
            let help = match closest(&name.name, params.iter().copied()) {
                Some(c) => format!("did you mean `{c}`?"),
                None if params.is_empty() => format!("`{}` has no parameters", decl.name.name),
                None => format!(
                    "the parameters of `{}` are: {}",
                    decl.name.name,
                    params.join(", ")
                ),
            };
            self.diags.push(
                Diagnostic::error(
                    "BG0206",
                    format!(
                        "component `{}` has no parameter `{}`",
                        decl.name.name, name.name
                    ),
                )
                .with_primary(name.span, "no such parameter")
                .with_secondary(decl.name.span, "component declared here")
                .with_help(help),
            );
        }
    }

    fn param(&mut self, sid: usize, p: &'a ast::ParamDecl, overrides: Option<&Overrides<'a>>) {
        let (unit, text) = self.unit(&p.unit);
        let unit_ok = self.last_unit_ok;
        if !unit_ok {
            self.bad_units.push(Entity::Param(self.model.params.len()));
        }
        let over = overrides.and_then(|o| {
            o.instance
                .overrides
                .iter()
                .find(|(n, _)| n.name == p.name.name)
                .map(|(_, e)| (e, o.parent))
        });
        let (expr, scope) = over.unwrap_or((&p.default, sid));
        let what = if over.is_some() {
            "a parameter override"
        } else {
            "a parameter default"
        };
        let cx = Cx {
            scope,
            allow: Allow::Constant,
            host: None,
            what,
        };
        let mut value = 0.0;
        let mut derived = None;
        let mut value_reported = true;
        if let Some((ir_expr, q)) = self.expr(expr, cx) {
            match q {
                Q::Dim(d) if unit_ok && d != unit.dim => {
                    self.diags.push(
                        Diagnostic::error(
                            "BG0303",
                            format!("the value of `{}` has unit `{d}`, but it is declared `[{text}]`", p.name.name),
                        )
                        .with_primary(expr.span, format!("this is in {d}"))
                        .with_secondary(p.unit.span, "declared unit")
                        .with_help("make the expression's unit match the declared one, or fix the declaration"),
                    );
                }
                _ => {}
            }
            let mut refs = Vec::new();
            super::consteval::params_of(&ir_expr, &mut refs);
            match eval(&ir_expr, &self.model.params) {
                // A bare number is written in the declared unit; an expression of parameters is already in SI.
                Some(v) if q == Q::Free => value = v * unit.scale,
                Some(v) => value = v,
                None => {}
            }
            value_reported = self.values_reported(&refs);
            if !value.is_finite() {
                value_reported = true;
                self.diags.push(
                    Diagnostic::error(
                        "BG0403",
                        format!("the value of `{}` is not finite", p.name.name),
                    )
                    .with_primary(expr.span, format!("this evaluates to {value}"))
                    .with_help("check for a division by zero or an overflow"),
                );
                value = 0.0;
            }
            if !refs.is_empty() {
                derived = Some(ir_expr);
            }
        }
        let id = self.model.params.len();
        // A duplicate cannot be referred to; it is not reported as unused as well.
        let used = !self.declare(sid, &p.name, Entity::Param(id));
        self.model.params.push(ir::Param {
            name: self.qualified(sid, &p.name.name),
            default: value,
            unit,
            unit_text: text,
            description: p.description.clone(),
            doc: p.doc.clone(),
            derived,
        });
        self.model.spans.params.push(p.span);
        self.params.push(ParamInfo {
            used,
            name_span: p.name.span,
            value_span: expr.span,
            unit_span: p.unit.span,
            value_reported,
        });
    }

    /// Whether one of the parameters `ids` has a value that could not be computed (already reported).
    pub fn values_reported(&self, ids: &[usize]) -> bool {
        ids.iter()
            .any(|&id| self.params.get(id).is_some_and(|p| p.value_reported))
    }

    fn element(&mut self, sid: usize, e: &'a ast::ElementDecl) {
        let explicit_domain = e
            .domain
            .as_ref()
            .and_then(|d| self.domain_name(d).map(|dom| (dom, d.span)));
        let ports = match e.kind {
            k if k.is_junction() => 0,
            k if k.is_two_port() => 2,
            k if k.is_field() => e.ports.map(|(n, _)| n).unwrap_or(0),
            _ => 1,
        };
        if let Some((n, span)) = e.ports.filter(|(n, _)| *n as usize > MAX_FIELD_PORTS) {
            self.diags.push(
                Diagnostic::error(
                    "BG0115",
                    format!(
                        "a field has at most {MAX_FIELD_PORTS} ports, `{}` declares {n}",
                        e.name.name
                    ),
                )
                .with_primary(span, "too many ports")
                .with_help("split the field into smaller fields, or check the port count"),
            );
        }
        let node = self.model.graph.add_node(ir::Node {
            name: self.qualified(sid, &e.name.name),
            kind: e.kind,
            relation: ir::Relation::Junction,
            ports,
            doc: e.doc.clone(),
        });
        let _ = self.declare(sid, &e.name, Entity::Node(node));
        let relation_span = match &e.body {
            ast::ElementBody::None => None,
            ast::ElementBody::Value(v) => Some(v.span),
            ast::ElementBody::Laws(laws) => laws
                .first()
                .zip(laws.last())
                .map(|(a, b)| a.span.to(b.span)),
        };
        let spans = &mut self.model.spans;
        spans.nodes.push(e.span);
        spans.node_names.push(e.name.span);
        spans.node_relations.push(relation_span);
        spans
            .node_instances
            .push(self.scopes.get(sid).and_then(|s| s.instance_span));
        self.nodes.push(NodeInfo {
            scope: sid,
            decl: e,
            explicit_domain,
            domain: None,
        });
    }

    fn instance(&mut self, sid: usize, inst: &'a InstanceDecl) {
        if !self.try_instance(sid, inst) {
            // Keep the name so that bonds to its ports are not reported again.
            self.scopes.push(Scope {
                broken: true,
                ..Default::default()
            });
            let child = self.scopes.len() - 1;
            let _ = self.declare(sid, &inst.name, Entity::Instance(child));
        }
    }

    /// Instantiates a component; false (with BG0204 reported) when it cannot be.
    fn try_instance(&mut self, sid: usize, inst: &'a InstanceDecl) -> bool {
        let name = &inst.component.name;
        let Some(&comp) = self.decls.get(name) else {
            let mut candidates: Vec<&str> = self
                .decls
                .iter()
                .filter(|(_, d)| d.kind == ModelKind::Component)
                .map(|(n, _)| n.as_str())
                .collect();
            candidates.sort_unstable();
            let help = match closest(name, candidates.iter().copied()) {
                Some(c) => format!("did you mean `{c}`?"),
                None => "declare the component in this file or import the file that declares it (`import \"std.bg\";` for the standard library)".to_string(),
            };
            self.diags.push(
                Diagnostic::error("BG0204", format!("unknown component `{name}`"))
                    .with_primary(inst.component.span, "no component of this name")
                    .with_help(help),
            );
            return false;
        };
        if comp.kind == ModelKind::Model {
            self.diags.push(
                Diagnostic::error("BG0204", format!("`{name}` is a model, not a component"))
                    .with_primary(inst.component.span, "instantiated here")
                    .with_secondary(comp.name.span, "declared as a model here")
                    .with_help("only components can be instantiated; declare it with `component`"),
            );
            return false;
        }
        if self.component_stack.iter().any(|c| c == name) {
            self.diags.push(
                Diagnostic::error("BG0204", format!("component `{name}` contains itself"))
                    .with_primary(inst.span, "this instance repeats an enclosing component")
                    .with_secondary(comp.name.span, "component declared here")
                    .with_help("a component cannot instantiate itself, directly or through other components"),
            );
            return false;
        }
        if self.component_stack.len() >= MAX_NESTING || self.instance_count >= MAX_INSTANCES {
            let what = if self.component_stack.len() >= MAX_NESTING {
                format!("components nest more than {MAX_NESTING} deep here")
            } else {
                format!("the model expands to more than {MAX_INSTANCES} component instances")
            };
            self.diags.push(
                Diagnostic::error("BG0204", what)
                    .with_primary(inst.span, "this instance is not expanded")
                    .with_help("a model this large is almost always a mistake: check the components that instantiate one another"),
            );
            return false;
        }
        self.instance_count += 1;
        self.component_stack.push(name.clone());
        self.instantiated.push(name.clone());
        let prefix = format!("{}{}.", self.scopes[sid].prefix, inst.name.name);
        let child = self.instantiate(
            comp,
            prefix,
            Some(Overrides {
                instance: inst,
                parent: sid,
            }),
        );
        self.component_stack.pop();
        let _ = self.declare(sid, &inst.name, Entity::Instance(child));
        true
    }
}

/// Span helper for messages that name an element kind.
pub(crate) fn kind_name(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Zero => "0-junction",
        ElementKind::One => "1-junction",
        k => k.keyword(),
    }
}

/// [`kind_name`] after its indefinite article: "a 0-junction", "an `R`", "a `TF`".
pub(crate) fn kind_with_article(kind: ElementKind) -> String {
    match kind {
        ElementKind::Zero | ElementKind::One => format!("a {}", kind_name(kind)),
        k => k.with_article(),
    }
}

/// Whether a statement declares a name in its scope (bond labels, rare, are left to grow the table).
fn declares_name(stmt: &Stmt) -> bool {
    matches!(
        stmt,
        Stmt::Param(_)
            | Stmt::Input(_)
            | Stmt::Output(_)
            | Stmt::Var(_)
            | Stmt::Element(_)
            | Stmt::Instance(_)
    )
}
