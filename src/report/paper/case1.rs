//! Case 1 in the paper's box: Table 3, its seeds, Table 4, the box plots and the approach figure.

use super::convergence;
use super::{completed, mean, seed_list, table3_ensemble, Inputs, Paper};
use crate::analysis::stats::{ci95_half_width, summary};
use crate::plot::{
    box_panels, category_panels, engine_colour, line_chart_with_legend, palette, BarGroup, BarPanel, BoxPanel,
    BoxStats, Mark, RGBColor, Series, SeriesLabelPosition,
};
use crate::report::runs::Run;
use crate::report::tables::{col, floats, frame, markdown, same, ucol, write};
use crate::scene::Scene;
use minijinja::{context, Value};
use polars::prelude::PolarsResult;
use std::path::Path;

type Error = Box<dyn std::error::Error>;

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

/// The seed whose runs the gap-tolerance check re-analyses.
const GAP_SEED: u64 = 1;

/// Share of an ensemble's aggregates at the box edge from which its mark is ringed as a lower bound.
const RINGED: f64 = 0.1;

/// Magnetisation-sweep variant at bulk magnetite's saturation: the headline comparison.
pub const SATURATED: &str = "ms-4.8e5";

/// One concentration's row of Table 3.
#[derive(serde::Serialize)]
struct Table3Row {
    c: f64,
    runs: usize,
    seeds: String,
    mean: f64,
    ci95: f64,
    pop_std: f64,
    box_limited: f64,
    paper: f64,
    paper_std: f64,
    experiment: f64,
    experiment_std: f64,
    /// magdem's mean against the experiment's and the paper's (%).
    vs_experiment: f64,
    vs_paper: f64,
    /// The magnetisation sweep at bulk saturation (r-RESPA, the paper's box): mean ± CI95 (µm),
    /// seeds, and its difference to the paper's and the experiment's (%).
    saturated: convergence::Estimate,
    saturated_box_limited: f64,
    saturated_vs_paper: f64,
    saturated_vs_experiment: f64,
}

