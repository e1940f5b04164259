//! Characters that text shown to a user, or written into a generated file, must not hold as they are.
//!
//! - Control characters (other than tab) move a terminal's cursor, change its colours, ring its bell or clear it: a
//!   source line echoed in a diagnostic would do the same.
//! - The bidirectional controls reorder what an editor or terminal shows, so that text reads other than it is
//!   parsed (the "Trojan Source" attack on compilers).
//! - The noncharacters U+FFFE and U+FFFF are not characters of XML 1.0: a description holding one makes a
//!   `modelDescription.xml` that no FMI importer reads.
//!
//! The lexer refuses them in strings; the diagnostic renderer shows them by a visible stand-in.

/// Whether `c` must not be shown or written as it is (see the module docs). Line breaks count: a caller that
/// keeps them tests for them first.
pub fn is_unprintable(c: char) -> bool {
    (c.is_control() && c != '\t') || is_bidi_control(c) || matches!(c, '\u{FFFE}' | '\u{FFFF}')
}

/// The embeddings, overrides and isolates, which reorder the text up to their end (rustc refuses the same ones
/// in its literals and comments). The marks U+200E and U+200F, which only set the direction of a neighbour and
/// which right-to-left text needs, are text.
fn is_bidi_control(c: char) -> bool {
    matches!(c, '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
}

/// What a diagnostic shows in place of an unprintable `c`: the control picture of a C0 control or DEL (`␛` for
/// escape, as rustc shows it), U+FFFD for the others. One character for one, so columns stay the same.
pub fn stand_in(c: char) -> char {
    match c {
        '\0'..='\u{1F}' => char::from_u32(0x2400 + c as u32).unwrap_or('\u{FFFD}'),
        '\u{7F}' => '\u{2421}',
        _ => '\u{FFFD}',
    }
}

/// `text` with every unprintable character but the line break `\n` replaced by its [`stand_in`].
pub fn shown(text: &str) -> String {
    text.chars()
        .map(|c| {
            if c != '\n' && is_unprintable(c) {
                stand_in(c)
            } else {
                c
            }
        })
        .collect()
}

/// `text` with every unprintable character but the line breaks replaced by one of the same UTF-8 length (`?`,
/// `¿` or U+FFFD), so that every byte offset into `text` stays valid: for the lines an excerpt shows around its
/// labels, which it does not show through a window.
pub fn same_length(text: &str) -> std::borrow::Cow<'_, str> {
    if !text
        .chars()
        .any(|c| c != '\n' && c != '\r' && is_unprintable(c))
    {
        return std::borrow::Cow::Borrowed(text);
    }
    let replaced = text
        .chars()
        .map(|c| match c {
            '\n' | '\r' => c,
            c if is_unprintable(c) => match c.len_utf8() {
                1 => '?',
                2 => '¿',
                _ => '\u{FFFD}',
            },
            c => c,
        })
        .collect();
    std::borrow::Cow::Owned(replaced)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn controls_and_direction_overrides_are_unprintable_and_text_is_not() {
        for c in [
            '\u{1b}', '\u{7}', '\0', '\r', '\u{7f}', '\u{85}', '\u{202e}', '\u{2067}', '\u{fffe}',
        ] {
            assert!(is_unprintable(c), "{c:?}");
        }
        for c in [
            '\t', 'a', ' ', 'µ', 'Ω', '→', '\u{fffd}', '日', '\u{200f}', 'ש',
        ] {
            assert!(!is_unprintable(c), "{c:?}");
        }
    }

    #[test]
    fn a_stand_in_is_one_visible_character_for_one() {
        assert_eq!(
            shown("a\u{1b}[31mb\u{7f}\u{202e}c\td"),
            "a␛[31mb␡\u{fffd}c\td"
        );
        assert_eq!(stand_in('\0'), '␀');
        assert_eq!(stand_in('\u{1f}'), '␟');
        let text = "a\u{c}b\u{85}c\u{202e}d\u{fffe}\r\n";
        let kept = same_length(text);
        assert_eq!(kept, "a?b¿c\u{fffd}d\u{fffd}\r\n");
        assert_eq!(kept.len(), text.len());
        assert!(matches!(
            same_length("plain\r\n"),
            std::borrow::Cow::Borrowed(_)
        ));
    }
}
