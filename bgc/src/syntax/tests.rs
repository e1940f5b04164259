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
            let sizes: Vec<usize> = b.chain.iter().map(|g| g.len()).collect();
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
    let src = format!("model m {{ output y [1] = {}1; }}", "2 ^ ".repeat(10_000));
    assert_eq!(codes(&src), vec!["BG0105"]);
    // A long chain builds a deep tree too.
    let src = format!("model m {{ output y [1] = {}1; }}", "x + ".repeat(10_000));
    assert_eq!(codes(&src), vec!["BG0105"]);
    let src = format!("model m {{ output y [1] = {}1; }}", "x * ".repeat(10_000));
    assert_eq!(codes(&src), vec!["BG0105"]);
    // The advice for a long chain is to group its terms, and 400 terms in 20 groups of 20 are within the limit.
    let src = format!("model m {{ output y [1] = {}1; }}", "x + ".repeat(400));
    let (_, diags) = parse(FileId(0), &src);
    assert!(
        diags[0]
            .help
            .as_deref()
            .unwrap_or("")
            .contains("group the terms"),
        "{diags:#?}"
    );
    let group = format!("({}x)", "x + ".repeat(19));
    let src = format!(
        "model m {{ output y [1] = {}; }}",
        vec![group; 20].join(" + ")
    );
    assert!(codes(&src).is_empty());
    // Within the limit, all is well: 150 terms, 150 parentheses.
    let src = format!("model m {{ output y [1] = {}1; }}", "x + ".repeat(150));
    assert!(codes(&src).is_empty());
    let src = format!(
        "model m {{ output y [1] = {}1{}; }}",
        "(".repeat(150),
        ")".repeat(150)
    );
    assert!(codes(&src).is_empty());
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

#[test]
fn megabyte_long_line() {
    let stmt = "param p = 1 [kg]; ";
    let n = 1_000_000 / stmt.len();
    let mut src = String::from("model m { ");
    for i in 0..n {
        src.push_str(&stmt.replace("p =", &format!("p{i} =")));
    }
    src.push('}');
    assert!(src.len() > 1_000_000);
    assert_eq!(body_of(&parse_ok(&src)).len(), n);
    // One name a megabyte long.
    let long = "x".repeat(1 << 20);
    let f = parse_ok(&format!("model m {{ input {long} [1]; }}"));
    match &body_of(&f)[0] {
        Stmt::Input(i) => assert_eq!(i.name.name.len(), 1 << 20),
        other => panic!("{other:?}"),
    }
}

