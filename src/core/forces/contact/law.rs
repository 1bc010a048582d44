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
    /// kn and the restitution damping γn at overlap δ (`sq` = √(R*δ)).
    #[inline(always)]
    fn stiffness_and_damping(self, m: &PairMaterial, sq: f64, m_eff: f64) -> (f64, f64) {
        match self {
            Normal::Hertz => {
                (4.0 / 3.0 * m.e_star * sq, -2.0 * SQRT_5_6 * m.beta * (2.0 * m.e_star * sq * m_eff).sqrt())
            }
            Normal::Hooke { stiffness } => (stiffness, -2.0 * m.beta * (stiffness * m_eff).sqrt()),
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

/// Geometry and kinematics of one contact, the input of the contact law.
pub struct ContactPoint {
    pub overlap: f64,
    pub normal: Vec3,
    pub r_eff: f64,
    pub m_eff: f64,
    /// v_i − v_j
    pub rel_velocity: Vec3,
    /// cr_i ω_i + cr_j ω_j (lever arms a − δ/2)
    pub spin: Vec3,
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
    /// Returns (Fn n + Ft) on i, updating the shear history `s` in place.
    #[inline(always)]
    pub fn force(&self, c: &ContactPoint, m: &PairMaterial, s: &mut Vec3, dt: f64) -> Vec3 {
        let sq = (c.r_eff * c.overlap).sqrt();
        let (kn, gamma_n) = self.normal.stiffness_and_damping(m, sq, c.m_eff);
        let vn = c.rel_velocity.dot(&c.normal);
        let fn_mag = kn * c.overlap - gamma_n * vn;
        match self.tangential {
            Tangential::Mindlin => fn_mag * c.normal + mindlin(c, m, sq, vn, fn_mag, s, dt),
            Tangential::None => fn_mag * c.normal,
        }
    }
}

/// Mindlin's tangential force with history and the Coulomb limit.
#[inline(always)]
fn mindlin(c: &ContactPoint, m: &PairMaterial, sq: f64, vn: f64, fn_mag: f64, s: &mut Vec3, dt: f64) -> Vec3 {
    let kt = 8.0 * m.g_star * sq;
    let gamma_t = -2.0 * SQRT_5_6 * m.beta * (kt * c.m_eff).sqrt();
    let vt = c.rel_velocity - vn * c.normal;
    let vtr = vt - c.spin.cross(&c.normal);
    *s += vtr * dt;
    *s -= s.dot(&c.normal) * c.normal;
    let mut ft = -kt * *s;
    let limit = m.friction * fn_mag.abs();
    let ft_norm = ft.norm();
    if ft_norm > limit {
        ft *= if ft_norm > 0.0 { limit / ft_norm } else { 0.0 };
        *s = -ft / kt;
    } else {
        ft -= gamma_t * vtr;
    }
    ft
}
