//! Reports built from experiment runs and measurements (outside the physics core): the paper
//! reproduction, the hydrodynamics study and the performance report.

pub mod digest;
pub mod estimate;
pub mod hydrodynamics;
pub mod paper;
pub mod performance;
pub mod runs;
pub mod tables;
pub mod template;
