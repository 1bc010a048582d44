//! Pair search: a cell list rebuilt every step (no hidden state, so a resumed run is bitwise equal),
//! or all pairs when no cut-off is set. Periodic axes use the minimum image.

use super::domain::Domain;
use super::parallel::{self, PieceList, Pieced, Pieces};
use super::renumber::Renumbering;
use super::state::{Motion, Positions, Vec3};
use super::timers::PhaseTimers;

/// Pairs in (i, j) order, in the pieces the parallel filter wrote ([`parallel::PieceList`]).
pub type PairList = PieceList<Pair>;

/// A pair (i < j) closer than the search range; `r = x_i − x_j` (minimum image), `dist = |r|`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Pair {
    pub i: u32,
    pub j: u32,
    pub r: Vec3,
    pub dist: f64,
}

/// Reusable cell-list buffers.
#[derive(Debug, Default, Clone)]
pub struct CellList {
    cell_start: Vec<u32>,
    cell_particles: Vec<u32>,
    particle_cell: Vec<u32>,
    /// Chunk buffers of the parallel candidate collection.
    candidate_pieces: Pieces<(u32, u32)>,
}

impl CellList {
    /// Fills `out` with every pair (i < j) closer than `range`, in (i, j) order. `range = None`
    /// means all pairs.
    pub fn pairs_within(&mut self, positions: &[Vec3], domain: &Domain, range: Option<f64>, out: &mut Vec<Pair>) {
        out.clear();
        let n = positions.len();
        let Some(range) = range else {
            for i in 0..n {
                for j in i + 1..n {
                    let r = domain.displacement(&positions[i], &positions[j]);
                    out.push(Pair { i: i as u32, j: j as u32, r, dist: r.norm() });
                }
            }
            return;
        };
        // The candidates at `range` are exactly these pairs; their separations are taken as
        // the Verlet filter takes them (the same bits).
        let mut candidates = vec![];
        self.candidates_within(positions, domain, range, &mut candidates);
        out.extend(candidates.into_iter().map(|(i, j)| {
            let r = domain.displacement(&positions[i as usize], &positions[j as usize]);
            Pair { i, j, r, dist: r.norm_squared().sqrt() }
        }));
    }

    /// Fills `out` with every (i, j), i < j, closer than `range`, in (i, j) order: the pairs of
    /// [`Self::pairs_within`] without their separations (a fifth of the bytes: a Verlet list's
    /// candidates). A cell's members are in ascending order, and in particles kept in
    /// spatial order most cells lie wholly above or below a row, so a row's partners j > i in a
    /// cell are all, none, or a tail found by a binary search; the distance test then picks
    /// without a branch.
    pub fn candidates_within(&mut self, positions: &[Vec3], domain: &Domain, range: f64, out: &mut Vec<(u32, u32)>) {
        let n = positions.len();
        let dims = self.bin(positions, domain, range);
        let range2 = range * range;
        let Self { cell_start, cell_particles, particle_cell, candidate_pieces, .. } = self;
        let periodic = domain.periodic != [false; 3];
        parallel::collect_ordered_ranges(n, out, candidate_pieces, |rows, out| {
            for i in rows {
                let row = out.len();
                let (cells, count) = neighbour_cells(particle_cell[i], dims, domain);
                let x = positions[i];
                for &c2 in &cells[..count] {
                    let members =
                        &cell_particles[cell_start[c2 as usize] as usize..cell_start[c2 as usize + 1] as usize];
                    // Particles in spatial order fill most cells wholly below or above i.
                    let above = match (members.first(), members.last()) {
                        (Some(&first), _) if first as usize > i => members,
                        (_, Some(&last)) if last as usize > i => {
                            &members[members.partition_point(|&j| j as usize <= i)..]
                        }
                        _ => &[],
                    };
                    let mut kept = out.len();
                    out.resize(kept + above.len(), (0, 0));
                    for &j in above {
                        let y = &positions[j as usize];
                        let r = if periodic { domain.displacement(&x, y) } else { x - y };
                        out[kept] = (i as u32, j);
                        kept += (r.norm_squared() < range2) as usize;
                    }
                    out.truncate(kept);
                }
                out[row..].sort_unstable_by_key(|&(_, j)| j);
            }
        });
    }

