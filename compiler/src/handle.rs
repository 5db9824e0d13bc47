//! Typed handles into typed arenas, as naga's `Handle<T>` and `Table<T>`: a handle of a
//! channel cannot index the resources, and a dump prints `channel#3`, not `3`.

use std::fmt;
use std::hash::{Hash, Hasher};
use std::marker::PhantomData;

/// What a handle's `Debug` form calls the entity it names (`node#3`, `channel#0`).
pub trait Kind {
    const KIND: &'static str;
}

/// An index into an [`Table<T>`] (or the expression arena, for `Handle<Node>`).
pub struct Handle<T> {
    index: u32,
    marker: PhantomData<fn() -> T>,
}

impl<T> Handle<T> {
    /// The handle of the `index`-th element. Valid only for an arena holding more than
    /// `index` elements (`ir::validate` checks every handle of an IR).
    pub fn new(index: usize) -> Handle<T> {
        Handle {
            index: u32::try_from(index).expect("arena holds at most 2^32 elements"),
            marker: PhantomData,
        }
    }

    pub fn index(self) -> usize {
        self.index as usize
    }
}

impl<T> Clone for Handle<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Handle<T> {}

impl<T> PartialEq for Handle<T> {
    fn eq(&self, other: &Self) -> bool {
        self.index == other.index
    }
}

impl<T> Eq for Handle<T> {}

impl<T> PartialOrd for Handle<T> {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl<T> Ord for Handle<T> {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.index.cmp(&other.index)
    }
}

impl<T> Hash for Handle<T> {
    fn hash<S: Hasher>(&self, state: &mut S) {
        self.index.hash(state)
    }
}

impl<T: Kind> fmt::Debug for Handle<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}#{}", T::KIND, self.index)
    }
}

impl<T: Kind> fmt::Display for Handle<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}#{}", T::KIND, self.index)
    }
}

/// A vector of `T` indexed by `Handle<K>`; elements are only appended. `K` is `T` but for
/// a side table that maps the entities of another arena one to one (the laid-out
/// resources of `pack`, indexed by the handles of the lowered ones).
pub struct Table<T, K = T> {
    items: Vec<T>,
    marker: PhantomData<fn() -> K>,
}

impl<T: Clone, K> Clone for Table<T, K> {
    fn clone(&self) -> Self {
        Table {
            items: self.items.clone(),
            marker: PhantomData,
        }
    }
}

impl<T, K> Default for Table<T, K> {
    fn default() -> Self {
        Table {
            items: Vec::new(),
            marker: PhantomData,
        }
    }
}

impl<T: fmt::Debug, K: Kind> fmt::Debug for Table<T, K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_map().entries(self.with_handles()).finish()
    }
}

impl<T, K> Table<T, K> {
    pub fn append(&mut self, item: T) -> Handle<K> {
        let h = Handle::new(self.items.len());
        self.items.push(item);
        h
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// Whether `h` indexes an element of this arena.
    pub fn contains(&self, h: Handle<K>) -> bool {
        h.index() < self.items.len()
    }

    pub fn get(&self, h: Handle<K>) -> Option<&T> {
        self.items.get(h.index())
    }

    /// Elements with their handles, in order.
    pub fn with_handles(&self) -> impl DoubleEndedIterator<Item = (Handle<K>, &T)> + ExactSizeIterator {
        self.items.iter().enumerate().map(|(i, t)| (Handle::new(i), t))
    }

    pub fn with_handles_mut(&mut self) -> impl DoubleEndedIterator<Item = (Handle<K>, &mut T)> + ExactSizeIterator {
        self.items.iter_mut().enumerate().map(|(i, t)| (Handle::new(i), t))
    }

    /// Elements alone, in order.
    pub fn iter(&self) -> std::slice::Iter<'_, T> {
        self.items.iter()
    }

    pub fn iter_mut(&mut self) -> std::slice::IterMut<'_, T> {
        self.items.iter_mut()
    }

    pub fn handles(&self) -> impl DoubleEndedIterator<Item = Handle<K>> + ExactSizeIterator + use<T, K> {
        (0..self.items.len()).map(Handle::new)
    }
}

impl<T, K> std::ops::Index<Handle<K>> for Table<T, K> {
    type Output = T;
    fn index(&self, h: Handle<K>) -> &T {
        &self.items[h.index()]
    }
}

impl<T, K> std::ops::IndexMut<Handle<K>> for Table<T, K> {
    fn index_mut(&mut self, h: Handle<K>) -> &mut T {
        &mut self.items[h.index()]
    }
}

impl<'a, T, K> IntoIterator for &'a Table<T, K> {
    type Item = &'a T;
    type IntoIter = std::slice::Iter<'a, T>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.iter()
    }
}

impl<T, K> FromIterator<T> for Table<T, K> {
    fn from_iter<I: IntoIterator<Item = T>>(iter: I) -> Self {
        Table {
            items: iter.into_iter().collect(),
            marker: PhantomData,
        }
    }
}

impl<T, K> Extend<T> for Table<T, K> {
    fn extend<I: IntoIterator<Item = T>>(&mut self, iter: I) {
        self.items.extend(iter)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Thing;
    impl Kind for Thing {
        const KIND: &'static str = "thing";
    }

    #[test]
    fn handles_print_their_kind_and_index() {
        let mut a: Table<Thing> = Table::default();
        a.append(Thing);
        let h = a.append(Thing);
        assert_eq!(format!("{h:?}"), "thing#1");
        assert!(a.contains(h) && !a.contains(Handle::new(2)));
        assert_eq!(a.handles().collect::<Vec<_>>(), vec![Handle::new(0), h]);
    }
}
