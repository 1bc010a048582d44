//! Random sequential placement of non-overlapping spheres in a region, from a seed, and lattice
//! packings.

use crate::core::domain::Domain;
use crate::core::state::Vec3;
use rand::{RngExt, SeedableRng};
use std::collections::HashMap;

/// Placed spheres (centre, radius) by hash-grid cell.
type Grid = HashMap<(i64, i64, i64), Vec<(Vec3, f64)>>;

/// Attempts per particle before placement gives up.
pub const MAX_ATTEMPTS: usize = 100_000;

/// Where the centre of a sphere of `radius` may lie in the region `[lo, hi]`: kept its radius
/// from the walls on walled axes. An axis whose lower end exceeds its upper one cannot hold it.
pub fn centre_range(radius: f64, lo: Vec3, hi: Vec3, domain: &Domain) -> (Vec3, Vec3) {
    let (mut lo_c, mut hi_c) = (lo, hi);
    for k in 0..3 {
        if !domain.periodic[k] {
            lo_c[k] = lo[k].max(domain.lo[k] + radius);
            hi_c[k] = hi[k].min(domain.hi[k] - radius);
        }
    }
    (lo_c, hi_c)
}

/// Places spheres of `radii` uniformly in `[lo, hi]` (centres kept their radius from wall faces),
/// in order, avoiding `existing` spheres (centre, radius), keeping a drawn centre only where
/// `accept(centre, radius, rng)` holds (a shape inside the region, or a density by rejection from
/// the same stream). Returns the index of the first particle that could not be placed on failure.
pub fn place_random(
    radii: &[f64],
    lo: Vec3,
    hi: Vec3,
    domain: &Domain,
    existing: &[(Vec3, f64)],
    seed: u64,
    mut accept: impl FnMut(&Vec3, f64, &mut rand_chacha::ChaCha8Rng) -> bool,
) -> Result<Vec<Vec3>, usize> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let clamp = |radius: f64| centre_range(radius, lo, hi, domain);
    let mut placed: Vec<Vec3> = Vec::with_capacity(radii.len());
    let mut grid = SphereGrid::new(radii.iter().copied().fold(0.0, f64::max), existing);
    for (k, &radius) in radii.iter().enumerate() {
        let (lo_c, hi_c) = clamp(radius);
        let mut ok = false;
        for _ in 0..MAX_ATTEMPTS {
            let x = Vec3::from_fn(|a, _| lo_c[a] + (hi_c[a] - lo_c[a]) * rng.random::<f64>());
            if !accept(&x, radius, &mut rng) || grid.overlaps(&x, radius, domain) {
                continue;
            }
            grid.insert(x, radius);
            placed.push(x);
            ok = true;
            break;
        }
        if !ok {
            return Err(k);
        }
    }
    Ok(placed)
}

/// Placed spheres in a hash grid with cells of one largest contact distance.
struct SphereGrid {
    cell: f64,
    grid: Grid,
}

impl SphereGrid {
    /// A grid for spheres of `radius` among `existing` ones (centre, radius).
    fn new(radius: f64, existing: &[(Vec3, f64)]) -> Self {
        let max_other = existing.iter().map(|e| e.1).fold(radius, f64::max);
        let mut grid = SphereGrid { cell: radius + max_other, grid: Default::default() };
        for &(x, r) in existing {
            grid.insert(x, r);
        }
        grid
    }
    fn key(&self, x: &Vec3) -> (i64, i64, i64) {
        let c = |v: f64| (v / self.cell).floor() as i64;
        (c(x.x), c(x.y), c(x.z))
    }
    fn insert(&mut self, x: Vec3, radius: f64) {
        self.grid.entry(self.key(&x)).or_default().push((x, radius));
    }
    /// Whether a sphere of `radius` at `x` (or a periodic image of it) overlaps a stored one.
    fn overlaps(&self, x: &Vec3, radius: f64, domain: &Domain) -> bool {
        periodic_images(x, domain).iter().any(|y| {
            let (cx, cy, cz) = self.key(y);
            (-1..=1).any(|dz| {
                (-1..=1).any(|dy| {
                    (-1..=1).any(|dx| {
                        self.grid
                            .get(&(cx + dx, cy + dy, cz + dz))
                            .is_some_and(|v| v.iter().any(|(z, r)| (y - z).norm() < radius + r))
                    })
                })
            })
        })
    }
}

/// The sites of a face-centred cubic lattice: the points `start + (i, j, k) step` with i + j + k
/// even, 0 ≤ i < n[0] and so on (step = half the cubic cell, √2/2 × the nearest-neighbour distance).
#[derive(Debug, Clone, PartialEq)]
pub struct FccGrid {
    start: Vec3,
    step: f64,
    n: [usize; 3],
}

impl FccGrid {
    /// The lattice of nearest-neighbour distance `spacing` filling `[lo, hi]` with spheres of
    /// `radius`: on a walled axis the centres stay a radius from the walls; a periodic axis must
    /// be spanned by the region and hold a whole number of cubic cells (else the reason).
    pub fn new(spacing: f64, radius: f64, lo: Vec3, hi: Vec3, domain: &Domain) -> Result<Self, String> {
        let step = spacing / std::f64::consts::SQRT_2;
        let (mut start, mut n) = (lo, [0usize; 3]);
        for k in 0..3 {
            let axis = ["x", "y", "z"][k];
            if domain.periodic[k] {
                let len = domain.hi[k] - domain.lo[k];
                let cells = len / (2.0 * step);
                if lo[k] != domain.lo[k] || hi[k] != domain.hi[k] || (cells - cells.round()).abs() > 1e-6 * cells {
                    return Err(format!(
                        "on the periodic {axis} axis the region must span the box and its length be a whole number of cubic cells (√2 × spacing = {:e} m; the box holds {cells:.4})",
                        2.0 * step
                    ));
                }
                n[k] = 2 * cells.round() as usize;
            } else {
                start[k] = lo[k].max(domain.lo[k] + radius);
                let end = hi[k].min(domain.hi[k] - radius);
                // Sites on the far bound count (a block fitted to its box touches both walls).
                n[k] = if end >= start[k] { ((end - start[k]) / step * (1.0 + 1e-12)).floor() as usize + 1 } else { 0 };
            }
        }
        Ok(FccGrid { start, step, n })
    }