    /// Sorts the particles into cells at least `range` wide (no more than ~2 cells per
    /// particle: empty cells cost); returns the cells per axis.
    fn bin(&mut self, positions: &[Vec3], domain: &Domain, range: f64) -> [usize; 3] {
        let n = positions.len();
        let len = domain.length();
        let max_cells = (2 * n).max(27) as f64;
        let mut width = range;
        let count = |w: f64| (0..3).map(|k| (len[k] / w).floor().max(1.0)).product::<f64>();
        while count(width) > max_cells {
            width *= 1.26;
        }
        let dims: [usize; 3] = std::array::from_fn(|k| ((len[k] / width).floor() as usize).max(1));
        let ncells = dims[0] * dims[1] * dims[2];
        let cell_of = |p: &Vec3| -> u32 {
            let mut idx = [0usize; 3];
            for k in 0..3 {
                let f = (p[k] - domain.lo[k]) / len[k] * dims[k] as f64;
                idx[k] = (f.floor().max(0.0) as usize).min(dims[k] - 1);
            }
            ((idx[2] * dims[1] + idx[1]) * dims[0] + idx[0]) as u32
        };

        // Counting sort of particles into cells: each cell's members in ascending order.
        self.particle_cell.clear();
        self.particle_cell.extend(positions.iter().map(cell_of));
        self.cell_start.clear();
        self.cell_start.resize(ncells + 1, 0);
        for &c in &self.particle_cell {
            self.cell_start[c as usize + 1] += 1;
        }
        for c in 0..ncells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.cell_particles.clear();
        self.cell_particles.resize(n, 0);
        let mut fill = self.cell_start.clone();
        for (i, &c) in self.particle_cell.iter().enumerate() {
            self.cell_particles[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        dims
    }
}

/// The distinct cells within one cell of `cell` (wrapped on periodic axes), and how many.
fn neighbour_cells(cell: u32, dims: [usize; 3], domain: &Domain) -> ([u32; 27], usize) {
    let c = cell as usize;
    let idx = [c % dims[0], (c / dims[0]) % dims[1], c / (dims[0] * dims[1])];
    // Up to three distinct indices per axis (fewer at walls or in short periodic axes).
    let axis = |k: usize| -> ([usize; 3], usize) {
        let (mut v, mut len) = ([0usize; 3], 0);
        for off in [-1i64, 0, 1] {
            let n = dims[k] as i64;
            let c = idx[k] as i64 + off;
            let c = if domain.periodic[k] { c.rem_euclid(n) } else { c };
            if (0..n).contains(&c) && !v[..len].contains(&(c as usize)) {
                v[len] = c as usize;
                len += 1;
            }
        }
        (v, len)
    };
    let ((ax, nx), (ay, ny), (az, nz)) = (axis(0), axis(1), axis(2));
    let (mut cells, mut count) = ([0u32; 27], 0);
    for &z in &az[..nz] {
        for &y in &ay[..ny] {
            for &x in &ax[..nx] {
                cells[count] = ((z * dims[1] + y) * dims[0] + x) as u32;
                count += 1;
            }
        }
    }
    (cells, count)
}

/// Pairs within a fixed range, found through a Verlet list: candidates within range + skin are
/// kept (sorted by (i, j)) until some particle has moved more than half the skin, and each call
/// filters them by the current distance. Because the candidates are sorted, the pairs come out
/// in (i, j) order whenever the list was built, so results do not depend on the rebuild history
/// (a resumed run stays bitwise equal).
///
/// A skin wider than [`ADAPTIVE_SKIN_FLOOR`] of the range (the dilute scenes' whole range) is the
/// widest the list uses: at each rebuild the skin in use narrows (down to that floor) while
/// rebuilds are rare and widens again while they are frequent ([`VerletList::adapt`]), so a
/// suspension whose particles snap together at m/s rebuilds seldom and its chains, once formed
/// and slow, filter few candidates. Which pairs come out never depends on the skin.
#[derive(Debug, Default, Clone)]
pub struct VerletList {
    cells: CellList,
    candidates: Vec<(u32, u32)>,
    /// `reach[j]`: the lowest row i of a candidate (i, j') with j' ≥ j (`u32::MAX` if none).
    reach: Vec<u32>,
    reference: Vec<Vec3>,
    /// What the list knows of the displacements from `reference`.
    anchor: Anchor,
    built_for: Option<(f64, f64)>,
    /// The skin of the last build (at most the declared one).
    in_use: f64,
    /// Updates since the last build.
    since_build: u64,
    /// Rebuilds so far (diagnostic).
    pub rebuilds: u64,
    /// Updates so far at which every particle was compared with its reference (diagnostic; at the
    /// others the drifts' bounds settled that none had moved far enough, [`Anchor::settles`]).
    pub examined: u64,
}

/// The narrowest skin, as a fraction of the range, to which [`VerletList`] narrows a wider one.
/// 0.4: in chains nothing lies between 1.2 and 1.4 diameters (the touching neighbours at one,
/// the next along the chain at two), so against 0.2 the near list of the chained 100× run holds
/// the same candidates (33 580 against 33 579) and is rebuilt half as often (320 against 649
/// times in 20 000 steps of its mid state).
pub const ADAPTIVE_SKIN_FLOOR: f64 = 0.4;

impl VerletList {
    /// The skin for the next build, given the updates between the last two: narrower by 3/4 after
    /// more than 50 (rebuilding costs a cell search, filtering costs per candidate and step:
    /// rare rebuilds mean the skin holds more candidates than it needs), wider by 3/2 after fewer
    /// than 10, within [`ADAPTIVE_SKIN_FLOOR`] × range … `skin`.
    fn adapt(&self, range: f64, skin: f64) -> f64 {
        let floor = skin.min(ADAPTIVE_SKIN_FLOOR * range);
        if self.built_for != Some((range, skin)) {
            return skin;
        }
        let next = match self.since_build {
            0..10 => self.in_use * 1.5,
            10..=50 => self.in_use,
            _ => self.in_use * 0.75,
        };
        next.clamp(floor, skin)
    }

    /// The skin the candidates were last built with.
    pub fn skin_in_use(&self) -> f64 {
        self.in_use
    }

    /// Brings the candidates up to date for `range` and at most `skin` (rebuilt when some
    /// particle has moved more than half the skin in use since the last build); returns the skin
    /// in use if it rebuilt them.
    pub fn update(&mut self, positions: &Positions, domain: &Domain, range: f64, skin: f64) -> Option<f64> {
        let stale = self.reference.len() != positions.len() || self.built_for != Some((range, skin));
        let half = 0.5 * self.in_use;
        let moved_too_far = stale
            || (!self.anchor.settles(positions, half) && {
                self.examined += 1;
                moved_farther(positions, &self.reference, &mut self.anchor, domain, half)
            });
        if !moved_too_far {
            self.since_build += 1;
            return None;
        }
        self.in_use = self.adapt(range, skin);
        self.cells.candidates_within(positions, domain, range + self.in_use, &mut self.candidates);
        self.find_reach(positions.len());
        self.reference.clear();
        self.reference.extend_from_slice(positions);
        self.anchor = Anchor::at(positions);
        self.built_for = Some((range, skin));
        self.since_build = 0;
        self.rebuilds += 1;
        Some(self.in_use)
    }

    /// `reach` of the candidates, for `n` particles.
    fn find_reach(&mut self, n: usize) {
        self.reach.clear();
        self.reach.resize(n, u32::MAX);
        for &(i, j) in &self.candidates {
            let lowest = &mut self.reach[j as usize];
            *lowest = (*lowest).min(i);
        }
        for j in (1..self.reach.len()).rev() {
            self.reach[j - 1] = self.reach[j - 1].min(self.reach[j]);
        }
    }

    /// Renames the candidates and moves the reference positions to the particles' new slots:
    /// the same candidates as a build at those positions with the skin in use, so the rebuilds
    /// (and the adaptive skin) go on as without the renumbering. Returns whether there were
    /// candidates to rename (none before a build or for another particle set: rebuilt at the
    /// next update; so after a removal).
    pub fn renumber(&mut self, r: &Renumbering) -> bool {
        // A removal drops candidates too: rebuilt at the next update.
        if self.reference.len() != r.old_len() || r.removes() {
            self.reference.clear();
            return false;
        }
        use rayon::prelude::*;
        self.candidates.par_iter_mut().for_each(|c| *c = r.pair(*c).0);
        self.candidates.par_sort_unstable();
        self.find_reach(r.len());
        r.permute(&mut self.reference);
        true
    }

    /// Candidate pairs (i < j) within range + skin of the last build, sorted by (i, j).
    pub fn candidates(&self) -> &[(u32, u32)] {
        &self.candidates
    }

    /// The lowest row i of a candidate (i, j) with j ≥ `lo` (at most `lo`; 0 before a build):
    /// the rows before it reach no particle from `lo` on, so a share of particles from `lo`
    /// skips them.
    pub fn first_row_reaching(&self, lo: usize) -> usize {
        self.reach.get(lo).map_or(0, |&i| (i as usize).min(lo))
    }

    /// Fills `out` with the pairs closer than `range` in (i, j) order; `skin` is the largest
    /// extra candidate distance (a larger skin rebuilds less often but filters more candidates).
    /// Returns the skin in use if the candidates were rebuilt.
    pub fn pairs_within(
        &mut self,
        positions: &Positions,
        domain: &Domain,
        range: f64,
        skin: f64,
        out: &mut PairList,
    ) -> Option<f64> {
        let rebuilt = self.update(positions, domain, range, skin);
        self.filter_into(positions, domain, range, out);
        rebuilt
    }

    /// Fills `out` with the candidates closer than `range` now, in (i, j) order (the candidates
    /// must be up to date: [`Self::update`]).
    pub fn filter_into(&self, positions: &[Vec3], domain: &Domain, range: f64, out: &mut PairList) {
        filter_candidates(&self.candidates, positions, domain, range, out);
    }
}

/// The `candidates` closer than `range` now into `out`, in their order.
fn filter_candidates(candidates: &[(u32, u32)], positions: &[Vec3], domain: &Domain, range: f64, out: &mut PairList) {
    if domain.periodic == [false; 3] {
        filter(candidates, positions, range, out, |a, b| a - b);
    } else {
        filter(candidates, positions, range, out, |a, b| domain.displacement(a, b));
    }
}

/// A listed range's second level of candidates: those of the Verlet list closer than range +
/// a narrower skin, kept until some particle has moved more than half that skin (then taken
/// again from the Verlet candidates, a pass over them, not a cell search). The listed range's
/// filter reads them instead of the Verlet candidates: every pair within range is among them,
/// so the pairs, their order and their bits are the same. In the chained 100× state the
/// 15-diameter Verlet list holds 1.37 M candidates for 0.63 M pairs (a skin of two diameters,
/// which the particles snapping together early in a run need); its close level holds about as
/// many as the pairs.
///
/// The close skin adapts as the Verlet skin does: wider by 3/2 when it was taken again after
/// fewer than [`CloseCandidates::FEW`] updates, narrower by 3/4 after more than
/// [`CloseCandidates::MANY`]. At the Verlet skin, or holding nine tenths of the Verlet
/// candidates or more (the near lists, whose skin adapts itself), it is left out until the next
/// rebuild.
#[derive(Debug, Default, Clone)]
struct CloseCandidates {
    list: Vec<(u32, u32)>,
    pieces: Pieces<(u32, u32)>,
    /// Positions when `list` was taken; empty: not taken for the current Verlet candidates.
    reference: Vec<Vec3>,
    /// What the list knows of the displacements from `reference`.
    anchor: Anchor,
    /// The close skin; 0 before the first build.
    skin: f64,
    /// Whether `list` is in use (its skin narrower than the Verlet skin in use).
    in_use: bool,
    since: u64,
    /// Times taken again (diagnostic).
    builds: u64,
}

impl CloseCandidates {
    const FEW: u64 = 4;
    const MANY: u64 = 16;

    /// Drops the close candidates: taken again at the next update.
    fn forget(&mut self) {
        self.reference.clear();
    }

    /// The candidates the listed range's filter reads.
    fn candidates<'a>(&'a self, verlet: &'a VerletList) -> &'a [(u32, u32)] {
        if self.in_use {
            &self.list
        } else {
            verlet.candidates()
        }
    }

    /// Brings the close candidates up to date with the Verlet list `verlet` (rebuilt in this
    /// update if `rebuilt`).
    /// Returns whether the candidates it gives changed (other than by a Verlet rebuild).
    fn update(
        &mut self,
        verlet: &VerletList,
        rebuilt: bool,
        positions: &Positions,
        domain: &Domain,
        range: f64,
    ) -> bool {
        let outer = verlet.skin_in_use();
        if rebuilt || self.reference.len() != positions.len() {
            // A first build starts at half the Verlet skin; a rebuild tries again below it.
            self.skin = if self.skin == 0.0 { 0.5 * outer } else { self.skin.min(0.75 * outer) };
            self.reference.clear();
        } else if !self.in_use {
            return false;
        } else {
            let half = 0.5 * self.skin;
            let (reference, anchor) = (&self.reference, &mut self.anchor);
            if anchor.settles(positions, half) || !moved_farther(positions, reference, anchor, domain, half) {
                self.since += 1;
                return false;
            }
            self.skin = match self.since {
                0..Self::FEW => self.skin * 1.5,
                Self::FEW..=Self::MANY => self.skin,
                _ => self.skin * 0.75,
            };
        }
        self.since = 0;
        self.in_use = self.skin < outer;
        if !self.in_use {
            return true;
        }
        let reach2 = (range + self.skin).powi(2);
        let periodic = domain.periodic != [false; 3];
        let candidates = verlet.candidates();
        parallel::collect_ordered_ranges(candidates.len(), &mut self.list, &mut self.pieces, |ks, out| {
            // Each candidate written at the end of the kept ones, which advances only if it is
            // close: no branch on a test that goes either way from one candidate to the next.
            let mut kept = out.len();
            out.resize(kept + ks.len(), (0, 0));
            for &ij in &candidates[ks] {
                out[kept] = ij;
                kept += (separation(domain, periodic, positions, ij).norm_squared() < reach2) as usize;
            }
            out.truncate(kept);
        });
        self.reference.clear();
        self.reference.extend_from_slice(positions);
        self.anchor = Anchor::at(positions);
        self.builds += 1;
        // Hardly fewer than the Verlet candidates (a near list whose skin already adapts): not
        // worth the upkeep until the next rebuild.
        self.in_use = self.list.len() < candidates.len() / 10 * 9;
        true
    }
}

/// The `candidates` closer than `range` into `out`, with their separation `displacement(x_i, x_j)`
/// (generic, so that a box without periodic axes filters with a plain subtraction).
fn filter(
    candidates: &[(u32, u32)],
    positions: &[Vec3],
    range: f64,
    out: &mut PairList,
    displacement: impl Fn(&Vec3, &Vec3) -> Vec3 + Sync,
) {
    let range2 = range * range;
    out.collect(candidates.len(), |ks, slots| {
        // Every candidate is written at the end of the kept ones, which advances by one only if
        // it is in range: no branch on the test, which goes either way from one candidate to the
        // next in a wide list (61 % in range at 15 diameters in the chained 100× state).
        let mut kept = 0;
        // Four candidates at a time, their square roots independent of one another (the
        // compiled loop takes four scalar roots; one vector root, the same bits, was no faster).
        let mut quads = candidates[ks].chunks_exact(4);
        for quad in &mut quads {
            // Written out: through `array::from_fn` the displacement was called out of line, its
            // result passed through the stack (a third of the filter's time).
            let r_of = |(i, j): (u32, u32)| displacement(&positions[i as usize], &positions[j as usize]);
            let r = [r_of(quad[0]), r_of(quad[1]), r_of(quad[2]), r_of(quad[3])];
            let d2: [f64; 4] = std::array::from_fn(|k| r[k].norm_squared());
            let dist = d2.map(f64::sqrt);
            for k in 0..4 {
                slots[kept] = Pair { i: quad[k].0, j: quad[k].1, r: r[k], dist: dist[k] };
                kept += (d2[k] < range2) as usize;
            }
        }
        for &(i, j) in quads.remainder() {
            let r = displacement(&positions[i as usize], &positions[j as usize]);
            let d2 = r.norm_squared();
            slots[kept] = Pair { i, j, r, dist: d2.sqrt() };
            kept += (d2 < range2) as usize;
        }
        kept
    });
}

/// The listed pairs (i, j) whose j lies in a later share of particles than i (as
/// [`parallel::split_of`] splits the particles), in (i, j) order: what a share of a pair sum adds
/// before its own rows ([`parallel::add_pairs_in_order`]). Without them each share after the
/// first scans the rows before it, and in Morton order with periodic sides the first row
/// already reaches the last share: in the chained 100× state the second of two shares scanned
/// 335 000 pairs of the 15-diameter list for 21 000, in the moments sweep and again in the
/// dipole forces. They are filtered from the crossing candidates, found again when the
/// candidates change; the filter's arithmetic is the listing's, so they are the listed pairs,
/// bit for bit.
#[derive(Debug, Default, Clone)]
pub struct CrossingPairs {
    /// (share count, share length) of the split they were found for; (0, 0): none.
    split: (usize, usize),
    candidates: Vec<(u32, u32)>,
    candidate_pieces: Pieces<(u32, u32)>,
    pairs: PairList,
}

impl CrossingPairs {
    /// Finds the crossing candidates again if `changed` or the split of `n` particles is not
    /// the one they were found for.
    fn follow(&mut self, candidates: &[(u32, u32)], n: usize, changed: bool) {
        let split = parallel::split_of(n);
        if !changed && split == self.split {
            return;
        }
        let (shares, size) = split;
        let boundaries: Vec<u32> = (1..shares).map(|s| (s * size) as u32).collect();
        let crosses = |&(i, j): &(u32, u32)| boundaries.iter().any(|&b| i < b && j >= b);
        parallel::collect_ordered_ranges(
            candidates.len(),
            &mut self.candidates,
            &mut self.candidate_pieces,
            |ks, out| out.extend(candidates[ks].iter().filter(|c| crosses(c))),
        );
        self.split = split;
    }

    /// The crossing candidates within `range` now, filtered by the listing's own filter.
    fn filter(&mut self, positions: &[Vec3], domain: &Domain, range: f64) {
        filter_candidates(&self.candidates, positions, domain, range, &mut self.pairs);
    }

    /// Whether they were found for the split of `n` particles this thread pool makes.
    pub fn found_for(&self, n: usize) -> bool {
        self.split == parallel::split_of(n)
    }

    /// The crossing pairs into the share from `lo` of `len` particles (of the split they were
    /// found for).
    pub fn reaching(&self, lo: usize, len: usize) -> impl Iterator<Item = &Pair> {
        self.pairs.seq().iter().filter(move |q| (lo..lo + len).contains(&(q.j as usize)))
    }
}

/// x_i − x_j, the minimum image where the domain is `periodic` on some axis (without, the plain
/// difference: the same bits without the image arithmetic).
#[inline(always)]
fn separation(domain: &Domain, periodic: bool, positions: &[Vec3], (i, j): (u32, u32)) -> Vec3 {
    let (a, b) = (&positions[i as usize], &positions[j as usize]);
    if periodic {
        domain.displacement(a, b)
    } else {
        a - b
    }
}

/// What a list last knew of its particles' displacements from its reference positions: at the
/// positions' `motion`, none was farther than `within` (m, minimum image) from its reference.
#[derive(Debug, Clone, Copy, Default)]
struct Anchor {
    motion: Motion,
    within: f64,
}

impl Anchor {
    /// At the reference positions themselves.
    fn at(positions: &Positions) -> Self {
        Anchor { motion: positions.motion(), within: 0.0 }
    }

    /// Whether the displacement known then plus the drifts' bounds since keep every particle
    /// within half of `distance` of its reference: then none has moved `distance`, and
    /// [`moved_farther`] need not look (the other half is margin for the rounding of the
    /// displacements it compares).
    fn settles(&self, positions: &Positions, distance: f64) -> bool {
        positions.motion().since(self.motion).is_some_and(|bound| self.within + bound <= 0.5 * distance)
    }
}

/// Whether some particle has moved farther than `distance` (minimum image) from its `reference`
/// position; the anchor moves to the positions now, with the largest displacement found. The
/// largest squared displacement is taken branch-free over a share, one such loop per share
/// (not rayon's element-wise map and reduce: see `reports/performance-history.md`), and compared
/// with `distance`².
fn moved_farther(
    positions: &Positions,
    reference: &[Vec3],
    anchor: &mut Anchor,
    domain: &Domain,
    distance: f64,
) -> bool {
    let squared = |(x, x0): (&Vec3, &Vec3)| domain.displacement(x, x0).norm_squared();
    let largest = parallel::max_over_shares((&positions[..], reference), |(xs, x0s)| {
        xs.iter().zip(x0s).map(squared).fold(0.0, |largest, d| if d > largest { d } else { largest })
    });
    *anchor = Anchor { motion: positions.motion(), within: largest.sqrt() };
    largest > distance * distance
}

/// The pairs a force term needs from the neighbour layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairRange {
    /// Pairs closer than `range`, through a Verlet list with candidates out to `range + skin`.
    Within { range: f64, skin: f64 },
    /// Every pair, rebuilt at each evaluation.
    All,
}

impl PairRange {
    /// The pair distance (`None`: all pairs), whatever the skin.
    pub fn distance(&self) -> Option<f64> {
        match *self {
            PairRange::Within { range, .. } => Some(range),
            PairRange::All => None,
        }
    }
}

/// The pairs of one range as the layer lists them, with what a term summing them over shares of
/// particles needs: the Verlet candidates they were filtered from (whose
/// [`VerletList::first_row_reaching`] bounds the pairs too) and the pairs crossing between
/// shares.
#[derive(Debug, Clone, Copy)]
pub struct RangePairs<'a> {
    pub pairs: Pieced<'a, Pair>,
    /// The Verlet list the pairs were filtered from (`None`: every pair, or a term's own list).
    pub verlet: Option<&'a VerletList>,
    /// The listed pairs crossing from one share of particles to a later one, where known.
    pub crossing: Option<&'a CrossingPairs>,
}

