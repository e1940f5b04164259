//! Recovery from statements that do not parse: each syntax error is reported once, and what the failed statement
//! declared is not then reported as unknown wherever it is used.

use super::tests::lower_text;

fn codes_and_messages(text: &str) -> Vec<(&'static str, String)> {
    lower_text(text)
        .1
        .iter()
        .map(|d| (d.code.0, d.message.clone()))
        .collect()
}

/// Five statements with one syntax error each; every name they declare is used further on. Each name used to be
/// reported again as unknown where it was used ("unknown name `u`", "bond to `mass1`, which does not exist").
#[test]
fn names_of_statements_that_do_not_parse_are_not_reported_again() {
    let text = "model c1 {\n    domain translational;\n    param m = 2 [kg;\n    input u [N/m/s];\n    \
                Se src = u;\n    I mass1 = m +;\n    C spring = 1/3;\n    1 j;\n    \
                bond src -> j -> mass1, spring;\n    output v [m/s] = f(mass1);\n    output w [m/s] = u/m;\n    \
                output z [m/s] = v + w + zz;\n}\n";
    assert_eq!(
        codes_and_messages(text),
        vec![
            (
                "BG0101",
                "expected `]` to close the unit, found `;`".to_string()
            ),
            ("BG0116", "malformed unit".to_string()),
            ("BG0101", "expected an expression, found `;`".to_string()),
            // A name no statement declares is still unknown.
            ("BG0201", "unknown name `zz`".to_string()),
        ]
    );
}

/// An instance whose statement does not parse: its ports and elements are not reported as missing.
#[test]
fn an_instance_that_does_not_parse_is_not_reported_again() {
    let text = "component Spring {\n    domain translational;\n    param k = 1 [N/m];\n    C c = 1/k;\n    \
                0 a;\n    port p = a;\n    bond a -> c;\n}\nmodel m {\n    domain translational;\n    \
                Sf push = 1;\n    Spring s(k = );\n    bond push -> s.p;\n    output x [m] = q(s.c);\n}\n";
    let found = codes_and_messages(text);
    assert_eq!(
        found,
        vec![("BG0101", "expected an expression, found `)`".to_string())],
        "{found:?}"
    );
}

/// A domain that is misspelt or does not parse leaves the bonds without one: that follows from its error and is
/// not a second one (BG0311, whose help proposed `domain rotational;` whatever the elements were).
#[test]
fn an_unknown_domain_is_not_followed_by_bonds_without_a_domain() {
    for (domain, code) in [("domain mechanical;", "BG0201"), ("domain;", "BG0101")] {
        let text = format!(
            "model m {{\n    {domain}\n    param k = 1 [N/m];\n    Sf push = 1;\n    C c = 1/k;\n    \
             bond push -> c;\n}}\n"
        );
        let found: Vec<&str> = codes_and_messages(&text).iter().map(|d| d.0).collect();
        assert_eq!(found, vec![code], "{domain}");
    }
}

/// A parameter whose value cannot be computed is one error: 0 stands in for it, and the elements computed from it
/// were then reported with that stand-in ("`i` has an inertia of 0"), also through a derived parameter and an
/// instance's override.
#[test]
fn an_element_of_a_parameter_without_a_value_is_not_checked_with_the_stand_in() {
    let cases = [
        (
            "model a { domain translational; param m = 1/0 [kg]; Se s = 1; I i = m; bond s -> i; }",
            "the value of `m` is not finite",
        ),
        (
            "model a { domain translational; param m = n [kg]; param n = 1 [kg]; Se s = 1; I i = m; bond s -> i; }",
            "unknown name `n`",
        ),
        (
            "model a { domain translational; param m = 1e300*1e300 [kg]; param k = 2*m [kg]; Se s = 1; I i = k; \
             bond s -> i; }",
            "the value of `m` is not finite",
        ),
        (
            "component S { domain translational; param k = 1 [N/m]; C c = 1/k; port p = c; }\n\
             model a { domain translational; Se s = 1; S x(k = 1/0); bond s -> x.p; }",
            "the value of `k` is not finite",
        ),
    ];
    for (text, message) in cases {
        let found = codes_and_messages(text);
        assert_eq!(found.len(), 1, "{text}\n{found:?}");
        assert_eq!(found[0].1, message, "{text}");
    }
    // A value that is computed and unphysical is still reported.
    let found = codes_and_messages(
        "model a { domain translational; param m = 1 [kg]; Se s = 1; I i = m - 1; bond s -> i; }",
    );
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(
        found[0].1,
        "`i` has an inertia of 0 (an inertia must be positive)"
    );
}

