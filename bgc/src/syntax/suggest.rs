//! "Did you mean" suggestions for misspelt keywords.

use super::parser::KEYWORDS;

/// The keyword `word` is most likely a misspelling of: one edit away (two for words of six letters or more), case
/// ignored. Element kinds are left out: short words like `C` are one edit away from too many names.
pub fn keyword_like(word: &str) -> Option<&'static str> {
    if word.len() > 32 {
        return None;
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

/// Levenshtein distance over bytes, one row at a time.
fn edit_distance(a: &str, b: &str) -> usize {
    let b = b.as_bytes();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.bytes().enumerate() {
        let mut cur = Vec::with_capacity(b.len() + 1);
        cur.push(i + 1);
        for (j, cb) in b.iter().enumerate() {
            let diagonal = prev.get(j).copied().unwrap_or(usize::MAX - 1) + usize::from(ca != *cb);
            let up = prev.get(j + 1).copied().unwrap_or(usize::MAX - 1) + 1;
            let left = cur.last().copied().unwrap_or(usize::MAX - 1) + 1;
            cur.push(diagonal.min(up).min(left));
        }
        prev = cur;
    }
    prev.last().copied().unwrap_or(0)
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
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }
}
