//! The run driver: steps a scene's simulation, writes frames and checkpoints, shows progress,
//! stops cleanly on Ctrl-C and on instability. Outside the physics core.

use crate::core::simulation::{RunError, Simulation};
use crate::core::timers::PhaseTimers;
use crate::io::trajectory::{status, Cost, RunHeader, RunInfo, TrajectoryError, TrajectoryWriter};
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
    /// Replace an existing output file (otherwise it is refused, whatever its status).
    pub overwrite: bool,
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
    /// The output is not ours to write: it exists, or another process holds it (exit 2).
    #[error("{0}")]
    Refused(String),
    /// The disk holding the output is too full for the next frame; the run stopped before
    /// writing it, so that the file ends on a complete frame and checkpoint (exit 1).
    #[error(
        "stopped before frame {frame} of {path}: its disk has {free} bytes free and a frame needs about {needed}; the file keeps \
         frames 0-{last} and their checkpoint: free space and rerun with --resume"
    )]
    DiskFull { path: String, frame: usize, last: usize, free: u64, needed: u64 },
}

impl<'a> From<&'a Scene> for RunHeader<'a> {
    fn from(scene: &'a Scene) -> Self {
        RunHeader {
            scene_text: &scene.text,
            scene_hash: &scene.hash,
            scene_name: scene.spec.name.as_deref().unwrap_or(""),
            species_names: scene.species.iter().map(|s| s.name.as_str()).collect(),
            initial: &scene.initial,
            dt: scene.dt(),
            total_steps: scene.total_steps(),
            steps_per_frame: scene.steps_per_frame(),
            forces: scene.spec.output.forces,
            contacts: scene.spec.output.contacts,
            outlets: scene.spec.exits.iter().flat_map(|e| &e.outlets).map(|o| o.name.as_str()).collect(),
        }
    }
}

/// Free bytes for an unprivileged writer on the file system holding `path` (its directory).
fn free_space(path: &Path) -> Option<u64> {
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let c = std::ffi::CString::new(dir.as_os_str().as_encoded_bytes()).ok()?;
    let mut stat: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `c` is a valid NUL-terminated path and `stat` a writable statvfs.
    (unsafe { libc::statvfs(c.as_ptr(), &mut stat) } == 0).then(|| stat.f_bavail as u64 * stat.f_frsize as u64)
}

/// Uncompressed bytes of one frame's per-particle vectors: position, velocity, angular velocity
/// and moment, with force and torque when the scene writes them.
fn frame_vector_bytes(scene: &Scene) -> u64 {
    let vectors = if scene.spec.output.forces { 6 } else { 4 };
    scene.initial.len() as u64 * 24 * vectors
}

/// Bytes the next frame may take: twice the uncompressed frame and checkpoint (HDF5 may
/// allocate the new chunks before it frees anything) plus 256 KiB for metadata.
fn frame_budget(scene: &Scene, contacts: usize) -> u64 {
    let n = scene.initial.len() as u64;
    let frame = frame_vector_bytes(scene) + contacts as u64 * 16;
    let checkpoint = n * 24 * 9 + contacts as u64 * 40;
    2 * (frame + checkpoint) + 256 * 1024
}

/// Refuses to write frame `frame` when the disk cannot hold it.
fn check_space(scene: &Scene, output: &Path, frame: usize, contacts: usize) -> Result<(), RunFailure> {
    let needed = frame_budget(scene, contacts);
    match free_space(output) {
        Some(free) if free < needed => Err(RunFailure::DiskFull {
            path: output.display().to_string(),
            frame,
            last: frame.saturating_sub(1),
            free,
            needed,
        }),
        _ => Ok(()),
    }
}

/// How far compression could shrink a run's frames at most, for the check before it starts.
const COMPRESSION_LIMIT: f64 = 10.0;

/// Refuses, before anything is written, a run whose frames (without contacts) would not fit on
/// the output's disk even compressed tenfold: floating-point frames rarely compress below half
/// their size, so such a run can only stop on a full disk. Nearer the limit the run starts, and
/// stops cleanly before the frame that does not fit ([`RunFailure::DiskFull`]).
fn check_run_space(scene: &Scene, output: &Path) -> Result<(), RunFailure> {
    let frames = scene.total_steps() / scene.steps_per_frame() + 1;
    let frame = frame_vector_bytes(scene) as f64;
    let needed = frames as f64 * frame;
    match free_space(output) {
        Some(free) if needed > COMPRESSION_LIMIT * free as f64 => Err(RunFailure::Refused(format!(
            "integration.end_time = {:e} with output.interval = {:e} s gives {frames} frames of {:.3e} bytes ({needed:.3e} in all), \
             uncompressed, more than ten times the {free} bytes free on the disk of {}: shorten the run or write fewer frames",
            scene.spec.integration.end_time,
            scene.steps_per_frame() as f64 * scene.dt(),
            frame,
            output.display(),
        ))),
        _ => Ok(()),
    }
}

/// An exclusive lock on `<output>.lock` for the life of a run: a second process writing the
/// same file is refused at start. The operating system releases the lock when the process ends,
/// however it ends (a `kill -9` leaves the lock file but not the lock).
/// The lock file is left in place: removing it while locked would let a process that opened it
/// just before and one that creates it anew both hold "the" lock.
struct OutputLock {
    _file: std::fs::File,
}

