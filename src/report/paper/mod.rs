//! `magdem report paper`: the paper-reproduction report (`reports/paper/README.md` and its
//! appendices) from the runs of `experiments/paper/*.toml` (and `opt-in/*.toml` when run), beside
//! the paper's tables in `reference/paper/`.
//!
//! A report is data: [`SECTIONS`] lists each section's experiments and the function that computes
//! its numbers, tables and figures; [`DOCUMENTS`] lists the Markdown templates (`templates/paper/`)
//! that put them into words. Every section's values reach every template under the section's name.

mod box_count;
mod case1;
mod case2;
pub mod convergence;
mod drawing;
mod engines;
mod figures;
mod why;

use super::digest::load_runs_digested;
use super::runs::{experiment_files, Run};
use super::tables::{floats, read_csv};
use crate::analysis::stats::summary;
use convergence::{Effect, Targets};
use minijinja::Value;
use polars::prelude::{DataFrame, PolarsResult};
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

type Error = Box<dyn std::error::Error>;

pub struct PaperReportOptions {
    /// Directory of the experiment files (`experiments/paper`).
    pub experiments: PathBuf,
    /// Directory of the paper's tables (`reference/paper`).
    pub reference: PathBuf,
    /// Report directory (`reports/paper`).
    pub out: PathBuf,
    /// Aggregate gap tolerance (fraction of the smaller radius).
    pub gap: f64,
    /// Wall time of the `make reproduce` run that produced the runs, when known (s).
    pub wall_time: Option<f64>,
    /// The hydrodynamics study's experiments (`experiments/hydrodynamics`) and report directory
    /// (`reports/hydrodynamics`, whose `digests/` hold its runs): case 2's twenty-seed ensemble
    /// and the drag models come from there.
    pub hydrodynamics_experiments: PathBuf,
    pub hydrodynamics: PathBuf,
}

/// The paper's tables as read from `reference/paper/*.csv`.
pub struct Paper {
    pub table2: DataFrame,
    pub table3: DataFrame,
    pub table4: DataFrame,
}

/// What every section reads: the runs, the paper's tables, where figures and tables go, and the
/// effects (explanations of the differences) that sections measure and the ranking weighs.
pub struct Inputs<'a> {
    pub runs: &'a [Run],
    /// The hydrodynamics study's runs (case 1 and case 2 under each drag model).
    pub hydro: &'a [Run],
    pub files: &'a [PathBuf],
    pub paper: &'a Paper,
    pub targets: &'a Targets,
    pub options: &'a PaperReportOptions,
    /// The report directory (figures).
    pub out: &'a Path,
    /// Its `tables/` (CSV and Parquet).
    pub tables: PathBuf,
    pub effects: RefCell<Vec<Effect>>,
}

/// One section: the experiments it reads, the function that computes its values, the figures
/// that function draws and the template that puts them into words.
pub struct Section {
    /// The name its values carry in the templates.
    pub name: &'static str,
    /// The experiments (their `name` keys) whose runs it reads.
    pub experiments: &'static [&'static str],
    /// Its numbers, tables (Markdown, also written to `tables/`) and figures (written to the
    /// report directory).
    pub compute: fn(&Inputs) -> Result<Value, Error>,
    /// The figures it draws when its runs exist (PNG files in the report directory).
    pub figures: &'static [&'static str],
    /// Its words (`templates/paper/sections/`), which an appendix includes; none for a section
    /// that only the body quotes.
    pub template: Option<&'static str>,
}

macro_rules! section {
    ($name:literal, $experiments:expr, $compute:path, [$($figure:literal),*]) => {
        Section {
            name: $name,
            experiments: $experiments,
            compute: $compute,
            figures: &[$($figure),*],
            template: Some(concat!("paper/sections/", $name, ".md")),
        }
    };
}

/// The sections in the order they are computed: later ones (the ranking, the summary) read the
/// effects earlier ones measured.
pub const SECTIONS: &[Section] = &[
    section!("provenance", &[], engines::provenance, []),
    section!("table3", &convergence::TABLE3, case1::table3, ["table3.png", "table3-spread.png"]),
    section!("seeds", &convergence::SEEDS_EXPERIMENTS, convergence::seeds, []),
    Section { name: "inputs", experiments: &convergence::TABLE3, compute: why::inputs, figures: &[], template: None },
    section!("table4", &convergence::TABLE3, case1::table4, ["table4.png"]),
    section!("boxplots", &convergence::TABLE3, case1::boxplots, ["boxplots.png"]),
    section!("chains", &convergence::TABLE3, figures::chains, ["chains-3d.png", "chains-xy.png"]),
    section!("paraview", &convergence::TABLE3, figures::paraview, ["paraview-case1.png"]),
    section!("approach", &["paper-approach"], case1::approach, ["approach.png", "approach-distance.png"]),
    section!("finite_size", &convergence::FINITE_SIZE_EXPERIMENTS, convergence::finite_size, ["finite-size.png"]),
    section!("box_count", &box_count::EXPERIMENTS, box_count::box_count, ["box-and-count.png"]),
    section!(
        "growth",
        &["paper-long", "paper-table3", "paper-table3-seeds"],
        convergence::growth,
        ["length-vs-time.png"]
    ),
    section!(
        "magnetisation",
        &["paper-magnetisation"],
        convergence::magnetisation,
        ["magnetisation.png", "magnetisation-collapse.png"]
    ),
    section!("measurement", &convergence::TABLE3, convergence::measurement, []),
    section!(
        "sensitivity",
        &["paper-sensitivity", "paper-sensitivity-concentrations"],
        why::sensitivity,
        ["sensitivity.png"]
    ),
    section!(
        "shielding",
        &[why::SHIELDING_VERLET, "paper-sensitivity", "hydro-case1"],
        why::shielding,
        ["shielding.png"]
    ),
    section!("ranking", &[], why::ranking, []),
    section!(
        "case2",
        &["hydro-case2", "paper-case2", "paper-case2-permeability"],
        case2::case2,
        ["case2.png", "case2-velocity-by-size.png", "case2-positions.png"]
    ),
    section!("reynolds", &["paper-table3", "paper-case2"], why::reynolds, ["reynolds.png"]),
    section!(
        "engines",
        &["paper-reference", "paper-reference-table3"],
        engines::engines,
        ["reference-engines.png", "reference-table3.png"]
    ),
    section!("runs", &[], engines::runs, []),
];

