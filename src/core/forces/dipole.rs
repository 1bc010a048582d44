//! Dipole–dipole force between the particles' moments, on i from j with r = x_i − x_j:
//!
//!   F_ij = 3μ0/(4π r⁴) [ (m_i·r̂) m_j + (m_j·r̂) m_i + (m_i·m_j) r̂ − 5 (m_i·r̂)(m_j·r̂) r̂ ]
//!
//! summed over all pairs or, with a cut-off, over pairs closer than it (Verlet list). The torque
//! T_i = m_perm,i × B_loc,i acts only on permanent moments: an induced moment of a linear sphere is
//! parallel to its local field.
//!
//! All pairs need no pair list: below [`parallel::MIN_PARALLEL_LEN`] particles a half loop uses
//! F_ji = −F_ij; above it each particle sums its own row (twice the pair work, but rows run in
//! parallel and in the same order for any thread count). The loop over j works on coordinate
//! arrays so that it compiles to SIMD; its sums run in j order afterwards (a vectorised sum would
//! reorder the additions).

use super::{ForceContext, ForceTerm};
use crate::core::magnetisation::{dipole_field, MU0};
use crate::core::domain::Domain;
use crate::core::neighbours::{Pair, VerletList};
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

/// Writes F_ij for j in `js` into `out[k][j − js.start]` (k = x, y, z): the vectorisable part.
fn row_forces(c: &Columns, image: &Image, i: usize, js: std::ops::Range<usize>, out: &mut [Vec<f64>; 3]) {
    let (xi, mi) = ([c.x[0][i], c.x[1][i], c.x[2][i]], [c.m[0][i], c.m[1][i], c.m[2][i]]);
    let len = js.len();
    for o in out.iter_mut() {
        o.clear();
        o.resize(len, 0.0);
    }
    let [ox, oy, oz] = out;
    let (xs, ys, zs) = (&c.x[0][js.clone()], &c.x[1][js.clone()], &c.x[2][js.clone()]);
    let (mxs, mys, mzs) = (&c.m[0][js.clone()], &c.m[1][js.clone()], &c.m[2][js]);
    for j in 0..len {
        let d = [xi[0] - xs[j], xi[1] - ys[j], xi[2] - zs[j]];
        let d = [0, 1, 2].map(|k| d[k] - image.length[k] * (d[k] * image.inverse[k]).round());
        let inv = 1.0 / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let rhat = [d[0] * inv, d[1] * inv, d[2] * inv];
        let mj = [mxs[j], mys[j], mzs[j]];
        let mir = mi[0] * rhat[0] + mi[1] * rhat[1] + mi[2] * rhat[2];
        let mjr = mj[0] * rhat[0] + mj[1] * rhat[1] + mj[2] * rhat[2];
        let mimj = mi[0] * mj[0] + mi[1] * mj[1] + mi[2] * mj[2];
        let scale = PREFACTOR * (inv * inv) * (inv * inv);
        let radial = mimj - 5.0 * mir * mjr;
        ox[j] = scale * (mir * mj[0] + mjr * mi[0] + radial * rhat[0]);
        oy[j] = scale * (mir * mj[1] + mjr * mi[1] + radial * rhat[1]);
        oz[j] = scale * (mir * mj[2] + mjr * mi[2] + radial * rhat[2]);
    }
}

/// Adds Σ_j F_ij over all pairs to `force` (see the module note on the two orders).
fn add_all_pairs(position: &[Vec3], moment: &[Vec3], domain: &Domain, force: &mut [Vec3], columns: &mut Columns) {
    let n = position.len();
    columns.fill(position, moment);
    let length = [0, 1, 2].map(|k| if domain.periodic[k] { domain.hi[k] - domain.lo[k] } else { 0.0 });
    let image = Image { length, inverse: length.map(|l| if l > 0.0 { 1.0 / l } else { 0.0 }) };
    let sum = |v: &[f64]| v.iter().fold(0.0, |a, b| a + b);
    if n < parallel::MIN_PARALLEL_LEN {
        let mut row: [Vec<f64>; 3] = Default::default();
        for i in 0..n {
            row_forces(columns, &image, i, i + 1..n, &mut row);
            force[i] += Vec3::new(sum(&row[0]), sum(&row[1]), sum(&row[2]));
            for (k, (fx, (fy, fz))) in row[0].iter().zip(row[1].iter().zip(&row[2])).enumerate() {
                force[i + 1 + k] -= Vec3::new(*fx, *fy, *fz);
            }
        }
    } else {
        use rayon::prelude::*;
        let columns = &*columns;
        let rows: Vec<Vec3> = (0..n)
            .into_par_iter()
            .with_min_len(64)
            .map_init(
                || (<[Vec<f64>; 3]>::default(), <[Vec<f64>; 3]>::default()),
                |(before, after), i| {
                    row_forces(columns, &image, i, 0..i, before);
                    row_forces(columns, &image, i, i + 1..n, after);
                    Vec3::from_fn(|k, _| sum(&before[k]) + sum(&after[k]))
                },
            )
            .collect();
        force.iter_mut().zip(&rows).for_each(|(f, row)| *f += row);
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
}

impl DipoleForce {
    pub fn new(cutoff: Option<f64>, b0: Vec3, gradient: Matrix3<f64>) -> Self {
        Self { cutoff, b0, gradient, verlet: VerletList::default(), pairs: vec![], buffer: vec![], columns: Columns::default() }
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
        // The moments phase already found the pairs when its range is this cut-off.
        let pairs: Option<&[Pair]> = match (ctx.magnetic_pairs, self.cutoff) {
            (Some((range, pairs)), _) if range == self.cutoff => Some(pairs),
            (_, Some(c)) => {
                self.verlet.pairs_within(&p.position, ctx.domain, c, c / 15.0, &mut self.pairs);
                Some(&self.pairs)
            }
            (_, None) => None,
        };
        match pairs {
            Some(pairs) => add_listed_pairs(pairs, &p.moment, &mut p.force, &mut self.buffer),
            None => add_all_pairs(&p.position, &p.moment, ctx.domain, &mut p.force, &mut self.columns),
        }
        if p.has_permanent_moments {
            // B_loc = B_ext + μ0 Σ_j H_dip,j over the same pairs as the force.
            let mut b_loc: Vec<Vec3> = p.position.iter().map(|x| self.b0 + self.gradient * x).collect();
            let mut add = |i: usize, j: usize, r: &Vec3, dist: f64| {
                b_loc[i] += MU0 * dipole_field(&p.moment[j], r, dist);
                b_loc[j] += MU0 * dipole_field(&p.moment[i], &(-r), dist);
            };
            match pairs {
                Some(pairs) => pairs.iter().for_each(|pair| add(pair.i as usize, pair.j as usize, &pair.r, pair.dist)),
                None => {
                    for i in 0..p.len() {
                        for j in i + 1..p.len() {
                            let r = ctx.domain.displacement(&p.position[i], &p.position[j]);
                            add(i, j, &r, r.norm());
                        }
                    }
                }
            }
            for ((torque, m), b) in p.torque.iter_mut().zip(&p.permanent_moment).zip(&b_loc) {
                *torque += m.cross(b);
            }
        }
    }
}
