//! Formatter tests: exact layouts, idempotence and meaning preservation.

use super::ast::File;
use super::tests::language_examples;
use super::{format, format_source, parse};
use crate::span::FileId;
use serde_json::Value;

/// The tree without spans, blank-line offsets or comment positions: what a file means (plus its comments' text).
pub(super) fn meaning(file: &File) -> Value {
    fn strip(v: Value) -> Value {
        match v {
            Value::Object(map) => {
                let is_span =
                    map.len() == 3 && map.contains_key("file") && map.contains_key("start");
                if is_span {
                    return Value::Null;
                }
                Value::Object(
                    map.into_iter()
                        .filter(|(k, _)| k != "blank_lines" && k != "own_line")
                        .map(|(k, v)| (k, strip(v)))
                        .collect(),
                )
            }
            Value::Array(items) => Value::Array(items.into_iter().map(strip).collect()),
            other => other,
        }
    }
    strip(serde_json::to_value(file).unwrap_or(Value::Null))
}

/// Formats `src`, checks that formatting again changes nothing and that the tree is the same.
pub(super) fn check_round_trip(src: &str) -> String {
    let (tree, diags) = parse(FileId(0), src);
    assert!(!crate::diagnostic::has_errors(&diags), "{src}\n{diags:#?}");
    let once = format(&tree);
    let (tree2, diags2) = parse(FileId(0), &once);
    assert!(
        !crate::diagnostic::has_errors(&diags2),
        "formatted text has errors:\n{once}\n{diags2:#?}"
    );
    assert_eq!(
        meaning(&tree),
        meaning(&tree2),
        "formatting changed the meaning of\n{src}\ninto\n{once}"
    );
    let twice = format(&tree2);
    assert_eq!(once, twice, "formatting is not idempotent for\n{src}");
    once
}

fn fmt(src: &str) -> String {
    match format_source(FileId(0), src) {
        Ok(s) => s,
        Err(d) => panic!("{d:#?}"),
    }
}

#[test]
fn canonical_layout() {
    let src = "model   m{domain translational;param k=800[N/m]\"spring\";input F[N];\n\
               Se push=F;C spring=1/k;1 v;R fr{e=b0*sign(f)+b2*f;}\n\
               bond push->v->spring,fr;output x[m]=q(spring);}";
    let expected = "model m {\n    domain translational;\n    param k = 800 [N/m] \"spring\";\n    input F [N];\n\n    \
                    Se push = F;\n    C spring = 1 / k;\n    1 v;\n    R fr { e = b0 * sign(f) + b2 * f; }\n\n    \
                    bond push -> v -> spring, fr;\n    output x [m] = q(spring);\n}\n";
    // No blank lines in the source: none in the output.
    assert_eq!(fmt(src), expected.replace("\n\n", "\n"));
}

#[test]
fn minimal_parentheses_keep_the_tree() {
    let cases = [
        ("(a + b) + c", "a + b + c"),
        ("a + (b + c)", "a + (b + c)"),
        ("a - (b - c)", "a - (b - c)"),
        ("(a * b) / c", "a * b / c"),
        ("a / (b * c)", "a / (b * c)"),
        ("(a + b) * c", "(a + b) * c"),
        ("-(a ^ 2)", "-a ^ 2"),
        ("(-a) ^ 2", "(-a) ^ 2"),
        ("(a ^ b) ^ c", "(a ^ b) ^ c"),
        ("a ^ (b ^ c)", "a ^ b ^ c"),
        ("a ^ (-b)", "a ^ -b"),
        // Each parenthesis is a level of nesting to the parser: a negation of a negation goes without.
        ("-(-a)", "--a"),
        ("a * (-b)", "a * -b"),
        ("-(a + b)", "-(a + b)"),
        ("(((x)))", "x"),
        ("f((a))", "f(a)"),
        ("e(x.y) + f(leg[2]) + e[1]", "e(x.y) + f(leg[2]) + e[1]"),
    ];
    for (src, want) in cases {
        let out = check_round_trip(&format!("model m {{\n    output y [1] = {src};\n}}\n"));
        assert_eq!(
            out,
            format!("model m {{\n    output y [1] = {want};\n}}\n"),
            "{src}"
        );
    }
}

