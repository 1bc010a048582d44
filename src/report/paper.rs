//! `magdem report paper`: the paper-reproduction report (`reports/paper/README.md`) from the
//! runs of `experiments/paper/*.toml` (and `opt-in/*.toml` when run), beside the paper's tables
//! in `reference/paper/`. Every number in the report comes from the runs and those CSV files.

use super::convergence::{self, Effect, Explanation, Targets};
use super::figures;
use super::runs::{experiment_files, load_runs_digested, Run};
use super::tables::{col, floats, frame, markdown, read_csv, same, scol, ucol, write};
use crate::analysis::stats::{ci95_half_width, summary};
use crate::plot::{
    box_panels, category_panels, engine_colour, line_chart_with_legend, palette, BarGroup, BarPanel, BoxPanel,
    BoxStats, Mark, RGBColor, Series, SeriesLabelPosition,
};
use crate::scene::Scene;
use polars::prelude::{DataFrame, PolarsResult};
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
}

/// The paper's tables as read from `reference/paper/*.csv`.
struct Paper {
    table2: DataFrame,
    table3: DataFrame,
    table4: DataFrame,
}

fn strings(df: &DataFrame, name: &str) -> PolarsResult<Vec<String>> {
    Ok(df.column(name)?.str()?.into_iter().map(|v| v.unwrap_or_default().to_string()).collect())
}

/// Mean, NaN for no values.
fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        summary(v).mean
    }
}

fn completed<'a>(runs: &'a [Run], experiment: &str) -> Vec<&'a Run> {
    runs.iter().filter(|r| r.experiment == experiment && r.completed()).collect()
}

/// "1–20" for consecutive seeds, else the list.
fn seed_list(seeds: &[u64]) -> String {
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if seeds.len() > 2 && seeds.len() as u64 == b - a + 1 => format!("{a}–{b}"),
        _ => seeds.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", "),
    }
}

/// The completed runs of the Table 3 ensemble (default seeds and the opt-in continuation).
fn table3_ensemble(runs: &[Run]) -> Vec<&Run> {
    runs.iter().filter(|r| convergence::TABLE3.contains(&r.experiment.as_str()) && r.completed()).collect()
}

/// Writes the report; returns the path of its README.md.
pub fn write_report(options: &PaperReportOptions) -> Result<PathBuf, Error> {
    let files = experiment_files(&options.experiments, true)?;
    let runs = load_runs_digested(&files, options.gap, &options.out.join("digests"))?;
    let paper = Paper {
        table2: read_csv(&options.reference.join("table2_case2.csv"))?,
        table3: read_csv(&options.reference.join("table3_case1_lengths.csv"))?,
        table4: read_csv(&options.reference.join("table4_case1_sizes.csv"))?,
    };
    let out = &options.out;
    std::fs::create_dir_all(out)?;
    let tables = out.join("tables");

    let targets = Targets {
        concentration: floats(&paper.table3, "concentration_mg_per_ml")?,
        paper: floats(&paper.table3, "sim_mean_length_um")?,
        experiment: floats(&paper.table3, "exp_mean_length_um")?,
    };
    let mut effects: Vec<Effect> = vec![];
    let mut md = header(&runs, &files, options);
    md += &table3_section(&runs, &paper, out, &tables)?;
    md += &convergence::seeds_section(&runs, &targets, &tables, &mut effects)?;
    md += &table4_section(&runs, &paper, out, &tables)?;
    md += &box_section(&runs, &paper, out)?;
    let mut seed1: Vec<&Run> =
        table3_ensemble(&runs).into_iter().filter(|r| r.seed == 1 && r.has_trajectory()).collect();
    seed1.sort_by(|a, b| a.concentration.total_cmp(&b.concentration));
    md += &figures::chain_figures(&seed1, out)?;
    md += &figures::paraview_section(
        seed1.iter().copied().find(|r| same(r.concentration, 2.25)).or(seed1.first().copied()),
        out,
    )?;
    md += &convergence::finite_size_section(&runs, &targets, out, &tables, &mut effects)?;
    md += &convergence::growth_section(&runs, &targets, out, &tables, &mut effects)?;
    md += &convergence::magnetisation_section(&runs, &targets, out, &tables, &mut effects)?;
    md += &convergence::measurement_section(&runs, &targets, &tables, &mut effects)?;
    md += &sensitivity_section(&runs, out, &tables, &mut effects)?;
    md += &convergence::ranking_section(&effects, &targets, &runs, &tables)?;
    md += &figures::shielding_figure(out)?;
    md += &case2_section(&runs, &paper, out, &tables)?;
    md += &figures::case2_figure(
        runs.iter().find(|r| r.experiment == "paper-case2" && r.seed == 1 && r.completed() && r.has_trajectory()),
        out,
    )?;
    md += &approach_section(&runs, out)?;
    md += &box_effect_section(&runs, &paper, out, &tables)?;
    md += &reference_section(&runs, out, &tables)?;
    md += &runs_section(&runs, &tables)?;
    let path = out.join("README.md");
    std::fs::write(&path, md)?;
    Ok(path)
}

fn header(runs: &[Run], files: &[PathBuf], options: &PaperReportOptions) -> String {
    let done = runs.iter().filter(|r| r.completed()).count();
    let unstable = runs.iter().filter(|r| r.status == "unstable").count();
    let unreadable: Vec<String> = runs
        .iter()
        .filter(|r| r.status == crate::io::trajectory::status::UNREADABLE)
        .map(|r| format!("`{}` ({})", r.file.display(), r.message))
        .collect();
    let core_seconds: f64 = runs.iter().filter(|r| r.wall_time.is_finite()).map(|r| r.wall_time).sum();
    let mut md = format!(
        "# Reproducing the paper's case 1 and case 2\n\n\
         Generated by `magdem report paper` (magdem {}, commit {}) from the runs of {} experiment files: {} runs completed, {} stopped \
         as unstable (a result, reported below), {} not run{}. The runs took {:.0} core-seconds in all{}.\n\n\
         Reproduce: `make reproduce` (runs `experiments/paper/*.toml`, then this report). The opt-in studies in \
         `experiments/paper/opt-in/` enter the report when their runs exist (`magdem experiment experiments/paper/opt-in/FILE.toml`, \
         then `magdem report paper`).\n\n\
         Every number below is computed from the trajectories in `runs/paper-*` ({}), and from the paper's tables in \
         `reference/paper/` (transcribed, with sources, in its README). Tables are also written as CSV and Parquet in \
         [`tables/`](tables/).\n\n\
         Definitions (assumptions where the paper is silent): an aggregate is a connected set of particles whose gaps are at \
         most {:.0e} of the smaller radius; its length is the extent of its centres along its principal axis plus one \
         diameter (n × d for a straight chain of n); the standard deviation in the paper's Table 3 is the population \
         one (its 4.5 mg/ml row is reproduced from its Table 4 only so), and so it is here; CI95 is the 95% confidence \
         interval of a mean over independent seeds (Student's t).\n\n",
        env!("CARGO_PKG_VERSION"),
        env!("MAGDEM_GIT_COMMIT"),
        files.len(),
        done,
        unstable,
        runs.iter().filter(|r| r.status == "missing").count(),
        match runs.iter().filter(|r| !r.completed() && !matches!(r.status.as_str(), "unstable" | "missing") && r.status != crate::io::trajectory::status::UNREADABLE).count() {
            0 => String::new(),
            n => format!(", {n} not finished (interrupted or still running, left out of the tables)"),
        },
        core_seconds,
        options.wall_time.map_or(String::new(), |w| format!("; the `make reproduce` call that wrote this report took {:.0} s of wall time ({:.1} min) for its runs", w, w / 60.0)),
        super::digest::provenance(runs),
        options.gap
    );
    if !unreadable.is_empty() {
        md += &format!("Unreadable run files, left out of every table: {}.\n\n", unreadable.join("; "));
    }
    md += "Experiment files: ";
    md += &files.iter().map(|f| format!("`{}`", f.display())).collect::<Vec<_>>().join(", ");
    md += "\n\n";
    md
}

/// Per concentration of the Table 3 ensemble: the runs' mean lengths and population stds (µm).
struct Ensemble {
    concentration: f64,
    runs: Vec<f64>,
    pop_std: Vec<f64>,
    particles: f64,
    aggregates: f64,
    seeds: Vec<u64>,
    /// Mean over runs of the share of aggregates the box caps.
    box_limited: f64,
}