/// A bond statement that does not parse, or whose chain has a fan-out before its end, is one error: its nodes
/// were then reported as "not connected" or as 1-ports with two bonds, and the fan-out's guessed bonds as "a bond
/// cannot join a node to itself".
#[test]
fn the_nodes_of_a_bond_statement_in_error_are_not_reported_again() {
    let head = "model a { domain translational; param m = 1 [kg]; Se s = 1; Se t = 2; I i = m; R r = 1; 1 j; ";
    for (bond, message) in [
        (
            "bond s -> j -> i,; bond t -> r; }",
            "expected a node, found `;`",
        ),
        (
            "bond s -> j -> i r; bond t -> r; }",
            "expected `;` after the bond, found `r`",
        ),
        (
            "bond s -> j, t -> j -> i, r; }",
            "a fan-out must end the chain",
        ),
    ] {
        let text = format!("{head}{bond}");
        let found = codes_and_messages(&text);
        assert_eq!(found.len(), 1, "{text}\n{found:?}");
        assert_eq!(found[0].1, message, "{text}");
    }
    // A node that no statement bonds is still reported, with a junction to bond it from that is not itself.
    let (_, diags, _) = super::tests::lower_text(
        "model a { domain translational; Se s = 1; R r = 1; 1 j; bond s -> r; }",
    );
    let helps: Vec<Option<&str>> = diags.iter().map(|d| d.help.as_deref()).collect();
    assert_eq!(
        helps,
        vec![Some(
            "bond it (`bond j1 -> j;`, from a junction) or remove it"
        )]
    );
}

/// A bond to a port an instance does not have is one error: the instance was then also "not connected".
#[test]
fn a_bond_to_an_unknown_port_does_not_leave_its_instance_unconnected() {
    let text = "component S { domain translational; param k = 1 [N/m]; C c = 1/k; port p = c; }\n\
                model a { domain translational; Se s = 1; S sp; bond s -> sp.q; }";
    let found = codes_and_messages(text);
    assert_eq!(
        found,
        vec![(
            "BG0205",
            "instance `sp` (component `S`) has no port `q`".to_string()
        )]
    );
}

/// A model pasted from a paper or a word processor: `×`, `·`, `²`, `⁻¹`, `−`, `→`, typographic quotes and a
/// no-break space. Each is one BG0104 with the ASCII form, and is read as that form: `m·k` went on to "expected
/// `;`, found `k`", `[kg·m²]` to a unit mismatch against `[kg m]`, `“inertia”` to "expected `;`, found `inertia`".
#[test]
fn typographic_characters_are_one_error_each_and_read_as_their_ascii_form() {
    let text = "model a {\n    domain rotational;\n    param J = 2 × 1 [kg·m²] “inertia”;\n    \
                param k = 3 [N·m·rad⁻¹];\n    Se s = −1;\n    I i = J·k/k;\n    C c = 1/k;\n    1\u{a0}j;\n    \
                bond s → j -> i, c;\n}\n";
    let found = codes_and_messages(text);
    let shown: Vec<&str> = found.iter().map(|(_, m)| m.as_str()).collect();
    assert_eq!(
        shown,
        vec![
            "invalid character \"×\"",
            "invalid character \"·\"",
            "invalid character \"²\"",
            "a string between typographic quotes",
            "invalid character \"·\"",
            "invalid character \"·\"",
            "invalid characters \"⁻¹\"",
            "invalid character \"−\"",
            "invalid character \"·\"",
            "invalid character \"\\u{a0}\"",
            "invalid character \"→\"",
        ]
    );
    assert!(found.iter().all(|(code, _)| *code == "BG0104"));
}
