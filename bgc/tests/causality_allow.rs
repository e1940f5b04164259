//! `allow CODE NODE "reason";`: an intended finding acknowledged at its element leaves the diagnostics; the
//! causality itself is unchanged, a stale or misplaced `allow` is a warning, and only causality warnings located at
//! an element can be allowed. The model is the case that motivated it: `std.bg`'s `dc_motor` driving its `gearbox`,
//! whose input inertia turns rigidly with the rotor (derivative causality, BG0510).

use bgc::causality;
use bgc::diagnostic::{Diagnostic, Severity, render};
use bgc::lower::{MemoryLoader, lower};
use bgc::span::SourceMap;

/// The motor, its gearbox and an elastic shaft to a load; `extra` goes at the end of the model.
fn drive(extra: &str) -> String {
    format!(
        "import \"std.bg\";

model drive {{
    input V [V];
    Se supply: electrical = V;
    dc_motor m;
    gearbox g(ratio = 50);
    spring_damper_rot shaft(k = 300, d = 0.5);
    I load: rotational = 0.01;
    1 w_load;
    bond supply -> m.v;
    bond m.shaft -> g.in;
    bond g.out -> shaft.a;
    bond shaft.b -> w_load -> load;
    output rate [rad/s] = f(load);
{extra}
}}
"
    )
}

/// Lowering and causality diagnostics of `text`, and the names of the storages in derivative causality.
fn analyse(text: &str) -> (Vec<Diagnostic>, Vec<String>, String) {
    let mut sources = SourceMap::new();
    let root = sources.add("drive.bg", text.to_string());
    let (models, mut diags) = lower(&mut sources, root, &mut MemoryLoader::new());
    let mut derivative = Vec::new();
    if let Some(model) = models.first() {
        let (c, cdiags) = causality::analyse(model);
        derivative = c
            .derivative()
            .map(|s| model.graph[s.node].name.clone())
            .collect();
        diags.extend(cdiags);
    }
    let rendered = render::to_text(&sources, &diags, false);
    (diags, derivative, rendered)
}

fn codes(diags: &[Diagnostic]) -> Vec<&'static str> {
    diags.iter().map(|d| d.code.0).collect()
}

#[test]
fn the_gearbox_input_inertia_is_in_derivative_causality_without_an_allow() {
    let (diags, derivative, text) = analyse(&drive(""));
    assert_eq!(codes(&diags), ["BG0510"], "{text}");
    assert!(diags[0].message.contains("`g.inertia`"), "{text}");
    assert_eq!(derivative, ["g.inertia"]);
}

#[test]
fn an_allow_at_the_element_acknowledges_the_finding() {
    let (diags, derivative, text) = analyse(&drive(
        "    allow BG0510 g.inertia \"the gearbox input turns with the rotor\";",
    ));
    assert!(diags.is_empty(), "{text}");
    // Only the report changes: the inertia is still in derivative causality.
    assert_eq!(derivative, ["g.inertia"]);
}

#[test]
fn an_allow_that_matches_no_finding_is_a_warning_at_the_allow() {
    let (diags, _, text) = analyse(&drive("    allow BG0510 m.rotor;"));
    assert_eq!(codes(&diags), ["BG0510", "BG0542"], "{text}");
    let stale = &diags[1];
    assert_eq!(stale.severity, Severity::Warning);
    assert!(stale.message.contains("`allow BG0510 m.rotor`"), "{text}");
    assert!(text.contains("drive.bg:16:5"), "{text}");
}

#[test]
fn only_causality_warnings_at_an_element_can_be_allowed() {
    let (diags, _, text) = analyse(&drive("    allow BG0402 g.inertia;"));
    assert!(codes(&diags).contains(&"BG0209"), "{text}");
    assert!(diags.iter().any(|d| d.is_error()), "{text}");
    let (diags, _, text) = analyse(&drive("    allow BG0510 g.inertial;"));
    assert!(codes(&diags).contains(&"BG0201"), "{text}");
}

#[test]
fn allow_is_formatted_and_read_back() {
    let text = drive("    allow   BG0510   g.inertia\"why\" ;");
    let formatted =
        bgc::syntax::format_source(bgc::span::FileId(0), &text).unwrap_or_else(|d| panic!("{d:?}"));
    assert!(
        formatted.contains("\n    allow BG0510 g.inertia \"why\";\n"),
        "{formatted}"
    );
}