/// A file within the parser's nesting limit (200, BG0105) formats to one within it: two groups of 101 terms (each
/// operator of a chain counts a level, so the flat sum of 202 terms is too deep), the same for products and
/// differences, and 101 negations, which `-(-(…))` would nest twice as deep. The layout groups a chain's left
/// operands every 50 operators; the tree, and so the meaning, is the same.
#[test]
fn a_file_within_the_nesting_limit_formats_to_one_within_it() {
    let chain = |op: &str| vec!["p"; 101].join(op);
    let cases = [
        format!("({}) + ({})", chain(" + "), chain(" + ")),
        format!("({}) * ({})", chain(" * "), chain(" * ")),
        format!("({}) - ({})", chain(" - "), chain(" - ")),
        format!("{}p", "-".repeat(101)),
    ];
    for src in cases {
        let file = format!("model m {{\n    param p = 2 [1];\n    output y [1] = {src};\n}}\n");
        let (_, diags) = parse(FileId(0), &file);
        assert!(
            !crate::diagnostic::has_errors(&diags),
            "the case itself parses"
        );
        check_round_trip(&file);
        assert!(format_source(FileId(0), &file).is_ok());
    }
    // A flat chain of 120 terms (119 operators) comes out with 50 operators after each group: the innermost
    // group has the 20 terms left over.
    let flat = vec!["p"; 120].join(" + ");
    let out = check_round_trip(&format!("model m {{\n    output y [1] = {flat};\n}}\n"));
    let more = " + p".repeat(50);
    let want = format!("(({}){more}){more}", vec!["p"; 20].join(" + "));
    assert_eq!(out, format!("model m {{\n    output y [1] = {want};\n}}\n"));
}

#[test]
fn an_index_in_a_parameter_default_keeps_its_parentheses() {
    let out = check_round_trip(
        "model m {\n    param a = (e[1]) * 2 + (-f[2]) [1];\n    param b = n [1];\n}\n",
    );
    assert_eq!(
        out,
        "model m {\n    param a = (e[1] * 2 + -f[2]) [1];\n    param b = n [1];\n}\n"
    );
}

#[test]
fn numbers_round_trip_exactly() {
    let cases = [
        ("12", "12"),
        (".5", "0.5"),
        ("3.06e-4", "3.06e-4"),
        ("0.00119", "0.00119"),
        ("2.64e4", "26400"),
        ("0.40e-4", "4e-5"),
        ("1E6", "1e6"),
        ("1E5", "100000"),
        ("1e-7", "1e-7"),
        ("0.1", "0.1"),
        ("1.7976931348623157e308", "1.7976931348623157e308"),
        ("5e-324", "5e-324"),
        ("0.30000000000000004", "0.30000000000000004"),
        ("123456789012345678", "123456789012345680"),
        ("1e300", "1e300"),
        ("12.", "12"),
        ("1.e5", "100000"),
        ("1E+7", "1e7"),
    ];
    for (src, want) in cases {
        let out = check_round_trip(&format!("model m {{\n    param a = {src} [1];\n}}\n"));
        assert_eq!(
            out,
            format!("model m {{\n    param a = {want} [1];\n}}\n"),
            "{src}"
        );
    }
}

#[test]
fn units_are_canonical() {
    let cases = [
        ("[N  m / rad]", "[N m/rad]"),
        ("[kg m^2]", "[kg m^2]"),
        ("[1]", "[1]"),
        ("[1/s]", "[1/s]"),
        ("[m s^-2]", "[m s^-2]"),
        ("[m/s^2]", "[m/s^2]"),
        ("[µm]", "[µm]"),
    ];
    for (src, want) in cases {
        let out = check_round_trip(&format!("model m {{\n    input u {src};\n}}\n"));
        assert_eq!(
            out,
            format!("model m {{\n    input u {want};\n}}\n"),
            "{src}"
        );
    }
}