fn body_of(f: &File) -> &[Stmt] {
    match f.items.first() {
        Some(Item::Model(m)) => &m.body,
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_unit_with_only_a_comment_inside_is_reported_empty() {
    let (_, diags) = parse(FileId(0), "model m { param a = 1 [ // none\n ]; }");
    assert_eq!(diags.len(), 1, "{diags:#?}");
    assert_eq!(diags[0].code.0, "BG0116");
}

#[test]
fn a_unit_after_a_value_is_not_taken_for_an_index() {
    let (_, diags) = parse(FileId(0), "model m { C spring = 1/k [m/N]; }");
    assert_eq!(diags.len(), 1, "{diags:#?}");
    assert_eq!(diags[0].code.0, "BG0101");
    let said = diags[0].help.as_deref().unwrap_or("");
    assert!(
        said.contains("units are not written in an expression"),
        "{said}"
    );
    // After a number or a `)`, wherever the expression stops at the `[`: the end of the statement, a parenthesis, a
    // call's arguments.
    for text in [
        "C spring = 0.5 [m/N];",
        "C s { e = k*q^3/(1 [m^2]); }",
        "output y [m] = (a) [m];",
        "output y [m] = max(a, 2 [m]);",
    ] {
        let (_, diags) = parse(FileId(0), &format!("model m {{ {text} }}"));
        assert_eq!(diags.len(), 1, "{text}: {diags:#?}");
        let said = diags[0].help.as_deref().unwrap_or("");
        assert!(
            said.contains("units are not written in an expression"),
            "{text}: {said}"
        );
    }
    // A unit without brackets after a number, or a product without its `*`.
    for text in ["I mass = 2 kg;", "C spring = 2 k;"] {
        let (_, diags) = parse(FileId(0), &format!("model m {{ {text} }}"));
        assert_eq!(diags.len(), 1, "{diags:#?}");
        let said = diags[0].help.as_deref().unwrap_or("");
        assert!(
            said.contains("to multiply, write `*`") && said.contains("a unit is not written"),
            "{said}"
        );
    }
    // A missing `;` or `)` elsewhere keeps its own help.
    let (_, diags) = parse(FileId(0), "model m { C spring = 0.5 R; }");
    assert_eq!(
        diags[0].help.as_deref(),
        Some("end every statement with `;`")
    );
    // An index is still an index.
    let (_, diags) = parse(
        FileId(0),
        "model m { CF s(2) { e[1] = k * q[2]; e[2] = k * q[1]; } }",
    );
    assert!(diags.is_empty(), "{diags:#?}");
}

#[test]
fn characters_of_typeset_formulas_say_what_to_write() {
    for (text, help) in [
        ("param a = 90 [°];", "`deg`"),
        ("output y [1] = 2 · x;", "`*`"),
        ("output y [1] = x²;", "`^`"),
        ("output y [1] = 2 − x;", "`-`"),
        ("bond a <- b;", "`bond a -> b;`"),
        ("output y [1] = 2 * π;", "`pi`"),
        ("output y [1] = x > 0;", "`sign(x)`"),
    ] {
        let (_, diags) = parse(FileId(0), &format!("model m {{ {text} }}"));
        if text.contains('°') {
            // One error, at the character: `[°]` is not reported as an empty unit besides.
            assert_eq!(diags.len(), 1, "{text}: {diags:#?}");
        }
        let junk = diags.iter().find(|d| d.code.0 == "BG0104");
        let said = junk.and_then(|d| d.help.as_deref()).unwrap_or("");
        assert!(said.contains(help), "{text}: {diags:#?}");
    }
}

#[test]
fn comments_and_powers_as_other_languages_write_them_say_what_to_write() {
    // A `#` or `%` comment is one error and the rest of its line is skipped, not an error per word.
    for text in [
        "# the plant\n    param k = 1 [N/m];",
        "% the plant\n    param k = 1 [N/m];",
        "param k = 1 [N/m]; # stiffness",
        "param k = 1 [N/m]; % stiffness",
    ] {
        let (file, diags) = parse(FileId(0), &format!("model m {{\n    {text}\n}}"));
        assert_eq!(diags.len(), 1, "{text}: {diags:#?}");
        assert_eq!(diags[0].code.0, "BG0104");
        assert!(
            diags[0]
                .help
                .as_deref()
                .unwrap_or("")
                .contains("comments start with `//`")
        );
        assert_eq!(file.items.len(), 1, "{text}");
    }
    // A `%` as a unit is no comment.
    let (_, diags) = parse(FileId(0), "model m { param eff = 90 [%]; }");
    let said = diags
        .iter()
        .find(|d| d.code.0 == "BG0104")
        .and_then(|d| d.help.as_deref());
    assert!(
        said.unwrap_or("").contains("write a fraction"),
        "{diags:#?}"
    );
    let (_, diags) = parse(FileId(0), "model m { output y [1] = x**2; }");
    assert_eq!(diags.len(), 1, "{diags:#?}");
    assert!(
        diags[0].help.as_deref().unwrap_or("").contains("`x^2`"),
        "{diags:#?}"
    );
}

#[test]
fn declarations_as_other_tools_write_them_say_what_to_write() {
    for (text, help) in [
        ("input u [N] = 0;", "an input has no value in the file"),
        (
            "Se:source = u;",
            "write the kind, a space and the name: `Se source = ...;`",
        ),
    ] {
        let (_, diags) = parse(FileId(0), &format!("model m {{ {text} }}"));
        assert_eq!(diags.len(), 1, "{text}: {diags:#?}");
        assert!(
            diags[0].help.as_deref().unwrap_or("").contains(help),
            "{text}: {diags:#?}"
        );
    }
}

#[test]
fn binary_junk_is_one_diagnostic_per_run() {
    let junk: String = (0..100_000)
        .map(|i| char::from(b"#$%&?@`|~\x01"[i % 10]))
        .collect();
    let (file, diags) = parse(FileId(0), &junk);
    assert!(file.items.is_empty());
    assert_eq!(diags.len(), 1, "{:?}", &diags[..diags.len().min(3)]);
    assert_eq!(diags[0].code.0, "BG0104");
    assert_eq!(diags[0].primary_span().map(|s| s.range()), Some(0..100_000));
    // Junk between two models is reported and the models are kept.
    let (file, diags) = parse(FileId(0), "model a {}\n@@@ junk ###\nmodel b {}\n");
    assert_eq!(file.items.len(), 2);
    let c: Vec<&str> = diags.iter().map(|d| d.code.0).collect();
    assert_eq!(c, vec!["BG0104", "BG0101", "BG0104"]);
}

#[test]
fn crlf_line_endings() {
    let src = "/// Doc.\r\nmodel m {\r\n    param a = 1 [kg]; // c\r\n    bond a -> b;\r\n}\r\n";
    let f = parse_ok(src);
    match &f.items[0] {
        Item::Model(m) => {
            assert_eq!(m.doc, vec!["Doc.".to_string()]);
            assert_eq!(m.body.len(), 2);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(f.comments[0].text, "// c");
    // A missing `;` before a CRLF line break is found as before an LF one.
    let (_, d) = parse(
        FileId(0),
        "model m {\r\n    param a = 1 [kg]\r\n    param b = 2 [kg];\r\n}\r\n",
    );
    assert_eq!(d.len(), 1);
    let end_of_unit = "model m {\r\n    param a = 1 [kg]".len();
    assert_eq!(
        d[0].primary_span().map(|s| s.range()),
        Some(end_of_unit..end_of_unit)
    );
}

#[test]
fn missing_semicolon_before_a_statement_on_the_same_line() {
    let src = "model m { param a = 1 [kg] param b = 2 [kg]; }";
    let (file, diags) = parse(FileId(0), src);
    assert_eq!(diags.len(), 1);
    let end = "model m { param a = 1 [kg]".len();
    assert_eq!(diags[0].primary_span().map(|s| s.range()), Some(end..end));
    assert_eq!(body_of(&file).len(), 2);
}

#[test]
fn keyword_as_name_is_reported_and_the_statement_kept() {
    let (file, diags) = parse(FileId(0), "model m { param bond = 1 [1]; C R = 1; }");
    let c: Vec<&str> = diags.iter().map(|d| d.code.0).collect();
    assert_eq!(c, vec!["BG0109", "BG0109"]);
    assert_eq!(body_of(&file).len(), 2);
}

#[test]
fn misspelt_keyword_gets_a_suggestion() {
    let (_, diags) = parse(FileId(0), "model m { parm k = 1 [1]; }");
    assert_eq!(diags.len(), 1);
    assert_eq!(
        diags[0].help.as_deref(),
        Some("did you mean the keyword `param`?")
    );
}

#[test]
fn unclosed_paren_points_at_the_opening() {
    let src = "model m { output y [1] = (1 + 2; }";
    let (_, diags) = parse(FileId(0), src);
    assert_eq!(diags.len(), 1);
    let d = &diags[0];
    assert_eq!(d.code.0, "BG0101");
    assert_eq!(d.primary_span().map(|s| s.range()), Some(31..32));
    let secondary: Vec<_> = d
        .labels
        .iter()
        .filter(|l| !l.primary)
        .map(|l| l.span.range())
        .collect();
    assert_eq!(secondary, vec![25..26]);
}

#[test]
fn unclosed_law_block_stops_at_the_next_statement() {
    let src = "model m {\n    R r { e = f;\n    param k = 1 [1];\n}\n";
    let (file, diags) = parse(FileId(0), src);
    let c: Vec<&str> = diags.iter().map(|d| d.code.0).collect();
    assert_eq!(c, vec!["BG0106"]);
    assert_eq!(body_of(&file).len(), 2);
}

#[test]
fn spans_are_byte_ranges() {
    let src = "model m {\n    param µk = 1 [µm];\n    output y [1] = 2 * x;\n}\n";
    let (file, diags) = parse(FileId(0), src);
    // `µk` is not a name (non-ASCII); `µm` is a unit.
    assert_eq!(
        diags.iter().map(|d| d.code.0).collect::<Vec<_>>(),
        vec!["BG0104"]
    );
    let y = match &body_of(&file)[1] {
        Stmt::Output(o) => o.clone(),
        other => panic!("{other:?}"),
    };
    assert_eq!(&src[y.span.range()], "output y [1] = 2 * x;");
    assert_eq!(&src[y.value.span.range()], "2 * x");
    assert_eq!(&src[y.unit.span.range()], "[1]");
}

#[test]
fn decode_points_at_the_first_bad_byte() {
    use super::decode;
    assert_eq!(decode(FileId(3), b"model m {}"), Ok("model m {}"));
    // 0xC3 0x28: a two-byte sequence broken by its second byte; the error covers the first byte only.
    let d = decode(FileId(3), b"ab\xC3\x28cd").expect_err("an error");
    assert_eq!(d.code.0, "BG0100");
    assert_eq!(
        d.primary_span(),
        Some(crate::span::Span::new(FileId(3), 2, 3))
    );
    // A sequence cut short by the end of the file runs to the end.
    let d = decode(FileId(0), "é".as_bytes().get(..1).unwrap_or(&[])).expect_err("an error");
    assert_eq!(d.primary_span().map(|s| s.range()), Some(0..1));
    let d = decode(FileId(0), b"ab\xE2\x82").expect_err("an error");
    assert_eq!(d.primary_span().map(|s| s.range()), Some(2..4));
}

#[test]
fn a_file_in_utf16_is_one_error_that_says_so() {
    use super::decode;
    let text = "model m {\n}\n";
    let le: Vec<u8> = text.encode_utf16().flat_map(u16::to_le_bytes).collect();
    let be: Vec<u8> = text.encode_utf16().flat_map(u16::to_be_bytes).collect();
    let cases = [
        ([&[0xFF, 0xFE][..], &le].concat(), "byte-order mark"),
        ([&[0xFE, 0xFF][..], &be].concat(), "byte-order mark"),
        (le, "every other byte is zero"),
    ];
    for (bytes, why) in cases {
        let d = decode(FileId(0), &bytes).expect_err("UTF-16");
        assert_eq!(d.code.0, "BG0100");
        assert!(
            d.message.starts_with("the file is UTF-16 text, not UTF-8") && d.message.contains(why),
            "{}",
            d.message
        );
    }
    // One stray zero byte in a UTF-8 file is left to the lexer (an invalid character, located).
    assert!(decode(FileId(0), b"model m {\0\n  domain electrical;\n}\n").is_ok());
}

#[test]
fn byte_order_mark_is_ignored() {
    let f = parse_ok("\u{feff}model m { param a = 1 [kg]; }");
    assert_eq!(body_of(&f).len(), 1);
    match &body_of(&f)[0] {
        Stmt::Param(p) => assert_eq!(p.name.span.range(), 19..20),
        other => panic!("{other:?}"),
    }
}

#[test]
fn unclosed_unit_bracket_at_a_line_end() {
    let src = "model m {\n    param k = 800 [N/m\n    C s = 1 / k;\n}\n";
    let (file, diags) = parse(FileId(0), src);
    assert_eq!(diags.len(), 1, "{diags:#?}");
    let end = "model m {\n    param k = 800 [N/m".len();
    assert_eq!(diags[0].primary_span().map(|s| s.range()), Some(end..end));
    // The next statement is read, not swallowed as unit symbols.
    assert!(matches!(body_of(&file), [Stmt::Element(_)]));
}

#[test]
fn operators_of_other_tools_in_a_unit_say_how_to_write_it() {
    for (unit, at, help) in [
        ("[N*m]", "*", "multiply by a space"),
        ("[N.m]", ".", "multiply by a space"),
        ("[kg*m^2/s]", "*", "multiply by a space"),
        ("[m/s/s]", "/", "one `/`"),
    ] {
        let src = format!("model m {{ param a = 1 {unit}; }}");
        let (_, diags) = parse(FileId(0), &src);
        assert_eq!(diags.len(), 1, "{unit}: {diags:#?}");
        assert_eq!(diags[0].code.0, "BG0116", "{unit}");
        let start = src.find(unit).unwrap_or(0) + unit.rfind(at).unwrap_or(0);
        let span = diags[0].primary_span().map(|s| s.range());
        assert_eq!(span, Some(start..start + 1), "{unit}");
        let said = diags[0].help.as_deref().unwrap_or("");
        assert!(said.contains(help), "{unit}: {said}");
    }
}

/// Each `*` or `.` between factors is one error whose certain fix is a space, and the unit is read as meant, so the
/// statement stands (before, the first one dropped the statement and the rest were never seen).
#[test]
fn each_multiplication_in_a_unit_is_fixed_by_a_space_and_the_unit_is_read() {
    let src = "model m { param a = 1 [kg*m.s^-2]; }";
    let (file, diags) = parse(FileId(0), src);
    let found: Vec<(&str, Option<&str>, Option<usize>)> = diags
        .iter()
        .map(|d| {
            (
                d.code.0,
                d.fix(),
                d.primary_span().map(|s| s.start as usize),
            )
        })
        .collect();
    assert_eq!(
        found,
        [
            ("BG0116", Some(" "), src.find('*')),
            ("BG0116", Some(" "), src.find(".s")),
        ]
    );
    let [Stmt::Param(p)] = body_of(&file) else {
        panic!("{file:?}");
    };
    let factors: Vec<(&str, i32)> = p
        .unit
        .numerator
        .iter()
        .map(|(s, n)| (s.as_str(), *n))
        .collect();
    assert_eq!(factors, [("kg", 1), ("m", 1), ("s", -2)]);
    // `*` that is not between two factors has no certain fix.
    let (_, diags) = parse(FileId(0), "model m { param a = 1 [N m*]; }");
    assert_eq!(diags.len(), 1, "{diags:#?}");
    assert_eq!(diags[0].fix(), None);
}

/// Hyphens as other texts write units: a product (`[N-m]`), a power without `^` (`[m s-2]`) and the
/// dimensionless `[-]` of engineering tables. Each is one error with its certain fix, and the unit is read as meant.
#[test]
fn hyphens_in_a_unit_are_read_as_meant_with_their_fix() {
    for (unit, fix, numerator, denominator) in [
        ("[N-m]", " ", vec![("N", 1), ("m", 1)], vec![]),
        ("[m s-2]", "^-", vec![("m", 1), ("s", -2)], vec![]),
        (
            "[kg/m s-1]",
            "^-",
            vec![("kg", 1)],
            vec![("m", 1), ("s", -1)],
        ),
        ("[-]", "1", vec![], vec![]),
    ] {
        let src = format!("model m {{ param a = 1 {unit}; }}");
        let (file, diags) = parse(FileId(0), &src);
        let fixes: Vec<Option<&str>> = diags.iter().map(|d| d.fix()).collect();
        assert_eq!(fixes, [Some(fix)], "{unit}: {diags:#?}");
        let at = src.find(unit).unwrap_or(0) + unit.find('-').unwrap_or(0);
        assert_eq!(
            diags[0].primary_span().map(|s| s.start as usize),
            Some(at),
            "{unit}"
        );
        let [Stmt::Param(p)] = body_of(&file) else {
            panic!("{unit}: {file:?}");
        };
        let read =
            |fs: &[(String, i32)]| fs.iter().map(|(s, n)| (s.clone(), *n)).collect::<Vec<_>>();
        let want = |fs: Vec<(&str, i32)>| {
            fs.into_iter()
                .map(|(s, n)| (s.to_string(), n))
                .collect::<Vec<_>>()
        };
        assert_eq!(read(&p.unit.numerator), want(numerator), "{unit}");
        assert_eq!(read(&p.unit.denominator), want(denominator), "{unit}");
    }
}

/// MATLAB's element-wise operators: one error each whose fix removes the dot, and the expression is the one meant
/// (`m.^2/m` is `(m^2)/m`), so no error follows from it.
#[test]
fn elementwise_operators_are_read_as_the_operator_with_the_dot_removed() {
    let with_dots = "model m { param a = 1 [1]; param b = a.^2 ./a.*3 [1]; }";
    let without = "model m { param a = 1 [1]; param b = a^2/a*3 [1]; }";
    let (file, diags) = parse(FileId(0), with_dots);
    let found: Vec<(Option<&str>, Option<usize>)> = diags
        .iter()
        .map(|d| (d.fix(), d.primary_span().map(|s| s.start as usize)))
        .collect();
    let dots: Vec<(Option<&str>, Option<usize>)> = with_dots
        .match_indices(['.'])
        .map(|(i, _)| (Some(""), Some(i)))
        .collect();
    assert_eq!(found, dots);
    let (plain, none) = parse(FileId(0), without);
    assert!(none.is_empty(), "{none:#?}");
    // The tree without places: numbers, names and operators.
    fn shape(e: &Expr) -> String {
        match &e.kind {
            ExprKind::Binary(op, a, b) => format!("({} {op:?} {})", shape(a), shape(b)),
            ExprKind::Number(v) => v.to_string(),
            ExprKind::Name(n) => n.clone(),
            other => format!("{other:?}"),
        }
    }
    let value = |f: &File| match body_of(f) {
        [_, Stmt::Param(p)] => shape(&p.default),
        other => panic!("{other:?}"),
    };
    assert_eq!(value(&file), "(((a Pow 2) Div a) Mul 3)");
    assert_eq!(value(&plain), value(&file));
}

/// Statements as other languages write them get the statement bgc has: Modelica's `parameter`, a `const`, a unit
/// without its brackets.
#[test]
fn statements_of_other_languages_say_what_to_write() {
    for (stmt, help) in [
        ("parameter m = 1 [kg];", "did you mean the keyword `param`?"),
        ("const m = 1 [kg];", "did you mean the keyword `param`?"),
        ("param m = 1 kg;", "a unit goes in brackets: `[kg]`"),
        ("input u N;", "a unit goes in brackets: `[N]`"),
        (
            "param k = 2 N/m \"spring\";",
            "a unit goes in brackets: `[N/m]`",
        ),
        (
            "param g = 9.81 m/s^2;",
            "a unit goes in brackets: `[m/s^2]`",
        ),
    ] {
        let (_, diags) = parse(FileId(0), &format!("model m {{ {stmt} }}"));
        assert_eq!(diags.len(), 1, "{stmt}: {diags:#?}");
        assert_eq!(diags[0].help.as_deref(), Some(help), "{stmt}");
    }
}

#[test]
fn a_bad_model_name_is_one_error_and_the_body_is_read() {
    let (file, diags) = parse(FileId(0), "model 3 { param a = 1 [1]; }");
    assert_eq!(diags.len(), 1, "{diags:#?}");
    assert_eq!(body_of(&file).len(), 1);
}

#[test]
fn is_keyword_matches_the_keyword_list() {
    use super::parser::{KEYWORDS, is_keyword};
    for k in KEYWORDS {
        assert!(is_keyword(k), "{k}");
    }
    for w in [
        "", "models", "Model", "c", "i", "TF1", "0", "1", "x", "bonds", "hin",
    ] {
        assert!(!is_keyword(w), "{w}");
    }
}

/// A file of garbage is a bounded list of errors: each invalid character and each failed statement was one
/// diagnostic, so the 64 MiB a file may have made gigabytes of them (2,000,000 `·` took 1.5 GB). The lexer lists
/// 1,000 and counts the rest in one; the parser stops reading after 1,000 syntax errors and says so.
#[test]
fn a_file_of_garbage_is_a_bounded_list_of_errors() {
    let dots = format!("model a {{ param m = 1{} [kg]; }}", "·".repeat(5000));
    let (_, diags) = parse(FileId(0), &dots);
    assert_eq!(diags.len(), 1002, "{:?}", diags.last());
    assert!(
        diags
            .iter()
            .any(|d| d.message == "4000 more lexical errors are not listed")
    );
    let statements = format!("model a {{ {} }}", "x; ".repeat(3000));
    let (_, diags) = parse(FileId(0), &statements);
    assert_eq!(diags.len(), 1001);
    assert_eq!(
        diags.last().map(|d| d.message.as_str()),
        Some("more than 1000 syntax errors: the rest of the file is not read")
    );
}

#[test]
fn a_control_character_or_direction_override_in_a_string_is_refused_and_kept_out() {
    let text = "model m {\n  param k = 1 [1] \"a\u{1b}[31mb\u{202e}c\u{fffe}\";\n}\n";
    let (file, diags) = parse(FileId(0), text);
    let found: Vec<(&str, &str, Option<&str>)> = diags
        .iter()
        .map(|d| {
            let at = d.labels.iter().find(|l| l.primary).map(|l| l.span.range());
            (
                d.code.0,
                at.and_then(|r| text.get(r)).unwrap_or(""),
                d.fix(),
            )
        })
        .collect();
    assert_eq!(
        found,
        vec![
            ("BG0104", "\u{1b}", Some("")),
            ("BG0104", "\u{202e}", Some("")),
            ("BG0104", "\u{fffe}", Some("")),
        ]
    );
    assert!(
        diags[0].message.contains(r#""\u{1b}""#),
        "{}",
        diags[0].message
    );
    // The statement is kept, its description holding visible stand-ins only.
    let Some(Item::Model(m)) = file.items.first() else {
        panic!("{file:?}")
    };
    match m.body.first() {
        Some(Stmt::Param(p)) => {
            assert_eq!(p.description.as_deref(), Some("a␛[31mb\u{fffd}c\u{fffd}"))
        }
        other => panic!("{other:?}"),
    }
    // A tab and text in any script are printable.
    assert!(codes("model m { param k = 1 [1] \"a\tµ → Ω 日\"; }").is_empty());
}

#[test]
fn a_lone_carriage_return_ends_a_comment() {
    // Classic Mac OS line breaks: the comment ends at its line's `\r`, not at the end of the file.
    let text = "model m {\r  // a comment\r  domain electrical;\r  Se s = 1;\r  R r = 2;\r  bond s -> r;\r}\r";
    let file = parse_ok(text);
    let Some(Item::Model(m)) = file.items.first() else {
        panic!("{file:?}")
    };
    assert_eq!(m.body.len(), 4, "{:#?}", m.body);
}
