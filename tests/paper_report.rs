//! The committed paper report reads as a paper: its summary comes first and is short, its numbers
//! are its tables', its body stays within its word limit and its sentences are short.

#[path = "common/prose.rs"]
mod prose;

use polars::prelude::*;
use prose::sentences;
use std::path::{Path, PathBuf};

fn report() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/paper")
}

fn read(name: &str) -> String {
    std::fs::read_to_string(report().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Words of prose: whitespace-separated tokens holding a letter or digit (a table's bars and
/// rules are not words).
fn words(text: &str) -> usize {
    text.split_whitespace().filter(|w| w.chars().any(char::is_alphanumeric)).count()
}

/// The lines of a section, from its heading to the next heading of the same or a higher level.
fn section<'a>(text: &'a str, heading: &str) -> Vec<&'a str> {
    let level = heading.chars().take_while(|&c| c == '#').count();
    let mut lines = text.lines().skip_while(|l| l.trim() != heading);
    let first = lines.next().expect("the section exists");
    std::iter::once(first)
        .chain(lines.take_while(|l| {
            let hashes = l.chars().take_while(|&c| c == '#').count();
            hashes == 0 || hashes > level
        }))
        .collect()
}

#[test]
fn the_summary_comes_first_and_is_short() {
    let text = read("README.md");
    let at = text.lines().position(|l| l.trim() == "## Summary").expect("a summary");
    assert!(at < 10, "the summary starts on line {}", at + 1);
    let summary = section(&text, "## Summary");
    assert!(at + summary.len() <= 40, "the summary ends by line 40, not {}", at + summary.len());
    let n = words(&summary[1..].join("\n"));
    assert!(n <= 250, "the summary has {n} words");
}

#[test]
fn the_body_is_short_and_its_sentences_too() {
    let text = read("README.md");
    let n = words(&text);
    assert!(n <= 3000, "the body has {n} words");
    let mut files = vec!["README.md".to_string()];
    for entry in std::fs::read_dir(report()).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().to_string();
        if name.starts_with("appendix-") && name.ends_with(".md") {
            files.push(name);
        }
    }
    for f in files {
        for s in sentences(&read(&f)) {
            assert!(words(&s) < 40, "{f}: a sentence of {} words: {s}", words(&s));
        }
    }
}

/// "31 ± 4" → (31, 4); "31" → (31, NaN).
fn estimate(cell: &str) -> (f64, f64) {
    let mut parts = cell.split('±').map(|p| p.trim().replace('−', "-"));
    let mean = parts.next().unwrap().parse().unwrap_or(f64::NAN);
    let ci = parts.next().map_or(f64::NAN, |p| p.parse().unwrap_or(f64::NAN));
    (mean, ci)
}

#[test]
fn the_summary_numbers_are_the_tables() {
    let text = read("README.md");
    let summary = section(&text, "## Summary");
    let rows: Vec<Vec<String>> = summary
        .iter()
        .filter(|l| l.starts_with('|') && !l.contains("---"))
        .skip(1)
        .map(|l| l.trim_matches('|').split('|').map(|c| c.trim().to_string()).collect())
        .collect();
    let table = CsvReadOptions::default()
        .with_has_header(true)
        .try_into_reader_with_file_path(Some(report().join("tables/table3.csv")))
        .unwrap()
        .finish()
        .unwrap();
    let column = |name: &str| -> Vec<f64> {
        table
            .column(name)
            .unwrap()
            .cast(&DataType::Float64)
            .unwrap()
            .f64()
            .unwrap()
            .into_iter()
            .map(|v| v.unwrap_or(f64::NAN))
            .collect()
    };
    let c = column("concentration_mg_per_ml");
    assert_eq!(rows.len(), c.len(), "one summary row per concentration");
    let rounded = |x: f64| format!("{x:.0}");
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[0].parse::<f64>().unwrap(), c[k]);
        assert_eq!(row[1], rounded(column("experiment_mean_um")[k]), "experiment at {}", c[k]);
        assert_eq!(row[2], rounded(column("paper_sim_mean_um")[k]), "paper at {}", c[k]);
        let (sat, sat_ci) = estimate(&row[3]);
        assert_eq!(rounded(sat), rounded(column("saturated_mean_length_um")[k]), "saturated at {}", c[k]);
        assert_eq!(rounded(sat_ci), rounded(column("saturated_ci95_um")[k]), "saturated CI at {}", c[k]);
        let (lin, lin_ci) = estimate(&row[4]);
        assert_eq!(rounded(lin), rounded(column("magdem_mean_length_um")[k]), "linear at {}", c[k]);
        assert_eq!(rounded(lin_ci), rounded(column("magdem_ci95_um")[k]), "linear CI at {}", c[k]);
    }
}

#[test]
fn every_figure_the_report_links_exists() {
    for entry in std::fs::read_dir(report()).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().to_string();
        if !name.ends_with(".md") {
            continue;
        }
        let text = read(&name);
        for part in text.split("](").skip(1) {
            let target = &part[..part.find(')').unwrap()];
            if target.ends_with(".png") || (target.ends_with(".md") && !target.contains('/')) {
                assert!(report().join(target).exists(), "{name} links {target}, which is missing");
            }
        }
    }
}

#[test]
fn every_declared_figure_is_committed_and_shown() {
    let text: String = std::fs::read_dir(report())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.ends_with(".md"))
        .map(|n| read(&n))
        .collect();
    for section in magdem::report::paper::SECTIONS {
        for figure in section.figures {
            assert!(report().join(figure).exists(), "section {}: {figure} is not in reports/paper", section.name);
            assert!(text.contains(&format!("({figure})")), "section {}: {figure} is not shown", section.name);
        }
    }
}
