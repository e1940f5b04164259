//! Physical units and dimension checking.
//!
//! A [`Unit`] is a dimension (integer exponents of the seven SI base units m, kg, s, A, K, mol, cd) and a scale that
//! converts a value in that unit to SI base units: `mm` is `m` with scale 1e-3, `rpm` is `1/s` with scale 2π/60.
//! The radian and the steradian are dimensionless, as in SI, so `[N m/rad]` and `[N m]` are one dimension.
//!
//! Symbols are parsed by exact match first (so `min` is the minute, `mol` the mole, `cd` the candela, `Pa` the
//! pascal, `m` the metre) and only then as an SI prefix followed by a prefixable unit (`mm`, `kN`, `µs`, `mA`).
//! The kilogram is the base unit; the gram is `1e-3 kg` and takes prefixes (`mg`); `kg` itself is matched exactly.

mod help;

pub use help::unknown_symbol_help;

use crate::ir::Domain;
use crate::syntax::ast::UnitExpr;
use serde::Serialize;
use std::fmt;

/// Exponents of the SI base dimensions, in the order m, kg, s, A, K, mol, cd.
/// The radian and steradian are dimensionless, as in SI.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct Dim(pub [i8; 7]);

/// A unit: a dimension and the factor that converts a value in this unit to SI base units
/// (`mm` is `Dim(m)` with scale 1e-3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Unit {
    pub dim: Dim,
    pub scale: f64,
}

const BASE_SYMBOLS: [&str; 7] = ["m", "kg", "s", "A", "K", "mol", "cd"];

impl Dim {
    /// The dimension of a pure number.
    pub const NONE: Dim = Dim([0; 7]);

    /// Builds a dimension from exponents of (m, kg, s, A, K, mol, cd).
    pub const fn new(m: i8, kg: i8, s: i8, a: i8, k: i8, mol: i8, cd: i8) -> Dim {
        Dim([m, kg, s, a, k, mol, cd])
    }

    pub fn is_dimensionless(self) -> bool {
        self == Dim::NONE
    }

    /// The product of two dimensions, or `None` if an exponent leaves the range of `i8`.
    pub fn checked_mul(self, other: Dim) -> Option<Dim> {
        self.combine(other, |a, b| a.checked_add(b))
    }

    /// The quotient of two dimensions, or `None` if an exponent leaves the range of `i8`.
    pub fn checked_div(self, other: Dim) -> Option<Dim> {
        self.combine(other, |a, b| a.checked_sub(b))
    }

    /// The integer power, or `None` on overflow.
    pub fn powi(self, n: i32) -> Option<Dim> {
        let mut out = [0i8; 7];
        for (o, &a) in out.iter_mut().zip(self.0.iter()) {
            *o = i8::try_from(i32::from(a).checked_mul(n)?).ok()?;
        }
        Some(Dim(out))
    }

    /// The square root, when every exponent is even.
    pub fn sqrt(self) -> Option<Dim> {
        let mut out = [0i8; 7];
        for (o, &a) in out.iter_mut().zip(self.0.iter()) {
            if a % 2 != 0 {
                return None;
            }
            *o = a / 2;
        }
        Some(Dim(out))
    }

    fn combine(self, other: Dim, op: impl Fn(i8, i8) -> Option<i8>) -> Option<Dim> {
        let mut out = [0i8; 7];
        for ((o, &a), &b) in out.iter_mut().zip(self.0.iter()).zip(other.0.iter()) {
            *o = op(a, b)?;
        }
        Some(Dim(out))
    }

    /// The sum of the absolute exponents: how many base symbols it takes to write this dimension.
    fn weight(self) -> u32 {
        self.0.iter().map(|e| e.unsigned_abs() as u32).sum()
    }
}

impl Unit {
    /// The dimensionless unit `[1]`.
    pub const ONE: Unit = Unit {
        dim: Dim::NONE,
        scale: 1.0,
    };

    pub const fn new(dim: Dim, scale: f64) -> Unit {
        Unit { dim, scale }
    }

    /// A coherent SI unit (scale 1) of this dimension.
    pub const fn si(dim: Dim) -> Unit {
        Unit { dim, scale: 1.0 }
    }

    pub fn checked_mul(self, other: Unit) -> Option<Unit> {
        Some(Unit::new(
            self.dim.checked_mul(other.dim)?,
            self.scale * other.scale,
        ))
    }

    pub fn checked_div(self, other: Unit) -> Option<Unit> {
        Some(Unit::new(
            self.dim.checked_div(other.dim)?,
            self.scale / other.scale,
        ))
    }

