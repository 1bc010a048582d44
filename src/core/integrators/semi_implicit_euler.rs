//! Semi-implicit (symplectic) Euler: v' = v + F(x, v)/m dt, x' = x + v' dt. First order,
//! stable for an oscillator while ω dt < 2.

use super::ForceGroup;
use super::{kick_drift, tick, Evaluate, Integrator, IntegratorContext, IntegratorSpec, Renumbering};
use crate::core::state::State;

pub struct SemiImplicitEuler;

impl Integrator for SemiImplicitEuler {
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        kick_drift(state, dt, dt);
        tick(state, dt);
        evaluate(state, ForceGroup::All, dt);
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `scheme = "semi-implicit-euler"`: no keys of its own.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SemiImplicitEulerSpec {}

impl IntegratorSpec for SemiImplicitEulerSpec {
    fn build(&self, _ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(SemiImplicitEuler)
    }
}
