//! Particle–particle and particle–wall contacts: the force term. The law is composed of
//! sub-models ([`law`]), the wall geometry is [`walls`]; with the defaults (Hertz, restitution
//! damping, Mindlin with history, Coulomb) it is LIGGGHTS' `model hertz tangential history`
//! (normal_model_hertz.h, tangential_model_history.h).

pub mod law;
mod spec;
mod walls;

use super::{Context, ForceTerm, Forces, Renumbering};
use crate::core::flow::Vessel;
use crate::core::neighbours::{Pair, PairRange};
use crate::core::parallel;
use crate::core::parallel::Pieced;
use crate::core::state::{
    ContactDiagnostics, PairSpring, PairSprings, Particles, Sizes, Species, Vec3, WallFace, WallSpring,
};
pub use law::PairMaterial;
use law::{ContactLaw, Lanes, LANES};
pub use spec::{ContactSpec, NormalSpec, TangentialSpec};
use std::sync::Mutex;
pub use walls::VESSEL_FACE;
use walls::{WallScan, WallTouch};

/// What one contact gives: the force on i (j receives −force), the torques on i and j, the
/// updated spring, the overlap and the smaller diameter (the wall's: the particle's).
#[derive(Clone, Copy, Default)]
struct ContactOutcome {
    force: Vec3,
    torque_i: Vec3,
    torque_j: Vec3,
    shear: Vec3,
    overlap: f64,
    diameter: f64,
}

impl ContactOutcome {
    /// Lane `l` of computed `lanes`.
    #[inline(always)]
    fn of(lanes: &Lanes, l: usize, diameter: f64) -> Self {
        ContactOutcome {
            force: lanes.force(l),
            torque_i: lanes.torque_i(l),
            torque_j: lanes.torque_j(l),
            shear: lanes.shear(l),
            overlap: lanes.overlap[l],
            diameter,
        }
    }

    /// The overlap as a fraction of the smaller diameter, if above `max`: the division is taken
    /// only where the ratio may exceed it (the margin 1e-12 keeps the test exact).
    #[inline(always)]
    fn overlap_ratio_above(&self, max: f64) -> Option<f64> {
        if self.overlap < max * self.diameter * (1.0 - 1e-12) {
            return None;
        }
        Some(self.overlap / self.diameter).filter(|&ratio| ratio > max)
    }
}

/// R* = a_i a_j/(a_i + a_j) and m* = m_i m_j/(m_i + m_j) of the last pair, reused while the
/// radii and masses repeat, where the particles have several sizes: the same operands give the
/// same bits.
#[derive(Default)]
struct ReducedCache {
    key: [f64; 4],
    value: (f64, f64),
}

impl ReducedCache {
    #[inline(always)]
    fn get(&mut self, (ai, aj, mi, mj): (f64, f64, f64, f64)) -> (f64, f64) {
        if self.key != [ai, aj, mi, mj] {
            self.key = [ai, aj, mi, mj];
            self.value = (ai * aj / (ai + aj), mi * mj / (mi + mj));
        }
        self.value
    }
}

/// R* = a a/(a + a) and m* = m m/(m + m) if every particle has radius a and mass m: the bits
/// [`ReducedCache`] gives every pair then.
fn alike(p: &Particles) -> Option<(f64, f64)> {
    match p.sizes {
        Sizes::One { radius: a, mass: m } => Some((a * a / (a + a), m * m / (m + m))),
        Sizes::NoParticles | Sizes::Several => None,
    }
}

/// What a share of the pair pass leaves: its part of the next history, its largest overlap.
type ShareOut = (Vec<PairSpring>, ContactDiagnostics);

/// What a share of the wall pass leaves: its part of the next wall history, its largest overlap.
type WallShareOut = (Vec<WallSpring>, ContactDiagnostics);