#[test]
fn comments_and_docs_are_kept() {
    let src = "// header\nimport \"std.bg\"; // the library\n\n/// The model.\n///\n/// More.\nmodel m { // opening\n\
               /// Mass.\n    param m = 1 [kg]; // trailing\n\n    // leading\n    R r { e = 1 // inside\n * f; }\n    \
               IF leg(2) {\n        // first\n        mass[1, 1] = a;\n        mass[2, 2] = c; // second\n    }\n    \
               // last\n}\n// end\n";
    let out = check_round_trip(src);
    let expected = "// header\nimport \"std.bg\"; // the library\n\n/// The model.\n///\n/// More.\nmodel m {\n    \
                    // opening\n    /// Mass.\n    param m = 1 [kg]; // trailing\n\n    // leading\n    \
                    R r {\n        e = 1 * f; // inside\n    }\n    IF leg(2) {\n        // first\n        \
                    mass[1, 1] = a;\n        mass[2, 2] = c; // second\n    }\n    // last\n}\n// end\n";
    assert_eq!(out, expected);
}

#[test]
fn stray_doc_comments_become_ordinary_comments() {
    let src =
        "model m {\n    param a = 1 /// oops\n        [kg];\n    bond a -> b; /// nothing\n}\n";
    let (_, diags) = parse(FileId(0), src);
    assert_eq!(
        diags.iter().map(|d| d.code.0).collect::<Vec<_>>(),
        vec!["BG0114", "BG0114"]
    );
    let out = check_round_trip(src);
    assert_eq!(
        out,
        "model m {\n    param a = 1 [kg]; // oops\n    bond a -> b; // nothing\n}\n"
    );
}

#[test]
fn files_with_errors_are_refused() {
    let err = format_source(FileId(0), "model m { param a = ; }").err();
    assert!(err.is_some_and(|d| d.iter().any(|d| d.code.0 == "BG0101")));
}

#[test]
fn language_reference_examples_round_trip() {
    for ex in language_examples() {
        check_round_trip(&ex);
    }
}

#[test]
fn crlf_input_formats_to_lf() {
    let out = check_round_trip("model m {\r\n    param a = 1 [kg]; // c\r\n}\r\n");
    assert_eq!(out, "model m {\n    param a = 1 [kg]; // c\n}\n");
}

mod generated_trees {
    //! Random expression trees printed by the formatter must parse back to themselves: this checks the minimal
    //! parenthesisation against every combination of operators, not just the cases written out above.

    use super::super::ast::*;
    use super::super::format::expr;
    use super::super::parse;
    use crate::span::{FileId, Span};
    use proptest::prelude::*;

    fn e(kind: ExprKind) -> Expr {
        Expr {
            kind,
            span: Span::default(),
        }
    }

    fn ident(name: &str) -> Ident {
        Ident {
            name: name.to_string(),
            span: Span::default(),
        }
    }

    fn leaf() -> impl Strategy<Value = Expr> {
        prop_oneof![
            prop_oneof![
                Just(0.0),
                Just(1.0),
                Just(0.1),
                Just(3.06e-4),
                Just(1e300),
                Just(5e-324),
                Just(f64::MAX),
                0.0..1e6f64,
                (0u32..u32::MAX).prop_map(f64::from),
            ]
            .prop_map(|v| e(ExprKind::Number(v))),
            prop::sample::select(vec!["x", "k_1", "t", "pi", "mass"])
                .prop_map(|n| e(ExprKind::Name(n.into()))),
            (prop::sample::select(vec!["e", "f", "p", "q"]), 1u32..5)
                .prop_map(|(n, i)| e(ExprKind::Indexed(n.into(), i))),
            (
                prop::sample::select(vec!["e", "f", "p", "q"]),
                prop::collection::vec(prop::sample::select(vec!["a", "b", "leg"]), 1..3),
                prop::option::of(1u32..4),
            )
                .prop_map(|(f, path, port)| {
                    let node = NodeRef {
                        path: path.iter().map(|p| ident(p)).collect(),
                        port: port.map(|p| (p, Span::default())),
                        span: Span::default(),
                    };
                    e(ExprKind::Call(ident(f), vec![e(ExprKind::Node(node))]))
                }),
        ]
    }

