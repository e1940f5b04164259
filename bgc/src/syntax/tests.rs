//! Unit tests of the parser: one or more per construct.

use super::ast::*;
use super::parse;
use crate::diagnostic::Diagnostic;
use crate::span::FileId;

fn parse_ok(text: &str) -> File {
    let (file, diags) = parse(FileId(0), text);
    let errors: Vec<&Diagnostic> = diags.iter().filter(|d| d.is_error()).collect();
    assert!(errors.is_empty(), "unexpected errors: {errors:#?}");
    file
}

fn body(text: &str) -> Vec<Stmt> {
    let src = format!("model m {{\n{text}\n}}\n");
    let file = parse_ok(&src);
    match file.items.into_iter().next() {
        Some(Item::Model(m)) => m.body,
        other => panic!("expected a model, got {other:?}"),
    }
}

fn one(text: &str) -> Stmt {
    let mut b = body(text);
    assert_eq!(b.len(), 1, "{b:#?}");
    b.remove(0)
}

fn codes(text: &str) -> Vec<&'static str> {
    parse(FileId(0), text).1.iter().map(|d| d.code.0).collect()
}

/// An expression printed fully parenthesised, to check precedence and associativity.
fn show(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Number(v) => format!("{v}"),
        ExprKind::Name(n) => n.clone(),
        ExprKind::Indexed(n, i) => format!("{n}[{i}]"),
        ExprKind::Call(f, args) => {
            let a: Vec<String> = args.iter().map(show).collect();
            format!("{}({})", f.name, a.join(", "))
        }
        ExprKind::Node(n) => {
            let p: Vec<&str> = n.path.iter().map(|i| i.name.as_str()).collect();
            match n.port {
                Some((i, _)) => format!("<{}[{i}]>", p.join(".")),
                None => format!("<{}>", p.join(".")),
            }
        }
        ExprKind::Neg(x) => format!("(-{})", show(x)),
        ExprKind::Binary(op, a, b) => {
            let o = match op {
                BinOp::Add => "+",
                BinOp::Sub => "-",
                BinOp::Mul => "*",
                BinOp::Div => "/",
                BinOp::Pow => "^",
            };
            format!("({} {o} {})", show(a), show(b))
        }
    }
}

fn output_expr(src: &str) -> String {
    match one(&format!("output y [1] = {src};")) {
        Stmt::Output(o) => show(&o.value),
        other => panic!("{other:?}"),
    }
}

#[test]
fn empty_input_and_only_comments_give_an_empty_file() {
    assert!(parse_ok("").items.is_empty());
    let f = parse_ok("// one\n// two\n");
    assert!(f.items.is_empty());
    assert_eq!(f.comments.len(), 2);
    assert_eq!(f.comments[0].text, "// one");
}

#[test]
fn precedence_and_associativity() {
    assert_eq!(output_expr("1 + 2 * 3"), "(1 + (2 * 3))");
    assert_eq!(output_expr("1 - 2 - 3"), "((1 - 2) - 3)");
    assert_eq!(output_expr("a / b / c"), "((a / b) / c)");
    assert_eq!(output_expr("a ^ b ^ c"), "(a ^ (b ^ c))");
    assert_eq!(output_expr("-a ^ 2"), "(-(a ^ 2))");
    assert_eq!(output_expr("-a * b"), "((-a) * b)");
    assert_eq!(output_expr("2 ^ -x"), "(2 ^ (-x))");
    assert_eq!(output_expr("(1 + 2) * 3"), "((1 + 2) * 3)");
    assert_eq!(
        output_expr("atan2(y, x) + f(sensor.spring)"),
        "(atan2(y, x) + f(<sensor.spring>))"
    );
    assert_eq!(output_expr("e(leg[2]) * e[1]"), "(e(<leg[2]>) * e[1])");
    assert_eq!(output_expr("f(a + b)"), "f((a + b))");
}

#[test]
fn numbers() {
    assert_eq!(
        output_expr("12 + 0.5 + .5 + 3.06e-4 + 1E6"),
        "((((12 + 0.5) + 0.5) + 0.0003060) + 1000000)".replace("0.0003060", "0.000306")
    );
    assert_eq!(codes("model m { param a = 1e999 [1]; }"), vec!["BG0103"]);
    assert_eq!(codes("model m { param a = 1.2.3 [1]; }"), vec!["BG0103"]);
    assert_eq!(codes("model m { param a = 1e [1]; }"), vec!["BG0103"]);
}