fn ensembles(runs: &[Run], concentrations: &[f64]) -> Vec<Ensemble> {
    concentrations
        .iter()
        .map(|&c| {
            let here = convergence::table3_runs(runs, c);
            Ensemble {
                concentration: c,
                runs: here.iter().map(|r| r.mean_length_um()).collect(),
                pop_std: here.iter().map(|r| summary(&r.lengths_um()).population_std).collect(),
                particles: mean(&here.iter().map(|r| r.particles as f64).collect::<Vec<_>>()),
                aggregates: mean(&here.iter().map(|r| r.last.len() as f64).collect::<Vec<_>>()),
                seeds: here.iter().map(|r| r.seed).collect(),
                box_limited: mean(&here.iter().map(|r| r.box_limited_fraction()).collect::<Vec<_>>()),
            }
        })
        .collect()
}

fn table3_section(runs: &[Run], paper: &Paper, out: &Path, tables: &Path) -> Result<String, Error> {
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let ens = ensembles(runs, &conc);
    let mut df = frame(vec![
        col("concentration_mg_per_ml", conc.clone()),
        ucol("runs", ens.iter().map(|e| e.runs.len() as u64).collect()),
        col("particles", ens.iter().map(|e| e.particles).collect::<Vec<_>>()),
        col("paper_particles", floats(&paper.table3, "particles")?),
        col("aggregates_per_run", ens.iter().map(|e| e.aggregates).collect::<Vec<_>>()),
        col("magdem_mean_length_um", ens.iter().map(|e| mean(&e.runs)).collect::<Vec<_>>()),
        col("magdem_ci95_um", ens.iter().map(|e| ci95_half_width(&e.runs)).collect::<Vec<_>>()),
        col("magdem_pop_std_um", ens.iter().map(|e| mean(&e.pop_std)).collect::<Vec<_>>()),
        col("box_limited_fraction", ens.iter().map(|e| e.box_limited).collect::<Vec<_>>()),
        col("paper_sim_mean_um", floats(&paper.table3, "sim_mean_length_um")?),
        col("paper_sim_std_um", floats(&paper.table3, "sim_std_um")?),
        col("experiment_mean_um", floats(&paper.table3, "exp_mean_length_um")?),
        col("experiment_std_um", floats(&paper.table3, "exp_std_um")?),
    ])?;
    write(&mut df, tables, "table3")?;
    let mut md = String::from("## Table 3: mean aggregate length in case 1 at t = 5 ms\n\n");
    md += &format!(
        "magdem: the `experiments/paper/table3.toml` ensemble and its opt-in continuation \
         `experiments/paper/opt-in/table3-seeds.toml` (scenes `experiments/scenes/case1-c*.toml`, seeds {}), velocity Verlet \
         at dt = 1e-8 s (every force every step). Mean over seeds of each run's mean length, ± CI95 over seeds; the std \
         column is the mean over seeds of each run's population std; `box-limited` is the mean share of aggregates whose \
         extent along the field reaches 90 % of the box edge. Converged against: time step and integrator (the accuracy \
         study; r-RESPA's bias below). Not converged against: box size and stopping time (sections below), which both \
         still lengthen the chains.\n\n",
        ens.iter().max_by_key(|e| e.seeds.len()).map_or(String::new(), |e| seed_list(&e.seeds))
    );
    let stopped: Vec<String> = runs
        .iter()
        .filter(|r| convergence::TABLE3.contains(&r.experiment.as_str()) && !r.completed() && r.status != "missing")
        .map(|r| format!("{} ({}: {})", r.id, r.status, r.message))
        .collect();
    if !stopped.is_empty() {
        md += &format!("Runs not in the table (not completed): {}.\n\n", stopped.join("; "));
    }
    md += &markdown(
        &df,
        &[
            "c (mg/ml)",
            "runs",
            "particles",
            "paper particles",
            "aggregates/run",
            "magdem mean (µm)",
            "± CI95",
            "magdem std",
            "box-limited",
            "paper sim mean",
            "paper sim std",
            "experiment mean",
            "experiment std",
        ],
        &[3, 0, 0, 0, 1, 1, 1, 1, 3, 1, 1, 0, 0],
    )?;
    table3_figures(&ens, paper, &conc, out)?;
    md += "\n![Table 3](table3.png)\n\n![Spread of the lengths](table3-spread.png)\n\n";
    // Honest reading of the comparison.
    let within: Vec<String> = ens
        .iter()
        .zip(floats(&paper.table3, "exp_mean_length_um")?)
        .zip(floats(&paper.table3, "sim_mean_length_um")?)
        .map(|((e, x), s)| {
            format!(
                "{} mg/ml: {:+.0}% against the experiment, {:+.0}% against the paper's simulation",
                e.concentration,
                100.0 * (mean(&e.runs) / x - 1.0),
                100.0 * (mean(&e.runs) / s - 1.0)
            )
        })
        .collect();
    md += &format!("magdem's mean length: {}.\n\n", within.join("; "));
    md += &gap_sensitivity(runs)?;
    md += "The paper's own tables disagree in places (Table 4's columns hold 318/375/417/293 particles against Table 6's \
           311/385/336/307; Table 4 reproduces Table 3's mean and population std only at 4.5 mg/ml): the audit is in \
           [reference/paper/README.md](../../reference/paper/README.md) and is checked by `tests/analysis.rs`.\n\n";
    Ok(md)
}

/// Table 3's figures: the means (magdem with its CI95 over seeds; the paper's and the
/// experiment's means carry no CI) and, apart, the intrinsic spread of the lengths.
fn table3_figures(ens: &[Ensemble], paper: &Paper, conc: &[f64], out: &Path) -> Result<(), Error> {
    let offset = |k: f64| conc.iter().map(move |&c| c * (1.0 + k)).collect::<Vec<f64>>();
    let pts = |x: Vec<f64>, y: Vec<f64>| x.into_iter().zip(y).collect::<Vec<_>>();
    let series = vec![
        Series::markers(
            "magdem (mean ± CI95 over seeds)",
            pts(offset(0.0), ens.iter().map(|e| mean(&e.runs)).collect()),
            engine_colour("magdem"),
            6,
        )
        .with_errors(ens.iter().map(|e| ci95_half_width(&e.runs)).collect()),
        Series::markers(
            "paper simulation (mean)",
            pts(offset(0.04), floats(&paper.table3, "sim_mean_length_um")?),
            palette(3),
            6,
        ),
        Series::markers(
            "experiment, Mathieu & Martel (mean)",
            pts(offset(-0.04), floats(&paper.table3, "exp_mean_length_um")?),
            RGBColor(0, 0, 0),
            6,
        ),
    ];
    line_chart_with_legend(
        &out.join("table3.png"),
        "Case 1: mean aggregate length at 5 ms",
        "concentration (mg/ml)",
        "mean length (µm)",
        &series,
        SeriesLabelPosition::UpperLeft,
    )?;
    let spread = vec![
        Series::markers(
            "magdem (mean over seeds of each run's population std)",
            pts(offset(0.0), ens.iter().map(|e| mean(&e.pop_std)).collect()),
            engine_colour("magdem"),
            6,
        ),
        Series::markers(
            "paper simulation (std)",
            pts(offset(0.04), floats(&paper.table3, "sim_std_um")?),
            palette(3),
            6,
        ),
        Series::markers(
            "experiment (std)",
            pts(offset(-0.04), floats(&paper.table3, "exp_std_um")?),
            RGBColor(0, 0, 0),
            6,
        ),
    ];
    line_chart_with_legend(
        &out.join("table3-spread.png"),
        "Case 1: spread of the aggregate lengths at 5 ms",
        "concentration (mg/ml)",
        "standard deviation of the lengths (µm)",
        &spread,
        SeriesLabelPosition::UpperLeft,
    )?;
    Ok(())
}

/// Mean length of the seed-1 Table 3 runs at several aggregate gap tolerances: the definition
/// of "in contact" must not decide the answer.
fn gap_sensitivity(runs: &[Run]) -> Result<String, Error> {
    let gaps = [1e-4, 1e-3, 1e-2, 5e-2];
    let mut md = format!(
        "Gap tolerance (fraction of the smaller radius below which two particles count as touching) against the mean length \
         (µm) of each concentration's seed-1 run:\n\n| run | {} |\n|---|{}\n",
        gaps.iter().map(|g| format!("{g:e}")).collect::<Vec<_>>().join(" | "),
        "---|".repeat(gaps.len())
    );
    let respa = runs
        .iter()
        .filter(|r| r.experiment == "paper-sensitivity" && r.variant == "respa" && r.seed == 1 && r.completed())
        .filter(|r| r.has_trajectory());
    // Largest relative change of each run's mean from 1e-3 to 5e-2, and below 1e-3.
    let (mut above, mut below) = (0.0_f64, 0.0_f64);
    for r in table3_ensemble(runs).into_iter().filter(|r| r.seed == 1 && r.has_trajectory()).chain(respa) {
        let t = crate::io::trajectory::Trajectory::open(&r.file)?;
        let reader = crate::analysis::trajectory::FrameReader::new(&t)?;
        let values: Vec<f64> = gaps
            .iter()
            .map(|&g| {
                reader.aggregates(-1, g).map(|(_, a)| 1e6 * mean(&crate::analysis::aggregates::finite_lengths(&a)))
            })
            .collect::<Result<_, _>>()?;
        above = values[1..].iter().fold(above, |m, v| m.max((v / values[1] - 1.0).abs()));
        below = below.max((values[0] / values[1] - 1.0).abs());
        md += &format!("| {} | {} |\n", r.id, values.iter().map(|v| format!("{v:.1}")).collect::<Vec<_>>().join(" | "));
    }
    Ok(md
        + &format!(
            "\nFrom 1e-3 to 5e-2 the mean moves by at most {:.1} %; at 1e-4 (a gap of 0.55 nm) by up to {:.1} %: a contact \
             held by a magnetic attraction can be open by a fraction of a nanometre at a frame while it rings. 1e-3 is the \
             tolerance used throughout.\n\n",
            100.0 * above,
            100.0 * below
        ))
}