impl<'a> RangePairs<'a> {
    /// `pairs`, a term's own, with no candidates or crossing pairs behind them.
    pub fn own(pairs: Pieced<'a, Pair>) -> Self {
        RangePairs { pairs, verlet: None, crossing: None }
    }

    /// The lowest row with a pair reaching particle `lo` or beyond, or a row before it (0 without
    /// candidates behind the pairs): every pair is a candidate.
    pub fn first_row_reaching(&self, lo: usize) -> usize {
        self.verlet.map_or(0, |v| v.first_row_reaching(lo))
    }

    /// Σ over the pairs of `both(pair).0` into `out[i]` and `both(pair).1` into `out[j]`, each
    /// particle's terms in pair order, the same bits on any thread count
    /// ([`parallel::add_pairs_in_order`]); `second(pair)` is `both(pair).1` alone. A term with a
    /// lane kernel passes it to [`Self::add_in_order_by_four`] instead: through this one, a
    /// listed range's pairs are still taken four at a time, each by `both`.
    pub fn add_in_order<T: Copy + Send + std::ops::AddAssign>(
        &self,
        out: &mut [T],
        both: impl Fn(&Pair) -> (T, T) + Sync + Send,
        second: impl Fn(&Pair) -> T + Sync + Send,
    ) {
        self.add_in_order_by_four(out, &both, second, |q| q.map(&both))
    }

