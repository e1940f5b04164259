//! Rust identifiers for the names of a model.
//!
//! Names in a `.bg` file are identifiers, possibly qualified (`sensor.spring`); in Rust they must be valid, must
//! not be keywords, and must not collide with each other or with the names the generated functions use for their
//! own arguments (`p`, `t`, `x`, `u`, ...). [`Namer`] turns each name into a unique identifier: characters other
//! than letters, digits and `_` become `_`, a leading digit gets a `_` prefix, a keyword or a reserved name gets a
//! `_` suffix, and a name already taken gets `_2`, `_3`, ... appended.

use std::collections::HashSet;
use std::sync::Arc;

/// The identifiers the generated functions use for themselves, and the constants of the module (a `let` cannot
/// shadow a constant).
pub const RESERVED: &[&str] = &[
    "p",
    "t",
    "x",
    "u",
    "dx",
    "y",
    "jac",
    "v",
    "a",
    "b",
    "c",
    "d",
    "params",
    "index",
    "value",
    "values",
    "name",
    "next",
    "out",
    "terms",
    "bgc_sign",
    "bgc_min",
    "bgc_max",
    "m",
    "dm",
    "force",
    "rate",
    "rows",
    "solved",
    "correction",
    "bgc_powi",
    "bgc_solve",
    "bgc_newton",
    "bgc_start",
    "solve_loops",
    "solve_loops_from",
    "loop_values",
    "z",
    "r",
    "s",
    "jz",
    "rz",
    "rv",
    "gz",
    "dz",
    "at",
    "N_TEARS",
    "TEAR_NAMES",
    "LOOP_RTOL",
    "LOOP_MAX_ITERATIONS",
    "LOOP_BRACKET_EVALUATIONS",
    "LOOP_STEP_RTOL",
    "libm",
    "core",
    "N_STATES",
    "N_ENERGY_STATES",
    "N_INPUTS",
    "N_OUTPUTS",
    "N_PARAMS",
    "N_COORDS",
    "STATE_NAMES",
    "INPUT_NAMES",
    "OUTPUT_NAMES",
    "PARAM_NAMES",
    "COORD_NAMES",
    "entry",
    "total",
];

const KEYWORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern",
    "false", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut",
    "pub", "ref", "return", "self", "Self", "static", "struct", "super", "trait", "true", "type",
    "unsafe", "use", "where", "while", "abstract", "become", "box", "do", "final", "macro",
    "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "union", "_",
];

/// `name` with every character that cannot be in an identifier replaced.
pub fn sanitize(name: &str) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

/// Hands out unique identifiers.
#[derive(Clone, Debug, Default)]
pub struct Namer {
    /// Names taken before [`Namer::frozen`], shared by the clones (a model of 10,000 masses has 80,000 names,
    /// and each function body clones the namer of the module).
    frozen: Arc<HashSet<String>>,
    taken: HashSet<String>,
}

impl Namer {
    /// A namer with the generated code's own names already taken.
    pub fn with_reserved() -> Namer {
        Namer {
            frozen: Arc::default(),
            taken: RESERVED.iter().map(|s| s.to_string()).collect(),
        }
    }

    /// The same namer, its names kept where clones share them: cloning it then costs only the names taken since.
    pub fn frozen(self) -> Namer {
        let mut all = Arc::unwrap_or_clone(self.frozen);
        all.extend(self.taken);
        Namer {
            frozen: Arc::new(all),
            taken: HashSet::new(),
        }
    }

    fn is_taken(&self, name: &str) -> bool {
        self.taken.contains(name) || self.frozen.contains(name)
    }

    /// A unique identifier for `name`.
    pub fn ident(&mut self, name: &str) -> String {
        let mut base = sanitize(name);
        if KEYWORDS.contains(&base.as_str()) {
            base.push('_');
        }
        let mut candidate = base.clone();
        let mut k = 2;
        while self.is_taken(&candidate) {
            candidate = format!("{base}_{k}");
            k += 1;
        }
        self.taken.insert(candidate.clone());
        candidate
    }
}

/// `s` as the contents of a Rust string literal.
pub fn string_literal(s: &str) -> String {
    format!("{s:?}")
}

/// `s` made safe for a `///` or `//` comment line (no line breaks).
pub fn comment(s: &str) -> String {
    s.replace(['\n', '\r'], " ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_valid_and_unique() {
        let mut n = Namer::with_reserved();
        assert_eq!(n.ident("J_m"), "J_m");
        assert_eq!(n.ident("sensor.spring"), "sensor_spring");
        assert_eq!(n.ident("sensor_spring"), "sensor_spring_2");
        assert_eq!(n.ident("type"), "type_");
        assert_eq!(n.ident("p"), "p_2");
        assert_eq!(n.ident("2x"), "_2x");
    }
}
