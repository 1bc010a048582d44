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

use super::{Context, ForceTerm, Forces};
use crate::core::neighbours::{Pair, PairRange};
use crate::core::parallel::{self, Pieces};
use crate::core::state::{ContactDiagnostics, Particles, Species, Vec3, WallFace};

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

/// What one contact gives: the force on i (j receives −force), the torques on i and j, the
/// updated spring and the overlap as a fraction of the smaller diameter.
struct ContactOutcome {
    force: Vec3,
    torque_i: Vec3,
    torque_j: Vec3,
    shear: Vec3,
    overlap_ratio: f64,
}

/// A particle touching a wall face: (particle, face, axis, upper face?, overlap).
#[derive(Clone, Copy, Default)]
struct WallTouch {
    i: u32,
    face: WallFace,
    axis: usize,
    upper: bool,
    overlap: f64,
}

/// Particle–particle and particle–wall contacts.
///
/// Each evaluation runs in three passes: find the touching pairs and wall contacts and their
/// springs (a merge with the sorted history), compute each contact (in parallel for many
/// contacts), then add the results in contact order — the same bits for any thread count.
pub struct Contact {
    /// Pair constants indexed `[species_i * n_species + species_j]`.
    materials: Vec<PairMaterial>,
    n_species: usize,
    walls: bool,
    /// The near-pair search: the largest contact distance (times 1 + a touch tolerance).
    near: PairRange,
    touching: Vec<(u32, Vec3)>,
    /// Particles that may touch a wall before the near list's next rebuild (`None`: not known
    /// yet, test every particle).
    wall_candidates: Option<Vec<u32>>,
    wall_found: Vec<WallTouch>,
    /// Buffers of the parallel wall scans.
    wall_candidate_pieces: Pieces<u32>,
    wall_found_pieces: Pieces<WallTouch>,
    wall_touching: Vec<(WallTouch, Vec3)>,
    outcomes: Vec<ContactOutcome>,
    spare_pairs: Vec<((u32, u32), Vec3)>,
    spare_walls: Vec<((u32, WallFace), Vec3)>,
}

/// The spring stored under `key` in the sorted `history`, advancing the merge `cursor`.
fn spring<K: Ord + Copy>(history: &[(K, Vec3)], cursor: &mut usize, key: K) -> Vec3 {
    while *cursor < history.len() && history[*cursor].0 < key {
        *cursor += 1;
    }
    match history.get(*cursor) {
        Some(&(k, s)) if k == key => s,
        _ => Vec3::zeros(),
    }
}

impl Contact {
    pub fn new(species: &[Species], walls: bool, near: PairRange) -> Self {
        let n = species.len();
        let materials = (0..n * n).map(|k| PairMaterial::new(&species[k / n], &species[k % n])).collect();
        Self {
            materials,
            n_species: n,
            walls,
            near,
            touching: vec![],
            wall_candidates: None,
            wall_found: vec![],
            wall_candidate_pieces: Pieces::default(),
            wall_found_pieces: Pieces::default(),
            wall_touching: vec![],
            outcomes: vec![],
            spare_pairs: vec![],
            spare_walls: vec![],
        }
    }

    fn material(&self, si: u16, sj: u16) -> &PairMaterial {
        &self.materials[si as usize * self.n_species + sj as usize]
    }

    fn pair_contact(&self, p: &Particles, pair: &Pair, mut shear: Vec3, dt: f64) -> ContactOutcome {
        let (i, j) = (pair.i as usize, pair.j as usize);
        let overlap = p.radius[i] + p.radius[j] - pair.dist;
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
        let force = contact_force(&point, self.material(p.species[i], p.species[j]), &mut shear, dt);
        let n_x_ft = normal.cross(&(force - force.dot(&normal) * normal));
        ContactOutcome {
            force,
            torque_i: -cr_i * n_x_ft,
            torque_j: -cr_j * n_x_ft,
            shear,
            overlap_ratio: overlap / (2.0 * p.radius[i].min(p.radius[j])),
        }
    }

    fn wall_contact(&self, p: &Particles, touch: &WallTouch, mut shear: Vec3, dt: f64) -> ContactOutcome {
        let i = touch.i as usize;
        let a = p.radius[i];
        let mut normal = Vec3::zeros();
        normal[touch.axis] = if touch.upper { -1.0 } else { 1.0 };
        let cr = a - 0.5 * touch.overlap;
        let point = ContactPoint {
            overlap: touch.overlap,
            normal,
            r_eff: a,
            m_eff: p.mass[i],
            rel_velocity: p.velocity[i],
            spin: cr * p.angular_velocity[i],
        };
        let force = contact_force(&point, self.material(p.species[i], p.species[i]), &mut shear, dt);
        let ft = force - force.dot(&normal) * normal;
        ContactOutcome { force, torque_i: -cr * normal.cross(&ft), torque_j: Vec3::zeros(), shear, overlap_ratio: touch.overlap / (2.0 * a) }
    }

