//! Case 2 (Table 2): aggregates driven by a gradient. Table 2 comes from the twenty-seed ensemble
//! of the hydrodynamics study (`hydro-case2`, variant `a-eff`: the paper's model), beside the
//! drag models' size dependence and a calibration of M that does not use the measured velocity.

use super::{completed, mean, seed_list, strings, Inputs};
use crate::analysis::stats::summary;
use crate::core::forces::magnetisation::MU0;
use crate::plot::{
    category_panels, engine_colour, palette, BarGroup, BarPanel, Mark, RGBColor, Series, SeriesLabelPosition,
};
use crate::report::estimate::Estimate;
use crate::report::estimate::{log_slope, sizes_and_velocities};
use crate::report::runs::Run;
use crate::report::tables::{col, floats, frame, markdown, scol, write};
use crate::scene::Scene;
use minijinja::{context, Value};
use std::collections::BTreeMap;
use std::path::Path;

type Error = Box<dyn std::error::Error>;

/// The twenty-seed case-2 ensemble and its variant with the paper's model.
const ENSEMBLE: (&str, &str) = ("hydro-case2", "a-eff");
/// The drag models of the hydrodynamics study, as named there and here.
const DRAG_MODELS: [(&str, &str); 3] =
    [("a-eff", "the paper's A_eff"), ("no-shielding", "every sphere its own drag"), ("rpy", "RPY (Stokes flow)")];
/// Case 2 with the paper's stated permeability instead of a velocity-matched M.
const PERMEABILITY: (&str, &str) = ("paper-case2-permeability", "permeability");
/// Sizes with fewer aggregates than this (pooled over seeds) are left out of the size figure.
const MIN_AGGREGATES: usize = 5;

/// Per run: mean aggregate size (particles) and mean tracked x velocity of the free aggregates
/// (µm/s), over aggregates of `min_size` or more.
fn run_means(r: &Run, min_size: usize) -> (f64, f64) {
    let sizes: Vec<f64> = r.last.iter().map(|a| a.size()).filter(|&n| n >= min_size).map(|n| n as f64).collect();
    (mean(&sizes), mean(&r.free_velocities_um_per_s(min_size)))
}

/// One ensemble's Table 2 numbers: size and velocity, mean ± CI95 over seeds, and the mean over
/// seeds of each run's population std over its aggregates.
#[derive(serde::Serialize, Clone, Copy)]
struct Row {
    size: Estimate,
    size_std: f64,
    velocity: Estimate,
    velocity_std: f64,
}

fn row(here: &[&Run], min_size: usize) -> Row {
    let means: Vec<(f64, f64)> = here.iter().map(|r| run_means(r, min_size)).collect();
    let std_of =
        |f: &dyn Fn(&Run) -> Vec<f64>| mean(&here.iter().map(|r| summary(&f(r)).population_std).collect::<Vec<_>>());
    Row {
        size: Estimate::of(&means.iter().map(|m| m.0).collect::<Vec<_>>()),
        size_std: std_of(&|r| r.last.iter().map(|a| a.size()).filter(|&n| n >= min_size).map(|n| n as f64).collect()),
        velocity: Estimate::of(&means.iter().map(|m| m.1).collect::<Vec<_>>()),
        velocity_std: std_of(&|r| r.free_velocities_um_per_s(min_size)),
    }
}

fn pick<'a>(runs: &'a [Run], (experiment, variant): (&str, &str)) -> Vec<&'a Run> {
    let mut v: Vec<&Run> =
        runs.iter().filter(|r| r.experiment == experiment && r.variant == variant && r.completed()).collect();
    v.sort_by_key(|r| r.seed);
    v
}

/// A drag model's velocity against size: per size, the mean ± CI95 over the aggregates of that
/// size pooled over seeds, their count, and the exponent α of v ∝ n^α.
#[derive(serde::Serialize)]
struct SizeCurve {
    model: &'static str,
    seeds: usize,
    alpha: f64,
    sizes: Vec<(usize, Estimate)>,
}

