//! What a live input already handed on, so that a record or message arriving again (a page
//! polled twice, a broker's redelivery) counts once: a set of keys in bounded memory, the
//! oldest forgotten first.

use std::collections::{HashSet, VecDeque};
use std::hash::Hash;

/// The keys seen, at most `N` of them.
#[derive(Debug)]
pub struct Seen<K, const N: usize> {
    order: VecDeque<K>,
    set: HashSet<K>,
}

impl<K, const N: usize> Default for Seen<K, N> {
    fn default() -> Self {
        Self {
            order: VecDeque::new(),
            set: HashSet::new(),
        }
    }
}

impl<K: Hash + Eq + Clone, const N: usize> Seen<K, N> {
    /// Whether `key` is new; remember it (forgetting the oldest past `N`).
    pub fn first_time(&mut self, key: K) -> bool {
        if !self.set.insert(key.clone()) {
            return false;
        }
        self.order.push_back(key);
        if self.order.len() > N
            && let Some(old) = self.order.pop_front()
        {
            self.set.remove(&old);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_key_counts_once_until_forgotten() {
        let mut s: Seen<u32, 2> = Seen::default();
        assert!(s.first_time(1) && s.first_time(2));
        assert!(!s.first_time(1));
        // A third key forgets the oldest.
        assert!(s.first_time(3) && s.first_time(1));
    }
}
