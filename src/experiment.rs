//! `magdem experiment FILE…`: runs every point of one or more experiments (in parallel, longest
//! first, one HDF5 file per run, a manifest beside each experiment's runs), skipping runs already
//! complete, resuming interrupted ones, and refusing to overwrite a finished run whose scene
//! changed unless told to. A run that goes unstable is a result, recorded as such, not retried.
//! A run that a report's digest records as finished with the same scene is not run again: the
//! digests are how an ensemble grows across machines that do not keep each other's trajectories.

use crate::io::trajectory::{status, Trajectory};
use crate::reference::{self, Engine};
use crate::report::digest::{self, Recorded};
use crate::run::{run, RunFailure, RunOptions, INTERRUPTED};
use crate::scene::experiment::{Experiment, Point};
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt::Write as _;
use std::io::{stderr, stdout, IsTerminal};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

#[derive(Debug, Clone, Default)]
pub struct ExperimentOptions {
    /// Runs at once (default: the number of cores).
    pub jobs: Option<usize>,
    /// Replace finished runs whose scene changed (otherwise they are kept and reported).
    pub overwrite_changed: bool,
    pub progress: bool,
    /// Reports' digest directories (`reports/*/digests`): a run one records as finished with the
    /// same scene is taken as done.
    pub digests: Vec<PathBuf>,
}

/// What happened to one point.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    Completed,
    Resumed,
    /// Already complete with the same scene.
    Skipped,
    /// A report's digest records it as complete with the same scene (its trajectory is elsewhere).
    Digested,
    /// Finished earlier with a different scene; kept.
    KeptChanged {
        old_hash: String,
    },
    /// The solver stopped the run (instability monitor); the message says why.
    Unstable(String),
    /// A reference engine the point asks for is not installed (not a failure: the report shows
    /// the point as missing).
    EngineMissing(&'static str),
    Failed(String),
    Interrupted,
}

