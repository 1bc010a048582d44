//! One simulation: state, force pipeline, integrator and monitor. A step runs the named phases
//! neighbours → seed (forces start from the constant term's, torques from zero) → moments → one
//! phase per other force term (inside the integrator's force evaluation), then integrate and
//! monitor; each is timed.

use super::domain::Domain;
use super::forces::{ConstantForce, ForceContext, ForceTerm};
use super::integrators::Integrator;
use super::magnetisation::{InductionError, Magnetisation};
use super::neighbours::{Pair, VerletList};
use super::parallel;
use super::stability::{Instability, Monitor, StepEstimate};
use super::state::{State, Vec3};
use super::timers::PhaseTimers;
use rayon::prelude::*;
use std::time::Duration;

/// Which forces an evaluation computes (multiple time stepping splits them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceGroup {
    /// Everything, into `force`/`torque`.
    All,
    /// Every term that is not slow, into `force`/`torque`.
    Fast,
    /// Moments and the slow (magnetic) terms, into `slow_force`/`slow_torque`.
    Slow,
}

/// Everything that turns a state into forces and torques.
pub struct ForceField {
    pub domain: Domain,
    pub magnetisation: Option<Magnetisation>,
    pub terms: Vec<Box<dyn ForceTerm>>,
    /// Range of the near-pair search (contact and shielding), if a term needs it.
    near_range: Option<f64>,
    near: VerletList,
    near_pairs: Vec<Pair>,
    pub timers: PhaseTimers,
    /// Time spent in evaluations, to separate integration time from force time.
    evaluation_time: Duration,
    /// An induction failure inside an evaluation (reported after the step).
    induction_error: Option<InductionError>,
}

impl ForceField {
    /// `near_range`: largest contact distance times (1 + touch tolerance).
    pub fn new(domain: Domain, magnetisation: Option<Magnetisation>, given: Vec<Box<dyn ForceTerm>>, near_range: f64) -> Self {
        // Constant terms first, so that one can seed each evaluation's force; otherwise in order.
        // (Asking a term for its force on no particles tells whether it has a constant one.)
        let (mut terms, mut others) = (vec![], vec![]);
        for mut term in given {
            let constant = term.constant_force(&Default::default()).is_some();
            if constant { &mut terms } else { &mut others }.push(term);
        }
        terms.append(&mut others);
        let needs = terms.iter().any(|t| t.needs_near_pairs());
        Self {
            domain,
            magnetisation,
            terms,
            near_range: needs.then_some(near_range),
            near: VerletList::default(),
            near_pairs: vec![],
            timers: PhaseTimers::default(),
            evaluation_time: Duration::ZERO,
            induction_error: None,
        }
    }

    /// Computes `force`, `torque` and `moment` for the current state.
    pub fn evaluate(&mut self, state: &mut State, dt: f64) {
        self.evaluate_group(state, dt, ForceGroup::All);
    }

    /// Computes one group of forces (see [`ForceGroup`]).
    pub fn evaluate_group(&mut self, state: &mut State, dt: f64, group: ForceGroup) {
        let started = self.timers.start();
        let p = &mut state.particles;
        if self.domain.periodic.contains(&true) {
            p.position.iter_mut().for_each(|x| self.domain.wrap(x));
        }
        if group == ForceGroup::Slow {
            // Slow terms add into force/torque: point those at the slow arrays for this pass.
            std::mem::swap(&mut p.force, &mut p.slow_force);
            std::mem::swap(&mut p.torque, &mut p.slow_torque);
        }
        let mut near_rebuilt = None;
        if let Some(range) = self.near_range.filter(|_| group != ForceGroup::Slow) {
            // Skin 0.2 of the contact range (0.2 diameters), as in the reference decks.
            let (near, pairs, skin) = (&mut self.near, &mut self.near_pairs, 0.2 * range);
            if self.timers.time("neighbours", || near.pairs_within(&p.position, &self.domain, range, skin, pairs)) {
                near_rebuilt = Some(skin);
            }
        }
        let wanted = |term: &dyn ForceTerm| match group {
            ForceGroup::All => true,
            ForceGroup::Fast => !term.is_slow(),
            ForceGroup::Slow => term.is_slow(),
        };
        // The first term, if wanted and constant, seeds the force (the constant terms come first).
        let t0 = self.timers.start();
        let seed = match self.terms.first_mut() {
            Some(first) if wanted(first.as_ref()) => first.constant_force(p),
            _ => None,
        };
        let seeded = seed.is_some();
        start_forces(&mut p.force, &mut p.torque, seed);
        self.timers.stop("seed", t0);
        if let Some(mag) = self.magnetisation.as_mut().filter(|_| group != ForceGroup::Fast) {
            let result = self.timers.time("moments", || mag.update(p, &self.domain));
            if let Err(e) = result {
                self.induction_error.get_or_insert(e);
            }
        }
        let ctx = ForceContext {
            domain: &self.domain,
            near_pairs: &self.near_pairs,
            near_rebuilt,
            dt,
            magnetic_pairs: self.magnetisation.as_ref().and_then(|m| m.pairs()),
        };
        for term in self.terms.iter_mut().skip(seeded as usize) {
            if wanted(term.as_ref()) {
                let t0 = self.timers.start();
                term.apply(&ctx, state);
                self.timers.stop(term.name(), t0);
            }
        }
        if group == ForceGroup::Slow {
            let p = &mut state.particles;
            std::mem::swap(&mut p.force, &mut p.slow_force);
            std::mem::swap(&mut p.torque, &mut p.slow_torque);
        }
        if let Some(t0) = started {
            self.evaluation_time += t0.elapsed();
        }
    }
}

