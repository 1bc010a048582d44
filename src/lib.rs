//! magdem: a research harness for magnetic particle DEM.
//!
//! Layers: [`core`] (physics, never touches files) ← [`scene`] (the only TOML reader, builds a
//! simulation) ← [`io`] (HDF5 trajectories and checkpoints) ← [`run`] (the driver used by the CLI).

pub mod analysis;
pub mod bench;
pub mod core;
pub mod experiment;
pub mod io;
pub mod plot;
pub mod reference;
pub mod report;
pub mod run;
pub mod scene;
pub mod study;
pub mod verify;
