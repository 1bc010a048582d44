//! Input/output outside the physics core: HDF5 trajectories with checkpoints, and their XDMF
//! and LAMMPS-dump exports.

pub mod export;
pub mod trajectory;
