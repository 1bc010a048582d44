//! The contact law, composed of sub-models as in LAMMPS' `pair granular` (normal, damping,
//! tangential; rolling resistance is not modelled), each owning its parameters. The pair
//! constants (E*, G*, β, μ) come from the two species ([`PairMaterial`]).
//!
//! Per contact, with overlap δ, unit normal n (from j to i), R* = a_i a_j/(a_i + a_j),
//! m* = m_i m_j/(m_i + m_j) (a wall has infinite radius and mass: R* = a_i, m* = m_i):
//!
//! - normal, Hertz: kn = 4/3 E* √(R*δ); Hooke: kn = k (a given stiffness, N/m)
//! - damping from restitution, β = ln e / √(ln² e + π²): Hertz γn = −2√(5/6) β √(2E*√(R*δ) m*)
//!   (LIGGGHTS `hertz`); Hooke γn = −2β √(k m*), which gives the restitution e exactly for a
//!   linear spring-dashpot
//! - Fn = kn δ − γn v_n (v_n = (v_i − v_j)·n; not clipped at zero, as LIGGGHTS' default)
//! - tangential, Mindlin with history: kt = 8 G* √(R*δ), γt = −2√(5/6) β √(kt m*); shear history
//!   s += v_t,rel dt, then projected onto the tangent plane; Ft = −kt s; if |Ft| > μ|Fn|: Ft
//!   scaled to μ|Fn| and s = −Ft/kt, else Ft −= γt v_t,rel. Tangential none: Ft = 0
//!   (frictionless spheres).
//! - lever arm a − δ/2 for the torque and the rolling part of v_t,rel.

use crate::core::state::{Species, Vec3};

/// Pair constants of the contact law for two species (the wall takes the particle's own species).
#[derive(Debug, Clone, Copy)]
pub struct PairMaterial {
    /// E* = 1 / ((1 − ν_i²)/E_i + (1 − ν_j²)/E_j)
    pub e_star: f64,
    /// G* = 1 / (2(2 − ν_i)(1 + ν_i)/E_i + 2(2 − ν_j)(1 + ν_j)/E_j)
    pub g_star: f64,
    /// β = ln e / √(ln² e + π²) with e the mean of the two restitution coefficients.
    pub beta: f64,
    /// Friction: the mean of the two coefficients.
    pub friction: f64,
}

impl PairMaterial {
    pub fn new(a: &Species, b: &Species) -> Self {
        let e_star = 1.0
            / ((1.0 - a.poisson_ratio.powi(2)) / a.youngs_modulus + (1.0 - b.poisson_ratio.powi(2)) / b.youngs_modulus);
        let g_term = |s: &Species| 2.0 * (2.0 - s.poisson_ratio) * (1.0 + s.poisson_ratio) / s.youngs_modulus;
        let g_star = 1.0 / (g_term(a) + g_term(b));
        let e = 0.5 * (a.restitution + b.restitution);
        Self { e_star, g_star, beta: restitution_beta(e), friction: 0.5 * (a.friction + b.friction) }
    }
}

/// β = ln e / √(ln² e + π²), the restitution coefficient's damping parameter.
pub fn restitution_beta(e: f64) -> f64 {
    let ln_e = e.ln();
    ln_e / (ln_e * ln_e + std::f64::consts::PI.powi(2)).sqrt()
}

/// √(5/6), Tsuji's factor of the Hertzian damping.
const SQRT_5_6: f64 = 0.912_870_929_175_276_8;

/// The normal elastic force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Normal {
    /// Hertz: kn = 4/3 E* √(R*δ).
    Hertz,
    /// Hooke: a linear spring of `stiffness` (N/m) for every pair and wall.
    Hooke { stiffness: f64 },
}

impl Normal {
    /// kn and the restitution damping γn at overlap δ (`sq` = √(R*δ)) for E* and β of the pair.
    #[inline(always)]
    fn stiffness_and_damping(self, e_star: f64, beta: f64, sq: f64, m_eff: f64) -> (f64, f64) {
        match self {
            Normal::Hertz => (4.0 / 3.0 * e_star * sq, -2.0 * SQRT_5_6 * beta * (2.0 * e_star * sq * m_eff).sqrt()),
            Normal::Hooke { stiffness } => (stiffness, -2.0 * beta * (stiffness * m_eff).sqrt()),
        }
    }
}

/// The tangential force.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tangential {
    /// Mindlin's spring with shear history, damped, capped by Coulomb friction.
    Mindlin,
    /// No tangential force (frictionless spheres); the history stays zero.
    None,
}

/// Contacts taken [`LANES`] at a time, one array per quantity, so that the law's loop over them
/// runs in SIMD lanes (each lane's arithmetic is the scalar law's, operation for operation).
pub const LANES: usize = 8;