fn size_curve(here: &[&Run], model: &'static str) -> SizeCurve {
    let mut by_size: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
    for r in here {
        for (n, v) in sizes_and_velocities(r).1 {
            by_size.entry(n).or_default().push(v);
        }
    }
    SizeCurve {
        model,
        seeds: here.len(),
        alpha: log_slope(&by_size),
        sizes: by_size.iter().filter(|(_, v)| v.len() >= MIN_AGGREGATES).map(|(&n, v)| (n, Estimate::of(v))).collect(),
    }
}

/// The lone-sphere velocity the scene's magnetisation gives under Stokes drag (µm/s):
/// U = M V G / (3π μ d), M = χ_eff B0/μ0 (the species' χ_eff, Clausius–Mossotti).
fn single_velocity(scene: &Scene) -> (f64, f64) {
    let s = &scene.species[0];
    let field = scene.spec.field.as_ref();
    let b0 = field.map_or(0.0, |f| nalgebra::Vector3::from(f.b0).norm());
    let g = field.map_or(0.0, |f| f.linear_gradient()[(0, 0)]);
    let mu = scene.spec.fluid.as_ref().map_or(f64::NAN, |f| f.viscosity);
    let m = s.susceptibility * b0 / MU0;
    let volume = 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3);
    (m, 1e6 * m * volume * g / (6.0 * std::f64::consts::PI * mu * s.radius))
}

