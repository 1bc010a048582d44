//! `magdem verify contacts|magnetic` (against the reference codes) and `magdem study
//! accuracy|stability` (the solver alone).

use super::{current_exe, fail};
use magdem::reference::{self, Engine};
use std::path::Path;
use std::process::ExitCode;

const ENGINES: [Engine; 2] = [Engine::LIGGGHTS, Engine::LAMMPS];

/// `magdem verify contacts`: the single-contact benchmarks in magdem and every installed engine.
pub fn contacts(report: &Path, work: &Path) -> ExitCode {
    let engines: Vec<Engine> = ENGINES.into_iter().filter(|e| e.available()).collect();
    if engines.len() < 2 {
        let missing: Vec<&str> = ENGINES.iter().filter(|e| !e.available()).map(|e| e.name()).collect();
        eprintln!(
            "note: reference engines missing ({}); their columns stay empty. `make setup` installs them.",
            missing.join(", ")
        );
    }
    match magdem::verify::contacts::verify(report, work, &engines) {
        Ok(r) => {
            println!(
                "wrote {} and {} figures; largest difference to LIGGGHTS: {:.4}% normal, {:.4}% tangential",
                report.join("contact-verification.md").display(),
                r.figures.len(),
                100.0 * r.worst_normal,
                100.0 * r.worst_tangential
            );
            ExitCode::SUCCESS
        }
        Err(e) => fail(e, 1),
    }
}

/// `magdem verify magnetic`: the magnetic scenes in lock step with every engine whose library loads.
pub fn magnetic(report: &Path, work: &Path, case1_time: f64) -> ExitCode {
    let engines: Vec<Engine> = ENGINES
        .into_iter()
        .filter(|e| match reference::library::available(*e) {
            Ok(()) => true,
            Err(why) => {
                eprintln!("note: {} skipped: {why}", e.name());
                false
            }
        })
        .collect();
    match magdem::verify::magnetic::verify(report, work, &engines, case1_time, &current_exe()) {
        Ok(_) => {
            println!("wrote {}", report.join("magnetic-verification.md").display());
            ExitCode::SUCCESS
        }
        Err(e) => fail(e, 1),
    }
}

/// `magdem study accuracy`: writes `REPORT/README.md`.
pub fn accuracy(report: &Path) -> ExitCode {
    study_written(magdem::study::accuracy::study(report), &report.join("README.md"))
}

/// `magdem study stability`: writes `REPORT/stability.md`.
pub fn stability(report: &Path) -> ExitCode {
    study_written(magdem::study::stability::study(report), &report.join("stability.md"))
}

fn study_written<T, E: std::fmt::Display>(result: Result<T, E>, written: &Path) -> ExitCode {
    match result {
        Ok(_) => {
            println!("wrote {}", written.display());
            ExitCode::SUCCESS
        }
        Err(e) => fail(e, 1),
    }
}
