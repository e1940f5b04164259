//! Tests of the lowering stage through the parser: valid models (structure, domains, units, values) and one test
//! per diagnostic code with its primary span.

use super::*;
use crate::diagnostic::has_errors;
use crate::ir::{Domain, Expr, Relation, Target};
use crate::syntax::ast::ElementKind;
use petgraph::visit::EdgeRef;

/// Lowers `text` as file `main.bg` with extra in-memory files.
fn lower_with(text: &str, loader: MemoryLoader) -> (Vec<ir::Model>, Vec<Diagnostic>, SourceMap) {
    let mut sources = SourceMap::new();
    let root = sources.add("main.bg", text);
    let mut loader = loader;
    let (models, diags) = lower(&mut sources, root, &mut loader);
    (models, diags, sources)
}

pub(super) fn lower_text(text: &str) -> (Vec<ir::Model>, Vec<Diagnostic>, SourceMap) {
    lower_with(text, MemoryLoader::new())
}

fn codes(text: &str) -> Vec<&'static str> {
    lower_text(text).1.iter().map(|d| d.code.0).collect()
}

/// The single model of `text`, which must lower without any diagnostic.
fn clean(text: &str) -> ir::Model {
    let (mut models, diags, sources) = lower_text(text);
    assert!(
        diags.is_empty(),
        "{}",
        crate::diagnostic::render::to_text(&sources, &diags, false)
    );
    assert_eq!(models.len(), 1);
    let m = models.remove(0);
    assert_eq!(validate(&m), Ok(()));
    m
}

/// Asserts that `text` gives exactly one diagnostic with `code`, whose primary label covers `snippet`.
fn expect_one(text: &str, code: &str, snippet: &str) -> Diagnostic {
    let (_, diags, sources) = lower_text(text);
    let matching: Vec<&Diagnostic> = diags.iter().filter(|d| d.code.0 == code).collect();
    assert_eq!(
        matching.len(),
        1,
        "expected one {code}, got:\n{}",
        crate::diagnostic::render::to_text(&sources, &diags, false)
    );
    let d = matching[0].clone();
    let span = d.primary_span().unwrap_or_default();
    assert_eq!(sources.snippet(span), snippet, "primary span of {code}");
    assert!(d.help.is_some(), "{code} has no help");
    d
}

const OSCILLATOR: &str = r#"
model oscillator {
    domain translational;
    param m = 2 [kg]      "moving mass";
    param k = 800 [N/m]   "spring stiffness";
    param d = 4 [N s/m]   "damping";
    input F [N]           "applied force";
    Se push = F;
    I  mass = m;
    C  spring = 1/k;
    R  damper = d;
    1  v;
    bond push -> v -> mass, spring, damper;
    output x [m] = q(spring);
    output v_mass [m/s] = f(mass);
}
"#;

#[test]
fn oscillator_lowers_to_five_nodes_and_four_bonds() {
    let m = clean(OSCILLATOR);
    assert_eq!(m.graph.node_count(), 5);
    assert_eq!(m.graph.edge_count(), 4);
    assert!(
        m.graph
            .edge_weights()
            .all(|b| b.domain == Domain::Translational)
    );
    let spring = m.node_by_name("spring").unwrap_or_default();
    let k = m.param_by_name("k").unwrap_or(99);
    assert_eq!(
        m.graph[spring].relation,
        Relation::Linear(Expr::Binary(
            crate::syntax::ast::BinOp::Div,
            Box::new(Expr::Const(1.0)),
            Box::new(Expr::Param(k))
        ))
    );
    assert_eq!(m.params[k].default, 800.0);
    assert_eq!(m.outputs[0].value, Expr::Displacement(spring));
    let mass = m.node_by_name("mass").unwrap_or_default();
    assert_eq!(m.outputs[1].value, Expr::Flow(Target::Node(mass)));
    // Every bond points away from the source and the 1-junction.
    let v = m.node_by_name("v").unwrap_or_default();
    assert_eq!(m.graph.edges_directed(v, Direction::Outgoing).count(), 3);
    assert_eq!(m.spans.nodes.len(), 5);
}

const BACK_SUPPORT: &str = include_str!("../../../models/back_support.bg");

