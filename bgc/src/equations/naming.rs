//! Unique names for everything the equations stage names: states, intermediates, declared coordinates.
//!
//! Derived names are built from element names (`q_<element>`, `f_<field>_<port>`, `e_<element>`) with the
//! qualification dots of instances replaced (`s.spring` → `s_spring`), so two elements can give one name (element
//! `s_spring` and instance element `s.spring` both give `q_s_spring`). Every name printed or generated must
//! identify one quantity (`--x0 q_s_spring=…`, CSV headers, JSON, `STATE_NAMES`), so names are handed out by a
//! [`UniqueNames`]: the first claim of a name gets it, a later one gets the first free `_2`, `_3`, … suffix.
//! Names the user chose (parameters, inputs, outputs, `var`s) are reserved or claimed before derived ones, and
//! among derived state names the elements of the model itself claim before those of component instances, so that
//! adding an instance never renames an existing state.

use super::StateSpec;
use crate::ir::Model;
use std::collections::HashSet;

/// Hands out names that are unique among themselves and the reserved ones.
#[derive(Clone, Debug, Default)]
pub(crate) struct UniqueNames {
    taken: HashSet<String>,
}

impl UniqueNames {
    /// Marks `name` as taken without handing it out.
    pub fn reserve(&mut self, name: &str) {
        self.taken.insert(name.to_string());
    }

    /// `base` if it is free, else `base_2`, `base_3`, … (the first free one).
    pub fn claim(&mut self, base: &str) -> String {
        let mut candidate = base.to_string();
        let mut k = 2usize;
        while self.taken.contains(&candidate) {
            candidate = format!("{base}_{k}");
            k += 1;
        }
        self.taken.insert(candidate.clone());
        candidate
    }
}

/// The user's own names of a model: parameters, inputs and outputs, as printed.
pub(crate) fn user_names(model: &Model) -> UniqueNames {
    let mut names = UniqueNames::default();
    for p in &model.params {
        names.reserve(&p.name);
    }
    for i in &model.inputs {
        names.reserve(&i.name);
    }
    for o in &model.outputs {
        names.reserve(&o.name);
    }
    names
}

/// Makes the state names unique: `var`s first (their names are the user's), then the states of the model's own
/// elements, then those of instance elements (qualified names), each group in state order.
pub(crate) fn unique_states(model: &Model, states: &mut [StateSpec]) -> UniqueNames {
    let mut names = user_names(model);
    let qualified = |s: &StateSpec| {
        s.node
            .and_then(|n| model.graph.node_weight(n))
            .is_some_and(|w| w.name.contains('.'))
    };
    let group = |s: &StateSpec| match (s.var, qualified(s)) {
        (Some(_), _) => 0,
        (None, false) => 1,
        (None, true) => 2,
    };
    for g in 0..3 {
        for s in states.iter_mut().filter(|s| group(s) == g) {
            s.name = names.claim(&s.name);
        }
    }
    names
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn later_claims_get_the_first_free_suffix() {
        let mut n = UniqueNames::default();
        n.reserve("q_a_2");
        assert_eq!(n.claim("q_a"), "q_a");
        assert_eq!(n.claim("q_a"), "q_a_3");
        assert_eq!(n.claim("q_a"), "q_a_4");
        assert_eq!(n.claim("q_b"), "q_b");
    }
}
