//! The help of an unknown unit symbol (BG0312): what the writer most likely meant, from the ways units are written
//! elsewhere (a power without `^`, spellings such as `sec`, imperial units, two symbols written together).

use super::parse_symbol;
use crate::diagnostic::suggest::closest;

/// The units a misspelt symbol is compared with.
const KNOWN: [&str; 28] = [
    "m", "g", "kg", "s", "A", "K", "mol", "cd", "rad", "sr", "Hz", "N", "Pa", "J", "W", "C", "V",
    "F", "Ohm", "S", "Wb", "T", "H", "min", "h", "deg", "rpm", "L",
];

/// Spellings of other tools and texts, with the symbol to write: compounds of datasheets first, which splitting
/// into two symbols would get wrong (`Nms` is not `N ms`).
const SPELLINGS: [(&str, &str); 20] = [
    ("Nms", "N m s"),
    ("mNm", "mN m"),
    ("mNms", "mN m s"),
    ("kgm", "kg m"),
    ("gcm", "g cm"),
    ("Ah", "A h"),
    ("mAh", "mA h"),
    ("RPM", "rpm"),
    ("sec", "s"),
    ("secs", "s"),
    ("msec", "ms"),
    ("usec", "us"),
    ("hr", "h"),
    ("hrs", "h"),
    ("mins", "min"),
    ("degree", "deg"),
    ("degrees", "deg"),
    ("ohm", "Ohm"),
    ("ohms", "Ohm"),
    ("Nm", "N m"),
];

/// Units outside SI (imperial and US customary ones, and others of datasheets), with their value in SI.
const NOT_SI: [(&str, &str); 20] = [
    ("in", "0.0254 m"),
    ("inch", "0.0254 m"),
    ("ft", "0.3048 m"),
    ("foot", "0.3048 m"),
    ("feet", "0.3048 m"),
    ("yd", "0.9144 m"),
    ("mi", "1609.344 m"),
    ("lb", "0.45359237 kg"),
    ("lbm", "0.45359237 kg"),
    ("lbs", "0.45359237 kg"),
    ("oz", "0.028349523125 kg"),
    ("lbf", "4.4482216152605 N"),
    ("ozf", "0.27801385095378125 N"),
    ("psi", "6894.757293168361 Pa"),
    ("mph", "0.44704 m/s"),
    ("slug", "14.593902937206364 kg"),
    ("gf", "0.00980665 N"),
    ("kgf", "9.80665 N"),
    ("bar", "100000 Pa"),
    ("atm", "101325 Pa"),
];

/// Symbols that read as two units but are one that is not SI, with what to write.
const MISREAD: [(&str, &str); 5] = [
    (
        "rev",
        "a revolution is 2 pi rad: write angles in `rad` or `deg`, and revolutions per minute as `rpm`",
    ),
    ("kph", "write `km/h`"),
    (
        "degC",
        "temperatures are in `K`: a difference of 1 degC is 1 K, and 0 degC is 273.15 K",
    ),
    (
        "degF",
        "temperatures are in `K`: a difference of 1 degF is 5/9 K",
    ),
    (
        "Nm2",
        "a pressure is `Pa` (N/m^2); for a product write `N m^2`",
    ),
];

/// The help for the unknown unit `symbol`.
pub fn unknown_symbol_help(symbol: &str) -> String {
    if let Some((_, write)) = SPELLINGS.iter().find(|(s, _)| *s == symbol) {
        return format!("write `{write}`");
    }
    if let Some((_, si)) = NOT_SI.iter().find(|(s, _)| *s == symbol) {
        return format!("units are SI: write the value in SI units (1 {symbol} = {si})");
    }
    if let Some((_, help)) = MISREAD.iter().find(|(s, _)| *s == symbol) {
        return help.to_string();
    }
    if let Some(known) = KNOWN.iter().find(|k| k.eq_ignore_ascii_case(symbol)) {
        return format!("did you mean `{known}`?");
    }
    if let Some((stem, power)) = power_without_caret(symbol) {
        return format!("a unit's power follows `^`: `{stem}^{power}`");
    }
    // A case slip of a known unit was answered above, so two units written together (`[Ns/m]`, `[kgm^2]`) come
    // before the nearest unit.
    match (joined_factors(symbol), closest(symbol, KNOWN.into_iter())) {
        (Some((a, b)), _) => format!("unit factors are separated by a space: `{a} {b}`, as in `[N m]`"),
        (None, Some(c)) => format!("did you mean `{c}`?"),
        (None, None) => {
            "units are SI symbols with optional prefixes p n u µ m c d k M G (docs/language.md, Units)".to_string()
        }
    }
}

/// `m2` → (`m`, `2`): a unit followed by a whole power written without `^`.
fn power_without_caret(symbol: &str) -> Option<(&str, &str)> {
    let stem = symbol.trim_end_matches(|c: char| c.is_ascii_digit());
    let power = &symbol[stem.len()..];
    let whole = !power.is_empty() && !power.starts_with('0');
    (whole && parse_symbol(stem).is_some()).then_some((stem, power))
}

/// `Ns` → (`N`, `s`): two unit symbols of different quantities written without the space between them.
fn joined_factors(symbol: &str) -> Option<(&str, &str)> {
    (1..symbol.len())
        .filter(|&i| symbol.is_char_boundary(i))
        .map(|i| symbol.split_at(i))
        // Two factors of one quantity (`kg g`, `N N`) are a typo of one unit (`kgg`, `NN`), not a product.
        .find(|(a, b)| {
            parse_symbol(a)
                .zip(parse_symbol(b))
                .is_some_and(|(x, y)| x.dim != y.dim)
        })
}

#[cfg(test)]
mod tests {
    use super::unknown_symbol_help;

    #[test]
    fn each_way_of_writing_a_unit_elsewhere_gets_what_to_write() {
        for (symbol, help) in [
            ("m2", "a unit's power follows `^`: `m^2`"),
            ("mm3", "a unit's power follows `^`: `mm^3`"),
            ("sec", "write `s`"),
            ("hr", "write `h`"),
            (
                "in",
                "units are SI: write the value in SI units (1 in = 0.0254 m)",
            ),
            (
                "lbf",
                "units are SI: write the value in SI units (1 lbf = 4.4482216152605 N)",
            ),
            ("Kg", "did you mean `kg`?"),
            ("RPM", "write `rpm`"),
            ("HZ", "did you mean `Hz`?"),
            ("Nms", "write `N m s`"),
            ("mAh", "write `mA h`"),
            (
                "degC",
                "temperatures are in `K`: a difference of 1 degC is 1 K, and 0 degC is 273.15 K",
            ),
            (
                "bar",
                "units are SI: write the value in SI units (1 bar = 100000 Pa)",
            ),
            (
                "Ns",
                "unit factors are separated by a space: `N s`, as in `[N m]`",
            ),
            ("kgg", "did you mean `kg`?"),
        ] {
            assert_eq!(unknown_symbol_help(symbol), help, "{symbol}");
        }
    }
}