    /// [`Self::add_in_order`] with `four(pairs)`, `both` of four pairs computed together with
    /// the same bits (in SIMD lanes).
    pub fn add_in_order_by_four<T: Copy + Send + std::ops::AddAssign>(
        &self,
        out: &mut [T],
        both: impl Fn(&Pair) -> (T, T) + Sync + Send,
        second: impl Fn(&Pair) -> T + Sync + Send,
        four: impl Fn([&Pair; 4]) -> [(T, T); 4] + Sync + Send,
    ) {
        let ij = |q: &Pair| (q.i as usize, q.j as usize);
        // The pairs crossing into a share from the rows before it: those found as the range was
        // listed, for this split (compared here: inside a share, on the pool's other thread, the
        // split is not the step's), or the rows before it scanned. The same pairs, in order.
        let crossing = self.crossing.filter(|c| c.found_for(out.len()));
        let earlier = |lo: usize, share: &mut [T]| match crossing {
            Some(c) => c.reaching(lo, share.len()).for_each(|q| share[q.j as usize - lo] += second(q)),
            None => {
                let first_row = self.first_row_reaching(lo);
                parallel::add_earlier_rows(self.pairs, ij, first_row, &second, lo, share)
            }
        };
        parallel::add_pairs_in_order(out, self.pairs, ij, earlier, both, four);
    }
}

