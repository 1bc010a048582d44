//! Hertz normal + Mindlin tangential contact with history and a Coulomb limit, particle–particle
//! and particle–wall, composed as in LIGGGHTS `model hertz tangential history` (normal_model_hertz.h,
//! tangential_model_history.h), with damping set from the restitution coefficient.
//!
//! Per contact, with overlap δ, unit normal n (from j to i), R* = a_i a_j/(a_i + a_j),
//! m* = m_i m_j/(m_i + m_j) (a wall has infinite radius and mass: R* = a_i, m* = m_i):
//!
//! - kn = 4/3 E* √(R*δ),  kt = 8 G* √(R*δ)
//! - β = ln e / √(ln² e + π²),  γn = −2√(5/6) β √(2E*√(R*δ) m*),  γt = −2√(5/6) β √(kt m*)
//! - Fn = kn δ − γn v_n (v_n = (v_i − v_j)·n; not clipped at zero, as LIGGGHTS' default)
//! - shear history s += v_t,rel dt, then projected onto the tangent plane; Ft = −kt s;
//!   if |Ft| > μ|Fn|: Ft scaled to μ|Fn| and s = −Ft/kt, else Ft −= γt v_t,rel
//! - lever arm a − δ/2 for the torque and the rolling part of v_t,rel.

use super::{ForceContext, ForceTerm};
use crate::core::domain::Domain;
use crate::core::state::{ContactDiagnostics, Species, State, Vec3};
use std::collections::HashMap;

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
            / ((1.0 - a.poisson_ratio.powi(2)) / a.youngs_modulus
                + (1.0 - b.poisson_ratio.powi(2)) / b.youngs_modulus);
        let g_term = |s: &Species| 2.0 * (2.0 - s.poisson_ratio) * (1.0 + s.poisson_ratio) / s.youngs_modulus;
        let g_star = 1.0 / (g_term(a) + g_term(b));
        let e = 0.5 * (a.restitution + b.restitution);
        let ln_e = e.ln();
        let beta = ln_e / (ln_e * ln_e + std::f64::consts::PI.powi(2)).sqrt();
        Self { e_star, g_star, beta, friction: 0.5 * (a.friction + b.friction) }
    }
}

/// Geometry and kinematics of one contact, the input of the contact law.
struct ContactPoint {
    overlap: f64,
    normal: Vec3,
    r_eff: f64,
    m_eff: f64,
    /// v_i − v_j
    rel_velocity: Vec3,
    /// cr_i ω_i + cr_j ω_j (lever arms a − δ/2)
    spin: Vec3,
}

/// Contact law: returns (Fn n + Ft) on i, updating the shear history `s` in place.
fn contact_force(c: &ContactPoint, m: &PairMaterial, s: &mut Vec3, dt: f64) -> Vec3 {
    const SQRT_5_6: f64 = 0.912_870_929_175_276_8;
    let sq = (c.r_eff * c.overlap).sqrt();
    let kn = 4.0 / 3.0 * m.e_star * sq;
    let kt = 8.0 * m.g_star * sq;
    let gamma_n = -2.0 * SQRT_5_6 * m.beta * (2.0 * m.e_star * sq * c.m_eff).sqrt();
    let gamma_t = -2.0 * SQRT_5_6 * m.beta * (kt * c.m_eff).sqrt();

    let vn = c.rel_velocity.dot(&c.normal);
    let fn_mag = kn * c.overlap - gamma_n * vn;

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
    fn_mag * c.normal + ft
}

/// Particle–particle and particle–wall contacts.
pub struct Contact {
    /// Pair constants indexed `[species_i * n_species + species_j]`.
    materials: Vec<PairMaterial>,
    n_species: usize,
    walls: bool,
}

impl Contact {
    pub fn new(species: &[Species], walls: bool) -> Self {
        let n = species.len();
        let materials = (0..n * n).map(|k| PairMaterial::new(&species[k / n], &species[k % n])).collect();
        Self { materials, n_species: n, walls }
    }