    fn tree() -> impl Strategy<Value = Expr> {
        leaf().prop_recursive(6, 48, 3, |inner| {
            prop_oneof![
                inner.clone().prop_map(|x| e(ExprKind::Neg(Box::new(x)))),
                (
                    prop::sample::select(vec![
                        BinOp::Add,
                        BinOp::Sub,
                        BinOp::Mul,
                        BinOp::Div,
                        BinOp::Pow
                    ]),
                    inner.clone(),
                    inner.clone()
                )
                    .prop_map(|(op, a, b)| e(ExprKind::Binary(
                        op,
                        Box::new(a),
                        Box::new(b)
                    ))),
                (
                    prop::sample::select(vec!["sin", "atan2", "min"]),
                    prop::collection::vec(inner, 0..3)
                )
                    .prop_map(|(f, args)| e(ExprKind::Call(ident(f), args))),
            ]
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 1024, ..ProptestConfig::default() })]

        #[test]
        fn printed_trees_parse_back_to_themselves(t in tree()) {
            let src = format!("model m {{\n    output y [1] = {};\n}}\n", expr(&t));
            let (file, diags) = parse(FileId(0), &src);
            prop_assert!(diags.is_empty(), "{src}\n{diags:?}");
            let value = match file.items.first() {
                Some(Item::Model(m)) => match m.body.first() {
                    Some(Stmt::Output(o)) => o.value.clone(),
                    other => return Err(TestCaseError::fail(format!("{other:?}"))),
                },
                other => return Err(TestCaseError::fail(format!("{other:?}"))),
            };
            let strip = |x: &Expr| super::meaning(&File {
                items: vec![Item::Model(ModelDecl {
                    kind: ModelKind::Model,
                    doc: vec![],
                    name: ident("m"),
                    body: vec![Stmt::Coords(Box::new(CoordsDecl { coords: vec![x.clone()], span: Span::default() }))],
                    unparsed: Unparsed::default(),
                    span: Span::default(),
                })],
                ..File::default()
            });
            prop_assert_eq!(strip(&value), strip(&t), "{}", src);
        }
    }
}

/// A file with CRLF line breaks (a Windows checkout) or a byte-order mark was rewritten with `\n` and without the
/// mark: `bgc fmt` changed every line, and `bgc fmt --check` and the editor's formatting reported a formatted
/// file as unformatted. The layout is canonical; the line breaks and the mark are the file's.
#[test]
fn line_endings_and_byte_order_mark_are_the_files_own() {
    let lf = "model a {\n    domain electrical; // note\n    param r = 1 [Ohm];\n}\n";
    let crlf = lf.replace('\n', "\r\n");
    assert_eq!(
        format_source(FileId(0), &crlf).ok().as_deref(),
        Some(crlf.as_str())
    );
    let messy = "model a {\r\n  domain electrical; // note\r\n  param r=1 [Ohm];}\r\n";
    assert_eq!(
        format_source(FileId(0), messy).ok().as_deref(),
        Some(crlf.as_str())
    );
    let bom = format!("\u{feff}{lf}");
    assert_eq!(
        format_source(FileId(0), &bom).ok().as_deref(),
        Some(bom.as_str())
    );
    let bom_crlf = format!("\u{feff}{crlf}");
    assert_eq!(
        format_source(FileId(0), &bom_crlf).ok().as_deref(),
        Some(bom_crlf.as_str())
    );
    // The first line break decides: a file in LF with one stray CR line is made LF throughout.
    let mixed = "model a {\n    domain electrical;\r\n}\n";
    assert_eq!(
        format_source(FileId(0), mixed).ok().as_deref(),
        Some("model a {\n    domain electrical;\n}\n")
    );
}