/// Aggregate-size histograms of an ensemble, sizes 1..=largest.
struct Histograms {
    /// Mean count over the runs.
    magdem: Vec<f64>,
    /// Mean over the runs of each size's fraction of the run's aggregates, and its std over runs.
    fraction: Vec<f64>,
    fraction_std: Vec<f64>,
}

fn histograms(here: &[&&Run], largest: usize) -> Histograms {
    let per_run: Vec<Vec<f64>> = here
        .iter()
        .map(|r| {
            let mut h = vec![0.0; largest];
            r.last.iter().for_each(|a| h[a.size() - 1] += 1.0);
            h
        })
        .collect();
    let magdem: Vec<f64> = (0..largest).map(|s| mean(&per_run.iter().map(|h| h[s]).collect::<Vec<_>>())).collect();
    let fractions: Vec<Vec<f64>> =
        per_run.iter().map(|h| h.iter().map(|n| n / h.iter().sum::<f64>()).collect()).collect();
    let fraction: Vec<f64> = (0..largest).map(|s| mean(&fractions.iter().map(|f| f[s]).collect::<Vec<_>>())).collect();
    let fraction_std: Vec<f64> =
        (0..largest).map(|s| summary(&fractions.iter().map(|f| f[s]).collect::<Vec<_>>()).sample_std).collect();
    Histograms { magdem, fraction, fraction_std }
}

fn table4_section(runs: &[Run], paper: &Paper, out: &Path, tables: &Path) -> Result<String, Error> {
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let paper_sizes: Vec<usize> =
        floats(&paper.table4, "particles_per_aggregate")?.iter().map(|&s| s as usize).collect();
    let table3 = table3_ensemble(runs);
    let largest = table3
        .iter()
        .flat_map(|r| r.last.iter().map(|a| a.size()))
        .chain(paper_sizes.iter().copied())
        .max()
        .unwrap_or(1);
    let (mut c_col, mut size_col, mut magdem_col, mut paper_col) = (vec![], vec![], vec![], vec![]);
    let (mut frac_col, mut frac_std_col, mut paper_frac_col) = (vec![], vec![], vec![]);
    let mut panels = vec![];
    let mut summary_rows: Vec<SizeSummary> = vec![];
    for &c in &conc {
        let here: Vec<&&Run> = table3.iter().filter(|r| same(r.concentration, c)).collect();
        let paper_counts = floats(&paper.table4, &format!("count_c{c}"))?;
        let Histograms { magdem, fraction, fraction_std } = histograms(&here, largest);
        let mut paper_row = vec![0.0; largest];
        for (s, n) in paper_sizes.iter().zip(&paper_counts) {
            paper_row[s - 1] = *n;
        }
        let paper_total: f64 = paper_row.iter().sum();
        let paper_fraction: Vec<f64> = paper_row.iter().map(|n| n / paper_total).collect();
        for s in 1..=largest {
            c_col.push(c);
            size_col.push(s as u64);
            magdem_col.push(magdem[s - 1]);
            paper_col.push(paper_row[s - 1]);
            frac_col.push(fraction[s - 1]);
            frac_std_col.push(fraction_std[s - 1]);
            paper_frac_col.push(paper_fraction[s - 1]);
        }
        let total = |v: &[f64]| v.iter().sum::<f64>();
        let max_size = |v: &[f64]| v.iter().rposition(|&n| n > 0.0).map_or(0.0, |k| (k + 1) as f64);
        let mean_max =
            mean(&here.iter().map(|r| r.last.iter().map(|a| a.size()).max().unwrap_or(0) as f64).collect::<Vec<_>>());
        summary_rows.push((
            c,
            total(&paper_row),
            total(&magdem),
            paper_row[0],
            magdem[0],
            max_size(&paper_row),
            mean_max,
        ));
        panels.push(BarPanel {
            title: format!("{c} mg/ml"),
            y_label: "fraction of aggregates".into(),
            categories: (1..=largest).map(|s| s.to_string()).collect(),
            groups: vec![
                BarGroup {
                    label: format!("magdem: mean of {} seeds, bars ± std over seeds", here.len()),
                    color: engine_colour("magdem"),
                    values: fraction,
                    errors: fraction_std,
                },
                BarGroup {
                    label: "paper simulation (one run)".into(),
                    color: palette(3),
                    values: paper_fraction,
                    errors: vec![],
                },
            ],
        });
    }
    let mut df = frame(vec![
        col("concentration_mg_per_ml", c_col),
        ucol("particles_per_aggregate", size_col),
        col("magdem_mean_count", magdem_col),
        col("paper_count", paper_col),
        col("magdem_fraction", frac_col),
        col("magdem_fraction_std_over_seeds", frac_std_col),
        col("paper_fraction", paper_frac_col),
    ])?;
    write(&mut df, tables, "table4")?;
    category_panels(
        &out.join("table4.png"),
        "Case 1: aggregate size distributions at 5 ms (x: particles per aggregate)",
        &panels,
        2,
        (760, 420),
        Mark::Bars,
    )?;
    table4_summary(&summary_rows, tables)
}

/// Per concentration: (c, paper aggregates, magdem aggregates per run, paper singles, magdem
/// singles per run, paper largest, magdem largest mean over runs).
type SizeSummary = (f64, f64, f64, f64, f64, f64, f64);

/// Table 4's summary table and its prose.
fn table4_summary(summary_rows: &[SizeSummary], tables: &Path) -> Result<String, Error> {
    let mut sdf = frame(vec![
        col("concentration_mg_per_ml", summary_rows.iter().map(|r| r.0).collect::<Vec<_>>()),
        col("paper_aggregates", summary_rows.iter().map(|r| r.1).collect::<Vec<_>>()),
        col("magdem_aggregates_per_run", summary_rows.iter().map(|r| r.2).collect::<Vec<_>>()),
        col("paper_single_particles", summary_rows.iter().map(|r| r.3).collect::<Vec<_>>()),
        col("magdem_single_particles_per_run", summary_rows.iter().map(|r| r.4).collect::<Vec<_>>()),
        col("paper_largest", summary_rows.iter().map(|r| r.5).collect::<Vec<_>>()),
        col("magdem_largest_mean_over_runs", summary_rows.iter().map(|r| r.6).collect::<Vec<_>>()),
    ])?;
    write(&mut sdf, tables, "table4_summary")?;
    let mut md = String::from("## Table 4: aggregate size distributions\n\n");
    md += "Number of aggregates of each size (particles per aggregate) at 5 ms; magdem's counts are means over the seeds. \
           The figure shows each size's fraction of the aggregates (magdem: mean over seeds, bars ± the std over seeds, the \
           seed-to-seed spread; the paper: its one run). The full histograms, counts and fractions, are in \
           `tables/table4.csv`.\n\n";
    md += &markdown(
        &sdf,
        &[
            "c (mg/ml)",
            "paper aggregates",
            "magdem aggregates/run",
            "paper singles",
            "magdem singles/run",
            "paper largest",
            "magdem largest (mean)",
        ],
        &[3, 0, 1, 0, 1, 0, 1],
    )?;
    md += "\n![Table 4](table4.png)\n\n";
    Ok(md)
}

/// Lengths (µm) of the paper's simulated aggregates from its Table 4 histogram (n × 11 µm).
fn paper_lengths(paper: &Paper, c: f64) -> PolarsResult<Vec<f64>> {
    let sizes = floats(&paper.table4, "particles_per_aggregate")?;
    let counts = floats(&paper.table4, &format!("count_c{c}"))?;
    Ok(sizes.iter().zip(&counts).flat_map(|(&s, &n)| std::iter::repeat_n(s * 11.0, n as usize)).collect())
}