/// Particle–particle and particle–wall contacts.
///
/// Pairs: one pass per particle share over the listed near pairs in (i, j) order finds the
/// touching ones (the list, filtered from the Verlet candidates once per evaluation, is shared
/// with the shielding where the drag has it) and their springs (a merge with the sorted
/// history), computes them [`LANES`] at a time and adds them in order (see
/// [`Contact::share_pass`]). Walls: found in particle order, then computed and added in the same
/// particle shares ([`Contact::apply_walls`]), their springs merged the same way. The same bits
/// for any thread count.
pub struct Contact {
    /// Pair constants indexed `[species_i * n_species + species_j]`.
    materials: Vec<PairMaterial>,
    n_species: usize,
    law: ContactLaw,
    /// Contacts between particles (false: the particles touch the walls only).
    particles: bool,
    /// Contacts with the box's wall faces, and with the vessel's surface if there is one.
    walls: bool,
    vessel: Option<Vessel>,
    /// The near-pair search: the largest contact distance (times 1 + a touch tolerance).
    near: PairRange,
    wall_scan: WallScan,
    wall_found: Vec<WallTouch>,
    /// Per particle share of the wall pass: its piece of the next wall history and largest
    /// overlap.
    wall_shares: Vec<Mutex<WallShareOut>>,
    /// Per particle share of the pair pass: its piece of the next history and largest overlap.
    shares: Vec<Mutex<ShareOut>>,
    /// The pieces of the history before last, reused for the next one.
    spare_pairs: Vec<Vec<PairSpring>>,
}

/// A merge cursor over springs sorted by key, held in consecutive pieces (each sorted, every key
/// of a piece below those of the pieces after it): looked up with ascending keys, it finds each
/// spring by walking forward, never searching.
struct Springs<'a, K> {
    pieces: &'a [Vec<(K, Vec3)>],
    piece: usize,
    at: usize,
}

impl<'a, K: Ord + Copy> Springs<'a, K> {
    /// Positioned at the first spring whose key is not below `from`.
    fn from(pieces: &'a [Vec<(K, Vec3)>], from: K) -> Self {
        let piece = pieces.iter().position(|p| p.last().is_some_and(|last| last.0 >= from)).unwrap_or(pieces.len());
        let at = pieces.get(piece).map_or(0, |p| p.partition_point(|s| s.0 < from));
        Self { pieces, piece, at }
    }

