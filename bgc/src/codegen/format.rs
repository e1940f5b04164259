//! Text of generated code that `rustfmt` leaves as it is, and the lint checks the generator needs.
//!
//! - Comments: `rustfmt` does not rewrap comments, so [`comment`] wraps them to the line width itself: prose at
//!   spaces (a markdown list item continues under its text, and no line starts with what markdown would read as
//!   a list or a heading), equations also after `*` and `/`, their continuation lines indented.
//! - Arrays ([`array`]): one line when the elements take at most [`ARRAY_WIDTH`] columns and the line fits;
//!   otherwise, when every element is at most [`SHORT_ELEMENT_WIDTH`] columns, as many per line as fit (the last
//!   line too ends in a comma); otherwise one per line. These are `rustfmt`'s `array_width`,
//!   `short_array_element_width_threshold` and "mixed" layout.
//! - Long string literals ([`string_literal`]) continue on the next line after `\`, which Rust skips together with
//!   the next line's indentation, so the value is unchanged.
//! - Function signatures ([`signature`]) on one line when it fits, else one parameter per line.

use super::layout::width;

/// `rustfmt`'s `array_width`.
pub(super) const ARRAY_WIDTH: usize = 60;
/// `rustfmt`'s `short_array_element_width_threshold`.
pub(super) const SHORT_ELEMENT_WIDTH: usize = 10;

/// What a comment holds, which decides where it may break.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Wrap {
    /// Sentences: break at spaces.
    Prose,
    /// An equation: break at spaces and after `*` and `/`; continuation lines indented by four spaces.
    Equation,
}

