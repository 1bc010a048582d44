//! Dipole–dipole force between the particles' moments, on i from j with r = x_i − x_j:
//!
//!   F_ij = 3μ0/(4π r⁴) [ (m_i·r̂) m_j + (m_j·r̂) m_i + (m_i·m_j) r̂ − 5 (m_i·r̂)(m_j·r̂) r̂ ]
//!
//! summed over all pairs or, with a cut-off, over pairs closer than it (Verlet list). The torque
//! T_i = m_perm,i × B_loc,i acts only on permanent moments: an induced moment of a linear sphere is
//! parallel to its local field.
//!
//! The sum runs over rows of partners (all other particles, or the Verlet candidates within the
//! cut-off): below [`parallel::MIN_PARALLEL_LEN`] particles half rows with F_ji = −F_ij; above
//! it full rows, each particle summing its own (twice the pair work, but rows run in parallel
//! and in the same order for any thread count). The loop over a row works on coordinate arrays
//! so that it compiles to SIMD; its sum runs in eight lanes by partner index, a fixed order.
//! Walled boxes skip the minimum-image arithmetic. When the moments phase has already listed the pairs (the paper's
//! induction), the term sums over that list instead.

use super::{ForceContext, ForceTerm};
use crate::core::magnetisation::{pair_dipole_fields, MU0};
use crate::core::domain::Domain;
use crate::core::neighbours::{CellList, Pair, VerletList};
use crate::core::parallel;
use crate::core::state::{State, Vec3};
use nalgebra::Matrix3;
use std::f64::consts::PI;

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

/// Coordinates in separate arrays (structure of arrays), so that loops over j compile to SIMD.
#[derive(Debug, Default, Clone)]
struct Columns {
    x: [Vec<f64>; 3],
    m: [Vec<f64>; 3],
}

impl Columns {
    fn fill(&mut self, position: &[Vec3], moment: &[Vec3]) {
        for k in 0..3 {
            self.x[k].clear();
            self.x[k].extend(position.iter().map(|v| v[k]));
            self.m[k].clear();
            self.m[k].extend(moment.iter().map(|v| v[k]));
        }
    }
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

/// Neighbour rows of the cut-off sum, from the Verlet candidates: row i lists its j in ascending
/// order, only j > i (half rows, for F_ji = −F_ij) or every neighbour (full rows).
#[derive(Debug, Default, Clone)]
struct Rows {
    start: Vec<usize>,
    js: Vec<u32>,
}

impl Rows {
    fn build(&mut self, n: usize, candidates: &[(u32, u32)], full: bool) {
        self.start.clear();
        self.start.resize(n + 1, 0);
        for &(i, j) in candidates {
            self.start[i as usize + 1] += 1;
            if full {
                self.start[j as usize + 1] += 1;
            }
        }
        for i in 0..n {
            self.start[i + 1] += self.start[i];
        }
        let mut fill = self.start.clone();
        self.js.clear();
        self.js.resize(self.start[n], 0);
        // Candidates are sorted by (i, j): each row receives its entries in ascending order.
        for &(i, j) in candidates {
            self.js[fill[i as usize]] = j;
            fill[i as usize] += 1;
            if full {
                self.js[fill[j as usize]] = i;
                fill[j as usize] += 1;
            }
        }
    }

    fn row(&self, i: usize) -> &[u32] {
        &self.js[self.start[i]..self.start[i + 1]]
    }
}

/// Partner coordinates and moments of one row, contiguous: x, y, z, mx, my, mz.
type Partners<'a> = [&'a [f64]; 6];

