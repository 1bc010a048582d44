//! The performance report rendered from the committed record (`reports/performance.json`): its
//! summary comes first and names every target, its sentences are short, and its tables hold the
//! record's numbers.

#[path = "common/prose.rs"]
mod prose;

use magdem::bench::record::BenchRecord;
use magdem::report::performance;
use prose::sentences;
use std::path::Path;

fn record() -> BenchRecord {
    BenchRecord::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("reports")).unwrap()
}

/// The report and figure rendered into a temporary directory.
fn rendered() -> (tempfile::TempDir, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = performance::write(&record(), dir.path()).unwrap();
    let text = std::fs::read_to_string(path).unwrap();
    (dir, text)
}

/// The lines of the section under `heading`, up to the next heading of that level.
fn section<'a>(text: &'a str, heading: &str) -> Vec<&'a str> {
    text.lines().skip_while(|l| l.trim() != heading).skip(1).take_while(|l| !l.starts_with("## ")).collect()
}

/// The cells of the Markdown table whose header holds `column`, by row: (first cell, that cell).
fn column(text: &str, column: &str) -> Vec<(String, String)> {
    let mut lines = text.lines().skip_while(|l| !(l.starts_with('|') && l.contains(column)));
    let header: Vec<&str> = lines.next().expect("the table").trim_matches('|').split('|').map(str::trim).collect();
    let k = header.iter().position(|h| *h == column).expect("the column");
    lines
        .skip(1)
        .take_while(|l| l.starts_with('|'))
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            (cells[0].to_string(), cells[k].to_string())
        })
        .collect()
}

#[test]
fn the_summary_comes_first_and_names_every_target() {
    let (_dir, text) = rendered();
    let at = text.lines().position(|l| l == "## Summary").expect("a summary");
    assert!(at < 10, "the summary starts on line {}", at + 1);
    let summary = section(&text, "## Summary");
    assert!(at + 1 + summary.len() <= 40, "the summary ends after line 40, on line {}", at + 1 + summary.len());
    let record = record();
    let mut targets = vec![];
    for case in ["contact packed 3000", "contact packed 30000"] {
        targets.push((
            case,
            format!("{:.2}× as fast as LIGGGHTS", record.speedup(case, ("magdem", 1), ("liggghts", 1)).unwrap()),
        ));
    }
    for case in ["dipole all pairs 307", "dipole cut-off 15 d 307"] {
        targets.push((
            case,
            format!("{:.2}× as fast as LAMMPS", record.speedup(case, ("magdem", 1), ("lammps", 1)).unwrap()),
        ));
    }
    let paired = record.paired_speedups.iter().find(|p| p.case == "contact packed 30000").unwrap();
    targets.push(("contact packed 30000", format!("two threads runs {:.3}× as fast as on one", paired.ratio.median)));
    for (case, claim) in &targets {
        let names = |l: &&&str| {
            l.strip_prefix("- ").is_some_and(|r| r.strip_prefix(case).is_some_and(|r| r.starts_with([' ', ':'])))
        };
        let line = summary.iter().find(|l| names(l) && l.contains(claim.as_str()));
        let line = line.unwrap_or_else(|| panic!("no target line for {case}: {claim}"));
        assert!(line.ends_with("**met**.") || line.ends_with("**not met**."), "{line}");
    }
    assert_eq!(summary.iter().filter(|l| l.contains("target ≥")).count(), targets.len());
}

#[test]
fn every_sentence_is_under_forty_words() {
    let (_dir, text) = rendered();
    for s in sentences(&text) {
        let words = s.split_whitespace().count();
        assert!(words < 40, "a sentence of {words} words: {s}");
    }
}

#[test]
fn the_tables_hold_the_records_medians() {
    let (dir, text) = rendered();
    let record = record();
    let rows = column(&text, "magdem, one thread (s)");
    assert!(rows.len() >= 9, "{} contact and dipole rows", rows.len());
    for (case, cell) in rows {
        let m = record.find(&case, "magdem", 1).unwrap_or_else(|| panic!("{case} is not in the record"));
        let median = cell.split(" / ").nth(1).expect("min / median / max");
        assert_eq!(median, format!("{:.3}", m.seconds.median), "{case}");
    }
    for (case, cell) in column(&text, "LIGGGHTS (s)") {
        let expected = record.find(&case, "liggghts", 1).map_or("–".into(), |m| format!("{:.3}", m.seconds.median));
        assert_eq!(cell.split(" / ").nth(1).unwrap_or("–"), expected, "{case}");
    }
    let figure = dir.path().join(performance::FIGURE);
    assert!(std::fs::metadata(figure).unwrap().len() > 10_000, "a drawn figure");
}

/// `--redraw` reads the record alone, and a file that is not one is refused with its name.
#[test]
fn a_redraw_needs_the_record() {
    let dir = tempfile::tempdir().unwrap();
    let e = performance::redraw(dir.path()).unwrap_err().to_string();
    assert!(e.contains("performance.json"), "{e}");
    std::fs::write(dir.path().join("performance.json"), "{\"measurements\": []}").unwrap();
    let e = performance::redraw(dir.path()).unwrap_err().to_string();
    assert!(e.contains("performance.json") && e.contains("missing field"), "{e}");
    record().save(dir.path()).unwrap();
    assert!(performance::redraw(dir.path()).unwrap().ends_with(performance::REPORT));
}
