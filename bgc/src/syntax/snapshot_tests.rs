//! Snapshot tests: an outline of the tree of every valid fixture, the rendered diagnostics of every invalid fixture,
//! and the formatting of a file written carelessly.

use super::ast::*;
use super::{decode, format_source, parse};
use crate::diagnostic::render;
use crate::span::{FileId, SourceMap};
use std::fmt::Write;
use std::path::{Path, PathBuf};

fn fixture_files(kind: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(kind);
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.flatten().map(|e| e.path()).collect())
        .unwrap_or_default();
    files.retain(|p| p.extension().is_some_and(|e| e == "bg"));
    files.sort();
    files
}

/// An expression as an S-expression, which shows its structure.
fn sexpr(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Number(v) => format!("{v:?}"),
        ExprKind::Name(n) => n.clone(),
        ExprKind::Indexed(n, i) => format!("{n}[{i}]"),
        ExprKind::Call(f, args) => {
            let mut s = format!("(call {}", f.name);
            for a in args {
                s.push(' ');
                s.push_str(&sexpr(a));
            }
            s + ")"
        }
        ExprKind::Node(n) => format!("<{}>", super::format::node(n)),
        ExprKind::Neg(x) => format!("(neg {})", sexpr(x)),
        ExprKind::Binary(op, a, b) => {
            let o = match op {
                BinOp::Add => "+",
                BinOp::Sub => "-",
                BinOp::Mul => "*",
                BinOp::Div => "/",
                BinOp::Pow => "^",
            };
            format!("({o} {} {})", sexpr(a), sexpr(b))
        }
    }
}

fn at(s: crate::span::Span) -> String {
    format!("@{}..{}", s.start, s.end)
}

/// One line per item, statement and law, with spans.
fn outline(file: &File) -> String {
    let mut o = String::new();
    for item in &file.items {
        match item {
            Item::Import(i) => {
                let _ = writeln!(o, "import {:?} {}", i.path, at(i.span));
            }
            Item::Model(m) => {
                let _ = writeln!(
                    o,
                    "{:?} {} doc={:?} {}",
                    m.kind,
                    m.name.name,
                    m.doc,
                    at(m.span)
                );
                for s in &m.body {
                    let _ = writeln!(o, "  {}", stmt(s));
                    if let Stmt::Element(e) = s
                        && let ElementBody::Laws(laws) = &e.body
                    {
                        for l in laws {
                            let idx: Vec<u32> = l.indices.iter().map(|i| i.0).collect();
                            let _ = writeln!(
                                o,
                                "    law {}{:?} = {} {}",
                                l.lhs.name,
                                idx,
                                sexpr(&l.rhs),
                                at(l.span)
                            );
                        }
                    }
                }
            }
        }
    }
    for c in &file.comments {
        let _ = writeln!(
            o,
            "comment {:?} own_line={} {}",
            c.text,
            c.own_line,
            at(c.span)
        );
    }
    o
}

