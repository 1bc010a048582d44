//! Hydrodynamic interactions in Stokes flow: the Rotne–Prager–Yamakawa far-field mobility with
//! the regularised forms for overlapping spheres of unequal radii (Zuk, Wajnryb, Mizerski &
//! Szymczak, J. Fluid Mech. 741, R5, 2014). For spheres i ≠ j, r = x_i − x_j, r̂ = r/|r|:
//!
//! - apart, r > a_i + a_j:   M_ij = 1/(8π μ r) [(1 + (a_i² + a_j²)/(3r²)) I + (1 − (a_i² + a_j²)/r²) r̂r̂]
//! - overlapping, |a_i − a_j| < r ≤ a_i + a_j: M_ij = 1/(6π μ a_i a_j) [A I + B r̂r̂] with
//!   A = (16 r³ (a_i + a_j) − ((a_i − a_j)² + 3r²)²)/(32 r³), B = 3((a_i − a_j)² − r²)²/(32 r³)
//! - one inside the other, r ≤ |a_i − a_j|:   M_ij = I/(6π μ max(a_i, a_j))
//! - self: M_ii = I/(6π μ a_i)
//!
//! In an unbounded fluid the 3N × 3N mobility is symmetric positive definite for any configuration
//! (above a wall, [`super::blake`], for spheres that do not overlap); the drag is
//! F_h = −R (U − u_f) with R = M⁻¹, formed from a Cholesky factor of M (faer). docs/model.md §7.

use super::setup::Fluid;
use super::wall_drag::PlaneWall;
use super::{Context, ForceTerm, Forces, Renewal, Renumbering, TermError};
use crate::core::state::{Particles, State, Vec3};
use faer::linalg::solvers::DenseSolveCore;
use nalgebra::Matrix3;
use std::f64::consts::PI;

/// The mobility block M_ij (m/(N s)) coupling the velocity of sphere i to the force on sphere j.
pub fn pair_mobility(a_i: f64, a_j: f64, r: &Vec3, viscosity: f64) -> Matrix3<f64> {
    let d = r.norm();
    let rr = if d > 0.0 { (r / d) * (r / d).transpose() } else { Matrix3::zeros() };
    let id = Matrix3::identity();
    if d > a_i + a_j {
        let s = (a_i * a_i + a_j * a_j) / (d * d);
        (id * (1.0 + s / 3.0) + rr * (1.0 - s)) / (8.0 * PI * viscosity * d)
    } else if d > (a_i - a_j).abs() {
        let diff2 = (a_i - a_j).powi(2);
        let d3 = d * d * d;
        let iso = (16.0 * d3 * (a_i + a_j) - (diff2 + 3.0 * d * d).powi(2)) / (32.0 * d3);
        let aniso = 3.0 * (diff2 - d * d).powi(2) / (32.0 * d3);
        (id * iso + rr * aniso) / (6.0 * PI * viscosity * a_i * a_j)
    } else {
        id / (6.0 * PI * viscosity * a_i.max(a_j))
    }
}

/// The dense 3N × 3N mobility of spheres at `positions` with `radii`: an unbounded fluid, or above
/// `wall` (equal radii, [`super::blake`]).
pub fn mobility(positions: &[Vec3], radii: &[f64], viscosity: f64, wall: Option<&PlaneWall>) -> faer::Mat<f64> {
    let n = positions.len();
    let mut m = faer::Mat::<f64>::zeros(3 * n, 3 * n);
    for i in 0..n {
        for k in 0..3 {
            m[(3 * i + k, 3 * i + k)] = 1.0 / (6.0 * PI * viscosity * radii[i]);
        }
        for j in i + 1..n {
            let block = pair_mobility(radii[i], radii[j], &(positions[i] - positions[j]), viscosity);
            for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                m[(3 * i + r, 3 * j + c)] = block[(r, c)];
                m[(3 * j + r, 3 * i + c)] = block[(c, r)];
            }
        }
    }
    if let (Some(wall), Some(&a)) = (wall, radii.first()) {
        for (i, j, block) in wall.corrections(positions, a, viscosity) {
            for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                m[(3 * i + r, 3 * j + c)] += block[(r, c)];
                if i != j {
                    m[(3 * j + r, 3 * i + c)] += block[(c, r)];
                }
            }
        }
    }
    m
}

/// The resistance R = M⁻¹ of a configuration, from the Cholesky factor of its mobility: the
/// forces R U that move the spheres at U. Kept explicit so that each drag is one matrix–vector
/// product (a refreshed factor serves many steps).
pub struct Resistance {
    inverse: faer::Mat<f64>,
}