/// The table (in `tables/`) holding the wall time of the `make reproduce` call that wrote the report.
pub const REPRODUCE_TABLE: &str = "reproduce";

/// One output file and the template that writes it.
pub struct Document {
    pub file: &'static str,
    pub template: &'static str,
}

/// The report's files: the paper-shaped body, then its appendices.
pub const DOCUMENTS: &[Document] = &[
    Document { file: "README.md", template: "paper/README.md" },
    Document { file: "appendix-a-case1.md", template: "paper/appendix-a-case1.md" },
    Document { file: "appendix-b-why.md", template: "paper/appendix-b-why.md" },
    Document { file: "appendix-c-finite-size.md", template: "paper/appendix-c-finite-size.md" },
    Document { file: "appendix-d-magnetisation.md", template: "paper/appendix-d-magnetisation.md" },
    Document { file: "appendix-e-case2.md", template: "paper/appendix-e-case2.md" },
    Document { file: "appendix-f-engines.md", template: "paper/appendix-f-engines.md" },
    Document { file: "appendix-g-runs.md", template: "paper/appendix-g-runs.md" },
];

pub(crate) fn strings(df: &DataFrame, name: &str) -> PolarsResult<Vec<String>> {
    Ok(df.column(name)?.str()?.into_iter().map(|v| v.unwrap_or_default().to_string()).collect())
}

/// Mean, NaN for no values.
pub(crate) fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        summary(v).mean
    }
}

pub(crate) fn completed<'a>(runs: &'a [Run], experiment: &str) -> Vec<&'a Run> {
    runs.iter().filter(|r| r.experiment == experiment && r.completed()).collect()
}

/// "1–20" for consecutive seeds, else the list.
pub(crate) fn seed_list(seeds: &[u64]) -> String {
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if seeds.len() > 2 && seeds.len() as u64 == b - a + 1 => format!("{a}–{b}"),
        _ => seeds.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", "),
    }
}

/// The completed runs of the Table 3 ensemble (default seeds and the opt-in continuation).
pub(crate) fn table3_ensemble(runs: &[Run]) -> Vec<&Run> {
    runs.iter().filter(|r| convergence::TABLE3.contains(&r.experiment.as_str()) && r.completed()).collect()
}

/// Computes every section, then renders every document; returns the path of the README.
pub fn write_report(options: &PaperReportOptions) -> Result<PathBuf, Error> {
    let files = experiment_files(&options.experiments, true)?;
    let runs = load_runs_digested(&files, options.gap, &options.out.join("digests"))?;
    let hydro_files: Vec<PathBuf> = ["case1-drag.toml", "case2-drag.toml"]
        .iter()
        .map(|f| options.hydrodynamics_experiments.join(f))
        .filter(|f| f.exists())
        .collect();
    let hydro = load_runs_digested(&hydro_files, options.gap, &options.hydrodynamics.join("digests"))?;
    let paper = Paper {
        table2: read_csv(&options.reference.join("table2_case2.csv"))?,
        table3: read_csv(&options.reference.join("table3_case1_lengths.csv"))?,
        table4: read_csv(&options.reference.join("table4_case1_sizes.csv"))?,
    };
    let targets = Targets {
        concentration: floats(&paper.table3, "concentration_mg_per_ml")?,
        paper: floats(&paper.table3, "sim_mean_length_um")?,
        experiment: floats(&paper.table3, "exp_mean_length_um")?,
    };
    std::fs::create_dir_all(&options.out)?;
    let inputs = Inputs {
        runs: &runs,
        hydro: &hydro,
        files: &files,
        paper: &paper,
        targets: &targets,
        options,
        out: &options.out,
        tables: options.out.join("tables"),
        effects: RefCell::new(vec![]),
    };
    if let Some(wall_time) = options.wall_time {
        // The main job's wall time, for the performance report to read as data.
        let mut df = super::tables::frame(vec![
            super::tables::col("experiments_wall_time_s", vec![wall_time]),
            super::tables::ucol("completed_runs", vec![runs.iter().filter(|r| r.completed()).count() as u64]),
            super::tables::scol("commit", vec![env!("MAGDEM_GIT_COMMIT").to_string()]),
        ])?;
        super::tables::write(&mut df, &inputs.tables, REPRODUCE_TABLE)?;
    }
    let mut context: BTreeMap<&str, Value> = BTreeMap::new();
    for section in SECTIONS {
        let values = (section.compute)(&inputs).map_err(|e| format!("section {}: {e}", section.name))?;
        context.insert(section.name, values);
    }
    for document in DOCUMENTS {
        let text = super::template::render(document.template, &context)?;
        std::fs::write(options.out.join(document.file), text)?;
    }
    Ok(options.out.join("README.md"))
}
