//! Numerical studies of the solver itself (accuracy against time step; more to come).

pub mod accuracy;