#[test]
fn back_support_lowers_cleanly_element_for_element() {
    let m = clean(BACK_SUPPORT);
    assert_eq!(m.name, "back_support");
    // Fig. 6: Se, Sf, TF, 5 I, 3 C, 6 R, 3 0-junctions and 8 1-junctions: 28 nodes in a tree of 27 bonds.
    assert_eq!(m.graph.node_count(), 28);
    assert_eq!(m.graph.edge_count(), 27);
    let count = |k: ElementKind| m.graph.node_weights().filter(|n| n.kind == k).count();
    assert_eq!(count(ElementKind::I), 5);
    assert_eq!(count(ElementKind::C), 3);
    assert_eq!(count(ElementKind::I) + count(ElementKind::C), 8);
    assert_eq!(count(ElementKind::R), 6);
    assert_eq!(count(ElementKind::TF), 1);
    assert_eq!(count(ElementKind::Se), 1);
    assert_eq!(count(ElementKind::Sf), 1);
    assert_eq!(count(ElementKind::Zero), 3);
    assert_eq!(count(ElementKind::One), 8);
    assert!(
        m.graph
            .edge_weights()
            .all(|b| b.domain == Domain::Rotational)
    );
    // Parameters as in the paper, with the defaults of the seeds' README, in SI units.
    let p = |name: &str| {
        m.param_by_name(name)
            .map(|i| (m.params[i].default, m.params[i].unit.dim))
    };
    let inertia = crate::units::Dim::new(2, 1, 0, 0, 0, 0, 0);
    let torsion = crate::units::Dim::new(2, 1, -2, 0, 0, 0, 0);
    let damping = crate::units::Dim::new(2, 1, -1, 0, 0, 0, 0);
    assert_eq!(p("J_m"), Some((3.06e-4, inertia)));
    assert_eq!(p("J_g"), Some((0.40e-4, inertia)));
    assert_eq!(p("r_g"), Some((160.0, crate::units::Dim::NONE)));
    assert_eq!(p("k_g"), Some((2.64e4, torsion)));
    assert_eq!(p("k_s"), Some((3.38e4, torsion)));
    assert_eq!(p("k_eh"), Some((1125.0, torsion)));
    assert_eq!(p("d_g"), Some((6.0, damping)));
    assert_eq!(p("b_g"), Some((0.65, damping)));
    assert_eq!(p("b_h"), Some((0.75, damping)));
    assert_eq!(p("J_sint"), Some((1e-4, inertia)));
    assert_eq!(p("J_sext"), Some((1.19e-3, inertia)));
    assert_eq!(p("J_h"), Some((0.0491, inertia)));
    for zero in ["b_f", "d_s", "d_eh"] {
        assert_eq!(p(zero), Some((0.0, damping)), "{zero}");
    }
    assert_eq!(m.params.len(), 15);
    // The gearbox: input bond from the motor junction on port 0, output bond to the gearbox junction on port 1.
    let gear = m.node_by_name("gear").unwrap_or_default();
    let j_m = m.node_by_name("j_m").unwrap_or_default();
    let j_g = m.node_by_name("j_g").unwrap_or_default();
    let input = m.graph.edges_directed(gear, Direction::Incoming).next();
    let output = m.graph.edges_directed(gear, Direction::Outgoing).next();
    assert_eq!(
        input.map(|e| (e.source(), e.weight().to_port)),
        Some((j_m, 0))
    );
    assert_eq!(
        output.map(|e| (e.target(), e.weight().from_port)),
        Some((j_g, 1))
    );
    let r_g = m.param_by_name("r_g").unwrap_or(99);
    assert_eq!(m.graph[gear].relation, Relation::Modulus(Expr::Param(r_g)));
    // Inputs, outputs, vars and the coordinates of Eq. (2).
    let names = |v: Vec<&str>| v.into_iter().map(String::from).collect::<Vec<_>>();
    assert_eq!(
        m.inputs.iter().map(|i| i.name.clone()).collect::<Vec<_>>(),
        names(vec!["tau_m", "omega_h"])
    );
    assert_eq!(
        m.outputs.iter().map(|o| o.name.clone()).collect::<Vec<_>>(),
        names(vec!["omega_m", "tau_s", "tau_h"])
    );
    assert_eq!(m.vars.len(), 4);
    assert!(m.vars.iter().all(|v| v.unit.dim.is_dimensionless()));
    let coords = m.coords.clone().unwrap_or_default();
    assert_eq!(coords.len(), 7);
    assert_eq!(coords[0], Expr::Var(0));
    let rotor = m.node_by_name("rotor").unwrap_or_default();
    assert_eq!(coords[1], Expr::Flow(Target::Node(rotor)));
    assert_eq!(coords[6], Expr::Var(3));
    let s_spring = m.node_by_name("sensor_spring").unwrap_or_default();
    let s_damper = m.node_by_name("sensor_damper").unwrap_or_default();
    assert_eq!(
        m.outputs[1].value,
        Expr::Binary(
            crate::syntax::ast::BinOp::Add,
            Box::new(Expr::Effort(Target::Node(s_spring))),
            Box::new(Expr::Effort(Target::Node(s_damper)))
        )
    );
}

const STD_RIG: &str = r#"
import "std.bg";
model rig {
    domain rotational;
    input u [V] "supply voltage";
    Se supply : electrical = u;
    dc_motor motor(R_a = 2, k_t = 0.1);
    gearbox gb(ratio = 50);
    spring_damper_rot shaft(k = 500, d = 0.5);
    1 load_speed;
    I load = 0.1;
    bond supply -> motor.v;
    bond motor.shaft -> gb.in;
    bond gb.out -> shaft.a;
    bond shaft.b -> load_speed -> load;
    output tau [N m] = e(shaft.spring) + e(shaft.damper);
    output current [A] = f(motor.current);
}
"#;