/// The words of `text` with the break opportunities of `wrap`: each piece ends where a line may end (a trailing
/// space is dropped at a line end).
fn pieces(text: &str, wrap: Wrap) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    for c in text.chars() {
        cur.push(c);
        if c == ' ' || (wrap == Wrap::Equation && matches!(c, '*' | '/')) {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Whether `word` is a markdown list marker (`-`, `*`, `+`, `1.`, `1)`).
fn is_list_marker(word: &str) -> bool {
    matches!(word, "-" | "*" | "+")
        || (word.len() > 1
            && (word.ends_with('.') || word.ends_with(')'))
            && word[..word.len() - 1].chars().all(|c| c.is_ascii_digit()))
}

/// Whether a doc line starting with `word` would start a markdown list item, heading, quote or table.
fn starts_markdown_block(word: &str) -> bool {
    let w = word.trim_end();
    is_list_marker(w) || matches!(w, ">" | "|") || w.starts_with('#')
}

/// `text` as comment lines `{indent}{marker} ...` of at most `line_width` columns (longer only for a single word
/// that does not fit).
pub(super) fn comment(
    indent: usize,
    marker: &str,
    text: &str,
    wrap: Wrap,
    line_width: usize,
) -> Vec<String> {
    let text = text.replace(['\n', '\r'], " ");
    let text = text.trim_end();
    let lead = format!("{}{marker}", " ".repeat(indent));
    if text.is_empty() {
        return vec![lead];
    }
    let hanging = match wrap {
        Wrap::Prose => {
            let first = text.split(' ').next().unwrap_or_default();
            if is_list_marker(first) {
                first.len() + 1
            } else {
                0
            }
        }
        Wrap::Equation => 4,
    };
    let first_lead = format!("{lead} ");
    if width(&first_lead) + width(text) <= line_width {
        // The common case, and what the wrapping below gives for it: one line.
        return vec![format!("{first_lead}{text}")];
    }
    let next_lead = format!("{lead} {}", " ".repeat(hanging));
    let mut lines: Vec<String> = Vec::new();
    let mut cur = String::new();
    for word in pieces(text, wrap) {
        let lead = if lines.is_empty() {
            &first_lead
        } else {
            &next_lead
        };
        let candidate = format!("{cur}{word}");
        if cur.is_empty() || width(lead) + width(candidate.trim_end()) <= line_width {
            cur = candidate;
            continue;
        }
        let mut next = word.clone();
        // In prose, a line must not start with what markdown reads as a list item or a heading: the previous
        // word comes down too.
        if wrap == Wrap::Prose && starts_markdown_block(&word) {
            let kept = cur.trim_end();
            if let Some(space) = kept.rfind(' ') {
                next = format!("{} {word}", &kept[space + 1..]);
                cur = kept[..space + 1].to_string();
            }
        }
        lines.push(format!("{lead}{}", cur.trim_end()));
        cur = next;
    }
    let lead = if lines.is_empty() {
        &first_lead
    } else {
        &next_lead
    };
    lines.push(format!("{lead}{}", cur.trim_end()));
    lines
}

/// Documentation lines (as the model file writes them) joined into paragraphs that [`comment`] can rewrap: a line
/// continues the paragraph above unless it is empty, starts a list item, a heading, a quote or a table row, or
/// either line is in a code block; code blocks (between ```` ``` ```` fences) stay as they are. Each paragraph
/// comes with whether it must be kept verbatim.
pub(super) fn paragraphs(lines: &[String]) -> Vec<(String, bool)> {
    let mut out: Vec<(String, bool)> = Vec::new();
    let mut in_code = false;
    let mut open = false;
    for line in lines {
        let trimmed = line.trim();
        let fence = trimmed.starts_with("```");
        if in_code || fence {
            out.push((line.trim_end().to_string(), true));
            if fence {
                in_code = !in_code;
            }
            open = false;
            continue;
        }
        let first = trimmed.split(' ').next().unwrap_or_default();
        if trimmed.is_empty() {
            out.push((String::new(), false));
            open = false;
        } else if open && !starts_markdown_block(first) {
            if let Some(last) = out.last_mut() {
                last.0.push(' ');
                last.0.push_str(trimmed);
            }
        } else {
            out.push((trimmed.to_string(), false));
            // A heading, quote or table row stands alone; a list item or a sentence goes on.
            open = !matches!(first, ">" | "|") && !first.starts_with('#');
        }
    }
    out
}

/// An array literal `{head}[items]{tail}` laid out as `rustfmt` lays it out, the continuation lines indented by
/// `indent + 4` spaces and the closing bracket by `indent`. `head` must include the indentation of the first line.
pub(super) fn array(
    head: &str,
    items: &[String],
    tail: &str,
    indent: usize,
    line_width: usize,
) -> String {
    let joined = items.join(", ");
    let inner = " ".repeat(indent + 4);
    if items.is_empty() || width(&joined) <= ARRAY_WIDTH {
        if width(head) + width(&joined) + 2 + width(tail) <= line_width {
            return format!("{head}[{joined}]{tail}");
        }
        // rustfmt moves a one-line right-hand side that does not fit after the `=` to the next line.
        if indent + 4 + width(&joined) + 2 + width(tail) <= line_width {
            return format!("{}\n{inner}[{joined}]{tail}", head.trim_end());
        }
    }
    let mut out = format!("{head}[\n");
    if items.iter().all(|i| width(i) <= SHORT_ELEMENT_WIDTH) {
        // Mixed: rustfmt fills a line while the items with their commas take at most the line less the
        // indentation and one column, the comma of the very last item not counted.
        let room = line_width.saturating_sub(indent + 4 + 1);
        let mut line = String::new();
        for (k, item) in items.iter().enumerate() {
            let counted = width(item) + usize::from(k + 1 < items.len());
            if !line.is_empty() && width(&line) + 1 + counted > room {
                out.push_str(&format!("{inner}{line}\n"));
                line.clear();
            }
            if !line.is_empty() {
                line.push(' ');
            }
            line.push_str(item);
            line.push(',');
        }
        out.push_str(&format!("{inner}{line}\n"));
    } else {
        for item in items {
            out.push_str(&format!("{inner}{item},\n"));
        }
    }
    out.push_str(&format!("{}]{tail}", " ".repeat(indent)));
    out
}

/// `s` as a Rust string literal starting at column `column` (after the text before it on its line) and followed by
/// `tail_width` columns; when it would pass `line_width`, it continues on following lines (after `\`, indented by
/// `indent` spaces, which Rust skips) at spaces.
pub(super) fn string_literal(
    s: &str,
    column: usize,
    tail_width: usize,
    indent: usize,
    line_width: usize,
) -> String {
    let quoted = format!("{s:?}");
    if column + width(&quoted) + tail_width <= line_width {
        return quoted;
    }
    // Break after spaces of the unquoted text; each piece is escaped on its own.
    let mut out = String::from("\"");
    let mut col = column + 1;
    let words: Vec<&str> = s.split_inclusive(' ').collect();
    let mut line_has_text = false;
    for (i, w) in words.iter().enumerate() {
        let esc = escape(w);
        let last = i + 1 == words.len();
        // Room for the word, then `\` (or the closing quote and the tail).
        let need = width(&esc) + if last { 1 + tail_width } else { 1 };
        if line_has_text && col + need > line_width && !esc.starts_with(' ') {
            out.push_str("\\\n");
            out.push_str(&" ".repeat(indent));
            col = indent;
            out.push_str(&esc);
            col += width(&esc);
        } else {
            out.push_str(&esc);
            col += width(&esc);
        }
        line_has_text = true;
    }
    out.push('"');
    out
}

/// The contents of a string literal for `s`.
fn escape(s: &str) -> String {
    let q = format!("{s:?}");
    q[1..q.len() - 1].to_string()
}

/// `{indent}{head}(params){ret} {` on one line when it fits, else with one parameter per line, as `rustfmt` lays
/// out a function signature; `{}` instead of `{` for an empty body.
pub(super) fn signature(
    indent: usize,
    head: &str,
    params: &[String],
    ret: &str,
    empty_body: bool,
    line_width: usize,
) -> String {
    let pad = " ".repeat(indent);
    let open = if empty_body { "{}" } else { "{" };
    let one = format!("{pad}{head}({}){ret} {open}", params.join(", "));
    if width(&one) <= line_width {
        return one;
    }
    let mut out = format!("{pad}{head}(\n");
    for p in params {
        out.push_str(&format!("{pad}    {p},\n"));
    }
    out.push_str(&format!("{pad}){ret} {open}"));
    out
}

/// `rustfmt`'s `struct_lit_width`: the columns of a struct literal's fields on one line.
pub(super) const STRUCT_LIT_WIDTH: usize = 18;

/// The struct literal `{name} {{ field: value, ... }}{tail}` on lines indented by `indent` spaces, as `rustfmt`
/// lays it out: on one line when the fields take at most [`STRUCT_LIT_WIDTH`] columns and the line fits, else one
/// field per line.
pub(super) fn struct_literal(
    name: &str,
    fields: &[(String, String)],
    tail: &str,
    indent: usize,
    line_width: usize,
) -> String {
    let pad = " ".repeat(indent);
    if fields.is_empty() {
        return format!("{pad}{name} {{}}{tail}");
    }
    let inline: Vec<String> = fields.iter().map(|(f, v)| format!("{f}: {v}")).collect();
    let joined = inline.join(", ");
    let one = format!("{pad}{name} {{ {joined} }}{tail}");
    if width(&joined) <= STRUCT_LIT_WIDTH && width(&one) <= line_width {
        return one;
    }
    let mut out = format!("{pad}{name} {{\n");
    for f in &inline {
        out.push_str(&format!("{pad}    {f},\n"));
    }
    out.push_str(&format!("{pad}}}{tail}"));
    out
}

/// Whether rustc's `non_snake_case` lint accepts `ident`: no upper-case letter and no `__` once leading and
/// trailing underscores are set aside.
pub(super) fn is_snake_case(ident: &str) -> bool {
    let core = ident.trim_matches('_');
    !core.chars().any(char::is_uppercase) && !core.contains("__")
}

/// The constants clippy's `approx_constant` lint knows, with the fewest characters a literal needs before the
/// lint compares it (clippy's list; four of them need fewer than five).
const KNOWN_CONSTANTS: [(f64, usize); 19] = [
    (std::f64::consts::E, 4),
    (std::f64::consts::FRAC_1_PI, 4),
    (std::f64::consts::FRAC_1_SQRT_2, 5),
    (std::f64::consts::FRAC_2_PI, 5),
    (std::f64::consts::FRAC_2_SQRT_PI, 5),
    (std::f64::consts::FRAC_PI_2, 5),
    (std::f64::consts::FRAC_PI_3, 5),
    (std::f64::consts::FRAC_PI_4, 5),
    (std::f64::consts::FRAC_PI_6, 5),
    (std::f64::consts::FRAC_PI_8, 5),
    (std::f64::consts::LN_10, 5),
    (std::f64::consts::LN_2, 5),
    (std::f64::consts::LOG10_E, 5),
    (std::f64::consts::LOG2_E, 5),
    (std::f64::consts::LOG2_10, 5),
    (std::f64::consts::LOG10_2, 5),
    (std::f64::consts::PI, 3),
    (std::f64::consts::SQRT_2, 5),
    (std::f64::consts::TAU, 3),
];

/// Whether clippy's `approx_constant` would take the float literal `literal` (as written) for `constant`: a
/// truncation or a rounding of it with more than `min_chars` characters. Three characters are assumed for every
/// constant, a little more cautious than clippy.
fn approximates(constant: f64, literal: &str, min_chars: usize) -> bool {
    if literal.len() <= min_chars.min(3) {
        return false;
    }
    if constant.to_string().starts_with(literal) {
        return true;
    }
    let decimals = literal.len().saturating_sub(2);
    format!("{constant:.decimals$}") == literal
}

/// Whether `code` has a float literal that clippy's `approx_constant` lint would take for an imprecise `π`, `e`,
/// `ln 2`, ... (a number of the model such as `3.1416`).
pub(super) fn may_look_like_a_constant(code: &str) -> bool {
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let starts_number = bytes[i].is_ascii_digit()
            && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
        if !starts_number {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len()
            && (bytes[i].is_ascii_alphanumeric() || bytes[i] == b'.' || bytes[i] == b'_')
        {
            i += 1;
        }
        let literal = &code[start..i];
        let is_float =
            literal.contains('.') && literal.chars().all(|c| c.is_ascii_digit() || c == '.');
        if is_float
            && KNOWN_CONSTANTS
                .iter()
                .any(|&(constant, min_chars)| approximates(constant, literal, min_chars))
        {
            return true;
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codegen::layout::MAX_WIDTH;
    use crate::codegen::test_support::{TestRng, assert_rustfmt_stable};

    #[test]
    fn equations_wrap_after_operators_with_indented_continuations() {
        let text = format!("d/dt x = {}", ["alpha*beta"; 12].join(" + "));
        let lines = comment(4, "//", &text, Wrap::Equation, 60);
        assert!(lines.len() > 1);
        assert!(lines.iter().all(|l| width(l) <= 60), "{lines:#?}");
        assert!(lines[0].starts_with("    // d/dt x = "));
        assert!(
            lines[1..].iter().all(|l| l.starts_with("    //     ")),
            "{lines:#?}"
        );
        // Nothing lost or added but the line breaks.
        let joined: String = lines
            .iter()
            .map(|l| l.trim_start().trim_start_matches("//").trim())
            .collect::<Vec<_>>()
            .join(" ");
        assert_eq!(joined.replace(' ', ""), text.replace(' ', ""));
    }

    #[test]
    fn prose_never_starts_a_line_with_a_list_marker() {
        let text = "the spring between the mass and the wall - the only compliance of the model - is linear";
        for w in 20..60 {
            for l in comment(0, "///", text, Wrap::Prose, w).iter().skip(1) {
                let first = l
                    .trim_start_matches("///")
                    .split_whitespace()
                    .next()
                    .unwrap_or("");
                assert!(!starts_markdown_block(first), "width {w}: {l}");
            }
        }
        let item = comment(
            0,
            "///",
            "- the first item of a list that is long enough to wrap",
            Wrap::Prose,
            30,
        );
        assert_eq!(item[0], "/// - the first item of a list");
        assert!(item[1].starts_with("///   "), "{item:#?}");
    }

    #[test]
    fn documentation_lines_join_into_paragraphs() {
        let lines: Vec<String> = [
            "A pendulum: the mass is tied",
            "to the pivot.",
            "",
            "- first item",
            "  continued",
            "- second item",
            "```text",
            "x = l sin(theta)",
            "```",
            "# Heading",
            "after the heading",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let p = paragraphs(&lines);
        let texts: Vec<&str> = p.iter().map(|(t, _)| t.as_str()).collect();
        assert_eq!(
            texts,
            [
                "A pendulum: the mass is tied to the pivot.",
                "",
                "- first item continued",
                "- second item",
                "```text",
                "x = l sin(theta)",
                "```",
                "# Heading",
                "after the heading",
            ]
        );
        assert_eq!(
            p.iter().map(|(_, v)| *v).collect::<Vec<_>>(),
            [false, false, false, false, true, true, true, false, false]
        );
    }

    #[test]
    fn arrays_take_rustfmts_three_layouts() {
        let short: Vec<String> = ["\"a\"", "\"b\""].iter().map(|s| s.to_string()).collect();
        assert_eq!(
            array("const A: [&str; 2] = ", &short, ";", 0, 100),
            "const A: [&str; 2] = [\"a\", \"b\"];"
        );
        let many: Vec<String> = (0..30).map(|i| format!("\"n{i}\"")).collect();
        let mixed = array("const A: [&str; 30] = ", &many, ";", 0, 100);
        let lines: Vec<&str> = mixed.lines().collect();
        assert!(lines.len() > 3, "{mixed}");
        assert!(lines[1].starts_with("    \"n0\", \"n1\", "));
        assert!(
            lines[1..3]
                .iter()
                .all(|l| l.ends_with(',') && width(l) <= 100)
        );
        let long: Vec<String> = (0..6).map(|i| format!("\"name_number_{i}\"")).collect();
        let vertical = array("const A: [&str; 6] = ", &long, ";", 0, 100);
        assert_eq!(vertical.lines().count(), 8, "{vertical}");
    }

    /// Random arrays of string literals and of fields at the top level and inside a module, laid out here and by
    /// rustfmt.
    #[test]
    fn arrays_match_rustfmt() {
        let mut rng = TestRng(7);
        let mut top = String::new();
        let mut nested = String::from("mod m {\n");
        for case in 0..120 {
            let n = rng.below(30);
            let short = rng.below(2) == 0;
            let items: Vec<String> = (0..n)
                .map(|_| {
                    let len = 1 + rng.below(if short { 8 } else { 14 });
                    if rng.below(4) == 0 {
                        format!("self.{}", "f".repeat(len))
                    } else {
                        format!("\"{}\"", "n".repeat(len))
                    }
                })
                .collect();
            let name = format!("A{case}_{}", "X".repeat(rng.below(40)));
            let head = format!("pub const {name}: [&str; {n}] = ");
            top.push_str(&array(&head, &items, ";", 0, MAX_WIDTH));
            top.push('\n');
            nested.push_str(&array(&format!("    {head}"), &items, ";", 4, MAX_WIDTH));
            nested.push('\n');
        }
        nested.push_str("}\n");
        assert_rustfmt_stable(&top);
        assert_rustfmt_stable(&nested);
    }

    /// Random literals as the tail of `default()`, as the generator prints them.
    #[test]
    fn struct_literals_match_rustfmt() {
        let mut rng = TestRng(5);
        let mut text = String::from("impl Params {\n");
        for k in 0..80 {
            let fields: Vec<(String, String)> = (0..rng.below(4))
                .map(|i| {
                    let name = format!("{}{i}", "k".repeat(1 + rng.below(6)));
                    (name, ["2.5", "1e-7", "0.25"][rng.below(3)].to_string())
                })
                .collect();
            text.push_str(&format!("    fn d{k}() -> Self {{\n"));
            text.push_str(&struct_literal("Params", &fields, "", 8, MAX_WIDTH));
            text.push_str("\n    }\n");
        }
        text.push_str("}\n");
        assert_rustfmt_stable(&text);
        assert!(
            text.contains("Params { k0: 2.5 }") || text.contains("Params { kk0: 2.5 }"),
            "{text}"
        );
    }

    #[test]
    fn long_string_literals_continue_after_a_backslash() {
        let s =
            "the resistance of `friction` (b_friction*2) must be non-negative and finite, always";
        let lit = string_literal(s, 24, 1, 16, 60);
        let mut widths = lit.lines().map(width);
        assert!(widths.next().is_some_and(|w| 24 + w <= 60), "{lit}");
        assert!(widths.all(|w| w <= 60), "{lit}");
        assert!(lit.lines().count() > 1, "{lit}");
        // What Rust reads: a `\` at a line end skips the line break and the next line's leading whitespace.
        let mut value = String::new();
        for l in lit.lines() {
            let l = if value.is_empty() { l } else { l.trim_start() };
            value.push_str(l.strip_suffix('\\').unwrap_or(l));
        }
        assert_eq!(value, format!("{s:?}"));
        assert_eq!(string_literal("short", 0, 0, 0, 100), "\"short\"");
    }

    #[test]
    fn signatures_go_vertical_when_they_do_not_fit() {
        let params: Vec<String> = vec!["p: &Params".into(), "t: f64".into()];
        assert_eq!(
            signature(0, "pub fn f", &params, "", true, 100),
            "pub fn f(p: &Params, t: f64) {}"
        );
        assert_eq!(
            signature(4, "pub fn f", &params, " -> f64", false, 30),
            "    pub fn f(\n        p: &Params,\n        t: f64,\n    ) -> f64 {"
        );
    }

    #[test]
    fn lint_predicates() {
        assert!(is_snake_case("theta_m") && is_snake_case("_2x") && is_snake_case("x_"));
        assert!(!is_snake_case("J_m") && !is_snake_case("a__b"));
        // The literals clippy's `approx_constant` flags: truncated or rounded π, 1/π, √2, ln 2.
        for flagged in ["x * 3.14", "0.318", "1.4142", "-0.6931 * y", "6.283"] {
            assert!(may_look_like_a_constant(flagged), "{flagged}");
        }
        // Ordinary numbers of a model.
        assert!(!may_look_like_a_constant(
            "x[10] * 0.5 + 2.0 - 1e-7 * p_12.25 + 9.81 * 0.01 + 3.1 + 1.5e-3"
        ));
    }
}