    fn apply_pairs(&mut self, ctx: &Context, p: &Particles, out: &mut Forces, diag: &mut ContactDiagnostics) {
        let history = std::mem::take(&mut out.contacts.pairs);
        let near_pairs = ctx.neighbours.pairs(self.near);
        let mut cursor = 0;
        self.touching.clear();
        for (k, pair) in near_pairs.iter().enumerate() {
            if pair.dist < p.radius[pair.i as usize] + p.radius[pair.j as usize] {
                self.touching.push((k as u32, spring(&history, &mut cursor, (pair.i, pair.j))));
            }
        }
        let mut outcomes = std::mem::take(&mut self.outcomes);
        let touching = &self.touching;
        parallel::map_ordered(touching.len(), &mut outcomes, |c| {
            let (k, s) = touching[c];
            self.pair_contact(p, &near_pairs[k as usize], s, ctx.dt)
        });
        let mut next = std::mem::replace(&mut self.spare_pairs, history);
        next.clear();
        for (&(k, _), o) in self.touching.iter().zip(&outcomes) {
            let pair = &near_pairs[k as usize];
            let (i, j) = (pair.i as usize, pair.j as usize);
            out.force[i] += o.force;
            out.force[j] -= o.force;
            out.torque[i] += o.torque_i;
            out.torque[j] += o.torque_j;
            next.push(((pair.i, pair.j), o.shear));
            if o.overlap_ratio > diag.max_overlap_ratio {
                *diag = ContactDiagnostics { max_overlap_ratio: o.overlap_ratio, max_overlap_pair: (pair.i, Some(pair.j)) };
            }
        }
        out.contacts.pairs = next;
        self.outcomes = outcomes;
    }

    fn apply_walls(&mut self, ctx: &Context, p: &Particles, out: &mut Forces, diag: &mut ContactDiagnostics) {
        let domain = ctx.domain;
        // Walls on periodic axes are infinitely far away.
        let lo = Vec3::from_fn(|k, _| if domain.periodic[k] { f64::NEG_INFINITY } else { domain.lo[k] });
        let hi = Vec3::from_fn(|k, _| if domain.periodic[k] { f64::INFINITY } else { domain.hi[k] });
        let near = |i: usize, margin: f64| {
            let (a, x) = (p.radius[i] + margin, p.position[i]);
            (x.x - lo.x < a) | (x.y - lo.y < a) | (x.z - lo.z < a) | (hi.x - x.x < a) | (hi.y - x.y < a) | (hi.z - x.z < a)
        };
        // After a rebuild of the near list no particle moves more than skin/2 before the next
        // one: only particles within a radius plus half the skin of a wall can touch it until then.
        if let Some(skin) = ctx.neighbours.rebuilt(self.near) {
            let mut candidates = self.wall_candidates.take().unwrap_or_default();
            parallel::collect_ordered(p.len(), &mut candidates, &mut self.wall_candidate_pieces, |i, out| {
                if near(i, 0.5 * skin) {
                    out.push(i as u32);
                }
            });
            self.wall_candidates = Some(candidates);
        }
        let history = std::mem::take(&mut out.contacts.walls);
        let mut found = std::mem::take(&mut self.wall_found);
        let touches = |i: usize, out: &mut Vec<WallTouch>| {
            if !near(i, 0.0) {
                return;
            }
            let (a, x) = (p.radius[i], p.position[i]);
            for axis in 0..3 {
                for (upper, gap) in [(false, x[axis] - lo[axis]), (true, hi[axis] - x[axis])] {
                    if gap < a {
                        let face = (2 * axis + upper as usize) as WallFace;
                        out.push(WallTouch { i: i as u32, face, axis, upper, overlap: a - gap });
                    }
                }
            }
        };
        match &self.wall_candidates {
            Some(candidates) => parallel::collect_ordered(candidates.len(), &mut found, &mut self.wall_found_pieces, |k, out| touches(candidates[k] as usize, out)),
            None => parallel::collect_ordered(p.len(), &mut found, &mut self.wall_found_pieces, touches),
        }
        let mut cursor = 0;
        self.wall_touching.clear();
        self.wall_touching.extend(found.iter().map(|&t| (t, spring(&history, &mut cursor, (t.i, t.face)))));
        self.wall_found = found;
        let mut outcomes = std::mem::take(&mut self.outcomes);
        let touching = &self.wall_touching;
        parallel::map_ordered(touching.len(), &mut outcomes, |c| self.wall_contact(p, &touching[c].0, touching[c].1, ctx.dt));
        let mut next = std::mem::replace(&mut self.spare_walls, history);
        next.clear();
        for ((t, _), o) in self.wall_touching.iter().zip(&outcomes) {
            let i = t.i as usize;
            out.force[i] += o.force;
            out.torque[i] += o.torque_i;
            next.push(((t.i, t.face), o.shear));
            if o.overlap_ratio > diag.max_overlap_ratio {
                *diag = ContactDiagnostics { max_overlap_ratio: o.overlap_ratio, max_overlap_pair: (t.i, None) };
            }
        }
        out.contacts.walls = next;
        self.outcomes = outcomes;
    }
}