/// Verlet skins, as fractions of the range they pad: the one numerical setting of the neighbour
/// layer. A skin changes how often candidates are rebuilt, never which pairs a search returns.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Skins {
    /// Contact and shielding lists (range about one diameter): 0.2, as in the reference decks,
    /// or a whole range in dilute scenes ([`Skins::for_density`]).
    pub near: f64,
    /// The dipole forces' own list (a cut-off without the paper's induction): 1/15, one
    /// diameter at 15 diameters.
    pub magnetic: f64,
    /// The paper's induction neighbourhood (15 diameters; the dipole forces of the same cut-off
    /// sum over it too): 2/15. Early in a run its particles snap together at m/s: in the 100×
    /// case-1 run at 0.3 ms a skin of 1/15 rebuilt the candidates every 8 outer steps (12 per
    /// 1 000 steps, 0.33 s of its 2.4 s); 2/15 rebuilt them 5 times, with 21 % more candidates to
    /// filter (`reports/performance-history.md`, stage 31).
    pub induction: f64,
}

impl Default for Skins {
    fn default() -> Self {
        Skins { near: 0.2, magnetic: 1.0 / 15.0, induction: 2.0 / 15.0 }
    }
}

impl Skins {
    /// The skins for `density` particles per m³ and a near range `range`: the default, with the
    /// near skin widened to a whole range where even then a particle has on average fewer than
    /// [`DILUTE_CANDIDATES`] candidates. A rebuild costs a cell search over every particle, and
    /// in a dilute suspension the fastest particle (two dipoles snapping together at m/s) sets
    /// it off every few steps for all; a wider skin there adds candidates that cost nearly
    /// nothing to filter. In 33 675 particles at 2.25 mg/ml a rebuild took 6-7 ms, every 10
    /// steps with the 0.2 skin.
    pub fn for_density(density: f64, range: f64) -> Self {
        let wide = 1.0;
        let candidates = density * 4.0 / 3.0 * std::f64::consts::PI * (range * (1.0 + wide)).powi(3);
        let default = Self::default();
        Skins { near: if candidates < DILUTE_CANDIDATES { wide } else { default.near }, ..default }
    }
}

/// Mean candidates per particle below which [`Skins::for_density`] widens the near skin.
pub const DILUTE_CANDIDATES: f64 = 1.0;

/// What one range of the neighbour layer did: see [`Neighbours::usage`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeUsage {
    pub range: PairRange,
    pub rebuilds: u64,
    /// Updates at which every particle was compared with its reference position.
    pub examined: u64,
    pub skin_in_use: f64,
    pub candidates: usize,
    /// Pairs in the last listing.
    pub listed: usize,
    /// Close candidates of a listed range, if in use: how many, their skin, how often taken.
    pub close: Option<(usize, f64, u64)>,
}

/// One pair range of the neighbour layer: its candidates and its pairs.
#[derive(Debug, Clone)]
struct Listed {
    range: PairRange,
    verlet: VerletList,
    /// The listed pairs' own, closer candidates.
    close: CloseCandidates,
    cells: CellList,
    pairs: PairList,
    crossing: CrossingPairs,
    /// The skin, when the candidates were rebuilt in the last update.
    rebuilt: Option<f64>,
}

/// The neighbour layer: one entry per distinct range the force terms declare, brought up to date
/// once per evaluation that needs it and shared by every term that declared it. Each range's
/// pairs are listed in a branch-free pass of their own, which every term reads: filtering the
/// candidates inside a term's own pass, with a branch per candidate, cost more than writing the
/// list, even for the contact, which reads each pair once (`reports/performance-history.md`,
/// stages 37 and 38).
#[derive(Debug, Default, Clone)]
pub struct Neighbours {
    lists: Vec<Listed>,
}

impl Neighbours {
    /// A layer serving `ranges` (equal ranges share one entry).
    pub fn new(ranges: impl IntoIterator<Item = PairRange>) -> Self {
        let mut lists: Vec<Listed> = vec![];
        for range in ranges {
            if !lists.iter().any(|l| l.range == range) {
                lists.push(Listed {
                    range,
                    verlet: VerletList::default(),
                    close: CloseCandidates::default(),
                    cells: CellList::default(),
                    pairs: PairList::default(),
                    crossing: CrossingPairs::default(),
                    rebuilt: None,
                });
            }
        }
        Self { lists }
    }