fn box_section(runs: &[Run], paper: &Paper, out: &Path) -> Result<String, Error> {
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let (exp_mean, exp_std) = (floats(&paper.table3, "exp_mean_length_um")?, floats(&paper.table3, "exp_std_um")?);
    let table3 = table3_ensemble(runs);
    let mut panels = vec![];
    for (k, &c) in conc.iter().enumerate() {
        let here: Vec<&&Run> = table3.iter().filter(|r| same(r.concentration, c)).collect();
        let magdem: Vec<f64> = here.iter().flat_map(|r| r.lengths_um()).collect();
        let capped = here.iter().map(|r| r.last.iter().filter(|a| a.box_limited(r.box_extent)).count()).sum::<usize>();
        let boxes = [
            BoxStats::of("magdem (all seeds)", engine_colour("magdem"), &magdem),
            BoxStats::of("paper simulation", palette(3), &paper_lengths(paper, c)?),
        ];
        // Every seed of a concentration has the same box; dashed: its edge along the field.
        let edge = here.first().map_or(f64::NAN, |r| r.box_extent * 1e6);
        panels.push(BoxPanel {
            title: format!(
                "{}) {c} mg/ml; magdem: {capped} of {} lengths box-limited",
                ["a", "b", "c", "d"][k % 4],
                magdem.len()
            ),
            limit: edge,
            y_label: "major axis length (µm)".into(),
            boxes: boxes.into_iter().flatten().collect(),
            markers: vec![("experiment (mean ± std)".into(), exp_mean[k], exp_std[k])],
        });
    }
    box_panels(
        &out.join("boxplots.png"),
        "Case 1 at 5 ms: quartiles, median (red), Tukey fences, mean (blue), box edge (dashed)",
        &panels,
        2,
    )?;
    Ok("## The box-plot figure\n\n\
        The paper's figure compares its simulated lengths with the experiment's as box plots. The experiment's distributions \
        are not published as numbers (only mean and std, Table 3), so the experiment appears as its mean ± std; the paper's \
        simulated distribution is rebuilt from its Table 4 (n × 11 µm per aggregate). The dashed line is the box edge along the field: \
        a magdem length near it is box-limited (its count is in each panel's title).\n\n![Box plots](boxplots.png)\n\n"
        .into())
}

fn case2_section(runs: &[Run], paper: &Paper, out: &Path, tables: &Path) -> Result<String, Error> {
    let here = completed(runs, "paper-case2");
    let mut md = String::from("## Table 2: case 2, aggregates driven by a gradient\n\n");
    if here.is_empty() {
        md += "No completed case-2 runs (`experiments/paper/case2.toml`).\n\n";
        return Ok(md);
    }
    // Per run: mean and population std of size and tracked x velocity, over all aggregates and
    // over aggregates of two or more particles.
    let per_run = |r: &Run, min_size: usize| {
        let size =
            summary(&r.last.iter().map(|a| a.size()).filter(|&n| n >= min_size).map(|n| n as f64).collect::<Vec<_>>());
        let vx = summary(&r.free_velocities_um_per_s(min_size));
        [size.mean, size.population_std, vx.mean, vx.population_std]
    };
    let instantaneous =
        mean(&here.iter().flat_map(|r| r.last.iter().map(|a| a.com_velocity.x * 1e6)).collect::<Vec<_>>());
    let walled = here.iter().map(|r| r.last.iter().filter(|a| a.at_x_wall).count()).sum::<usize>();
    let total = here.iter().map(|r| r.last.len()).sum::<usize>();
    let mut source = vec![];
    let mut cols: [Vec<f64>; 6] = Default::default();
    for (label, min_size) in [("magdem, all aggregates", 1), ("magdem, aggregates of 2+", 2)] {
        let rows: Vec<[f64; 4]> = here.iter().map(|r| per_run(r, min_size)).collect();
        let pick = |k: usize| rows.iter().map(|r| r[k]).collect::<Vec<f64>>();
        source.push(format!("{label} ({} seeds)", rows.len()));
        for (k, c) in cols.iter_mut().take(4).enumerate() {
            c.push(mean(&pick(k)));
        }
        cols[4].push(ci95_half_width(&pick(0)));
        cols[5].push(ci95_half_width(&pick(2)));
    }
    for (k, name) in strings(&paper.table2, "source")?.into_iter().enumerate() {
        source.push(name);
        for (c, key) in cols.iter_mut().zip([
            "mean_size_particles",
            "std_size_particles",
            "mean_velocity_um_per_s",
            "std_velocity_um_per_s",
        ]) {
            c.push(floats(&paper.table2, key)?[k]);
        }
        cols[4].push(f64::NAN);
        cols[5].push(f64::NAN);
    }
    let [size, size_std, vx, vx_std, size_ci, vx_ci] = cols;
    let mut df = frame(vec![
        scol("source", source.clone()),
        col("mean_size_particles", size.clone()),
        col("std_size_particles", size_std.clone()),
        col("ci95_size", size_ci),
        col("mean_velocity_um_per_s", vx.clone()),
        col("std_velocity_um_per_s", vx_std.clone()),
        col("ci95_velocity", vx_ci),
    ])?;
    write(&mut df, tables, "table2")?;
    let scene = Scene::parse(&here[0].scene_text, "case 2")?;
    let s = &scene.species[0];
    let b0 = scene.spec.field.as_ref().map_or(0.0, |f| nalgebra::Vector3::from(f.b0).norm());
    let h = b0 / crate::core::magnetisation::MU0;
    md += &format!(
        "magdem: `experiments/paper/case2.toml` (scene `experiments/scenes/case2.toml`, seeds {}), t = {} s. Size in particles; \
         velocity in µm/s along the gradient (x), tracked as the members' mean displacement over the last tenth of the run \
         (as a microscope tracks an aggregate; the instantaneous centre-of-mass velocity of the last frame, which catches \
         aggregates mid-collision, averages {:.1} µm/s over all aggregates). Aggregates reaching within one diameter of an x \
         wall are held by it and left out of the velocity ({} of {} at the end; the paper's box is 192 µm long and fast \
         chains cross a large part of it in 1.25 s). std is the population std over the aggregates of a run, averaged over \
         seeds; CI95 is over the seeds' means.\n\n\
         Derived magnetisation of the 5.5 µm particles (the paper gives none): χ_eff = {:.3} (material χ = {:.3}), so M = χ_eff H = \
         {:.3e} A/m at B0 = {} T (H = {:.0} A/m) — the value at which a single sphere moves at the measured 7.5 µm/s under 1.4 T/m \
         with Stokes drag.\n\n",
        here.iter().map(|r| r.seed.to_string()).collect::<Vec<_>>().join(", "),
        here[0].times.last().copied().unwrap_or(f64::NAN),
        instantaneous,
        walled,
        total,
        s.susceptibility,
        3.0 * s.susceptibility / (3.0 - s.susceptibility),
        s.susceptibility * h,
        b0,
        h
    );
    md += &markdown(
        &df,
        &["source", "mean size", "std", "± CI95", "mean velocity (µm/s)", "std", "± CI95"],
        &[0, 2, 2, 2, 2, 2, 2],
    )?;
    let panels = vec![
        BarPanel {
            title: "aggregate size".into(),
            y_label: "particles (± std)".into(),
            categories: source.iter().map(|s| short_source(s)).collect(),
            groups: vec![BarGroup { label: String::new(), color: palette(1), values: size, errors: size_std }],
        },
        BarPanel {
            title: "aggregate velocity".into(),
            y_label: "µm/s (± std)".into(),
            categories: source.iter().map(|s| short_source(s)).collect(),
            groups: vec![BarGroup { label: String::new(), color: palette(2), values: vx, errors: vx_std }],
        },
    ];
    category_panels(&out.join("case2.png"), "Case 2: aggregates at 1.25 s", &panels, 2, (760, 480), Mark::Bars)?;
    md += "\n![Case 2](case2.png)\n\n";
    md += &case2_velocity_by_size(&here, out)?;
    Ok(md)
}

