//! `magdem experiment FILE`: runs every point of an experiment (in parallel, one HDF5 file per
//! run, a manifest beside them), skipping runs already complete, resuming interrupted ones, and
//! refusing to overwrite a finished run whose scene changed unless told to.

use crate::io::trajectory::{status, Trajectory};
use crate::reference::{self, Engine};
use crate::run::{run, RunFailure, RunOptions, INTERRUPTED};
use crate::scene::experiment::{Experiment, Point};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Instant;

#[derive(Debug, Clone, Default)]
pub struct ExperimentOptions {
    /// Runs at once (default: the number of cores).
    pub jobs: Option<usize>,
    /// Replace finished runs whose scene changed (otherwise they are kept and reported).
    pub overwrite_changed: bool,
    pub progress: bool,
}

/// What happened to one point.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Completed,
    Resumed,
    /// Already complete with the same scene.
    Skipped,
    /// Finished earlier with a different scene; kept.
    KeptChanged { old_hash: String },
    Failed(String),
    Interrupted,
}

impl Outcome {
    pub fn label(&self) -> String {
        match self {
            Outcome::Completed => "completed".into(),
            Outcome::Resumed => "resumed".into(),
            Outcome::Skipped => "skipped (complete)".into(),
            Outcome::KeptChanged { old_hash } => format!("kept: finished with another scene ({})", &old_hash[..12.min(old_hash.len())]),
            Outcome::Failed(why) => format!("failed: {why}"),
            Outcome::Interrupted => "interrupted".into(),
        }
    }
}

pub struct PointResult {
    pub id: String,
    pub file: PathBuf,
    pub outcome: Outcome,
    pub wall_time: f64,
}

fn existing(file: &Path) -> Option<(String, String)> {
    let t = Trajectory::open(file).ok()?;
    Some((t.attr_string("status").ok()?, t.attr_string("scene_sha256").ok()?))
}

fn run_point(point: &Point, file: &Path, options: &ExperimentOptions) -> Outcome {
    if INTERRUPTED.load(Ordering::Relaxed) {
        return Outcome::Interrupted;
    }
    let hash = &point.scene.hash;
    let mut resume = false;
    if let Some((state, old_hash)) = existing(file) {
        match (state == status::COMPLETED, &old_hash == hash) {
            (true, true) => return Outcome::Skipped,
            (true, false) if !options.overwrite_changed => return Outcome::KeptChanged { old_hash },
            (false, true) if point.engine == "magdem" => resume = true,
            _ => {}
        }
    }
    let result = match point.engine.as_str() {
        "magdem" => run(&point.scene, file, &RunOptions { resume, ..Default::default() }).map(|_| ()).map_err(|e| match e {
            RunFailure::Interrupted { .. } => None,
            other => Some(other.to_string()),
        }),
        name => {
            let engine = if name == "liggghts" { Engine::Liggghts } else { Engine::Lammps };
            reference::run(engine, &point.scene, &file.with_extension(format!("{name}.deck")), file).map(|_| ()).map_err(|e| Some(e.to_string()))
        }
    };
    match result {
        Ok(()) if resume => Outcome::Resumed,
        Ok(()) => Outcome::Completed,
        Err(None) => Outcome::Interrupted,
        Err(Some(why)) => Outcome::Failed(why.replace('\n', " ")),
    }
}

/// Runs the experiment and writes `manifest.csv` in its output directory.
pub fn run_experiment(experiment: &Experiment, options: &ExperimentOptions) -> Result<Vec<PointResult>, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(&experiment.output)?;
    let bar = if options.progress { ProgressBar::new(experiment.points.len() as u64) } else { ProgressBar::hidden() };
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} runs | {elapsed} | ETA {eta} | {msg}")?);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(options.jobs.unwrap_or_else(rayon::current_num_threads).max(1)).build()?;
    let results: Vec<PointResult> = pool.install(|| {
        experiment
            .points
            .par_iter()
            .map(|point| {
                let file = experiment.output.join(format!("{}.h5", point.id));
                let start = Instant::now();
                let outcome = run_point(point, &file, options);
                bar.inc(1);
                bar.set_message(format!("{}: {}", point.id, outcome.label()));
                PointResult { id: point.id.clone(), file, outcome, wall_time: start.elapsed().as_secs_f64() }
            })
            .collect()
    });
    bar.finish_and_clear();
    write_manifest(experiment, &results)?;
    Ok(results)
}

fn csv_field(text: &str) -> String {
    format!("\"{}\"", text.replace('"', "\"\""))
}

fn write_manifest(experiment: &Experiment, results: &[PointResult]) -> std::io::Result<()> {
    let mut csv = String::from("id,base,overrides,engine,scene_sha256,outcome,wall_time_s,file\n");
    for (point, r) in experiment.points.iter().zip(results) {
        let overrides = point.overrides.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join("; ");
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{:.3},{}",
            csv_field(&point.id),
            csv_field(&point.base.display().to_string()),
            csv_field(&overrides),
            point.engine,
            point.scene.hash,
            csv_field(&r.outcome.label()),
            r.wall_time,
            csv_field(&r.file.display().to_string())
        );
    }
    std::fs::write(experiment.output.join("manifest.csv"), csv)
}