    /// Number of sites.
    pub fn count(&self) -> usize {
        // Even and odd indices along each axis; a site has an even index sum.
        let [(e0, o0), (e1, o1), (e2, o2)] = self.n.map(|n| (n.div_ceil(2), n / 2));
        e0 * (e1 * e2 + o1 * o2) + o0 * (e1 * o2 + o1 * e2)
    }

    /// The sites, x fastest.
    pub fn sites(&self) -> Vec<Vec3> {
        let mut sites = Vec::with_capacity(self.count());
        for k in 0..self.n[2] {
            for j in 0..self.n[1] {
                for i in (0..self.n[0]).filter(|i| (i + j + k) % 2 == 0) {
                    sites.push(self.start + self.step * Vec3::new(i as f64, j as f64, k as f64));
                }
            }
        }
        sites
    }
}

/// The first of `sites` (spheres of `radius`) that overlaps one of `existing` (centre, radius).
pub fn first_overlap(sites: &[Vec3], radius: f64, existing: &[(Vec3, f64)], domain: &Domain) -> Option<usize> {
    if existing.is_empty() {
        return None;
    }
    let grid = SphereGrid::new(radius, existing);
    sites.iter().position(|x| grid.overlaps(x, radius, domain))
}

/// The position and its periodic images one box length away along periodic axes.
fn periodic_images(x: &Vec3, domain: &Domain) -> Vec<Vec3> {
    let mut images = vec![*x];
    let len = domain.length();
    for k in 0..3 {
        if domain.periodic[k] {
            let current = images.clone();
            for y in current {
                for s in [-1.0, 1.0] {
                    let mut z = y;
                    z[k] += s * len[k];
                    images.push(z);
                }
            }
        }
    }
    images
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An FCC block fitted to a walled box: the count formula matches the sites, every site
    /// keeps a radius from the walls, nearest neighbours are `spacing` apart, and an interior
    /// site has the 12 of a face-centred cubic lattice (and 6 second neighbours at √2 spacing).
    #[test]
    fn fcc_block_has_the_lattice_geometry() {
        let (a, spacing) = (5.5e-6, 11e-6);
        let cells = 4.0;
        let edge = cells * spacing * std::f64::consts::SQRT_2 + 2.0 * a;
        let domain = Domain { lo: Vec3::zeros(), hi: Vec3::repeat(edge), periodic: [false; 3] };
        let grid = FccGrid::new(spacing, a, domain.lo, domain.hi, &domain).unwrap();
        let sites = grid.sites();
        // 2·cells + 1 half-cell positions per axis: (4n³ + 6n² + 3n + 1)/... counted directly.
        let n = 2 * cells as usize + 1;
        let direct = (0..n.pow(3)).filter(|m| (m % n + m / n % n + m / (n * n)).is_multiple_of(2)).count();
        assert_eq!(grid.count(), direct);
        assert_eq!(sites.len(), direct);
        for x in &sites {
            for k in 0..3 {
                assert!(x[k] >= a * (1.0 - 1e-12) && x[k] <= (edge - a) * (1.0 + 1e-12), "{x:?} beyond a wall");
            }
        }
        let centre = Vec3::repeat(0.5 * edge);
        let middle = sites.iter().min_by(|p, q| (*p - centre).norm().total_cmp(&(*q - centre).norm())).unwrap();
        let within = |r: f64| sites.iter().filter(|y| (*y - middle).norm() < r).count() - 1;
        assert_eq!(within(spacing * (1.0 + 1e-9)), 12);
        assert_eq!(within(spacing * (1.0 - 1e-9)), 0);
        assert_eq!(within(spacing * std::f64::consts::SQRT_2 * (1.0 + 1e-9)), 18);
    }

    /// On a periodic axis the lattice closes on itself: the sites nearest the seam are one
    /// spacing from their images, and a length that is not a whole number of cells is refused.
    #[test]
    fn fcc_lattice_closes_across_a_periodic_axis() {
        let (a, spacing) = (5.5e-6, 11e-6);
        let cell = spacing * std::f64::consts::SQRT_2;
        let hi = Vec3::new(3.0 * cell, 2.0 * cell + 2.0 * a, 2.0 * cell + 2.0 * a);
        let domain = Domain { lo: Vec3::zeros(), hi, periodic: [true, false, false] };
        let grid = FccGrid::new(spacing, a, domain.lo, domain.hi, &domain).unwrap();
        let sites = grid.sites();
        let domain = &domain;
        let closest = sites
            .iter()
            .enumerate()
            .flat_map(|(i, x)| sites[i + 1..].iter().map(move |y| domain.displacement(x, y).norm()))
            .fold(f64::INFINITY, f64::min);
        assert!((closest - spacing).abs() < 1e-9 * spacing, "closest pair {closest:e} m");
        let short = Domain { hi: Vec3::new(3.5 * cell, hi.y, hi.z), ..*domain };
        assert!(FccGrid::new(spacing, a, short.lo, short.hi, &short).unwrap_err().contains("whole number"));
    }
}
