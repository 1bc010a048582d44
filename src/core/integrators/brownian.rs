//! Overdamped Brownian dynamics, Euler–Maruyama (Ermak & McCammon, J. Chem. Phys. 69, 1352
//! (1978), without hydrodynamic interactions): over a step h, with the forces and torques of the
//! state at its start,
//!
//!   x ← x + (u_f + μ_t F) h + √(2 D_t h) ξ,  μ_t = 1/(6π μ a),  D_t = kT μ_t,
//!   m_perm ← R(μ_r T h + √(2 D_r h) ξ_r) m_perm,  μ_r = 1/(8π μ a³),  D_r = kT μ_r,
//!
//! R(φ) the rotation by |φ| about φ (Rodrigues), ξ, ξ_r independent standard normal 3-vectors.
//! The mobilities are Stokes's, from `[forces.drag]` (its viscosity) and `kT` from
//! `[forces.thermal]`; the scheme takes both over, so that the drag and the thermal forces are not
//! applied as forces. The mobility is constant, so the Itô drift kT ∇·μ is zero: no drift term.
//! The velocities are the drift velocities of the step, v = u_f + μ_t F and ω = μ_r T (the noise's
//! displacement has no velocity; Δx/h would grow as h^(−1/2)). ξ is drawn from the scene's seed,
//! the step the move starts at and the particle's id, in streams of its own
//! ([`Stream::BrownianTranslation`], [`Stream::BrownianRotation`]): the same bits on any number of
//! threads and after `--resume`. docs/model.md §14.

use super::Renumbering;
use super::{displacement_bound, step, tick, Evaluate, ForceGroup, Integrator, IntegratorContext, IntegratorSpec};
use crate::core::forces::thermal::BOLTZMANN;
use crate::core::noise::{Noise, Stream};
use crate::core::parallel;
use crate::core::state::{State, Vec3};
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

pub struct Brownian {
    /// kT (J).
    pub kt: f64,
    /// μ (Pa s) of the Stokes mobilities.
    pub viscosity: f64,
    /// u_f (m/s), uniform.
    pub fluid_velocity: Vec3,
    pub noise: Noise,
}

impl Brownian {
    /// μ_t = 1/(6π μ a).
    fn translational_mobility(&self, a: f64) -> f64 {
        1.0 / (6.0 * PI * self.viscosity * a)
    }

    /// μ_r = 1/(8π μ a³).
    fn rotational_mobility(&self, a: f64) -> f64 {
        1.0 / (8.0 * PI * self.viscosity * a * a * a)
    }

    /// One Euler–Maruyama move over `h` from the forces and torques in `state.fields`, with the
    /// noise of step `state.step`.
    fn advance(&self, state: &mut State, h: f64) {
        let State { particles: p, fields, ids, step: n, .. } = state;
        let (n, ids) = (*n, &ids[..]);
        let id = |slot: usize| ids.get(slot).map_or(slot as u32, |&id| id);
        let (force, torque, radius) = (&fields.force[..], &fields.torque[..], &p.radius[..]);
        let (v, w) = (&mut p.velocity[..], &mut p.angular_velocity[..]);
        let largest = AtomicU64::new(0);
        p.position.drift(|x| {
            parallel::for_each_share((x, v, (force, radius)), |first, (x, v, (f, a))| {
                let mut moved = 0;
                for k in 0..x.len() {
                    let mobility = self.translational_mobility(a[k]);
                    let spread = (2.0 * self.kt * mobility * h).sqrt();
                    let xi = self.noise.normal3(n, id(first + k), Stream::BrownianTranslation);
                    v[k] = self.fluid_velocity + f[k] * mobility;
                    moved = (0..3).fold(moved, |m, c| step(m, &mut x[k][c], v[k][c] * h + spread * xi[c]));
                }
                largest.fetch_max(moved, Ordering::Relaxed);
            });
            displacement_bound(largest.into_inner())
        });
        let turn = p.has_permanent_moments;
        parallel::for_each_share((w, &mut p.permanent_moment[..], (torque, radius)), |first, (w, m, (t, a))| {
            for k in 0..w.len() {
                let mobility = self.rotational_mobility(a[k]);
                w[k] = t[k] * mobility;
                if turn && m[k] != Vec3::zeros() {
                    let spread = (2.0 * self.kt * mobility * h).sqrt();
                    let xi = Vec3::from(self.noise.normal3(n, id(first + k), Stream::BrownianRotation));
                    m[k] = nalgebra::Rotation3::new(w[k] * h + xi * spread) * m[k];
                }
            }
        });
    }
}

impl Integrator for Brownian {
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        self.advance(state, dt);
        tick(state, dt);
        evaluate(state, ForceGroup::All, dt);
    }
    /// Holds nothing per particle: the mobilities come from the radii, the noise from the ids.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `scheme = "brownian"`: no keys of its own. It needs `[forces.thermal]` (kT) and a Stokes
/// `[forces.drag]` with its rotational part (the mobilities).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct BrownianSpec {}

impl IntegratorSpec for BrownianSpec {
    /// The drag enters as the mobility: the drag term applies none of its (Stokes) force.
    fn integrates_linear_drag(&self) -> bool {
        true
    }
    fn overdamped(&self) -> bool {
        true
    }
    /// Refuses a scene without the temperature or the Stokes mobilities the scheme takes.
    fn build(&self, ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(Brownian {
            kt: BOLTZMANN * ctx.temperature,
            viscosity: ctx.viscosity,
            fluid_velocity: ctx.fluid_velocity,
            noise: Noise { seed: ctx.seed },
        })
    }
}
