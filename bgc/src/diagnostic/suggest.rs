//! "Did you mean": the nearest of some names to a name that was not found, for the helps of every stage.

/// Levenshtein distance (in characters).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = Vec::with_capacity(b.len() + 1);
        cur.push(i + 1);
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            let del = prev[j + 1] + 1;
            let ins = cur[j] + 1;
            cur.push(sub.min(del).min(ins));
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The candidate nearest to `name`, if it is near enough to be a likely typo: at most one edit for short names,
/// a third of the length for longer ones, and never one that rewrites every character (`q` is not a typo of `m`)
/// unless it differs in case only. Among equally near candidates, one that differs from `name` in case only comes
/// first (`Kg` is `kg`, not `g`), then the first in the order given (callers give declaration order).
pub fn closest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Option<String> {
    let length = name.chars().count();
    let limit = (length / 3).max(1);
    candidates
        .filter(|c| *c != name)
        .map(|c| (edit_distance(name, c), !c.eq_ignore_ascii_case(name), c))
        .filter(|(d, case_differs, _)| *d <= limit && (*d < length || !*case_differs))
        .min_by_key(|(d, case_differs, _)| (*d, *case_differs))
        .map(|(_, _, c)| c.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edit_distance_counts_single_edits() {
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("J_m", "J_n"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("rotor", "rotor"), 0);
    }

    #[test]
    fn closest_picks_a_near_name_only() {
        let names = ["spring", "damper", "rotor"];
        assert_eq!(closest("sprin", names.into_iter()), Some("spring".into()));
        assert_eq!(closest("rotr", names.into_iter()), Some("rotor".into()));
        assert_eq!(closest("xyz", names.into_iter()), None);
        // A case slip beats another single edit, whatever the order; otherwise the first given.
        assert_eq!(closest("Kg", ["g", "kg"].into_iter()), Some("kg".into()));
        assert_eq!(closest("Kg", ["kg", "g"].into_iter()), Some("kg".into()));
        assert_eq!(closest("ab", ["ac", "aa"].into_iter()), Some("ac".into()));
        // A one-letter name is no typo of another letter, but is of the same letter in the other case.
        assert_eq!(closest("q", ["m", "k", "d"].into_iter()), None);
        assert_eq!(closest("G", ["F", "g"].into_iter()), Some("g".into()));
    }
}
