//! The simulation box: each axis is either bounded by two walls or periodic.

use super::state::Vec3;

#[derive(Debug, Clone, PartialEq)]
pub struct Domain {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Per axis: true = periodic, false = a wall at each end.
    pub periodic: [bool; 3],
}

impl Domain {
    pub fn length(&self) -> Vec3 {
        self.hi - self.lo
    }

    /// Minimum-image displacement a − b: d − L·round(d/L) on periodic axes. Only a component
    /// reaching half the box needs it (below, round(d/L) is 0), so most pairs skip the division.
    #[inline]
    pub fn displacement(&self, a: &Vec3, b: &Vec3) -> Vec3 {
        let mut d = a - b;
        for k in 0..3 {
            if self.periodic[k] {
                let l = self.hi[k] - self.lo[k];
                if d[k].abs() >= 0.5 * l {
                    d[k] -= l * (d[k] / l).round();
                }
            }
        }
        d
    }

    /// Maps a position back into the box along periodic axes.
    #[inline]
    pub fn wrap(&self, p: &mut Vec3) {
        for k in 0..3 {
            if self.periodic[k] {
                let l = self.hi[k] - self.lo[k];
                p[k] = self.lo[k] + (p[k] - self.lo[k]).rem_euclid(l);
            }
        }
    }

    /// Wall faces present (x-lo, x-hi, y-lo, ...), as (face index, axis, is_upper).
    pub fn walls(&self) -> impl Iterator<Item = (u8, usize, bool)> + '_ {
        (0..3usize).filter(|&k| !self.periodic[k]).flat_map(|k| [(2 * k as u8, k, false), (2 * k as u8 + 1, k, true)])
    }
}