#[test]
fn standard_rotational_components_instantiate_with_overrides() {
    let m = clean(STD_RIG);
    // dc_motor 7 nodes, gearbox 5, spring_damper_rot 4, plus supply, load_speed, load.
    assert_eq!(m.graph.node_count(), 19);
    assert_eq!(m.graph.edge_count(), 18);
    let p = |name: &str| m.param_by_name(name).map(|i| m.params[i].default);
    assert_eq!(p("motor.R_a"), Some(2.0));
    assert_eq!(p("motor.k_t"), Some(0.1));
    assert_eq!(p("motor.L_a"), Some(1e-3));
    assert_eq!(p("gb.ratio"), Some(50.0));
    assert_eq!(p("shaft.k"), Some(500.0));
    assert_eq!(p("shaft.d"), Some(0.5));
    // The motor joins the electrical and rotational domains through its gyrator.
    let emf = m.node_by_name("motor.emf").unwrap_or_default();
    let din = m
        .graph
        .edges_directed(emf, Direction::Incoming)
        .map(|e| e.weight().domain)
        .next();
    let dout = m
        .graph
        .edges_directed(emf, Direction::Outgoing)
        .map(|e| e.weight().domain)
        .next();
    assert_eq!(
        (din, dout),
        (Some(Domain::Electrical), Some(Domain::Rotational))
    );
    let winding = m.node_by_name("motor.winding").unwrap_or_default();
    let wb = m.graph.edges_directed(winding, Direction::Incoming).next();
    assert_eq!(wb.map(|e| e.weight().domain), Some(Domain::Electrical));
    // The instance span of flattened nodes points at the instance declaration in the model.
    let (_, _, sources) = lower_text(STD_RIG);
    let span = m.spans.node_instances[winding.index()].unwrap_or_default();
    assert_eq!(sources.snippet(span), "dc_motor motor(R_a = 2, k_t = 0.1);");
}

#[test]
fn standard_translational_spring_damper_instantiates() {
    let m = clean(
        r#"
import "std.bg";
model sled {
    domain translational;
    input F [N];
    Se push = F;
    1 v1;
    I cart = 3;
    spring_damper_trans mount(k = 2e4);
    1 v2;
    I payload = 1;
    bond push -> v1 -> cart;
    bond v1 -> mount.a;
    bond mount.b -> v2 -> payload;
    output x [m] = q(mount.spring);
}
"#,
    );
    assert!(
        m.graph
            .edge_weights()
            .all(|b| b.domain == Domain::Translational)
    );
    let k = m.param_by_name("mount.k").map(|i| m.params[i].default);
    let d = m.param_by_name("mount.d").map(|i| m.params[i].default);
    assert_eq!((k, d), (Some(2e4), Some(10.0)));
    let spring = m.node_by_name("mount.spring").unwrap_or_default();
    assert_eq!(m.outputs[0].value, Expr::Displacement(spring));
}

#[test]
fn standard_library_has_the_documented_ports() {
    // Every component of std.bg, instantiated alone with its ports bonded to sources or inertias.
    let (models, diags, sources) = lower_text(
        r#"
import "std.bg";
model ports {
    domain rotational;
    input u [V];
    input tau [N m];
    Se supply : electrical = u;
    dc_motor m1;
    I j1 = 1;
    bond supply -> m1.v;
    bond m1.shaft -> j1;
    Se drive = tau;
    gearbox g1;
    I j2 = 1;
    bond drive -> g1.in;
    bond g1.out -> j2;
}
"#,
    );
    assert!(
        diags.is_empty(),
        "{}",
        crate::diagnostic::render::to_text(&sources, &diags, false)
    );
    assert_eq!(models.len(), 1);
}

#[test]
fn unit_mismatch_names_the_expected_unit_of_the_kind_and_domain() {
    let d = expect_one(
        "model m { domain rotational; param k = 800 [N/m]; input tau [N m]; Se drive = tau; C spring = 1/k; bond drive -> spring; }",
        "BG0303",
        "1/k",
    );
    assert!(
        d.message
            .contains("expected rad/(N m) (a compliance in the rotational domain), found m/N"),
        "{}",
        d.message
    );
    // The parameter's declared unit explains it.
    let secondary: Vec<&str> = d
        .labels
        .iter()
        .filter(|l| !l.primary)
        .map(|l| l.message.as_str())
        .collect();
    assert_eq!(secondary, vec!["`k` is declared in N/m"]);
    // The same stiffness in a translational model is right.
    clean(
        "model m { domain translational; param k = 800 [N/m]; input F [N]; Se push = F; C spring = 1/k; bond push -> spring; }",
    );
}

#[test]
fn duplicate_points_back_at_the_first_declaration() {
    let text = "model m { domain rotational; input tau [N m]; Se drive = tau; I drive = 1; bond drive -> w; 1 w; }";
    let (_, diags, sources) = lower_text(text);
    let d = diags
        .iter()
        .find(|d| d.code.0 == "BG0202")
        .cloned()
        .unwrap_or_else(|| Diagnostic::error("none", ""));
    let secondary: Vec<&str> = d
        .labels
        .iter()
        .filter(|l| !l.primary)
        .map(|l| sources.snippet(l.span))
        .collect();
    assert_eq!(secondary, vec!["drive"]);
    let primary = d.primary_span().unwrap_or_default();
    assert_eq!(
        primary.start as usize,
        text.find("I drive").unwrap_or(0) + 2
    );
}

#[test]
fn unknown_name_suggests_the_closest_declared_name() {
    let d = expect_one(
        "model m { domain rotational; param damping = 1 [N m s/rad]; input tau [N m]; Se drive = tau; R fr = damping; 1 w; bond drive -> w -> fr; output y [N m] = dampin * f(w); }",
        "BG0201",
        "dampin",
    );
    assert_eq!(d.help.as_deref(), Some("did you mean `damping`?"));
}

