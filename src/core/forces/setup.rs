//! The contract between a term's scene keys and the core: each term's spec (plain serde data,
//! in the term's own file) checks its keys, bounds the step and builds the term through
//! [`TermSpec`]. The registry ([`super::ForcesSpec::terms`]) lists the present specs in build
//! order; the scene layer, which parses the file, runs them (the core reads no files).

use super::ForceTerm;
pub use crate::core::checks::{invalid, non_negative, positive, Invalid};
use crate::core::domain::Domain;
use crate::core::field::AppliedField;
use crate::core::flow::Flow;
use crate::core::integrators::Scheme;
use crate::core::neighbours::{PairRange, Skins};
use crate::core::state::{largest_diameter, Species};

/// The fluid the particles move in.
#[derive(Debug, Clone)]
pub struct Fluid {
    /// ρ_f (kg/m³).
    pub density: f64,
    /// μ (Pa s).
    pub viscosity: f64,
    /// u_f(x, t) (m/s).
    pub flow: Flow,
}

/// The moments' mutual induction (the moments term, [`super::magnetisation`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Induction {
    /// H_loc = H_ext.
    None,
    /// Dipoles within `radius` (m) contribute with the previous step's moments.
    Paper { radius: f64 },
    /// The self-consistent moments every step.
    Exact { tolerance: f64, max_iterations: usize, dense_max: usize },
}

/// The pair ranges built terms search: the near range shared by contact and shielding, and the
/// skins that pad every range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pairs {
    pub near: PairRange,
    pub skins: Skins,
}

/// What a term's spec sees of the checked scene.
#[derive(Debug, Clone)]
pub struct SceneContext<'a> {
    pub domain: &'a Domain,
    /// The checked species (full size distributions).
    pub species: &'a [Species],
    /// The `[fluid]` table, if given.
    pub fluid: Option<Fluid>,
    /// The `[field]` table, B_ext(x, t), if given.
    pub field: Option<AppliedField>,
    /// The integration scheme, with its parameters.
    pub scheme: Scheme,
    pub steps_per_frame: u64,
    /// The pair ranges to build with (defaults while checking).
    pub pairs: Pairs,
    /// Every term's spec, for a term that must agree with another (the thermal forces with the
    /// drag they balance).
    pub forces: &'a super::ForcesSpec,
    /// The scene's seed (the thermal noise's key).
    pub seed: u64,
}

impl SceneContext<'_> {
    /// The largest diameter any species can have (m): pair ranges are given in it.
    pub fn largest_diameter(&self) -> f64 {
        largest_diameter(self.species)
    }

    /// The applied field (zero without a `[field]` table).
    pub fn field(&self) -> AppliedField {
        self.field.clone().unwrap_or_else(AppliedField::zero)
    }
}

/// A force term's scene keys: its checks, its step bound and its construction. Implemented by
/// the term's spec, in the term's file.
pub trait TermSpec {
    /// Refuses a value the term cannot run with, naming the key, the value and why.
    fn check(&self, ctx: &SceneContext) -> Result<(), Invalid>;
    /// The induction of the moments the term reads, or `None` if it reads no moments. The moments
    /// term is built first whenever a term reads them.
    fn moments(&self, _ctx: &SceneContext) -> Option<Induction> {
        None
    }
    /// The gap below which the term counts two particles as near, as a fraction of the smaller
    /// radius: the near pair range is the largest diameter times 1 + the largest such gap.
    fn near_tolerance(&self) -> f64 {
        0.0
    }
    /// The term's bound on the step, if it is stiff (or reports a time scale).
    fn stable_dt(&self, _ctx: &StepContext) -> Option<StepBound> {
        None
    }
    /// A closing speed the term's agitation gives two particles of `species` (m/s), which the
    /// contact's bound must resolve; zero for a term that agitates nothing.
    fn agitation_speed(&self, _species: &Species) -> f64 {
        0.0
    }
    /// The term.
    fn build(&self, ctx: &SceneContext) -> Box<dyn ForceTerm>;
}

/// What a term's step bound may read about the scene.
#[derive(Debug, Clone)]
pub struct StepContext<'a> {
    /// The species, each at its smallest radius (the strictest case for every bound).
    pub species: &'a [Species],
    /// The integration scheme, with its parameters.
    pub scheme: Scheme,
    /// Largest isolated moment magnitude per species (A·m²), zero without magnetic terms.
    pub moments: Vec<f64>,
    /// Fastest expected impact speed per species (m/s), [`super::magnetisation::impact_speed`].
    pub impact_speeds: Vec<f64>,
    /// Viscosity if drag is included.
    pub drag_viscosity: Option<f64>,
    /// T (K) of `[forces.thermal]`, if listed.
    pub temperature: Option<f64>,
    pub max_initial_speed: f64,
}

/// The fastest collision a term expects: its speed and the shortest contact duration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collision {
    pub speed: f64,
    pub duration: f64,
}

/// One term's bound on the step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepBound {
    /// The term's name ([`ForceTerm::name`]).
    pub term: &'static str,
    /// The largest stable step (s), or `None` where the term only reports a time scale.
    pub dt: Option<f64>,
    /// What sets the bound, as the estimate names it.
    pub limited_by: &'static str,
    /// The collisions the term expects, if it is a contact law.
    pub collision: Option<Collision>,
    /// The term's clause of [`crate::core::stability::StepEstimate::summary`] (`"; …"`).
    pub summary: String,
}