type Lane = [f64; LANES];

/// Up to [`LANES`] contacts: the law's inputs (geometry, kinematics, pair constants, springs)
/// and, after [`ContactLaw::apply`], its outputs. A wall contact has R* = a, m* = m, the
/// particle's own velocity and one lever arm.
#[derive(Clone, Default)]
pub struct Lanes {
    pub overlap: Lane,
    /// Unit normal, from j to i (from the wall into the box).
    pub normal: [Lane; 3],
    pub r_eff: Lane,
    pub m_eff: Lane,
    /// v_i − v_j
    pub rel_velocity: [Lane; 3],
    /// cr_i ω_i + cr_j ω_j, with the lever arms cr = a − δ/2
    pub spin: [Lane; 3],
    pub lever_i: Lane,
    pub lever_j: Lane,
    pub e_star: Lane,
    pub g_star: Lane,
    pub beta: Lane,
    pub friction: Lane,
    /// The spring: in, the stored history; out, updated.
    pub shear: [Lane; 3],
    /// Out: Fn n + Ft on i (j receives −force).
    pub force: [Lane; 3],
    /// Out: the torques −cr_i n × Ft and −cr_j n × Ft.
    pub torque_i: [Lane; 3],
    pub torque_j: [Lane; 3],
}

impl Lanes {
    /// Fills lane `l` from a contact's geometry and kinematics, its R* and m* and its pair
    /// constants (`None`: those already in the lane).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn set(
        &mut self,
        l: usize,
        overlap: f64,
        normal: Vec3,
        reduced: Option<(f64, f64)>,
        rel_velocity: Vec3,
        spin: Vec3,
        (lever_i, lever_j): (f64, f64),
        material: Option<&PairMaterial>,
        shear: Vec3,
    ) {
        self.overlap[l] = overlap;
        (self.lever_i[l], self.lever_j[l]) = (lever_i, lever_j);
        if let Some(reduced) = reduced {
            self.set_reduced(l, reduced);
        }
        if let Some(m) = material {
            self.set_material(l, m);
        }
        for c in 0..3 {
            self.normal[c][l] = normal[c];
            self.rel_velocity[c][l] = rel_velocity[c];
            self.spin[c][l] = spin[c];
            self.shear[c][l] = shear[c];
        }
    }

    /// R* and m* of lane `l`.
    #[inline(always)]
    pub fn set_reduced(&mut self, l: usize, (r_eff, m_eff): (f64, f64)) {
        (self.r_eff[l], self.m_eff[l]) = (r_eff, m_eff);
    }

    /// The pair constants of lane `l`.
    #[inline(always)]
    pub fn set_material(&mut self, l: usize, m: &PairMaterial) {
        (self.e_star[l], self.g_star[l], self.beta[l], self.friction[l]) = (m.e_star, m.g_star, m.beta, m.friction);
    }

    fn get(v: &[Lane; 3], l: usize) -> Vec3 {
        Vec3::new(v[0][l], v[1][l], v[2][l])
    }
    pub fn force(&self, l: usize) -> Vec3 {
        Self::get(&self.force, l)
    }
    pub fn torque_i(&self, l: usize) -> Vec3 {
        Self::get(&self.torque_i, l)
    }
    pub fn torque_j(&self, l: usize) -> Vec3 {
        Self::get(&self.torque_j, l)
    }
    pub fn shear(&self, l: usize) -> Vec3 {
        Self::get(&self.shear, l)
    }
    #[cfg(test)]
    fn normal_of(&self, l: usize) -> Vec3 {
        Self::get(&self.normal, l)
    }
}

/// The composed law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaw {
    pub normal: Normal,
    pub tangential: Tangential,
}

impl Default for ContactLaw {
    /// LIGGGHTS' `model hertz tangential history` with restitution damping.
    fn default() -> Self {
        ContactLaw { normal: Normal::Hertz, tangential: Tangential::Mindlin }
    }
}

impl ContactLaw {
    /// The law on every lane of `c` (lanes past the contacts in use compute what they hold).
    pub fn apply(&self, c: &mut Lanes, dt: f64) {
        let normal = self.normal;
        let normal_law = move |e, b, sq, m| normal.stiffness_and_damping(e, b, sq, m);
        match self.tangential {
            // First as if every contact sticks, which leaves out the sliding side's four divisions
            // per lane; if one of them slides after all, the batch again from its stored springs
            // with both sides (the same bits as taking both sides at once).
            Tangential::Mindlin => {
                let shear = c.shear;
                if lanes::<true, false>(c, dt, normal_law) {
                    c.shear = shear;
                    lanes::<true, true>(c, dt, normal_law);
                }
            }
            Tangential::None => {
                lanes::<false, false>(c, dt, normal_law);
            }
        }
    }
}