#[test]
fn a_function_name_of_another_tool_or_a_value_called_says_what_to_write() {
    let model = |expr: &str| {
        format!(
            "model m {{ domain translational; param k = 2 [N/m]; input F [N]; Se drive = F; I mass = 1; 1 v; \
             bond drive -> v -> mass; output y [N] = {expr}; }}"
        )
    };
    for (expr, called, help) in [
        (
            "F(t)",
            "F",
            "`F` is an input, a value and not a function: write `F`, its value at the current time",
        ),
        (
            "k(2) * 1",
            "k",
            "`k` is a parameter, a value and not a function: write `k`",
        ),
        (
            "effort(mass)",
            "effort",
            "the effort of element or port `x` is `e(x)`",
        ),
        (
            "F * log(2)",
            "log",
            "write `ln` for the natural logarithm, `log10` for the decimal one",
        ),
        ("F * sgn(F)", "sgn", "did you mean `sign`?"),
    ] {
        let d = expect_one(&model(expr), "BG0208", called);
        assert_eq!(d.help.as_deref(), Some(help), "{expr}");
    }
}

#[test]
fn two_unit_symbols_written_together_are_told_apart_from_a_case_slip() {
    for (unit, help) in [
        ("N s/m", None),
        (
            "Ns/m",
            Some("unit factors are separated by a space: `N s`, as in `[N m]`"),
        ),
        ("kgm^2", Some("write `kg m`")),
        (
            "Wh",
            Some("unit factors are separated by a space: `W h`, as in `[N m]`"),
        ),
        // `K g` would split too, but a case slip of a known unit comes first.
        ("Kg", Some("did you mean `kg`?")),
        // Two factors of one quantity are a typo of one unit, not a product (the help was `kg g`, `N N`).
        ("kgg", Some("did you mean `kg`?")),
        ("NN", Some("did you mean `N`?")),
    ] {
        let text = format!(
            "model m {{ domain translational; param d = 4 [{unit}]; input F [N]; Se s = F; I i = 1; R r = d; \
             1 v; bond s -> v -> i, r; }}"
        );
        let (_, diags, _) = lower_text(&text);
        let found = diags.iter().find(|d| d.code.0 == "BG0312");
        assert_eq!(
            found.and_then(|d| d.help.as_deref()),
            help,
            "[{unit}]: {diags:#?}"
        );
    }
}

#[test]
fn non_physical_values_are_errors_and_zero_resistance_is_not() {
    // A zero stiffness makes an infinite compliance; the secondary label shows the parameter's value.
    let d = expect_one(
        "model m { domain rotational; param k = 0 [N m/rad]; input tau [N m]; Se drive = tau; C spring = 1/k; bond drive -> spring; }",
        "BG0401",
        "1/k",
    );
    assert!(d.message.contains("infinite compliance"), "{}", d.message);
    assert!(
        d.labels
            .iter()
            .any(|l| !l.primary && l.message == "`k` is 0")
    );
    expect_one(
        "model m { domain rotational; param r = 0 [1]; input tau [N m]; Se drive = tau; TF gear = r; I load = 1; bond drive -> gear -> load; }",
        "BG0401",
        "r",
    );
    expect_one(
        "model m { domain rotational; param b = -0.5 [N m s/rad]; input tau [N m]; Se drive = tau; R fr = b; bond drive -> fr; }",
        "BG0401",
        "b",
    );
    clean(
        "model m { domain rotational; param b = 0 [N m s/rad]; input tau [N m]; Se drive = tau; R fr = b; bond drive -> fr; }",
    );
}

#[test]
fn import_cycle_and_missing_import_are_reported_at_the_import() {
    let loader = MemoryLoader::new()
        .with(
            "lib/a.bg",
            "import \"b.bg\"; component ca { domain rotational; 1 j; port p = j; }",
        )
        .with("lib/b.bg", "import \"a.bg\";");
    let (_, diags, sources) = lower_with("import \"lib/a.bg\"; model m { }", loader);
    assert_eq!(
        diags.iter().map(|d| d.code.0).collect::<Vec<_>>(),
        vec!["BG0107"]
    );
    let span = diags[0].primary_span().unwrap_or_default();
    assert_eq!(
        sources.get(span.file).map(|f| f.name.as_str()),
        Some("lib/b.bg")
    );
    assert_eq!(sources.snippet(span), "import \"a.bg\";");
    assert!(
        diags[0]
            .message
            .contains("`lib/a.bg` -> `lib/b.bg` -> `lib/a.bg`"),
        "{}",
        diags[0].message
    );

    let (_, diags, sources) = lower_text("import \"nowhere.bg\";\nmodel m { }");
    assert_eq!(
        diags.iter().map(|d| d.code.0).collect::<Vec<_>>(),
        vec!["BG0108"]
    );
    assert_eq!(
        sources.snippet(diags[0].primary_span().unwrap_or_default()),
        "import \"nowhere.bg\";"
    );
}

#[test]
fn imports_resolve_relative_to_the_importing_file_and_load_once() {
    // main imports lib/a.bg and lib/b.bg; both import lib/common.bg (a diamond, not a cycle).
    let loader = MemoryLoader::new()
        .with("lib/a.bg", "import \"common.bg\";")
        .with("lib/b.bg", "import \"./common.bg\";")
        .with(
            "lib/common.bg",
            "component inertia_c { domain rotational; param J = 2 [kg m^2]; 1 w; I body = J; bond w -> body; port p = w; }",
        );
    let text = r#"import "lib/a.bg"; import "lib/b.bg";
model m { domain rotational; input tau [N m]; Se drive = tau; inertia_c c1(J = 3); 1 w; I other = 1; bond drive -> w -> other; bond w -> c1.p; }"#;
    let (models, diags, sources) = lower_with(text, loader);
    assert!(
        diags.is_empty(),
        "{}",
        crate::diagnostic::render::to_text(&sources, &diags, false)
    );
    assert_eq!(sources.files().count(), 4);
    let m = &models[0];
    assert_eq!(
        m.param_by_name("c1.J").map(|i| m.params[i].default),
        Some(3.0)
    );
}

