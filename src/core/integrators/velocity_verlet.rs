//! Velocity Verlet as in LAMMPS/LIGGGHTS `fix nve/sphere`: half kick, drift, forces (velocity-
//! dependent ones see the half-step velocity), half kick. Second order for position-dependent
//! forces; stable for an oscillator while ω dt < 2.

use super::ForceGroup;
use super::{kick, kick_drift, tick, Evaluate, Integrator, IntegratorContext, IntegratorSpec, Renumbering};
use crate::core::state::State;

pub struct VelocityVerlet;

impl Integrator for VelocityVerlet {
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        kick_drift(state, 0.5 * dt, dt);
        tick(state, dt);
        evaluate(state, ForceGroup::All, dt);
        kick(state, 0.5 * dt);
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `scheme = "velocity-verlet"`: no keys of its own.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityVerletSpec {}

impl IntegratorSpec for VelocityVerletSpec {
    fn build(&self, _ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(VelocityVerlet)
    }
}