impl ForceTerm for Contact {
    fn name(&self) -> &'static str {
        "contact"
    }
    fn pairs(&self) -> Option<PairRange> {
        Some(self.near)
    }
    fn apply(&mut self, ctx: &Context, p: &Particles, out: &mut Forces) {
        let mut diag = ContactDiagnostics::default();
        self.apply_pairs(ctx, p, out, &mut diag);
        if self.walls {
            self.apply_walls(ctx, p, out, &mut diag);
        }
        *out.diagnostics = diag;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::domain::Domain;
    use crate::core::forces::ForceGroup;
    use crate::core::neighbours::Neighbours;
    use crate::core::state::State;

    /// Particles drifting in a walled box, in and out of the walls' reach: the wall contacts
    /// found among the candidates kept between rebuilds of the near list are, spring for spring,
    /// those found by testing every particle.
    #[test]
    fn wall_candidates_miss_no_wall_contact() {
        let a = 5e-6;
        let species = crate::core::state::test_sphere(a);
        let edge = 100e-6;
        let domain = Domain { lo: Vec3::zeros(), hi: Vec3::repeat(edge), periodic: [false; 3] };
        let value = |k: usize| (k as f64 * 0.618_033_988_75).fract();
        let mut state = State::default();
        // Each particle moves 0.02 a per step in its own direction, so the near list (skin 0.4 a,
        // rebuilt when a particle has moved 0.2 a) is rebuilt about every ten steps.
        for i in 0..300 {
            let x = Vec3::from_fn(|c, _| 0.5 * a + (edge - a) * value(3 * i + c));
            let v = Vec3::from_fn(|c, _| value(1000 + 3 * i + c) - 0.5).normalize() * 0.02 * a;
            state.particles.push(0, &species, x, v);
        }
        let (range, skin, dt) = (2.0 * a, 0.4 * a, 1e-8);
        let near = PairRange::Within { range, skin };
        let (mut neighbours, mut contact) = (Neighbours::new([near]), Contact::new(std::slice::from_ref(&species), true, near));
        let (mut found, mut rebuilds) = (0, 0);
        state.fields.fit(state.particles.len());
        for step in 0..400 {
            let p = &mut state.particles;
            for (x, v) in p.position.iter_mut().zip(&mut p.velocity) {
                *x += *v;
                // Back into the box once a particle is half a radius into a wall.
                for c in 0..3 {
                    if (x[c] < 0.5 * a && v[c] < 0.0) || (x[c] > edge - 0.5 * a && v[c] > 0.0) {
                        v[c] = -v[c];
                    }
                }
            }
            neighbours.update(&p.position, &domain, |_| true);
            rebuilds += neighbours.rebuilt(near).is_some() as usize;
            let ctx = Context { domain: &domain, neighbours: &neighbours, dt };
            let mut every_particle = state.clone();
            let (p, mut out) = Forces::of(&mut every_particle, ForceGroup::All);
            Contact::new(std::slice::from_ref(&species), true, near).apply(&ctx, p, &mut out);
            let (p, mut out) = Forces::of(&mut state, ForceGroup::All);
            contact.apply(&ctx, p, &mut out);
            let (kept, all) = (&state.contacts.walls, &every_particle.contacts.walls);
            assert!(kept == all, "step {step}: {} wall contacts among the candidates, {} testing every particle", kept.len(), all.len());
            assert!(state.fields.force == every_particle.fields.force, "step {step}: forces differ");
            found += state.contacts.walls.len();
        }
        assert!(rebuilds > 20, "{rebuilds} rebuilds");
        assert!(found > 1000, "{found} wall contacts over the run");
    }
}
