//! The paper report is computed from the runs: its tables equal what the analysis gives for the
//! trajectories, the Parquet and CSV copies agree, and missing studies are said to be missing.

mod common;

use magdem::analysis::stats::summary;
use magdem::analysis::trajectory::frame_aggregates;
use magdem::experiment::{run_experiment, ExperimentOptions};
use magdem::io::trajectory::Trajectory;
use magdem::plot::{BoxStats, RGBColor};
use magdem::report::paper::{write_report, PaperReportOptions};
use magdem::scene::experiment::Experiment;
use polars::prelude::*;
use std::path::{Path, PathBuf};

/// A case-1-like scene at 0.563 mg/ml in a 300 µm box (20 particles, about 10 diameters apart)
/// at the paper's 0.4 T, integrated as the Table 3 ensemble is; some chains form within 2 ms.
fn scene() -> String {
    common::scene(
        r#"version = 1
name = "case1-c0.563"
seed = 1
[domain]
lo = [0.0, 0.0, 0.0]
hi = [3.0e-4, 3.0e-4, 3.0e-4]
"#,
        r#"[[particles]]
species = "p"
concentration = 0.563
[forces.contact]
walls = true
[forces.dipole]
induction = "paper"
cutoff_diameters = 15.0
[forces.drag]
[integration]
scheme = "respa"
slow_every = 10
dt = 1.0e-8
end_time = 2.0e-3
[output]
interval = 2.0e-4
"#,
    )
}

fn read_csv(path: &Path) -> DataFrame {
    CsvReadOptions::default()
        .with_has_header(true)
        .try_into_reader_with_file_path(Some(path.to_path_buf()))
        .unwrap()
        .finish()
        .unwrap()
}

/// A work directory holding [`scene`] and the experiment `experiments/FILE.toml` named `name`
/// (its `[sweep]` and `[variants]` in `table`), run on two jobs into `runs/`; returns the
/// directory's guard, its `experiments/` and its `runs/`.
fn ran(file: &str, name: &str, table: &str) -> (tempfile::TempDir, PathBuf, PathBuf) {
    let work = tempfile::Builder::new().prefix("magdem-report-").tempdir().unwrap();
    let dir = work.path();
    let experiments = dir.join("experiments");
    std::fs::create_dir_all(&experiments).unwrap();
    std::fs::write(dir.join("case1-c0.563.toml"), scene()).unwrap();
    let runs = dir.join("runs");
    let file = experiments.join(file);
    let text =
        format!("name = \"{name}\"\nbases = [\"../case1-c0.563.toml\"]\noutput = \"{}\"\n{table}", runs.display());
    std::fs::write(&file, text).unwrap();
    let experiment = Experiment::from_file(&file).unwrap();
    run_experiment(&experiment, &ExperimentOptions { jobs: Some(2), ..Default::default() }).unwrap();
    (work, experiments, runs)
}

/// The paper report of the runs of `experiments`, written to `out`; returns its README.
fn paper_report(experiments: &Path, out: &Path, wall_time: Option<f64>) -> PathBuf {
    write_report(&PaperReportOptions {
        experiments: experiments.to_path_buf(),
        reference: PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("reference/paper"),
        out: out.to_path_buf(),
        gap: 1e-3,
        wall_time,
        hydrodynamics_experiments: experiments.join("no-hydrodynamics"),
        hydrodynamics: out.join("no-hydrodynamics"),
    })
    .unwrap()
}

