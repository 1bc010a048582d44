//! Numerical studies of the solver itself: accuracy against time step, stability (largest stable
//! step, stiff and extreme cases, dipole cut-off error).

pub mod accuracy;
pub mod stability;
