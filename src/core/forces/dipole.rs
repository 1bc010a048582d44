//! Dipole–dipole force between the particles' moments, on i from j with r = x_i − x_j:
//!
//!   F_ij = 3μ0/(4π r⁴) [ (m_i·r̂) m_j + (m_j·r̂) m_i + (m_i·m_j) r̂ − 5 (m_i·r̂)(m_j·r̂) r̂ ]
//!
//! summed over all pairs or, with a cut-off, over pairs closer than it (Verlet list). The torque
//! T_i = m_perm,i × B_loc,i acts only on permanent moments: an induced moment of a linear sphere is
//! parallel to its local field.
//!
//! The sum runs over half rows of partners (the particles above, or the Verlet candidates above
//! within the cut-off) with F_ji = −F_ij; from [`parallel::MIN_PARALLEL_LEN`] particles on the
//! rows are split into bands summed apart (in parallel) and then added in band order, the same
//! order for any thread count (see [`BANDS`]). A row visits its partners in blocks of four
//! consecutive particles, one SIMD vector each, and sums in eight lanes by partner index, a
//! fixed order. Walled boxes skip the minimum-image arithmetic. Where the neighbour layer holds
//! the cut-off's range (the paper's induction declares it), the term sums over its pairs instead.

use super::magnetisation::{
    needs_field, pair_dipole_field, pair_dipole_fields, pair_dipole_fields_four, Induction, MU0,
};
use super::setup::{invalid, positive, Invalid, SceneContext, TermSpec};
use super::{Context, ForceTerm, Forces, Renumbering};
use crate::core::domain::Domain;
use crate::core::field::{AppliedField, FieldAt};
use crate::core::lanes;
use crate::core::neighbours::{CellList, Pair, PairList, RangePairs, Skins, VerletList};
use crate::core::parallel;
use crate::core::state::{Particles, Vec3};
use std::f64::consts::PI;
use wide::f64x4;

/// 3μ0/(4π) (N·m⁴/(A·m²)²).
const PREFACTOR: f64 = 3.0 * MU0 / (4.0 * PI);

/// Force on a dipole `mi` at r (relative to `mj`), `r = x_i − x_j`, `dist = |r|`.
#[inline]
pub fn dipole_pair_force(mi: &Vec3, mj: &Vec3, r: &Vec3, dist: f64) -> Vec3 {
    let inv = 1.0 / dist;
    let rhat = r * inv;
    let (mir, mjr) = (mi.dot(&rhat), mj.dot(&rhat));
    let inv2 = inv * inv;
    (PREFACTOR * inv2 * inv2) * (mir * mj + mjr * mi + (mi.dot(mj) - 5.0 * mir * mjr) * rhat)
}

/// [`dipole_pair_force`] of four pairs at once, `moment` indexed by particle: the same
/// operations in SIMD lanes, so the same bits.
#[inline(always)]
fn dipole_pair_forces_four(moment: &[Vec3], q: [&Pair; 4]) -> [Vec3; 4] {
    let inv = f64x4::ONE / f64x4::new(q.map(|q| q.dist));
    let rhat = lanes::gather(q.map(|q| &q.r)).map(|c| c * inv);
    let (mi, mj) = (lanes::gather(q.map(|q| &moment[q.i as usize])), lanes::gather(q.map(|q| &moment[q.j as usize])));
    let (mir, mjr) = (lanes::dot(&mi, &rhat), lanes::dot(&mj, &rhat));
    let inv2 = inv * inv;
    let scale = f64x4::splat(PREFACTOR) * inv2 * inv2;
    let along = lanes::dot(&mi, &mj) - f64x4::splat(5.0) * mir * mjr;
    lanes::scatter(&std::array::from_fn(|c| scale * (mir * mj[c] + mjr * mi[c] + along * rhat[c])))
}

/// Partners are taken in blocks of four consecutive particles 4b..4b+4, one SIMD vector of f64
/// (`wide::f64x4`, AVX where the CPU has it): the loads are contiguous, and the particles of a
/// block that are not partners of the row cost a masked lane instead of a gather.
const BLOCK: usize = 4;

/// The x, y and z components of a vector for the four particles of a block.
type BlockVectors = [f64x4; 3];

/// Positions and moments of four consecutive particles, by component. The last block is padded
/// with NaN positions, which no distance test passes, and zero moments.
#[derive(Debug, Clone, Copy)]
struct ParticleBlock {
    x: BlockVectors,
    m: BlockVectors,
}

