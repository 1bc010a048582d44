//! Explicit (forward) Euler, the paper's scheme: x' = x + v dt, v' = v + F(x, v)/m dt.
//! First order; unconditionally unstable for an undamped oscillator.

use super::ForceGroup;
use super::{drift, kick, tick, Evaluate, Integrator, Renumbering};
use crate::core::state::State;

pub struct ExplicitEuler;

impl Integrator for ExplicitEuler {
    fn name(&self) -> &'static str {
        "explicit-euler"
    }
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        drift(state, dt);
        kick(state, dt);
        tick(state, dt);
        evaluate(state, ForceGroup::All, dt);
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}
