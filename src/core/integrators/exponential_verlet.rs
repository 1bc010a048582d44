//! Velocity Verlet with the linear drag integrated exactly (exponential time differencing): each
//! half kick solves m dv/dt = F − γ (v − u_f) exactly with F held at its evaluated value,
//!
//!   v ← u_f + (v − u_f) e^{−x} + (F h/m) (1 − e^{−x})/x,  x = γ h/m,
//!
//! and likewise for ω with the rotational drag γ_r = 8π μ a³, while the drag term leaves these
//! linear parts out (`Drag::exclude_linear`). Second order and time-symmetric like Verlet; exact
//! for the terminal velocity at any dt, so the drag relaxation time m/γ no longer limits dt
//! (contact still does) — what sub-micron particles need. At γ = 0 it is velocity Verlet.

use super::ForceGroup;
use super::{advance, drift, tick, Evaluate, Integrator, IntegratorContext, IntegratorSpec, Kick, Renumbering};
use crate::core::state::{State, Vec3};

pub struct ExponentialVerlet {
    /// Linear drag coefficient 6π μ a per particle (kg/s).
    pub gamma: Vec<f64>,
    /// Rotational drag coefficient 8π μ a³ per particle (kg m²/s).
    pub gamma_rotational: Vec<f64>,
    pub fluid_velocity: Vec3,
}

impl ExponentialVerlet {
    fn half_kick(&self, state: &mut State, h: f64) {
        let kick = Kick::Exponential {
            h,
            gamma: &self.gamma,
            gamma_rotational: &self.gamma_rotational,
            fluid_velocity: self.fluid_velocity,
        };
        advance(&mut state.particles, &state.fields.force, &state.fields.torque, kick, 0.0);
    }
}

impl Integrator for ExponentialVerlet {
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        self.half_kick(state, 0.5 * dt);
        drift(state, dt);
        tick(state, dt);
        evaluate(state, ForceGroup::All, dt);
        self.half_kick(state, 0.5 * dt);
    }
    fn renumber(&mut self, r: &Renumbering) {
        r.permute(&mut self.gamma);
        r.permute(&mut self.gamma_rotational);
    }
}

/// `scheme = "exponential-verlet"`: no keys of its own; it takes each particle's drag
/// coefficients from the scene.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExponentialVerletSpec {}

impl IntegratorSpec for ExponentialVerletSpec {
    fn integrates_linear_drag(&self) -> bool {
        true
    }
    fn build(&self, ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(ExponentialVerlet {
            gamma: ctx.linear_drag.to_vec(),
            gamma_rotational: ctx.rotational_drag.to_vec(),
            fluid_velocity: ctx.fluid_velocity,
        })
    }
}