/// Velocity against size, pooled over seeds: the paper's shielding lets only a chain's leading
/// sphere feel drag, so a chain of n along the gradient moves about n times faster.
fn case2_velocity_by_size(here: &[&Run], out: &Path) -> Result<String, Error> {
    let mut by_size: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    for r in here {
        for a in r.last.iter().filter(|a| !a.at_x_wall) {
            by_size.entry(a.size).or_default().push(a.tracked_vx * 1e6);
        }
    }
    let single = by_size.get(&1).map_or(f64::NAN, |v| mean(v));
    let points: Vec<(f64, f64)> = by_size.iter().map(|(&n, v)| (n as f64, mean(v))).collect();
    let ideal: Vec<(f64, f64)> = points.iter().map(|&(n, _)| (n, n * single)).collect();
    line_chart_with_legend(
        &out.join("case2-velocity-by-size.png"),
        "Case 2: tracked velocity against aggregate size (all seeds)",
        "particles in the aggregate",
        "velocity along the gradient (µm/s)",
        &[
            Series::markers("magdem, mean per size", points.clone(), engine_colour("magdem"), 6),
            Series::line("n × single-particle velocity", ideal, palette(6)),
            Series::markers(
                "experiment (7.5 µm/s, any size)",
                vec![(1.0, 7.5), (points.last().map_or(1.0, |p| p.0), 7.5)],
                RGBColor(0, 0, 0),
                4,
            ),
        ],
        SeriesLabelPosition::UpperLeft,
    )?;
    Ok(format!(
        "Why magdem's aggregates move faster than the experiment's: single particles move at {single:.1} µm/s on average (an \
         isolated one at 7.5–7.8 µm/s, the field growing along x; neighbours' attraction holds the others back), but under the paper's A_eff a chain aligned with the gradient hides all spheres but \
         the leading one, so its drag stays that of one sphere while its magnetic force grows n-fold: {}. In Stokes flow a \
         chain's drag grows nearly linearly with n (slender-body theory), which is why measured aggregates all move at \
         about the same speed; the shielding model overstates the speed-up, and the paper's own 8.3 µm/s suggests its \
         chains were not aligned with their motion.\n\n![Velocity by size](case2-velocity-by-size.png)\n\n",
        points.iter().map(|(n, v)| format!("n = {n:.0}: {v:.1} µm/s")).collect::<Vec<_>>().join(", ")
    ))
}

fn short_source(s: &str) -> String {
    if s.starts_with("magdem, all") {
        "magdem all".into()
    } else if s.starts_with("magdem") {
        "magdem 2+".into()
    } else if s.starts_with("experiment") {
        "experiment".into()
    } else if s.contains("this paper") {
        "paper sim".into()
    } else {
        "V&M sim".into()
    }
}

fn approach_section(runs: &[Run], out: &Path) -> Result<String, Error> {
    let Some(run) = completed(runs, "paper-approach").into_iter().find(|r| r.has_trajectory()) else {
        return Ok("## Approach velocity\n\nNo completed run of `experiments/paper/approach.toml`.\n\n".into());
    };
    let t = crate::io::trajectory::Trajectory::open(&run.file)?;
    let x = t.all_vectors("position")?;
    let v = t.all_vectors("velocity")?;
    let times = t.times()?;
    let d = 2.0 * t.file.dataset("particles/radius")?.read_raw::<f64>()?[0];
    let (mut speed, mut gap) = (vec![], vec![]);
    for k in 0..times.len() {
        let r = (0..3).map(|c| (x[[k, 1, c]] - x[[k, 0, c]]).powi(2)).sum::<f64>().sqrt();
        let s = (0..3).map(|c| v[[k, 1, c]].powi(2)).sum::<f64>().sqrt();
        if s > 0.0 {
            speed.push((times[k] * 1e3, (s * 1e3).log10()));
            gap.push((r / d, (s * 1e3).log10()));
        }
    }
    let contact = gap.iter().position(|&(r, _)| r <= 1.0).map(|k| times[k]);
    let peak = speed.iter().cloned().fold((0.0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
    let peak = (peak.0, 10f64.powf(peak.1));
    line_chart_with_legend(
        &out.join("approach.png"),
        "Two 11 µm particles from 15 diameters at 1.5 T",
        "time (ms)",
        "log10 speed of one particle (mm/s)",
        &[Series::line("magdem", speed, engine_colour("magdem"))],
        SeriesLabelPosition::UpperLeft,
    )?;
    line_chart_with_legend(
        &out.join("approach-distance.png"),
        "Approach speed against centre distance",
        "centre distance (diameters)",
        "log10 speed of one particle (mm/s)",
        &[Series::line("magdem", gap.into_iter().filter(|p| p.0 > 1.0).collect(), engine_colour("magdem"))],
        SeriesLabelPosition::UpperRight,
    )?;
    Ok(format!(
        "## Approach velocity (the paper's 15-diameter figure)\n\n\
         `experiments/scenes/approach-1.5T.toml`: two 11 µm Fe3O4 spheres start 15 diameters apart along a uniform 1.5 T field \
         (exact mutual induction, Schiller–Naumann drag with the paper's shielding). They touch at t = {} ms; the peak speed of \
         one particle is {:.1} mm/s at {:.4} ms (the last frame before contact; frames every 2 µs). The speed grows as the \
         separation closes (the dipole force goes as r⁻⁴), as the paper's figure shows. The linear magnetisation law at 1.5 T \
         gives M = χ_eff B0/μ0 = {:.2e} A/m, {:.1}× bulk magnetite's saturation (4.8e5 A/m): with saturation the force, and \
         the impact speed, would be far smaller.\n\n![Approach speed against time](approach.png)\n![Approach speed against distance](approach-distance.png)\n\n",
        contact.map_or("– (not within the run)".into(), |t| format!("{:.4}", t * 1e3)),
        peak.1,
        peak.0,
        3.0 * (12.3 - 1.0) / (12.3 + 2.0) * 1.5 / crate::core::magnetisation::MU0,
        3.0 * (12.3 - 1.0) / (12.3 + 2.0) * 1.5 / crate::core::magnetisation::MU0 / 4.8e5
    ))
}

/// The sensitivity experiments: `sensitivity.toml` (2.25 mg/ml, ten seeds, numerical and
/// physical changes) and `sensitivity-concentrations.toml` (the physical changes at the other three).
const SENSITIVITY: [&str; 2] = ["paper-sensitivity", "paper-sensitivity-concentrations"];

fn sensitivity_section(runs: &[Run], out: &Path, tables: &Path, effects: &mut Vec<Effect>) -> Result<String, Error> {
    let mut md = String::from("## Sensitivity: which choices move the case-1 answer\n\n");
    // Concentration (as printed) → variant → runs.
    let mut studies: BTreeMap<u64, BTreeMap<String, Vec<&Run>>> = BTreeMap::new();
    for r in runs.iter().filter(|r| SENSITIVITY.contains(&r.experiment.as_str())) {
        let key = (r.concentration * 1e3).round() as u64;
        studies.entry(key).or_default().entry(r.variant.clone()).or_default().push(r);
    }
    studies.retain(|_, groups| !reference_of(groups).is_empty());
    if studies.is_empty() {
        md += "Not run: `experiments/paper/opt-in/sensitivity.toml` (its reference variant `respa` has no completed runs) enters here \
               when its runs exist.\n\n";
        return Ok(md);
    }
    let (mut conc, mut names, mut changes, mut done_runs, mut means) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut deltas, mut delta_cis, mut outcome, mut cost, mut capped, mut fastest) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let (mut panels, mut references) = (vec![], vec![]);
    for groups in studies.values() {
        let reference = reference_of(groups);
        let c = reference[0].concentration;
        let base = convergence::Estimate::of(&reference.iter().map(|r| r.mean_length_um()).collect::<Vec<_>>());
        let shared = reference[0].variant_overrides.clone();
        references.push(format!(
            "{c} mg/ml: `{}`, seeds {}, reference {} µm",
            reference[0].scene,
            seed_list(&reference.iter().map(|r| r.seed).collect::<Vec<_>>()),
            base.cell(1)
        ));
        let mut bars = vec![];
        for (name, group) in groups.iter().filter(|(name, _)| name.as_str() != "respa") {
            let ok: Vec<&Run> = group.iter().copied().filter(|r| r.completed()).collect();
            let d = convergence::paired_change(&reference, &ok);
            conc.push(c);
            names.push(name.clone());
            changes.push(
                group[0]
                    .variant_overrides
                    .iter()
                    .filter(|o| !shared.contains(o))
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", "),
            );
            done_runs.push(ok.len() as u64);
            means.push(mean(&ok.iter().map(|r| r.mean_length_um()).collect::<Vec<_>>()));
            capped.push(mean(&ok.iter().map(|r| r.box_limited_fraction()).collect::<Vec<_>>()));
            // A held force that pumps energy into contacts shows as aggregates still flying at the end.
            fastest.push(ok.iter().flat_map(|r| r.last.iter().map(|a| a.com_velocity.norm())).fold(f64::NAN, f64::max));
            deltas.push(d.mean);
            delta_cis.push(d.ci95);
            outcome.push(variant_outcome(group, ok.len()));
            cost.push(mean(&group.iter().map(|r| r.wall_time).collect::<Vec<_>>()));
            if d.n > 0 {
                bars.push((name.clone(), d));
                if let Some(explanation) = sensitivity_explanation(name) {
                    effects.push(Effect {
                        concentration: c,
                        explanation,
                        what: format!("{name} against r-RESPA, paired over {} seeds", d.n),
                        change: d,
                    });
                }
            }
        }
        let seeds = reference.len();
        panels.push(sensitivity_panel(&bars, c, seeds));
    }
    let mut df = frame(vec![
        col("concentration_mg_per_ml", conc),
        scol("variant", names),
        scol("change", changes),
        ucol("runs", done_runs),
        col("mean_length_um", means),
        col("box_limited_fraction", capped),
        col("fastest_aggregate_at_end_m_per_s", fastest),
        col("paired_change_percent", deltas),
        col("paired_change_ci95_percent", delta_cis),
        col("wall_time_per_run_s", cost),
        scol("outcome", outcome),
    ])?;
    write(&mut df, tables, "sensitivity")?;
    md += &format!(
        "`experiments/paper/opt-in/sensitivity.toml` (2.25 mg/ml, ten seeds: numerical and physical choices) and \
         `sensitivity-concentrations.toml` (the physical choices and the paper's pipeline at the other concentrations, three \
         seeds); one change at a time against the reference variant `respa` (integration.scheme = \"respa\", \
         integration.slow_every = 10) of the same scene and seeds ({}). Each change is paired seed by seed: each seed's \
         difference over the reference mean, mean ± CI95 over the seeds. A change matters when its CI95 excludes zero.\n\n",
        references.join("; ")
    );
    md += &markdown(
        &df,
        &[
            "c (mg/ml)",
            "variant",
            "change",
            "runs",
            "mean length (µm)",
            "box-limited",
            "fastest aggregate at 5 ms (m/s)",
            "paired change (%)",
            "± CI95",
            "wall time/run (s)",
            "outcome",
        ],
        &[3, 0, 0, 0, 1, 3, 4, 1, 1, 0, 0],
    )?;
    md += "\nThe paper's pipeline holds the moments and dipole forces over each 1e-6 s outer step while contacts are resolved at \
           1e-8 s. A contact closes and reopens within about 7e-8 s, so the held attraction keeps pulling on a pair that has already \
           rebounded. The fastest-aggregate column (the largest centre-of-mass speed of any aggregate in the last frame, collisions \
           under way included) shows whether that pumped energy into the particles; compare it across the variants. `drag-held` \
           is a numerical choice, not a modelling one: the shielded drag's coefficients renewed once per outer step \
           instead of every step (a 100× step 28 % shorter, `reports/performance-history.md`); it is not an explanation \
           and stays out of the ranking below. Nor are `respa-20` and `respa-50`: r-RESPA with the magnetic forces held over \
           20 and 50 steps of 1e-8 s instead of 10, the outer step whose length sets the cost of the 100× runs (the moments, \
           the 15-diameter pairs and the dipole forces are computed once per outer step). Their rows show where between \
           1e-7 s and the paper's 1e-6 s the held attraction starts to pump energy and shorten the chains. Nor is \
           `renumbered`: the reference with the particles renumbered along a Morton curve every 1 000 steps \
           (`integration.renumber_every`), which changes only the order of the force sums; its row says whether that \
           round-off, grown by the chaotic dynamics, moves the statistics.\n";
    category_panels(
        &out.join("sensitivity.png"),
        "Case 1: which choices move the mean length (each variant against r-RESPA, paired seed by seed)",
        &panels,
        2,
        (900, 520),
        Mark::Dots,
    )?;
    md += "\n![Sensitivity](sensitivity.png)\n\n";
    Ok(md)
}