#[test]
fn declarations() {
    match one("/// mass\nparam m = 2 [kg] \"moving mass\";") {
        Stmt::Param(p) => {
            assert_eq!(p.doc, vec!["mass".to_string()]);
            assert_eq!(p.name.name, "m");
            assert_eq!(p.default.kind, ExprKind::Number(2.0));
            assert_eq!(p.unit.numerator, vec![("kg".to_string(), 1)]);
            assert_eq!(p.description.as_deref(), Some("moving mass"));
        }
        other => panic!("{other:?}"),
    }
    match one("param r = n [1];") {
        Stmt::Param(p) => {
            assert_eq!(p.default.kind, ExprKind::Name("n".into()));
            assert!(p.unit.numerator.is_empty() && p.unit.denominator.is_empty());
        }
        other => panic!("{other:?}"),
    }
    match one("input tau [N m/rad] \"torque\";") {
        Stmt::Input(i) => {
            assert_eq!(i.unit.numerator, vec![("N".into(), 1), ("m".into(), 1)]);
            assert_eq!(i.unit.denominator, vec![("rad".into(), 1)]);
        }
        other => panic!("{other:?}"),
    }
    match one("output a [m/s^2] = e(x) + 1;") {
        Stmt::Output(o) => assert_eq!(o.unit.denominator, vec![("s".into(), 2)]),
        other => panic!("{other:?}"),
    }
    match one("var th [rad] = int(f(rotor));") {
        Stmt::Var(v) => assert_eq!(show(&v.integrand), "f(<rotor>)"),
        other => panic!("{other:?}"),
    }
    match one("coords [th, f(rotor), p(m) - q(c)];") {
        Stmt::Coords(c) => assert_eq!(c.coords.len(), 3),
        other => panic!("{other:?}"),
    }
    match one("domain rotational;") {
        Stmt::Domain(d) => assert_eq!(d.domain.name, "rotational"),
        other => panic!("{other:?}"),
    }
    match one("port a = shaft.b;") {
        Stmt::Port(p) => assert_eq!(p.target.path.len(), 2),
        other => panic!("{other:?}"),
    }
}

#[test]
fn elements() {
    let b = body(
        "Se push = F;\nI rotor : rotational = J;\n0 j;\n1 v;\nR fr { e = b0*sign(f) + b2*f; }\n\
         IF leg(2) { mass[1,2] = c; mass[2,2] = c; }\nRF b(2) { e[1] = r*f[1]; e[2] = r*f[2]; };",
    );
    assert_eq!(b.len(), 7);
    let kinds: Vec<ElementKind> = b
        .iter()
        .map(|s| match s {
            Stmt::Element(e) => e.kind,
            other => panic!("{other:?}"),
        })
        .collect();
    use ElementKind::*;
    assert_eq!(kinds, vec![Se, I, Zero, One, R, IF, RF]);
    match &b[1] {
        Stmt::Element(e) => assert_eq!(
            e.domain.as_ref().map(|d| d.name.as_str()),
            Some("rotational")
        ),
        _ => unreachable!(),
    }
    match &b[5] {
        Stmt::Element(e) => {
            assert_eq!(e.ports.map(|p| p.0), Some(2));
            match &e.body {
                ElementBody::Laws(l) => {
                    assert_eq!(l[0].lhs.name, "mass");
                    assert_eq!(
                        l[0].indices.iter().map(|i| i.0).collect::<Vec<_>>(),
                        vec![1, 2]
                    );
                }
                other => panic!("{other:?}"),
            }
        }
        _ => unreachable!(),
    }
}

#[test]
fn instances() {
    match one("spring_damper shaft(k = 500, d = 0.5);") {
        Stmt::Instance(i) => {
            assert_eq!(i.component.name, "spring_damper");
            assert_eq!(i.name.name, "shaft");
            assert_eq!(i.overrides.len(), 2);
            assert_eq!(i.overrides[1].0.name, "d");
        }
        other => panic!("{other:?}"),
    }
    match one("gearbox g;") {
        Stmt::Instance(i) => assert!(i.overrides.is_empty()),
        other => panic!("{other:?}"),
    }
}

