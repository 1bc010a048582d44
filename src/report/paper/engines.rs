//! LIGGGHTS and LAMMPS on the same case-1 scenes, and the list of every run.

use super::convergence;
use super::{mean, Inputs};
use crate::analysis::stats::{ci95_half_width, summary};
use crate::plot::{category_panels, engine_colour, line_chart_with_legend, BarGroup, BarPanel, Mark, Series};
use crate::report::runs::Run;
use crate::report::tables::{col, frame, markdown, same, scol, ucol, write};
use crate::scene::Scene;
use minijinja::{context, Value};
use std::path::Path;

type Error = Box<dyn std::error::Error>;

/// The reference engines: `experiments/paper/reference.toml` (one seed of one case-1 scene in
/// magdem, LIGGGHTS and LAMMPS, Stokes drag) with its table and the figure
/// `reference-engines.png`, and the opt-in Table 3 ensemble in all three engines
/// (`reference-table3.png`) when its runs exist.
pub fn engines(inp: &Inputs) -> Result<Value, Error> {
    Ok(context! {
        reference => reference(inp.runs, inp.out, &inp.tables)?,
        ensemble => reference_ensemble(inp.runs, inp.out, &inp.tables)?,
    })
}

fn reference(runs: &[Run], out: &Path, tables: &Path) -> Result<Value, Error> {
    let here: Vec<&Run> = runs.iter().filter(|r| r.experiment == "paper-reference").collect();
    let Some(first) = here.first() else {
        return Ok(context! { run => false });
    };
    // The integration every engine ran, from the stored scene.
    let (spec, _) = Scene::layout(&first.scene_text, &first.id)?;
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
        col("aggregates", of_completed(here.iter().copied(), |r| r.last.len() as f64)),
        col("mean_length_um", of_completed(here.iter().copied(), Run::mean_length_um)),
        col("pop_std_um", of_completed(here.iter().copied(), |r| summary(&r.lengths_um()).population_std)),
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
    let table = markdown(
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
    }
    let mut seeds: Vec<u64> = here.iter().map(|r| r.seed).collect();
    seeds.sort();
    seeds.dedup();
    let mut scenes: Vec<String> = here.iter().map(|r| r.scene.clone()).collect();
    scenes.sort();
    scenes.dedup();
    Ok(context! {
        run => true,
        table => table,
        figure => !series.is_empty(),
        scenes => scenes,
        seeds => super::seed_list(&seeds),
        scheme => spec.integration.scheme.name(),
        dt => spec.integration.dt,
        end_time_ms => spec.integration.end_time * 1e3,
        missing => here.iter().filter(|r| r.status == "missing").map(|r| r.engine.clone()).collect::<Vec<_>>(),
    })
}

/// One reference engine's mean length against magdem's at one concentration (µm, %), and whether
/// the difference is within the CI95 of a difference of two independent means.
#[derive(serde::Serialize)]
struct Comparison {
    c: f64,
    engine: &'static str,
    difference: f64,
    relative: f64,
    within: bool,
}

/// The opt-in Table 3 ensemble in all three engines, when its runs exist.
fn reference_ensemble(runs: &[Run], out: &Path, tables: &Path) -> Result<Value, Error> {
    let all: Vec<&Run> = runs.iter().filter(|r| r.experiment == "paper-reference-table3").collect();
    if all.iter().all(|r| !r.completed()) {
        return Ok(context! { run => false });
    }
    const ENGINES: [&str; 3] = ["magdem", "liggghts", "lammps"];
    let (mut c_col, mut e_col, mut n_col, mut m_col, mut ci_col, mut s_col) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut concentrations: Vec<f64> = all.iter().map(|r| r.concentration).collect();
    concentrations.sort_by(f64::total_cmp);
    concentrations.dedup();
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
        for (&engine, &(m, ci)) in ENGINES.iter().zip(&per_engine).skip(1) {
            if m.is_finite() && m0.is_finite() {
                comparisons.push(Comparison {
                    c,
                    engine,
                    difference: m - m0,
                    relative: 100.0 * (m - m0) / m0,
                    within: (m - m0).abs() <= (ci * ci + ci0 * ci0).sqrt(),
                });
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
        title: "engine minus magdem, mean aggregate length at the end, Stokes drag".into(),
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
    Ok(context! {
        run => true,
        table => markdown(&df, &["c (mg/ml)", "engine", "runs", "mean length (µm)", "± CI95", "pop std (µm)"], &[3, 0, 0, 1, 1, 1])?,
        comparisons => comparisons,
    })
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

/// Every run with its status and statistics (`tables/runs.csv`) and every aggregate of every
/// completed run's last frame (`tables/aggregates.csv`).
pub fn runs(inp: &Inputs) -> Result<Value, Error> {
    let (runs, tables) = (inp.runs, inp.tables.as_path());
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
        col("aggregates", of_completed(runs, |r| r.last.len() as f64)),
        col("mean_length_um", of_completed(runs, Run::mean_length_um)),
        col("pop_std_um", of_completed(runs, |r| summary(&r.lengths_um()).population_std)),
        col("sample_std_um", of_completed(runs, |r| summary(&r.lengths_um()).sample_std)),
        col("box_limited_fraction", of_completed(runs, Run::box_limited_fraction)),
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
    Ok(context! {
        runs => runs.len(),
        completed => runs.iter().filter(|r| r.completed()).count(),
        aggregates => aggs.height(),
    })
}

/// What the report was made from: the build, the experiment files, how many runs ended how, the
/// core-seconds they took and, when given, the wall time of the `make reproduce` call.
pub fn provenance(inp: &Inputs) -> Result<Value, Error> {
    use crate::io::trajectory::status::UNREADABLE;
    let runs = inp.runs;
    let count = |f: &dyn Fn(&Run) -> bool| runs.iter().filter(|r| f(r)).count();
    let unreadable: Vec<String> = runs
        .iter()
        .filter(|r| r.status == UNREADABLE)
        .map(|r| format!("`{}` ({})", r.file.display(), r.message))
        .collect();
    Ok(context! {
        version => env!("CARGO_PKG_VERSION"),
        commit => env!("MAGDEM_GIT_COMMIT"),
        files => inp.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
        completed => count(&|r| r.completed()),
        unstable => count(&|r| r.status == "unstable"),
        missing => count(&|r| r.status == "missing"),
        unfinished => count(&|r| !r.completed() && !matches!(r.status.as_str(), "unstable" | "missing") && r.status != UNREADABLE),
        unreadable => unreadable,
        core_seconds => runs.iter().filter(|r| r.wall_time.is_finite()).map(|r| r.wall_time).sum::<f64>(),
        wall_time_s => inp.options.wall_time,
        read_here => count(&|r| r.source == crate::report::runs::Source::Trajectory),
        from_digests => count(&|r| r.source == crate::report::runs::Source::Digest),
        gap => inp.options.gap,
    })
}

/// `value` of each completed run, NaN for the others: a column of a run table.
fn of_completed<'a>(runs: impl IntoIterator<Item = &'a Run>, value: impl Fn(&Run) -> f64) -> Vec<f64> {
    runs.into_iter().map(|r| if r.completed() { value(r) } else { f64::NAN }).collect()
}