/// What a stopped or partly run variant's row says.
fn variant_outcome(group: &[&Run], completed: usize) -> String {
    let stopped: Vec<&&Run> = group.iter().filter(|r| r.status == "unstable").collect();
    match stopped.first() {
        Some(r) => {
            format!(
                "{} of {} stopped: {}",
                stopped.len(),
                group.len(),
                r.message.split(';').next().unwrap_or(&r.message)
            )
        }
        None if completed < group.len() => format!("{} of {} not run", group.len() - completed, group.len()),
        None => String::new(),
    }
}

/// The explanation of the "why the numbers differ" ranking a sensitivity variant (named in the
/// experiment file) measures.
fn sensitivity_explanation(variant: &str) -> Option<Explanation> {
    match variant {
        "no-induction" => Some(Explanation::Induction),
        "no-shielding" => Some(Explanation::Shielding),
        "restitution-0.2" | "restitution-0.9" => Some(Explanation::Restitution),
        "paper-pipeline" => Some(Explanation::PaperPipeline),
        _ => None,
    }
}

/// The completed runs of a sensitivity study's reference variant `respa`.
fn reference_of<'a>(groups: &BTreeMap<String, Vec<&'a Run>>) -> Vec<&'a Run> {
    groups.get("respa").map_or(vec![], |g| g.iter().copied().filter(|r| r.completed()).collect())
}

/// One concentration's panel of the sensitivity figure: each variant's paired change with its
/// CI95 over seeds.
fn sensitivity_panel(bars: &[(String, convergence::Estimate)], concentration: f64, seeds: usize) -> BarPanel {
    BarPanel {
        title: format!("{concentration} mg/ml ({seeds} seeds)"),
        y_label: "change of the mean length at 5 ms (%)".into(),
        categories: bars.iter().map(|(name, _)| name.clone()).collect(),
        groups: vec![BarGroup {
            label: "mean ± CI95 over seeds".into(),
            color: palette(1),
            values: bars.iter().map(|(_, d)| d.mean).collect(),
            errors: bars.iter().map(|(_, d)| d.ci95).collect(),
        }],
    }
}

/// The paper's box in the walls-and-count comparison.
const PAPER_BOX: &str = "walls, paper's box";

