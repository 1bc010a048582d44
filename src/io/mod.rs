//! Input/output outside the physics core: HDF5 trajectories with checkpoints, and their XDMF
//! and LAMMPS-dump exports; flow fields on grids.

pub mod export;
pub mod flow_grid;
pub mod trajectory;