fn fill_particle_blocks(blocks: &mut Vec<ParticleBlock>, position: &[Vec3], moment: &[Vec3]) {
    let padding = ParticleBlock { x: [f64x4::splat(f64::NAN); 3], m: [f64x4::ZERO; 3] };
    let n = position.len();
    blocks.resize(n.div_ceil(BLOCK), padding);
    let fill = |q: usize, block: &mut ParticleBlock| {
        *block = padding;
        for (lane, i) in (q * BLOCK..n.min((q + 1) * BLOCK)).enumerate() {
            set_lane(&mut block.x, lane, &position[i]);
            set_lane(&mut block.m, lane, &moment[i]);
        }
    };
    parallel::for_each_share(&mut blocks[..], |first, blocks| {
        blocks.iter_mut().enumerate().for_each(|(k, b)| fill(first + k, b))
    });
}

/// `blocks` = `vectors` in blocks of four, the last one padded with zeros.
fn fill_blocks(blocks: &mut Vec<BlockVectors>, vectors: &[Vec3]) {
    blocks.clear();
    blocks.resize(vectors.len().div_ceil(BLOCK), [f64x4::ZERO; 3]);
    for (q, v) in vectors.iter().enumerate() {
        set_lane(&mut blocks[q / BLOCK], q % BLOCK, v);
    }
}

fn set_lane(block: &mut BlockVectors, lane: usize, v: &Vec3) {
    for k in 0..3 {
        block[k].as_mut_array()[lane] = v[k];
    }
}

fn lane(block: &BlockVectors, lane: usize) -> Vec3 {
    Vec3::new(block[0].as_array()[lane], block[1].as_array()[lane], block[2].as_array()[lane])
}

/// Minimum image on periodic axes: d − L round(d/L), with L = 0 on walled axes.
struct Image {
    length: [f64; 3],
    inverse: [f64; 3],
}

impl Image {
    fn of(domain: &Domain) -> Self {
        let length = [0, 1, 2].map(|k| if domain.periodic[k] { domain.hi[k] - domain.lo[k] } else { 0.0 });
        Image { length, inverse: length.map(|l| if l > 0.0 { 1.0 / l } else { 0.0 }) }
    }
}

/// Neighbour rows of the cut-off sum, from the Verlet candidates: row i lists, ascending, the
/// blocks that hold its candidates j > i (half rows, for F_ji = −F_ij).
#[derive(Debug, Default, Clone)]
struct Rows {
    start: Vec<usize>,
    blocks: Vec<u32>,
}

impl Rows {
    fn build(&mut self, n: usize, candidates: &[(u32, u32)]) {
        self.start.clear();
        self.blocks.clear();
        // Candidates are sorted by (i, j): each row's candidates come together, in ascending order.
        let mut candidates = candidates.iter().peekable();
        for i in 0..n {
            self.start.push(self.blocks.len());
            while let Some((_, j)) = candidates.next_if(|(owner, _)| *owner as usize == i) {
                let block = j / BLOCK as u32;
                if self.blocks.len() == self.start[i] || self.blocks.last() != Some(&block) {
                    self.blocks.push(block);
                }
            }
        }
        self.start.push(self.blocks.len());
        debug_assert!(candidates.next().is_none(), "candidates sorted by (i, j), i < n");
    }

    fn row(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.blocks[self.start[i]..self.start[i + 1]].iter().map(|&b| b as usize)
    }
}

/// One row of the sum: particle i and the test of its partners j, closer than the cut-off
/// (squared distance `cutoff2`) and, in i's own block, j > i.
struct Row {
    /// Particle i's position and moment in every lane.
    x: BlockVectors,
    m: BlockVectors,
    cutoff2: f64x4,
    own_block: usize,
    /// Lanes of the own block that are partners.
    own_lanes: f64x4,
}

impl Row {
    fn new(blocks: &[ParticleBlock], i: usize, cutoff2: f64) -> Self {
        let block = &blocks[i / BLOCK];
        let (x, m) = (lane(&block.x, i % BLOCK), lane(&block.m, i % BLOCK));
        let (lanes, own_lane) = (f64x4::new([0.0, 1.0, 2.0, 3.0]), f64x4::splat((i % BLOCK) as f64));
        let own_lanes = lanes.simd_gt(own_lane);
        let splat = |v: Vec3| [0, 1, 2].map(|k| f64x4::splat(v[k]));
        Row { x: splat(x), m: splat(m), cutoff2: f64x4::splat(cutoff2), own_block: i / BLOCK, own_lanes }
    }
}

