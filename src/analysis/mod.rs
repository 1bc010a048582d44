//! Analysis of trajectories (outside the core): aggregates and their statistics.

pub mod aggregates;
pub mod image;
pub mod stats;
pub mod timing;
pub mod trajectory;