    /// Brings the ranges `wanted` selects up to date for `positions`, timing the candidates'
    /// upkeep (the displacement check and the rebuilds) apart from the filtering of the listed
    /// pairs.
    pub fn update(
        &mut self,
        positions: &Positions,
        domain: &Domain,
        wanted: impl Fn(PairRange) -> bool,
        timers: &mut PhaseTimers,
    ) {
        for list in self.lists.iter_mut().filter(|l| wanted(l.range)) {
            list.rebuilt = match list.range {
                PairRange::Within { range, skin } => {
                    let (verlet, close, crossing) = (&mut list.verlet, &mut list.close, &mut list.crossing);
                    let rebuilt = timers.time("neighbours", || {
                        let rebuilt = verlet.update(positions, domain, range, skin);
                        let retaken = close.update(verlet, rebuilt.is_some(), positions, domain, range);
                        crossing.follow(close.candidates(verlet), positions.len(), rebuilt.is_some() || retaken);
                        rebuilt
                    });
                    let (candidates, pairs) = (close.candidates(verlet), &mut list.pairs);
                    timers.time("pair-list", || {
                        filter_candidates(candidates, positions, domain, range, pairs);
                        crossing.filter(positions, domain, range);
                    });
                    rebuilt
                }
                PairRange::All => {
                    let (cells, pairs) = (&mut list.cells, &mut list.pairs);
                    timers
                        .time("all-pairs", || pairs.fill_whole(|out| cells.pairs_within(positions, domain, None, out)));
                    None
                }
            };
        }
    }

    /// Follows a renumbering of the particles: candidates renamed ([`VerletList::renumber`]);
    /// the listed pairs are filtered again at the next update that wants them.
    pub fn renumber(&mut self, r: &Renumbering) {
        for list in &mut self.lists {
            list.verlet.renumber(r);
            list.close.forget();
            list.pairs.clear();
            list.crossing = CrossingPairs::default();
            list.rebuilt = None;
        }
    }

    /// Per range: how often its candidates were rebuilt, how many there are now and how many
    /// pairs the last update listed (a diagnostic, for `magdem run --timings`).
    pub fn usage(&self) -> Vec<RangeUsage> {
        self.lists
            .iter()
            .map(|l| RangeUsage {
                range: l.range,
                rebuilds: l.verlet.rebuilds,
                examined: l.verlet.examined,
                skin_in_use: l.verlet.skin_in_use(),
                candidates: l.verlet.candidates().len(),
                listed: l.pairs.len(),
                close: l.close.in_use.then_some((l.close.list.len(), l.close.skin, l.close.builds)),
            })
            .collect()
    }

    fn list(&self, range: PairRange) -> Option<&Listed> {
        self.lists.iter().find(|l| l.range == range)
    }