/// F_ij of row i's particle on the particles j of block b, by component, zero for the j that are
/// not its partners: the module's formula with d = x_i − x_j not normalised,
///
///   F_ij = 3μ0/(4π r⁵) [ (m_i·d) m_j + (m_j·d) m_i + (m_i·m_j − 5 (m_i·d)(m_j·d)/r²) d ],
///
/// and 1/r = √(r²)·(1/r²), whose square root and division run side by side rather than one
/// after the other. It equals [`dipole_pair_force`] to rounding (tests/parallel.rs).
#[inline(always)]
fn block_forces<const PERIODIC: bool>(block: &ParticleBlock, image: &Image, row: &Row, b: usize) -> BlockVectors {
    let (xi, mi, mj) = (&row.x, &row.m, &block.m);
    let mut d = [xi[0] - block.x[0], xi[1] - block.x[1], xi[2] - block.x[2]];
    if PERIODIC {
        for (dk, (length, inverse)) in d.iter_mut().zip(image.length.iter().zip(&image.inverse)) {
            *dk -= f64x4::splat(*length) * (*dk * f64x4::splat(*inverse)).round_ties_even();
        }
    }
    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let inv2 = f64x4::ONE / r2;
    let inv = r2.sqrt() * inv2;
    let mid = mi[0] * d[0] + mi[1] * d[1] + mi[2] * d[2];
    let mjd = mj[0] * d[0] + mj[1] * d[1] + mj[2] * d[2];
    let mimj = mi[0] * mj[0] + mi[1] * mj[1] + mi[2] * mj[2];
    let scale = f64x4::splat(PREFACTOR) * (inv2 * inv2) * inv;
    let radial = mimj - f64x4::splat(5.0) * mid * mjd * inv2;
    let mut partner = r2.simd_lt(row.cutoff2);
    if b == row.own_block {
        partner &= row.own_lanes;
    }
    // A selection, not a product: the lanes left out (i itself, padding) may hold NaN.
    let component = |k: usize| partner.select(scale * (mid * mj[k] + mjd * mi[k] + radial * d[k]), f64x4::ZERO);
    [component(0), component(1), component(2)]
}

/// Σ_j F_ij over the partners in `blocks` (ascending), subtracting each F_ij from the reaction
/// of j's block b, `reaction[b − first_block]`, on the way (F_ji = −F_ij). The sum runs in eight
/// running sums, the term of partner j in sum j mod 8, then the eight in order: a fixed order, in
/// which the zero terms of the lanes left out change nothing (so the sum does not depend on
/// which candidates the Verlet list holds, and a resumed run stays bitwise equal).
#[inline(always)]
fn row_sum<const PERIODIC: bool>(
    particles: &[ParticleBlock],
    image: &Image,
    row: &Row,
    blocks: impl Iterator<Item = usize>,
    reaction: &mut [BlockVectors],
    first_block: usize,
) -> Vec3 {
    let mut sums = [[f64x4::ZERO; 2]; 3];
    for b in blocks {
        let f = block_forces::<PERIODIC>(&particles[b], image, row, b);
        for k in 0..3 {
            sums[k][b % 2] += f[k];
            reaction[b - first_block][k] -= f[k];
        }
    }
    Vec3::from_fn(|k, _| sums[k].iter().flat_map(|s| s.to_array()).fold(0.0, |a, s| a + s))
}

/// Rows of the sum in bands of consecutive rows, each summing half rows into its own buffer; the
/// buffers are then added in band order. The bands are fixed by the particle count alone (one
/// below [`parallel::MIN_PARALLEL_LEN`] particles, [`BANDS`] from there on), never by the thread
/// count or the Verlet list, so the sum's order, and its bits, are the same on any number of
/// threads and after any rebuild history.
const BANDS: usize = 16;

/// One band: rows `rows`, and the forces they give to blocks `first_block..` (their own row
/// sums and their reactions, which go only to higher particles).
#[derive(Debug, Default, Clone)]
struct Band {
    rows: std::ops::Range<usize>,
    first_block: usize,
    forces: Vec<BlockVectors>,
}

