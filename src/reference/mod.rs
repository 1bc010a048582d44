//! The reference codes: the same scene as an input deck for LIGGGHTS 3.8 or LAMMPS (Debian's
//! `liggghts` and `lmp`), run as a separate process, and its dump read back into magdem's HDF5
//! trajectory schema. Outside the physics core.
//!
//! What the decks express: Hertz–Mindlin contact with restitution damping (particle–particle and
//! walls), weight minus buoyancy (`fix gravity`), Stokes drag without shielding (`fix viscous`),
//! and a `fix external` through which magdem supplies the magnetic forces in lock step
//! ([`library`]). Anything else is refused with a message naming the term.

pub mod deck;
pub mod dialect;
pub mod dipole_check;
pub mod dump;
pub mod files_route;
pub mod lammps;
pub mod library;
pub mod liggghts;

use crate::io::trajectory::{status, Cost, RunInfo, TrajectoryError, TrajectoryWriter};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::Command;

#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    Liggghts,
    Lammps,
}

impl Engine {
    /// What differs between the engines: decks, limits, binary and library.
    pub fn dialect(self) -> &'static dyn dialect::Dialect {
        match self {
            Engine::Liggghts => &liggghts::Liggghts,
            Engine::Lammps => &lammps::Lammps,
        }
    }

    pub fn name(self) -> &'static str {
        self.dialect().name()
    }

    pub fn binary(self) -> &'static str {
        self.dialect().binary()
    }

    /// Whether the engine's binary is on the PATH.
    pub fn available(self) -> bool {
        std::env::var_os("PATH")
            .map(|paths| std::env::split_paths(&paths).any(|d| d.join(self.binary()).is_file()))
            .unwrap_or(false)
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    #[error("{engine} cannot express {term}: {why}")]
    Unsupported { engine: &'static str, term: String, why: String },
    #[error("{engine} is not installed (no `{binary}` on the PATH): run `make setup` as root, or `apt-get install liggghts lammps`")]
    NotInstalled { engine: &'static str, binary: &'static str },
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("{engine} failed (exit {code:?}); the end of its log {log}:\n{tail}")]
    Failed { engine: &'static str, code: Option<i32>, log: String, tail: String },
    #[error("reading the {engine} dump {path}: {message}")]
    Dump { engine: &'static str, path: String, message: String },
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
}

/// A reference-code run that finished.
pub struct ReferenceRun {
    pub frames: usize,
    pub log: PathBuf,
    pub wall_time: std::time::Duration,
}

/// Writes the deck for `scene` into `dir`, runs the engine there (its binary; a magnetic scene
/// in process, in lock step with magdem's magnetic forces), and converts its dump into the
/// trajectory `output` (same schema as a native run, `engine` attribute set). The engine's log is
/// kept beside the output as `OUTPUT.ENGINE.log`.
pub fn run(engine: Engine, scene: &Scene, dir: &Path, output: &Path) -> Result<ReferenceRun, ReferenceError> {
    if scene.magnetic_force_field().is_some() {
        return library::run_coupled(engine, scene, dir, output);
    }
    run_binary(engine, scene, dir, output, &deck::Coupling::Callback, 1)
}

/// Runs the engine's binary on the deck (with the files route for magnetic forces, if given),
/// under `mpirun -np procs` when `procs` > 1: the deck is the same, each process holds part of
/// the box, and the files route's `shell` exchange runs on the first process.
pub fn run_binary(
    engine: Engine,
    scene: &Scene,
    dir: &Path,
    output: &Path,
    coupling: &deck::Coupling,
    procs: usize,
) -> Result<ReferenceRun, ReferenceError> {
    if !engine.available() {
        return Err(ReferenceError::NotInstalled { engine: engine.name(), binary: engine.binary() });
    }
    let start = std::time::Instant::now();
    std::fs::create_dir_all(dir)?;
    let written = deck::write_with(engine, scene, dir, coupling)?;
    let mut command = engine_command(engine, procs);
    let result = command.arg("-in").arg(&written.input).arg("-log").arg("log.engine").current_dir(dir).output()?;
    let log = output.with_extension(format!("{}.log", engine.name()));
    let engine_log = dir.join("log.engine");
    if engine_log.exists() {
        std::fs::copy(&engine_log, &log)?;
    }
    if !result.status.success() {
        let text = String::from_utf8_lossy(&result.stdout);
        let tail: Vec<&str> = text.lines().rev().take(15).collect::<Vec<_>>().into_iter().rev().collect();
        return Err(ReferenceError::Failed {
            engine: engine.name(),
            code: result.status.code(),
            log: log.display().to_string(),
            tail: tail.join("\n"),
        });
    }
    let frames = dump::read(engine, &dir.join(&written.dump), scene)?;
    let integrator = match coupling {
        deck::Coupling::Files { every, .. } if scene.magnetic_force_field().is_some() => {
            format!("velocity-verlet (nve/sphere), magnetic forces from magdem by file exchange every {every} steps, {procs} MPI process(es)")
        }
        deck::Coupling::Native => format!(
            "velocity-verlet (nve/sphere), fixed moments in LAMMPS' lj/cut/dipole/cut (no magdem in the loop), {procs} MPI process(es)"
        ),
        _ => "velocity-verlet (nve/sphere)".to_string(),
    };
    store(engine, &integrator, scene, output, &frames, Cost { wall_time: start.elapsed(), threads: procs })?;
    Ok(ReferenceRun { frames: frames.len(), log, wall_time: start.elapsed() })
}

/// The engine's binary, under `mpirun -np procs` when procs > 1. The MPI environment of this
/// process is not passed on: after an in-process engine has initialised MPI here (the callback
/// route), its OMPI_/PMIX_ variables would make the child `mpirun` fail as a nested launch.
pub fn engine_command(engine: Engine, procs: usize) -> Command {
    if procs <= 1 {
        return Command::new(engine.binary());
    }
    let mut mpirun = Command::new("mpirun");
    mpirun.args(["--allow-run-as-root", "--oversubscribe", "-np", &procs.to_string(), engine.binary()]);
    for (name, _) in std::env::vars_os() {
        if name.to_str().is_some_and(|n| ["OMPI_", "PMIX_", "PMI_"].iter().any(|p| n.starts_with(p))) {
            mpirun.env_remove(name);
        }
    }
    mpirun
}

/// Writes a finished reference run's frames as a completed trajectory in magdem's schema.
fn store(
    engine: Engine,
    integrator: &str,
    scene: &Scene,
    output: &Path,
    frames: &[crate::core::state::State],
    cost: Cost,
) -> Result<(), ReferenceError> {
    let mut writer = TrajectoryWriter::create(output, &scene.into(), &RunInfo { engine: engine.name(), integrator })?;
    for state in frames {
        writer.write_frame(state)?;
    }
    writer.finish(status::COMPLETED, "", cost)?;
    Ok(())
}
