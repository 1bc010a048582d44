//! `magdem experiment FILE…`: every point of the experiment files, or with `--dry-run` their list.

use super::{fail, stop_on_ctrl_c};
use magdem::experiment::{run_experiments, ExperimentOptions, Outcome, PointResult};
use magdem::report::digest;
use magdem::scene::experiment::Experiment;
use std::path::PathBuf;
use std::process::ExitCode;

pub fn experiment(files: &[PathBuf], options: &ExperimentOptions, dry_run: bool) -> ExitCode {
    let mut experiments = vec![];
    for file in files {
        match Experiment::from_file(file) {
            Ok(e) => experiments.push(e),
            Err(e) => {
                eprintln!("error: {}: {e}", file.display());
                return ExitCode::from(2);
            }
        }
    }
    if dry_run {
        return match list_points(&experiments, &options.digests) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => fail(e, 1),
        };
    }
    stop_on_ctrl_c();
    match run_experiments(&experiments, options) {
        Ok(all) => {
            let mut failed = false;
            for (experiment, results) in experiments.iter().zip(&all) {
                failed |= report_outcomes(results);
                println!(
                    "{}: {} runs in {} (manifest.csv)",
                    experiment.spec.name,
                    results.len(),
                    experiment.output.display()
                );
            }
            if failed {
                ExitCode::from(1)
            } else {
                ExitCode::SUCCESS
            }
        }
        Err(e) => fail(e, 1),
    }
}

/// Every `reports/*/digests` directory under the current directory, in name order.
pub fn report_digests() -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir("reports")
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path().join("digests"))
        .filter(|d| d.is_dir())
        .collect();
    dirs.sort();
    dirs
}

/// `--dry-run`: each point's output, particles, steps and engine, with its scene's warnings (each
/// printed once, at the first point that has it, with how many points share it), and whether a
/// digest records it as finished.
fn list_points(experiments: &[Experiment], digests: &[PathBuf]) -> Result<(), Box<dyn std::error::Error>> {
    let mut points_with = std::collections::HashMap::<&str, usize>::new();
    for p in experiments.iter().flat_map(|e| &e.points) {
        let distinct: std::collections::HashSet<&str> = p.scene.warnings.iter().map(String::as_str).collect();
        distinct.into_iter().for_each(|w| *points_with.entry(w).or_default() += 1);
    }
    let mut printed = std::collections::HashSet::new();
    for e in experiments {
        let recorded = digest::recorded(digests, &e.spec.name)?;
        for p in &e.points {
            let done = match recorded.get(&p.id) {
                Some(r) if r.scene_hash == p.scene.hash => format!("  ({} in a digest)", r.status),
                _ => String::new(),
            };
            println!(
                "{}/{}.h5  {} particles  {} steps  {}{done}",
                e.output.display(),
                p.id,
                p.scene.initial.len(),
                p.scene.total_steps(),
                p.engine
            );
            for w in p.scene.warnings.iter().filter(|w| printed.insert(w.as_str())) {
                match points_with[w.as_str()] {
                    1 => println!("  warning: {w}"),
                    n => println!("  warning ({n} points): {w}"),
                }
            }
        }
    }
    Ok(())
}

/// Prints the runs that did not end well; whether one of them fails the command (an unstable run
/// is a result, not a failure).
fn report_outcomes(results: &[PointResult]) -> bool {
    let mut failed = false;
    for r in results {
        match &r.outcome {
            Outcome::Failed(_) | Outcome::KeptChanged { .. } | Outcome::Interrupted => {
                failed = true;
                eprintln!("{}: {}", r.id, r.outcome.label());
            }
            Outcome::Unstable(_) => eprintln!("{}: {}", r.id, r.outcome.label()),
            _ => {}
        }
    }
    failed
}