    /// The listed pairs of `range` (i < j, in (i, j) order); empty for a range no term declared.
    pub fn pairs(&self, range: PairRange) -> Pieced<'_, Pair> {
        self.list(range).map_or(Pieced::Whole(&[]), |l| l.pairs.seq())
    }

    /// The pairs of `range`: those listed within its distance for any term, with any skin (a
    /// term reuses them instead of filtering again); none for a distance no term declared. Every
    /// pair of [`PairRange::All`] is listed.
    pub fn range_pairs(&self, range: PairRange) -> RangePairs<'_> {
        match self.lists.iter().find(|l| l.range.distance() == range.distance()) {
            Some(l) => RangePairs {
                pairs: l.pairs.seq(),
                verlet: matches!(l.range, PairRange::Within { .. }).then_some(&l.verlet),
                crossing: Some(&l.crossing),
            },
            None => RangePairs::own(Pieced::Whole(&[])),
        }
    }

    /// The range some term declared within `distance` (`None`: all pairs), with its skin: a term
    /// that can sum over another's pairs finds them here instead of searching again.
    pub fn declared(&self, distance: Option<f64>) -> Option<PairRange> {
        self.lists.iter().map(|l| l.range).find(|r| r.distance() == distance)
    }

    /// `Some(skin)` when the candidates of `range` were rebuilt in the last update, with the skin
    /// in use: until the next rebuild no particle moves more than skin/2 from where it is now.
    pub fn rebuilt(&self, range: PairRange) -> Option<f64> {
        self.list(range).and_then(|l| l.rebuilt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    fn brute(positions: &[Vec3], domain: &Domain, range: f64) -> Vec<(u32, u32)> {
        let mut v = vec![];
        for i in 0..positions.len() {
            for j in i + 1..positions.len() {
                if domain.displacement(&positions[i], &positions[j]).norm() < range {
                    v.push((i as u32, j as u32));
                }
            }
        }
        v
    }

    /// 300 particles at random in a 1 × 0.8 × 0.6 box with the given periodic axes.
    fn random_box(seed: u64, periodic: [bool; 3]) -> (rand_chacha::ChaCha8Rng, Domain, Vec<Vec3>) {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let domain = Domain { lo: Vec3::zeros(), hi: Vec3::new(1.0, 0.8, 0.6), periodic };
        let pos = (0..300)
            .map(|_| Vec3::new(rng.random::<f64>(), 0.8 * rng.random::<f64>(), 0.6 * rng.random::<f64>()))
            .collect();
        (rng, domain, pos)
    }

    /// Moves every particle by up to `step`/2 per axis, kept in the box.
    fn jiggle(rng: &mut rand_chacha::ChaCha8Rng, pos: &mut [Vec3], domain: &Domain, step: f64) {
        for x in pos.iter_mut() {
            *x += Vec3::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5) * step;
            domain.wrap(x);
            *x = x.zip_map(&domain.hi, |c, hi| c.clamp(0.0, hi));
        }
    }

    /// A list fed drifts with their bounds leaves out the comparison of every particle while the
    /// bounds allow it, and rebuilds exactly when a list that compares every particle at every
    /// update does (each update it is handed a clone: another set of positions, whose motion
    /// says nothing), so the two list the same pairs, those of a brute-force search. A move
    /// written otherwise, without a bound, is examined at the next update and rebuilds both.
    #[test]
    fn drifts_with_their_bounds_give_the_rebuilds_of_examining_every_particle() {
        let (mut rng, domain, start) = random_box(17, [true, false, true]);
        let velocity: Vec<Vec3> = start.iter().map(|_| Vec3::from_fn(|_, _| 2.0 * rng.random::<f64>() - 1.0)).collect();
        let largest = velocity.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let mut positions = Positions::from(start);
        let (mut fed, mut examining) = (VerletList::default(), VerletList::default());
        let (mut listed, mut compared) = (PairList::default(), PairList::default());
        let pairs = |list: &PairList| list.seq().iter().map(|p| (p.i, p.j)).collect::<Vec<_>>();
        let updates = 600;
        for update in 0..updates {
            fed.pairs_within(&positions, &domain, 0.1, 0.02, &mut listed);
            examining.pairs_within(&positions.clone(), &domain, 0.1, 0.02, &mut compared);
            assert_eq!(fed.rebuilds, examining.rebuilds, "update {update}");
            assert_eq!(pairs(&listed), pairs(&compared), "update {update}");
            if update % 25 == 0 {
                assert_eq!(pairs(&listed), brute(&positions, &domain, 0.1), "update {update}");
            }
            // Slow, then ten times faster; walls bounce the particles back inside.
            let speed = if update < 300 { 2e-5 } else { 2e-4 };
            positions.drift(|x| {
                for (x, v) in x.iter_mut().zip(&velocity) {
                    *x += v * speed;
                    domain.wrap(x);
                    x.y = x.y.clamp(0.0, domain.hi.y);
                }
                largest * speed * (1.0 + 1e-12) + domain.wrap_rounding()
            });
            match update {
                // Written without moving (as a renumbering writes them): examined once, then
                // settled again from the displacement found.
                200 => _ = positions.write(),
                450 => positions.write()[7].y = (positions[7].y + 0.3) % 0.8,
                _ => {}
            }
        }
        assert!(fed.rebuilds >= 5, "the particles moved enough to rebuild: {} rebuilds", fed.rebuilds);
        assert_eq!(examining.examined, updates - 1, "a clone is examined at every update but the first (a build)");
        assert!(
            fed.examined * 2 < examining.examined,
            "the bounds settled most updates: examined at {} of {updates} against {}",
            fed.examined,
            examining.examined
        );
    }

    #[test]
    fn verlet_list_gives_the_same_pairs_in_ij_order_as_particles_move() {
        // Periodic on two axes, and walled on all three (filtered with a plain subtraction).
        for periodic in [[true, false, true], [false; 3]] {
            let (mut rng, domain, mut pos) = random_box(11, periodic);
            let mut list = VerletList::default();
            let mut out = PairList::default();
            for _ in 0..40 {
                list.pairs_within(&pos.clone().into(), &domain, 0.15, 0.03, &mut out);
                let got: Vec<(u32, u32)> = out.seq().iter().map(|p| (p.i, p.j)).collect();
                assert_eq!(got, brute(&pos, &domain, 0.15), "periodic {periodic:?}");
                for p in out.seq().iter() {
                    assert_eq!(
                        p.r,
                        domain.displacement(&pos[p.i as usize], &pos[p.j as usize]),
                        "periodic {periodic:?}"
                    );
                }
                jiggle(&mut rng, &mut pos, &domain, 0.004);
            }
            assert!(list.rebuilds > 1 && list.rebuilds < 40, "{} rebuilds", list.rebuilds);
        }
    }

    /// A listed range with a wide skin reads its close candidates between rebuilds: the listed
    /// pairs are the brute-force ones, with their separations bit for bit, whether the close
    /// level is in use or not, and it is taken again as the particles move.
    #[test]
    fn the_close_candidates_give_the_listed_pairs_as_particles_move() {
        let (mut rng, domain, mut pos) = random_box(13, [true, false, true]);
        let range = PairRange::Within { range: 0.12, skin: 0.06 };
        let mut layer = Neighbours::new([range]);
        let (mut in_use, mut taken) = (0, 0);
        for step in 0..120 {
            layer.update(&pos.clone().into(), &domain, |_| true, &mut PhaseTimers::default());
            let got: Vec<(u32, u32)> = layer.pairs(range).iter().map(|p| (p.i, p.j)).collect();
            assert_eq!(got, brute(&pos, &domain, 0.12), "step {step}");
            for p in layer.pairs(range).iter() {
                let r = domain.displacement(&pos[p.i as usize], &pos[p.j as usize]);
                assert!(p.r == r && p.dist == r.norm_squared().sqrt(), "step {step}");
            }
            let usage = layer.usage()[0];
            if let Some((count, skin, builds)) = usage.close {
                in_use += 1;
                taken = builds;
                assert!(count < usage.candidates && skin < usage.skin_in_use, "step {step}");
            }
            jiggle(&mut rng, &mut pos, &domain, 0.004);
        }
        assert!(in_use > 60 && taken > 5, "in use in {in_use} updates, taken {taken} times");
    }

    /// Summed on two threads, the pairs crossing into the second share come from those found as
    /// the range was listed, not from a scan of the first share's rows: the sums are the serial
    /// loop's bits, order-sensitive terms included, step after step as the particles move (the
    /// close candidates and the Verlet list rebuilt on the way, and with them the crossing
    /// candidates).
    #[test]
    fn pairs_crossing_between_shares_sum_as_the_serial_loop() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
        let n = 2 * crate::core::parallel::MIN_PARALLEL_LEN + 301;
        let domain = Domain { lo: Vec3::zeros(), hi: Vec3::new(1.0, 0.8, 0.6), periodic: [true, true, false] };
        let mut pos: Vec<Vec3> = (0..n)
            .map(|_| Vec3::new(rng.random::<f64>(), 0.8 * rng.random::<f64>(), 0.6 * rng.random::<f64>()))
            .collect();
        // In Morton order, as the renumbering keeps them: rows of the first share reach the second.
        pos = crate::core::renumber::morton_order(&pos, 0.05, &domain).into_iter().map(|i| pos[i]).collect();
        let range = PairRange::Within { range: 0.06, skin: 0.03 };
        let mut layer = Neighbours::new([range]);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let term = |q: &Pair| (1.0 / (1.0 + q.dist * q.i as f64), -3.0e5 / (1.0 + q.r.x * q.j as f64));
        for step in 0..12 {
            let mut sums = vec![0.1; n];
            let crossing = pool.install(|| {
                parallel::with_warm_pool(n, &mut parallel::Balance::default(), || {
                    layer.update(&pos.clone().into(), &domain, |_| true, &mut PhaseTimers::default());
                    let pairs = layer.range_pairs(range);
                    pairs.add_in_order(&mut sums, term, |q| term(q).1);
                    pairs.crossing.map(|c| (c.split, c.pairs.len()))
                })
            });
            let (split, count) = crossing.expect("a listed range");
            assert_eq!(split, (2, n.div_ceil(2)), "step {step}: found for the two shares");
            let listed = layer.pairs(range);
            let lo = split.1 as u32;
            assert_eq!(count, listed.iter().filter(|q| q.i < lo && q.j >= lo).count(), "step {step}");
            assert!(count > 1000, "step {step}: {count} crossing pairs");
            let mut serial = vec![0.1; n];
            for q in listed.iter() {
                let (a, b) = term(q);
                serial[q.i as usize] += a;
                serial[q.j as usize] += b;
            }
            assert!(sums == serial, "step {step}");
            jiggle(&mut rng, &mut pos, &domain, 0.004);
        }
    }

    /// The row bound a share of particles from `lo` starts its earlier rows at: no candidate of a
    /// row before it reaches `lo` or beyond, and one of its own row does (unless it is `lo`).
    #[test]
    fn the_first_row_reaching_a_share_is_the_lowest_whose_candidates_reach_it() {
        let (_, domain, pos) = random_box(9, [true, false, true]);
        let mut list = VerletList::default();
        assert_eq!(list.first_row_reaching(150), 0, "before a build, no row is skipped");
        list.update(&pos.clone().into(), &domain, 0.1, 0.02);
        let candidates = list.candidates();
        for lo in [1, 17, 150, 299] {
            let first = list.first_row_reaching(lo);
            assert!(candidates.iter().all(|&(i, j)| (i as usize) >= first || (j as usize) < lo), "lo {lo}");
            let reaching = candidates.iter().any(|&(i, j)| i as usize == first && j as usize >= lo);
            assert!(first == lo || reaching, "lo {lo}: row {first} reaches nothing from lo on");
            assert!(first < lo, "lo {lo}: 300 particles in a 0.1-range box have partners across any split");
        }
    }

    /// A skin of a whole range narrows to its floor while the particles drift slowly (rebuilds
    /// rare) and widens again while they drift fast (rebuilds frequent); the pairs are the
    /// brute-force ones throughout.
    #[test]
    fn a_wide_skin_narrows_when_rebuilds_are_rare_and_widens_when_they_are_frequent() {
        let (mut rng, domain, mut pos) = random_box(3, [true; 3]);
        let (range, skin) = (0.1, 0.1);
        let mut list = VerletList::default();
        let mut out = PairList::default();
        let mut drift = |list: &mut VerletList, pos: &mut Vec<Vec3>, speed: f64, updates: usize| {
            for _ in 0..updates {
                list.pairs_within(&pos.clone().into(), &domain, range, skin, &mut out);
                let got: Vec<(u32, u32)> = out.seq().iter().map(|p| (p.i, p.j)).collect();
                assert_eq!(got, brute(pos, &domain, range));
                for x in pos.iter_mut() {
                    x.x += speed;
                }
                jiggle(&mut rng, pos, &domain, 0.1 * speed);
            }
        };
        // Half the floor's skin (0.02) in 200 updates: rebuilds 50+ updates apart narrow the skin.
        drift(&mut list, &mut pos, 1e-4, 2500);
        assert_eq!(list.skin_in_use(), ADAPTIVE_SKIN_FLOOR * range, "slow particles: the floor");
        // Half the declared skin in 8.3 updates: rebuilds under 10 apart widen it.
        drift(&mut list, &mut pos, 6e-3, 60);
        assert_eq!(list.skin_in_use(), skin, "fast particles: the declared skin");
        // A declared skin at or below the floor is kept.
        let mut narrow = VerletList::default();
        for _ in 0..300 {
            narrow.pairs_within(&pos.clone().into(), &domain, range, 0.01, &mut out);
            pos.iter_mut().for_each(|x| x.x += 1e-4);
        }
        assert!(narrow.rebuilds > 1);
        assert_eq!(narrow.skin_in_use(), 0.01);
    }

    /// The listed pairs are the brute-force pairs in (i, j) order, each with r the minimum-image
    /// displacement x_i − x_j (the plain difference in a walled box) and dist = |r|, bit for
    /// bit: walled and periodic boxes, as the particles move and the candidates are rebuilt.
    #[test]
    fn listed_pairs_carry_their_displacement_bit_for_bit() {
        for periodic in [[true, false, true], [false; 3]] {
            let (mut rng, domain, mut pos) = random_box(5, periodic);
            let range = PairRange::Within { range: 0.12, skin: 0.03 };
            let mut layer = Neighbours::new([range]);
            for step in 0..30 {
                layer.update(&pos.clone().into(), &domain, |_| true, &mut PhaseTimers::default());
                let listed: Vec<Pair> = layer.pairs(range).iter().copied().collect();
                let ij: Vec<(u32, u32)> = listed.iter().map(|q| (q.i, q.j)).collect();
                assert_eq!(ij, brute(&pos, &domain, 0.12), "step {step}, periodic {periodic:?}");
                assert!(listed.len() > 100, "{} pairs", listed.len());
                for q in &listed {
                    let (a, b) = (&pos[q.i as usize], &pos[q.j as usize]);
                    let r = if periodic == [false; 3] { a - b } else { domain.displacement(a, b) };
                    assert!(q.r == r && q.dist == r.norm_squared().sqrt(), "step {step}: {q:?}");
                }
                jiggle(&mut rng, &mut pos, &domain, 0.01);
            }
        }
    }

    /// The paper's suspensions (336 particles of 11 µm in a 484 µm cube: 0.13 candidates per
    /// particle within two ranges) get the wide near skin; a packed bed (FCC of touching spheres,
    /// √2/d³) keeps 0.2; the magnetic skin is the default either way.
    #[test]
    fn dilute_scenes_widen_the_near_skin_and_dense_ones_do_not() {
        let d = 11.0e-6;
        let case1 = Skins::for_density(336.0 / 484.0e-6f64.powi(3), d);
        assert_eq!(case1, Skins { near: 1.0, ..Skins::default() });
        let packed = Skins::for_density(std::f64::consts::SQRT_2 / d.powi(3), d);
        assert_eq!(packed, Skins::default());
    }

    #[test]
    fn cell_list_finds_exactly_the_brute_force_pairs() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for periodic in [[false; 3], [true; 3], [true, false, true]] {
            let domain = Domain { lo: Vec3::zeros(), hi: Vec3::new(1.0, 0.7, 0.45), periodic };
            let pos: Vec<Vec3> = (0..400)
                .map(|_| Vec3::new(rng.random::<f64>(), 0.7 * rng.random::<f64>(), 0.45 * rng.random::<f64>()))
                .collect();
            // Also in spatial order (by z), where most cells lie wholly above or below a row.
            let mut ordered = pos.clone();
            ordered.sort_by(|a, b| a.z.total_cmp(&b.z));
            for (pos, order) in [(&pos, "random"), (&ordered, "spatial")] {
                for range in [0.05, 0.2, 0.3] {
                    let expected = brute(pos, &domain, range);
                    let mut out = vec![];
                    CellList::default().pairs_within(pos, &domain, Some(range), &mut out);
                    let got: Vec<_> = out.iter().map(|p| (p.i, p.j)).collect();
                    assert_eq!(got, expected, "pairs, periodic {periodic:?} range {range}, {order} order");
                    let mut candidates = vec![];
                    CellList::default().candidates_within(pos, &domain, range, &mut candidates);
                    assert_eq!(candidates, expected, "candidates, periodic {periodic:?} range {range}, {order} order");
                }
            }
        }
    }
}
