//! Counter-based random numbers for thermal forces: the draw of particle `id` at step `step` is a
//! pure function of (seed, step, id, stream), so it is the same on any number of threads, in any
//! particle order, and after `--resume` without storing a generator state.
//!
//! The generator is Philox4x32-10 (Salmon, Moraes, Dror & Shaw, "Parallel random numbers: as
//! easy as 1, 2, 3", SC11), as in HOOMD-blue and OpenMM; normals come from the Box–Muller
//! transform of its uniform words.

/// Philox4x32 multipliers and Weyl key increments (Salmon et al., table 2).
const M0: u32 = 0xD251_1F53;
const M1: u32 = 0xCD9E_8D57;
const W0: u32 = 0x9E37_79B9;
const W1: u32 = 0xBB67_AE85;

/// Philox4x32-10: ten rounds of the bijection on the 128-bit counter under the 64-bit key.
pub fn philox4x32(counter: [u32; 4], key: [u32; 2]) -> [u32; 4] {
    let (mut c, mut k) = (counter, key);
    for round in 0..10 {
        if round > 0 {
            k = [k[0].wrapping_add(W0), k[1].wrapping_add(W1)];
        }
        let p0 = u64::from(M0) * u64::from(c[0]);
        let p1 = u64::from(M1) * u64::from(c[2]);
        c = [((p1 >> 32) as u32) ^ c[1] ^ k[0], p1 as u32, ((p0 >> 32) as u32) ^ c[3] ^ k[1], p0 as u32];
    }
    c
}

/// What a draw is for, so that two uses at the same step and particle never share numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
pub enum Stream {
    /// The thermal force (`[forces.thermal]`).
    Translation = 0,
    /// The thermal torque.
    Rotation = 1,
    /// The overdamped scheme's displacement (`scheme = "brownian"`).
    BrownianTranslation = 2,
    /// The overdamped scheme's turn of a permanent moment.
    BrownianRotation = 3,
}

/// The noise source of one run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Noise {
    pub seed: u64,
}

impl Noise {
    /// Four uniform words of (step, id, stream).
    fn words(&self, step: u64, id: u32, stream: Stream) -> [u32; 4] {
        let counter = [step as u32, (step >> 32) as u32, id, stream as u32];
        philox4x32(counter, [self.seed as u32, (self.seed >> 32) as u32])
    }

    /// Three independent standard normals for particle `id` at `step` (the fourth of the two
    /// Box–Muller pairs is dropped).
    pub fn normal3(&self, step: u64, id: u32, stream: Stream) -> [f64; 3] {
        let w = self.words(step, id, stream);
        let (n0, n1) = box_muller(w[0], w[1]);
        let (n2, _) = box_muller(w[2], w[3]);
        [n0, n1, n2]
    }
}

/// Uniform in (0, 1] from a 32-bit word: never 0, so its logarithm is finite.
fn open_unit(w: u32) -> f64 {
    (f64::from(w) + 1.0) / 4_294_967_296.0
}

/// Two independent standard normals from two uniform words (Box & Muller, 1958).
fn box_muller(u: u32, v: u32) -> (f64, f64) {
    let r = (-2.0 * open_unit(u).ln()).sqrt();
    let theta = 2.0 * std::f64::consts::PI * open_unit(v);
    (r * theta.cos(), r * theta.sin())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Known-answer vectors of Philox4x32-10 from the Random123 distribution (kat_vectors).
    #[test]
    fn philox_matches_the_random123_known_answers() {
        assert_eq!(philox4x32([0; 4], [0; 2]), [0x6627_e8d5, 0xe169_c58d, 0xbc57_ac4c, 0x9b00_dbd8]);
        assert_eq!(philox4x32([u32::MAX; 4], [u32::MAX; 2]), [0x408f_276d, 0x41c8_3b0e, 0xa20b_c7c6, 0x6d54_51fd]);
        assert_eq!(
            philox4x32([0x243f_6a88, 0x85a3_08d3, 0x1319_8a2e, 0x0370_7344], [0xa409_3822, 0x299f_31d0]),
            [0xd16c_fe09, 0x94fd_cceb, 0x5001_e420, 0x2412_6ea1]
        );
    }

    /// 3 × 10⁵ normals: mean within 5 standard errors of 0, variance within 5 of 1, no
    /// correlation between neighbouring ids or steps or between the two streams.
    #[test]
    fn normals_have_unit_variance_and_no_correlation() {
        let noise = Noise { seed: 42 };
        let n = 100_000;
        let draws: Vec<[f64; 3]> = (0..n).map(|k| noise.normal3(7, k as u32, Stream::Translation)).collect();
        let all: Vec<f64> = draws.iter().flatten().copied().collect();
        let m = all.len() as f64;
        let mean = all.iter().sum::<f64>() / m;
        let var = all.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / m;
        assert!(mean.abs() < 5.0 / m.sqrt(), "mean {mean}");
        // The variance of a sample variance of normals is 2/m.
        assert!((var - 1.0).abs() < 5.0 * (2.0 / m).sqrt(), "variance {var}");
        let corr =
            |a: &dyn Fn(usize) -> f64, b: &dyn Fn(usize) -> f64| (0..n).map(|k| a(k) * b(k)).sum::<f64>() / n as f64;
        let bound = 5.0 / (n as f64).sqrt();
        let next_id = corr(&|k| draws[k][0], &|k| draws[(k + 1) % n][0]);
        let next_step = corr(&|k| draws[k][1], &|k| noise.normal3(8, k as u32, Stream::Translation)[1]);
        let other_stream = corr(&|k| draws[k][2], &|k| noise.normal3(7, k as u32, Stream::Rotation)[2]);
        let within = corr(&|k| draws[k][0], &|k| draws[k][1]);
        for (what, c) in [("ids", next_id), ("steps", next_step), ("streams", other_stream), ("components", within)] {
            assert!(c.abs() < bound, "{what}: correlation {c}");
        }
    }

    /// A draw depends on its counter and key alone: the same (seed, step, id) gives the same
    /// numbers in any order, and another seed gives others.
    #[test]
    fn a_draw_is_a_function_of_its_counter() {
        let a = Noise { seed: 1 };
        let forward: Vec<[f64; 3]> = (0..100).map(|k| a.normal3(5, k, Stream::Rotation)).collect();
        let backward: Vec<[f64; 3]> = (0..100).rev().map(|k| a.normal3(5, k, Stream::Rotation)).collect();
        assert!(forward.iter().zip(backward.iter().rev()).all(|(x, y)| x.map(f64::to_bits) == y.map(f64::to_bits)));
        assert_ne!(a.normal3(5, 3, Stream::Rotation), Noise { seed: 2 }.normal3(5, 3, Stream::Rotation));
    }
}
