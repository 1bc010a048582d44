//! Force terms. Each term is one file behind [`ForceTerm`]; a scene includes only the terms it
//! lists, so an absent term costs nothing.

pub mod contact;
pub mod dipole;
pub mod drag;
pub mod gradient;
pub mod gravity;
pub mod shielding;

use super::domain::Domain;
use super::neighbours::Pair;
use super::state::{Particles, State, Vec3};

/// What a term may read besides the state during one force evaluation.
pub struct ForceContext<'a> {
    pub domain: &'a Domain,
    /// Pairs within contact range (touching or overlapping within the touch tolerance), in
    /// (i, j) order.
    pub near_pairs: &'a [Pair],
    /// `Some(skin)` when the near-pair candidates were rebuilt in this evaluation: until the next
    /// rebuild no particle moves more than skin/2 from where it is now.
    pub near_rebuilt: Option<f64>,
    /// Time step, for history-dependent terms (tangential spring).
    pub dt: f64,
    /// Pairs the moments phase found this evaluation, with their range (`None` = all pairs),
    /// for terms that sum over the same pairs.
    pub magnetic_pairs: Option<(Option<f64>, &'a [Pair])>,
}

/// A force that does not change during a run (see [`ForceTerm::constant_force`]).
pub enum ConstantForce<'a> {
    /// The same on every particle.
    Uniform(Vec3),
    /// Particle by particle.
    PerParticle(&'a [Vec3]),
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
    /// Whether the term needs `ForceContext::near_pairs`.
    fn needs_near_pairs(&self) -> bool {
        false
    }
    /// The term's force when it depends on nothing but fixed particle properties (mass, radius)
    /// and exerts no torque: the force field then starts each evaluation from it instead of
    /// from zero, saving a pass over the particles.
    fn constant_force(&mut self, _particles: &Particles) -> Option<ConstantForce<'_>> {
        None
    }
    /// Adds this term's force and torque into `state.particles.force/torque`.
    fn apply(&mut self, ctx: &ForceContext, state: &mut State);
}
