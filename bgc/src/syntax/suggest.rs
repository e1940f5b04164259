//! "Did you mean" suggestions for misspelt keywords.

use super::parser::KEYWORDS;
use crate::diagnostic::suggest::edit_distance;

/// Keywords of other modelling languages (Modelica, 20-sim's SIDOPS, MATLAB, Python) with bgc's keyword for the
/// same statement.
const OTHER_LANGUAGES: [(&str, &str); 12] = [
    ("parameter", "param"),
    ("parameters", "param"),
    ("const", "param"),
    ("constant", "param"),
    ("constants", "param"),
    ("let", "param"),
    ("inputs", "input"),
    ("outputs", "output"),
    ("variable", "var"),
    ("variables", "var"),
    ("connect", "bond"),
    ("submodel", "component"),
];

/// The keyword `word` is most likely a misspelling of: one edit away (two for words of six letters or more), case
/// ignored. Element kinds are left out: short words like `C` are one edit away from too many names.
pub fn keyword_like(word: &str) -> Option<&'static str> {
    if word.len() > 32 {
        return None;
    }
    if let Some((_, kw)) = OTHER_LANGUAGES.iter().find(|(w, _)| *w == word) {
        return Some(kw);
    }
    let lower = word.to_ascii_lowercase();
    KEYWORDS
        .iter()
        .copied()
        .filter(|k| k.len() > 3)
        .map(|k| (k, edit_distance(&lower, k)))
        .filter(|(k, d)| *k != word && *d <= if k.len() >= 6 { 2 } else { 1 })
        .min_by_key(|(_, d)| *d)
        .map(|(k, _)| k)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn misspelt_keywords_are_recognised() {
        assert_eq!(keyword_like("parm"), Some("param"));
        assert_eq!(keyword_like("ouput"), Some("output"));
        assert_eq!(keyword_like("Bond"), Some("bond"));
        assert_eq!(keyword_like("spring_damper"), None);
        assert_eq!(keyword_like("parameter"), Some("param"));
        assert_eq!(keyword_like("const"), Some("param"));
        assert_eq!(keyword_like("connect"), Some("bond"));
    }
}