pub fn case2(inp: &Inputs) -> Result<Value, Error> {
    let ensemble = pick(inp.hydro, ENSEMBLE);
    let verlet = completed(inp.runs, "paper-case2");
    let permeability = pick(inp.runs, PERMEABILITY);
    if ensemble.is_empty() && verlet.is_empty() {
        return Ok(context! { present => false });
    }
    let base = ensemble.first().or(verlet.first()).copied().expect("one of the two is not empty");
    let scene = Scene::parse(&base.scene_text, &base.id)?;
    let integration = &scene.spec.integration;
    let (m_scene, u_scene) = single_velocity(&scene);
    let (m_perm, u_perm, dt_perm) = match permeability.first() {
        Some(r) => {
            let scene = Scene::parse(&r.scene_text, &r.id)?;
            let (m, u) = single_velocity(&scene);
            (m, u, scene.spec.integration.dt)
        }
        None => (f64::NAN, f64::NAN, f64::NAN),
    };
    let experiment = context! {
        size => floats(&inp.paper.table2, "mean_size_particles")?[0],
        size_std => floats(&inp.paper.table2, "std_size_particles")?[0],
        velocity => floats(&inp.paper.table2, "mean_velocity_um_per_s")?[0],
        velocity_std => floats(&inp.paper.table2, "std_velocity_um_per_s")?[0],
    };

    // Table 2: magdem's ensembles, then the paper's rows.
    let mut rows: Vec<(String, Row)> = vec![];
    if !ensemble.is_empty() {
        rows.push((format!("magdem, paper's model, all aggregates ({} seeds)", ensemble.len()), row(&ensemble, 1)));
        rows.push((format!("magdem, paper's model, aggregates of 2+ ({} seeds)", ensemble.len()), row(&ensemble, 2)));
    }
    if !permeability.is_empty() {
        rows.push((
            format!("magdem, μr of the paper's case 1, all aggregates ({} seeds)", permeability.len()),
            row(&permeability, 1),
        ));
    }
    if !verlet.is_empty() {
        rows.push((
            format!("magdem, paper's model, velocity Verlet, all aggregates ({} seeds)", verlet.len()),
            row(&verlet, 1),
        ));
    }
    let n_magdem = rows.len();
    let sources = strings(&inp.paper.table2, "source")?;
    let published = |key: &str| floats(&inp.paper.table2, key);
    let (ps, pss, pv, pvs) = (
        published("mean_size_particles")?,
        published("std_size_particles")?,
        published("mean_velocity_um_per_s")?,
        published("std_velocity_um_per_s")?,
    );
    let mut df = frame(vec![
        scol("source", rows.iter().map(|r| r.0.clone()).chain(sources.iter().cloned()).collect()),
        col("mean_size_particles", rows.iter().map(|r| r.1.size.mean).chain(ps.iter().copied()).collect::<Vec<_>>()),
        col("std_size_particles", rows.iter().map(|r| r.1.size_std).chain(pss.iter().copied()).collect::<Vec<_>>()),
        col("ci95_size", rows.iter().map(|r| r.1.size.ci95).chain(ps.iter().map(|_| f64::NAN)).collect::<Vec<_>>()),
        col(
            "mean_velocity_um_per_s",
            rows.iter().map(|r| r.1.velocity.mean).chain(pv.iter().copied()).collect::<Vec<_>>(),
        ),
        col(
            "std_velocity_um_per_s",
            rows.iter().map(|r| r.1.velocity_std).chain(pvs.iter().copied()).collect::<Vec<_>>(),
        ),
        col(
            "ci95_velocity",
            rows.iter().map(|r| r.1.velocity.ci95).chain(pv.iter().map(|_| f64::NAN)).collect::<Vec<_>>(),
        ),
    ])?;
    write(&mut df, &inp.tables, "table2")?;
    let table = markdown(
        &df,
        &["source", "mean size", "std", "± CI95", "mean velocity (µm/s)", "std", "± CI95"],
        &[0, 2, 2, 2, 2, 2, 2],
    )?;
    table2_figure(&rows[..n_magdem], &sources, &ps, &pv, inp.out)?;

    // Velocity against size under each drag model (the hydrodynamics study's runs).
    let curves: Vec<SizeCurve> = DRAG_MODELS
        .iter()
        .map(|&(variant, model)| size_curve(&pick(inp.hydro, (ENSEMBLE.0, variant)), model))
        .filter(|c| c.seeds > 0)
        .collect();
    velocity_by_size_figure(&curves, pv[0], inp.out)?;
    // The paper's figure from the first run with a trajectory.
    let pictured = ensemble.iter().chain(&verlet).find(|r| r.has_trajectory());
    let (positions, box_um) = match pictured {
        Some(r) => super::drawing::case2_positions(r, inp.out)?,
        None => (vec![], f64::NAN),
    };
    let walled = ensemble.iter().map(|r| r.last.iter().filter(|a| a.at_x_wall).count()).sum::<usize>();
    let total = ensemble.iter().map(|r| r.last.len()).sum::<usize>();
    let velocity_of = |k: usize| rows.get(k).map(|r| r.1.velocity);
    Ok(context! {
        present => true,
        table => table,
        seeds => seed_list(&ensemble.iter().map(|r| r.seed).collect::<Vec<_>>()),
        ensemble_seeds => ensemble.len(),
        verlet_seeds => verlet.len(),
        permeability_seeds => permeability.len(),
        all => rows.first().map(|r| r.1),
        two_plus => rows.get(1).map(|r| r.1),
        permeability => (!permeability.is_empty()).then(|| row(&permeability, 1)),
        experiment => experiment,
        paper_velocity => pv.get(1).copied(),
        paper_size => ps.get(1).copied(),
        end_time => base.times.last().copied(),
        dt => integration.dt,
        slow_every => integration.slow_every(),
        b0 => scene.spec.field.as_ref().map(|f| nalgebra::Vector3::from(f.b0).norm()),
        gradient => scene.spec.field.as_ref().map(|f| f.linear_gradient()[(0, 0)]),
        diameter_um => 2e6 * scene.species[0].radius,
        susceptibility => scene.species[0].susceptibility,
        m_scene => m_scene,
        u_scene => u_scene,
        m_permeability => m_perm,
        u_permeability => u_perm,
        permeability_dt => dt_perm,
        curves => curves,
        min_aggregates => MIN_AGGREGATES,
        walled => walled,
        total => total,
        velocity_ratio => velocity_of(0).map(|v| v.mean / pv[0]),
        positions => context! {
            times => positions,
            box_um => box_um,
            id => pictured.map(|r| r.id.clone()),
            experiment => pictured.map(|r| r.experiment.clone()),
        },
    })
}