    fn material(&self, si: u16, sj: u16) -> &PairMaterial {
        &self.materials[si as usize * self.n_species + sj as usize]
    }

    fn apply_walls(&self, domain: &Domain, state: &mut State, dt: f64, diag: &mut ContactDiagnostics) {
        let p = &mut state.particles;
        let mut next = HashMap::with_capacity(state.contacts.walls.len());
        for i in 0..p.len() {
            let a = p.radius[i];
            for (face, k, upper) in domain.walls() {
                let gap = if upper { domain.hi[k] - p.position[i][k] } else { p.position[i][k] - domain.lo[k] };
                let overlap = a - gap;
                if overlap <= 0.0 {
                    continue;
                }
                let mut normal = Vec3::zeros();
                normal[k] = if upper { -1.0 } else { 1.0 };
                let cr = a - 0.5 * overlap;
                let point = ContactPoint {
                    overlap,
                    normal,
                    r_eff: a,
                    m_eff: p.mass[i],
                    rel_velocity: p.velocity[i],
                    spin: cr * p.angular_velocity[i],
                };
                let mut s = state.contacts.walls.get(&(i as u32, face)).copied().unwrap_or_else(Vec3::zeros);
                let f = contact_force(&point, self.material(p.species[i], p.species[i]), &mut s, dt);
                next.insert((i as u32, face), s);
                let ft = f - f.dot(&normal) * normal;
                p.force[i] += f;
                p.torque[i] += -cr * normal.cross(&ft);
                let ratio = overlap / (2.0 * a);
                if ratio > diag.max_overlap_ratio {
                    *diag = ContactDiagnostics { max_overlap_ratio: ratio, max_overlap_pair: (i as u32, None) };
                }
            }
        }
        state.contacts.walls = next;
    }
}

impl ForceTerm for Contact {
    fn name(&self) -> &'static str {
        "contact"
    }
    fn needs_near_pairs(&self) -> bool {
        true
    }
    fn apply(&mut self, ctx: &ForceContext, state: &mut State) {
        let mut diag = ContactDiagnostics::default();
        let mut next = HashMap::with_capacity(state.contacts.pairs.len());
        let p = &mut state.particles;
        for pair in ctx.near_pairs {
            let (i, j) = (pair.i as usize, pair.j as usize);
            let overlap = p.radius[i] + p.radius[j] - pair.dist;
            if overlap <= 0.0 {
                continue;
            }
            let normal = pair.r / pair.dist;
            let (cr_i, cr_j) = (p.radius[i] - 0.5 * overlap, p.radius[j] - 0.5 * overlap);
            let point = ContactPoint {
                overlap,
                normal,
                r_eff: p.radius[i] * p.radius[j] / (p.radius[i] + p.radius[j]),
                m_eff: p.mass[i] * p.mass[j] / (p.mass[i] + p.mass[j]),
                rel_velocity: p.velocity[i] - p.velocity[j],
                spin: cr_i * p.angular_velocity[i] + cr_j * p.angular_velocity[j],
            };
            let key = (pair.i, pair.j);
            let mut s = state.contacts.pairs.get(&key).copied().unwrap_or_else(Vec3::zeros);
            let f = contact_force(&point, self.material(p.species[i], p.species[j]), &mut s, ctx.dt);
            next.insert(key, s);
            let ft = f - f.dot(&normal) * normal;
            let n_x_ft = normal.cross(&ft);
            p.force[i] += f;
            p.force[j] -= f;
            p.torque[i] -= cr_i * n_x_ft;
            p.torque[j] -= cr_j * n_x_ft;
            let ratio = overlap / (2.0 * p.radius[i].min(p.radius[j]));
            if ratio > diag.max_overlap_ratio {
                diag = ContactDiagnostics { max_overlap_ratio: ratio, max_overlap_pair: (pair.i, Some(pair.j)) };
            }
        }
        state.contacts.pairs = next;
        if self.walls {
            self.apply_walls(ctx.domain, state, ctx.dt, &mut diag);
        }
        state.diagnostics = diag;
    }
}
