//! `magdem report paper`, `magdem report hydrodynamics` and `magdem bench`: commands that write a report and name it;
//! `magdem report digests`: a report's digests alone.

use super::report_written;
use magdem::report::paper::PaperReportOptions;
use std::process::ExitCode;

/// `magdem report paper`.
pub fn paper(options: &PaperReportOptions) -> ExitCode {
    report_written(magdem::report::paper::write_report(options))
}

/// `magdem report hydrodynamics`.
pub fn hydrodynamics(options: &magdem::report::hydrodynamics::HydrodynamicsReportOptions) -> ExitCode {
    report_written(magdem::report::hydrodynamics::write_report(options))
}

/// `magdem bench` (at least one repeat per measurement): measures, saves the record, then
/// writes the report from it.
pub fn bench(options: magdem::bench::Options) -> ExitCode {
    let options = magdem::bench::Options { repeats: options.repeats.max(1), ..options };
    match magdem::bench::measure::run(&options) {
        Ok(record) => report_written(magdem::report::performance::write(&record, &options.out)),
        Err(e) => super::fail(e, 1),
    }
}

/// `magdem bench --redraw`: the report and its figure from the saved record in `out`.
pub fn redraw_bench(out: &std::path::Path) -> ExitCode {
    report_written(magdem::report::performance::redraw(out))
}

/// `magdem report digests`: names the experiments whose digest changed.
pub fn digests(experiments: &std::path::Path, dir: &std::path::Path, gap: f64) -> ExitCode {
    match magdem::report::digest::update(experiments, dir, gap) {
        Ok(changed) if changed.is_empty() => {
            println!("{}: no digest changed", dir.display());
            ExitCode::SUCCESS
        }
        Ok(changed) => {
            changed.iter().for_each(|e| println!("wrote {}", dir.join(e).display()));
            ExitCode::SUCCESS
        }
        Err(e) => super::fail(e, 1),
    }
}