impl Outcome {
    pub fn label(&self) -> String {
        match self {
            Outcome::Completed => "completed".into(),
            Outcome::Resumed => "resumed".into(),
            Outcome::Skipped => "skipped (complete)".into(),
            Outcome::Digested => "skipped (complete in a report's digest)".into(),
            Outcome::KeptChanged { old_hash } => {
                format!("kept: finished with another scene ({})", &old_hash[..12.min(old_hash.len())])
            }
            Outcome::Unstable(why) => format!("unstable: {why}"),
            Outcome::EngineMissing(engine) => format!("not run: {engine} is not installed"),
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

/// Status, scene hash and status message of an existing run file.
fn existing(file: &Path) -> Option<(String, String, String)> {
    let t = Trajectory::open(file).ok()?;
    Some((
        t.attr_string("status").ok()?,
        t.attr_string("scene_sha256").ok()?,
        t.attr_string("status_message").unwrap_or_default(),
    ))
}

fn run_point(point: &Point, file: &Path, digested: Option<&Recorded>, options: &ExperimentOptions) -> Outcome {
    if INTERRUPTED.load(Ordering::Relaxed) {
        return Outcome::Interrupted;
    }
    let hash = &point.scene.hash;
    if let Some(d) = digested.filter(|d| &d.scene_hash == hash) {
        return match d.status.as_str() {
            status::UNSTABLE => Outcome::Unstable(d.message.clone()),
            _ => Outcome::Digested,
        };
    }
    let mut resume = false;
    if let Some((state, old_hash, message)) = existing(file) {
        if state == status::UNSTABLE && &old_hash == hash {
            return Outcome::Unstable(message);
        }
        match (state == status::COMPLETED, &old_hash == hash) {
            (true, true) => return Outcome::Skipped,
            (true, false) if !options.overwrite_changed => return Outcome::KeptChanged { old_hash },
            (false, true) if point.engine == "magdem" => resume = true,
            _ => {}
        }
    }
    let result = match point.engine.as_str() {
        // The runner has decided above which existing files it may replace.
        "magdem" => {
            let go = |resume: bool| {
                run(&point.scene, file, &RunOptions { resume, overwrite: !resume, ..Default::default() })
            };
            let mut outcome = go(resume);
            // A file killed while it was being written may hold a checkpoint that cannot be read
            // back (a torn HDF5 write). The run was not finished, and it is deterministic: it
            // starts again from t = 0 and ends the same.
            if resume && matches!(outcome, Err(RunFailure::Trajectory(_))) {
                resume = false;
                outcome = go(false);
            }
            match outcome {
                Err(RunFailure::Unstable(e)) => return Outcome::Unstable(e.to_string().replace('\n', " ")),
                other => other.map(|_| ()).map_err(|e| match e {
                    RunFailure::Interrupted { .. } => None,
                    other => Some(other.to_string()),
                }),
            }
        }
        name => {
            let Some(engine) = Engine::named(name) else {
                return Outcome::Failed(format!("no engine named {name}"));
            };
            if !engine.available() {
                return Outcome::EngineMissing(engine.name());
            }
            reference::run(engine, &point.scene, &file.with_extension(format!("{name}.deck")), file)
                .map(|_| ())
                .map_err(|e| Some(e.to_string()))
        }
    };
    match result {
        Ok(()) if resume => Outcome::Resumed,
        Ok(()) => Outcome::Completed,
        Err(None) => Outcome::Interrupted,
        Err(Some(why)) => Outcome::Failed(why.replace('\n', " ")),
    }
}

/// Rough cost of a point for scheduling: steps × particles (reference engines count double).
fn cost(point: &Point) -> f64 {
    let factor = if point.engine == "magdem" { 1.0 } else { 2.0 };
    factor * point.scene.total_steps() as f64 * point.scene.initial.len() as f64
}

/// The order points are started in, as (experiment, point) indices: the most expensive first, and
/// equal costs seed by seed, so that an experiment cut short has its variants at equal seeds.
pub fn run_order(experiments: &[Experiment]) -> Vec<(usize, usize)> {
    let point = |(e, p): (usize, usize)| &experiments[e].points[p];
    let mut queue: Vec<(usize, usize)> =
        experiments.iter().enumerate().flat_map(|(e, x)| (0..x.points.len()).map(move |p| (e, p))).collect();
    queue.sort_by(|&a, &b| {
        cost(point(b)).total_cmp(&cost(point(a))).then(point(a).scene.spec.seed.cmp(&point(b).scene.spec.seed))
    });
    queue
}

/// Runs every point of `experiments` on `jobs` workers in [`run_order`], and writes the
/// `manifest.csv` of each output directory (experiment files that continue one experiment share
/// one). Results come back per experiment, in point order. Two points with one output file (the
/// same id in one output directory) are refused before anything runs.
pub fn run_experiments(
    experiments: &[Experiment],
    options: &ExperimentOptions,
) -> Result<Vec<Vec<PointResult>>, Box<dyn std::error::Error>> {
    let mut files = std::collections::HashSet::new();
    for e in experiments {
        if let Some(p) = e.points.iter().find(|p| !files.insert(e.output.join(&p.id))) {
            return Err(format!(
                "experiment `{}`: run `{}` in {} is listed by two experiment files (or twice); each run belongs to one",
                e.spec.name,
                p.id,
                e.output.display()
            )
            .into());
        }
    }
    for experiment in experiments {
        std::fs::create_dir_all(&experiment.output)?;
    }
    let queue = run_order(experiments);
    let recorded =
        experiments.iter().map(|e| digest::recorded(&options.digests, &e.spec.name)).collect::<Result<Vec<_>, _>>()?;
    // A progress bar on stderr when it is a terminal; one line per finished run on stdout when
    // stdout is not a terminal (a log file, a pipe, CI) or the bar cannot be shown.
    let bar_shown = options.progress && stderr().is_terminal();
    let lines = options.progress && !(stdout().is_terminal() && stderr().is_terminal());
    let bar = if bar_shown { ProgressBar::new(queue.len() as u64) } else { ProgressBar::hidden() };
    let finished = AtomicUsize::new(0);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} runs | {elapsed} | ETA {eta} | {msg}")?);
    let next = AtomicUsize::new(0);
    let done: Mutex<Vec<Vec<Option<PointResult>>>> =
        Mutex::new(experiments.iter().map(|e| e.points.iter().map(|_| None).collect()).collect());
    let cores = rayon::current_num_threads();
    let workers = options.jobs.unwrap_or(cores).max(1).min(queue.len().max(1));
    // Each worker's runs get their own share of the cores (one thread each when the runs fill
    // them): runs do not compete for one pool, and results do not depend on it.
    let threads_per_run = (cores / workers).max(1);
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads_per_run).build().expect("a thread pool");
                pool.install(|| {
                    while let Some(&(e, p)) = queue.get(next.fetch_add(1, Ordering::Relaxed)) {
                        let point = &experiments[e].points[p];
                        let file = experiments[e].output.join(format!("{}.h5", point.id));
                        let start = Instant::now();
                        let outcome = run_point(point, &file, recorded[e].get(&point.id), options);
                        bar.inc(1);
                        bar.set_message(format!("{}: {}", point.id, outcome.label()));
                        let wall_time = start.elapsed().as_secs_f64();
                        let count = finished.fetch_add(1, Ordering::Relaxed) + 1;
                        if lines {
                            println!(
                                "{}: {} ({wall_time:.0} s; {} of {} runs left)",
                                point.id,
                                outcome.label(),
                                queue.len() - count,
                                queue.len()
                            );
                        }
                        let result = PointResult { id: point.id.clone(), file, outcome, wall_time };
                        done.lock().expect("no worker panicked")[e][p] = Some(result);
                    }
                });
            });
        }
    });
    bar.finish_and_clear();
    let results: Vec<Vec<PointResult>> = done
        .into_inner()
        .expect("no worker panicked")
        .into_iter()
        .map(|r| r.into_iter().map(|x| x.expect("every point ran")).collect())
        .collect();
    // One manifest per output directory: files that continue one experiment (same name, other
    // seeds) share it, and each lists its points there; runs of earlier calls stay listed.
    let mut outputs: Vec<&Path> = experiments.iter().map(|e| e.output.as_path()).collect();
    outputs.sort();
    outputs.dedup();
    for output in outputs {
        let sharing = experiments.iter().zip(&results).filter(|(e, _)| e.output == output);
        write_manifest(output, sharing)?;
    }
    Ok(results)
}

