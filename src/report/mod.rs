//! Reports built from experiment runs (outside the physics core): the paper reproduction.

pub mod convergence;
pub mod figures;
pub mod paper;
pub mod runs;
pub mod tables;