#[test]
fn report_tables_are_the_analysis_of_the_runs() {
    let (work, experiments, runs) = ran("table3.toml", "paper-table3", "[sweep]\nseed = [1, 2, 3]\n");
    let out = work.path().join("report");
    let report = |wall_time| paper_report(&experiments, &out, wall_time);
    let readme = report(Some(12.0));
    // The body and its appendices, as one text.
    let whole = |readme: &Path| {
        let dir = readme.parent().unwrap();
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .filter(|n| n.ends_with(".md"))
            .collect();
        names.sort();
        names.iter().map(|n| std::fs::read_to_string(dir.join(n)).unwrap()).collect::<Vec<_>>().join("\n")
    };
    let text = whole(&readme);
    let measured = |out: &Path| {
        let m =
            ParquetReader::new(std::fs::File::open(out.join("tables/measurement.parquet")).unwrap()).finish().unwrap();
        ["runs", "projected_all_um", "projected_2_um", "image_all_um", "image_2_um"]
            .map(|c| m.column(c).unwrap().cast(&DataType::Float64).unwrap().f64().unwrap().get(0).unwrap().to_bits())
    };
    let first_measures = measured(&out);

    // Independent analysis of the three runs' last frames.
    let means: Vec<f64> = (1..=3)
        .map(|seed| {
            let t = Trajectory::open(&runs.join(format!("case1-c0.563__seed-{seed}.h5"))).unwrap();
            let (_, aggs) = frame_aggregates(&t, -1, 1e-3).unwrap();
            summary(&aggs.iter().map(|a| a.length * 1e6).collect::<Vec<_>>()).mean
        })
        .collect();
    let expected = summary(&means).mean;
    assert!(expected > 11.0, "some chains formed: {means:?}");
    let table3 = read_csv(&out.join("tables/table3.csv"));
    let row = table3
        .column("concentration_mg_per_ml")
        .unwrap()
        .f64()
        .unwrap()
        .into_iter()
        .position(|c| c == Some(0.563))
        .unwrap();
    let reported = table3.column("magdem_mean_length_um").unwrap().f64().unwrap().get(row).unwrap();
    assert!((reported - expected).abs() <= 1e-9 * expected, "report {reported} vs analysis {expected}");
    assert_eq!(table3.column("runs").unwrap().cast(&DataType::UInt64).unwrap().u64().unwrap().get(row), Some(3));
    // The paper's columns come from reference/paper/table3_case1_lengths.csv.
    assert_eq!(table3.column("paper_sim_mean_um").unwrap().f64().unwrap().get(row), Some(34.02));
    // Concentrations without runs are empty, not invented.
    assert!(table3.column("magdem_mean_length_um").unwrap().f64().unwrap().get((row + 1) % 4).is_none_or(f64::is_nan));

    // Parquet holds the same table as the CSV.
    let parquet = ParquetReader::new(std::fs::File::open(out.join("tables/table3.parquet")).unwrap()).finish().unwrap();
    assert_eq!(parquet.height(), table3.height());
    assert_eq!(parquet.column("magdem_mean_length_um").unwrap().f64().unwrap().get(row), Some(reported));

    // The histogram table counts every particle of the runs once per run.
    let table4 = read_csv(&out.join("tables/table4.csv"));
    let rows = table4.filter(&table4.column("concentration_mg_per_ml").unwrap().f64().unwrap().equal(0.563)).unwrap();
    let particles: f64 = rows
        .column("particles_per_aggregate")
        .unwrap()
        .cast(&DataType::Float64)
        .unwrap()
        .f64()
        .unwrap()
        .into_no_null_iter()
        .zip(rows.column("magdem_mean_count").unwrap().f64().unwrap().into_no_null_iter())
        .map(|(s, n)| s * n)
        .sum();
    assert!((particles - 20.0).abs() < 1e-9, "{particles}");

    for figure in ["table3.png", "table4.png", "boxplots.png", "length-vs-time.png"] {
        assert!(out.join(figure).metadata().unwrap().len() > 10_000, "{figure}");
        assert!(text.contains(&format!("({figure})")), "{figure} linked");
    }
    assert!(text.contains("No completed case-2 runs"), "missing studies are said to be missing");
    assert!(text.contains("spent 12 s of wall time"), "the main job's wall time is stated");
    let reproduce = read_csv(&out.join("tables/reproduce.csv"));
    assert_eq!(reproduce.column("experiments_wall_time_s").unwrap().f64().unwrap().get(0), Some(12.0));

    // A damaged run file is marked and the report goes on with the others.
    let damaged = runs.join("case1-c0.563__seed-3.h5");
    let bytes = std::fs::read(&damaged).unwrap();
    std::fs::write(&damaged, &bytes[..bytes.len() / 3]).unwrap();
    let readme = report(None);
    let text = whole(&readme);
    assert!(
        text.contains("Unreadable run files") && text.contains("case1-c0.563__seed-3.h5"),
        "the damaged run is named"
    );
    let runs_table = read_csv(&out.join("tables/runs.csv"));
    let status: Vec<String> =
        runs_table.column("status").unwrap().str().unwrap().into_no_null_iter().map(str::to_string).collect();
    assert_eq!(status.iter().filter(|s| *s == "unreadable").count(), 1, "{status:?}");
    let table3 = read_csv(&out.join("tables/table3.csv"));
    assert_eq!(table3.column("runs").unwrap().cast(&DataType::UInt64).unwrap().u64().unwrap().get(row), Some(2));

    // Runs whose trajectories are gone are read from the report's digests, which the first
    // report made: the table is the first one, to the bit.
    std::fs::remove_file(&damaged).unwrap();
    std::fs::remove_file(runs.join("case1-c0.563__seed-2.h5")).unwrap();
    let readme = report(None);
    let text = whole(&readme);
    assert!(text.contains("trajectories in `runs/`: 1.") && text.contains("digests/): 2."), "provenance stated");
    let parquet = ParquetReader::new(std::fs::File::open(out.join("tables/table3.parquet")).unwrap()).finish().unwrap();
    assert_eq!(parquet.column("runs").unwrap().cast(&DataType::UInt64).unwrap().u64().unwrap().get(row), Some(3));
    assert_eq!(parquet.column("magdem_mean_length_um").unwrap().f64().unwrap().get(row), Some(reported));
    let runs_table = read_csv(&out.join("tables/runs.csv"));
    let source: Vec<String> =
        runs_table.column("source").unwrap().str().unwrap().into_no_null_iter().map(str::to_string).collect();
    assert_eq!(source.iter().filter(|s| *s == "digest").count(), 2, "{source:?}");
    // The image measures, which need positions, are kept in the digests too.
    assert_eq!(measured(&out), first_measures, "the measurement table from digests is the first one");
    assert!(out.join("digests/paper-table3/aggregates.parquet").exists());
}

