//! A list that is almost always one item long: the path of a node reference (`j1`, rarely `inst.port`) and each
//! group of a bond chain (`a -> b`, rarely a fan-out `a -> b, c`). A large model has hundreds of thousands of them;
//! held inline until a second item comes, they cost no allocation of their own.

use serde::{Serialize, Serializer};
use std::fmt;
use std::ops::Deref;

/// A list of `T`, one item inline. It reads as a slice (through `Deref`), prints and serialises as a `Vec` would,
/// and compares by its items.
#[derive(Clone)]
pub enum ShortList<T> {
    One(T),
    Many(Vec<T>),
}

impl<T> ShortList<T> {
    pub fn one(item: T) -> Self {
        ShortList::One(item)
    }

    pub fn push(&mut self, item: T) {
        let old = std::mem::replace(self, ShortList::Many(Vec::new()));
        *self = match old {
            ShortList::One(first) => ShortList::Many(vec![first, item]),
            ShortList::Many(mut items) => {
                items.push(item);
                ShortList::Many(items)
            }
        };
    }
}

impl<T> Deref for ShortList<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        match self {
            ShortList::One(item) => std::slice::from_ref(item),
            ShortList::Many(items) => items,
        }
    }
}

impl<'l, T> IntoIterator for &'l ShortList<T> {
    type Item = &'l T;
    type IntoIter = std::slice::Iter<'l, T>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl<T> FromIterator<T> for ShortList<T> {
    fn from_iter<I: IntoIterator<Item = T>>(iter: I) -> Self {
        let mut items: Vec<T> = iter.into_iter().collect();
        match items.len() {
            1 => items
                .pop()
                .map_or(ShortList::Many(Vec::new()), ShortList::One),
            _ => ShortList::Many(items),
        }
    }
}

impl<T: PartialEq> PartialEq for ShortList<T> {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl<T: fmt::Debug> fmt::Debug for ShortList<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl<T: Serialize> Serialize for ShortList<T> {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(self.iter())
    }
}

#[cfg(test)]
mod tests {
    use super::ShortList;

    #[test]
    fn reads_prints_and_compares_like_a_vec() {
        let mut l = ShortList::one(1);
        assert_eq!(&*l, &[1]);
        l.push(2);
        l.push(3);
        assert_eq!(&*l, &[1, 2, 3]);
        assert_eq!(format!("{l:?}"), format!("{:?}", vec![1, 2, 3]));
        assert_eq!(l, [1, 2, 3].into_iter().collect());
        assert_eq!(ShortList::one(4), ShortList::Many(vec![4]));
        let empty: ShortList<i32> = std::iter::empty().collect();
        assert!(empty.is_empty());
        assert_eq!(
            serde_json::to_string(&l).ok(),
            serde_json::to_string(&vec![1, 2, 3]).ok()
        );
    }
}
