//! `modelDescription.xml` for FMI 2.0 and 3.0, from the variables of [`super::variables`].

use super::Version;
use super::structure::Dependencies;
use super::variables::{Role, Variable};
use crate::diagnostic::unprintable::{is_unprintable, stand_in};
use crate::units::Dim;
use std::fmt::Write;

/// What the description says about the model besides its variables.
pub struct Header<'a> {
    pub model_name: &'a str,
    pub identifier: &'a str,
    pub guid: &'a str,
    pub description: Option<String>,
}

/// The text of `modelDescription.xml`.
pub fn model_description(
    version: Version,
    h: &Header,
    vars: &[Variable],
    deps: &Dependencies,
) -> String {
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let description = h
        .description
        .as_deref()
        .map(|d| format!(" description=\"{}\"", escape(d)))
        .unwrap_or_default();
    let tool = format!("bgc {}", crate::codegen::rust::BGC_VERSION);
    match version {
        Version::Fmi2 => {
            let _ = writeln!(
                x,
                "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{}\" guid=\"{}\"{description} \
                 generationTool=\"{tool}\" variableNamingConvention=\"flat\" numberOfEventIndicators=\"0\">",
                escape(h.model_name),
                h.guid
            );
            let common = "canGetAndSetFMUstate=\"true\" providesDirectionalDerivative=\"true\"";
            let _ = writeln!(
                x,
                "  <ModelExchange modelIdentifier=\"{}\" completedIntegratorStepNotNeeded=\"true\" {common}/>",
                h.identifier
            );
            let _ = writeln!(
                x,
                "  <CoSimulation modelIdentifier=\"{}\" canHandleVariableCommunicationStepSize=\"true\" {common}/>",
                h.identifier
            );
        }
        Version::Fmi3 => {
            let _ = writeln!(
                x,
                "<fmiModelDescription fmiVersion=\"3.0\" modelName=\"{}\" instantiationToken=\"{}\"{description} \
                 generationTool=\"{tool}\" variableNamingConvention=\"flat\">",
                escape(h.model_name),
                h.guid
            );
            let common = "canGetAndSetFMUState=\"true\" providesDirectionalDerivatives=\"true\"";
            let _ = writeln!(
                x,
                "  <ModelExchange modelIdentifier=\"{}\" needsCompletedIntegratorStep=\"false\" {common}/>",
                h.identifier
            );
            let _ = writeln!(
                x,
                "  <CoSimulation modelIdentifier=\"{}\" canHandleVariableCommunicationStepSize=\"true\" {common}/>",
                h.identifier
            );
        }
    }
    unit_definitions(&mut x, vars);
    // The categories the C interface logs under (`template/fmi2.rs`, `template/fmi3.rs`).
    x.push_str(
        "  <LogCategories>\n    <Category name=\"logStatusError\" description=\"a call refused, and why\"/>\n    \
         <Category name=\"logStatusFatal\" description=\"an internal error\"/>\n  </LogCategories>\n",
    );
    match version {
        Version::Fmi2 => variables2(&mut x, vars),
        Version::Fmi3 => variables3(&mut x, vars),
    }
    structure(&mut x, version, vars, deps);
    x.push_str("</fmiModelDescription>\n");
    x
}

/// One `<Unit>` per distinct unit name, with its SI base-unit exponents and factor.
fn unit_definitions(x: &mut String, vars: &[Variable]) {
    let mut units: Vec<(&str, Dim, f64)> = Vec::new();
    for (name, dim, factor) in vars.iter().filter_map(|v| v.unit.as_ref()) {
        if !units.iter().any(|(n, ..)| n == name) {
            units.push((name, *dim, *factor));
        }
    }
    if units.is_empty() {
        return;
    }
    x.push_str("  <UnitDefinitions>\n");
    for (name, dim, factor) in units {
        let mut base = String::new();
        for (symbol, e) in ["m", "kg", "s", "A", "K", "mol", "cd"].iter().zip(dim.0) {
            if e != 0 {
                let _ = write!(base, " {symbol}=\"{e}\"");
            }
        }
        if factor != 1.0 {
            let _ = write!(base, " factor=\"{}\"", number(factor));
        }
        let _ = writeln!(
            x,
            "    <Unit name=\"{}\">\n      <BaseUnit{base}/>\n    </Unit>",
            escape(name)
        );
    }
    x.push_str("  </UnitDefinitions>\n");
}