#[test]
fn box_statistics_follow_the_definitions() {
    let values: Vec<f64> = (1..=9).map(f64::from).collect();
    let b = BoxStats::of("x", RGBColor(0, 0, 0), &values).unwrap();
    assert_eq!((b.lower_fence, b.q1, b.median, b.q3, b.upper_fence, b.mean), (1.0, 3.0, 5.0, 7.0, 9.0, 5.0));
    // An outlier beyond q3 + 1.5 IQR moves the mean but not the whisker.
    let mut with_outlier = values.clone();
    with_outlier.push(100.0);
    let b = BoxStats::of("x", RGBColor(0, 0, 0), &with_outlier).unwrap();
    assert_eq!(b.upper_fence, 9.0);
    assert!((b.mean - 14.5).abs() < 1e-12);
    assert!(BoxStats::of("x", RGBColor(0, 0, 0), &[]).is_none());
}

/// The sensitivity study at a concentration other than the paper's 2.25 mg/ml: each change is
/// paired seed by seed with the `respa` reference of the same concentration, in the table and in
/// the ranking of explanations at that concentration.
#[test]
fn sensitivity_changes_are_paired_and_ranked_at_their_own_concentration() {
    let (work, experiments, runs) = ran(
        "sensitivity-concentrations.toml",
        "paper-sensitivity-concentrations",
        "[sweep]\nseed = [1, 2, 3]\n[variants.respa]\n[variants.no-induction]\n\"forces.dipole.induction\" = \"none\"\n",
    );
    let out = work.path().join("report");
    paper_report(&experiments, &out, None);

    // Independently: each seed's mean length, then the paired relative change.
    let mean_length = |variant: &str, seed: u64| {
        let t = Trajectory::open(&runs.join(format!("case1-c0.563__{variant}__seed-{seed}.h5"))).unwrap();
        let (_, aggs) = frame_aggregates(&t, -1, 1e-3).unwrap();
        summary(&aggs.iter().map(|a| a.length * 1e6).collect::<Vec<_>>()).mean
    };
    let reference: Vec<f64> = (1..=3).map(|s| mean_length("respa", s)).collect();
    let changed: Vec<f64> = (1..=3).map(|s| mean_length("no-induction", s)).collect();
    let base = summary(&reference).mean;
    let expected =
        summary(&reference.iter().zip(&changed).map(|(a, b)| 100.0 * (b - a) / base).collect::<Vec<_>>()).mean;
    assert!(expected != 0.0, "induction changes the chains: {reference:?} vs {changed:?}");

    let number = |df: &DataFrame, column: &str| df.column(column).unwrap().f64().unwrap().get(0).unwrap();
    let sensitivity = read_csv(&out.join("tables/sensitivity.csv"));
    assert_eq!(sensitivity.height(), 1, "one change at one concentration");
    assert_eq!(number(&sensitivity, "concentration_mg_per_ml"), 0.563);
    let reported = number(&sensitivity, "paired_change_percent");
    assert!((reported - expected).abs() <= 1e-9 * expected.abs(), "table {reported} vs analysis {expected}");

    let ranking = read_csv(&out.join("tables/explanations.csv"));
    let induction = ranking.filter(&ranking.column("explanation").unwrap().str().unwrap().equal("induction")).unwrap();
    assert_eq!(induction.height(), 1, "{ranking}");
    assert_eq!(number(&induction, "concentration_mg_per_ml"), 0.563);
    assert_eq!(number(&induction, "change_percent"), reported);
}