/// Gathers the columns of the particles `js` into `buffer` (one row's partners), in one pass.
fn gather<'a>(c: &Columns, js: &[u32], buffer: &'a mut [Vec<f64>; 6]) -> Partners<'a> {
    for b in buffer.iter_mut() {
        b.resize(js.len(), 0.0);
    }
    let [x, y, z, mx, my, mz] = buffer;
    let partners = x.iter_mut().zip(y.iter_mut()).zip(z.iter_mut()).zip(mx.iter_mut().zip(my.iter_mut()).zip(mz.iter_mut()));
    for ((((x, y), z), ((mx, my), mz)), &j) in partners.zip(js) {
        let j = j as usize;
        (*x, *y, *z) = (c.x[0][j], c.x[1][j], c.x[2][j]);
        (*mx, *my, *mz) = (c.m[0][j], c.m[1][j], c.m[2][j]);
    }
    [x, y, z, mx, my, mz]
}

/// The columns of particles `range` (contiguous already).
fn slice(c: &Columns, range: std::ops::Range<usize>) -> Partners<'_> {
    [&c.x[0][range.clone()], &c.x[1][range.clone()], &c.x[2][range.clone()], &c.m[0][range.clone()], &c.m[1][range.clone()], &c.m[2][range]]
}

/// Writes F_ij into `out[k][q]` (k = x, y, z) for each partner q of particle i, zero beyond
/// the cut-off (squared distance `cutoff2`). The vectorisable part: contiguous arrays, no sums.
fn row_forces(c: &Columns, image: &Image, i: usize, partners: Partners, cutoff2: f64, out: &mut [Vec<f64>; 3]) {
    // Without periodic axes the image term is d − 0 = d: the same bits without its arithmetic.
    if image.length == [0.0; 3] {
        row_forces_in::<false>(c, image, i, partners, cutoff2, out)
    } else {
        row_forces_in::<true>(c, image, i, partners, cutoff2, out)
    }
}

#[inline(always)]
fn row_forces_in<const PERIODIC: bool>(c: &Columns, image: &Image, i: usize, partners: Partners, cutoff2: f64, out: &mut [Vec<f64>; 3]) {
    let (xi, mi) = ([c.x[0][i], c.x[1][i], c.x[2][i]], [c.m[0][i], c.m[1][i], c.m[2][i]]);
    let len = partners[0].len();
    // Every entry is written below: resized, not cleared.
    for o in out.iter_mut() {
        o.resize(len, 0.0);
    }
    let [ox, oy, oz] = out.each_mut().map(|o| &mut o[..len]);
    let [xs, ys, zs, mxs, mys, mzs] = partners.map(|p| &p[..len]);
    for q in 0..len {
        let d = [xi[0] - xs[q], xi[1] - ys[q], xi[2] - zs[q]];
        let d = if PERIODIC { [0, 1, 2].map(|k| d[k] - image.length[k] * (d[k] * image.inverse[k]).round_ties_even()) } else { d };
        let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let inv = 1.0 / r2.sqrt();
        let rhat = [d[0] * inv, d[1] * inv, d[2] * inv];
        let mj = [mxs[q], mys[q], mzs[q]];
        let mir = mi[0] * rhat[0] + mi[1] * rhat[1] + mi[2] * rhat[2];
        let mjr = mj[0] * rhat[0] + mj[1] * rhat[1] + mj[2] * rhat[2];
        let mimj = mi[0] * mj[0] + mi[1] * mj[1] + mi[2] * mj[2];
        let scale = if r2 < cutoff2 { PREFACTOR * (inv * inv) * (inv * inv) } else { 0.0 };
        let radial = mimj - 5.0 * mir * mjr;
        ox[q] = scale * (mir * mj[0] + mjr * mi[0] + radial * rhat[0]);
        oy[q] = scale * (mir * mj[1] + mjr * mi[1] + radial * rhat[1]);
        oz[q] = scale * (mir * mj[2] + mjr * mi[2] + radial * rhat[2]);
    }
}

/// Σ of one row's forces in eight running sums, the term of partner j in sum j mod 8, then the
/// eight in order: a fixed order for any thread count, in which the zero terms of candidates
/// beyond the cut-off change nothing (so the sum does not depend on when the candidates were
/// built, and a resumed run stays bitwise equal).
fn row_sum(out: &[Vec<f64>; 3], js: &[u32]) -> Vec3 {
    row_sum_and_scatter(out, js, |_, _| ())
}