    /// The spring stored under `key` (zero if none), advancing past the keys below it.
    #[inline(always)]
    fn get(&mut self, key: K) -> Vec3 {
        while let Some(p) = self.pieces.get(self.piece) {
            while self.at < p.len() && p[self.at].0 < key {
                self.at += 1;
            }
            if let Some(&(k, s)) = p.get(self.at) {
                return if k == key { s } else { Vec3::zeros() };
            }
            (self.piece, self.at) = (self.piece + 1, 0);
        }
        Vec3::zeros()
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
            particles: true,
            walls,
            vessel: None,
            near,
            wall_scan: WallScan::default(),
            wall_found: vec![],
            wall_shares: vec![],
            shares: vec![],
            spare_pairs: vec![],
        }
    }

    /// The same contacts, and the vessel's surface a wall too (with `walls`).
    pub fn with_vessel(self, vessel: Option<Vessel>) -> Self {
        Self { vessel, ..self }
    }

    /// The same contacts without those between particles: non-interacting particles that
    /// touch the walls only.
    pub fn walls_only(self) -> Self {
        Self { particles: false, ..self }
    }

    /// The pair constants of every pair, with one species.
    fn shared_material(&self) -> Option<&PairMaterial> {
        (self.n_species == 1).then(|| &self.materials[0])
    }

    /// Lanes for a batch; with one species, its pair constants already in every lane, and
    /// `reduced` R* and m*, if given, too.
    fn fresh_lanes(&self, reduced: Option<(f64, f64)>) -> Lanes {
        let mut lanes = Lanes::default();
        let material = self.shared_material();
        for l in 0..LANES {
            if let Some(material) = material {
                lanes.set_material(l, material);
            }
            if let Some(reduced) = reduced {
                lanes.set_reduced(l, reduced);
            }
        }
        lanes
    }

    /// The pair constants for species `si` and `sj` to put in a lane of [`Self::fresh_lanes`]
    /// (`None`, with one species: already there).
    #[inline(always)]
    fn lane_material(&self, si: u16, sj: u16) -> Option<&PairMaterial> {
        match self.shared_material() {
            Some(_) => None,
            None => Some(&self.materials[si as usize * self.n_species + sj as usize]),
        }
    }

    /// Lane `l` for the touching `pair`, its R* and m* given as `reduced` (`None`: already in
    /// the lane); returns the smaller diameter.
    #[inline(always)]
    fn fill_pair(
        &self,
        lanes: &mut Lanes,
        l: usize,
        p: &Particles,
        pair: &Pair,
        reduced: Option<(f64, f64)>,
        shear: Vec3,
    ) -> f64 {
        let (i, j) = (pair.i as usize, pair.j as usize);
        let (ai, aj) = (p.radius[i], p.radius[j]);
        let overlap = ai + aj - pair.dist;
        let (cr_i, cr_j) = (ai - 0.5 * overlap, aj - 0.5 * overlap);
        let spin = cr_i * p.angular_velocity[i] + cr_j * p.angular_velocity[j];
        let material = self.lane_material(p.species[i], p.species[j]);
        let relative = p.velocity[i] - p.velocity[j];
        lanes.set(l, overlap, pair.r / pair.dist, reduced, relative, spin, (cr_i, cr_j), material, shear);
        2.0 * ai.min(aj)
    }

    /// Lane `l` for the wall contact `touch` (R* = a, m* = m, one lever arm); returns the diameter.
    #[inline(always)]
    fn fill_wall(&self, lanes: &mut Lanes, l: usize, p: &Particles, touch: &WallTouch, shear: Vec3) -> f64 {
        let i = touch.i as usize;
        let a = p.radius[i];
        let cr = a - 0.5 * touch.overlap;
        let material = self.lane_material(p.species[i], p.species[i]);
        let spin = cr * p.angular_velocity[i];
        lanes.set(
            l,
            touch.overlap,
            touch.normal,
            Some((a, p.mass[i])),
            p.velocity[i],
            spin,
            (cr, 0.0),
            material,
            shear,
        );
        2.0 * a
    }

    /// The wall contacts `touches` (in particle then face order), their springs merged from
    /// `springs`, computed [`LANES`] at a time; `emit(touch, outcome)` receives each in order.
    fn walls_in_lanes(
        &self,
        p: &Particles,
        touches: &[WallTouch],
        mut springs: Springs<(u32, WallFace)>,
        dt: f64,
        mut emit: impl FnMut(&WallTouch, &ContactOutcome),
    ) {
        let mut lanes = self.fresh_lanes(None);
        for batch in touches.chunks(LANES) {
            let mut diameters = [0.0; LANES];
            for (l, t) in batch.iter().enumerate() {
                diameters[l] = self.fill_wall(&mut lanes, l, p, t, springs.get((t.i, t.face)));
            }
            self.law.apply(&mut lanes, dt);
            for (l, t) in batch.iter().enumerate() {
                emit(t, &ContactOutcome::of(&lanes, l, diameters[l]));
            }
        }
    }

    /// The touching pairs among `pairs`, in order, their springs merged from `history`
    /// (positioned at or before the first), computed [`LANES`] at a time; `emit(batch, lanes)`
    /// receives each batch of pairs (with their smaller diameters) and its computed lanes, in
    /// order.
    fn in_lanes<'s>(
        &self,
        p: &Particles,
        pairs: impl Iterator<Item = &'s Pair>,
        mut history: Springs<(u32, u32)>,
        dt: f64,
        mut emit: impl FnMut(&[((u32, u32), f64)], &Lanes),
    ) {
        // With one size, R* and m* are set once in the lanes instead of per contact.
        let alike = alike(p);
        let (mut lanes, mut batch) = (self.fresh_lanes(alike), [((0, 0), 0.0); LANES]);
        let (mut cache, mut used) = (ReducedCache::default(), 0);
        let mut flush = |lanes: &mut Lanes, batch: &[((u32, u32), f64)]| {
            self.law.apply(lanes, dt);
            emit(batch, lanes);
        };
        let touching = |pair: &&Pair| pair.dist < p.radius[pair.i as usize] + p.radius[pair.j as usize];
        for pair in pairs.filter(touching) {
            let (i, j) = (pair.i as usize, pair.j as usize);
            let s = history.get((pair.i, pair.j));
            let reduced = match alike {
                Some(_) => None,
                None => Some(cache.get((p.radius[i], p.radius[j], p.mass[i], p.mass[j]))),
            };
            batch[used] = ((pair.i, pair.j), self.fill_pair(&mut lanes, used, p, pair, reduced, s));
            used += 1;
            if used == LANES {
                flush(&mut lanes, &batch);
                used = 0;
            }
        }
        flush(&mut lanes, &batch[..used]);
    }

    /// Pair contacts on the particles `lo..lo + force.len()` (a share; `force` and `torque` are
    /// its slices): first the pairs (i, j) of earlier rows (from `first_row`, the first whose
    /// pairs reach the share) with j in the share, in order (they come first in each j's serial
    /// sum; the share before computes them too, for its own i), then the share's own rows, whose
    /// j beyond the share are left to the shares after. Each particle's force and torque are so
    /// summed in the serial order, on any split.
    ///
    /// `crossing`, where given, holds those earlier pairs with j in the share (the near range's
    /// [`CrossingPairs`]): read instead of scanning the rows before the share.
    #[allow(clippy::too_many_arguments)]
    fn share_pass<'s>(
        &self,
        near: Pieced<'s, Pair>,
        crossing: Option<impl Iterator<Item = &'s Pair>>,
        p: &Particles,
        dt: f64,
        history: &PairSprings,
        (first_row, lo): (usize, usize),
        (force, torque): (&mut [Vec3], &mut [Vec3]),
        (next, diag): &mut ShareOut,
    ) {
        let hi = lo + force.len();
        let row_below = |bound: usize| near.partition_point(|q| (q.i as usize) < bound);
        let (rows, rest) = (row_below(lo), row_below(hi));
        let history_from = |row: usize| Springs::from(history.pieces(), (row as u32, 0));
        let in_share = |q: &&Pair| (lo..hi).contains(&(q.j as usize));
        let add_to_j = |batch: &[((u32, u32), f64)], lanes: &Lanes| {
            for (l, &((_, j), _)) in batch.iter().enumerate() {
                let j = j as usize - lo;
                force[j] -= lanes.force(l);
                torque[j] += lanes.torque_j(l);
            }
        };
        let springs = history_from(first_row);
        match crossing {
            Some(pairs) => self.in_lanes(p, pairs.filter(in_share), springs, dt, add_to_j),
            None => self.in_lanes(p, near.range(row_below(first_row), rows).filter(in_share), springs, dt, add_to_j),
        }
        next.clear();
        *diag = ContactDiagnostics::default();
        let mut adder = RowAdder::new(lo, diag, next);
        let add = |batch: &[((u32, u32), f64)], lanes: &Lanes| adder.add(force, torque, batch, lanes);
        self.in_lanes(p, near.range(rows, rest), history_from(lo), dt, add);
        adder.finish(force, torque);
    }

    fn apply_pairs(&mut self, ctx: &Context, p: &Particles, out: &mut Forces, diag: &mut ContactDiagnostics) {
        let history = std::mem::take(&mut out.history.pairs);
        let (shares, size) = parallel::split_of(out.force.len());
        let mut slots = std::mem::take(&mut self.shares);
        slots.resize_with(shares.max(slots.len()), Default::default);
        let near = ctx.neighbours.range_pairs(self.near);
        let crossing = near.crossing.filter(|c| c.found_for(out.force.len()));
        parallel::for_each_share((&mut *out.force, &mut *out.torque), |lo, parts| {
            let mut slot = slots[lo / size].lock().expect("one share per slot");
            // Filled on this thread's stack, not in the slot: the slots sit side by side, and
            // writing a history's length at every contact into a cache line the other share also
            // writes is false sharing.
            let mut share = std::mem::take(&mut *slot);
            let rows = (near.first_row_reaching(lo), lo);
            let crossing = crossing.map(|c| c.reaching(lo, parts.0.len()));
            self.share_pass(near.pairs, crossing, p, ctx.dt, &history, rows, parts, &mut share);
            *slot = share;
        });
        // The shares' pieces in order, swapped for those of the history before last (the slots'
        // buffers for the next step); the first largest overlap, as the serial pass finds it.
        let mut pieces = std::mem::take(&mut self.spare_pairs);
        pieces.resize_with(shares, Vec::new);
        *diag = ContactDiagnostics::default();
        for (slot, piece) in slots[..shares].iter_mut().zip(&mut pieces) {
            let (fresh, share_diag) = slot.get_mut().expect("the shares are done");
            if share_diag.max_overlap_ratio > diag.max_overlap_ratio {
                *diag = *share_diag;
            }
            std::mem::swap(fresh, piece);
        }
        out.history.pairs = PairSprings::from_pieces(pieces);
        self.spare_pairs = history.into_pieces();
        self.shares = slots;
    }

    /// Wall contacts in the pair pass's particle shares, each share's added to its particles
    /// after all their pair contacts (as in the serial order), its springs and largest overlap
    /// then gathered in share order.
    fn apply_walls(&mut self, ctx: &Context, p: &Particles, out: &mut Forces, diag: &mut ContactDiagnostics) {
        let history = std::mem::take(&mut out.history.walls);
        let mut found = std::mem::take(&mut self.wall_found);
        self.wall_scan.find(p, ctx.domain, self.vessel.as_ref(), ctx.neighbours.rebuilt(self.near), &mut found);
        let (shares, size) = parallel::split_of(out.force.len());
        let mut slots = std::mem::take(&mut self.wall_shares);
        slots.resize_with(shares.max(slots.len()), Default::default);
        let (pair_diag, dt) = (*diag, ctx.dt);
        parallel::for_each_share((&mut *out.force, &mut *out.torque), |lo, (force, torque)| {
            let mut slot = slots[lo / size].lock().expect("one share per slot");
            let (mut next, mut share_diag) = (std::mem::take(&mut slot.0), pair_diag);
            next.clear();
            let in_share = |bound: usize| found.partition_point(|t| (t.i as usize) < bound);
            let touches = &found[in_share(lo)..in_share(lo + force.len())];
            let springs = Springs::from(std::slice::from_ref(&history), (lo as u32, 0));
            self.walls_in_lanes(p, touches, springs, dt, |t, o| {
                let i = t.i as usize - lo;
                force[i] += o.force;
                torque[i] += o.torque_i;
                next.push(((t.i, t.face), o.shear));
                if let Some(ratio) = o.overlap_ratio_above(share_diag.max_overlap_ratio) {
                    share_diag = ContactDiagnostics { max_overlap_ratio: ratio, max_overlap_pair: (t.i, None) };
                }
            });
            *slot = (next, share_diag);
        });
        // Each share started from the pairs' largest overlap: the first share above it and
        // above the shares before is the first largest, as the serial pass finds it.
        // The next history is the first share's piece with the others appended; that share's
        // slot keeps the spent history's buffer for the next step.
        let mut spent = history;
        spent.clear();
        let mut next = vec![];
        for (k, slot) in slots[..shares].iter_mut().enumerate() {
            let (piece, share_diag) = slot.get_mut().expect("the shares are done");
            match k {
                0 => next = std::mem::replace(piece, std::mem::take(&mut spent)),
                _ => next.extend_from_slice(piece),
            }
            if share_diag.max_overlap_ratio > diag.max_overlap_ratio {
                *diag = *share_diag;
            }
        }
        out.history.walls = next;
        self.wall_found = found;
        self.wall_shares = slots;
    }
}

