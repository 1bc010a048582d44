//! The three-vector of the core.

/// Three-vector of f64 used throughout the core (SI units).
pub type Vec3 = nalgebra::Vector3<f64>;