/// Table 2 as a figure: magdem's means ± CI95 over seeds beside the published means (their
/// published stds are spreads over aggregates, not uncertainties of the mean, and are in the table).
fn table2_figure(rows: &[(String, Row)], sources: &[String], ps: &[f64], pv: &[f64], out: &Path) -> Result<(), Error> {
    let short = |s: &str| -> String {
        if s.contains("2+") {
            "magdem 2+".into()
        } else if s.contains("μr") {
            "magdem μr".into()
        } else if s.contains("Verlet") {
            "magdem Verlet".into()
        } else if s.starts_with("magdem") {
            "magdem".into()
        } else if s.starts_with("experiment") {
            "experiment".into()
        } else if s.contains("this paper") {
            "paper sim".into()
        } else {
            "V&M sim".into()
        }
    };
    let cats: Vec<String> = rows.iter().map(|r| short(&r.0)).chain(sources.iter().map(|s| short(s))).collect();
    let nan = |n: usize| vec![f64::NAN; n];
    let panel = |title: &str, y: &str, values: Vec<f64>, errors: Vec<f64>| BarPanel {
        title: title.into(),
        y_label: y.into(),
        categories: cats.clone(),
        groups: vec![BarGroup {
            label: "magdem: ± CI95 over seeds; published: mean only".into(),
            color: palette(1),
            values,
            errors,
        }],
    };
    let panels = vec![
        panel(
            "aggregate size",
            "mean particles per aggregate",
            rows.iter().map(|r| r.1.size.mean).chain(ps.iter().copied()).collect(),
            rows.iter().map(|r| r.1.size.ci95).chain(nan(ps.len())).collect(),
        ),
        panel(
            "aggregate velocity",
            "mean velocity along the gradient (µm/s)",
            rows.iter().map(|r| r.1.velocity.mean).chain(pv.iter().copied()).collect(),
            rows.iter().map(|r| r.1.velocity.ci95).chain(nan(pv.len())).collect(),
        ),
    ];
    category_panels(&out.join("case2.png"), "Case 2 at the end of the run", &panels, 2, (820, 480), Mark::Dots)?;
    Ok(())
}

fn velocity_by_size_figure(curves: &[SizeCurve], experiment: f64, out: &Path) -> Result<(), Error> {
    let mut series: Vec<Series> = curves
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let shift = 0.08 * (k as f64 - 1.0);
            Series::markers(
                format!("{} ({} seeds), α = {:.2}", c.model, c.seeds, c.alpha),
                c.sizes.iter().map(|(n, e)| (*n as f64 + shift, e.mean)).collect(),
                if k == 0 { engine_colour("magdem") } else { palette(k + 1) },
                5,
            )
            .with_errors(c.sizes.iter().map(|(_, e)| e.ci95).collect())
        })
        .collect();
    let largest = curves.iter().flat_map(|c| c.sizes.iter().map(|s| s.0)).max().unwrap_or(1) as f64;
    series.push(Series::line(
        "experiment's mean, any size",
        vec![(1.0, experiment), (largest, experiment)],
        RGBColor(0, 0, 0),
    ));
    crate::plot::line_chart_with_legend(
        &out.join("case2-velocity-by-size.png"),
        "Case 2: velocity against aggregate size, three drag models",
        "particles in the aggregate",
        "velocity along the gradient (µm/s)",
        &series,
        SeriesLabelPosition::UpperLeft,
    )?;
    Ok(())
}