/// The mobility is not positive definite: in an unbounded fluid it always is (a failure means
/// non-finite positions or radii); above a wall, spheres that overlap may also cause it.
#[derive(Debug, Clone, thiserror::Error)]
#[error("the RPY mobility of {particles} spheres has no Cholesky factor (non-finite positions or radii, or overlaps near the wall)")]
pub struct NotPositiveDefinite {
    pub particles: usize,
}

impl Resistance {
    pub fn new(
        positions: &[Vec3],
        radii: &[f64],
        viscosity: f64,
        wall: Option<&PlaneWall>,
    ) -> Result<Self, NotPositiveDefinite> {
        let m = mobility(positions, radii, viscosity, wall);
        let factor = m.llt(faer::Side::Lower).map_err(|_| NotPositiveDefinite { particles: positions.len() })?;
        Ok(Self { inverse: factor.inverse() })
    }

    /// The hydrodynamic forces F_h = −M⁻¹ (U − u_f) on spheres moving at `velocity`, the
    /// background flow u_f(x_k) at sphere k given by `fluid_velocity(k)` (Faxén's a²∇²u/6 left
    /// out: docs/assumptions.md).
    pub fn drag(&self, velocity: &[Vec3], fluid_velocity: impl Fn(usize) -> Vec3) -> Vec<Vec3> {
        let mut f = vec![Vec3::zeros(); velocity.len()];
        let out: &mut [f64] = bytemuck::cast_slice_mut(&mut f);
        // F = −Σ_k R[:, k] u_k over R's contiguous columns (R is symmetric).
        for (k, v) in velocity.iter().enumerate() {
            let u = v - fluid_velocity(k);
            for c in 0..3 {
                let column = self.inverse.col_as_slice(3 * k + c);
                out.iter_mut().zip(column).for_each(|(o, r)| *o -= r * u[c]);
            }
        }
        f
    }
}

/// Drag with hydrodynamic interactions (RPY): F_h = −M⁻¹ (U − u_f) on every sphere, with each
/// evaluation's velocities, the mobility factorised every `refactor_every` steps from the
/// positions of the evaluation that renews it ([`Renewal`]: every evaluation for 1; a resumed run
/// renews where the uninterrupted one did).
/// With `rotational`, each sphere's own rotational Stokes drag −8π μ a³ ω (no rotational
/// coupling). A factorisation failure (non-finite positions) leaves the force non-finite, which
/// the run's monitor reports.
pub struct RpyDrag {
    pub fluid: Fluid,
    pub rotational: bool,
    /// A no-slip wall the spheres move above (its image system in the mobility), or none.
    pub wall: Option<PlaneWall>,
    resistance: Option<Result<Resistance, NotPositiveDefinite>>,
    /// When the factor is renewed (every `refactor_every` steps).
    renewal: Renewal,
}

impl RpyDrag {
    pub fn new(fluid: Fluid, rotational: bool, refactor_every: u64) -> Self {
        Self { fluid, rotational, wall: None, resistance: None, renewal: Renewal::every(refactor_every) }
    }
}

