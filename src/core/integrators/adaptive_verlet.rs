//! Velocity Verlet with an adaptive step and error control (step doubling). Each call advances
//! exactly the scene's dt — the largest step, and the clock of frames and checkpoints — in
//! substeps h chosen by the error:
//!
//!   one Verlet step of h and two of h/2 from the same state; their difference estimates the
//!   local error of the two half steps (Richardson, order 2: err ≈ |y_{h/2} − y_h| / 3),
//!   measured per particle as (|Δx| + h |Δv|) / 3 against `tolerance` × its radius.
//!
//! A substep is accepted when the largest scaled error is ≤ 1 (the two half steps are kept) and
//! retried from a saved state otherwise; the next h is h · clamp(0.9 err^(−1/3), 0.2, 2), kept
//! in `State::next_substep` between calls (so checkpoints carry it). The
//! accepted solution is velocity Verlet at h/2: order 2, with errors proportional to the
//! tolerance for position-dependent forces (with velocity-dependent drag, first order, as velocity
//! Verlet). Three force evaluations per accepted substep; one impact anywhere shortens the step
//! for all particles (the step is global). The forces must be functions of the state: the scene
//! layer refuses the paper's lagged induction, which advances one sweep per evaluation.

use super::ForceGroup;
use super::{kick, kick_drift, Evaluate, Integrator, IntegratorContext, IntegratorSpec, Renumbering};
use crate::core::checks::{invalid, Invalid};
use crate::core::state::State;

pub struct AdaptiveVerlet {
    /// Local error allowed per substep, as a fraction of each particle's radius.
    pub tolerance: f64,
    /// Smallest substep taken so far (diagnostic).
    pub smallest: f64,
    /// Accepted and rejected substeps so far.
    pub accepted: u64,
    pub rejected: u64,
}

impl AdaptiveVerlet {
    pub fn new(tolerance: f64) -> Self {
        Self { tolerance, smallest: f64::INFINITY, accepted: 0, rejected: 0 }
    }
}

/// One velocity Verlet step of `h` (forces on entry belong to `state`).
fn verlet(state: &mut State, h: f64, evaluate: &mut Evaluate) {
    kick_drift(state, 0.5 * h, h);
    state.time += h;
    evaluate(state, ForceGroup::All, h);
    kick(state, 0.5 * h);
}

/// Largest per-particle (|Δx| + h|Δv|) / (3 · tolerance · radius) between two states.
fn scaled_error(a: &State, b: &State, h: f64, tolerance: f64) -> f64 {
    let (p, q) = (&a.particles, &b.particles);
    (0..p.len())
        .map(|i| {
            ((p.position[i] - q.position[i]).norm() + h * (p.velocity[i] - q.velocity[i]).norm())
                / (3.0 * tolerance * p.radius[i])
        })
        .fold(0.0, f64::max)
}

impl Integrator for AdaptiveVerlet {
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate) {
        let (start_step, start_time) = (state.step, state.time);
        let end = start_time + dt;
        let mut h = state.next_substep.unwrap_or(dt).min(dt);
        // A floor of 1e-6 dt bounds the cost of a step whose error will not fall (a discontinuous
        // force): the substep is then accepted and the monitor judges the result.
        let floor = dt * 1e-6;
        loop {
            let remaining = end - state.time;
            if remaining <= 1e-12 * dt {
                break;
            }
            let last = h >= remaining;
            let trial = if last { remaining } else { h };
            let saved = state.clone();
            let mut coarse = state.clone();
            verlet(&mut coarse, trial, evaluate);
            verlet(state, 0.5 * trial, evaluate);
            verlet(state, 0.5 * trial, evaluate);
            let err = scaled_error(state, &coarse, trial, self.tolerance);
            let factor = if err > 0.0 { (0.9 * err.powf(-1.0 / 3.0)).clamp(0.2, 2.0) } else { 2.0 };
            if err <= 1.0 || trial <= floor {
                self.accepted += 1;
                self.smallest = self.smallest.min(trial);
                // Keep the proposal for the next substep unless this one was cut short by the
                // end of the call.
                if !last || factor < 1.0 {
                    h = (trial * factor).max(floor);
                }
            } else {
                self.rejected += 1;
                *state = saved;
                h = (trial * factor).max(floor);
            }
        }
        state.next_substep = Some(h);
        state.step = start_step + 1;
        state.time = state.step as f64 * dt;
    }
    /// Holds nothing per particle.
    fn renumber(&mut self, _r: &Renumbering) {}
}

/// `scheme = "adaptive-verlet"`: `tolerance`, the local error allowed per substep as a fraction
/// of each particle's radius (default 1e-6); dt is the largest step.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveVerletSpec {
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
}

impl Default for AdaptiveVerletSpec {
    fn default() -> Self {
        Self { tolerance: default_tolerance() }
    }
}

fn default_tolerance() -> f64 {
    1e-6
}

impl IntegratorSpec for AdaptiveVerletSpec {
    fn check(&self) -> Result<(), Invalid> {
        if !(self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(invalid(
                "integration.tolerance",
                self.tolerance,
                "must lie in (0, 1): a fraction of a particle radius",
            ));
        }
        Ok(())
    }
    fn dt_is_a_cap(&self) -> bool {
        true
    }
    fn compares_evaluations(&self) -> bool {
        true
    }
    fn build(&self, _ctx: &IntegratorContext) -> Box<dyn Integrator> {
        Box::new(AdaptiveVerlet::new(self.tolerance))
    }
}