/// Adds Σ_j F_ij to `force` with partners from `rows` (`None` = all other particles) within
/// `cutoff2`, by half rows with F_ji = −F_ij in `bands` (see [`BANDS`]).
fn add_row_sums(
    particles: &[ParticleBlock],
    image: &Image,
    rows: Option<&Rows>,
    cutoff2: f64,
    force: &mut [Vec3],
    bands: &mut Vec<Band>,
) {
    // Without periodic axes the image term is d − 0 = d: the same bits without its arithmetic.
    if image.length == [0.0; 3] {
        add_row_sums_in::<false>(particles, image, rows, cutoff2, force, bands)
    } else {
        add_row_sums_in::<true>(particles, image, rows, cutoff2, force, bands)
    }
}

fn add_row_sums_in<const PERIODIC: bool>(
    particles: &[ParticleBlock],
    image: &Image,
    rows: Option<&Rows>,
    cutoff2: f64,
    force: &mut [Vec3],
    bands: &mut Vec<Band>,
) {
    use rayon::prelude::*;
    let n = force.len();
    let blocks = n.div_ceil(BLOCK);
    let count = if n < parallel::MIN_PARALLEL_LEN { 1 } else { BANDS };
    // Bands of about equal work, fixed by n alone: equal numbers of rows with a cut-off, and over
    // all pairs, rows weighted by their partner blocks. (A split by the Verlet candidates would
    // move with the list's rebuilds, and a resumed run would no longer be bitwise equal.)
    let work = |i: usize| if rows.is_some() { 1 } else { blocks - i / BLOCK };
    let total: usize = (0..n).map(work).sum();
    bands.resize_with(count, Band::default);
    let (mut i, mut done) = (0, 0);
    for (b, band) in bands.iter_mut().enumerate() {
        let start = i;
        while i < n && (b + 1 == count || done < total * (b + 1) / count) {
            done += work(i);
            i += 1;
        }
        band.rows = start..i;
        band.first_block = if b == 0 { 0 } else { start / BLOCK };
    }
    // Each band's buffer starts from zero, the first from the forces so far. Within a band, each
    // particle receives the reactions of the band's rows i' < i, in order, before its own row's
    // sum, as in a pair-by-pair loop; those of the other bands are added after, in band order.
    let sum_band = |(b, band): (usize, &mut Band)| {
        if b == 0 {
            fill_blocks(&mut band.forces, force);
        } else {
            band.forces.clear();
            band.forces.resize(blocks - band.first_block, [f64x4::ZERO; 3]);
        }
        let reactions = &mut band.forces;
        for i in band.rows.clone() {
            let row = Row::new(particles, i, cutoff2);
            let sum = match rows {
                Some(rows) => row_sum::<PERIODIC>(particles, image, &row, rows.row(i), reactions, band.first_block),
                None => {
                    row_sum::<PERIODIC>(particles, image, &row, (i + 1) / BLOCK..blocks, reactions, band.first_block)
                }
            };
            for k in 0..3 {
                reactions[i / BLOCK - band.first_block][k].as_mut_array()[i % BLOCK] += sum[k];
            }
        }
    };
    let in_parallel = parallel::worth_it(n);
    if in_parallel {
        bands.par_iter_mut().enumerate().for_each(sum_band);
    } else {
        bands.iter_mut().enumerate().for_each(sum_band);
    }
    let (first, others) = bands.split_first_mut().expect("at least one band");
    // Block by block, the other bands' forces in band order.
    let add_others = |q0: usize, out: &mut [BlockVectors]| {
        for band in others.iter() {
            let skip = band.first_block.saturating_sub(q0);
            let theirs = band.forces.iter().skip((q0 + skip).saturating_sub(band.first_block));
            for (sum, forces) in out.iter_mut().skip(skip).zip(theirs) {
                (0..3).for_each(|k| sum[k] += forces[k]);
            }
        }
    };
    parallel::for_each_share(&mut first.forces[..], add_others);
    for (i, f) in force.iter_mut().enumerate() {
        *f = lane(&first.forces[i / BLOCK], i % BLOCK);
    }
}

/// Adds F_ij to i and −F_ij to j for each pair of the range, each particle's in pair order.
fn add_range_pairs(pairs: &RangePairs, moment: &[Vec3], force: &mut [Vec3]) {
    let pair_force = |q: &Pair| dipole_pair_force(&moment[q.i as usize], &moment[q.j as usize], &q.r, q.dist);
    // −F_ij added is F_ij subtracted, bit for bit.
    pairs.add_in_order_by_four(
        force,
        |q| {
            let f = pair_force(q);
            (f, -f)
        },
        |q| -pair_force(q),
        |q| dipole_pair_forces_four(moment, q).map(|f| (f, -f)),
    );
}

