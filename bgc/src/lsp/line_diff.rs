//! The line diff of a file and its canonical layout, for `bgc fmt --check` (a unified diff) and for range
//! formatting in the editor (the changed lines).
//!
//! Formatting changes lines in place and keeps their order, and most lines of a model are unique (they name
//! their elements), so the lines that occur once in each text and in the same order anchor the diff (patience
//! diffing): they are found by a longest increasing subsequence in `O(n log n)`, and Myers' algorithm runs only
//! on the gaps between them, which are a line or two. Myers' algorithm on the whole text costs the product of its
//! length and the number of changes: 83 s for a file of a million lines with 100,000 changed ones (similar's
//! own patience diff is no faster there). A deadline bounds gaps with many repeated lines: past it a gap is
//! reported as replaced whole, still a correct diff.

use similar::{Algorithm, DiffOp};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// How long the gaps may take together before the rest are reported replaced whole.
const DEADLINE: Duration = Duration::from_secs(2);

/// The lines of `text`, each with its line break.
pub fn lines(text: &str) -> Vec<&str> {
    text.split_inclusive('\n').collect()
}

/// The diff from the lines `old` to the lines `new`, as consecutive operations over both.
pub fn ops(old: &[&str], new: &[&str]) -> Vec<DiffOp> {
    let deadline = Instant::now() + DEADLINE;
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    for (a, b) in anchors(old, new) {
        gap(old, i..a, new, j..b, deadline, &mut out);
        out.push(DiffOp::Equal {
            old_index: a,
            new_index: b,
            len: 1,
        });
        (i, j) = (a + 1, b + 1);
    }
    gap(old, i..old.len(), new, j..new.len(), deadline, &mut out);
    merge_equal(out)
}

/// Myers' diff of one gap between anchors.
fn gap(
    old: &[&str],
    a: std::ops::Range<usize>,
    new: &[&str],
    b: std::ops::Range<usize>,
    deadline: Instant,
    out: &mut Vec<DiffOp>,
) {
    if a.is_empty() && b.is_empty() {
        return;
    }
    out.extend(similar::capture_diff_deadline(
        Algorithm::Myers,
        old,
        a,
        new,
        b,
        Some(deadline),
    ));
}

/// The pairs `(i, j)` of lines that occur once in `old` (at `i`) and once in `new` (at `j`), the longest chain of
/// them increasing in both.
fn anchors(old: &[&str], new: &[&str]) -> Vec<(usize, usize)> {
    // Per line: occurrences in old and new, and the last index in each.
    let mut seen: HashMap<&str, (u32, u32, usize, usize)> = HashMap::with_capacity(old.len());
    for (i, line) in old.iter().enumerate() {
        let e = seen.entry(line).or_insert((0, 0, 0, 0));
        e.0 += 1;
        e.2 = i;
    }
    for (j, line) in new.iter().enumerate() {
        if let Some(e) = seen.get_mut(line) {
            e.1 += 1;
            e.3 = j;
        }
    }
    let mut pairs: Vec<(usize, usize)> = seen
        .into_values()
        .filter(|e| e.0 == 1 && e.1 == 1)
        .map(|e| (e.2, e.3))
        .collect();
    pairs.sort_unstable();
    longest_increasing(&pairs)
}

/// The longest subsequence of `pairs` (sorted by their first) whose seconds increase: patience sorting, with a
/// link from each pair to the one before it in the best chain ending there.
fn longest_increasing(pairs: &[(usize, usize)]) -> Vec<(usize, usize)> {
    // tails[k]: the pair ending the best chain of length k + 1 found so far (smallest second).
    let mut tails: Vec<usize> = Vec::new();
    let mut before: Vec<Option<usize>> = vec![None; pairs.len()];
    for (p, &(_, second)) in pairs.iter().enumerate() {
        let k = tails.partition_point(|&t| pairs[t].1 < second);
        before[p] = k.checked_sub(1).map(|k| tails[k]);
        match tails.get_mut(k) {
            Some(t) => *t = p,
            None => tails.push(p),
        }
    }
    let mut chain = Vec::with_capacity(tails.len());
    let mut at = tails.last().copied();
    while let Some(p) = at {
        chain.push(pairs[p]);
        at = before[p];
    }
    chain.reverse();
    chain
}

/// `ops` with adjacent equal runs joined, as the grouping into hunks expects.
fn merge_equal(ops: Vec<DiffOp>) -> Vec<DiffOp> {
    let mut out: Vec<DiffOp> = Vec::with_capacity(ops.len());
    for op in ops {
        if let (
            Some(DiffOp::Equal {
                old_index,
                new_index,
                len,
            }),
            DiffOp::Equal {
                old_index: o,
                new_index: n,
                len: more,
            },
        ) = (out.last_mut(), op)
            && *old_index + *len == o
            && *new_index + *len == n
        {
            *len += more;
            continue;
        }
        out.push(op);
    }
    out
}