/// [`row_sum`], calling `each(j, F_ij)` for every partner on the way (the half rows' reaction).
#[inline(always)]
fn row_sum_and_scatter(out: &[Vec<f64>; 3], js: &[u32], mut each: impl FnMut(usize, Vec3)) -> Vec3 {
    let mut lanes = [[0.0; 3]; 8];
    let terms = out[0].iter().zip(&out[1]).zip(&out[2]);
    for (((&fx, &fy), &fz), &j) in terms.zip(js) {
        let lane = &mut lanes[j as usize % 8];
        lane[0] += fx;
        lane[1] += fy;
        lane[2] += fz;
        each(j as usize, Vec3::new(fx, fy, fz));
    }
    Vec3::from_fn(|k, _| lanes.iter().fold(0.0, |a, lane| a + lane[k]))
}

/// [`row_sum`] for the contiguous partners `start..`: the same sums, vectorised (lane j mod 8 of
/// partner q = j − start is lane q mod 8 turned by start).
fn contiguous_row_sum(out: &[Vec<f64>; 3], start: usize) -> Vec3 {
    let lanes_of = |v: &[f64]| {
        let mut lanes = [0.0; 8];
        let chunks = v.chunks_exact(8);
        let rest = chunks.remainder();
        for chunk in chunks {
            for l in 0..8 {
                lanes[l] += chunk[l];
            }
        }
        for (l, x) in rest.iter().enumerate() {
            lanes[l] += x;
        }
        // Lane q mod 8 holds the partners j = start + q: in j order it is lane (l − start) mod 8.
        (0..8).fold(0.0, |a, l| a + lanes[(l + 8 - start % 8) % 8])
    };
    Vec3::new(lanes_of(&out[0]), lanes_of(&out[1]), lanes_of(&out[2]))
}

/// Adds Σ_j F_ij to `force` with partners from `rows` (`None` = all other particles) within
/// `cutoff2`: half rows with F_ji = −F_ij below [`parallel::MIN_PARALLEL_LEN`] particles, full
/// rows summed per particle in parallel above (see the module note).
fn add_row_sums(c: &Columns, image: &Image, rows: Option<&Rows>, cutoff2: f64, force: &mut [Vec3]) {
    let n = force.len();
    if n < parallel::MIN_PARALLEL_LEN {
        let (mut out, mut buffer): ([Vec<f64>; 3], [Vec<f64>; 6]) = Default::default();
        for i in 0..n {
            match rows {
                Some(rows) => {
                    let js = rows.row(i);
                    row_forces(c, image, i, gather(c, js, &mut buffer), cutoff2, &mut out);
                    let sum = row_sum_and_scatter(&out, js, |j, f| force[j] -= f);
                    force[i] += sum;
                }
                None => {
                    row_forces(c, image, i, slice(c, i + 1..n), cutoff2, &mut out);
                    force[i] += contiguous_row_sum(&out, i + 1);
                    for q in 0..n - i - 1 {
                        force[i + 1 + q] -= Vec3::new(out[0][q], out[1][q], out[2][q]);
                    }
                }
            }
        }
    } else {
        use rayon::prelude::*;
        let sums: Vec<Vec3> = (0..n)
            .into_par_iter()
            .with_min_len(64)
            .map_init(
                || <([Vec<f64>; 3], [Vec<f64>; 6])>::default(),
                |(out, buffer), i| match rows {
                    Some(rows) => {
                        let js = rows.row(i);
                        row_forces(c, image, i, gather(c, js, buffer), cutoff2, out);
                        row_sum(out, js)
                    }
                    None => {
                        row_forces(c, image, i, slice(c, 0..i), cutoff2, out);
                        let before = contiguous_row_sum(out, 0);
                        row_forces(c, image, i, slice(c, i + 1..n), cutoff2, out);
                        before + contiguous_row_sum(out, i + 1)
                    }
                },
            )
            .collect();
        force.iter_mut().zip(&sums).for_each(|(f, sum)| *f += sum);
    }
}

