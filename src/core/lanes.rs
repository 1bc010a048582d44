//! Four 3-vectors by component in SIMD lanes (`wide::f64x4`): for pair kernels that compute four
//! pairs at once. Lane arithmetic is IEEE's, operation by operation, so a kernel that repeats the
//! scalar one's operations in the same order gives its bits in every lane.

use super::state::Vec3;
use wide::f64x4;

/// The x, y and z components of four vectors.
pub type Vec3x4 = [f64x4; 3];

/// Four vectors into lanes, each component read from where the vector is. (Copied first into
/// an array of four vectors, they went through the stack, written 8 bytes at a time and read
/// back 32 bytes at a time: a failed store forwarding, a stall, on each read; a fifth of the
/// moments sweep's time.)
#[inline(always)]
pub fn gather(v: [&Vec3; 4]) -> Vec3x4 {
    std::array::from_fn(|c| f64x4::new([v[0][c], v[1][c], v[2][c], v[3][c]]))
}

/// The four vectors of lanes `v`.
#[inline(always)]
pub fn scatter(v: &Vec3x4) -> [Vec3; 4] {
    let [x, y, z] = v.map(|c| c.to_array());
    std::array::from_fn(|k| Vec3::new(x[k], y[k], z[k]))
}

/// a·b lane by lane, summed as nalgebra's `dot` sums three components: (a_x b_x + a_y b_y) + a_z b_z.
#[inline(always)]
pub fn dot(a: &Vec3x4, b: &Vec3x4) -> f64x4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Inputs for the lane kernels' tests.
#[cfg(test)]
pub(crate) mod testing {
    use crate::core::neighbours::Pair;
    use crate::core::state::Vec3;
    use rand::{RngExt, SeedableRng};

    /// Moments for 64 particles (any orientation) and `quads` groups of four pairs among them,
    /// separated by up to 15 diameters of 11 µm in every direction.
    pub fn random_quads(seed: u64, quads: usize) -> (Vec<Vec3>, Vec<[Pair; 4]>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut vector = |scale: f64| {
            Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * scale
        };
        let moment: Vec<Vec3> = (0..64).map(|_| vector(4e-10)).collect();
        let pairs = (0..quads)
            .map(|k| {
                std::array::from_fn(|l| {
                    let (i, j) = ((k + 3 * l) % 63, 63 - (k * 7 + l) % 31);
                    let r = vector(1.65e-4);
                    Pair { i: i.min(j) as u32, j: i.max(j) as u32, r, dist: r.norm_squared().sqrt() }
                })
            })
            .collect();
        (moment, pairs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lanes' dot product is nalgebra's, bit for bit, and vectors come back out unchanged.
    #[test]
    fn lanes_give_the_scalar_bits() {
        let v = |k: f64| Vec3::new((1.3 * k).sin() * 1e-7, (0.7 * k).cos() * 3e5, (k * k).sqrt() - 2.5);
        for k in 0..64 {
            let (a, b) =
                (std::array::from_fn(|l| v((k * 4 + l) as f64)), std::array::from_fn(|l| v((k * 8 + l) as f64 + 0.5)));
            let (la, lb): ([Vec3; 4], [Vec3; 4]) = (a, b);
            let (ga, gb) = (gather(la.each_ref()), gather(lb.each_ref()));
            assert_eq!(scatter(&ga), la);
            let dots = dot(&ga, &gb).to_array();
            for l in 0..4 {
                assert_eq!(dots[l].to_bits(), la[l].dot(&lb[l]).to_bits());
            }
        }
    }
}
