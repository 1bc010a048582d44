//! The subcommands of the `magdem` binary, one function each; `main` parses the command line and
//! dispatches here. Every function prints its own messages and returns the exit code (docs/running.md's
//! table: 0 done, 1 I/O or engine failure, 2 invalid input, 3 unstable, 130 interrupted).

pub mod experiment;
pub mod report;
pub mod run;
pub mod scene;
pub mod trajectory;
pub mod verify;

use magdem::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The scene at `path`, or exit code 2 after printing why it cannot be read.
pub fn load(path: &Path) -> Result<Scene, ExitCode> {
    Scene::from_file(path).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(2)
    })
}

/// Exit status of a command that writes a report: its path on success, the error otherwise.
pub fn report_written<E: std::fmt::Display>(result: Result<PathBuf, E>) -> ExitCode {
    match result {
        Ok(path) => {
            println!("wrote {}", path.display());
            ExitCode::SUCCESS
        }
        Err(e) => fail(e, 1),
    }
}

/// Prints `error: {e}` and returns exit code `code`.
pub fn fail(e: impl std::fmt::Display, code: u8) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::from(code)
}

/// The path of the running binary (for decks and studies that call `magdem` back).
pub fn current_exe() -> PathBuf {
    std::env::current_exe().unwrap_or_else(|_| PathBuf::from("magdem"))
}

/// Ctrl-C sets [`magdem::run::INTERRUPTED`]; runs then checkpoint and stop.
pub fn stop_on_ctrl_c() {
    let _ = ctrlc::set_handler(|| magdem::run::INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed));
}