fn attributes(v: &Variable) -> (String, String) {
    let description = v
        .description
        .as_deref()
        .map(|d| format!(" description=\"{}\"", escape(d)))
        .unwrap_or_default();
    let unit = v
        .unit
        .as_ref()
        .map(|(n, ..)| format!(" unit=\"{}\"", escape(n)))
        .unwrap_or_default();
    (description, unit)
}

/// `causality`, `variability` and `initial` of a variable (the same words in both versions).
fn kind(v: &Variable, version: Version) -> &'static str {
    match (v.role, version) {
        (Role::Time, _) => "causality=\"independent\" variability=\"continuous\"",
        (Role::Parameter, _) => "causality=\"parameter\" variability=\"fixed\"",
        (Role::Input, _) => "causality=\"input\" variability=\"continuous\"",
        (Role::Output, _) => {
            "causality=\"output\" variability=\"continuous\" initial=\"calculated\""
        }
        (Role::State, _) => "causality=\"local\" variability=\"continuous\" initial=\"exact\"",
        (Role::Derivative(_), _) => {
            "causality=\"local\" variability=\"continuous\" initial=\"calculated\""
        }
    }
}

fn variables2(x: &mut String, vars: &[Variable]) {
    x.push_str("  <ModelVariables>\n");
    // The time is left out: FMI 2.0 then declares it implicitly, and some importers (the FMI Library) refuse an
    // `independent` variable without a start value, which the standard forbids it to have. The value reference
    // 0 it keeps in the binary makes each variable's 1-based index in ModelVariables its value reference.
    for v in vars.iter().filter(|v| v.role != Role::Time) {
        let (description, unit) = attributes(v);
        let start = v
            .start
            .map(|s| format!(" start=\"{}\"", number(s)))
            .unwrap_or_default();
        let derivative = match v.role {
            Role::Derivative(k) => state_vr(vars, k)
                .map(|i| format!(" derivative=\"{i}\""))
                .unwrap_or_default(),
            _ => String::new(),
        };
        let _ = writeln!(
            x,
            "    <ScalarVariable name=\"{}\" valueReference=\"{}\" {}{description}>\n      \
             <Real{unit}{start}{derivative}/>\n    </ScalarVariable>",
            escape(&v.name),
            v.vr,
            kind(v, Version::Fmi2)
        );
    }
    x.push_str("  </ModelVariables>\n");
}

fn variables3(x: &mut String, vars: &[Variable]) {
    x.push_str("  <ModelVariables>\n");
    for v in vars {
        let (description, unit) = attributes(v);
        let start = v
            .start
            .map(|s| format!(" start=\"{}\"", number(s)))
            .unwrap_or_default();
        // FMI 3.0 refers to the state by its value reference.
        let derivative = match v.role {
            Role::Derivative(k) => state_vr(vars, k)
                .map(|i| format!(" derivative=\"{i}\""))
                .unwrap_or_default(),
            _ => String::new(),
        };
        let _ = writeln!(
            x,
            "    <Float64 name=\"{}\" valueReference=\"{}\" {}{description}{unit}{start}{derivative}/>",
            escape(&v.name),
            v.vr,
            kind(v, Version::Fmi3)
        );
    }
    x.push_str("  </ModelVariables>\n");
}

/// The value reference of the state with index `k` among the states (in FMI 2.0 also its 1-based index in
/// `ModelVariables`, see `variables2`).
fn state_vr(vars: &[Variable], k: usize) -> Option<u32> {
    vars.iter()
        .filter(|v| v.role == Role::State)
        .nth(k)
        .map(|v| v.vr)
}

