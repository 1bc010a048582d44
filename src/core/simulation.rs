//! One simulation: state, force pipeline, integrator and monitor. A step runs the named phases
//! renumber (on its schedule) → neighbours (candidate upkeep) → pair-list (the listed ranges
//! filtered) → seed (forces start from the constant term's, torques from zero; the next term
//! may write them with its own in one pass, then timed as that term) → one phase per force term,
//! the moments first (inside the integrator's force evaluation), then integrate and monitor;
//! each is timed.

use super::domain::Domain;
use super::exits::ExitRules;
use super::forces::{ConstantForce, Context, ForceGroup, ForceTerm, Forces, TermError};
use super::integrators::Integrator;
use super::neighbours::{Neighbours, RangeUsage};
use super::parallel;
use super::renumber::Renumbering;
use super::stability::{Instability, Monitor, StepEstimate};
use super::state::{State, Vec3};
use super::timers::PhaseTimers;
use std::time::Duration;

/// Everything that turns a state into forces and torques.
pub struct ForceField {
    pub domain: Domain,
    /// The terms in evaluation order: a constant one first (it seeds the force), the moments
    /// before the terms that read them, the rest in the order given.
    pub terms: Vec<Box<dyn ForceTerm>>,
    neighbours: Neighbours,
    pub timers: PhaseTimers,
    /// Time spent in evaluations, to separate integration time from force time.
    evaluation_time: Duration,
    /// A term's failure inside an evaluation (reported after the step).
    term_error: Option<TermError>,
}

impl ForceField {
    /// The force field of `terms`, in the order given but with a constant term first; the
    /// moments term, if any, must come before the terms that read moments.
    /// The force field of `terms` (at most one of which keeps a per-contact history).
    pub fn new(domain: Domain, mut terms: Vec<Box<dyn ForceTerm>>) -> Self {
        let keepers: Vec<&str> = terms.iter().filter(|t| t.keeps_history()).map(|t| t.name()).collect();
        assert!(keepers.len() <= 1, "one term may keep the per-contact history, not {keepers:?}");
        terms.sort_by_key(|t| !t.is_constant());
        let neighbours = Neighbours::new(terms.iter().filter_map(|t| t.pairs()));
        Self {
            domain,
            terms,
            neighbours,
            timers: PhaseTimers::default(),
            evaluation_time: Duration::ZERO,
            term_error: None,
        }
    }

    /// Follows a renumbering of the particles: the neighbour lists and every term.
    fn renumber(&mut self, r: &Renumbering) {
        self.neighbours.renumber(r);
        self.terms.iter_mut().for_each(|t| t.renumber(r));
    }

    /// The first term failure since the last call, if any.
    pub fn take_term_error(&mut self) -> Option<TermError> {
        self.term_error.take()
    }

    /// Computes `force`, `torque` and `moment` for the current state.
    pub fn evaluate(&mut self, state: &mut State, dt: f64) {
        self.evaluate_group(state, dt, ForceGroup::All);
    }

