//! Particle–particle and particle–wall contacts: the force term. The law is composed of
//! sub-models ([`law`]), the wall geometry is [`walls`]; with the defaults (Hertz, restitution
//! damping, Mindlin with history, Coulomb) it is LIGGGHTS' `model hertz tangential history`
//! (normal_model_hertz.h, tangential_model_history.h).

pub mod law;
mod walls;

use super::{Context, ForceTerm, Forces};
use crate::core::neighbours::{Pair, PairRange};
use crate::core::parallel;
use crate::core::state::{ContactDiagnostics, Particles, Species, Vec3, WallFace};
pub use law::PairMaterial;
use law::{ContactLaw, ContactPoint};
use walls::{WallScan, WallTouch};

/// What one contact gives: the force on i (j receives −force), the torques on i and j, the
/// updated spring and the overlap as a fraction of the smaller diameter.
struct ContactOutcome {
    force: Vec3,
    torque_i: Vec3,
    torque_j: Vec3,
    shear: Vec3,
    overlap_ratio: f64,
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
    law: ContactLaw,
    walls: bool,
    /// The near-pair search: the largest contact distance (times 1 + a touch tolerance).
    near: PairRange,
    touching: Vec<(u32, Vec3)>,
    wall_scan: WallScan,
    wall_found: Vec<WallTouch>,
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
    pub fn new(species: &[Species], law: ContactLaw, walls: bool, near: PairRange) -> Self {
        let n = species.len();
        let materials = (0..n * n).map(|k| PairMaterial::new(&species[k / n], &species[k % n])).collect();
        Self {
            materials,
            n_species: n,
            law,
            walls,
            near,
            touching: vec![],
            wall_scan: WallScan::default(),
            wall_found: vec![],
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
        let force = self.law.force(&point, self.material(p.species[i], p.species[j]), &mut shear, dt);
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
        let normal = touch.normal();
        let cr = a - 0.5 * touch.overlap;
        let point = ContactPoint {
            overlap: touch.overlap,
            normal,
            r_eff: a,
            m_eff: p.mass[i],
            rel_velocity: p.velocity[i],
            spin: cr * p.angular_velocity[i],
        };
        let force = self.law.force(&point, self.material(p.species[i], p.species[i]), &mut shear, dt);
        let ft = force - force.dot(&normal) * normal;
        ContactOutcome {
            force,
            torque_i: -cr * normal.cross(&ft),
            torque_j: Vec3::zeros(),
            shear,
            overlap_ratio: touch.overlap / (2.0 * a),
        }
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
                *diag =
                    ContactDiagnostics { max_overlap_ratio: o.overlap_ratio, max_overlap_pair: (pair.i, Some(pair.j)) };
            }
        }
        out.contacts.pairs = next;
        self.outcomes = outcomes;
    }

    fn apply_walls(&mut self, ctx: &Context, p: &Particles, out: &mut Forces, diag: &mut ContactDiagnostics) {
        let history = std::mem::take(&mut out.contacts.walls);
        let mut found = std::mem::take(&mut self.wall_found);
        self.wall_scan.find(p, ctx.domain, ctx.neighbours.rebuilt(self.near), &mut found);
        let mut cursor = 0;
        self.wall_touching.clear();
        self.wall_touching.extend(found.iter().map(|&t| (t, spring(&history, &mut cursor, (t.i, t.face)))));
        self.wall_found = found;
        let mut outcomes = std::mem::take(&mut self.outcomes);
        let touching = &self.wall_touching;
        parallel::map_ordered(touching.len(), &mut outcomes, |c| {
            self.wall_contact(p, &touching[c].0, touching[c].1, ctx.dt)
        });
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
        let (mut neighbours, mut contact) =
            (Neighbours::new([near]), Contact::new(std::slice::from_ref(&species), ContactLaw::default(), true, near));
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
            Contact::new(std::slice::from_ref(&species), ContactLaw::default(), true, near).apply(&ctx, p, &mut out);
            let (p, mut out) = Forces::of(&mut state, ForceGroup::All);
            contact.apply(&ctx, p, &mut out);
            let (kept, all) = (&state.contacts.walls, &every_particle.contacts.walls);
            assert!(
                kept == all,
                "step {step}: {} wall contacts among the candidates, {} testing every particle",
                kept.len(),
                all.len()
            );
            assert!(state.fields.force == every_particle.fields.force, "step {step}: forces differ");
            found += state.contacts.walls.len();
        }
        assert!(rebuilds > 20, "{rebuilds} rebuilds");
        assert!(found > 1000, "{found} wall contacts over the run");
    }
}
