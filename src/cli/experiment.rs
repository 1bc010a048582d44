//! `magdem experiment FILE…`: every point of the experiment files, or with `--dry-run` their list.

use super::{fail, stop_on_ctrl_c};
use magdem::experiment::{run_experiments, ExperimentOptions, Outcome, PointResult};
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
        list_points(&experiments);
        return ExitCode::SUCCESS;
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

/// `--dry-run`: each point's output, particles, steps and engine, with its scene's warnings.
fn list_points(experiments: &[Experiment]) {
    for e in experiments {
        for p in &e.points {
            println!(
                "{}/{}.h5  {} particles  {} steps  {}",
                e.output.display(),
                p.id,
                p.scene.initial.len(),
                p.scene.total_steps(),
                p.engine
            );
            for w in &p.scene.warnings {
                println!("  warning: {w}");
            }
        }
    }
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