/// `ModelStructure`: outputs, derivatives and initial unknowns. Outputs and derivatives list their dependencies
/// on states and inputs where [`Dependencies`] knows them; initial unknowns list none, which the standard reads as
/// "depends on every state start value, parameter and input" (they depend on the parameters).
fn structure(x: &mut String, version: Version, vars: &[Variable], deps: &Dependencies) {
    let outputs: Vec<&Variable> = vars.iter().filter(|v| v.role == Role::Output).collect();
    let derivatives: Vec<&Variable> = vars
        .iter()
        .filter(|v| matches!(v.role, Role::Derivative(_)))
        .collect();
    // The value reference of each dependency column: the states, then the inputs.
    let columns: Vec<u32> = vars
        .iter()
        .filter(|v| v.role == Role::State)
        .chain(vars.iter().filter(|v| v.role == Role::Input))
        .map(|v| v.vr)
        .collect();
    // FMI 2.0 names variables by their index in ModelVariables, FMI 3.0 by value reference: the same numbers.
    let listed = |sets: &Option<Vec<std::collections::BTreeSet<usize>>>, k: usize| {
        let set = sets.as_ref()?.get(k)?;
        let mut refs: Vec<u32> = set
            .iter()
            .filter_map(|&c| columns.get(c))
            .copied()
            .collect();
        refs.sort_unstable();
        let text: Vec<String> = refs.iter().map(u32::to_string).collect();
        Some(format!(" dependencies=\"{}\"", text.join(" ")))
    };
    let output_deps: Vec<String> = (0..outputs.len())
        .map(|k| listed(&deps.outputs, k).unwrap_or_default())
        .collect();
    let derivative_deps: Vec<String> = (0..derivatives.len())
        .map(|k| listed(&deps.derivatives, k).unwrap_or_default())
        .collect();
    x.push_str("  <ModelStructure>\n");
    match version {
        Version::Fmi2 => {
            let list = |x: &mut String, tag: &str, vs: &[&Variable], extra: &[String]| {
                if vs.is_empty() {
                    return;
                }
                let _ = writeln!(x, "    <{tag}>");
                for (k, v) in vs.iter().enumerate() {
                    let more = extra.get(k).map_or("", String::as_str);
                    let _ = writeln!(x, "      <Unknown index=\"{}\"{more}/>", v.vr);
                }
                let _ = writeln!(x, "    </{tag}>");
            };
            list(x, "Outputs", &outputs, &output_deps);
            list(x, "Derivatives", &derivatives, &derivative_deps);
            let mut initial: Vec<&Variable> = outputs.iter().chain(&derivatives).copied().collect();
            initial.sort_by_key(|v| v.vr);
            list(x, "InitialUnknowns", &initial, &[]);
        }
        Version::Fmi3 => {
            for (v, more) in outputs.iter().zip(&output_deps) {
                let _ = writeln!(x, "    <Output valueReference=\"{}\"{more}/>", v.vr);
            }
            for (v, more) in derivatives.iter().zip(&derivative_deps) {
                let _ = writeln!(
                    x,
                    "    <ContinuousStateDerivative valueReference=\"{}\"{more}/>",
                    v.vr
                );
            }
            for v in outputs.iter().chain(&derivatives) {
                let _ = writeln!(x, "    <InitialUnknown valueReference=\"{}\"/>", v.vr);
            }
        }
    }
    x.push_str("  </ModelStructure>\n");
}

/// A number as XML reads it back exactly (Rust's shortest round-trip form).
fn number(v: f64) -> String {
    format!("{v:?}")
}

/// Text for an XML attribute.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\n' | '\r' | '\t' => out.push(' '),
            // Not characters of XML 1.0 (a reader refuses the whole file), nor meant to be shown: the stand-in.
            c if is_unprintable(c) => out.push(stand_in(c)),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::escape;

    /// XML 1.0's `Char` production: what a conforming reader accepts anywhere in a document.
    fn xml_char(c: char) -> bool {
        matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' | '\u{10000}'..)
    }

    #[test]
    fn an_attribute_holds_only_characters_of_xml_and_no_markup() {
        let hostile = "a\u{1}b\u{1b}[31m\u{7f}\u{85}\u{202e}\u{fffe}\u{ffff}<\"&'>\u{10348}";
        let out = escape(hostile);
        assert!(out.chars().all(xml_char), "{out:?}");
        assert!(!out.contains(['<', '>', '"', '\'']), "{out:?}");
        assert_eq!(
            out,
            "a␁b␛[31m␡\u{fffd}\u{fffd}\u{fffd}\u{fffd}&lt;&quot;&amp;&apos;&gt;\u{10348}"
        );
    }
}
