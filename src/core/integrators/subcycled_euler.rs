//! The paper's pipeline as a CFD-DEM code runs it: an outer explicit-Euler step of K·dt for the
//! slow (magnetic) forces, with collisions resolved in sub-steps. The moments and magnetic
//! forces are evaluated once, at the start of each outer step, and held constant through it
//! (forward Euler in them: first order in K·dt); contact, drag and gravity are integrated by K
//! velocity-Verlet sub-steps of dt that see the held magnetic force as a constant one. With
//! K·dt = 1e-6 s this is the paper's explicit-Euler step with its collisions sub-cycled, as
//! OpenFOAM's colliding clouds do.

use super::ForceGroup;
use super::{check_slow_every, every_step};
use super::{kick, kick_drift, slow_kick, tick, Evaluate, Integrator, IntegratorContext, IntegratorSpec, Renumbering};
use crate::core::checks::Invalid;
use crate::core::state::State;

pub struct SubcycledEuler {
    /// K: collision sub-steps per outer (magnetic) step.
    pub slow_every: u64,
}

impl Integrator for SubcycledEuler {
    fn steps_per_call(&self) -> u64 {
        self.slow_every
    }
    fn splits_forces(&self) -> bool {
        true
    }
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        for _ in 0..self.slow_every {
            slow_kick(state, 0.5 * dt);
            kick_drift(state, 0.5 * dt, dt);
            tick(state, dt);
            evaluate(state, ForceGroup::Fast, dt);
            kick(state, 0.5 * dt);
            slow_kick(state, 0.5 * dt);
        }
        evaluate(state, ForceGroup::Slow, dt);
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `scheme = "subcycled-euler"`: `slow_every`, K fast steps per evaluation of the moments and magnetic
/// forces (default 1). It must divide the steps per output frame and the run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct SubcycledEulerSpec {
    #[serde(default = "every_step")]
    pub slow_every: u64,
}

impl Default for SubcycledEulerSpec {
    fn default() -> Self {
        Self { slow_every: every_step() }
    }
}

impl IntegratorSpec for SubcycledEulerSpec {
    fn check(&self) -> Result<(), Invalid> {
        check_slow_every(self.slow_every)
    }
    fn slow_every(&self) -> u64 {
        self.slow_every
    }
    fn build(&self, _ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(SubcycledEuler { slow_every: self.slow_every })
    }
}