impl OutputLock {
    fn acquire(output: &Path) -> Result<Self, RunFailure> {
        let mut name = output.as_os_str().to_owned();
        name.push(".lock");
        let path = std::path::PathBuf::from(name);
        let file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| RunFailure::Refused(format!("cannot create the lock {}: {e}", path.display())))?;
        match file.try_lock() {
            Ok(()) => Ok(Self { _file: file }),
            Err(std::fs::TryLockError::WouldBlock) => Err(RunFailure::Refused(format!(
                "{} is being written by another magdem process (it holds {})",
                output.display(),
                path.display()
            ))),
            Err(std::fs::TryLockError::Error(e)) => {
                Err(RunFailure::Refused(format!("cannot lock {}: {e}", path.display())))
            }
        }
    }
}

/// Refuses an existing output that `options` do not allow to touch: without `--resume` or
/// `--overwrite` any existing file; with `--resume` a completed file of another scene.
fn check_existing(scene: &Scene, output: &Path, options: &RunOptions) -> Result<(), RunFailure> {
    if !output.exists() || options.overwrite {
        return Ok(());
    }
    let described = crate::io::trajectory::Trajectory::open(output)
        .ok()
        .and_then(|t| Some((t.attr_string("status").ok()?, t.attr_string("scene_sha256").ok()?)));
    let Some((state, hash)) = described else {
        return Err(RunFailure::Refused(format!(
            "{} exists and is not a readable magdem trajectory; give --overwrite to replace it",
            output.display()
        )));
    };
    if !options.resume {
        let same = if hash == scene.hash { "this scene" } else { "another scene" };
        return Err(RunFailure::Refused(format!(
            "{} exists (status {state}, {same}); give --overwrite to replace it{}",
            output.display(),
            if state == status::COMPLETED { "" } else { ", or --resume to continue it" }
        )));
    }
    if state == status::COMPLETED && hash != scene.hash {
        return Err(RunFailure::Refused(format!(
            "{} is a completed run of a different scene (sha256 {}…); --resume continues only the same scene, --overwrite replaces it",
            output.display(),
            &hash[..12.min(hash.len())]
        )));
    }
    Ok(())
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
    if !(options.resume && output.exists()) {
        check_run_space(scene, output)?;
    }
    let _lock = OutputLock::acquire(output)?;
    check_existing(scene, output, options)?;
    let result = rayon::scope(|_| run_in_pool(scene, output, options));
    // The XDMF sidecar describes whatever frames the file holds, however the run ended.
    if output.exists() {
        if let Err(e) = crate::io::export::write_xdmf(output) {
            eprintln!("warning: no XDMF sidecar for {}: {e}", output.display());
        }
    }
    result
}

/// The cost of the piece of a run that began at `start`, on the current pool's threads.
fn cost(start: &Instant) -> Cost {
    Cost { wall_time: start.elapsed(), threads: rayon::current_num_threads() }
}

fn run_in_pool(scene: &Scene, output: &Path, options: &RunOptions) -> Result<RunSummary, RunFailure> {
    let start = Instant::now();
    let total = scene.total_steps();
    let per_frame = scene.steps_per_frame();
    let info = RunInfo { engine: "magdem", integrator: scene.spec.integration.scheme.name() };

    let (mut writer, mut sim) = if options.resume && output.exists() {
        let (writer, state) = TrajectoryWriter::resume(output, &scene.into())?;
        (writer, scene.simulation(Some(state)))
    } else {
        let writer = TrajectoryWriter::create(output, &scene.into(), &info)?;
        let mut sim = scene.simulation(None);
        if let Err(e) = sim.initialise() {
            writer.finish(status::UNSTABLE, &e.to_string(), cost(&start))?;
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
    let checkpoint_multiple = scene.checkpoint_multiple();

    while sim.state.step < total {
        if let Err(e) = sim.step() {
            bar.abandon();
            writer.finish(status::UNSTABLE, &e.to_string(), cost(&start))?;
            return Err(e.into());
        }
        let step = sim.state.step;
        if step % per_frame == 0 || step == total {
            if let Err(e) = check_space(scene, output, writer.frames(), sim.state.history.pairs.len()) {
                bar.abandon();
                writer.finish(status::INTERRUPTED, &e.to_string(), cost(&start))?;
                return Err(e);
            }
            writer.write_frame(&sim.state)?;
            if options.abort_after_frame == Some(writer.frames()) {
                std::process::abort();
            }
        }
        if step / 256 != (step - sim.integrator.steps_per_call()) / 256 {
            bar.set_position(step);
            bar.set_message(format!("{:.4e} / {:.4e} s", sim.state.time, end_time));
        }
        if INTERRUPTED.load(Ordering::Relaxed) && step.is_multiple_of(checkpoint_multiple) {
            bar.abandon();
            writer.write_checkpoint(&sim.state)?;
            writer.finish(status::INTERRUPTED, "interrupted by the user", cost(&start))?;
            return Err(RunFailure::Interrupted { step, time: sim.state.time });
        }
    }
    bar.finish_and_clear();
    writer.finish(status::COMPLETED, "", cost(&start))?;
    Ok(RunSummary {
        steps: sim.state.step,
        frames: writer.frames(),
        wall_time: start.elapsed(),
        already_complete,
        simulation: sim,
    })
}
