//! Copies among the bond variables: a junction's common effort or flow on its other bonds is defined as a bare
//! other variable (`v = w`). The readable equations print each copy as the variable at the end of its chain.

use super::build::Def;
use super::symbols::{Sym, SymExt};

/// The variable another one copies (`v = w`), when `v`'s definition is a bare other variable.
fn copied(defs: &[Option<Def>], v: usize) -> Option<usize> {
    match defs.get(v).and_then(Option::as_ref) {
        Some(Def::Plain(e)) => match e.as_sym() {
            Some(Sym::Var(w)) if w != v => Some(w),
            _ => None,
        },
        _ => None,
    }
}

/// Per bond variable: the end of its chain of copies. Each chain is walked once, and every variable on it takes its
/// end (the flows along 1-junctions bonded in series copy one another: following each chain from every variable on
/// it cost the square of its length). A variable on a cycle of copies (none is derived) takes where `n` steps from it
/// end, and a chain that runs into the cycle takes the representative of the variable where it enters.
pub(crate) fn representatives(defs: &[Option<Def>]) -> Vec<usize> {
    let n = defs.len();
    let mut rep: Vec<Option<usize>> = vec![None; n];
    let mut on_path = vec![false; n];
    for v in 0..n {
        let mut path = Vec::new();
        let mut cur = v;
        let end = loop {
            match rep.get(cur) {
                None => break Some(cur),
                Some(Some(r)) => break Some(*r),
                Some(None) if on_path[cur] => break None,
                Some(None) => {}
            }
            on_path[cur] = true;
            path.push(cur);
            match copied(defs, cur) {
                Some(w) => cur = w,
                None => break Some(cur),
            }
        };
        for &u in &path {
            on_path[u] = false;
            rep[u] = Some(end.unwrap_or_else(|| walk_copies(defs, u)));
        }
    }
    rep.into_iter()
        .enumerate()
        .map(|(v, r)| r.unwrap_or(v))
        .collect()
}

/// Where `n` steps along the copies from `v` end (the end of a cycle of copies).
fn walk_copies(defs: &[Option<Def>], v: usize) -> usize {
    let mut cur = v;
    for _ in 0..defs.len() {
        match copied(defs, cur) {
            Some(w) => cur = w,
            None => break,
        }
    }
    cur
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::equations::symbols;
    use crate::symbolic::Expr;

    fn copy(w: usize) -> Option<Def> {
        Some(Def::Plain(symbols::leaf(Sym::Var(w))))
    }

    #[test]
    fn every_variable_of_a_chain_of_copies_takes_its_end() {
        // 0 <- 1 <- 2 <- ... <- 999 (each copies the one before), 0 defined by a value; 1000 undefined.
        let mut defs: Vec<Option<Def>> = vec![Some(Def::Plain(Expr::one()))];
        defs.extend((1..1000).map(|v| copy(v - 1)));
        defs.push(None);
        let rep = representatives(&defs);
        assert!(rep[..1000].iter().all(|&r| r == 0), "{:?}", &rep[..10]);
        assert_eq!(rep[1000], 1000);
    }

    #[test]
    fn a_copy_of_a_variable_out_of_range_ends_there_and_a_cycle_ends_where_n_steps_do() {
        // 0 = var 7 (no such variable); 1 = 2, 2 = 1 (a cycle); 3 = 1 (into the cycle).
        let defs = vec![copy(7), copy(2), copy(1), copy(1)];
        let rep = representatives(&defs);
        assert_eq!(rep[0], 7);
        // Four steps from 1 end at 1, from 2 at 2; 3 enters the cycle, as 1 does.
        assert_eq!(&rep[1..], &[1, 2, 1]);
    }
}