/// Adds F_ij to i and −F_ij to j for each listed pair, in list order.
fn add_listed_pairs(pairs: &[Pair], moment: &[Vec3], force: &mut [Vec3], buffer: &mut Vec<Vec3>) {
    let pair_force = |pair: &Pair| dipole_pair_force(&moment[pair.i as usize], &moment[pair.j as usize], &pair.r, pair.dist);
    if parallel::worth_it(pairs.len()) {
        parallel::map_ordered(pairs.len(), buffer, |k| pair_force(&pairs[k]));
        for (pair, f) in pairs.iter().zip(buffer.iter()) {
            force[pair.i as usize] += f;
            force[pair.j as usize] -= f;
        }
    } else {
        for pair in pairs {
            let f = pair_force(pair);
            force[pair.i as usize] += f;
            force[pair.j as usize] -= f;
        }
    }
}

pub struct DipoleForce {
    /// Pair cut-off distance (m); `None` = all pairs.
    pub cutoff: Option<f64>,
    /// Applied field, for the torque on permanent moments.
    pub b0: Vec3,
    pub gradient: Matrix3<f64>,
    verlet: VerletList,
    pairs: Vec<Pair>,
    buffer: Vec<Vec3>,
    columns: Columns,
    rows: Rows,
}

impl DipoleForce {
    pub fn new(cutoff: Option<f64>, b0: Vec3, gradient: Matrix3<f64>) -> Self {
        Self { cutoff, b0, gradient, verlet: VerletList::default(), pairs: vec![], buffer: vec![], columns: Columns::default(), rows: Rows::default() }
    }
}

impl ForceTerm for DipoleForce {
    fn name(&self) -> &'static str {
        "dipole"
    }
    fn is_slow(&self) -> bool {
        true
    }
    fn apply(&mut self, ctx: &ForceContext, state: &mut State) {
        let p = &mut state.particles;
        let n = p.len();
        match (ctx.magnetic_pairs, self.cutoff) {
            // The moments phase already found the pairs when its range is this cut-off.
            (Some((range, pairs)), _) if range == self.cutoff => add_listed_pairs(pairs, &p.moment, &mut p.force, &mut self.buffer),
            (_, Some(c)) => {
                if self.verlet.update(&p.position, ctx.domain, c, c / 15.0) {
                    self.rows.build(n, self.verlet.candidates(), n >= parallel::MIN_PARALLEL_LEN);
                }
                self.columns.fill(&p.position, &p.moment);
                add_row_sums(&self.columns, &Image::of(ctx.domain), Some(&self.rows), c * c, &mut p.force);
            }
            (_, None) => {
                self.columns.fill(&p.position, &p.moment);
                add_row_sums(&self.columns, &Image::of(ctx.domain), None, f64::INFINITY, &mut p.force);
            }
        }
        if p.has_permanent_moments {
            // B_loc = B_ext + μ0 Σ_j H_dip,j over the pairs of the force sum.
            let pairs: &[Pair] = match (ctx.magnetic_pairs, self.cutoff) {
                (Some((range, pairs)), _) if range == self.cutoff => pairs,
                (_, cutoff) => {
                    match cutoff {
                        Some(c) => {
                            self.verlet.pairs_within(&p.position, ctx.domain, c, c / 15.0, &mut self.pairs);
                        }
                        None => CellList::default().pairs_within(&p.position, ctx.domain, None, &mut self.pairs),
                    }
                    &self.pairs
                }
            };
            let mut b_loc: Vec<Vec3> = p.position.iter().map(|x| self.b0 + self.gradient * x).collect();
            for pair in pairs {
                let (i, j) = (pair.i as usize, pair.j as usize);
                let (on_i, on_j) = pair_dipole_fields(&p.moment[i], &p.moment[j], pair);
                b_loc[i] += MU0 * on_i;
                b_loc[j] += MU0 * on_j;
            }
            for ((torque, m), b) in p.torque.iter_mut().zip(&p.permanent_moment).zip(&b_loc) {
                *torque += m.cross(b);
            }
        }
    }
}
