//! What a test does when a program it drives is absent. `make test` first runs scripts/setup.sh,
//! which installs every such program, so an absent one fails the test. Only MAGDEM_NO_REFERENCE=1
//! makes the programs setup then leaves out optional (README): the test is skipped, says so, and
//! writes a line to the skip ledger, which .ci/run requires to be empty.

use std::io::Write;
use std::path::PathBuf;

/// The skip ledger: one line per skipped test, under the target directory.
pub fn ledger() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("skipped-tests.txt")
}

/// Whether the test may go on. `available` false: with MAGDEM_NO_REFERENCE=1 the skip is printed
/// and written to the ledger (false); otherwise the test panics with `install`.
pub fn present(available: bool, what: &str, install: &str) -> bool {
    if available {
        return true;
    }
    if std::env::var("MAGDEM_NO_REFERENCE").as_deref() != Ok("1") {
        panic!("{what} is not installed: {install} (or set MAGDEM_NO_REFERENCE=1 to skip this test)");
    }
    let test = std::thread::current().name().unwrap_or("a test").to_string();
    println!("SKIPPED {test}: {what} is not installed and MAGDEM_NO_REFERENCE=1");
    let path = ledger();
    let line = format!("{test}: {what} (MAGDEM_NO_REFERENCE=1)\n");
    let written = std::fs::create_dir_all(path.parent().unwrap())
        .and_then(|_| std::fs::OpenOptions::new().create(true).append(true).open(&path))
        .and_then(|mut f| f.write_all(line.as_bytes()));
    if let Err(e) = written {
        panic!("cannot record the skip in {}: {e}", path.display());
    }
    false
}