    pub fn powi(self, n: i32) -> Option<Unit> {
        Some(Unit::new(self.dim.powi(n)?, self.scale.powi(n)))
    }

    /// The square root, when every exponent is even.
    pub fn sqrt(self) -> Option<Unit> {
        Some(Unit::new(self.dim.sqrt()?, self.scale.sqrt()))
    }

    /// True when both measure the same dimension (scales may differ: `mm` and `m`).
    pub fn same_dim(self, other: Unit) -> bool {
        self.dim == other.dim
    }
}

/// Why a unit could not be parsed.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum UnitError {
    #[error("unknown unit `{symbol}`")]
    UnknownSymbol { symbol: String },
    #[error("the exponents of the unit are too large")]
    Overflow,
}

// Dimensions used by the tables below.
const D_M: Dim = Dim::new(1, 0, 0, 0, 0, 0, 0);
const D_KG: Dim = Dim::new(0, 1, 0, 0, 0, 0, 0);
const D_S: Dim = Dim::new(0, 0, 1, 0, 0, 0, 0);
const D_A: Dim = Dim::new(0, 0, 0, 1, 0, 0, 0);
const D_K: Dim = Dim::new(0, 0, 0, 0, 1, 0, 0);
const D_MOL: Dim = Dim::new(0, 0, 0, 0, 0, 1, 0);
const D_CD: Dim = Dim::new(0, 0, 0, 0, 0, 0, 1);
const D_HZ: Dim = Dim::new(0, 0, -1, 0, 0, 0, 0);
const D_N: Dim = Dim::new(1, 1, -2, 0, 0, 0, 0);
const D_PA: Dim = Dim::new(-1, 1, -2, 0, 0, 0, 0);
const D_J: Dim = Dim::new(2, 1, -2, 0, 0, 0, 0);
const D_W: Dim = Dim::new(2, 1, -3, 0, 0, 0, 0);
const D_C: Dim = Dim::new(0, 0, 1, 1, 0, 0, 0);
const D_V: Dim = Dim::new(2, 1, -3, -1, 0, 0, 0);
const D_F: Dim = Dim::new(-2, -1, 4, 2, 0, 0, 0);
const D_OHM: Dim = Dim::new(2, 1, -3, -2, 0, 0, 0);
const D_S_IEMENS: Dim = Dim::new(-2, -1, 3, 2, 0, 0, 0);
const D_WB: Dim = Dim::new(2, 1, -2, -1, 0, 0, 0);
const D_T: Dim = Dim::new(0, 1, -2, -1, 0, 0, 0);
const D_H: Dim = Dim::new(2, 1, -2, -2, 0, 0, 0);
const D_M3: Dim = Dim::new(3, 0, 0, 0, 0, 0, 0);

/// Symbols that take SI prefixes, with their unit.
const PREFIXABLE: [(&str, Unit); 23] = [
    ("m", Unit::si(D_M)),
    ("g", Unit::new(D_KG, 1e-3)),
    ("s", Unit::si(D_S)),
    ("A", Unit::si(D_A)),
    ("K", Unit::si(D_K)),
    ("mol", Unit::si(D_MOL)),
    ("cd", Unit::si(D_CD)),
    ("rad", Unit::ONE),
    ("sr", Unit::ONE),
    ("Hz", Unit::si(D_HZ)),
    ("N", Unit::si(D_N)),
    ("Pa", Unit::si(D_PA)),
    ("J", Unit::si(D_J)),
    ("W", Unit::si(D_W)),
    ("C", Unit::si(D_C)),
    ("V", Unit::si(D_V)),
    ("F", Unit::si(D_F)),
    ("Ohm", Unit::si(D_OHM)),
    ("S", Unit::si(D_S_IEMENS)),
    ("Wb", Unit::si(D_WB)),
    ("T", Unit::si(D_T)),
    ("H", Unit::si(D_H)),
    ("L", Unit::new(D_M3, 1e-3)),
];

/// Symbols matched only exactly (no prefixes).
const EXACT: [(&str, Unit); 7] = [
    ("1", Unit::ONE),
    ("kg", Unit::si(D_KG)),
    ("min", Unit::new(D_S, 60.0)),
    ("h", Unit::new(D_S, 3600.0)),
    ("deg", Unit::new(Dim::NONE, std::f64::consts::PI / 180.0)),
    ("rpm", Unit::new(D_HZ, 2.0 * std::f64::consts::PI / 60.0)),
    ("Ω", Unit::si(D_OHM)),
];

