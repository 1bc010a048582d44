//! Force terms. Each term is one file: the force behind [`ForceTerm`], its scene keys behind
//! [`setup::TermSpec`]; it is declared here, in the module list and in the registry
//! ([`ForcesSpec`]). A scene includes only the terms it lists, so an absent term costs nothing. A
//! term reads the particles (never writes them), declares the pairs it needs, and adds its
//! contribution into [`Forces`].

pub mod blake;
pub mod contact;
pub mod dipole;
pub mod drag;
pub mod gradient;
pub mod gravity;
pub mod hydrodynamics;
pub mod magnetisation;
pub mod setup;
pub mod shielding;
pub mod thermal;
pub mod wall_drag;

use super::domain::Domain;
use super::neighbours::{Neighbours, PairRange};
pub use super::renumber::Renumbering;
use super::state::{ContactDiagnostics, PairHistory, Particles, State, Vec3};

/// [`ForcesSpec`] with the table `[forces.$name]` of each term, read as its module's `$spec`.
macro_rules! registry {
    ($($name:ident: $spec:ident,)*) => {
        /// `[forces.*]`: the terms of the model; a term absent here is not computed.
        #[derive(Debug, Clone, Default, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct ForcesSpec {
            $(pub $name: Option<$name::$spec>,)*
        }

        impl ForcesSpec {
            /// The terms present, in build (and summation) order.
            pub fn terms(&self) -> Vec<&dyn setup::TermSpec> {
                [$(self.$name.as_ref().map(|t| t as &dyn setup::TermSpec)),*].into_iter().flatten().collect()
            }

            /// The keys of the terms present, in build order.
            pub fn names(&self) -> Vec<&'static str> {
                [$(self.$name.as_ref().map(|_| stringify!($name))),*].into_iter().flatten().collect()
            }
        }
    };
}

// The registry of force terms, in build (and summation) order.
registry! {
    dipole: DipoleSpec,
    gradient: GradientSpec,
    drag: DragSpec,
    gravity: GravitySpec,
    contact: ContactSpec,
    thermal: ThermalSpec,
}

/// What a term may read besides the particles during one force evaluation.
pub struct Context<'a> {
    pub domain: &'a Domain,
    /// Pair lists for the ranges the terms declared ([`ForceTerm::pairs`]), up to date.
    pub neighbours: &'a Neighbours,
    /// Time step by which history-dependent terms advance (tangential springs); 0 in the setup
    /// evaluation ([`crate::core::simulation::Simulation::initialise`]).
    pub dt: f64,
    /// Time of the state evaluated (s): a flow that varies in time is taken at it.
    pub time: f64,
}

/// What a force evaluation writes: the force and torque of the evaluated group, the moments
/// (written by the moments term, read by the magnetic force terms after it), the per-contact
/// history of the term that keeps one ([`ForceTerm::keeps_history`]), and what the stability
/// monitor reads of the contacts.
pub struct Forces<'a> {
    pub force: &'a mut [Vec3],
    pub torque: &'a mut [Vec3],
    pub moment: &'a mut [Vec3],
    pub history: &'a mut PairHistory,
    pub diagnostics: &'a mut ContactDiagnostics,
}

/// Why a term could not evaluate its forces ([`ForceTerm::prepare`]); the run stops after the step.
#[derive(Debug, Clone, thiserror::Error)]
pub enum TermError {
    /// The moments' fixed-point iteration (exact induction) did not reach its tolerance.
    #[error(
        "mutual induction did not converge: relative change {residual:.3e} after {iterations} sweeps \
         (tolerance {tolerance:.1e}); the dipole coupling is near or beyond its limit"
    )]
    Induction { residual: f64, iterations: usize, tolerance: f64 },
    /// Any other term: its name and what went wrong.
    #[error("{term}: {reason}")]
    Failed { term: &'static str, reason: String },
}

/// A force that does not change during a run (see [`ForceTerm::constant_force`]).
pub enum ConstantForce<'a> {
    /// The same on every particle.
    Uniform(Vec3),
    /// Particle by particle.
    PerParticle(&'a [Vec3]),
}

impl ConstantForce<'_> {
    /// The force on particle `i`.
    #[inline(always)]
    pub fn on(&self, i: usize) -> Vec3 {
        match self {
            ConstantForce::Uniform(force) => *force,
            ConstantForce::PerParticle(forces) => forces[i],
        }
    }
}