#[test]
fn a_component_that_contains_itself_is_refused() {
    let text = "component loop_c { domain rotational; 1 j; I x = 1; bond j -> x; loop_c inner; port p = j; }
model m { domain rotational; input tau [N m]; Se drive = tau; loop_c c; bond drive -> c.p; }";
    assert!(codes(text).contains(&"BG0204"));
}

#[test]
fn domains_propagate_through_junctions_and_transformers_join_domains() {
    // Only the source names a domain on the left; the pulley's right side is translational.
    let m = clean(
        r#"model m {
    param r = 0.05 [m] "pulley radius: angular speed times r is the belt speed";
    input tau [N m];
    Se drive : rotational = tau;
    1 w;
    I wheel = 0.01;
    TF pulley = 1/r;
    1 v;
    I belt : translational = 2;
    bond drive -> w -> wheel;
    bond w -> pulley -> v -> belt;
}"#,
    );
    let dom = |name: &str| {
        let n = m.node_by_name(name).unwrap_or_default();
        m.graph
            .edges_directed(n, Direction::Incoming)
            .map(|e| e.weight().domain)
            .next()
    };
    assert_eq!(dom("wheel"), Some(Domain::Rotational));
    assert_eq!(dom("belt"), Some(Domain::Translational));
    // The TF ratio (rad/s)/(m/s) is 1/m: a ratio given in [1] is wrong.
    expect_one(
        r#"model m {
    param n = 20 [1];
    input tau [N m];
    Se drive : rotational = tau;
    TF pulley = n;
    I belt : translational = 2;
    bond drive -> pulley -> belt;
}"#,
        "BG0303",
        "n",
    );
}

#[test]
fn laws_and_fields_resolve_their_local_variables() {
    let m = clean(
        r#"model m {
    domain rotational;
    param b0 = 0.2 [N m];
    param b2 = 0.01 [N m s/rad];
    param a = 1 [kg m^2];
    param c = 0.5 [kg m^2];
    input tau [N m];
    Se drive = tau;
    Se drive2 = tau;
    1 w;
    R friction { e = b0*sign(f) + b2*f; }
    IF leg(2) { mass[1,1] = a + c*cos(q[2]); mass[1,2] = c; mass[2,2] = c; }
    bond drive -> w -> friction;
    bond w -> leg[1];
    bond drive2 -> leg[2];
    output knee_torque [N m] = e(leg[2]);
}"#,
    );
    let friction = m.node_by_name("friction").unwrap_or_default();
    let Relation::Laws(laws) = &m.graph[friction].relation else {
        panic!("friction has no laws: {:?}", m.graph[friction].relation);
    };
    assert_eq!(laws.len(), 1);
    assert_eq!(laws[0].lhs, crate::ir::PortVar::Effort);
    let leg = m.node_by_name("leg").unwrap_or_default();
    let Relation::MassMatrix { n, entries } = &m.graph[leg].relation else {
        panic!("leg has no mass matrix");
    };
    assert_eq!(*n, 2);
    // Symmetric fill of the lower triangle.
    assert_eq!(entries[1], entries[2]);
    assert_eq!(entries[1], Expr::Param(m.param_by_name("c").unwrap_or(99)));
    // e(leg[2]) is the effort on the bond of port 2.
    let port2 = m
        .graph
        .edges_directed(leg, Direction::Incoming)
        .find(|e| e.weight().to_port == 1);
    assert_eq!(
        m.outputs[0].value,
        Expr::Effort(Target::Bond(port2.map(|e| e.id()).unwrap_or_default()))
    );
}

#[test]
fn parameter_defaults_use_earlier_parameters_and_unit_scales() {
    let m = clean(
        r#"model m {
    domain rotational;
    param J1 = 2 [kg m^2];
    param J2 = 3 * J1 [kg m^2];
    param c = 2 [g m^2] "a bare number is written in the declared unit";
    param speed = 60 [rpm];
    input tau [N m];
    Se drive = tau;
    1 w;
    I a = J2 + c;
    R fr = 1;
    bond drive -> w -> a, fr;
    output s [rad/s] = speed;
}"#,
    );
    let v = |n: &str| {
        m.param_by_name(n)
            .map(|i| m.params[i].default)
            .unwrap_or(f64::NAN)
    };
    assert_eq!(v("J2"), 6.0);
    assert!((v("c") - 2e-3).abs() < 1e-15);
    // 60 rpm = 2 pi rad/s.
    assert!((v("speed") - 2.0 * std::f64::consts::PI).abs() < 1e-12);
    // A later parameter is not visible to an earlier default.
    assert!(codes("model m { param a = b [1]; param b = 1 [1]; }").contains(&"BG0201"));
    // An output may use earlier outputs only.
    assert!(codes(
        "model m { domain rotational; input tau [N m]; Se drive = tau; I r = 1; bond drive -> r; output a [rad/s] = b; output b [rad/s] = f(r); }"
    )
    .contains(&"BG0314"));
}