impl ForceTerm for RpyDrag {
    fn name(&self) -> &'static str {
        "drag"
    }
    fn begin_step(&mut self, state: &State) {
        self.renewal.begin_step(state.step);
    }
    fn prepare(&mut self, _ctx: &Context, state: &State) -> Result<(), TermError> {
        if self.renewal.now(self.resistance.is_some()) {
            let p = &state.particles;
            self.resistance = Some(Resistance::new(&p.position, &p.radius, self.fluid.viscosity, self.wall.as_ref()));
        }
        Ok(())
    }
    fn apply(&mut self, ctx: &Context, p: &Particles, out: &mut Forces) {
        let flow = &self.fluid.flow;
        let fluid_velocity = |k: usize| flow.velocity(p.position[k], ctx.time);
        match self.resistance.as_ref().expect("prepared before applied") {
            Ok(r) => {
                for (f, d) in out.force.iter_mut().zip(r.drag(&p.velocity, fluid_velocity)) {
                    *f += d;
                }
            }
            Err(_) => out.force.iter_mut().for_each(|f| *f = Vec3::repeat(f64::NAN)),
        }
        if self.rotational {
            for ((t, w), a) in out.torque.iter_mut().zip(&p.angular_velocity).zip(&p.radius) {
                *t -= 8.0 * PI * self.fluid.viscosity * a.powi(3) * w;
            }
        }
    }
    /// The factorised mobility is dropped and factorised again at the next evaluation, from the
    /// positions then: with `refactor_every` > 1 a renumbering is a renewal.
    fn renumber(&mut self, _r: &Renumbering) {
        self.resistance = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal radii: Zuk's overlapping form reduces to the classic regularised RPY,
    /// (1/(6π μ a)) [(1 − 9r/(32a)) I + 3r/(32a) r̂r̂], and both forms meet at contact.
    #[test]
    fn overlapping_form_reduces_to_classic_rpy_and_is_continuous_at_contact() {
        let (a, mu) = (1.0, 1.0 / (6.0 * PI));
        for d in [0.3, 1.0, 1.7, 2.0] {
            let m = pair_mobility(a, a, &Vec3::new(d, 0.0, 0.0), mu);
            let (iso, aniso) = (1.0 - 9.0 * d / 32.0, 3.0 * d / 32.0);
            assert!((m[(0, 0)] - (iso + aniso)).abs() < 1e-14, "d = {d}: axial {}", m[(0, 0)]);
            assert!((m[(1, 1)] - iso).abs() < 1e-14, "d = {d}: transverse {}", m[(1, 1)]);
        }
        for (ai, aj) in [(1.0, 1.0), (1.0, 0.4)] {
            let at = |d: f64| pair_mobility(ai, aj, &Vec3::new(d, 0.0, 0.0), mu);
            let (inside, outside) = (at((ai + aj) * (1.0 - 1e-12)), at((ai + aj) * (1.0 + 1e-12)));
            assert!((inside - outside).norm() < 1e-10 * outside.norm(), "radii {ai}, {aj}");
        }
    }

    /// Unequal radii, a_2 = λ a_1. Apart, the pair block is the Rotne–Prager truncation of the
    /// exact two-sphere mobility: Jeffrey & Onishi's (J. Fluid Mech. 139, 261, 1984) far-field
    /// series, u_1 = [x dd + y (I − dd)] F_2 / (3π μ (a_1 + a_2)) with s = 2r/(a_1 + a_2),
    /// x = 3/(2s) − 2(1 + λ²)/((1 + λ)² s³) + O(s⁻⁷), y = 3/(4s) + (1 + λ²)/((1 + λ)² s³) + O(s⁻⁵).
    /// Inside, where the smaller sphere lies within the larger (r ≤ |a_1 − a_2|), the block is the
    /// larger sphere's self-mobility, and the overlapping form meets it there (Zuk et al. 2014).
    #[test]
    fn unequal_spheres_follow_the_published_far_field_series_and_meet_the_inner_limit() {
        let (a1, mu) = (1.0e-6, 1.0e-3);
        for lambda in [0.25_f64, 0.5, 2.0, 4.0] {
            let a2 = lambda * a1;
            let k = (1.0 + lambda * lambda) / (1.0 + lambda).powi(2);
            for s in [2.5_f64, 4.0, 10.0, 40.0] {
                let r = 0.5 * s * (a1 + a2);
                let m = pair_mobility(a1, a2, &Vec3::new(0.0, 0.0, r), mu) * (3.0 * PI * mu * (a1 + a2));
                let (x, y) = (1.5 / s - 2.0 * k / s.powi(3), 0.75 / s + k / s.powi(3));
                assert!((m[(2, 2)] / x - 1.0).abs() < 1e-12, "λ = {lambda}, s = {s}: x {} vs {x}", m[(2, 2)]);
                assert!((m[(0, 0)] / y - 1.0).abs() < 1e-12, "λ = {lambda}, s = {s}: y {} vs {y}", m[(0, 0)]);
                assert!(m[(0, 2)].abs() < 1e-15 && m[(0, 1)].abs() < 1e-15, "λ = {lambda}: off-axis coupling");
            }
            let inner = (a1 - a2).abs();
            let self_mobility = 1.0 / (6.0 * PI * mu * a1.max(a2));
            for d in [0.5 * inner, inner * (1.0 - 1e-12), inner * (1.0 + 1e-12)] {
                let m = pair_mobility(a1, a2, &Vec3::new(d, 0.0, 0.0), mu);
                let expected = Matrix3::identity() * self_mobility;
                assert!((m - expected).norm() < 1e-9 * self_mobility, "λ = {lambda}, r = {d:e}: {m:?}");
            }
        }
    }
}