/// Adds a share's pair contacts, taken in (i, j) order, to its particles' forces and torques
/// (slices from particle `lo`), its next history and diagnostics; a j beyond the share is left
/// to the shares after. Particle i's force and torque are summed over its row and stored once
/// (no store-to-load chain through memory from one contact to the next); nothing else touches
/// particle i during its row, so the sums are those of adding one contact at a time, bit for bit.
struct RowAdder<'a> {
    lo: usize,
    diag: &'a mut ContactDiagnostics,
    next: &'a mut Vec<PairSpring>,
    /// The row's particle (share index; `usize::MAX` before the first) and its force and
    /// torque so far.
    row: usize,
    force_i: Vec3,
    torque_i: Vec3,
}

impl<'a> RowAdder<'a> {
    fn new(lo: usize, diag: &'a mut ContactDiagnostics, next: &'a mut Vec<PairSpring>) -> Self {
        RowAdder { lo, diag, next, row: usize::MAX, force_i: Vec3::zeros(), torque_i: Vec3::zeros() }
    }

    /// Adds a computed batch. The row's particle and sums are held in locals over the batch
    /// (in registers, not read back from memory contact after contact).
    #[inline(always)]
    fn add(&mut self, force: &mut [Vec3], torque: &mut [Vec3], batch: &[((u32, u32), f64)], lanes: &Lanes) {
        let (mut row, mut force_i, mut torque_i) = (self.row, self.force_i, self.torque_i);
        for (l, &((pi, pj), diameter)) in batch.iter().enumerate() {
            let o = ContactOutcome::of(lanes, l, diameter);
            let i = pi as usize - self.lo;
            if i != row {
                if row != usize::MAX {
                    (force[row], torque[row]) = (force_i, torque_i);
                }
                (row, force_i, torque_i) = (i, force[i], torque[i]);
            }
            force_i += o.force;
            torque_i += o.torque_i;
            if let Some(j) = (pj as usize).checked_sub(self.lo).filter(|&j| j < force.len()) {
                force[j] -= o.force;
                torque[j] += o.torque_j;
            }
            self.next.push(((pi, pj), o.shear));
            if let Some(ratio) = o.overlap_ratio_above(self.diag.max_overlap_ratio) {
                *self.diag = ContactDiagnostics { max_overlap_ratio: ratio, max_overlap_pair: (pi, Some(pj)) };
            }
        }
        (self.row, self.force_i, self.torque_i) = (row, force_i, torque_i);
    }