#[test]
fn lowered_models_with_errors_are_still_returned() {
    let (models, diags, _) = lower_text("model m { domain rotational; I lonely = 1; }");
    assert_eq!(models.len(), 1);
    assert!(has_errors(&diags));
    // Components are not returned as models.
    let (models, _, _) =
        lower_text("component c { domain rotational; 1 j; I x = 1; bond j -> x; port p = j; }");
    assert!(models.is_empty());
}

#[test]
fn complete_models_of_the_language_reference_lower_without_errors() {
    let doc = include_str!("../../../docs/language.md");
    let mut complete = 0;
    for block in doc.split("```bg").skip(1) {
        let block = block.split("```").next().unwrap_or("");
        let (_, parse_diags) = crate::syntax::parse(FileId(0), block);
        if !parse_diags.is_empty() {
            continue; // a fragment (statements shown outside a model)
        }
        let (_, diags, sources) = lower_text(block);
        // Sketches may leave a parameter unused (a warning); nothing may be an error.
        assert!(
            !has_errors(&diags),
            "{block}\n{}",
            crate::diagnostic::render::to_text(&sources, &diags, false)
        );
        complete += 1;
    }
    assert!(complete >= 3, "only {complete} complete examples");
}

#[test]
fn valid_syntax_fixtures_lower_with_explained_diagnostics_only() {
    // The syntax fixtures need not be sound models (one bonds a junction once, to show the syntax); lowering them
    // must finish, and everything it reports must come with its place and a help line.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/valid");
    let paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|rd| rd.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    assert!(paths.len() >= 5);
    for path in paths {
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let (_, diags, _) = lower_text(&text);
        for d in &diags {
            assert!(
                d.primary_span().is_some() && d.help.is_some(),
                "{}: {d:?}",
                path.display()
            );
        }
    }
}

#[test]
fn an_instance_with_no_bonded_port_is_reported_once() {
    let text = r#"import "std.bg";
model m { domain rotational; input tau [N m]; Se drive = tau; I r = 1; bond drive -> r; spring_damper_rot spare; }"#;
    let (_, diags, sources) = lower_text(text);
    assert_eq!(
        diags.iter().map(|d| d.code.0).collect::<Vec<_>>(),
        vec!["BG0306"]
    );
    assert_eq!(
        sources.snippet(diags[0].primary_span().unwrap_or_default()),
        "spring_damper_rot spare;"
    );
}

#[test]
fn a_misspelt_bond_end_does_not_cascade_into_bond_counts() {
    // `wheel` would otherwise have one bond (BG0305).
    let text = "model m { domain rotational; input tau [N m]; Se drive = tau; 1 wheel; I r = 1; bond drive -> wheel; bond wheel -> rotr; }";
    let (_, diags, _) = lower_text(text);
    assert_eq!(
        diags.iter().map(|d| d.code.0).collect::<Vec<_>>(),
        vec!["BG0203", "BG0306"]
    );
}

#[test]
fn damaged_models_never_panic_and_always_explain_themselves() {
    // Every single-line deletion and duplication of two full models: lowering returns, and whatever is wrong is
    // reported as an error with a primary label and a help line.
    for source in [BACK_SUPPORT, STD_RIG] {
        let lines: Vec<&str> = source.lines().collect();
        for i in 0..lines.len() {
            for dup in [false, true] {
                let mut edited: Vec<&str> = lines.clone();
                if dup {
                    edited.insert(i, lines[i]);
                } else {
                    edited.remove(i);
                }
                let text = edited.join("\n");
                let (_, diags, _) = lower_text(&text);
                for d in &diags {
                    assert!(
                        d.primary_span().is_some(),
                        "{}: no primary label\n{text}",
                        d.code.0
                    );
                    assert!(d.help.is_some(), "{}: no help\n{text}", d.code.0);
                }
            }
        }
    }
}

#[test]
fn the_standard_library_checks_cleanly_on_its_own() {
    let (models, diags, sources) = lower_text(STD_SOURCE);
    assert!(models.is_empty());
    assert!(
        diags.is_empty(),
        "{}",
        crate::diagnostic::render::to_text(&sources, &diags, false)
    );
}

#[test]
fn an_unused_component_of_the_root_file_is_still_checked() {
    // Its unknown name is found; its port junction's single internal bond is not a count error.
    let text = "component c { domain rotational; 0 j; C s = 1/kk; bond j -> s; port a = j; }";
    assert_eq!(codes(text), vec!["BG0201"]);
    // Its parameters' uses count: no BG0402 for a used one, BG0402 for an unused one.
    let text = "component c { domain rotational; param k = 1 [N m/rad]; param z = 1 [1]; 0 j; C s = 1/k; bond j -> s; port a = j; }";
    assert_eq!(codes(text), vec!["BG0402"]);
}

