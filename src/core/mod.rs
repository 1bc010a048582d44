//! The physics core: state, neighbour search, force terms, integrators, stability. It never reads
//! files; the scene layer builds a [`simulation::Simulation`] from TOML.

pub mod checks;
pub mod coils;
pub mod domain;
pub mod exits;
pub mod field;
pub mod flow;
pub mod forces;
pub mod integrators;
pub mod lanes;
pub mod neighbours;
pub mod noise;
pub mod parallel;
pub mod renumber;
pub mod simulation;
pub mod stability;
pub mod state;
pub mod timers;
pub mod vector;

pub use vector::Vec3;
