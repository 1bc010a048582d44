//! Random sequential placement of non-overlapping spheres in a region, from a seed.

use crate::core::domain::Domain;
use crate::core::state::Vec3;
use rand::{RngExt, SeedableRng};
use std::collections::HashMap;

/// Placed spheres (centre, radius) by hash-grid cell.
type Grid = HashMap<(i64, i64, i64), Vec<(Vec3, f64)>>;

/// Attempts per particle before placement gives up.
pub const MAX_ATTEMPTS: usize = 100_000;

/// Places `count` spheres of `radius` uniformly in `[lo, hi]` (centres kept a radius from wall
/// faces), avoiding `existing` spheres (centre, radius). Returns the index of the first particle
/// that could not be placed on failure.
pub fn place_random(
    count: usize,
    radius: f64,
    lo: Vec3,
    hi: Vec3,
    domain: &Domain,
    existing: &[(Vec3, f64)],
    seed: u64,
) -> Result<Vec<Vec3>, usize> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let (mut lo_c, mut hi_c) = (lo, hi);
    for k in 0..3 {
        if !domain.periodic[k] {
            lo_c[k] = lo[k].max(domain.lo[k] + radius);
            hi_c[k] = hi[k].min(domain.hi[k] - radius);
        }
    }
    let mut placed: Vec<Vec3> = Vec::with_capacity(count);
    let max_other = existing.iter().map(|e| e.1).fold(radius, f64::max);
    // Hash grid with cells of one largest contact distance.
    let cell = radius + max_other;
    let key = |x: &Vec3| -> (i64, i64, i64) {
        ((x.x / cell).floor() as i64, (x.y / cell).floor() as i64, (x.z / cell).floor() as i64)
    };
    let mut grid: Grid = Default::default();
    for e in existing {
        grid.entry(key(&e.0)).or_default().push(*e);
    }
    let overlaps = |x: &Vec3, grid: &Grid| {
        let (cx, cy, cz) = key(x);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(v) = grid.get(&(cx + dx, cy + dy, cz + dz)) {
                        if v.iter().any(|(y, r)| (x - y).norm() < radius + r) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    };
    for k in 0..count {
        let mut ok = false;
        for _ in 0..MAX_ATTEMPTS {
            let x = Vec3::from_fn(|a, _| lo_c[a] + (hi_c[a] - lo_c[a]) * rng.random::<f64>());
            // Periodic axes: test the candidate and its images shifted by ±L.
            let images = periodic_images(&x, domain);
            if images.iter().any(|y| overlaps(y, &grid)) {
                continue;
            }
            grid.entry(key(&x)).or_default().push((x, radius));
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

/// `positions` sorted along a Morton (Z-order) curve through cubic cells of edge `cell` from the
/// box's low corner (ties keep their order): neighbours in space become neighbours in memory.
pub fn morton_order(mut positions: Vec<Vec3>, cell: f64, domain: &Domain) -> Vec<Vec3> {
    // Spreads the low 21 bits of v to every third bit.
    let spread = |v: u64| (0..21).fold(0u64, |out, b| out | ((v >> b) & 1) << (3 * b));
    let key = |x: &Vec3| {
        let c = |k: usize| (((x[k] - domain.lo[k]) / cell).max(0.0) as u64).min((1 << 21) - 1);
        spread(c(0)) | spread(c(1)) << 1 | spread(c(2)) << 2
    };
    positions.sort_by_cached_key(key);
    positions
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
