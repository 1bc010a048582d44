//! Reports built from experiment runs (outside the physics core): the paper reproduction and the
//! hydrodynamics study.

pub mod digest;
pub mod estimate;
pub mod hydrodynamics;
pub mod paper;
pub mod runs;
pub mod tables;
pub mod template;