pub struct DipoleForce {
    /// Pair cut-off distance (m); `None` = all pairs.
    pub cutoff: Option<f64>,
    /// Verlet skin of the cut-off list: `cutoff` times this.
    skin: f64,
    /// Applied field, for the torque on permanent moments.
    pub applied: AppliedField,
    verlet: VerletList,
    pairs: PairList,
    particle_blocks: Vec<ParticleBlock>,
    rows: Rows,
    bands: Vec<Band>,
}

impl DipoleForce {
    pub fn new(cutoff: Option<f64>, applied: AppliedField, skins: Skins) -> Self {
        Self {
            cutoff,
            skin: skins.magnetic,
            applied,
            verlet: VerletList::default(),
            pairs: PairList::default(),
            particle_blocks: vec![],
            rows: Rows::default(),
            bands: vec![],
        }
    }
}

/// `[forces.dipole]`: dipole–dipole forces and the moments they act between.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DipoleSpec {
    /// `none` | `paper` | `exact`.
    pub induction: InductionSpec,
    /// Pair cut-off of the force sum in diameters (largest species); absent = all pairs.
    pub cutoff_diameters: Option<f64>,
    /// Radius of the `paper` induction neighbourhood, in diameters (default 15, as the paper).
    #[serde(default = "default_paper_radius")]
    pub paper_radius_diameters: f64,
    /// `exact`: relative change of the moments at which iteration stops (default 1e-10).
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// `exact`: most fixed-point sweeps per step (default 500).
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// `exact`: largest N solved by a dense LU instead of iteration (default 150).
    #[serde(default = "default_dense_max")]
    pub dense_max: usize,
}

/// `forces.dipole.induction`: the moments' mutual induction ([`Induction`]).
#[derive(Debug, Clone, Copy, serde::Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum InductionSpec {
    None,
    Paper,
    Exact,
}

fn default_paper_radius() -> f64 {
    15.0
}
fn default_tolerance() -> f64 {
    1e-10
}
fn default_max_iterations() -> usize {
    500
}
fn default_dense_max() -> usize {
    150
}

impl TermSpec for DipoleSpec {
    fn check(&self, ctx: &SceneContext) -> Result<(), Invalid> {
        needs_field(ctx)?;
        let tol = self.tolerance;
        if !(1e-15..1.0).contains(&tol) {
            return Err(invalid(
                "forces.dipole.tolerance",
                tol,
                "impossible mutual-induction tolerance: double precision resolves relative changes \
                 down to about 1e-15, and it must be below 1",
            ));
        }
        if self.max_iterations == 0 {
            return Err(invalid("forces.dipole.max_iterations", 0, "must be at least 1"));
        }
        let mut ranges = vec![];
        if let Some(c) = self.cutoff_diameters {
            positive("forces.dipole.cutoff_diameters", c)?;
            ranges.push(("forces.dipole.cutoff_diameters", c));
        }
        if self.induction == InductionSpec::Paper {
            positive("forces.dipole.paper_radius_diameters", self.paper_radius_diameters)?;
            ranges.push(("forces.dipole.paper_radius_diameters", self.paper_radius_diameters));
        }
        let (domain, largest) = (ctx.domain, ctx.largest_diameter());
        for (key, diameters) in ranges {
            for k in 0..3 {
                let half = 0.5 * domain.length()[k];
                if domain.periodic[k] && diameters * largest >= half {
                    return Err(invalid(
                        key,
                        diameters,
                        format!(
                            "{:e} m is not below half the periodic box length {half:e} m along {}",
                            diameters * largest,
                            ["x", "y", "z"][k]
                        ),
                    ));
                }
            }
        }
        if ctx.scheme.spec().compares_evaluations() && self.induction == InductionSpec::Paper {
            return Err(invalid(
                "integration.scheme",
                ctx.scheme,
                "needs forces that depend on the state alone, and the paper's induction advances its moments by one sweep per \
                 force evaluation (step doubling would compare one sweep with two); use forces.dipole.induction = \"exact\" or \"none\"",
            ));
        }
        Ok(())
    }

    fn moments(&self, ctx: &SceneContext) -> Option<Induction> {
        Some(match self.induction {
            InductionSpec::None => Induction::None,
            InductionSpec::Paper => Induction::Paper { radius: self.paper_radius_diameters * ctx.largest_diameter() },
            InductionSpec::Exact => Induction::Exact {
                tolerance: self.tolerance,
                max_iterations: self.max_iterations,
                dense_max: self.dense_max,
            },
        })
    }

