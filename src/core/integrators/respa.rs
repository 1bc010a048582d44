//! Multiple time stepping (r-RESPA, Tuckerman, Berne & Martyna 1992, "impulse" form) with
//! velocity Verlet inside: the slow (magnetic) forces kick for half an outer step K·dt at its
//! start and end, and the fast forces (contact, drag, gravity) are integrated by K Verlet steps
//! of dt in between. The moments and dipole sums are computed once per K steps. Second order and
//! time-reversible for smooth slow forces; like every impulse scheme it can resonate when K·dt
//! approaches half the period of a fast oscillation, which the stability studies measure.

use super::ForceGroup;
use super::{check_slow_every, every_step};
use super::{
    kick, kick_twice_drift, slow_kick, slow_kick_then_kick_drift, tick, Evaluate, Integrator, IntegratorContext,
    IntegratorSpec, Renumbering,
};
use crate::core::checks::Invalid;
use crate::core::state::State;

pub struct Respa {
    /// K: fast steps per slow evaluation.
    pub slow_every: u64,
}

impl Integrator for Respa {
    fn steps_per_call(&self) -> u64 {
        self.slow_every
    }
    fn splits_forces(&self) -> bool {
        true
    }
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        let outer = self.slow_every as f64 * dt;
        // Slow half kick, then K Verlet steps: kick, drift, evaluate, kick. Kicks that follow
        // one another without an evaluation between them share one pass over the particles
        // (the same arithmetic: each velocity takes the kicks in order).
        slow_kick_then_kick_drift(state, 0.5 * outer, 0.5 * dt, dt);
        for k in 0..self.slow_every {
            tick(state, dt);
            evaluate(state, ForceGroup::Fast, dt);
            if k + 1 < self.slow_every {
                kick_twice_drift(state, 0.5 * dt, dt);
            } else {
                kick(state, 0.5 * dt);
            }
        }
        evaluate(state, ForceGroup::Slow, dt);
        slow_kick(state, 0.5 * outer);
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `scheme = "respa"`: `slow_every`, K fast steps per evaluation of the moments and magnetic
/// forces (default 1). It must divide the steps per output frame and the run.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct RespaSpec {
    #[serde(default = "every_step")]
    pub slow_every: u64,
}

impl Default for RespaSpec {
    fn default() -> Self {
        Self { slow_every: every_step() }
    }
}

impl IntegratorSpec for RespaSpec {
    fn check(&self) -> Result<(), Invalid> {
        check_slow_every(self.slow_every)
    }
    fn slow_every(&self) -> u64 {
        self.slow_every
    }
    fn build(&self, _ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(Respa { slow_every: self.slow_every })
    }
}
