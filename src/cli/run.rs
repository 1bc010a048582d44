//! `magdem run SCENE`: a scene in magdem's solver or, from a generated deck, in a reference code.

use super::{current_exe, fail, load, stop_on_ctrl_c};
use magdem::core::neighbours::PairRange;
use magdem::reference::{self, deck::Coupling, Engine, ReferenceError};
use magdem::run::{run as run_scene, RunFailure, RunOptions, RunSummary};
use magdem::scene::Scene;
use std::path::Path;
use std::process::ExitCode;

/// `magdem run --engine`: magdem's own solver or a reference engine.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum EngineChoice {
    Magdem,
    Reference(Engine),
}

impl clap::ValueEnum for EngineChoice {
    fn value_variants<'a>() -> &'a [Self] {
        static ALL: std::sync::OnceLock<Vec<EngineChoice>> = std::sync::OnceLock::new();
        ALL.get_or_init(|| {
            std::iter::once(EngineChoice::Magdem)
                .chain(Engine::all().iter().map(|&e| EngineChoice::Reference(e)))
                .collect()
        })
    }
    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(match self {
            EngineChoice::Magdem => "magdem",
            EngineChoice::Reference(engine) => engine.name(),
        }))
    }
}

/// How a reference code gets its magnetic forces and how many processes it runs on.
pub struct CouplingChoice {
    /// The files route every K steps.
    pub exchange_every: Option<u64>,
    pub mpi: usize,
    /// LAMMPS' own dipole pair style ([`Coupling::Native`]).
    pub native: bool,
}

/// Runs the scene at `path` into `output` with the chosen engine; `coupling` applies to the
/// reference codes only.
pub fn run(
    path: &Path,
    output: &Path,
    engine: EngineChoice,
    coupling: CouplingChoice,
    options: &RunOptions,
) -> ExitCode {
    let scene = match load(path) {
        Ok(s) => s,
        Err(code) => return code,
    };
    match engine {
        EngineChoice::Magdem => run_native(&scene, output, options),
        EngineChoice::Reference(engine) => run_reference(engine, &scene, output, coupling),
    }
}

/// A reference code on the scene's deck (beside the output, `OUTPUT.ENGINE.deck/`): in process
/// for magnetic scenes, its binary otherwise, by the files route with `--exchange-every`.
fn run_reference(engine: Engine, scene: &Scene, output: &Path, coupling: CouplingChoice) -> ExitCode {
    let dir = output.with_extension(format!("{}.deck", engine.name()));
    let CouplingChoice { exchange_every, mpi, native } = coupling;
    let result = match exchange_every {
        _ if native => reference::run_binary(engine, scene, &dir, output, &Coupling::Native, mpi),
        Some(every) => {
            reference::run_binary(engine, scene, &dir, output, &Coupling::Files { magdem: current_exe(), every }, mpi)
        }
        None if mpi > 1 && scene.magnetic_force_field().is_some() => {
            eprintln!("error: --mpi {mpi}: magnetic forces reach MPI processes only by the files route; add --exchange-every K");
            return ExitCode::from(2);
        }
        None if mpi > 1 => reference::run_binary(engine, scene, &dir, output, &Coupling::Callback, mpi),
        None => reference::run(engine, scene, &dir, output),
    };
    match result {
        Ok(r) => {
            println!(
                "{}: {} frames from {} in {:.2} s (deck and dump in {}, log {})",
                output.display(),
                r.frames,
                engine.name(),
                r.wall_time.as_secs_f64(),
                dir.display(),
                r.log.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            let code = match e {
                ReferenceError::Unsupported { .. } | ReferenceError::NotInstalled { .. } => 2,
                _ => 1,
            };
            fail(e, code)
        }
    }
}

/// magdem's own solver: warnings first, then the run (Ctrl-C checkpoints it), then its summary.
fn run_native(scene: &Scene, output: &Path, options: &RunOptions) -> ExitCode {
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
        if let Err(e) = std::fs::create_dir_all(dir) {
            eprintln!("error: cannot create {}: {e}", dir.display());
            return ExitCode::from(2);
        }
    }
    stop_on_ctrl_c();
    match run_scene(scene, output, options) {
        Ok(summary) => {
            print_summary(output, &summary);
            if options.timings {
                print_timings(&summary);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            let code = match e {
                RunFailure::Interrupted { .. } => 130,
                RunFailure::Unstable(_) => 3,
                RunFailure::Trajectory(_) => 1,
                RunFailure::Refused(_) => 2,
                RunFailure::DiskFull { .. } => 1,
            };
            fail(e, code)
        }
    }
}

fn print_summary(output: &Path, summary: &RunSummary) {
    if summary.already_complete {
        println!("{} is already complete ({} frames); nothing to do", output.display(), summary.frames);
    } else {
        let secs = summary.wall_time.as_secs_f64();
        println!(
            "{}: {} steps, {} frames in {:.2} s ({:.0} steps/s)",
            output.display(),
            summary.steps,
            summary.frames,
            secs,
            summary.steps as f64 / secs.max(1e-9)
        );
    }
}

/// `--timings`: wall time per step phase and its share of the total.
fn print_timings(summary: &RunSummary) {
    let total: f64 = summary.simulation.timers().phases().iter().map(|p| p.1.as_secs_f64()).sum();
    println!("phase timings:");
    for (name, d) in summary.simulation.timers().phases() {
        println!("  {name:<12} {:>9.3} s  {:>5.1}%", d.as_secs_f64(), 100.0 * d.as_secs_f64() / total.max(1e-12));
    }
    println!("neighbour ranges (neighbours: candidate upkeep and rebuilds; pair-list: filtering the listed pairs):");
    for u in summary.simulation.neighbour_usage() {
        let mut listed = format!("{} listed", u.listed);
        if let Some((count, skin, builds)) = u.close {
            listed = format!("{count} close candidates (skin {skin:.3e} m, taken {builds} times), {listed}");
        }
        match u.range {
            PairRange::Within { range, skin } => println!(
                "  within {range:.3e} m, skin up to {skin:.3e} m: {} rebuilds, every particle examined at {} updates \
                 (the others settled by the drifts' bound), skin in use {:.3e} m, {} candidates, {listed}",
                u.rebuilds, u.examined, u.skin_in_use, u.candidates
            ),
            PairRange::All => println!("  all pairs: searched at every evaluation, {listed}"),
        }
    }
    let particles = summary.simulation.state.particles.len();
    if rayon::current_num_threads() == 2 && particles >= magdem::core::parallel::MIN_PARALLEL_LEN {
        let balance = &summary.simulation.balance;
        println!("two threads: the first share held {:.1} % of the particles at the end", 100.0 * balance.first());
        let g = balance.gaps();
        if g.loops > 0 {
            println!(
                "  {} loops in two shares: the later share ended {:.1} µs after the other on average, {:.1} % of a loop's time",
                g.loops,
                1e6 * g.gap / g.loops as f64,
                100.0 * g.gap / g.span
            );
        }
    }
}