#[test]
fn hints_named_bonds_and_modulated_elements() {
    let m = clean(
        r#"model m {
    domain rotational;
    param l = 0.3 [1];
    input tau [N m];
    Se drive = tau;
    1 w1;
    I a = 1;
    MTF lever = l * cos(theta);
    1 w2;
    I b = 2;
    C spring = 0.01;
    bond drive -> w1 -> a;
    bond w1 -> lever -> w2;
    bond s1: w2 -> b stroke! w2;
    bond w2 -> spring stroke spring;
    var theta [rad] = int(f(w1));
    output torque [N m] = e(s1);
}"#,
    );
    let hints: Vec<Option<crate::ir::Hint>> = m.graph.edge_weights().map(|b| b.hint).collect();
    assert_eq!(hints.iter().flatten().count(), 2);
    let s1 = m
        .graph
        .edge_indices()
        .find(|&e| m.graph[e].name.as_deref() == Some("s1"));
    let s1 = s1.unwrap_or_default();
    assert_eq!(
        m.graph[s1].hint,
        Some(crate::ir::Hint {
            stroke_at_to: false,
            fixed: true
        })
    );
    let spring = m.node_by_name("spring").unwrap_or_default();
    let to_spring = m.graph.edges_directed(spring, Direction::Incoming).next();
    assert_eq!(
        to_spring.and_then(|e| e.weight().hint),
        Some(crate::ir::Hint {
            stroke_at_to: true,
            fixed: false
        })
    );
    assert_eq!(m.outputs[0].value, Expr::Effort(Target::Bond(s1)));
    // The modulus of the MTF depends on the integrated flow.
    let lever = m.node_by_name("lever").unwrap_or_default();
    let Relation::Modulus(Expr::Binary(_, _, cos)) = &m.graph[lever].relation else {
        panic!("{:?}", m.graph[lever].relation);
    };
    assert_eq!(**cos, Expr::Call(crate::ir::Func::Cos, vec![Expr::Var(0)]));
    // A plain TF may not depend on the state.
    assert!(codes(
        "model m { domain rotational; param l = 1 [1]; input tau [N m]; Se d = tau; TF g = l * f(a); I a = 1; I b = 1; 1 w; bond d -> w -> a; bond w -> g -> b; }"
    )
    .contains(&"BG0314"));
}

#[test]
fn a_bond_between_two_two_ports_takes_the_default_domain() {
    // The bond gear1 -> gear2 touches no junction or 1-port; the model's default decides it.
    let m = clean(
        "model m { domain rotational; input tau [N m]; Se d = tau; TF gear1 = 2; TF gear2 = 3; I load = 1; bond d -> gear1 -> gear2 -> load; }",
    );
    assert!(
        m.graph
            .edge_weights()
            .all(|b| b.domain == Domain::Rotational)
    );
}

#[test]
fn library_and_model_files_are_in_canonical_layout() {
    for (name, text) in [("std.bg", STD_SOURCE), ("back_support.bg", BACK_SUPPORT)] {
        let (tree, diags) = crate::syntax::parse(FileId(0), text);
        assert!(diags.is_empty(), "{name}: {diags:?}");
        assert_eq!(
            crate::syntax::format(&tree),
            text,
            "{name} is not formatted"
        );
    }
}

mod random_models {
    use super::*;
    use proptest::prelude::*;

    /// Statements over a small pool of names, so that random picks collide, repeat and reference each other.
    const FRAGMENTS: &[&str] = &[
        "domain rotational;",
        "domain electrical;",
        "param k = 1e3 [N m/rad];",
        "param k = 0 [N/m];",
        "param J = 2 [kg m^2];",
        "param J = -1 [kg];",
        "param r = k * J [1];",
        "input u [N m];",
        "input u [V];",
        "output y [N m] = e(a) + e(b);",
        "output y [rad/s] = f(j) * r;",
        "output z [1] = sin(q(b)) + p(a);",
        "var th [rad] = int(f(j));",
        "coords [th, p(a), q(b)];",
        "Se s = u;",
        "Sf s = u;",
        "MSe s = u * cos(th);",
        "I a = J;",
        "I a : electrical = 1/k;",
        "C b = 1/k;",
        "C b { e = k*q + q^3; }",
        "R c = r;",
        "R c { f = sqrt(abs(e)) * sign(e); }",
        "TF g = r;",
        "GY g = 0.1;",
        "MTF g = th;",
        "0 j;",
        "1 j;",
        "1 w : translational;",
        "RF fld(2) { e[1] = f[2]; e[2] = f[1]; }",
        "IF fld(2) { mass[1,1] = J; mass[2,1] = J; mass[2,2] = 1; }",
        "spring_damper_rot sd(k = k, d = 1);",
        "dc_motor mot(R_a = r);",
        "nothing x;",
        "bond s -> j -> a, b, c;",
        "bond j -> g -> w;",
        "bond w -> sd.a;",
        "bond sd.b -> j;",
        "bond mot.shaft -> j;",
        "bond s -> mot.v;",
        "bond j -> fld[1];",
        "bond w -> fld[2];",
        "bond j -> fld[3];",
        "bond x: j -> a stroke! a;",
        "bond a -> a;",
        "port p = j;",
    ];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]
        #[test]
        fn any_mix_of_statements_lowers_and_explains_itself(picks in proptest::collection::vec(0..FRAGMENTS.len(), 0..24)) {
            let body: Vec<&str> = picks.iter().map(|&i| FRAGMENTS[i]).collect();
            let text = format!("import \"std.bg\";\nmodel m {{\n{}\n}}\n", body.join("\n"));
            let (models, diags, sources) = lower_text(&text);
            prop_assert_eq!(models.len(), 1);
            for d in &diags {
                let span = d.primary_span();
                prop_assert!(span.is_some(), "{}: no primary label\n{}", d.code.0, text);
                prop_assert!(d.help.is_some(), "{}: no help\n{}", d.code.0, text);
                // Labels lie inside their files.
                for l in &d.labels {
                    let len = sources.get(l.span.file).map(|f| f.text.len()).unwrap_or(0);
                    prop_assert!(l.span.end as usize <= len, "{:?} out of its file\n{}", l, text);
                }
            }
            // A model without errors keeps the IR invariants.
            if !has_errors(&diags) {
                prop_assert_eq!(validate(&models[0]), Ok(()), "{}", text);
            }
        }
    }
}