#[test]
fn bonds() {
    match one("bond motor -> j1 -> gear -> rotor, fric;") {
        Stmt::Bond(b) => {
            let sizes: Vec<usize> = b.chain.iter().map(Vec::len).collect();
            assert_eq!(sizes, vec![1, 1, 1, 2]);
        }
        other => panic!("{other:?}"),
    }
    match one("bond s1: j2 -> spring stroke! spring;") {
        Stmt::Bond(b) => {
            assert_eq!(b.label.map(|l| l.name), Some("s1".into()));
            let h = b.hint.expect("hint");
            assert!(h.fixed);
            assert_eq!(h.at.path[0].name, "spring");
        }
        other => panic!("{other:?}"),
    }
    match one("bond leg[2] -> coupling.a;") {
        Stmt::Bond(b) => {
            assert_eq!(b.chain[0][0].port.map(|p| p.0), Some(2));
            assert_eq!(b.chain[1][0].path.len(), 2);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(codes("model m { bond a, b -> c; }"), vec!["BG0110"]);
    assert_eq!(codes("model m { bond s: a -> b -> c; }"), vec!["BG0110"]);
    assert_eq!(
        codes("model m { bond a -> b, c stroke b; }"),
        vec!["BG0110"]
    );
    assert_eq!(codes("model m { bond a -> b stroke c; }"), vec!["BG0113"]);
}

#[test]
fn imports_models_and_components() {
    let f = parse_ok("import \"std.bg\";\n/// doc\ncomponent c { port a = j; }\nmodel m { }\n");
    assert_eq!(f.items.len(), 3);
    match &f.items[0] {
        Item::Import(i) => assert_eq!(i.path, "std.bg"),
        other => panic!("{other:?}"),
    }
    match &f.items[1] {
        Item::Model(m) => {
            assert_eq!(m.kind, ModelKind::Component);
            assert_eq!(m.doc, vec!["doc".to_string()]);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn recovery_reports_several_errors() {
    let src = "model m {\n    param a = ;\n    param b = 2 [kg];\n    input c [N;\n    output d [1] = 1 +;\n    R r = 1;\n}\n";
    let (file, diags) = parse(FileId(0), src);
    assert_eq!(
        diags.iter().filter(|d| d.is_error()).count(),
        3,
        "{diags:#?}"
    );
    match &file.items[0] {
        Item::Model(m) => assert_eq!(m.body.len(), 2),
        other => panic!("{other:?}"),
    }
}

#[test]
fn deep_nesting_is_an_error_not_a_crash() {
    let src = format!(
        "model m {{ output y [1] = {}1{}; }}",
        "(".repeat(10_000),
        ")".repeat(10_000)
    );
    assert_eq!(codes(&src), vec!["BG0105"]);
    let src = format!("model m {{ output y [1] = {}1; }}", "-".repeat(10_000));
    assert_eq!(codes(&src), vec!["BG0105"]);
}

/// The ```bg blocks of docs/language.md. A block without a `model`, `component` or `import` at its top level is a
/// fragment of a body and is checked inside a model.
pub(super) fn language_examples() -> Vec<String> {
    let doc = include_str!("../../../docs/language.md");
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in doc.lines() {
        match &mut current {
            None if line.trim_start() == "```bg" => current = Some(String::new()),
            None => {}
            Some(block) if line.trim_start() == "```" => {
                let top_level = block.lines().any(|l| {
                    l.starts_with("model") || l.starts_with("component") || l.starts_with("import")
                });
                out.push(if top_level {
                    block.clone()
                } else {
                    format!("model example {{\n{block}}}\n")
                });
                current = None;
            }
            Some(block) => {
                block.push_str(line);
                block.push('\n');
            }
        }
    }
    out
}

#[test]
fn every_example_of_the_language_reference_parses() {
    let examples = language_examples();
    assert!(
        examples.len() >= 13,
        "found only {} examples",
        examples.len()
    );
    for ex in &examples {
        let (_, diags) = parse(FileId(0), ex);
        assert!(diags.is_empty(), "{ex}\n{diags:#?}");
    }
}