const PREFIXES: [(&str, f64); 11] = [
    ("p", 1e-12),
    ("n", 1e-9),
    ("u", 1e-6),
    ("µ", 1e-6),
    ("m", 1e-3),
    ("c", 1e-2),
    ("d", 1e-1),
    ("k", 1e3),
    ("M", 1e6),
    ("G", 1e9),
    ("μ", 1e-6), // U+03BC GREEK SMALL LETTER MU, which keyboards produce as often as U+00B5
];

/// Parses one unit symbol such as `m`, `mm`, `kN`, `min`, `µs`.
pub fn parse_symbol(symbol: &str) -> Option<Unit> {
    resolve_symbol(symbol).map(|(_, u)| u)
}

/// One unit symbol as the table's symbol it is made from (`kHz` is `Hz`) and its unit, the prefix applied.
fn resolve_symbol(symbol: &str) -> Option<(&'static str, Unit)> {
    let exact = EXACT
        .iter()
        .chain(PREFIXABLE.iter())
        .find(|(name, _)| *name == symbol);
    if let Some(&(name, u)) = exact {
        return Some((name, u));
    }
    for (prefix, factor) in PREFIXES {
        if let Some(rest) = symbol.strip_prefix(prefix)
            && let Some(&(name, u)) = PREFIXABLE.iter().find(|(name, _)| *name == rest)
        {
            return Some((name, Unit::new(u.dim, u.scale * factor)));
        }
    }
    None
}

/// Every unit symbol, with its unit (the prefixable ones also take the SI prefixes `p n µ m c d k M G`).
pub fn symbols() -> impl Iterator<Item = (&'static str, Unit)> {
    EXACT.iter().chain(PREFIXABLE.iter()).copied()
}

/// Parses a bracketed unit of the AST (`[N m/rad]`, `[kg m^2]`, `[1]`).
pub fn parse_unit(u: &UnitExpr) -> Result<Unit, UnitError> {
    let mut out = Unit::ONE;
    for (list, sign) in [(&u.numerator, 1i32), (&u.denominator, -1i32)] {
        for (symbol, power) in list {
            let base = parse_symbol(symbol).ok_or_else(|| UnitError::UnknownSymbol {
                symbol: symbol.clone(),
            })?;
            let p = power.checked_mul(sign).ok_or(UnitError::Overflow)?;
            let factor = base.powi(p).ok_or(UnitError::Overflow)?;
            out = out.checked_mul(factor).ok_or(UnitError::Overflow)?;
        }
    }
    Ok(out)
}

/// Whether a unit text (as [`parse_unit_text`] reads it) counts cycles (`Hz`, with any prefix) and whether it counts
/// angle (`rad`, `deg`, `rpm`). Both kinds are `1/s` apart from a factor, since the radian is dimensionless; but a
/// hertz is one cycle per second and a cycle is 2π rad, so a value converted between the two would be off by 2π.
pub fn cycles_and_angle(text: &str) -> (bool, bool) {
    let mut cycles = false;
    let mut angle = false;
    for factor in text.split(|c: char| c.is_whitespace() || c == '/') {
        let symbol = factor.split('^').next().unwrap_or("");
        match resolve_symbol(symbol.trim_matches(|c| c == '(' || c == ')')) {
            Some(("Hz", _)) => cycles = true,
            Some(("rad" | "deg" | "rpm", _)) => angle = true,
            _ => {}
        }
    }
    (cycles, angle)
}

/// Parses a unit written as in a `.bg` file but without the brackets (`mH`, `N m/rad`, `rad/s^2`, `1`), as the
/// command line takes it after a number: `--param 'L_a=2.5 [mH]'`.
pub fn parse_unit_text(text: &str) -> Result<Unit, String> {
    let (num, den) = match text.split_once('/') {
        Some((n, d)) => (n, Some(d)),
        None => (text, None),
    };
    let factors = |part: &str| -> Result<Vec<(String, i32)>, String> {
        let mut out = Vec::new();
        for f in part.split_whitespace() {
            if let Some(help) = operator_in_factor(f) {
                return Err(format!("`{f}`: {help}"));
            }
            let (symbol, power) = match f.split_once('^') {
                Some((b, p)) => match p.parse::<i32>() {
                    Ok(v) if v != 0 && !p.starts_with('+') => (b, v),
                    _ => return Err(format!("`{f}`: a unit's power is a non-zero whole number")),
                },
                None => (f, 1),
            };
            out.push((symbol.to_string(), power));
        }
        Ok(out)
    };
    let mut numerator = factors(num)?;
    if numerator.len() == 1 && numerator[0] == ("1".to_string(), 1) && den.is_some() {
        numerator.clear();
    }
    let denominator = match den {
        Some(d) => {
            let d = d.trim().trim_start_matches('(').trim_end_matches(')');
            let list = factors(d)?;
            if list.is_empty() || d.contains('/') {
                return Err(format!(
                    "`{text}`: one `/` followed by the denominator's units"
                ));
            }
            list
        }
        None => Vec::new(),
    };
    if numerator.is_empty() && denominator.is_empty() {
        return Err("an empty unit: write `1` for a dimensionless value".into());
    }
    parse_unit(&UnitExpr {
        numerator,
        denominator,
        span: crate::span::Span::default(),
    })
    .map_err(|e| match &e {
        UnitError::UnknownSymbol { symbol } => format!("{e}: {}", unknown_symbol_help(symbol)),
        _ => e.to_string(),
    })
}