    fn build(&self, ctx: &SceneContext) -> Box<dyn ForceTerm> {
        let cutoff = self.cutoff_diameters.map(|c| c * ctx.largest_diameter());
        Box::new(DipoleForce::new(cutoff, ctx.field(), ctx.pairs.skins))
    }
}

impl ForceTerm for DipoleForce {
    fn name(&self) -> &'static str {
        "dipole"
    }
    fn is_slow(&self) -> bool {
        true
    }
    /// Sums over the pairs of the neighbour layer's range at the cut-off where a term declared
    /// one (the paper's induction reads the same neighbourhood), otherwise over rows of particle
    /// blocks.
    fn apply(&mut self, ctx: &Context, p: &Particles, out: &mut Forces) {
        let n = p.len();
        let shared = ctx.neighbours.declared(self.cutoff).map(|range| ctx.neighbours.range_pairs(range));
        match (&shared, self.cutoff) {
            (Some(pairs), _) => add_range_pairs(pairs, out.moment, out.force),
            (None, Some(c)) => {
                if self.verlet.update(&p.position, ctx.domain, c, c * self.skin).is_some() {
                    self.rows.build(n, self.verlet.candidates());
                }
                fill_particle_blocks(&mut self.particle_blocks, &p.position, out.moment);
                add_row_sums(
                    &self.particle_blocks,
                    &Image::of(ctx.domain),
                    Some(&self.rows),
                    c * c,
                    out.force,
                    &mut self.bands,
                );
            }
            (None, None) => {
                fill_particle_blocks(&mut self.particle_blocks, &p.position, out.moment);
                add_row_sums(
                    &self.particle_blocks,
                    &Image::of(ctx.domain),
                    None,
                    f64::INFINITY,
                    out.force,
                    &mut self.bands,
                );
            }
        }
        if p.has_permanent_moments {
            // B_loc = B_ext + μ0 Σ_j H_dip,j over the pairs of the force sum.
            let pairs = match shared {
                Some(pairs) => pairs,
                None => {
                    match self.cutoff {
                        Some(c) => {
                            self.verlet.pairs_within(&p.position, ctx.domain, c, c * self.skin, &mut self.pairs);
                        }
                        None => self
                            .pairs
                            .fill_whole(|out| CellList::default().pairs_within(&p.position, ctx.domain, None, out)),
                    }
                    RangePairs::own(self.pairs.seq())
                }
            };
            let mut b_loc: Vec<Vec3> = match self.applied.at(ctx.time) {
                FieldAt::Linear { b0, g } => p.position.iter().map(|x| b0 + g * x).collect(),
                applied => p.position.iter().map(|x| applied.field(x)).collect(),
            };
            let moment = &*out.moment;
            pairs.add_in_order_by_four(
                &mut b_loc,
                |q| {
                    let (on_i, on_j) = pair_dipole_fields(&moment[q.i as usize], &moment[q.j as usize], q);
                    (MU0 * on_i, MU0 * on_j)
                },
                |q| MU0 * pair_dipole_field(&moment[q.i as usize], q),
                |q| pair_dipole_fields_four(moment, q).map(|(on_i, on_j)| (MU0 * on_i, MU0 * on_j)),
            );
            for ((torque, m), b) in out.torque.iter_mut().zip(&p.permanent_moment).zip(&b_loc) {
                *torque += m.cross(b);
            }
        }
    }
    /// The own Verlet candidates (without a shared range) are renamed and their rows built
    /// again; the blocks, bands and pairs are working space of an evaluation.
    fn renumber(&mut self, r: &Renumbering) {
        if self.verlet.renumber(r) {
            self.rows.build(r.len(), self.verlet.candidates());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Four pairs in lanes give each pair's scalar force bit for bit, over separations from touching
    /// to the cut-off in every direction and moments of any orientation.
    #[test]
    fn forces_in_lanes_are_the_scalar_forces_bit_for_bit() {
        let (moment, quads) = lanes::testing::random_quads(7, 4000);
        for pairs in &quads {
            let lanes = dipole_pair_forces_four(&moment, [&pairs[0], &pairs[1], &pairs[2], &pairs[3]]);
            for (q, f) in pairs.iter().zip(lanes) {
                let scalar = dipole_pair_force(&moment[q.i as usize], &moment[q.j as usize], &q.r, q.dist);
                assert_eq!(f.map(f64::to_bits), scalar.map(f64::to_bits), "pair {q:?}");
            }
        }
    }
}