/// Table 3: the Verlet ensemble in the paper's box against the paper and the experiment, beside
/// the magnetisation sweep at bulk saturation; figures `table3.png` and `table3-spread.png`.
pub fn table3(inp: &Inputs) -> Result<Value, Error> {
    let (runs, paper, out) = (inp.runs, inp.paper, inp.out);
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let ens = ensembles(runs, &conc);
    let (paper_mean, paper_std) = (floats(&paper.table3, "sim_mean_length_um")?, floats(&paper.table3, "sim_std_um")?);
    let (exp_mean, exp_std) = (floats(&paper.table3, "exp_mean_length_um")?, floats(&paper.table3, "exp_std_um")?);
    let sweep = |c: f64| convergence::select(runs, &["paper-magnetisation"], SATURATED, c);
    let saturated: Vec<convergence::Estimate> = conc
        .iter()
        .map(|&c| convergence::Estimate::of(&sweep(c).iter().map(|r| r.mean_length_um()).collect::<Vec<_>>()))
        .collect();
    let saturated_box_limited: Vec<f64> =
        conc.iter().map(|&c| mean(&sweep(c).iter().map(|r| r.box_limited_fraction()).collect::<Vec<_>>())).collect();
    let rows: Vec<Table3Row> = ens
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let m = mean(&e.runs);
            Table3Row {
                c: e.concentration,
                runs: e.runs.len(),
                seeds: seed_list(&e.seeds),
                mean: m,
                ci95: ci95_half_width(&e.runs),
                pop_std: mean(&e.pop_std),
                box_limited: e.box_limited,
                paper: paper_mean[k],
                paper_std: paper_std[k],
                experiment: exp_mean[k],
                experiment_std: exp_std[k],
                vs_experiment: 100.0 * (m / exp_mean[k] - 1.0),
                vs_paper: 100.0 * (m / paper_mean[k] - 1.0),
                saturated: saturated[k],
                saturated_box_limited: saturated_box_limited[k],
                saturated_vs_paper: 100.0 * (saturated[k].mean / paper_mean[k] - 1.0),
                saturated_vs_experiment: 100.0 * (saturated[k].mean / exp_mean[k] - 1.0),
            }
        })
        .collect();
    let mut df = frame(vec![
        col("concentration_mg_per_ml", conc.clone()),
        ucol("runs", ens.iter().map(|e| e.runs.len() as u64).collect()),
        col("particles", ens.iter().map(|e| e.particles).collect::<Vec<_>>()),
        col("paper_particles", floats(&paper.table3, "particles")?),
        col("aggregates_per_run", ens.iter().map(|e| e.aggregates).collect::<Vec<_>>()),
        col("magdem_mean_length_um", rows.iter().map(|r| r.mean).collect::<Vec<_>>()),
        col("magdem_ci95_um", rows.iter().map(|r| r.ci95).collect::<Vec<_>>()),
        col("magdem_pop_std_um", rows.iter().map(|r| r.pop_std).collect::<Vec<_>>()),
        col("box_limited_fraction", ens.iter().map(|e| e.box_limited).collect::<Vec<_>>()),
        col("paper_sim_mean_um", paper_mean.clone()),
        col("paper_sim_std_um", paper_std.clone()),
        col("experiment_mean_um", exp_mean.clone()),
        col("experiment_std_um", exp_std.clone()),
        col("saturated_mean_length_um", saturated.iter().map(|e| e.mean).collect::<Vec<_>>()),
        col("saturated_ci95_um", saturated.iter().map(|e| e.ci95).collect::<Vec<_>>()),
        ucol("saturated_seeds", saturated.iter().map(|e| e.n as u64).collect()),
        col("saturated_box_limited_fraction", saturated_box_limited.clone()),
    ])?;
    write(&mut df, &inp.tables, "table3")?;
    let table = markdown(
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
            "saturated M, mean (µm)",
            "± CI95",
            "seeds",
            "box-limited",
        ],
        &[3, 0, 0, 0, 1, 1, 1, 1, 3, 1, 1, 0, 0, 1, 1, 0, 3],
    )?;
    table3_figures(&rows, &conc, out)?;
    let stopped: Vec<String> = runs
        .iter()
        .filter(|r| convergence::TABLE3.contains(&r.experiment.as_str()) && !r.completed() && r.status != "missing")
        .map(|r| format!("{} ({}: {})", r.id, r.status, r.message))
        .collect();
    let (gap_table, gap_above, gap_below) = gap_sensitivity(runs)?;
    let within = |f: &dyn Fn(&Table3Row) -> f64| rows.iter().map(|r| f(r).abs()).fold(0.0, f64::max);
    Ok(context! {
        table => table,
        seeds => ens.iter().max_by_key(|e| e.seeds.len()).map_or(String::new(), |e| seed_list(&e.seeds)),
        runs => rows.iter().map(|r| r.runs).min().unwrap_or(0),
        saturated_seeds => saturated.iter().map(|e| e.n).min().unwrap_or(0),
        ringed_percent => 100.0 * RINGED,
        box_limited_percent => 100.0 * crate::analysis::aggregates::BOX_LIMITED_FRACTION,
        saturated_within_paper => within(&|r| r.saturated_vs_paper),
        saturated_within_experiment_lower => rows[..rows.len().saturating_sub(1)].iter().map(|r| r.saturated_vs_experiment.abs()).fold(0.0, f64::max),
        saturated_vs_experiment_last => rows.last().map(|r| r.saturated_vs_experiment),
        linear_vs_paper_min => rows.iter().map(|r| r.vs_paper).fold(f64::INFINITY, f64::min),
        linear_vs_paper_max => rows.iter().map(|r| r.vs_paper).fold(f64::NEG_INFINITY, f64::max),
        rows => rows,
        stopped => stopped,
        gap => context! { table => gap_table, above => gap_above, below => gap_below, used => inp.options.gap, seed => GAP_SEED },
    })
}

