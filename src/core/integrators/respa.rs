//! Multiple time stepping (r-RESPA, Tuckerman, Berne & Martyna 1992, "impulse" form) with
//! velocity Verlet inside: the slow (magnetic) forces kick for half an outer step K·dt at its
//! start and end, and the fast forces (contact, drag, gravity) are integrated by K Verlet steps
//! of dt in between. The moments and dipole sums are computed once per K steps. Second order and
//! time-reversible for smooth slow forces; like every impulse scheme it can resonate when K·dt
//! approaches half the period of a fast oscillation, which the stability studies measure.

use super::ForceGroup;
use super::{kick, kick_twice_drift, slow_kick, slow_kick_then_kick_drift, tick, Evaluate, Integrator, Renumbering};
use crate::core::state::State;

pub struct Respa {
    /// K: fast steps per slow evaluation.
    pub slow_every: u64,
}

impl Integrator for Respa {
    fn name(&self) -> &'static str {
        "respa"
    }
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
