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

/// A permutation of the particles' slots: new slot k holds the particle of old slot `from[k]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Renumbering {
    from: Vec<u32>,
    /// `to[i]`: the new slot of old slot i.
    to: Vec<u32>,
}

impl Renumbering {
    /// The renumbering whose new slot k holds old slot `from[k]` (`from` a permutation of 0..n).
    pub fn new(from: Vec<u32>) -> Self {
        let mut to = vec![u32::MAX; from.len()];
        for (k, &i) in from.iter().enumerate() {
            assert!(to[i as usize] == u32::MAX, "slot {i} appears twice in a renumbering");
            to[i as usize] = k as u32;
        }
        Self { from, to }
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

    /// The new slot of old slot `i`.
    #[inline]
    pub fn to(&self, i: u32) -> u32 {
        self.to[i as usize]
    }

    /// The key (a, b) of the pair of old slots (i, j), a < b, and whether its ends swapped.
    #[inline]
    pub fn pair(&self, (i, j): (u32, u32)) -> ((u32, u32), bool) {
        let (a, b) = (self.to(i), self.to(j));
        ((a.min(b), a.max(b)), a > b)
    }

    /// `v` in the new order. A vector of another length (a cache not yet filled or left over from
    /// another particle set) is emptied: its holder fills it again.
    pub fn permute<T: Copy>(&self, v: &mut Vec<T>) {
        if v.len() == self.len() {
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

    /// Points on a line of cells come out in cell order; two in one cell keep theirs.
    #[test]
    fn morton_order_follows_the_cells() {
        let domain = Domain { lo: Vec3::zeros(), hi: Vec3::repeat(10.0), periodic: [false; 3] };
        let x = |a: f64| Vec3::new(a, 0.5, 0.5);
        let order = morton_order(&[x(3.5), x(0.2), x(2.5), x(0.7)], 1.0, &domain);
        assert_eq!(order, [1, 3, 2, 0]);
    }
}