/// The law lane by lane, branch-free (with `SLIDING`, both sides of the Coulomb test are
/// computed and one is kept; without, every lane takes the sticking side), written component by
/// component in nalgebra's order of operations: the bits are those of the vector expressions in
/// the module's doc. Eight independent contacts in one loop keep the core's pipelines full (a
/// contact alone is one long chain of dependent √ and ÷). Returns whether a lane slides.
#[inline(always)]
fn lanes<const MINDLIN: bool, const SLIDING: bool>(
    c: &mut Lanes,
    dt: f64,
    normal_law: impl Fn(f64, f64, f64, f64) -> (f64, f64),
) -> bool {
    let mut any_sliding = false;
    for l in 0..LANES {
        let [nx, ny, nz] = [c.normal[0][l], c.normal[1][l], c.normal[2][l]];
        let [rx, ry, rz] = [c.rel_velocity[0][l], c.rel_velocity[1][l], c.rel_velocity[2][l]];
        let (overlap, m_eff) = (c.overlap[l], c.m_eff[l]);
        let sq = (c.r_eff[l] * overlap).sqrt();
        let (kn, gamma_n) = normal_law(c.e_star[l], c.beta[l], sq, m_eff);
        let vn = rx * nx + ry * ny + rz * nz;
        let fn_mag = kn * overlap - gamma_n * vn;
        let (mut fx, mut fy, mut fz) = (fn_mag * nx, fn_mag * ny, fn_mag * nz);
        if MINDLIN {
            let kt = 8.0 * c.g_star[l] * sq;
            let gamma_t = -2.0 * SQRT_5_6 * c.beta[l] * (kt * m_eff).sqrt();
            let [wx, wy, wz] = [c.spin[0][l], c.spin[1][l], c.spin[2][l]];
            // v_t,rel = (v − vn n) − spin × n
            let vtx = (rx - vn * nx) - (wy * nz - wz * ny);
            let vty = (ry - vn * ny) - (wz * nx - wx * nz);
            let vtz = (rz - vn * nz) - (wx * ny - wy * nx);
            let (sx, sy, sz) = (c.shear[0][l] + vtx * dt, c.shear[1][l] + vty * dt, c.shear[2][l] + vtz * dt);
            let sn = sx * nx + sy * ny + sz * nz;
            let (sx, sy, sz) = (sx - sn * nx, sy - sn * ny, sz - sn * nz);
            let (tx, ty, tz) = (-kt * sx, -kt * sy, -kt * sz);
            let limit = c.friction[l] * fn_mag.abs();
            let ft_norm2 = tx * tx + ty * ty + tz * tz;
            let ft_norm = ft_norm2.sqrt();
            // Sliding: Ft scaled to the limit, the spring to −Ft/kt; sticking: Ft damped.
            let sliding = ft_norm2 > limit * limit * (1.0 - 1e-12) && ft_norm > limit;
            any_sliding |= sliding;
            let stick = (tx - gamma_t * vtx, ty - gamma_t * vty, tz - gamma_t * vtz);
            let (tx, ty, tz, spring) = if SLIDING {
                let scale = if ft_norm > 0.0 { limit / ft_norm } else { 0.0 };
                let slide = (tx * scale, ty * scale, tz * scale);
                let (tx, ty, tz) = if sliding { slide } else { stick };
                (tx, ty, tz, if sliding { (-tx / kt, -ty / kt, -tz / kt) } else { (sx, sy, sz) })
            } else {
                (stick.0, stick.1, stick.2, (sx, sy, sz))
            };
            (c.shear[0][l], c.shear[1][l], c.shear[2][l]) = spring;
            (fx, fy, fz) = (fx + tx, fy + ty, fz + tz);
        }
        (c.force[0][l], c.force[1][l], c.force[2][l]) = (fx, fy, fz);
        // n × (F − (F·n) n), the lever arms' torques
        let fd = fx * nx + fy * ny + fz * nz;
        let (ux, uy, uz) = (fx - fd * nx, fy - fd * ny, fz - fd * nz);
        let (qx, qy, qz) = (ny * uz - nz * uy, nz * ux - nx * uz, nx * uy - ny * ux);
        let (ai, aj) = (-c.lever_i[l], -c.lever_j[l]);
        (c.torque_i[0][l], c.torque_i[1][l], c.torque_i[2][l]) = (ai * qx, ai * qy, ai * qz);
        (c.torque_j[0][l], c.torque_j[1][l], c.torque_j[2][l]) = (aj * qx, aj * qy, aj * qz);
    }
    any_sliding
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The module doc's vector expressions, one contact at a time (nalgebra): (force, spring,
    /// n × Ft).
    fn reference(law: &ContactLaw, c: &Lanes, l: usize, dt: f64) -> (Vec3, Vec3, Vec3) {
        let get = |v: &[Lane; 3]| Vec3::new(v[0][l], v[1][l], v[2][l]);
        let (n, v, spin, mut s) = (get(&c.normal), get(&c.rel_velocity), get(&c.spin), get(&c.shear));
        let (overlap, m_eff) = (c.overlap[l], c.m_eff[l]);
        let sq = (c.r_eff[l] * overlap).sqrt();
        let (kn, gamma_n) = law.normal.stiffness_and_damping(c.e_star[l], c.beta[l], sq, m_eff);
        let vn = v.dot(&n);
        let fn_mag = kn * overlap - gamma_n * vn;
        let mut force = fn_mag * n;
        if law.tangential == Tangential::Mindlin {
            let kt = 8.0 * c.g_star[l] * sq;
            let gamma_t = -2.0 * SQRT_5_6 * c.beta[l] * (kt * m_eff).sqrt();
            let vtr = (v - vn * n) - spin.cross(&n);
            s += vtr * dt;
            s -= s.dot(&n) * n;
            let mut ft = -kt * s;
            let (limit, ft_norm) = (c.friction[l] * fn_mag.abs(), ft.norm());
            if ft_norm > limit {
                ft *= if ft_norm > 0.0 { limit / ft_norm } else { 0.0 };
                s = -ft / kt;
            } else {
                ft -= gamma_t * vtr;
            }
            force += ft;
        }
        (force, s, n.cross(&(force - force.dot(&n) * n)))
    }

    /// Every lane of the law gives the bits of the vector expressions, for both normal models,
    /// with and without Mindlin, over contacts that stick and contacts that slide, in batches
    /// where all stick (taken once) and batches where some slide (taken again with both sides).
    #[test]
    fn lanes_give_the_bits_of_the_vector_law() {
        let value = |k: usize| (k as f64 * 0.618_033_988_749_895).fract() - 0.5;
        let species = crate::core::state::test_sphere(5.5e-6);
        let m = PairMaterial::new(&species, &species);
        let (mut sliding, mut sticking) = (0, 0);
        let (mut batches_sticking, mut batches_sliding) = (0, 0);
        for law in [
            ContactLaw::default(),
            ContactLaw { normal: Normal::Hertz, tangential: Tangential::None },
            ContactLaw { normal: Normal::Hooke { stiffness: 50.0 }, tangential: Tangential::Mindlin },
        ] {
            for batch in 0..40 {
                let mut c = Lanes::default();
                for l in 0..LANES {
                    let k = 40 * (batch * LANES + l);
                    let normal = Vec3::new(value(k), value(k + 1), value(k + 2)).normalize();
                    let v = 1e-4 * Vec3::new(value(k + 3), value(k + 4), value(k + 5));
                    let spin = 1e-4 * Vec3::new(value(k + 6), value(k + 7), value(k + 8));
                    // Springs from none to well past the Coulomb limit.
                    let shear = 1e-9 * (batch as f64 / 10.0) * Vec3::new(value(k + 9), value(k + 10), value(k + 11));
                    let overlap = 1e-9 * (1.0 + value(k + 12));
                    c.set(l, overlap, normal, Some((2.75e-6, 3.8e-13)), v, spin, (5.5e-6, 5.5e-6), Some(&m), shear);
                }
                let input = c.clone();
                law.apply(&mut c, 1e-8);
                let mut sticks = input.clone();
                if law.tangential == Tangential::Mindlin {
                    match lanes::<true, false>(&mut sticks, 1e-8, |e, b, sq, m| {
                        law.normal.stiffness_and_damping(e, b, sq, m)
                    }) {
                        true => batches_sliding += 1,
                        false => batches_sticking += 1,
                    }
                }
                for l in 0..LANES {
                    let (force, shear, n_x_ft) = reference(&law, &input, l, 1e-8);
                    assert_eq!(c.force(l), force, "{law:?} lane {l}: force");
                    assert_eq!(c.shear(l), shear, "{law:?} lane {l}: spring");
                    assert_eq!(c.torque_i(l), -input.lever_i[l] * n_x_ft, "{law:?} lane {l}: torque");
                    if law.tangential == Tangential::Mindlin {
                        let fn_mag = force.dot(&input.normal_of(l));
                        let ft = force - fn_mag * input.normal_of(l);
                        if ft.norm() >= 0.999 * m.friction * fn_mag.abs() {
                            sliding += 1;
                        } else {
                            sticking += 1;
                        }
                    }
                }
            }
        }
        assert!(sliding > 50 && sticking > 50, "{sliding} sliding and {sticking} sticking contacts");
        assert!(
            batches_sticking > 5 && batches_sliding > 5,
            "{batches_sticking} batches all sticking, {batches_sliding} not"
        );
    }
}
