//! Dipole–dipole force between the particles' moments, on i from j with r = x_i − x_j:
//!
//!   F_ij = 3μ0/(4π r⁴) [ (m_i·r̂) m_j + (m_j·r̂) m_i + (m_i·m_j) r̂ − 5 (m_i·r̂)(m_j·r̂) r̂ ]
//!
//! summed over all pairs or, with a cut-off, over pairs closer than it (cell list). The torque
//! T_i = m_perm,i × B_loc,i acts only on permanent moments: an induced moment of a linear sphere is
//! parallel to its local field.

use super::{ForceContext, ForceTerm};
use crate::core::magnetisation::{dipole_field, MU0};
use crate::core::neighbours::{CellList, Pair, VerletList};
use crate::core::state::{State, Vec3};
use nalgebra::Matrix3;
use std::f64::consts::PI;

/// Force on a dipole `mi` at r (relative to `mj`), `r = x_i − x_j`, `dist = |r|`.
#[inline]
pub fn dipole_pair_force(mi: &Vec3, mj: &Vec3, r: &Vec3, dist: f64) -> Vec3 {
    let rhat = r / dist;
    let (mir, mjr) = (mi.dot(&rhat), mj.dot(&rhat));
    3.0 * MU0 / (4.0 * PI * dist.powi(4)) * (mir * mj + mjr * mi + (mi.dot(mj) - 5.0 * mir * mjr) * rhat)
}

pub struct DipoleForce {
    /// Pair cut-off distance (m); `None` = all pairs.
    pub cutoff: Option<f64>,
    /// Applied field, for the torque on permanent moments.
    pub b0: Vec3,
    pub gradient: Matrix3<f64>,
    cells: CellList,
    verlet: VerletList,
    pairs: Vec<Pair>,
}

impl DipoleForce {
    pub fn new(cutoff: Option<f64>, b0: Vec3, gradient: Matrix3<f64>) -> Self {
        Self { cutoff, b0, gradient, cells: CellList::default(), verlet: VerletList::default(), pairs: vec![] }
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
        let pairs: &[Pair] = match ctx.magnetic_pairs {
            Some((range, pairs)) if range == self.cutoff => pairs,
            _ => {
                match self.cutoff {
                    Some(c) => self.verlet.pairs_within(&p.position, ctx.domain, c, c / 15.0, &mut self.pairs),
                    None => self.cells.pairs_within(&p.position, ctx.domain, None, &mut self.pairs),
                }
                &self.pairs
            }
        };
        let torques = p.permanent_moment.iter().any(|m| *m != Vec3::zeros());
        for pair in pairs {
            let (i, j) = (pair.i as usize, pair.j as usize);
            let f = dipole_pair_force(&p.moment[i], &p.moment[j], &pair.r, pair.dist);
            p.force[i] += f;
            p.force[j] -= f;
        }
        if torques {
            let mut b_loc: Vec<Vec3> = p.position.iter().map(|x| self.b0 + self.gradient * x).collect();
            for pair in pairs {
                let (i, j) = (pair.i as usize, pair.j as usize);
                b_loc[i] += MU0 * dipole_field(&p.moment[j], &pair.r, pair.dist);
                b_loc[j] += MU0 * dipole_field(&p.moment[i], &(-pair.r), pair.dist);
            }
            for ((torque, m), b) in p.torque.iter_mut().zip(&p.permanent_moment).zip(&b_loc) {
                *torque += m.cross(b);
            }
        }
    }
}
