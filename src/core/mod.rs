//! The physics core: state, neighbour search, force terms, integrators, stability. It never reads
//! files; the scene layer builds a [`simulation::Simulation`] from TOML.

pub mod domain;
pub mod forces;
pub mod integrators;
pub mod lanes;
pub mod magnetisation;
pub mod neighbours;
pub mod parallel;
pub mod renumber;
pub mod simulation;
pub mod stability;
pub mod state;
pub mod timers;

pub use state::Vec3;