    /// Computes one group of forces (see [`ForceGroup`]).
    pub fn evaluate_group(&mut self, state: &mut State, dt: f64, group: ForceGroup) {
        let started = self.timers.start();
        state.fields.fit(state.particles.len());
        if self.domain.periodic.contains(&true) {
            let domain = &self.domain;
            self.timers.time("wrap", || {
                state.particles.position.drift(|position| {
                    parallel::for_each_share(position, |_, xs| xs.iter_mut().for_each(|x| domain.wrap(x)));
                    domain.wrap_rounding()
                })
            });
        }
        let terms = &self.terms;
        let wanted = |range| terms.iter().any(|t| group.has(t.as_ref()) && t.pairs() == Some(range));
        self.neighbours.update(&state.particles.position, &self.domain, wanted, &mut self.timers);
        let ctx = Context { domain: &self.domain, neighbours: &self.neighbours, dt, time: state.time };
        for term in self.terms.iter_mut().filter(|t| group.has(t.as_ref())) {
            let t0 = self.timers.start();
            if let Err(e) = term.prepare(&ctx, state) {
                self.term_error.get_or_insert(e);
            }
            self.timers.stop(term.name(), t0);
        }
        let (particles, mut out) = Forces::of(state, group);
        // The first term, if evaluated and constant, seeds the force (the constant terms come
        // first); the next term writes the seeded forces with its own in one pass if it can.
        let seeded = self.terms.first().is_some_and(|t| group.has(t.as_ref()) && t.is_constant());
        let (constant, others) = self.terms.split_at_mut(seeded as usize);
        let mut others = others.iter_mut().filter(|t| group.has(t.as_ref()));
        let t0 = self.timers.start();
        let seed = constant.first_mut().and_then(|t| t.constant_force(particles));
        let mut first = others.next();
        match first.as_mut().is_some_and(|t| t.apply_from(&ctx, particles, &mut out, seed.as_ref())) {
            true => self.timers.stop(first.map_or("seed", |t| t.name()), t0),
            false => {
                start_forces(out.force, out.torque, seed);
                self.timers.stop("seed", t0);
                if let Some(term) = first {
                    let t0 = self.timers.start();
                    term.apply(&ctx, particles, &mut out);
                    self.timers.stop(term.name(), t0);
                }
            }
        }
        for term in others {
            let t0 = self.timers.start();
            term.apply(&ctx, particles, &mut out);
            self.timers.stop(term.name(), t0);
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
    parallel::for_each_share((force, torque), |first, (f, t)| start(f, t, first));
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

/// When the particles are renumbered along a Morton curve (as LAMMPS sorts its atoms): at the
/// start of every step call that begins on a multiple of `every` steps, through cells of edge
/// `cell`. A function of the step count and the state only, so a resumed run renumbers where the
/// uninterrupted one did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenumberSchedule {
    pub every: u64,
    /// Cell edge of the curve (m): the smallest particle diameter.
    pub cell: f64,
}

pub struct Simulation {
    pub state: State,
    pub field: ForceField,
    pub integrator: Box<dyn Integrator>,
    pub dt: f64,
    pub monitor: Monitor,
    pub estimate: StepEstimate,
    /// Renumbering during the run, or none.
    pub renumber: Option<RenumberSchedule>,
    /// How particles leave the run (none leave by default).
    pub exits: ExitRules,
    /// How the step's loops split between two threads (learnt as the run goes; never changes a
    /// result).
    pub balance: parallel::Balance,
}

impl Simulation {
    /// Evaluates the forces of a fresh state (not needed after a checkpoint restore). Like
    /// LAMMPS' and LIGGGHTS' setup (pair gran: "do not update shear history during setup"), this
    /// evaluation does not advance the tangential springs (dt = 0 for them), so a state started
    /// from a stored contact history sees its springs as stored.
    pub fn initialise(&mut self) -> Result<(), RunError> {
        if self.integrator.splits_forces() {
            self.field.evaluate_group(&mut self.state, 0.0, ForceGroup::Fast);
            self.field.evaluate_group(&mut self.state, 0.0, ForceGroup::Slow);
        } else {
            self.field.evaluate(&mut self.state, 0.0);
        }
        self.check()
    }

    /// Renumbers the particles along the Morton curve of their current positions: the state,
    /// the neighbour lists, the terms and the integrator follow.
    pub fn renumber(&mut self, cell: f64) {
        let r = Renumbering::morton(&self.state.particles.position, cell, &self.field.domain);
        self.state.renumber(&r);
        self.field.renumber(&r);
        self.integrator.renumber(&r);
    }

    /// Removes the particles that leave by the exit rules after a step: the state, the
    /// neighbour lists, the terms and the integrator follow.
    fn remove_leaving(&mut self) {
        let leaving = self.exits.leaving(&mut self.state);
        if !leaving.is_empty() {
            let r = ExitRules::remove(&mut self.state, &leaving);
            self.state.renumber(&r);
            self.field.renumber(&r);
            self.integrator.renumber(&r);
        }
    }

    /// Advances one step and checks it.
    pub fn step(&mut self) -> Result<(), RunError> {
        let n = self.state.particles.len();
        let mut balance = self.balance;
        let result = parallel::with_warm_pool(n, &mut balance, || {
            if let Some(s) = self.renumber.filter(|s| self.state.step.is_multiple_of(s.every)) {
                let t0 = self.field.timers.start();
                self.renumber(s.cell);
                self.field.timers.stop("renumber", t0);
            }
            let started = self.field.timers.start();
            let eval_before = self.field.evaluation_time;
            let (field, dt) = (&mut self.field, self.dt);
            field.terms.iter_mut().for_each(|t| t.begin_step(&self.state));
            self.integrator.step(&mut self.state, dt, &mut |s, group, h| field.evaluate_group(s, h, group));
            if let Some(t0) = started {
                // The integrator's own work: the step's time less its force evaluations.
                let evaluations = self.field.evaluation_time - eval_before;
                self.field.timers.add("integrate", t0.elapsed().saturating_sub(evaluations));
            }
            let t0 = self.field.timers.start();
            let result = self.check();
            self.field.timers.stop("monitor", t0);
            if !self.exits.is_empty() {
                let t0 = self.field.timers.start();
                self.remove_leaving();
                self.field.timers.stop("exits", t0);
            }
            result
        });
        self.balance = balance;
        result
    }

    fn check(&mut self) -> Result<(), RunError> {
        let cause = match self.field.take_term_error() {
            Some(e) => Err(Instability::Term(e)),
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

    /// What each neighbour range did so far (rebuilds, candidates, listed pairs).
    pub fn neighbour_usage(&self) -> Vec<RangeUsage> {
        self.field.neighbours.usage()
    }
}
