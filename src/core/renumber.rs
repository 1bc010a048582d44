//! Renumbering the particles: a new order of the per-particle arrays, so that particles close in
//! space sit close in memory (as LAMMPS sorts its atoms, `atom_modify sort`). Each particle keeps
//! its id ([`crate::core::state::State::ids`]); the order of the arrays is an implementation
//! detail that outputs undo.
//!
//! Everything that holds per-particle data or particle indices says what a renumbering does to
//! it: the state ([`crate::core::state::State::renumber`]), the neighbour lists, every force term
//! ([`crate::core::forces::ForceTerm::renumber`]) and every integrator
//! ([`crate::core::integrators::Integrator::renumber`]), each a required method.

use super::domain::Domain;
use super::vector::Vec3;

/// A new order of the particles' slots, perhaps without some: new slot k holds the particle of
/// old slot `from[k]`. A particle that leaves the run (through an outlet, or captured) has no new
/// slot; everything that follows a renumbering drops what it holds of it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Renumbering {
    from: Vec<u32>,
    /// `to[i]`: the new slot of old slot i ([`GONE`] for a particle removed).
    to: Vec<u32>,
}

/// The new slot of a removed particle.
pub const GONE: u32 = u32::MAX;

impl Renumbering {
    /// The renumbering whose new slot k holds old slot `from[k]` (`from` a permutation of 0..n).
    pub fn new(from: Vec<u32>) -> Self {
        let n = from.len();
        Self::keeping(from, n)
    }

    /// The renumbering of `old` slots that keeps slots `from` (distinct, each below `old`), new
    /// slot k holding old slot `from[k]`; the others are removed.
    pub fn keeping(from: Vec<u32>, old: usize) -> Self {
        let mut to = vec![GONE; old];
        for (k, &i) in from.iter().enumerate() {
            assert!(to[i as usize] == GONE, "slot {i} appears twice in a renumbering");
            to[i as usize] = k as u32;
        }
        Self { from, to }
    }

    /// The number of slots before.
    pub fn old_len(&self) -> usize {
        self.to.len()
    }

    /// Whether some particles leave.
    pub fn removes(&self) -> bool {
        self.from.len() < self.to.len()
    }

    /// The slots in the order of a Morton (Z-order) curve through cubic cells of edge `cell` from
    /// the box's low corner; slots in one cell keep their order. Neighbours in space become
    /// neighbours in memory.
    pub fn morton(positions: &[Vec3], cell: f64, domain: &Domain) -> Self {
        Self::new(morton_order(positions, cell, domain).into_iter().map(|i| i as u32).collect())
    }

    pub fn len(&self) -> usize {
        self.from.len()
    }

    pub fn is_empty(&self) -> bool {
        self.from.is_empty()
    }

    /// The new slot of old slot `i` ([`GONE`] if removed).
    #[inline]
    pub fn to(&self, i: u32) -> u32 {
        self.to[i as usize]
    }

    /// The key (a, b) of the pair of old slots (i, j), a < b, and whether its ends swapped (b is
    /// [`GONE`] if either end is removed).
    #[inline]
    pub fn pair(&self, (i, j): (u32, u32)) -> ((u32, u32), bool) {
        let (a, b) = (self.to(i), self.to(j));
        ((a.min(b), a.max(b)), a > b)
    }

    /// `v` in the new order, without the removed slots. A vector of another length than the old
    /// slots (a cache not yet filled or left over from another particle set) is emptied: its
    /// holder fills it again.
    pub fn permute<T: Copy>(&self, v: &mut Vec<T>) {
        if v.len() == self.old_len() {
            *v = self.from.iter().map(|&i| v[i as usize]).collect();
        } else {
            v.clear();
        }
    }
}

/// The order of `positions` (their indices) along a Morton (Z-order) curve through cubic cells of
/// edge `cell` from the box's low corner (ties keep their order).
pub fn morton_order(positions: &[Vec3], cell: f64, domain: &Domain) -> Vec<usize> {
    // Spreads the low 21 bits of v to every third bit.
    let spread = |v: u64| (0..21).fold(0u64, |out, b| out | ((v >> b) & 1) << (3 * b));
    let key = |x: &Vec3| {
        let c = |k: usize| (((x[k] - domain.lo[k]) / cell).max(0.0) as u64).min((1 << 21) - 1);
        spread(c(0)) | spread(c(1)) << 1 | spread(c(2)) << 2
    };
    let mut order: Vec<usize> = (0..positions.len()).collect();
    order.sort_by_cached_key(|&i| key(&positions[i]));
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `to` inverts `from`; a pair's key is renamed and ordered, with the swap reported.
    #[test]
    fn a_renumbering_and_its_inverse_agree() {
        let r = Renumbering::new(vec![2, 0, 3, 1]);
        assert_eq!((0..4).map(|i| r.to(i)).collect::<Vec<_>>(), [1, 3, 0, 2]);
        assert_eq!(r.pair((0, 2)), ((0, 1), true));
        assert_eq!(r.pair((0, 3)), ((1, 2), false));
        let mut v = vec!['a', 'b', 'c', 'd'];
        r.permute(&mut v);
        assert_eq!(v, ['c', 'a', 'd', 'b']);
        let mut stale = vec![1.0; 3];
        r.permute(&mut stale);
        assert!(stale.is_empty());
    }

    /// Keeping slots 3 and 1 of five: the others have no new slot, vectors lose them, and a pair
    /// with a removed end is keyed [`GONE`].
    #[test]
    fn a_renumbering_that_removes() {
        let r = Renumbering::keeping(vec![3, 1], 5);
        assert!(r.removes() && r.len() == 2 && r.old_len() == 5);
        assert_eq!((0..5).map(|i| r.to(i)).collect::<Vec<_>>(), [GONE, 1, GONE, 0, GONE]);
        let mut v = vec!['a', 'b', 'c', 'd', 'e'];
        r.permute(&mut v);
        assert_eq!(v, ['d', 'b']);
        assert_eq!(r.pair((1, 3)), ((0, 1), true));
        assert_eq!(r.pair((0, 3)).0 .1, GONE);
    }

    /// Points on a line of cells come out in cell order; two in one cell keep theirs.
    #[test]
    fn morton_order_follows_the_cells() {
        let domain = Domain { lo: Vec3::zeros(), hi: Vec3::repeat(10.0), periodic: [false; 3] };
        let x = |a: f64| Vec3::new(a, 0.5, 0.5);
        let order = morton_order(&[x(3.5), x(0.2), x(2.5), x(0.7)], 1.0, &domain);
        assert_eq!(order, [1, 3, 2, 0]);
    }
}