/// One physical contribution to the force and torque on every particle.
pub trait ForceTerm: Send {
    /// Name used in timers and messages.
    fn name(&self) -> &'static str;
    /// Whether the term varies slowly and may be evaluated less often (multiple time stepping):
    /// the magnetic terms.
    fn is_slow(&self) -> bool {
        false
    }
    /// The pairs the term needs from the neighbour layer (`None`: none), which lists them.
    fn pairs(&self) -> Option<PairRange> {
        None
    }
    /// Whether the term's force depends on nothing but fixed particle properties (mass,
    /// radius) and it exerts no torque; then [`ForceTerm::constant_force`] gives it.
    fn is_constant(&self) -> bool {
        false
    }
    /// The constant force of a term with [`ForceTerm::is_constant`]: the evaluation starts from
    /// it instead of from zero, saving a pass over the particles.
    fn constant_force(&mut self, _particles: &Particles) -> Option<ConstantForce<'_>> {
        None
    }
    /// Called once at the start of every integrator step call (between two calls a run may
    /// checkpoint): a term that caches work over several steps decides here when to renew it.
    fn begin_step(&mut self, _state: &State) {}
    /// Work that reads the whole state before any term adds forces (the moments' induction
    /// solve); an error stops the run after the step.
    fn prepare(&mut self, _ctx: &Context, _state: &State) -> Result<(), TermError> {
        Ok(())
    }
    /// Adds this term's contribution into `out`.
    fn apply(&mut self, ctx: &Context, particles: &Particles, out: &mut Forces);
    /// Writes `out`'s forces as `start` (zero if `None`) plus this term's contribution and its
    /// torques as zero plus its torque, in one pass over the particles: the bits of starting
    /// them and then [`ForceTerm::apply`], without the starting pass. Returns whether it did; a
    /// term without such a pass (the default) leaves `out` alone, and the evaluation starts the
    /// forces itself.
    fn apply_from(
        &mut self,
        _ctx: &Context,
        _p: &Particles,
        _out: &mut Forces,
        _start: Option<&ConstantForce>,
    ) -> bool {
        false
    }
    /// Whether the term keeps a value per contact across steps in [`Forces::history`] (LAMMPS'
    /// `size_history`). The framework holds, renumbers and checkpoints it; one term may keep it.
    fn keeps_history(&self) -> bool {
        false
    }
    /// The particles were renumbered between two step calls: per-particle values the term holds
    /// follow `r` ([`Renumbering::permute`]), particle indices it holds are renamed or dropped.
    /// Required, so that a term cannot hold particle data and miss a renumbering.
    fn renumber(&mut self, r: &Renumbering);
}

/// When a term that holds work over several steps (a mobility factor, drag coefficients) renews
/// it: at the first evaluation of a step call that begins on a multiple of `every` (its
/// [`ForceTerm::begin_step`]), at every evaluation with `every` = 1, and whenever nothing is held
/// (the first evaluation, or after a checkpoint restore). Checkpoints fall on multiples of
/// `every`, so a resumed run renews where the uninterrupted one did: bitwise equal.
#[derive(Debug, Clone, Copy)]
pub struct Renewal {
    every: u64,
    /// The step call began on a multiple of `every`: renew at the next evaluation.
    due: bool,
}

impl Renewal {
    /// Renewed every `every` steps (at least 1).
    pub fn every(every: u64) -> Self {
        Self { every: every.max(1), due: false }
    }

    /// Called from [`ForceTerm::begin_step`] with the step the call begins at.
    pub fn begin_step(&mut self, step: u64) {
        self.due = step.is_multiple_of(self.every);
    }

    /// Whether to renew at this evaluation, given whether anything is `held`; a renewal due at
    /// this step call is then spent.
    pub fn now(&mut self, held: bool) -> bool {
        let renew = self.every == 1 || self.due || !held;
        self.due &= !renew;
        renew
    }
}

/// Which forces an evaluation computes (multiple time stepping splits them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceGroup {
    /// Everything, into `force`/`torque`.
    All,
    /// Every term that is not slow, into `force`/`torque`.
    Fast,
    /// The slow (magnetic) terms, moments included, into `slow_force`/`slow_torque`.
    Slow,
}

impl ForceGroup {
    /// Whether the group evaluates `term`.
    pub fn has(self, term: &dyn ForceTerm) -> bool {
        match self {
            ForceGroup::All => true,
            ForceGroup::Fast => !term.is_slow(),
            ForceGroup::Slow => term.is_slow(),
        }
    }
}

impl<'a> Forces<'a> {
    /// The arrays `group` writes, from `state`; the particles stay readable beside them.
    pub fn of(state: &'a mut State, group: ForceGroup) -> (&'a Particles, Self) {
        let State { particles, fields, history, diagnostics, .. } = state;
        let (force, torque) = match group {
            ForceGroup::Slow => (&mut fields.slow_force, &mut fields.slow_torque),
            ForceGroup::All | ForceGroup::Fast => (&mut fields.force, &mut fields.torque),
        };
        (particles, Forces { force, torque, moment: &mut fields.moment, history, diagnostics })
    }
}
