//! Input/output outside the physics core: HDF5 trajectories with checkpoints.

pub mod trajectory;
