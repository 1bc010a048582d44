//! The run driver: steps a scene's simulation, writes frames and checkpoints, shows progress,
//! stops cleanly on Ctrl-C and on instability. Outside the physics core.

use crate::core::simulation::{RunError, Simulation};
use crate::core::timers::PhaseTimers;
use crate::io::trajectory::{status, RunInfo, TrajectoryError, TrajectoryWriter};
use crate::scene::Scene;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Set by the Ctrl-C handler; the run loop checkpoints and stops when it sees it.
pub static INTERRUPTED: AtomicBool = AtomicBool::new(false);

#[derive(Debug, Default, Clone)]
pub struct RunOptions {
    pub resume: bool,
    pub progress: bool,
    /// Time each step phase (`Simulation::timers`); costs a few per cent on small scenes.
    pub timings: bool,
    /// Testing aid: abort the process (no clean-up, like a kill) right after writing this frame.
    pub abort_after_frame: Option<usize>,
}

#[derive(Debug, thiserror::Error)]
pub enum RunFailure {
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    #[error(transparent)]
    Unstable(#[from] RunError),
    #[error("interrupted at step {step} (t = {time:.6e} s); the checkpoint is saved: rerun with --resume to continue")]
    Interrupted { step: u64, time: f64 },
}

/// How a finished run went.
pub struct RunSummary {
    pub steps: u64,
    pub frames: usize,
    pub wall_time: Duration,
    pub already_complete: bool,
    pub simulation: Simulation,
}

/// Runs `scene` into `output`, from t = 0 or (with `resume`) from the file's checkpoint. The run
/// executes on a thread of the current rayon pool, so that a step's parallel loops start from
/// inside the pool instead of handing work over from outside it at every step.
pub fn run(scene: &Scene, output: &Path, options: &RunOptions) -> Result<RunSummary, RunFailure> {
    rayon::scope(|_| run_in_pool(scene, output, options))
}

fn run_in_pool(scene: &Scene, output: &Path, options: &RunOptions) -> Result<RunSummary, RunFailure> {
    let start = Instant::now();
    let total = scene.total_steps();
    let per_frame = scene.steps_per_frame();
    let info = RunInfo { engine: "magdem", integrator: &scene.spec.integration.scheme };

    let (mut writer, mut sim) = if options.resume && output.exists() {
        let (writer, state) = TrajectoryWriter::resume(output, scene)?;
        (writer, scene.simulation(Some(state)))
    } else {
        let writer = TrajectoryWriter::create(output, scene, &info)?;
        let mut sim = scene.simulation(None);
        if let Err(e) = sim.initialise() {
            writer.finish(status::UNSTABLE, &e.to_string(), start.elapsed())?;
            return Err(e.into());
        }
        let mut writer = writer;
        writer.write_frame(&sim.state)?;
        (writer, sim)
    };
    if options.timings {
        sim.field.timers = PhaseTimers::enabled();
    }
    let already_complete = sim.state.step >= total;

    let bar = if options.progress { ProgressBar::new(total) } else { ProgressBar::hidden() };
    if options.progress {
        bar.set_draw_target(ProgressDrawTarget::stderr_with_hz(4));
        bar.set_style(
            ProgressStyle::with_template("{bar:30} {percent:>3}% t = {msg} | {per_sec} | ETA {eta}")
                .expect("valid template"),
        );
    }
    bar.set_position(sim.state.step);
    let end_time = total as f64 * scene.dt();

    while sim.state.step < total {
        if let Err(e) = sim.step() {
            bar.abandon();
            writer.finish(status::UNSTABLE, &e.to_string(), start.elapsed())?;
            return Err(e.into());
        }
        let step = sim.state.step;
        if step % per_frame == 0 || step == total {
            writer.write_frame(&sim.state)?;
            if options.abort_after_frame == Some(writer.frames()) {
                std::process::abort();
            }
        }
        if step / 256 != (step - sim.integrator.steps_per_call()) / 256 {
            bar.set_position(step);
            bar.set_message(format!("{:.4e} / {:.4e} s", sim.state.time, end_time));
        }
        if INTERRUPTED.load(Ordering::Relaxed) {
            bar.abandon();
            writer.write_checkpoint(&sim.state)?;
            writer.finish(status::INTERRUPTED, "interrupted by the user", start.elapsed())?;
            return Err(RunFailure::Interrupted { step, time: sim.state.time });
        }
    }
    bar.finish_and_clear();
    writer.finish(status::COMPLETED, "", start.elapsed())?;
    Ok(RunSummary {
        steps: sim.state.step,
        frames: writer.frames(),
        wall_time: start.elapsed(),
        already_complete,
        simulation: sim,
    })
}
