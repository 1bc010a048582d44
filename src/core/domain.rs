//! The simulation box: each axis is either bounded by two walls or periodic.

use super::vector::Vec3;

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
                let (l, a) = (self.hi[k] - self.lo[k], p[k] - self.lo[k]);
                // Inside the box rem_euclid returns a itself: skip its fmod.
                p[k] = self.lo[k] + if (0.0..l).contains(&a) { a } else { a.rem_euclid(l) };
            }
        }
    }

    /// A bound (m) on how far a [`Domain::wrap`] moves a position's minimum image: the rounding of
    /// lo + (x − lo) mod L, two roundings of numbers below 2 (max(|lo|, |hi|) + L) on each
    /// periodic axis, each at most half an ulp (ε |y| for |y| below it), summed over the axes.
    pub fn wrap_rounding(&self) -> f64 {
        (0..3)
            .filter(|&k| self.periodic[k])
            .map(|k| 4.0 * f64::EPSILON * (self.lo[k].abs().max(self.hi[k].abs()) + (self.hi[k] - self.lo[k])))
            .sum()
    }

    /// Wall faces present (x-lo, x-hi, y-lo, ...), as (face index, axis, is_upper).
    pub fn walls(&self) -> impl Iterator<Item = (u8, usize, bool)> + '_ {
        (0..3usize).filter(|&k| !self.periodic[k]).flat_map(|k| [(2 * k as u8, k, false), (2 * k as u8 + 1, k, true)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wrapping gives the bits of lo + (x − lo).rem_euclid(L) everywhere: inside the box (where
    /// it skips the remainder), on its faces, and one or several lengths outside either side.
    #[test]
    fn wrap_gives_the_bits_of_the_euclidean_remainder() {
        let domain =
            Domain { lo: Vec3::new(-1.3e-4, 0.0, 2.0e-5), hi: Vec3::new(7.1e-4, 3.3e-4, 1.0e-3), periodic: [true; 3] };
        let l = domain.hi - domain.lo;
        for k in 0..3 {
            let (lo, hi) = (domain.lo[k], domain.hi[k]);
            let xs = [
                lo,
                hi,
                lo + 0.37 * l[k],
                hi - 1e-19,
                lo - 1e-19,
                lo - 0.0,
                hi + 0.25 * l[k],
                lo - 2.6 * l[k],
                hi + 3.9 * l[k],
            ];
            for x in xs {
                let mut p = domain.lo;
                p[k] = x;
                domain.wrap(&mut p);
                let expected = lo + (x - lo).rem_euclid(l[k]);
                assert_eq!(p[k].to_bits(), expected.to_bits(), "axis {k}, x = {x:e}");
                assert!((lo..=hi).contains(&p[k]), "axis {k}, x = {x:e} wrapped to {:e}", p[k]);
            }
        }
    }
}
