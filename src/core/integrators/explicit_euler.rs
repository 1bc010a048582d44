//! Explicit (forward) Euler, the paper's scheme: x' = x + v dt, v' = v + F(x, v)/m dt.
//! First order; unconditionally unstable for an undamped oscillator.

use super::ForceGroup;
use super::{drift, kick, tick, Evaluate, Integrator, IntegratorContext, IntegratorSpec, Renumbering};
use crate::core::state::State;

pub struct ExplicitEuler;

impl Integrator for ExplicitEuler {
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        drift(state, dt);
        kick(state, dt);
        tick(state, dt);
        evaluate(state, ForceGroup::All, dt);
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `scheme = "explicit-euler"`: no keys of its own.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ExplicitEulerSpec {}

impl IntegratorSpec for ExplicitEulerSpec {
    fn forward_euler_in_contact(&self) -> bool {
        true
    }
    fn build(&self, _ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(ExplicitEuler)
    }
}