/// Names and units written with letters outside ASCII (`τ_m`, `π`, `[kΩ]`), as papers write them: each letter was
/// an invalid character, and each statement went on to a cascade ("expected the name of the parameter, found `=`",
/// "unknown name", "unknown unit `k`"). Each is now one BG0104 per occurrence, with the ASCII spelling.
#[test]
fn names_and_units_outside_ascii_are_one_error_each_with_the_ascii_spelling() {
    let text = "model a {\n    domain electrical;\n    param r = 1 [kΩ];\n    input τ_m [V];\n    \
                Se s = τ_m;\n    R res = r * π;\n    bond s -> res;\n}\n";
    let (_, diags, _) = lower_text(text);
    let found: Vec<(&str, String, Option<String>)> = diags
        .iter()
        .map(|d| (d.code.0, d.message.clone(), d.help.clone()))
        .collect();
    let spelled = |name: &str, what: &str, help: &str| {
        (
            "BG0104",
            format!("the {what} `{name}` has letters outside ASCII"),
            Some(help.to_string()),
        )
    };
    assert_eq!(
        found,
        vec![
            spelled("kΩ", "unit", "the ohm is written `Ohm`: `kOhm`"),
            spelled(
                "τ_m",
                "name",
                "names are ASCII letters, digits and `_`: write `tau_m`"
            ),
            spelled(
                "τ_m",
                "name",
                "names are ASCII letters, digits and `_`: write `tau_m`"
            ),
            spelled(
                "π",
                "name",
                "names are ASCII letters, digits and `_`: write `pi`"
            ),
        ]
    );
    // An ASCII name joined to a letter outside it is one name.
    let (_, diags, _) = lower_text("model a { domain electrical; param masse_é = 1 [1]; }");
    let messages: Vec<&str> = diags.iter().map(|d| d.message.as_str()).collect();
    assert_eq!(messages[0], "the name `masse_é` has letters outside ASCII");
    assert!(
        !messages.iter().any(|m| m.contains("expected")),
        "{messages:?}"
    );
}

/// An angle added to an angular velocity shows as "1/s and 1", since SI's `rad` is 1: the error says so, and only
/// where an angle-like unit is one of the two.
#[test]
fn a_mismatch_of_angle_like_units_explains_the_missing_rad() {
    let model = |expr: &str| {
        format!(
            "model r {{\n    domain rotational;\n    param w0 = 3 [rad/s];\n    param th = 1 [rad];\n    \
             param m = 2 [kg];\n    param L = 1 [m];\n    output z [1] = {expr};\n}}\n"
        )
    };
    for (expr, noted) in [("w0 + th", true), ("m + th", true), ("m + L", false)] {
        let (_, diags, _) = lower_text(&model(expr));
        let mismatch: Vec<&Diagnostic> = diags.iter().filter(|d| d.code.0 == "BG0310").collect();
        assert_eq!(mismatch.len(), 1, "{expr}: {diags:#?}");
        let says = mismatch[0].notes.iter().any(|n| n.contains("`rad` is 1"));
        assert_eq!(says, noted, "{expr}: {:?}", mismatch[0].notes);
    }
}

/// Constants as other tools spell them: `PI` and `M_PI` get `pi` as their certain fix, Euler's `e` the way to write
/// it (it is no name here: `e(x)` is an effort).
#[test]
fn constants_of_other_tools_say_how_to_write_them() {
    for (value, help, fix) in [
        ("2*PI", "write `pi`", Some("pi")),
        ("M_PI/2", "write `pi`", Some("pi")),
        (
            "e^2",
            "Euler's number is `exp(1)`, and `e^x` is `exp(x)`",
            None,
        ),
    ] {
        let text = format!("model m {{\n    param a = {value} [1];\n    output y [1] = a;\n}}\n");
        let (_, diags, _) = lower_text(&text);
        let unknown: Vec<&Diagnostic> = diags.iter().filter(|d| d.code.0 == "BG0201").collect();
        assert_eq!(unknown.len(), 1, "{value}: {diags:#?}");
        assert!(
            unknown[0]
                .help
                .as_deref()
                .is_some_and(|h| h.starts_with(help)),
            "{value}: {:?}",
            unknown[0].help
        );
        assert_eq!(unknown[0].fix(), fix, "{value}");
    }
}

#[test]
fn a_bond_name_refused_on_a_chain_is_not_reported_again_where_it_is_used() {
    // BG0110 drops the name; `f(d)` is then no "unknown element `d`" (BG0201), a follow-on of the same mistake.
    let text = "model m { domain electrical; Se drive = 1; 0 n; R r = 2; C c = 1; \
                bond d: drive -> n -> r, c; output y [A] = f(d); }";
    assert_eq!(codes(text), vec!["BG0110"]);
    // A name no statement declares still is.
    let text = "model m { domain electrical; Se drive = 1; 0 n; R r = 2; C c = 1; \
                bond drive -> n -> r, c; output y [A] = f(d); }";
    assert_eq!(codes(text), vec!["BG0201"]);
}