/// The unified diff (three lines of context) from `old` to `new`, headed `--- old_name` / `+++ new_name`, as
/// `diff -u` writes it; empty when the texts are equal.
pub fn unified(old: &str, new: &str, old_name: &str, new_name: &str) -> String {
    let (a, b) = (lines(old), lines(new));
    let hunks = similar::group_diff_ops(ops(&a, &b), 3);
    if hunks.is_empty() {
        return String::new();
    }
    let mut out = format!("--- {old_name}\n+++ {new_name}\n");
    for hunk in hunks {
        out.push_str(&format!(
            "{}\n",
            similar::udiff::UnifiedHunkHeader::new(&hunk)
        ));
        for op in hunk {
            let (tag, o, n) = op.as_tag_tuple();
            let (sign, shown) = match tag {
                similar::DiffTag::Equal => (' ', &a[o]),
                similar::DiffTag::Delete => ('-', &a[o]),
                similar::DiffTag::Insert => ('+', &b[n]),
                similar::DiffTag::Replace => {
                    push_lines(&mut out, '-', &a[o]);
                    ('+', &b[n])
                }
            };
            push_lines(&mut out, sign, shown);
        }
    }
    out
}

fn push_lines(out: &mut String, sign: char, lines: &[&str]) {
    for line in lines {
        out.push(sign);
        out.push_str(line);
        if !line.ends_with('\n') {
            out.push_str("\n\\ No newline at end of file\n");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Applies `ops` to `old` and returns the text: it must be `new`.
    fn apply(old: &[&str], new: &[&str], ops: &[DiffOp]) -> Vec<String> {
        let mut out = Vec::new();
        let mut expected_old = 0;
        for op in ops {
            let (tag, o, n) = op.as_tag_tuple();
            assert_eq!(o.start, expected_old, "{ops:?}");
            expected_old = o.end;
            match tag {
                similar::DiffTag::Equal => {
                    assert_eq!(&old[o.clone()], &new[n.clone()]);
                    out.extend(old[o].iter().map(|s| s.to_string()));
                }
                _ => out.extend(new[n].iter().map(|s| s.to_string())),
            }
        }
        assert_eq!(expected_old, old.len());
        out
    }

    #[test]
    fn the_ops_turn_the_old_lines_into_the_new_with_few_changes() {
        let old = lines("a\nb\nx\nc\nd\nx\ne\n");
        let new = lines("a\nB\nx\nc\nx\nd\ne\nf\n");
        let ops = ops(&old, &new);
        assert_eq!(apply(&old, &new, &ops), new);
        let changed: usize = ops
            .iter()
            .filter(|o| o.tag() != similar::DiffTag::Equal)
            .map(|o| o.old_range().len() + o.new_range().len())
            .sum();
        // b → B (2), a moved x (2), f added (1): the shortest edit.
        assert_eq!(changed, 5, "{ops:?}");
    }

    #[test]
    fn the_unified_diff_is_the_one_diff_writes() {
        // `diff -u` of these two texts (GNU diffutils 3.8), with its headers replaced.
        let old = "model m {\n  C c = 1/k;\n  R r = b;\n}\n";
        let new = "model m {\n    C c = 1 / k;\n    R r = b;\n}";
        assert_eq!(
            unified(old, new, "m.bg", "m.bg (canonical layout)"),
            "--- m.bg\n+++ m.bg (canonical layout)\n@@ -1,4 +1,4 @@\n model m {\n-  C c = 1/k;\n-  R r = b;\n-}\n\
             +    C c = 1 / k;\n+    R r = b;\n+}\n\\ No newline at end of file\n"
        );
        assert_eq!(unified(old, old, "a", "b"), "");
    }

    #[test]
    fn a_long_file_with_every_tenth_line_changed_diffs_line_by_line() {
        let old: String = (0..200_000).map(|k| format!("line {k}\n")).collect();
        let new: String = (0..200_000)
            .map(|k| match k % 10 {
                0 => format!("line  {k}\n"),
                _ => format!("line {k}\n"),
            })
            .collect();
        let (a, b) = (lines(&old), lines(&new));
        let ops = ops(&a, &b);
        assert_eq!(apply(&a, &b, &ops), b);
        let replaced = ops
            .iter()
            .filter(|o| o.tag() == similar::DiffTag::Replace)
            .count();
        assert_eq!(replaced, 20_000);
    }
}
