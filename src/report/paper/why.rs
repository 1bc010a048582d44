//! Why the numbers differ: the sensitivity study and the ranking of explanations.

use super::convergence::{self, Effect, Explanation};
use super::{completed, mean, seed_list, table3_ensemble, Inputs};
use crate::plot::{category_panels, palette, BarGroup, BarPanel, Mark, Series, SeriesLabelPosition};
use crate::report::runs::Run;
use crate::report::tables::{col, frame, markdown, same, scol, ucol, write};
use crate::scene::Scene;
use minijinja::{context, Value};
use std::collections::BTreeMap;
use std::path::Path;

type Error = Box<dyn std::error::Error>;

const SENSITIVITY: [&str; 2] = ["paper-sensitivity", "paper-sensitivity-concentrations"];

/// The sensitivity variants that change the physics (the figure shows these; the numerical ones
/// are in the table).
const PHYSICAL: [&str; 5] = ["no-induction", "no-shielding", "restitution-0.2", "restitution-0.9", "saturated"];

pub fn sensitivity(inp: &Inputs) -> Result<Value, Error> {
    let (runs, out, tables) = (inp.runs, inp.out, &inp.tables);
    let mut effects = inp.effects.borrow_mut();
    // Concentration (as printed) → variant → runs.
    let mut studies: BTreeMap<u64, BTreeMap<String, Vec<&Run>>> = BTreeMap::new();
    for r in runs.iter().filter(|r| SENSITIVITY.contains(&r.experiment.as_str())) {
        let key = (r.concentration * 1e3).round() as u64;
        studies.entry(key).or_default().entry(r.variant.clone()).or_default().push(r);
    }
    studies.retain(|_, groups| !reference_of(groups).is_empty());
    if studies.is_empty() {
        return Ok(context! { present => false });
    }
    let (mut conc, mut names, mut changes, mut done_runs, mut means) = (vec![], vec![], vec![], vec![], vec![]);
    let (mut deltas, mut delta_cis, mut outcome, mut cost, mut capped, mut fastest) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut energy = vec![];
    let (mut panels, mut references) = (vec![], vec![]);
    for groups in studies.values() {
        let reference = reference_of(groups);
        let c = reference[0].concentration;
        let base = convergence::Estimate::of(&reference.iter().map(|r| r.mean_length_um()).collect::<Vec<_>>());
        let shared = reference[0].variant_overrides.clone();
        let reference_energy = mean(&reference.iter().map(|r| aggregate_energy(r)).collect::<Vec<_>>());
        references.push(context! {
            c => c,
            scene => reference[0].scene.clone(),
            seeds => seed_list(&reference.iter().map(|r| r.seed).collect::<Vec<_>>()),
            reference => base,
        });
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
            energy.push(mean(&ok.iter().map(|r| aggregate_energy(r)).collect::<Vec<_>>()) / reference_energy);
            deltas.push(d.mean);
            delta_cis.push(d.ci95);
            outcome.push(variant_outcome(group, ok.len()));
            cost.push(mean(&group.iter().map(|r| r.wall_time).collect::<Vec<_>>()));
            if d.n > 0 {
                if PHYSICAL.contains(&name.as_str()) {
                    bars.push((name.clone(), d));
                }
                if let Some(explanation) = sensitivity_explanation(name).filter(|_| !shielding_on_verlet(inp, name, c))
                {
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
        col("aggregate_kinetic_energy_over_reference", energy),
        col("paired_change_percent", deltas),
        col("paired_change_ci95_percent", delta_cis),
        col("wall_time_per_run_s", cost),
        scol("outcome", outcome),
    ])?;
    write(&mut df, tables, "sensitivity")?;
    let table = markdown(
        &df,
        &[
            "c (mg/ml)",
            "variant",
            "change",
            "runs",
            "mean length (µm)",
            "box-limited",
            "fastest aggregate at the end (m/s)",
            "aggregate kinetic energy ÷ reference",
            "paired change (%)",
            "± CI95",
            "wall time/run (s)",
            "outcome",
        ],
        &[3, 0, 0, 0, 1, 3, 4, 1, 1, 1, 0, 0],
    )?;
    category_panels(
        &out.join("sensitivity.png"),
        "Case 1: physical choices against the r-RESPA reference (paired change, mean ± CI95 over seeds)",
        &panels,
        2,
        (900, 520),
        Mark::Dots,
    )?;
    Ok(context! {
        present => true,
        table => table,
        references => references,
        reference_slow_every => reference_slow_every(runs),
    })
}

/// Kinetic energy of the aggregates' centre-of-mass motion in a run's last frame, per particle,
/// in units of one particle's mass (m²/s²): Σ n v² / 2N over the aggregates (equal particles).
fn aggregate_energy(r: &Run) -> f64 {
    let n: usize = r.last.iter().map(|a| a.size()).sum();
    r.last.iter().map(|a| a.size() as f64 * a.com_velocity.norm_squared()).sum::<f64>() / (2.0 * n as f64)
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

/// The r-RESPA outer step of the sensitivity study's reference (its `slow_every`), from a run's scene.
fn reference_slow_every(runs: &[Run]) -> Option<u64> {
    let r = runs.iter().find(|r| SENSITIVITY.contains(&r.experiment.as_str()) && r.variant == "respa")?;
    let scene = Scene::parse(&r.scene_text, &r.id).ok()?;
    Some(scene.spec.integration.slow_every())
}

/// The experiment that switches the shielding off under Table 3's integrator and seeds.
pub const SHIELDING_VERLET: &str = "paper-shielding-verlet";
/// Its variant without the shielded area.
const SHIELDING_OFF: &str = "no-shielding";

/// Paired change of the mean length when the shielded area is switched off, under velocity
/// Verlet against the Table 3 runs of the same seeds (%).
fn shielding_verlet(runs: &[Run], c: f64) -> convergence::Estimate {
    let off = convergence::select(runs, &[SHIELDING_VERLET], SHIELDING_OFF, c);
    convergence::paired_change(&convergence::table3_runs(runs, c), &off)
}

/// True where the shielding's effect at `c` comes from the Verlet pairs instead of the
/// sensitivity study's r-RESPA pairs.
fn shielding_on_verlet(inp: &Inputs, variant: &str, c: f64) -> bool {
    variant == SHIELDING_OFF && shielding_verlet(inp.runs, c).n >= 2
}

/// One effect in a concentration's ranking.
#[derive(serde::Serialize)]
struct Ranked {
    explanation: &'static str,
    /// The explanation, with the variant where one explanation has several (restitution).
    label: String,
    what: String,
    change: convergence::Estimate,
    /// Effects in one tier are not resolved from each other; tier 1 is the largest.
    tier: usize,
}

/// One concentration's block of the ranking.
#[derive(serde::Serialize)]
struct Block {
    c: f64,
    magdem: convergence::Estimate,
    experiment: f64,
    paper: f64,
    vs_experiment: f64,
    vs_paper: f64,
    resolved: Vec<Ranked>,
    unresolved: Vec<Ranked>,
    not_measured: Vec<&'static str>,
    table: String,
}

/// Groups effects sorted by decreasing |change| into tiers: an effect opens a new tier when its
/// whole CI95 lies below the CI95 of the tier's first (largest) effect. So every effect is resolved
/// below the first effect of each tier above its own; it is not ranked against the rest of its tier.
fn tiers(sorted: &[&Effect]) -> Vec<usize> {
    let (mut tier, mut leader_low) = (0, f64::NEG_INFINITY);
    sorted
        .iter()
        .map(|e| {
            let (low, high) = (e.change.mean.abs() - e.change.ci95, e.change.mean.abs() + e.change.ci95);
            if tier == 0 || high < leader_low {
                tier += 1;
                leader_low = low;
            }
            tier
        })
        .collect()
}

/// Why the numbers differ: at each concentration, the effects whose CI95 excludes zero, in tiers
/// that their CIs resolve, and the effects that are not resolved.
pub fn ranking(inp: &Inputs) -> Result<Value, Error> {
    let effects = inp.effects.borrow();
    let t = inp.targets;
    let mut blocks = vec![];
    let (mut c_col, mut e_col, mut w_col, mut m_col, mut ci_col, mut n_col, mut tier_col) =
        (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    for (&c, (&exp, &paper)) in t.concentration.iter().zip(t.experiment.iter().zip(&t.paper)) {
        let here: Vec<&Effect> = effects
            .iter()
            .filter(|e| same(e.concentration, c) && e.explanation != Explanation::Seeds && e.change.mean.is_finite())
            .collect();
        let is_resolved =
            |e: &&Effect| e.change.n >= 2 && e.change.ci95.is_finite() && e.change.mean.abs() > e.change.ci95;
        let mut resolved: Vec<&Effect> = here.iter().copied().filter(is_resolved).collect();
        resolved.sort_by(|a, b| b.change.mean.abs().total_cmp(&a.change.mean.abs()));
        let mut unresolved: Vec<&Effect> = here.iter().copied().filter(|e| !is_resolved(e)).collect();
        unresolved.sort_by(|a, b| b.change.mean.abs().total_cmp(&a.change.mean.abs()));
        let ranked = |list: &[&Effect], tiers: &[usize]| -> Vec<Ranked> {
            list.iter()
                .zip(tiers)
                .map(|(e, &tier)| Ranked {
                    explanation: e.explanation.name(),
                    label: match e.explanation {
                        Explanation::Restitution => e.what.split_whitespace().next().unwrap_or_default().to_string(),
                        x => x.name().to_string(),
                    },
                    what: e.what.clone(),
                    change: e.change,
                    tier,
                })
                .collect()
        };
        let resolved = ranked(&resolved, &tiers(&resolved));
        let unresolved = ranked(&unresolved, &vec![0; unresolved.len()]);
        let mut table =
            String::from("| tier | explanation | effect (%) | ± CI95 | what is compared |\n|---|---|---|---|---|\n");
        for r in resolved.iter().chain(&unresolved) {
            let tier = if r.tier == 0 { "not resolved".to_string() } else { r.tier.to_string() };
            table += &format!(
                "| {tier} | {} | {:+.1} | {:.1} | {} |\n",
                r.explanation, r.change.mean, r.change.ci95, r.what
            );
            c_col.push(c);
            e_col.push(r.explanation.to_string());
            w_col.push(r.what.clone());
            m_col.push(r.change.mean);
            ci_col.push(r.change.ci95);
            n_col.push(r.change.n as f64);
            tier_col.push(r.tier as u64);
        }
        let magdem = convergence::Estimate::of(
            &convergence::table3_runs(inp.runs, c).iter().map(|r| r.mean_length_um()).collect::<Vec<_>>(),
        );
        let not_measured = Explanation::ALL
            .into_iter()
            .filter(|x| *x != Explanation::Seeds && !here.iter().any(|e| e.explanation == *x))
            .map(Explanation::name)
            .collect();
        blocks.push(Block {
            c,
            magdem,
            experiment: exp,
            paper,
            vs_experiment: 100.0 * (magdem.mean / exp - 1.0),
            vs_paper: 100.0 * (magdem.mean / paper - 1.0),
            resolved,
            unresolved,
            not_measured,
            table,
        });
    }
    let mut df = frame(vec![
        col("concentration_mg_per_ml", c_col),
        scol("explanation", e_col),
        scol("what", w_col),
        col("change_percent", m_col),
        col("ci95_percent", ci_col),
        col("runs_or_pairs", n_col),
        ucol("tier", tier_col),
    ])?;
    write(&mut df, &inp.tables, "explanations")?;
    Ok(Value::from_serialize(context! { blocks => Value::from_serialize(&blocks) }))
}

/// Stokes' drag on two touching equal spheres moving along their line of centres, per sphere, as
/// a share of a lone sphere's (Stimson & Jeffery 1926, Proc. R. Soc. A 111, 110).
const STIMSON_JEFFERY_PAIR: f64 = 0.645;

/// The paper's shielded area: its geometry (`shielding.png`) and its effect on case 1 at
/// 2.25 mg/ml, measured three ways, with the Verlet pairs as the estimate that enters the ranking.
pub fn shielding(inp: &Inputs) -> Result<Value, Error> {
    let geometry = shielding_geometry(inp.out)?;
    let c = 2.25;
    let verlet = shielding_verlet(inp.runs, c);
    if verlet.n >= 2 {
        inp.effects.borrow_mut().push(Effect {
            concentration: c,
            explanation: Explanation::Shielding,
            what: format!("no shielding against Table 3, velocity Verlet, paired over {} seeds", verlet.n),
            change: verlet,
        });
    }
    let pick = |runs, experiment, variant| convergence::select(runs, &[experiment], variant, c);
    let respa = convergence::paired_change(
        &pick(inp.runs, "paper-sensitivity", "respa"),
        &pick(inp.runs, "paper-sensitivity", "no-shielding"),
    );
    let stokes =
        convergence::paired_change(&pick(inp.hydro, "hydro-case1", "a-eff"), &pick(inp.hydro, "hydro-case1", "stokes"));
    // Whether the r-RESPA and the Verlet estimates differ by more than their combined CI95.
    let gap = convergence::Estimate {
        n: respa.n.min(verlet.n),
        mean: respa.mean - verlet.mean,
        ci95: respa.ci95.hypot(verlet.ci95),
    };
    Ok(context! {
        geometry => geometry,
        angles => SHIELDING_ANGLES,
        stimson_jeffery => STIMSON_JEFFERY_PAIR,
        c => c,
        verlet => verlet,
        respa => respa,
        stokes => stokes,
        gap => gap,
        consistent => gap.mean.abs() <= gap.ci95,
    })
}

/// Particle Reynolds numbers Re = ρ_f |v| d / μ over every particle and stored frame of a run.
fn reynolds_numbers(r: &Run) -> Result<Vec<f64>, Error> {
    let scene = Scene::parse(&r.scene_text, &r.id)?;
    let Some(fluid) = scene.spec.fluid.as_ref() else { return Ok(vec![]) };
    let t = crate::io::trajectory::Trajectory::open(&r.file)?;
    let v = t.all_vectors("velocity")?;
    let radius = t.file.dataset("particles/radius")?.read_raw::<f64>()?;
    let mut re = vec![];
    for k in 1..v.shape()[0] {
        for (i, a) in radius.iter().enumerate() {
            let speed = (0..3).map(|c| v[[k, i, c]].powi(2)).sum::<f64>().sqrt();
            re.push(fluid.density * speed * 2.0 * a / fluid.viscosity);
        }
    }
    Ok(re)
}

/// One run's distribution of particle Reynolds numbers.
#[derive(serde::Serialize)]
struct ReynoldsRow {
    label: String,
    samples: usize,
    median: f64,
    p99: f64,
    max: f64,
    /// Shares of particle-frames above the limits (%).
    above: Vec<f64>,
}

/// Above these Re, Stokes' drag (and RPY, which assumes Stokes flow) is off by more than
/// Schiller–Naumann's correction 0.15 Re^0.687: about 3 % at 0.1 and 15 % at 1.
const REYNOLDS_LIMITS: [f64; 2] = [0.1, 1.0];

/// The seed of each Table 3 ensemble whose trajectories the Reynolds numbers are read from.
const REYNOLDS_SEED: u64 = 1;

/// The particle Reynolds numbers of the seed-1 Table 3 runs, the approach run and a case-2 run:
/// where Stokes drag and RPY leave their range; figure `reynolds.png` (fraction of particle-frames
/// above each Re).
pub fn reynolds(inp: &Inputs) -> Result<Value, Error> {
    let mut picked: Vec<(String, &Run)> = vec![];
    let mut seed1: Vec<&Run> =
        table3_ensemble(inp.runs).into_iter().filter(|r| r.seed == REYNOLDS_SEED && r.has_trajectory()).collect();
    seed1.sort_by(|a, b| a.concentration.total_cmp(&b.concentration));
    picked.extend(seed1.into_iter().map(|r| (format!("case 1, {} mg/ml", r.concentration), r)));
    if let Some(r) = completed(inp.runs, "paper-case2").into_iter().find(|r| r.has_trajectory()) {
        picked.push(("case 2".into(), r));
    }
    if picked.is_empty() {
        return Ok(context! { present => false });
    }
    let (mut rows, mut series) = (vec![], vec![]);
    let mut interval = f64::NAN;
    for (k, (label, r)) in picked.iter().enumerate() {
        let mut re = reynolds_numbers(r)?;
        if re.is_empty() {
            continue;
        }
        re.sort_by(f64::total_cmp);
        let quantile = |q: f64| re[((re.len() - 1) as f64 * q).round() as usize];
        rows.push(ReynoldsRow {
            label: label.clone(),
            samples: re.len(),
            median: quantile(0.5),
            p99: quantile(0.99),
            max: quantile(1.0),
            above: REYNOLDS_LIMITS
                .iter()
                .map(|l| 100.0 * re.iter().filter(|&&x| x > *l).count() as f64 / re.len() as f64)
                .collect(),
        });
        if label.starts_with("case 1") && r.times.len() > 1 {
            interval = r.times[1] - r.times[0];
        }
        // The share of particle-frames above each Re, on log axes (positive values only).
        let n = re.len() as f64;
        let points: Vec<(f64, f64)> = (0..=45)
            .map(|j| -6.0 + j as f64 * 0.2)
            .map(|x| (x, re.partition_point(|&v| v <= 10f64.powf(x)) as f64))
            .map(|(x, below)| (x, (n - below) / n))
            .filter(|&(_, share)| share > 0.0)
            .collect();
        series.push(Series::line(label.clone(), points, palette(k)));
    }
    crate::plot::chart(
        &inp.out.join("reynolds.png"),
        "Particle Reynolds numbers over every stored frame",
        ("log10 of the particle Reynolds number Re = ρ_f |v| d / μ", "fraction of particle-frames above Re"),
        &series,
        SeriesLabelPosition::LowerLeft,
        (crate::plot::Scale::Linear, crate::plot::Scale::Log),
    )?;
    let mut table = format!(
        "| run | particle-frames | median Re | 99th percentile | largest | % above {} | % above {} |\n|---|---|---|---|---|---|---|\n",
        REYNOLDS_LIMITS[0], REYNOLDS_LIMITS[1]
    );
    for r in &rows {
        table += &format!(
            "| {} | {} | {:.1e} | {:.1e} | {:.2} | {:.2} | {:.2} |\n",
            r.label, r.samples, r.median, r.p99, r.max, r.above[0], r.above[1]
        );
    }
    let case1: Vec<&ReynoldsRow> = rows.iter().filter(|r| r.label.starts_with("case 1")).collect();
    Ok(context! {
        present => true,
        seed => REYNOLDS_SEED,
        table => table,
        limits => REYNOLDS_LIMITS,
        interval => interval,
        case1_max => case1.iter().map(|r| r.max).fold(f64::NAN, f64::max),
        case1_median_min => case1.iter().map(|r| r.median).fold(f64::NAN, f64::min),
        case1_median_max => case1.iter().map(|r| r.median).fold(f64::NAN, f64::max),
        case1_p99_max => case1.iter().map(|r| r.p99).fold(f64::NAN, f64::max),
        case1_above_max => case1.iter().map(|r| r.above[0]).fold(f64::NAN, f64::max),
        case1_above1_max => case1.iter().map(|r| r.above[1]).fold(f64::NAN, f64::max),
        case2_max => rows.iter().find(|r| r.label == "case 2").map(|r| r.max),
        corrections => REYNOLDS_LIMITS.iter().map(|re| 100.0 * 0.15 * re.powf(0.687)).collect::<Vec<_>>(),
    })
}

/// The angles (degrees) at which the report quotes A_eff.
const SHIELDING_ANGLES: [usize; 4] = [0, 30, 60, 90];

/// A_eff/πa² of a sphere behind a touching equal neighbour against the angle between their line
/// of centres and the motion (the paper's Figs. 1–3 as a curve, `shielding.png`); returns its
/// values at 0°, 30°, 60° and 90°.
fn shielding_geometry(out: &Path) -> Result<Vec<f64>, Error> {
    use crate::core::forces::shielding::shadow_area;
    use crate::core::state::Vec3;
    let a = 5.5e-6;
    let curve: Vec<(f64, f64)> = (0..=180)
        .map(|deg| {
            let theta = (deg as f64).to_radians();
            let offset = Vec3::new(theta.cos(), theta.sin(), 0.0) * 2.0 * a;
            (deg as f64, 1.0 - shadow_area(a, a, &offset, &Vec3::x()) / (std::f64::consts::PI * a * a))
        })
        .collect();
    crate::plot::chart(
        &out.join("shielding.png"),
        "The paper's A_eff: a sphere behind a touching neighbour",
        ("angle between the line of centres and the motion (degrees)", "A_eff / (π a²)"),
        &[Series::line("magdem's shielding (lens area of the projected circles)", curve.clone(), palette(1))],
        SeriesLabelPosition::LowerRight,
        (crate::plot::Scale::Linear, crate::plot::Scale::Linear),
    )?;
    Ok(SHIELDING_ANGLES.iter().map(|&d| curve[d].1).collect())
}

/// Density of polystyrene, the matrix of composite magnetic beads (kg/m³).
const POLYSTYRENE_DENSITY: f64 = 1050.0;
/// Density of magnetite, Fe₃O₄ (kg/m³).
const MAGNETITE_DENSITY: f64 = 5170.0;
/// Bulk magnetite's saturation magnetisation at room temperature (A/m).
pub const MAGNETITE_MS: f64 = 4.8e5;

/// What the paper's case-1 inputs imply for the bead magnetisation: the linear law of its μr in
/// its field, against a composite bead of its density (magnetite in polystyrene) at saturation,
/// and the ratio of the aggregation times τ ∝ 1/M² of the two.
pub fn inputs(inp: &Inputs) -> Result<Value, Error> {
    let Some(r) = convergence::table3_runs(inp.runs, inp.targets.concentration[0]).into_iter().next() else {
        return Ok(context! { present => false });
    };
    let scene = Scene::parse(&r.scene_text, &r.id)?;
    let s = &scene.species[0];
    let b0 = scene.spec.field.as_ref().map_or(f64::NAN, |f| nalgebra::Vector3::from(f.b0).norm());
    let linear = s.susceptibility * b0 / crate::core::forces::magnetisation::MU0;
    // Volume fraction of magnetite that gives the bead its density.
    let fraction = (s.density - POLYSTYRENE_DENSITY) / (MAGNETITE_DENSITY - POLYSTYRENE_DENSITY);
    let composite = fraction * MAGNETITE_MS;
    let mu_r = (3.0 + 2.0 * s.susceptibility) / (3.0 - s.susceptibility);
    Ok(context! {
        present => true,
        mu_r => mu_r,
        b0 => b0,
        density => s.density,
        diameter_um => 2e6 * s.radius,
        linear => linear,
        saturation => MAGNETITE_MS,
        over_saturation => linear / MAGNETITE_MS,
        polystyrene => POLYSTYRENE_DENSITY,
        magnetite => MAGNETITE_DENSITY,
        fraction_percent => 100.0 * fraction,
        composite => composite,
        tau_ratio => (linear / composite).powi(2),
        end_time_ms => 1e3 * r.times.last().copied().unwrap_or(f64::NAN),
        dt => scene.spec.integration.dt,
    })
}