/// What to write for a factor with an operator inside, as other tools write units: `N*m`, `N.m`, `N-m` (a space
/// between the factors) or `s-1` (`s^-1`).
fn operator_in_factor(factor: &str) -> Option<String> {
    // Only before a `^`: `s^-1` is a power.
    let base = factor.split_once('^').map_or(factor, |(b, _)| b);
    let (stem, rest) = base.split_once(['*', '.', '-'])?;
    if stem.is_empty() || rest.is_empty() {
        return None;
    }
    let power = rest.bytes().all(|b| b.is_ascii_digit()) && base.contains('-');
    Some(match power {
        true => format!("a unit's power follows `^`: `{stem}^-{rest}`"),
        false => format!(
            "unit factors multiply by a space: `{}`",
            factor.replace(['*', '.', '-'], " ")
        ),
    })
}

/// The unit as it was written, `N m/rad`, for messages.
pub fn unit_text(u: &UnitExpr) -> String {
    let part = |list: &[(String, i32)]| {
        list.iter()
            .map(|(s, p)| {
                if *p == 1 {
                    s.clone()
                } else {
                    format!("{s}^{p}")
                }
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let num = if u.numerator.is_empty() {
        "1".to_string()
    } else {
        part(&u.numerator)
    };
    if u.denominator.is_empty() {
        num
    } else if u.denominator.len() == 1 {
        format!("{num}/{}", part(&u.denominator))
    } else {
        format!("{num}/({})", part(&u.denominator))
    }
}

/// Derived units the display may use to shorten a dimension, tried in this order. The joule is left out on purpose
/// so that a torque reads `N m`.
const DISPLAY_DERIVED: [(&str, Dim); 7] = [
    ("N", D_N),
    ("Pa", D_PA),
    ("W", D_W),
    ("V", D_V),
    ("Ohm", D_OHM),
    ("F", D_F),
    ("H", D_H),
];

impl Dim {
    /// The writing with the fewest symbols: base units alone, or one derived unit (to the power ±1) times base
    /// units, the derived unit chosen from `derived`. Ties keep the earlier candidate, base units first.
    fn shortest(self, derived: &[(&'static str, Dim)]) -> (u32, Option<(&'static str, i8)>, Dim) {
        let mut best: (u32, Option<(&str, i8)>, Dim) = (self.weight(), None, self);
        for &(name, d) in derived {
            for p in [1i8, -1] {
                let Some(rest) = d.powi(i32::from(p)).and_then(|dp| self.checked_div(dp)) else {
                    continue;
                };
                // A derived unit must not bring in a mass the dimension does not have: `m/s^2` must not read
                // `N/kg` (but a compliance `kg^-1 s^2` reads `m/N`).
                let introduces = self.0[1] == 0 && rest.0[1] != 0;
                let w = rest.weight() + 1;
                if !introduces && w < best.0 {
                    best = (w, Some((name, p)), rest);
                }
            }
        }
        best
    }

    /// The other way a datasheet writes an electromechanical unit: a unit with a current written with the volt is
    /// also given with the newton (`V s` = `N m/A`, a motor's torque and back-EMF constant), and one written with
    /// the newton also with the volt (`N/A` = `V s/m`), when that takes at most two symbols more.
    pub fn datasheet_form(self) -> Option<String> {
        if self.0[3] == 0 {
            return None;
        }
        let (w, derived, _) = self.shortest(&DISPLAY_DERIVED);
        let other: &[(&'static str, Dim)] = match derived {
            Some(("N", _)) => &[("V", D_V)],
            Some(("V", _)) | Some(("W", _)) => &[("N", D_N)],
            _ => return None,
        };
        let alt = self.shortest(other);
        (alt.1.is_some() && alt.0 <= w + 2).then(|| write_dim(alt.1, alt.2))
    }
}

/// `derived` (a unit and its power) times the base units of `rest`, as [`Dim`]'s display writes it.
fn write_dim(derived: Option<(&str, i8)>, rest: Dim) -> String {
    let mut num: Vec<String> = Vec::new();
    let mut den: Vec<String> = Vec::new();
    let mut push = |name: &str, p: i8| {
        let target = if p > 0 { &mut num } else { &mut den };
        let a = p.unsigned_abs();
        if a == 1 {
            target.push(name.to_string());
        } else {
            target.push(format!("{name}^{a}"));
        }
    };
    if let Some((name, p)) = derived {
        push(name, p);
    }
    // Mass first, as engineers write `kg m^2`.
    for i in [1usize, 0, 2, 3, 4, 5, 6] {
        if rest.0[i] != 0 {
            push(BASE_SYMBOLS[i], rest.0[i]);
        }
    }
    let n = if num.is_empty() {
        "1".to_string()
    } else {
        num.join(" ")
    };
    match den.len() {
        0 => n,
        1 => format!("{n}/{}", den[0]),
        _ => format!("{n}/({})", den.join(" ")),
    }
}

impl fmt::Display for Dim {
    /// Readable SI form: `N m s`, `1/(N m)`, `kg m^2`, `V`, `1`; an electromechanical unit also in its other
    /// datasheet form, `V s (= N m/A)` (see [`Dim::datasheet_form`]).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (_, derived, rest) = self.shortest(&DISPLAY_DERIVED);
        write!(f, "{}", write_dim(derived, rest))?;
        match self.datasheet_form() {
            Some(alt) => write!(f, " (= {alt})"),
            None => Ok(()),
        }
    }
}

impl fmt::Display for Unit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.scale == 1.0 {
            write!(f, "{}", self.dim)
        } else {
            write!(f, "{} {}", self.scale, self.dim)
        }
    }
}

/// The units of one domain's power and energy variables, with the way they are written in docs/language.md.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DomainUnits {
    pub effort: Dim,
    pub flow: Dim,
    pub momentum: Dim,
    pub displacement: Dim,
    pub effort_text: &'static str,
    pub flow_text: &'static str,
    pub momentum_text: &'static str,
    pub displacement_text: &'static str,
}

/// The per-domain units table of docs/language.md.
pub fn domain_units(d: Domain) -> DomainUnits {
    match d {
        Domain::Translational => DomainUnits {
            effort: D_N,
            flow: Dim::new(1, 0, -1, 0, 0, 0, 0),
            momentum: Dim::new(1, 1, -1, 0, 0, 0, 0),
            displacement: D_M,
            effort_text: "N",
            flow_text: "m/s",
            momentum_text: "N s",
            displacement_text: "m",
        },
        Domain::Rotational => DomainUnits {
            effort: D_J,
            flow: D_HZ,
            momentum: Dim::new(2, 1, -1, 0, 0, 0, 0),
            displacement: Dim::NONE,
            effort_text: "N m",
            flow_text: "rad/s",
            momentum_text: "N m s",
            displacement_text: "rad",
        },
        Domain::Electrical => DomainUnits {
            effort: D_V,
            flow: D_A,
            momentum: D_WB,
            displacement: D_C,
            effort_text: "V",
            flow_text: "A",
            momentum_text: "V s",
            displacement_text: "C",
        },
        Domain::Hydraulic => DomainUnits {
            effort: D_PA,
            flow: Dim::new(3, 0, -1, 0, 0, 0, 0),
            momentum: Dim::new(-1, 1, -1, 0, 0, 0, 0),
            displacement: D_M3,
            effort_text: "Pa",
            flow_text: "m^3/s",
            momentum_text: "Pa s",
            displacement_text: "m^3",
        },
        Domain::Thermal => DomainUnits {
            effort: D_K,
            flow: Dim::new(2, 1, -3, 0, -1, 0, 0),
            momentum: Dim::new(0, 0, 1, 0, 1, 0, 0),
            displacement: Dim::new(2, 1, -2, 0, -1, 0, 0),
            effort_text: "K",
            flow_text: "W/K",
            momentum_text: "K s",
            displacement_text: "J/K",
        },
    }
}

/// The expected dimension and the conventional way to write the linear parameter of a `C` (compliance), `I`
/// (inertia) or `R` (resistance) in a domain: `q/e`, `p/f`, `e/f`.
pub fn storage_parameter_unit(
    kind: crate::syntax::ast::ElementKind,
    d: Domain,
) -> Option<(Dim, &'static str)> {
    use crate::syntax::ast::ElementKind as K;
    let u = domain_units(d);
    let (num, den) = match kind {
        K::C => (u.displacement, u.effort),
        K::I => (u.momentum, u.flow),
        K::R => (u.effort, u.flow),
        _ => return None,
    };
    let text = match (kind, d) {
        (K::C, Domain::Translational) => "m/N",
        (K::C, Domain::Rotational) => "rad/(N m)",
        (K::C, Domain::Electrical) => "F",
        (K::C, Domain::Hydraulic) => "m^3/Pa",
        (K::C, Domain::Thermal) => "J/K^2",
        (K::I, Domain::Translational) => "kg",
        (K::I, Domain::Rotational) => "kg m^2",
        (K::I, Domain::Electrical) => "H",
        (K::I, Domain::Hydraulic) => "Pa s^2/m^3",
        (K::I, Domain::Thermal) => "K^2 s/W",
        (K::R, Domain::Translational) => "N s/m",
        (K::R, Domain::Rotational) => "N m s/rad",
        (K::R, Domain::Electrical) => "Ohm",
        (K::R, Domain::Hydraulic) => "Pa s/m^3",
        _ => "K^2/W",
    };
    Some((num.checked_div(den)?, text))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::span::Span;

    fn unit(num: &[(&str, i32)], den: &[(&str, i32)]) -> Result<Unit, UnitError> {
        let conv = |l: &[(&str, i32)]| l.iter().map(|(s, p)| (s.to_string(), *p)).collect();
        parse_unit(&UnitExpr {
            numerator: conv(num),
            denominator: conv(den),
            span: Span::default(),
        })
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * b.abs().max(1.0)
    }

    #[test]
    fn metre_milli_and_minute_are_told_apart() {
        assert_eq!(parse_symbol("m"), Some(Unit::si(D_M)));
        let mm = parse_symbol("mm").unwrap_or(Unit::ONE);
        assert_eq!(mm.dim, D_M);
        assert!(close(mm.scale, 1e-3));
        let ms = parse_symbol("ms").unwrap_or(Unit::ONE);
        assert_eq!(ms.dim, D_S);
        assert!(close(ms.scale, 1e-3));
        assert_eq!(parse_symbol("min"), Some(Unit::new(D_S, 60.0)));
        assert_eq!(parse_symbol("mol"), Some(Unit::si(D_MOL)));
        assert_eq!(parse_symbol("cd"), Some(Unit::si(D_CD)));
        assert_eq!(parse_symbol("Pa"), Some(Unit::si(D_PA)));
        assert_eq!(parse_symbol("kg"), Some(Unit::si(D_KG)));
        let g = parse_symbol("g").unwrap_or(Unit::ONE);
        assert!(g.dim == D_KG && close(g.scale, 1e-3));
        let mg = parse_symbol("mg").unwrap_or(Unit::ONE);
        assert!(mg.dim == D_KG && close(mg.scale, 1e-6));
        let us = parse_symbol("µs").unwrap_or(Unit::ONE);
        assert!(us.dim == D_S && close(us.scale, 1e-6));
        let ma = parse_symbol("mA").unwrap_or(Unit::ONE);
        assert!(ma.dim == D_A && close(ma.scale, 1e-3));
        let kn = parse_symbol("kN").unwrap_or(Unit::ONE);
        assert!(kn.dim == D_N && close(kn.scale, 1e3));
        // Unknown and half-prefixed symbols are refused.
        assert_eq!(parse_symbol("furlong"), None);
        assert_eq!(parse_symbol("kmin"), None);
        assert_eq!(parse_symbol("x"), None);
    }

    #[test]
    fn derived_units_reduce_to_base_dimensions() {
        // 1 N m/rad = 1 kg m^2 s^-2 (rad is dimensionless).
        let u = unit(&[("N", 1), ("m", 1)], &[("rad", 1)]);
        assert_eq!(u, Ok(Unit::si(Dim::new(2, 1, -2, 0, 0, 0, 0))));
        // V = W/A and Ohm = V/A.
        assert_eq!(unit(&[("W", 1)], &[("A", 1)]), Ok(Unit::si(D_V)));
        assert_eq!(unit(&[("V", 1)], &[("A", 1)]), Ok(Unit::si(D_OHM)));
        // F = C/V, H = Wb/A, T = Wb/m^2, S = 1/Ohm.
        assert_eq!(unit(&[("C", 1)], &[("V", 1)]), Ok(Unit::si(D_F)));
        assert_eq!(unit(&[("Wb", 1)], &[("A", 1)]), Ok(Unit::si(D_H)));
        assert_eq!(unit(&[("Wb", 1)], &[("m", 2)]), Ok(Unit::si(D_T)));
        assert_eq!(unit(&[("S", 1), ("Ohm", 1)], &[]), Ok(Unit::ONE));
        assert_eq!(unit(&[("1", 1)], &[]), Ok(Unit::ONE));
    }

    #[test]
    fn scales_of_non_si_units() {
        // 1 rpm = 2 pi / 60 rad/s = 0.10471975511965977 rad/s.
        let rpm = unit(&[("rpm", 1)], &[]).unwrap_or(Unit::ONE);
        assert_eq!(rpm.dim, D_HZ);
        assert!(close(rpm.scale, 0.10471975511965977));
        // 1 deg = pi/180 rad = 0.017453292519943295.
        let deg = unit(&[("deg", 1)], &[]).unwrap_or(Unit::ONE);
        assert!(deg.dim.is_dimensionless() && close(deg.scale, 0.017453292519943295));
        // 1 L/min = 1e-3 m^3 / 60 s = 1.6666666666666667e-5 m^3/s.
        let lpm = unit(&[("L", 1)], &[("min", 1)]).unwrap_or(Unit::ONE);
        assert_eq!(lpm.dim, Dim::new(3, 0, -1, 0, 0, 0, 0));
        assert!(close(lpm.scale, 1.6666666666666667e-5));
        // (mm)^2 = 1e-6 m^2.
        let mm2 = unit(&[("mm", 2)], &[]).unwrap_or(Unit::ONE);
        assert!(mm2.dim == Dim::new(2, 0, 0, 0, 0, 0, 0) && close(mm2.scale, 1e-6));
        // 1 km/h = 1000/3600 m/s.
        let kmh = unit(&[("km", 1)], &[("h", 1)]).unwrap_or(Unit::ONE);
        assert!(close(kmh.scale, 1000.0 / 3600.0));
    }

    #[test]
    fn unit_text_of_the_command_line_parses_as_in_a_file() {
        let mh = parse_unit_text("mH").unwrap_or(Unit::ONE);
        assert!(mh.dim == D_H && close(mh.scale, 1e-3));
        assert_eq!(parse_unit_text("N m/rad"), Ok(Unit::si(D_J)));
        assert_eq!(parse_unit_text("1/s"), Ok(Unit::si(D_HZ)));
        assert_eq!(parse_unit_text("1"), Ok(Unit::ONE));
        let acc = parse_unit_text("m/s^2").map(|u| u.dim);
        assert_eq!(acc, Ok(Dim::new(1, 0, -2, 0, 0, 0, 0)));
        let rpm = parse_unit_text("rpm").unwrap_or(Unit::ONE);
        assert!(close(rpm.scale, 0.10471975511965977));
        assert!(parse_unit_text("").is_err());
        assert!(parse_unit_text("furlong").is_err());
        assert!(parse_unit_text("m^0").is_err());
        assert!(parse_unit_text("m/s/s").is_err());
        // Units as other tools write them are refused with what to write.
        for (text, said) in [
            ("N-m", "`N-m`: unit factors multiply by a space: `N m`"),
            (
                "kg*m^2",
                "`kg*m^2`: unit factors multiply by a space: `kg m^2`",
            ),
            ("N m-1", "`m-1`: a unit's power follows `^`: `m^-1`"),
            (
                "lbf",
                "unknown unit `lbf`: units are SI: write the value in SI units (1 lbf = 4.4482216152605 N)",
            ),
            ("m2", "unknown unit `m2`: a unit's power follows `^`: `m^2`"),
        ] {
            assert_eq!(parse_unit_text(text), Err(said.to_string()), "{text}");
        }
        for (text, dim) in [
            ("s^-1", D_HZ),
            ("kg m^2 s^-2", D_J),
            ("N m rad^-1 s^-1", D_W),
        ] {
            assert_eq!(parse_unit_text(text).map(|u| u.dim), Ok(dim), "{text}");
        }
        for text in ["m-", "-", "m*"] {
            assert!(parse_unit_text(text).is_err(), "{text}");
        }
    }

    #[test]
    fn unknown_symbol_is_reported_by_name() {
        assert_eq!(
            unit(&[("N", 1), ("furlong", 1)], &[]),
            Err(UnitError::UnknownSymbol {
                symbol: "furlong".into()
            })
        );
        assert_eq!(unit(&[("m", 200)], &[]).err(), Some(UnitError::Overflow));
    }

    #[test]
    fn arithmetic_and_square_root() {
        let n = Unit::si(D_N);
        let m = Unit::si(D_M);
        assert_eq!(n.checked_mul(m).map(|u| u.dim), Some(D_J));
        assert_eq!(n.checked_div(m).and_then(|u| u.checked_mul(m)), Some(n));
        assert_eq!(m.powi(3).map(|u| u.dim), Some(D_M3));
        assert_eq!(
            m.powi(-2).and_then(|u| u.sqrt()).map(|u| u.dim),
            m.powi(-1).map(|u| u.dim)
        );
        assert_eq!(m.sqrt(), None);
        let km = parse_symbol("km").unwrap_or(Unit::ONE);
        assert!(km.powi(2).is_some_and(|u| close(u.scale, 1e6)));
        assert!(
            km.powi(2)
                .and_then(|u| u.sqrt())
                .is_some_and(|u| close(u.scale, 1e3))
        );
    }

    #[test]
    fn display_is_readable_si() {
        assert_eq!(D_N.to_string(), "N");
        assert_eq!(D_J.to_string(), "N m");
        assert_eq!(Dim::new(2, 1, -1, 0, 0, 0, 0).to_string(), "N m s");
        assert_eq!(Dim::new(2, 1, 0, 0, 0, 0, 0).to_string(), "kg m^2");
        assert_eq!(Dim::new(-2, -1, 2, 0, 0, 0, 0).to_string(), "1/(N m)");
        assert_eq!(Dim::new(1, 0, -1, 0, 0, 0, 0).to_string(), "m/s");
        assert_eq!(Dim::NONE.to_string(), "1");
        assert_eq!(D_V.to_string(), "V");
        assert_eq!(D_OHM.to_string(), "Ohm");
        assert_eq!(Dim::new(1, 0, -2, 0, 0, 0, 0).to_string(), "m/s^2");
        assert_eq!(Dim::new(0, -1, 2, 0, 0, 0, 0).to_string(), "m/N");
        assert_eq!(Dim::new(-4, 1, -1, 0, 0, 0, 0).to_string(), "Pa s/m^3");
        assert_eq!(Dim::new(1, 1, -2, -1, 0, 0, 0).to_string(), "N/A (= V s/m)");
        // A motor constant: V s = Wb = N m/A.
        assert_eq!(D_WB.to_string(), "V s (= N m/A)");
        // Electrical units with no short mechanical writing stay as they are.
        assert_eq!(D_A.to_string(), "A");
        assert_eq!(Dim::new(2, 1, -3, -2, 0, 0, 0).to_string(), "Ohm");
    }

    #[test]
    fn domain_table_is_consistent_with_power_and_energy() {
        let watt = D_W;
        let second = D_S;
        for d in Domain::ALL {
            let u = domain_units(d);
            // effort x flow is a power, in every domain.
            assert_eq!(u.effort.checked_mul(u.flow), Some(watt), "{d:?}");
            // p = integral of e dt, q = integral of f dt.
            assert_eq!(u.effort.checked_mul(second), Some(u.momentum), "{d:?}");
            assert_eq!(u.flow.checked_mul(second), Some(u.displacement), "{d:?}");
        }
        // The conventional texts parse to the same dimensions.
        for d in Domain::ALL {
            let u = domain_units(d);
            for kind in [
                crate::syntax::ast::ElementKind::C,
                crate::syntax::ast::ElementKind::I,
                crate::syntax::ast::ElementKind::R,
            ] {
                let Some((dim, text)) = storage_parameter_unit(kind, d) else {
                    panic!("no unit for {kind:?}");
                };
                let parsed = parse_text(text);
                assert_eq!(parsed, Some(dim), "{kind:?} in {d:?}: {text}");
            }
            assert_eq!(parse_text(u.effort_text), Some(u.effort));
            assert_eq!(parse_text(u.flow_text), Some(u.flow));
            assert_eq!(parse_text(u.momentum_text), Some(u.momentum));
            assert_eq!(parse_text(u.displacement_text), Some(u.displacement));
        }
    }

    /// Parses the simple texts of the tables: `a b^2/(c d)` or `a/b`.
    fn parse_text(text: &str) -> Option<Dim> {
        let (num, den) = match text.split_once('/') {
            Some((n, d)) => (n, d.trim_start_matches('(').trim_end_matches(')')),
            None => (text, ""),
        };
        let factors = |s: &str| -> Vec<(String, i32)> {
            s.split_whitespace()
                .map(|f| match f.split_once('^') {
                    Some((b, p)) => (b.to_string(), p.parse().unwrap_or(0)),
                    None => (f.to_string(), 1),
                })
                .collect()
        };
        parse_unit(&UnitExpr {
            numerator: factors(num),
            denominator: factors(den),
            span: Span::default(),
        })
        .ok()
        .map(|u| u.dim)
    }
}