    /// Stores the last row's sums (none if there was no row).
    fn finish(self, force: &mut [Vec3], torque: &mut [Vec3]) {
        if self.row != usize::MAX {
            (force[self.row], torque[self.row]) = (self.force_i, self.torque_i);
        }
    }
}

impl ForceTerm for Contact {
    fn name(&self) -> &'static str {
        "contact"
    }
    fn pairs(&self) -> Option<PairRange> {
        self.particles.then_some(self.near)
    }
    /// The tangential springs.
    fn keeps_history(&self) -> bool {
        true
    }
    fn apply(&mut self, ctx: &Context, p: &Particles, out: &mut Forces) {
        let mut diag = ContactDiagnostics::default();
        if self.particles {
            self.apply_pairs(ctx, p, out, &mut diag);
        }
        if self.walls {
            self.apply_walls(ctx, p, out, &mut diag);
        }
        *out.diagnostics = diag;
    }
    /// The contact history is the state's; the wall candidates are dropped (every particle is
    /// tested until the near list is rebuilt: the same contacts).
    fn renumber(&mut self, _r: &Renumbering) {
        self.wall_scan.forget();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::domain::Domain;
    use crate::core::forces::ForceGroup;
    use crate::core::neighbours::Neighbours;
    use crate::core::state::State;

    /// Springs split into pieces anywhere (empty pieces included) are found as in one sorted
    /// piece, from any starting key, by ascending lookups of present and absent keys.
    #[test]
    fn springs_in_pieces_are_found_as_in_one() {
        let all: Vec<PairSpring> = (0..40u32).map(|k| ((k / 4, 2 * k + 1), Vec3::repeat(k as f64 + 1.0))).collect();
        let keys: Vec<(u32, u32)> = (0..44u32).flat_map(|k| [(k / 4, 2 * k), (k / 4, 2 * k + 1)]).collect();
        let lookup = |pieces: &[Vec<PairSpring>], from: u32| {
            let mut springs = Springs::from(pieces, (from, 0));
            keys.iter().filter(|k| k.0 >= from).map(|&k| springs.get(k)).collect::<Vec<_>>()
        };
        for cuts in [vec![], vec![0, 0, 13], vec![5, 20, 20, 39], vec![40]] {
            let mut pieces = vec![];
            let mut start = 0;
            for &cut in cuts.iter().chain([&40]) {
                pieces.push(all[start..cut].to_vec());
                start = cut;
            }
            for from in [0, 3, 7, 12] {
                let found = lookup(&pieces, from);
                assert_eq!(found, lookup(std::slice::from_ref(&all), from), "cuts {cuts:?}, from row {from}");
                assert_eq!(
                    found.iter().filter(|s| **s != Vec3::zeros()).count(),
                    40usize.saturating_sub(4 * from as usize)
                );
            }
        }
    }

    /// Two species of different stiffness: each lane of a batch takes its own pair's constants
    /// and its own R* and m*. Pairs at rest overlapping by δ (A–A, A–B, B–B, B–A, in one batch
    /// with two wall contacts) push with Hertz's 4/3 E* √(R*δ) δ for their own E* and R* (the
    /// wall's: the particle's species with itself, R* = a), to round-off; with the species of
    /// one size (R* and m* set once for all lanes) and of two.
    #[test]
    fn each_lane_takes_its_own_pair_constants() {
        let a = 5e-6;
        for b in [a, 0.6 * a] {
            let soft = crate::core::state::test_sphere(a);
            let stiff = Species { youngs_modulus: 7e9, poisson_ratio: 0.2, radius: b, ..soft.clone() };
            let species = [soft, stiff];
            let radius = |s: u16| species[s as usize].radius;
            let domain = Domain { lo: Vec3::zeros(), hi: Vec3::repeat(200e-6), periodic: [false; 3] };
            let delta = 1e-8;
            let mut state = State::default();
            let kinds = [(0, 0), (0, 1), (1, 1), (1, 0)];
            for (k, &(si, sj)) in kinds.iter().enumerate() {
                let x = Vec3::new(30e-6 + 40e-6 * k as f64, 100e-6, 100e-6);
                let r = Vec3::new(0.0, radius(si) + radius(sj) - delta, 0.0);
                state.particles.push(si, &species[si as usize], x, Vec3::zeros());
                state.particles.push(sj, &species[sj as usize], x + r, Vec3::zeros());
            }
            // Two wall contacts on the floor, one of each species.
            for (k, si) in [0u16, 1].into_iter().enumerate() {
                let x = Vec3::new(40e-6 + 80e-6 * k as f64, 40e-6, radius(si) - delta);
                state.particles.push(si, &species[si as usize], x, Vec3::zeros());
            }
            state.fields.fit(state.particles.len());
            let near = PairRange::Within { range: 2.0 * a, skin: 0.2 * a };
            let mut contact = Contact::new(&species, ContactLaw::default(), true, near);
            let mut neighbours = Neighbours::new(contact.pairs());
            let p = &state.particles;
            neighbours.update(&p.position, &domain, |_| true, &mut crate::core::timers::PhaseTimers::default());
            let ctx = Context { domain: &domain, neighbours: &neighbours, dt: 1e-8, time: 0.0 };
            let (p, mut out) = Forces::of(&mut state, ForceGroup::All);
            contact.apply(&ctx, p, &mut out);
            assert_eq!(alike(&state.particles).is_some(), b == a, "one size: R* and m* set once");
            assert_eq!((state.history.pairs.len(), state.history.walls.len()), (4, 2));
            let hertz = |si: u16, sj: u16, r_eff: f64| {
                let e_star = PairMaterial::new(&species[si as usize], &species[sj as usize]).e_star;
                4.0 / 3.0 * e_star * (r_eff * delta).sqrt() * delta
            };
            let force = &state.fields.force;
            for (k, &(si, sj)) in kinds.iter().enumerate() {
                let r_eff = radius(si) * radius(sj) / (radius(si) + radius(sj));
                let (expected, got) = (hertz(si, sj, r_eff), force[2 * k + 1].y);
                assert!((got / expected - 1.0).abs() < 1e-9, "pair {si}-{sj}: {got:e} N, Hertz {expected:e} N");
                assert_eq!(force[2 * k].y, -got);
            }
            for (k, si) in [0u16, 1].into_iter().enumerate() {
                let (expected, got) = (hertz(si, si, radius(si)), force[8 + k].z);
                assert!((got / expected - 1.0).abs() < 1e-9, "wall, species {si}: {got:e} N, Hertz {expected:e} N");
            }
            let stiff_soft = hertz(1, 1, b) / hertz(0, 0, a);
            assert!(stiff_soft > 2.0, "the species differ: {stiff_soft}");
        }
    }

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
        let mut contact = Contact::new(std::slice::from_ref(&species), ContactLaw::default(), true, near);
        let mut neighbours = Neighbours::new(contact.pairs());
        let (mut found, mut rebuilds) = (0, 0);
        state.fields.fit(state.particles.len());
        for step in 0..400 {
            let p = &mut state.particles;
            for (x, v) in p.position.write().iter_mut().zip(&mut p.velocity) {
                *x += *v;
                // Back into the box once a particle is half a radius into a wall.
                for c in 0..3 {
                    if (x[c] < 0.5 * a && v[c] < 0.0) || (x[c] > edge - 0.5 * a && v[c] > 0.0) {
                        v[c] = -v[c];
                    }
                }
            }
            neighbours.update(&p.position, &domain, |_| true, &mut crate::core::timers::PhaseTimers::default());
            rebuilds += neighbours.rebuilt(near).is_some() as usize;
            let ctx = Context { domain: &domain, neighbours: &neighbours, dt, time: 0.0 };
            let mut every_particle = state.clone();
            let (p, mut out) = Forces::of(&mut every_particle, ForceGroup::All);
            Contact::new(std::slice::from_ref(&species), ContactLaw::default(), true, near).apply(&ctx, p, &mut out);
            let (p, mut out) = Forces::of(&mut state, ForceGroup::All);
            contact.apply(&ctx, p, &mut out);
            let (kept, all) = (&state.history.walls, &every_particle.history.walls);
            assert!(
                kept == all,
                "step {step}: {} wall contacts among the candidates, {} testing every particle",
                kept.len(),
                all.len()
            );
            assert!(state.fields.force == every_particle.fields.force, "step {step}: forces differ");
            found += state.history.walls.len();
        }
        assert!(rebuilds > 20, "{rebuilds} rebuilds");
        assert!(found > 1000, "{found} wall contacts over the run");
    }
}
