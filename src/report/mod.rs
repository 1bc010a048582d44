//! Reports built from experiment runs (outside the physics core): the paper reproduction and the
//! hydrodynamics study.

pub mod convergence;
pub mod digest;
pub mod figures;
pub mod hydrodynamics;
pub mod paper;
pub mod runs;
pub mod tables;