fn box_effect_section(runs: &[Run], paper: &Paper, out: &Path, tables: &Path) -> Result<String, Error> {
    let in_box_study = |r: &Run| {
        r.experiment.starts_with("paper-box") && !convergence::NUMERICAL_X100.contains(&r.experiment.as_str())
    };
    let box_runs: Vec<&Run> = runs.iter().filter(|r| in_box_study(r) && r.completed()).collect();
    let mut md = String::from("## Where the walls are, and how many particles\n\n");
    if box_runs.is_empty() {
        md += "Not run: the opt-in experiments `experiments/paper/opt-in/box-*.toml` (periodic faces; 10× the particles in a larger \
               box at equal concentration) and `x100-*.toml` (100×) enter here when their runs exist.\n\n";
        return Ok(md);
    }
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let exp = floats(&paper.table3, "exp_mean_length_um")?;
    let (mut c_col, mut v_col, mut n_col, mut p_col, mut m_col, mut ci_col, mut cap_col, mut e_col) =
        (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut panels = vec![];
    let mut findings = vec![];
    for (k, &c) in conc.iter().enumerate() {
        let mut groups: BTreeMap<String, Vec<&Run>> = BTreeMap::new();
        for r in box_runs.iter().filter(|r| same(r.concentration, c)) {
            groups.entry(r.variant.clone()).or_default().push(r);
        }
        if groups.is_empty() {
            continue;
        }
        // The paper's box under the same integrator (r-RESPA) and seeds.
        let seeds: Vec<u64> = groups.values().flatten().map(|r| r.seed).collect();
        groups.insert(
            PAPER_BOX.into(),
            convergence::respa_runs(runs, c).into_iter().filter(|r| seeds.contains(&r.seed)).collect(),
        );
        let (mut cats, mut vals, mut errs) = (vec![], vec![], vec![]);
        for (variant, group) in &groups {
            let m: Vec<f64> = group.iter().map(|r| r.mean_length_um()).collect();
            c_col.push(c);
            v_col.push(variant.clone());
            n_col.push(group.len() as u64);
            p_col.push(mean(&group.iter().map(|r| r.particles as f64).collect::<Vec<_>>()));
            m_col.push(mean(&m));
            ci_col.push(ci95_half_width(&m));
            cap_col.push(mean(&group.iter().map(|r| r.box_limited_fraction()).collect::<Vec<_>>()));
            e_col.push(exp[k]);
            cats.push(variant.clone());
            vals.push(mean(&m));
            errs.push(ci95_half_width(&m));
        }
        // Each larger or periodic box against the paper's, seed by seed.
        let paper_box = &groups[PAPER_BOX];
        for (variant, group) in groups.iter().filter(|(v, _)| v.as_str() != PAPER_BOX) {
            let d = convergence::paired_change(paper_box, group);
            if d.n == 0 {
                continue;
            }
            let longer = group
                .iter()
                .filter(|r| paper_box.iter().any(|w| w.seed == r.seed && r.mean_length_um() > w.mean_length_um()))
                .count();
            findings.push(if d.n < 2 {
                format!("{c} mg/ml, {variant} against the paper's box: {:+.0} % (one seed)", d.mean)
            } else {
                format!(
                    "{c} mg/ml, {variant} against the paper's box: {:+.0} ± {:.0} % (paired over {} seeds; longer in {longer} of them)",
                    d.mean, d.ci95, d.n
                )
            });
        }
        cats.push("experiment".into());
        vals.push(exp[k]);
        errs.push(f64::NAN);
        panels.push(BarPanel {
            title: format!("{c} mg/ml"),
            y_label: "mean length (µm)".into(),
            categories: cats,
            groups: vec![BarGroup { label: String::new(), color: palette(1), values: vals, errors: errs }],
        });
    }
    let mut df = frame(vec![
        col("concentration_mg_per_ml", c_col),
        scol("domain", v_col),
        ucol("runs", n_col),
        col("particles", p_col),
        col("mean_length_um", m_col),
        col("ci95_um", ci_col),
        col("box_limited_fraction", cap_col),
        col("experiment_mean_um", e_col),
    ])?;
    write(&mut df, tables, "box_and_count")?;
    md += "The paper attributes its underestimate at 2.25 and 4.5 mg/ml to its ~300 particles. Same scenes and seeds, with \
           periodic faces instead of walls, and with 10× (and, where run, 100×) the particles in a box scaled at equal \
           concentration (`experiments/paper/opt-in/`), all under r-RESPA K = 10 (the paper's box: the magnetisation sweep's \
           linear law and the sensitivity study's reference, same seeds). `box-limited` as in Table 3 (a percolating aggregate counts as box-limited and is left out of the mean):\n\n";
    md += &markdown(
        &df,
        &["c (mg/ml)", "domain", "runs", "particles", "mean length (µm)", "± CI95", "box-limited", "experiment (µm)"],
        &[3, 0, 0, 0, 1, 1, 3, 0],
    )?;
    if !findings.is_empty() {
        md += &format!(
            "\nEach change, seed by seed (mean ± CI95 of the seeds' relative differences): {}. In magdem's model (the paper's \
             unsaturated magnetisation) more particles lengthen the chains, so the gap to the experiment widens rather than \
             closes wherever the change is positive.\n",
            findings.join("; ")
        );
    }
    category_panels(
        &out.join("box-and-count.png"),
        "Case 1: effect of the walls and of the particle count (± CI95)",
        &panels,
        2,
        (760, 460),
        Mark::Bars,
    )?;
    md += "\n![Walls and particle count](box-and-count.png)\n\n";
    Ok(md)
}

fn reference_section(runs: &[Run], out: &Path, tables: &Path) -> Result<String, Error> {
    let here: Vec<&Run> = runs.iter().filter(|r| r.experiment == "paper-reference").collect();
    let mut md = String::from("## LIGGGHTS and LAMMPS on the same case-1 scene\n\n");
    md += &reference_ensemble(runs, out, tables)?;
    if here.is_empty() {
        md += "No runs of `experiments/paper/reference.toml`.\n\n";
        return Ok(md);
    }
    // magdem's completed run of the same scene and seed, which each engine is held against.
    let native_of = |r: &Run| {
        here.iter().copied().find(|n| n.engine == "magdem" && n.scene == r.scene && n.seed == r.seed && n.completed())
    };
    // Position differences to it, frame by frame.
    let differences: Vec<(f64, f64)> = here
        .iter()
        .map(|r| match native_of(r) {
            Some(n) if r.completed() => position_difference(&n.file, &r.file).unwrap_or((f64::NAN, f64::NAN)),
            _ => (f64::NAN, f64::NAN),
        })
        .collect();
    let mut df = frame(vec![
        scol("scene", here.iter().map(|r| r.scene.clone()).collect()),
        scol("engine", here.iter().map(|r| r.engine.clone()).collect()),
        ucol("seed", here.iter().map(|r| r.seed).collect()),
        scol(
            "status",
            here.iter()
                .map(|r| if r.completed() { "completed".to_string() } else { format!("{} {}", r.status, r.message) })
                .collect(),
        ),
        col(
            "aggregates",
            here.iter().map(|r| if r.completed() { r.last.len() as f64 } else { f64::NAN }).collect::<Vec<_>>(),
        ),
        col(
            "mean_length_um",
            here.iter().map(|r| if r.completed() { r.mean_length_um() } else { f64::NAN }).collect::<Vec<_>>(),
        ),
        col(
            "pop_std_um",
            here.iter()
                .map(|r| if r.completed() { summary(&r.lengths_um()).population_std } else { f64::NAN })
                .collect::<Vec<_>>(),
        ),
        col(
            "largest",
            here.iter()
                .map(|r| r.last.iter().map(|a| a.size()).max().map_or(f64::NAN, |s| s as f64))
                .collect::<Vec<_>>(),
        ),
        scol("max_dx_end_m", differences.iter().map(|d| sci(d.0)).collect()),
        scol("max_dx_run_m", differences.iter().map(|d| sci(d.1)).collect()),
        col("wall_time_s", here.iter().map(|r| r.wall_time).collect::<Vec<_>>()),
    ])?;
    write(&mut df, tables, "reference_engines")?;
    md += "`experiments/paper/reference.toml`: the case-1 scene with the forces all three engines can express (Stokes drag, no \
         A_eff shielding, no rotational drag — neither LIGGGHTS nor LAMMPS has Schiller–Naumann or shielded drag), velocity \
         Verlet at dt = 1e-8 s in all three, magdem's moments and dipole forces handed to LIGGGHTS and LAMMPS through `fix \
         external` every step. Δx is the largest distance between a particle's position in that engine and in magdem, at the \
         last frame and over all frames. Aggregation is chaotic in general (contacts amplify round-off), so agreement of the \
         statistics is the requirement and agreement of trajectories a bonus; LAMMPS' tangential contact model differs from \
         LIGGGHTS' and magdem's by design (see the contact verification report). Engines not installed show as missing.\n\n";
    md += &markdown(
        &df,
        &[
            "scene",
            "engine",
            "seed",
            "status",
            "aggregates",
            "mean length (µm)",
            "pop std (µm)",
            "largest",
            "largest Δx at the end (m)",
            "largest Δx over the run (m)",
            "wall time (s)",
        ],
        &[0, 0, 0, 0, 0, 2, 2, 0, 0, 0, 1],
    )?;
    // The figure: each reference engine's mean length minus magdem's, frame by frame (the
    // curves themselves coincide to the width of a line).
    let series: Vec<Series> = here
        .iter()
        .filter(|r| r.completed() && r.engine != "magdem")
        .filter_map(|r| {
            let native = native_of(r)?;
            let points: Vec<(f64, f64)> = r
                .times
                .iter()
                .zip(&r.mean_length)
                .zip(native.times.iter().zip(&native.mean_length))
                .filter(|((t, _), (t0, _))| (*t - *t0).abs() <= 1e-9 * t.abs().max(1e-12))
                .map(|((t, l), (_, l0))| (t * 1e3, (l - l0) * 1e6))
                .collect();
            Some(Series::line(
                format!("{} − magdem ({}, seed {})", r.engine, r.scene, r.seed),
                points,
                engine_colour(&r.engine),
            ))
        })
        .collect();
    if !series.is_empty() {
        line_chart_with_legend(
            &out.join("reference-engines.png"),
            "Case 1 with Stokes drag: each engine's mean length minus magdem's",
            "time (ms)",
            "difference of the mean length (µm)",
            &series,
            crate::plot::Legend::above_data(0.3),
        )?;
        md += "\n![Engines](reference-engines.png)\n\n";
    }
    Ok(md)
}

/// The opt-in Table 3 ensemble in all three engines, when its runs exist.
fn reference_ensemble(runs: &[Run], out: &Path, tables: &Path) -> Result<String, Error> {
    let all: Vec<&Run> = runs.iter().filter(|r| r.experiment == "paper-reference-table3").collect();
    if all.iter().all(|r| !r.completed()) {
        return Ok("The full ensemble (four concentrations × five seeds × three engines, `experiments/paper/opt-in/reference-table3.toml`, \
                   about an hour on 2 cores) is opt-in and not in this report; the default run below is one seed at 0.563 mg/ml.\n\n"
            .into());
    }
    const ENGINES: [&str; 3] = ["magdem", "liggghts", "lammps"];
    let (mut c_col, mut e_col, mut n_col, mut m_col, mut ci_col, mut s_col) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut concentrations: Vec<f64> = all.iter().map(|r| r.concentration).collect();
    concentrations.sort_by(f64::total_cmp);
    concentrations.dedup();
    // Per concentration, each reference engine's mean against magdem's: the difference and
    // whether it exceeds the CI95 of a difference of two independent means.
    let mut comparisons = vec![];
    for &c in &concentrations {
        let mut per_engine = vec![];
        for engine in ENGINES {
            let done: Vec<&&Run> =
                all.iter().filter(|r| r.completed() && r.engine == engine && same(r.concentration, c)).collect();
            let means: Vec<f64> = done.iter().map(|r| r.mean_length_um()).collect();
            let (m, ci) = (mean(&means), ci95_half_width(&means));
            c_col.push(c);
            e_col.push(engine.to_string());
            n_col.push(done.len() as u64);
            m_col.push(m);
            ci_col.push(ci);
            s_col.push(mean(&done.iter().map(|r| summary(&r.lengths_um()).population_std).collect::<Vec<_>>()));
            per_engine.push((m, ci));
        }
        let (m0, ci0) = per_engine[0];
        for (engine, &(m, ci)) in ENGINES.iter().zip(&per_engine).skip(1) {
            if m.is_finite() && m0.is_finite() {
                let within = (m - m0).abs() <= (ci * ci + ci0 * ci0).sqrt();
                // Differences below the printed precision in exponent form, not rounded to a signed zero.
                let (d, rel) = (m - m0, 100.0 * (m - m0) / m0);
                let shown = if d == 0.0 {
                    "0 µm (identical)".to_string()
                } else if d.abs() < 0.05 {
                    format!("{d:+.1e} µm ({rel:+.1e} %)")
                } else {
                    format!("{d:+.1} µm ({rel:+.1} %)")
                };
                comparisons.push(format!(
                    "{c} mg/ml {engine} {shown}, {}",
                    if within { "within the CI95" } else { "outside the CI95" }
                ));
            }
        }
    }
    // The figure: each engine's difference to magdem, paired seed by seed (µm, mean ± CI95).
    let paired_difference = |engine: &str, c: f64| {
        let of = |e: &str| {
            all.iter()
                .filter(|r| r.completed() && r.engine == e && same(r.concentration, c))
                .map(|r| (r.seed, r.mean_length_um()))
                .collect::<Vec<_>>()
        };
        let base = of("magdem");
        let d: Vec<f64> =
            of(engine).iter().filter_map(|(s, l)| base.iter().find(|b| b.0 == *s).map(|b| l - b.1)).collect();
        convergence::Estimate::of(&d)
    };
    let panel = BarPanel {
        title: "engine minus magdem, mean aggregate length at 5 ms, Stokes drag".into(),
        y_label: "µm (mean ± CI95 of the paired differences)".into(),
        categories: concentrations.iter().map(|c| format!("{c} mg/ml")).collect(),
        groups: ENGINES[1..]
            .iter()
            .map(|engine| BarGroup {
                label: engine.to_string(),
                color: engine_colour(engine),
                values: concentrations.iter().map(|&c| paired_difference(engine, c).mean).collect(),
                errors: concentrations.iter().map(|&c| paired_difference(engine, c).ci95).collect(),
            })
            .collect(),
    };
    category_panels(
        &out.join("reference-table3.png"),
        "Table 3 in LIGGGHTS and LAMMPS against magdem (same scenes, same seeds)",
        &[panel],
        1,
        (900, 480),
        Mark::Dots,
    )?;
    let mut df = frame(vec![
        col("concentration_mg_per_ml", c_col),
        scol("engine", e_col),
        ucol("runs", n_col),
        col("mean_length_um", m_col),
        col("ci95_um", ci_col),
        col("pop_std_um", s_col),
    ])?;
    write(&mut df, tables, "reference_table3")?;
    Ok(format!(
        "Table 3 in all three engines (`experiments/paper/opt-in/reference-table3.toml`, Stokes drag — so not the paper's \
         drag model; the point is whether the engines agree on one model):\n\n{}\n![Table 3 in three engines](reference-table3.png)\n\n\
         Against magdem (the difference counts as within the CI95 when it is below √(CI₁² + CI₂²) of the two means): {}.\n\n",
        markdown(&df, &["c (mg/ml)", "engine", "runs", "mean length (µm)", "± CI95", "pop std (µm)"], &[3, 0, 0, 1, 1, 1])?,
        comparisons.join("; ")
    ))
}

/// A float in scientific notation for a table cell ("–" for NaN).
fn sci(v: f64) -> String {
    if v.is_nan() {
        "–".into()
    } else {
        format!("{v:.1e}")
    }
}

/// Largest particle position difference between two trajectories of the same scene: at the
/// last frame and over all frames (m).
fn position_difference(a: &Path, b: &Path) -> Result<(f64, f64), Error> {
    let (x, y) = (
        crate::io::trajectory::Trajectory::open(a)?.all_vectors("position")?,
        crate::io::trajectory::Trajectory::open(b)?.all_vectors("position")?,
    );
    if x.shape() != y.shape() {
        return Err(format!("{} and {} hold different frames", a.display(), b.display()).into());
    }
    let per_frame: Vec<f64> = (0..x.shape()[0])
        .map(|k| {
            (0..x.shape()[1])
                .map(|i| (0..3).map(|c| (x[[k, i, c]] - y[[k, i, c]]).powi(2)).sum::<f64>().sqrt())
                .fold(0.0, f64::max)
        })
        .collect();
    Ok((*per_frame.last().unwrap_or(&f64::NAN), per_frame.iter().copied().fold(0.0, f64::max)))
}

fn runs_section(runs: &[Run], tables: &Path) -> Result<String, Error> {
    let mut df = frame(vec![
        scol("experiment", runs.iter().map(|r| r.experiment.clone()).collect()),
        scol("id", runs.iter().map(|r| r.id.clone()).collect()),
        scol("scene", runs.iter().map(|r| r.scene.clone()).collect()),
        scol("variant", runs.iter().map(|r| r.variant.clone()).collect()),
        ucol("seed", runs.iter().map(|r| r.seed).collect()),
        scol("engine", runs.iter().map(|r| r.engine.clone()).collect()),
        ucol("particles", runs.iter().map(|r| r.particles as u64).collect()),
        scol("status", runs.iter().map(|r| r.status.clone()).collect()),
        scol("source", runs.iter().map(|r| r.source.name().to_string()).collect()),
        scol("message", runs.iter().map(|r| r.message.clone()).collect()),
        col("end_time_s", runs.iter().map(|r| r.times.last().copied().unwrap_or(f64::NAN)).collect::<Vec<_>>()),
        col(
            "aggregates",
            runs.iter().map(|r| if r.completed() { r.last.len() as f64 } else { f64::NAN }).collect::<Vec<_>>(),
        ),
        col(
            "mean_length_um",
            runs.iter().map(|r| if r.completed() { r.mean_length_um() } else { f64::NAN }).collect::<Vec<_>>(),
        ),
        col(
            "pop_std_um",
            runs.iter()
                .map(|r| if r.completed() { summary(&r.lengths_um()).population_std } else { f64::NAN })
                .collect::<Vec<_>>(),
        ),
        col(
            "sample_std_um",
            runs.iter()
                .map(|r| if r.completed() { summary(&r.lengths_um()).sample_std } else { f64::NAN })
                .collect::<Vec<_>>(),
        ),
        col(
            "box_limited_fraction",
            runs.iter().map(|r| if r.completed() { r.box_limited_fraction() } else { f64::NAN }).collect::<Vec<_>>(),
        ),
        ucol("percolating", runs.iter().map(|r| r.percolating() as u64).collect()),
        col("wall_time_s", runs.iter().map(|r| r.wall_time).collect::<Vec<_>>()),
    ])?;
    write(&mut df, tables, "runs")?;
    let (mut id, mut size, mut length, mut angle, mut vx) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut extent, mut capped) = (vec![], vec![]);
    for r in runs.iter().filter(|r| r.completed()) {
        for a in &r.last {
            id.push(r.id.clone());
            size.push(a.size() as u64);
            length.push(a.length * 1e6);
            extent.push(a.field_extent * 1e6);
            capped.push(a.box_limited(r.box_extent) as u64);
            angle.push(a.orientation_deg);
            vx.push(a.com_velocity.x * 1e6);
        }
    }
    let mut aggs = frame(vec![
        scol("id", id),
        ucol("size", size),
        col("length_um", length),
        col("field_extent_um", extent),
        ucol("box_limited", capped),
        col("orientation_deg", angle),
        col("vx_um_per_s", vx),
    ])?;
    write(&mut aggs, tables, "aggregates")?;
    Ok("## All runs\n\nEvery run with its status, statistics and wall time: `tables/runs.csv` (and `.parquet`); every aggregate of every \
        run's last frame (size, length — empty for an aggregate that percolates through a periodic face —, extent along the \
        field, whether the box caps it, orientation to the field, x velocity): `tables/aggregates.csv`.\n"
        .into())
}