fn stmt(s: &Stmt) -> String {
    use super::format::{node, unit};
    match s {
        Stmt::Domain(d) => format!("domain {} {}", d.domain.name, at(d.span)),
        Stmt::Param(p) => format!(
            "param {} = {} {} {:?} doc={:?} {}",
            p.name.name,
            sexpr(&p.default),
            unit(&p.unit),
            p.description,
            p.doc,
            at(p.span)
        ),
        Stmt::Input(i) => format!(
            "input {} {} {:?} {}",
            i.name.name,
            unit(&i.unit),
            i.description,
            at(i.span)
        ),
        Stmt::Output(x) => format!(
            "output {} {} = {} {:?} {}",
            x.name.name,
            unit(&x.unit),
            sexpr(&x.value),
            x.description,
            at(x.span)
        ),
        Stmt::Var(v) => format!(
            "var {} {} = int {} {}",
            v.name.name,
            unit(&v.unit),
            sexpr(&v.integrand),
            at(v.span)
        ),
        Stmt::Coords(c) => {
            let cs: Vec<String> = c.coords.iter().map(sexpr).collect();
            format!("coords [{}] {}", cs.join(", "), at(c.span))
        }
        Stmt::Element(e) => {
            let body = match &e.body {
                ElementBody::None => String::new(),
                ElementBody::Value(v) => format!(" = {}", sexpr(v)),
                ElementBody::Laws(l) => format!(" laws={}", l.len()),
            };
            format!(
                "element {:?} {} ports={:?} domain={:?}{body} doc={:?} {}",
                e.kind,
                e.name.name,
                e.ports.map(|p| p.0),
                e.domain.as_ref().map(|d| &d.name),
                e.doc,
                at(e.span)
            )
        }
        Stmt::Instance(i) => {
            let ov: Vec<String> = i
                .overrides
                .iter()
                .map(|(n, v)| format!("{}={}", n.name, sexpr(v)))
                .collect();
            format!(
                "instance {} {} ({}) {}",
                i.component.name,
                i.name.name,
                ov.join(", "),
                at(i.span)
            )
        }
        Stmt::Bond(b) => {
            let chain: Vec<String> = b
                .chain
                .iter()
                .map(|g| format!("[{}]", g.iter().map(node).collect::<Vec<_>>().join(", ")))
                .collect();
            let hint = b
                .hint
                .as_ref()
                .map(|h| format!(" stroke{} {}", if h.fixed { "!" } else { "" }, node(&h.at)))
                .unwrap_or_default();
            let label = b
                .label
                .as_ref()
                .map(|l| format!("{}: ", l.name))
                .unwrap_or_default();
            format!("bond {label}{}{hint} {}", chain.join(" -> "), at(b.span))
        }
        Stmt::Port(p) => format!("port {} = {} {}", p.name.name, node(&p.target), at(p.span)),
        Stmt::Allow(a) => format!("allow {} {} {}", a.code.name, node(&a.target), at(a.span)),
    }
}

#[test]
fn valid_fixture_trees() {
    for path in fixture_files("valid") {
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let (tree, diags) = parse(FileId(0), &text);
        assert!(diags.is_empty(), "{}: {diags:#?}", path.display());
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("fixture")
            .to_string();
        insta::assert_snapshot!(format!("tree_{name}"), outline(&tree));
    }
}

#[test]
fn invalid_fixture_diagnostics() {
    let mut all = String::new();
    for path in fixture_files("invalid") {
        let bytes = std::fs::read(&path).unwrap_or_default();
        let name = path
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or("fixture")
            .to_string();
        // The syntax stage's fixtures are the BG01xx ones; later stages' fixtures parse cleanly by design.
        if !(name.starts_with("BG01") && !name.starts_with("BG0107") && !name.starts_with("BG0108"))
        {
            continue;
        }
        let mut sources = SourceMap::new();
        let diags = match decode(FileId(0), &bytes) {
            Ok(text) => {
                sources.add(name.clone(), text);
                parse(FileId(0), text).1
            }
            Err(d) => {
                sources.add(name.clone(), String::from_utf8_lossy(&bytes).into_owned());
                vec![d]
            }
        };
        let _ = writeln!(all, "===== {name}");
        all.push_str(&render::to_text(&sources, &diags, false));
    }
    insta::assert_snapshot!("invalid_fixtures", all);
}

#[test]
fn careless_layout_is_formatted() {
    let src = "import \"std.bg\";import \"lib/parts.bg\" ;\n\
               /// Doc of m.\nmodel m{domain rotational;\n\n\n\
               param J=3.06E-4[kg  m^2]\"rotor \\\"inertia\\\"\";param k = 2.64e4 [ N m / rad ] ;\n\
               input tau[N m];   // motor\n\
               Se s=tau;1 w;I r=J;C c=1/k;TF g=160;MTF lever=l*cos(theta);\n\
               R fr{e=b0*sign(f)+b2*f;}\n\
               CF s2(2):rotational{e[1]=k1*q[1]-k12*q[2];e[2]=k2*q[2]-k12*q[1];}\n\
               spring_damper sd(k=500,d=(0.5));gearbox gb();\n\
               bond s->w->r,fr;bond x : w->c stroke!c;bond w->sd.a;bond sd.b->s2[1];\n\
               var th[rad]=int(f(r));coords[th,f(r)];port a=w;\n\
               output y[N m/rad]=-(e(c)+e(fr))^2/(2*k)*-1 \"odd\";}\n";
    match format_source(FileId(0), src) {
        Ok(out) => insta::assert_snapshot!("careless_layout", out),
        Err(d) => panic!("{d:#?}"),
    }
}