/// [`run_experiments`] for one experiment.
pub fn run_experiment(
    experiment: &Experiment,
    options: &ExperimentOptions,
) -> Result<Vec<PointResult>, Box<dyn std::error::Error>> {
    Ok(run_experiments(std::slice::from_ref(experiment), options)?.pop().unwrap_or_default())
}

fn csv_field(text: &str) -> String {
    format!("\"{}\"", text.replace('"', "\"\""))
}

fn write_manifest<'a>(
    output: &Path,
    experiments: impl Iterator<Item = (&'a Experiment, &'a Vec<PointResult>)>,
) -> std::io::Result<()> {
    const HEADER: &str = "id,base,variant,overrides,engine,scene_sha256,outcome,wall_time_s,file";
    let path = output.join("manifest.csv");
    let rows: Vec<_> = experiments.flat_map(|(e, results)| e.points.iter().zip(results)).collect();
    // Rows of earlier calls for points this call did not run (other seeds, other files) are kept.
    let written: std::collections::HashSet<String> = rows.iter().map(|(point, _)| csv_field(&point.id)).collect();
    let earlier = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => String::new(),
        Err(e) => return Err(e),
    };
    let mut csv = format!("{HEADER}\n");
    // Only rows of the same layout are kept.
    let same_layout = earlier.lines().next() == Some(HEADER);
    let kept = earlier
        .lines()
        .skip(1)
        .filter(|line| same_layout && quoted_field(line).is_some_and(|id| !written.contains(id)));
    kept.for_each(|line| {
        csv.push_str(line);
        csv.push('\n');
    });
    for (point, r) in rows {
        let overrides = point.overrides.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join("; ");
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{:.3},{}",
            csv_field(&point.id),
            csv_field(&point.base.display().to_string()),
            point.variant.as_deref().unwrap_or(""),
            csv_field(&overrides),
            point.engine,
            point.scene.hash,
            csv_field(&r.outcome.label()),
            r.wall_time,
            csv_field(&r.file.display().to_string())
        );
    }
    // Written beside and renamed into place: an interrupted write leaves the previous manifest.
    let partial = output.join("manifest.csv.partial");
    std::fs::write(&partial, csv)?;
    std::fs::rename(partial, path)
}

/// The quoted first field of a CSV row as [`csv_field`] writes it (quotes included, an inner
/// quote doubled), or `None` if the row does not start with one.
fn quoted_field(line: &str) -> Option<&str> {
    let rest = line.strip_prefix('"')?;
    let mut chars = rest.char_indices().peekable();
    while let Some((k, c)) = chars.next() {
        if c == '"' && chars.next_if(|&(_, c)| c == '"').is_none() {
            return Some(&line[..k + 2]);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The id a manifest row starts with, as `csv_field` wrote it, whatever it holds.
    #[test]
    fn a_row_id_is_read_back_as_written() {
        for id in ["case1__seed-1", "a,b__seed-2", "say \"x\"", ""] {
            let row = format!("{},base,,\"\",magdem", csv_field(id));
            assert_eq!(quoted_field(&row), Some(csv_field(id).as_str()), "{row}");
        }
        assert_eq!(quoted_field("id,base"), None);
        assert_eq!(quoted_field("\"unterminated"), None);
    }
}