/// Sets each force to `constant` (zero without one) and each torque to zero: one parallel loop,
/// each thread over its share of both arrays.
fn start_forces(force: &mut [Vec3], torque: &mut [Vec3], constant: Option<ConstantForce>) {
    let start = |force: &mut [Vec3], torque: &mut [Vec3], first: usize| {
        match &constant {
            Some(ConstantForce::PerParticle(weights)) => force.copy_from_slice(&weights[first..first + force.len()]),
            Some(ConstantForce::Uniform(weight)) => fill(force, *weight),
            None => fill(force, Vec3::zeros()),
        }
        fill(torque, Vec3::zeros());
    };
    if parallel::worth_it(force.len()) {
        let share = parallel::share(force.len());
        force.par_chunks_mut(share).zip(torque.par_chunks_mut(share)).enumerate().for_each(|(k, (f, t))| start(f, t, k * share));
    } else {
        start(force, torque, 0);
    }
}

/// `out[i] = value` for every i, stored four vectors at a time (a 96-byte copy the compiler
/// writes as wide stores; one vector at a time it is not).
fn fill(out: &mut [Vec3], value: Vec3) {
    let four = [value; 4];
    let mut quads = out.chunks_exact_mut(4);
    quads.by_ref().for_each(|q| q.copy_from_slice(&four));
    quads.into_remainder().fill(value);
}

/// A run that went unstable: what happened, when, and the step that would be stable.
#[derive(Debug, thiserror::Error)]
#[error(
    "unstable at step {step} (t = {time:.6e} s): {cause}. Estimated stable dt {stable_dt:.3e} s \
     ({limited_by}); this run used dt = {dt:.3e} s"
)]
pub struct RunError {
    pub step: u64,
    pub time: f64,
    pub cause: Instability,
    pub stable_dt: f64,
    pub limited_by: &'static str,
    pub dt: f64,
}

pub struct Simulation {
    pub state: State,
    pub field: ForceField,
    pub integrator: Box<dyn Integrator>,
    pub dt: f64,
    pub monitor: Monitor,
    pub estimate: StepEstimate,
}

impl Simulation {
    /// Evaluates the forces of a fresh state (not needed after a checkpoint restore).
    pub fn initialise(&mut self) -> Result<(), RunError> {
        if self.integrator.splits_forces() {
            self.field.evaluate_group(&mut self.state, self.dt, ForceGroup::Fast);
            self.field.evaluate_group(&mut self.state, self.dt, ForceGroup::Slow);
        } else {
            self.field.evaluate(&mut self.state, self.dt);
        }
        self.check()
    }

    /// Advances one step and checks it.
    pub fn step(&mut self) -> Result<(), RunError> {
        let n = self.state.particles.len();
        parallel::with_warm_pool(n, || {
            let started = self.field.timers.start();
            let eval_before = self.field.evaluation_time;
            let (field, dt) = (&mut self.field, self.dt);
            self.integrator.step(&mut self.state, dt, &mut |s, group, h| field.evaluate_group(s, h, group));
            if let Some(t0) = started {
                // The integrator's own work: the step's time less its force evaluations.
                let evaluations = self.field.evaluation_time - eval_before;
                self.field.timers.add("integrate", t0.elapsed().saturating_sub(evaluations));
            }
            let t0 = self.field.timers.start();
            let result = self.check();
            self.field.timers.stop("monitor", t0);
            result
        })
    }

    fn check(&mut self) -> Result<(), RunError> {
        let cause = match self.field.induction_error.take() {
            Some(e) => Err(Instability::Induction(e)),
            None => self.monitor.check(&self.state, &self.field.domain, self.dt),
        };
        cause.map_err(|cause| RunError {
            step: self.state.step,
            time: self.state.time,
            cause,
            stable_dt: self.estimate.stable_dt,
            limited_by: self.estimate.limited_by,
            dt: self.dt,
        })
    }

    pub fn timers(&self) -> &PhaseTimers {
        &self.field.timers
    }
}
