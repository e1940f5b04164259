//! Names written with letters outside ASCII (`ρ`, `τ_m`, `masse_é`), as papers and other tools write them.
//!
//! Names are ASCII. Such a name is one error, not one per letter, and stays one name token, so that the rest of
//! its statement parses without a cascade ("expected the name of the parameter, found `=`"). Greek letters, the
//! ones engineers use for names, have an ASCII spelling to propose (`τ_m` → `tau_m`).

/// The length in bytes of the name at the start of `rest` when it starts with a letter outside ASCII: the run of
/// letters, digits and `_` (of any script).
pub(super) fn name_len(rest: &str) -> Option<usize> {
    let first = rest.chars().next()?;
    if first.is_ascii() || !first.is_alphabetic() {
        return None;
    }
    Some(
        rest.find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len()),
    )
}

/// Whether the lexer reported `name` as a name with letters outside ASCII (every such letter but the micro sign,
/// which names a unit prefix and is reported where it names something else): later stages leave it to that error.
pub fn reported_by_lexer(name: &str) -> bool {
    name.chars()
        .any(|c| !c.is_ascii() && !super::lexer::is_micro(c))
}

/// The help for a name with letters outside ASCII: its ASCII spelling when there is one.
pub(super) fn name_help(name: &str) -> String {
    match ascii_spelling(name) {
        Some(ascii) => format!("names are ASCII letters, digits and `_`: write `{ascii}`"),
        None => "names are ASCII letters, digits and `_`; text belongs in a \"string\"".to_string(),
    }
}

/// The Greek capital omega and the ohm sign (U+2126), which look alike; the ohm is written `Ohm`.
const OHM_SIGNS: [char; 2] = ['\u{3a9}', '\u{2126}'];

/// The help for a unit symbol with letters outside ASCII: the ohm's ASCII symbol (`[kΩ]` → `[kOhm]`), else where
/// the units are listed.
pub(super) fn unit_help(symbol: &str) -> String {
    if symbol.contains(OHM_SIGNS) {
        let ascii = symbol.replace(OHM_SIGNS, "Ohm");
        return match ascii.as_str() {
            "Ohm" => "the ohm is written `Ohm`".to_string(),
            _ => format!("the ohm is written `Ohm`: `{ascii}`"),
        };
    }
    "units are ASCII SI symbols with optional prefixes p n u µ m c d k M G (docs/language.md, Units)".to_string()
}

/// The ASCII spelling of a unit symbol with letters outside ASCII, where there is one: the ohm (`kΩ` → `kOhm`).
pub(super) fn unit_spelling(symbol: &str) -> Option<String> {
    let ascii = symbol.replace(OHM_SIGNS, "Ohm");
    ascii.is_ascii().then_some(ascii)
}

/// `name` with each Greek letter spelled out (`τ_m` → `tau_m`, `Δx` → `Deltax`); `None` when some other letter
/// outside ASCII has no spelling here.
pub fn ascii_spelling(name: &str) -> Option<String> {
    let mut out = String::with_capacity(name.len() + 8);
    for c in name.chars() {
        match c {
            c if c.is_ascii() => out.push(c),
            c => out.push_str(greek(c)?),
        }
    }
    Some(out)
}

/// The name of a Greek letter (upper case for a capital), the micro sign as `mu`.
fn greek(c: char) -> Option<&'static str> {
    const LOWER: [&str; 25] = [
        "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
        "lambda", "mu", "nu", "xi", "omicron", "pi", "rho", "sigma", "sigma", "tau", "upsilon",
        "phi", "chi", "psi", "omega",
    ];
    const UPPER: [&str; 25] = [
        "Alpha", "Beta", "Gamma", "Delta", "Epsilon", "Zeta", "Eta", "Theta", "Iota", "Kappa",
        "Lambda", "Mu", "Nu", "Xi", "Omicron", "Pi", "Rho", "", "Sigma", "Tau", "Upsilon", "Phi",
        "Chi", "Psi", "Omega",
    ];
    let name = match c {
        // α..ω, with the final sigma ς (U+03C2) in its place.
        'α'..='ω' => LOWER[(c as u32 - 'α' as u32) as usize],
        // Α..Ω; U+03A2 is unassigned.
        'Α'..='Ω' => UPPER[(c as u32 - 'Α' as u32) as usize],
        'µ' => "mu",
        'ϑ' => "theta",
        'ϕ' => "phi",
        'ϵ' => "epsilon",
        'ϱ' => "rho",
        _ => return None,
    };
    (!name.is_empty()).then_some(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greek_letters_are_spelled_out() {
        assert_eq!(ascii_spelling("τ_m").as_deref(), Some("tau_m"));
        assert_eq!(ascii_spelling("ω").as_deref(), Some("omega"));
        assert_eq!(ascii_spelling("Δx").as_deref(), Some("Deltax"));
        assert_eq!(ascii_spelling("ς").as_deref(), Some("sigma"));
        assert_eq!(ascii_spelling("Σ").as_deref(), Some("Sigma"));
        assert_eq!(ascii_spelling("µ0").as_deref(), Some("mu0"));
        assert_eq!(ascii_spelling("masse_é"), None);
        assert_eq!(ascii_spelling("\u{3a2}"), None);
    }

    #[test]
    fn the_ohm_is_spelled_in_a_unit() {
        assert_eq!(unit_help("k\u{3a9}"), "the ohm is written `Ohm`: `kOhm`");
        assert_eq!(unit_help("M\u{2126}"), "the ohm is written `Ohm`: `MOhm`");
        assert_eq!(unit_help("\u{3a9}"), "the ohm is written `Ohm`");
        assert!(unit_help("Å").contains("docs/language.md"));
    }

    #[test]
    fn a_name_runs_over_letters_of_any_script() {
        assert_eq!(name_len("ρ = 1"), Some("ρ".len()));
        assert_eq!(name_len("élan_2x;"), Some("élan_2x".len()));
        assert_eq!(name_len("x"), None);
        assert_eq!(name_len("° C"), None);
    }
}