/// Table 3's figures: the means (magdem with its CI95 over seeds, at the paper's linear law and at
/// bulk saturation; box-limited points marked; the paper's and the experiment's means carry no
/// CI) and, apart, the intrinsic spread of the lengths.
fn table3_figures(rows: &[Table3Row], conc: &[f64], out: &Path) -> Result<(), Error> {
    let offset = |k: f64| conc.iter().map(move |&c| c * (1.0 + k)).collect::<Vec<f64>>();
    let pts = |x: Vec<f64>, y: Vec<f64>| x.into_iter().zip(y).collect::<Vec<_>>();
    // A point whose ensemble has at least a tenth of its aggregates at the box edge is a lower bound.
    let capped: Vec<(f64, f64)> = rows
        .iter()
        .flat_map(|r| [(r.box_limited, r.c, r.mean), (r.saturated_box_limited, r.c * 1.03, r.saturated.mean)])
        .filter(|&(share, _, _)| share >= RINGED)
        .map(|(_, c, l)| (c, l))
        .collect();
    let series = vec![
        Series::markers(
            "magdem, the paper's linear M (mean ± CI95 over seeds)",
            pts(offset(0.0), rows.iter().map(|r| r.mean).collect()),
            engine_colour("magdem"),
            6,
        )
        .with_errors(rows.iter().map(|r| r.ci95).collect()),
        Series::markers(
            format!("ringed: ≥ {:.0} % of the aggregates box-limited", 100.0 * RINGED),
            capped,
            RGBColor(120, 60, 180),
            10,
        ),
        Series::markers(
            "magdem, M at bulk saturation (mean ± CI95 over seeds)",
            pts(offset(0.03), rows.iter().map(|r| r.saturated.mean).collect()),
            palette(2),
            6,
        )
        .with_errors(rows.iter().map(|r| r.saturated.ci95).collect()),
        Series::markers(
            "paper simulation (mean of one run)",
            pts(offset(0.06), rows.iter().map(|r| r.paper).collect()),
            palette(3),
            6,
        ),
        Series::markers(
            "experiment, Mathieu & Martel (mean)",
            pts(offset(-0.03), rows.iter().map(|r| r.experiment).collect()),
            RGBColor(0, 0, 0),
            6,
        ),
    ];
    crate::plot::chart(
        &out.join("table3.png"),
        "Case 1: mean aggregate length at the end of the run",
        ("concentration (mg/ml)", "mean length (µm)"),
        &series,
        SeriesLabelPosition::UpperLeft,
        (crate::plot::Scale::Log, crate::plot::Scale::Log),
    )?;
    let spread = vec![
        Series::markers(
            "magdem (mean over seeds of each run's population std)",
            pts(offset(0.0), rows.iter().map(|r| r.pop_std).collect()),
            engine_colour("magdem"),
            6,
        ),
        Series::markers(
            "paper simulation (std)",
            pts(offset(0.04), rows.iter().map(|r| r.paper_std).collect()),
            palette(3),
            6,
        ),
        Series::markers(
            "experiment (std)",
            pts(offset(-0.04), rows.iter().map(|r| r.experiment_std).collect()),
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
fn gap_sensitivity(runs: &[Run]) -> Result<(String, f64, f64), Error> {
    let gaps = [1e-4, 1e-3, 1e-2, 5e-2];
    let mut md = format!(
        "| run | {} |\n|---|{}\n",
        gaps.iter().map(|g| format!("{g:e}")).collect::<Vec<_>>().join(" | "),
        "---|".repeat(gaps.len())
    );
    let respa = runs
        .iter()
        .filter(|r| r.experiment == "paper-sensitivity" && r.variant == "respa" && r.seed == GAP_SEED && r.completed())
        .filter(|r| r.has_trajectory());
    // Largest relative change of each run's mean from 1e-3 to 5e-2, and below 1e-3.
    let (mut above, mut below) = (0.0_f64, 0.0_f64);
    for r in table3_ensemble(runs).into_iter().filter(|r| r.seed == GAP_SEED && r.has_trajectory()).chain(respa) {
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
    Ok((md, 100.0 * above, 100.0 * below))
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

/// Table 4: magdem's aggregate-size histograms (means over the Table 3 seeds) against the paper's
/// one run, as `tables/table4.csv`, a summary table and the figure `table4.png`.
pub fn table4(inp: &Inputs) -> Result<Value, Error> {
    let (runs, paper, out, tables) = (inp.runs, inp.paper, inp.out, inp.tables.as_path());
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let paper_sizes: Vec<usize> =
        floats(&paper.table4, "particles_per_aggregate")?.iter().map(|&s| s as usize).collect();
    let table3 = table3_ensemble(runs);
    if table3.is_empty() {
        return Ok(context! { run => false });
    }
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
    let end_ms = table3.iter().filter_map(|r| r.times.last()).fold(f64::NAN, |a, &t| a.max(t)) * 1e3;
    category_panels(
        &out.join("table4.png"),
        &format!("Case 1: aggregate size distributions at {end_ms:.0} ms (x: particles per aggregate)"),
        &panels,
        2,
        (760, 420),
        Mark::Bars,
    )?;
    let seeds = conc.iter().map(|&c| table3.iter().filter(|r| same(r.concentration, c)).count()).collect::<Vec<_>>();
    Ok(context! {
        run => true,
        table => table4_summary(&summary_rows, tables)?,
        end_ms => end_ms,
        seeds_min => seeds.iter().copied().min().unwrap_or(0),
        seeds_max => seeds.iter().copied().max().unwrap_or(0),
    })
}

/// Per concentration: (c, paper aggregates, magdem aggregates per run, paper singles, magdem
/// singles per run, paper largest, magdem largest mean over runs).
type SizeSummary = (f64, f64, f64, f64, f64, f64, f64);

/// Table 4's summary, written to `tables/table4_summary.*`; returns it as Markdown.
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
    Ok(markdown(
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
    )?)
}

/// Lengths (µm) of the paper's simulated aggregates from its Table 4 histogram: n particles of
/// diameter `diameter_um` in a line.
fn paper_lengths(paper: &Paper, c: f64, diameter_um: f64) -> PolarsResult<Vec<f64>> {
    let sizes = floats(&paper.table4, "particles_per_aggregate")?;
    let counts = floats(&paper.table4, &format!("count_c{c}"))?;
    Ok(sizes.iter().zip(&counts).flat_map(|(&s, &n)| std::iter::repeat_n(s * diameter_um, n as usize)).collect())
}

/// The particle diameter of a run's first species (m), from its stored scene.
fn diameter(run: &Run) -> Result<f64, Error> {
    let (spec, _) = Scene::layout(&run.scene_text, &run.id)?;
    Ok(spec.species.first().ok_or("a scene without species")?.diameter)
}

/// The paper's box-plot figure (`boxplots.png`): magdem's lengths of all Table 3 seeds and the
/// paper's rebuilt from its Table 4, beside the experiment's mean ± std.
pub fn boxplots(inp: &Inputs) -> Result<Value, Error> {
    let (runs, paper, out) = (inp.runs, inp.paper, inp.out);
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let (exp_mean, exp_std) = (floats(&paper.table3, "exp_mean_length_um")?, floats(&paper.table3, "exp_std_um")?);
    let table3 = table3_ensemble(runs);
    let Some(first) = table3.first() else {
        return Ok(context! { run => false });
    };
    let diameter_um = diameter(first)? * 1e6;
    let end_ms = table3.iter().filter_map(|r| r.times.last()).fold(f64::NAN, |a, &t| a.max(t)) * 1e3;
    let mut panels = vec![];
    for (k, &c) in conc.iter().enumerate() {
        let here: Vec<&&Run> = table3.iter().filter(|r| same(r.concentration, c)).collect();
        let magdem: Vec<f64> = here.iter().flat_map(|r| r.lengths_um()).collect();
        let capped = here.iter().map(|r| r.last.iter().filter(|a| a.box_limited(r.box_extent)).count()).sum::<usize>();
        let boxes = [
            BoxStats::of("magdem (all seeds)", engine_colour("magdem"), &magdem),
            BoxStats::of("paper simulation", palette(3), &paper_lengths(paper, c, diameter_um)?),
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
        &format!("Case 1 at {end_ms:.0} ms: quartiles, median (red), Tukey fences, mean (blue), box edge (dashed)"),
        &panels,
        2,
    )?;
    Ok(context! { run => true, diameter_um => diameter_um, end_ms => end_ms })
}

/// The paper's approach-velocity figure from `experiments/paper/approach.toml`: the speed of one
/// of two particles against time (`approach.png`) and against their centre distance
/// (`approach-distance.png`), both up to contact.
pub fn approach(inp: &Inputs) -> Result<Value, Error> {
    let Some(run) = completed(inp.runs, "paper-approach").into_iter().find(|r| r.has_trajectory()) else {
        return Ok(context! { run => false });
    };
    let out = inp.out;
    let scene = Scene::parse(&run.scene_text, &run.id)?;
    let t = crate::io::trajectory::Trajectory::open(&run.file)?;
    let x = t.all_vectors("position")?;
    let v = t.all_vectors("velocity")?;
    let times = t.times()?;
    let radius = t.file.dataset("particles/radius")?.read_raw::<f64>()?;
    let d = 2.0 * radius[0];
    let distance = |k: usize| (0..3).map(|c| (x[[k, 1, c]] - x[[k, 0, c]]).powi(2)).sum::<f64>().sqrt();
    let speed = |k: usize| (0..3).map(|c| v[[k, 1, c]].powi(2)).sum::<f64>().sqrt();
    // Up to contact: the frames before the first whose centre distance is at most one diameter.
    let contact = (0..times.len()).find(|&k| distance(k) <= d);
    let before = contact.unwrap_or(times.len());
    let (mut against_time, mut against_distance) = (vec![], vec![]);
    for (k, &time) in times.iter().enumerate().take(before) {
        let s = speed(k);
        if s > 0.0 {
            against_time.push((time * 1e3, (s * 1e3).log10()));
            against_distance.push((distance(k) / d, (s * 1e3).log10()));
        }
    }
    // The fastest frame before contact: (time in ms, speed in mm/s).
    let peak = against_time.iter().copied().fold((f64::NAN, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
    let b0 = scene.spec.field.as_ref().map_or(0.0, |f| (f.b0[0].powi(2) + f.b0[1].powi(2) + f.b0[2].powi(2)).sqrt());
    let species = &scene.species[0];
    let start = distance(0) / d;
    line_chart_with_legend(
        &out.join("approach.png"),
        &format!("Two {:.0} µm particles from {start:.0} diameters at {b0} T, up to contact", d * 1e6),
        "time (ms)",
        "log10 speed of one particle (mm/s)",
        &[Series::line("magdem", against_time, engine_colour("magdem"))],
        SeriesLabelPosition::UpperLeft,
    )?;
    line_chart_with_legend(
        &out.join("approach-distance.png"),
        "Approach speed against centre distance, up to contact",
        "centre distance (diameters)",
        "log10 speed of one particle (mm/s)",
        &[Series::line("magdem", against_distance, engine_colour("magdem"))],
        SeriesLabelPosition::UpperRight,
    )?;
    // The linear law's magnetisation in the applied field alone, against bulk magnetite's saturation.
    let linear = species.susceptibility * b0 / crate::core::forces::magnetisation::MU0;
    let frame_us = times.get(1).map_or(f64::NAN, |t1| (t1 - times[0]) * 1e6);
    // The force models as the scene names them (`forces.dipole.induction`, `forces.drag.*`).
    let table: toml::Table = toml::from_str(&run.scene_text)?;
    let setting = |path: &[&str]| {
        let mut v = table.get(path[0]);
        for key in &path[1..] {
            v = v.and_then(|x| x.get(key));
        }
        v.and_then(|x| x.as_str()).unwrap_or("default").to_string()
    };
    Ok(context! {
        run => true,
        id => run.id.clone(),
        scene => run.scene.clone(),
        species => species.name.clone(),
        induction => setting(&["forces", "dipole", "induction"]),
        drag => setting(&["forces", "drag", "law"]),
        shielding => setting(&["forces", "drag", "shielding"]),
        diameter_um => d * 1e6,
        start_diameters => start,
        field_t => b0,
        relative_permeability => scene.spec.species[0].relative_permeability,
        susceptibility => species.susceptibility,
        contact_ms => contact.map(|k| times[k] * 1e3),
        last_before_contact_ms => before.checked_sub(1).map(|k| times[k] * 1e3),
        peak_ms => peak.0,
        peak_mm_s => if peak.1.is_finite() { 10f64.powf(peak.1) } else { f64::NAN },
        frame_us => frame_us,
        linear_magnetisation => linear,
        bulk_saturation => BULK_SATURATION,
        over_saturation => linear / BULK_SATURATION,
    })
}

/// Bulk magnetite's saturation magnetisation (A/m), the magnetisation sweep's upper variant.
const BULK_SATURATION: f64 = 4.8e5;
