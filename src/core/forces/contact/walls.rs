//! Wall geometry: which particles touch which walls, apart from the contact law. Walls stand on
//! the faces of non-periodic axes (faces 0–5: x-lo, x-hi, y-lo, …) and, in a vessel, on its
//! cylindrical surface ([`VESSEL_FACE`]). A particle touches a wall when its centre is closer to
//! it than its radius (overlap a − gap, normal pointing into the fluid).

use crate::core::domain::Domain;
use crate::core::flow::Vessel;
use crate::core::parallel::{self, Pieces};
use crate::core::state::{Particles, Vec3, WallFace};

/// The wall face of a vessel's cylindrical surface (after the box's six).
pub const VESSEL_FACE: WallFace = 6;

/// A particle touching a wall: (particle, face, unit normal into the fluid, overlap).
#[derive(Clone, Copy, Default)]
pub struct WallTouch {
    pub i: u32,
    pub face: WallFace,
    pub normal: Vec3,
    pub overlap: f64,
}

/// The wall search, with the particles that may touch a wall before the near list's next
/// rebuild kept between calls.
#[derive(Default)]
pub struct WallScan {
    /// Candidates (`None`: not known yet, test every particle).
    candidates: Option<Vec<u32>>,
    /// Buffers of the parallel scans.
    candidate_pieces: Pieces<u32>,
    found_pieces: Pieces<WallTouch>,
}

impl WallScan {
    /// Drops the candidates (their particle indices no longer hold).
    pub fn forget(&mut self) {
        self.candidates = None;
    }

    /// Every wall contact into `found`, in particle then face order. `rebuilt`: the near
    /// list's skin when it was rebuilt in this evaluation — until the next rebuild no particle
    /// moves more than skin/2, so only particles within a radius plus half the skin of a wall
    /// can touch it, and only those are tested.
    ///
    /// A `vessel`'s surface is a wall at distance R from its axis: gap R − ρ at a centre a
    /// distance ρ from the axis, normal −ρ̂ (LIGGGHTS' `zcylinder` seen from inside).
    pub fn find(
        &mut self,
        p: &Particles,
        domain: &Domain,
        vessel: Option<&Vessel>,
        rebuilt: Option<f64>,
        found: &mut Vec<WallTouch>,
    ) {
        // Walls on periodic axes are infinitely far away.
        let lo = Vec3::from_fn(|k, _| if domain.periodic[k] { f64::NEG_INFINITY } else { domain.lo[k] });
        let hi = Vec3::from_fn(|k, _| if domain.periodic[k] { f64::INFINITY } else { domain.hi[k] });
        // The centre's offset from the vessel's axis, and the gap to its surface.
        let radial = |x: &Vec3| {
            vessel.map(|v| {
                let d = x - v.centre;
                let off = d - d.dot(&v.axis) * v.axis.into_inner();
                let rho = off.norm();
                (off, rho, v.radius - rho)
            })
        };
        let near = |i: usize, margin: f64| {
            let (a, x) = (p.radius[i] + margin, p.position[i]);
            (x.x - lo.x < a)
                | (x.y - lo.y < a)
                | (x.z - lo.z < a)
                | (hi.x - x.x < a)
                | (hi.y - x.y < a)
                | (hi.z - x.z < a)
                | radial(&x).is_some_and(|(_, _, gap)| gap < a)
        };
        if let Some(skin) = rebuilt {
            let mut candidates = self.candidates.take().unwrap_or_default();
            parallel::collect_ordered(p.len(), &mut candidates, &mut self.candidate_pieces, |i, out| {
                if near(i, 0.5 * skin) {
                    out.push(i as u32);
                }
            });
            self.candidates = Some(candidates);
        }
        let touches = |i: usize, out: &mut Vec<WallTouch>| {
            if !near(i, 0.0) {
                return;
            }
            let (a, x) = (p.radius[i], p.position[i]);
            for axis in 0..3 {
                for (upper, gap) in [(false, x[axis] - lo[axis]), (true, hi[axis] - x[axis])] {
                    if gap < a {
                        let face = (2 * axis + upper as usize) as WallFace;
                        let mut normal = Vec3::zeros();
                        normal[axis] = if upper { -1.0 } else { 1.0 };
                        out.push(WallTouch { i: i as u32, face, normal, overlap: a - gap });
                    }
                }
            }
            if let Some((off, rho, gap)) = radial(&x).filter(|&(_, rho, gap)| gap < a && rho > 0.0) {
                out.push(WallTouch { i: i as u32, face: VESSEL_FACE, normal: -off / rho, overlap: a - gap });
            }
        };
        match &self.candidates {
            Some(candidates) => parallel::collect_ordered(candidates.len(), found, &mut self.found_pieces, |k, out| {
                touches(candidates[k] as usize, out)
            }),
            None => parallel::collect_ordered(p.len(), found, &mut self.found_pieces, touches),
        }
    }
}
