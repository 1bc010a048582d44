//! `magdem study accuracy`: error against time step, per integrator, on problems with a known
//! answer, with the observed order fitted on log–log axes.
//!
//! Problems (all with the paper's 11 µm Fe3O4 particles in water):
//! - terminal: one saturated particle set moving by a gradient force against Stokes drag from
//!   rest; exact v(t) = v_T (1 − e^{−t/τ}); error |v(2τ) − v_exact| / v_T.
//! - hertz: elastic head-on impact at 0.1 m/s; error of the largest overlap seen against the
//!   Hertz closed form (15 m* v²/(16 E* √R*))^(2/5), relative.
//! - dipoles: two dipoles closing with exact induction under Stokes drag (no contact) for
//!   96 µs; error of the final separation against the same scene with exponential Verlet at
//!   dt = 1e-10 s (second order, checked in tests/integrators.rs), relative to the distance
//!   travelled.

use crate::analysis::stats::slope_ci95;
use crate::analysis::timing::timed;
use crate::core::integrators::{
    AdaptiveVerletSpec, ExplicitEulerSpec, ExponentialVerletSpec, RespaSpec, Scheme, SemiImplicitEulerSpec,
    VelocityVerletSpec,
};
use crate::plot::{line_chart_with_legend, Series};
use crate::scene::spec::scheme_lines;
use crate::scene::Scene;
use minijinja::context;
use plotters::prelude::SeriesLabelPosition;
use plotters::style::RGBColor;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

type Error = Box<dyn std::error::Error>;

/// The fixed-step schemes of the stability map, r-RESPA at this study's [`RESPA_K`].
pub fn schemes() -> [Scheme; 5] {
    super::stability::SCHEMES.map(|s| match s {
        Scheme::Respa(_) => RESPA,
        s => s,
    })
}

const RESPA: Scheme = Scheme::Respa(RespaSpec { slow_every: RESPA_K });
const EXPONENTIAL: Scheme = Scheme::ExponentialVerlet(ExponentialVerletSpec {});
const VERLET: Scheme = Scheme::VelocityVerlet(VelocityVerletSpec {});
const EULER: Scheme = Scheme::ExplicitEuler(ExplicitEulerSpec {});
const SEMI_IMPLICIT: Scheme = Scheme::SemiImplicitEuler(SemiImplicitEulerSpec {});

fn colour(scheme: Scheme) -> RGBColor {
    match scheme {
        Scheme::ExplicitEuler(_) => RGBColor(200, 30, 30),
        Scheme::SemiImplicitEuler(_) => RGBColor(230, 140, 20),
        Scheme::VelocityVerlet(_) => RGBColor(20, 90, 200),
        Scheme::ExponentialVerlet(_) => RGBColor(30, 150, 60),
        Scheme::Respa(_) | Scheme::SubcycledEuler(_) => RGBColor(130, 60, 170),
        _ => crate::plot::palette(6),
    }
}

/// The case-1 species, elastic (restitution 1).
fn material(extra: &str) -> String {
    super::fe3o4(1.0e9, 1.0, extra)
}

/// `respa`'s ratio K of inner to outer steps in this study (magnetic forces every K steps).
pub const RESPA_K: u64 = 4;
/// Errors at or below this are round-off: the scheme is exact for the problem.
pub const ROUND_OFF: f64 = 1e-12;
/// Fewest points an order is fitted through, and fewest round-off points that make "exact".
pub const MIN_POINTS: usize = 3;
/// Closing speed of the Hertz impact (m/s).
pub const HERTZ_SPEED: f64 = 0.1;
/// The terminal-velocity problem runs for this many drag relaxation times τ.
pub const TERMINAL_TAUS: f64 = 2.0;
/// Step of the exponential-Verlet run that is the dipole problem's reference (s).
pub const REFERENCE_DT: f64 = 1e-10;
/// Repetitions of each timed run in the work–precision study (the median is plotted).
pub const TIMING_RUNS: usize = 5;
/// Tolerances of `adaptive-verlet` in the work–precision study (of a radius), at a largest step
/// of [`ADAPTIVE_DT`].
pub const TOLERANCES: [f64; 5] = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8];
pub const ADAPTIVE_DT: f64 = 6.4e-8;

const TAU: f64 = 1087.0 * 4.0 / 3.0 * std::f64::consts::PI * 5.5e-6 * 5.5e-6 / (6.0 * std::f64::consts::PI * 1.0e-3);

/// One problem: its scene for a scheme and dt, and the error of a finished simulation.
pub struct Problem {
    pub name: &'static str,
    pub dts: Vec<f64>,
    scene: fn(Scheme, f64) -> String,
}

fn integration(scheme: Scheme, dt: f64, end: f64) -> String {
    let scheme = scheme_lines(&scheme);
    format!("[integration]\n{scheme}dt = {dt:e}\nend_time = {end:e}\n[output]\ninterval = {end:e}\n[stability]\nmax_step_fraction = 1.0\nmax_overlap = 0.5\n")
}

fn terminal_scene(scheme: Scheme, dt: f64) -> String {
    let material = material("saturation_magnetisation = 1.0e4\n");
    format!(
        "version = 1\n[domain]\nlo = [-1e-3, -1e-3, -1e-3]\nhi = [1e-3, 1e-3, 1e-3]\n[fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n\
         [field]\nb0 = [0.5, 0.0, 0.0]\ngradient = [[1.4, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n{material}\
         [[particles]]\nspecies = \"p\"\npositions = [[0.0, 0.0, 0.0]]\n[forces.gradient]\n[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n{}",
        integration(scheme, dt, TERMINAL_TAUS * TAU)
    )
}

fn terminal_error(sim: &crate::core::simulation::Simulation) -> f64 {
    let vt = 4.0 / 3.0 * std::f64::consts::PI * 5.5e-6_f64.powi(3) * 1.0e4 * 1.4
        / (6.0 * std::f64::consts::PI * 1.0e-3 * 5.5e-6);
    let exact = vt * (1.0 - (-sim.state.time / TAU).exp());
    (sim.state.particles.velocity[0].x - exact).abs() / vt
}

fn hertz_scene(scheme: Scheme, dt: f64) -> String {
    format!(
        "version = 1\n[domain]\nlo = [-1e-4, -1e-4, -1e-4]\nhi = [1e-4, 1e-4, 1e-4]\n{}\
         [[particles]]\nspecies = \"p\"\npositions = [[-5.5005e-6, 0.0, 0.0], [5.5005e-6, 0.0, 0.0]]\nvelocities = [[{v:e}, 0.0, 0.0], [-{v:e}, 0.0, 0.0]]\n\
         [forces.contact]\n{}",
        material(""),
        integration(scheme, dt, 1.28e-7),
        v = HERTZ_SPEED / 2.0
    )
}

fn dipoles_scene(scheme: Scheme, dt: f64) -> String {
    crate::verify::magnetic::pair_before_contact(scheme, dt) + "[stability]\nmax_step_fraction = 1.0\n"
}

fn separation(sim: &crate::core::simulation::Simulation) -> f64 {
    let p = &sim.state.particles;
    (p.position[1] - p.position[0]).norm()
}

pub fn problems() -> Vec<Problem> {
    vec![
        Problem { name: "terminal", dts: (2..=8).map(|k| TAU / f64::powi(2.0, k)).collect(), scene: terminal_scene },
        Problem { name: "hertz", dts: (0..7).map(|k| 1.6e-8 / f64::powi(2.0, k)).collect(), scene: hertz_scene },
        Problem { name: "dipoles", dts: (0..6).map(|k| 6.4e-8 / f64::powi(2.0, k)).collect(), scene: dipoles_scene },
    ]
}

/// Runs a problem's scene to its end; returns the error (the Hertz problem tracks the overlap
/// during the run; `Err` if the run went unstable).
fn run_problem(problem: &Problem, scheme: Scheme, dt: f64, reference: Option<f64>) -> Result<f64, String> {
    let scene = Scene::parse(&(problem.scene)(scheme, dt), problem.name).map_err(|e| e.to_string())?;
    let mut sim = scene.simulation(None);
    sim.initialise().map_err(|e| e.to_string())?;
    let mut max_overlap = 0.0_f64;
    while sim.state.step < scene.total_steps() {
        sim.step().map_err(|e| e.to_string())?;
        if problem.name == "hertz" {
            let p = &sim.state.particles;
            max_overlap = max_overlap.max(1.1e-5 - (p.position[1] - p.position[0]).norm());
        }
    }
    Ok(match problem.name {
        "hertz" => {
            let s = &scene.species[0];
            let (m_eff, r_eff, e_star, v) = (
                s.mass() / 2.0,
                s.radius / 2.0,
                s.youngs_modulus / (2.0 * (1.0 - s.poisson_ratio.powi(2))),
                HERTZ_SPEED,
            );
            let delta = (15.0 * m_eff * v * v / (16.0 * e_star * r_eff.sqrt())).powf(0.4);
            (max_overlap - delta).abs() / delta
        }
        "dipoles" => dipoles_error(&sim, reference.expect("the dipole problem has a reference")),
        _ => terminal_error(&sim),
    })
}

/// Runs a scene text to its end; the finished simulation.
fn run_text(text: &str, origin: &str) -> Result<crate::core::simulation::Simulation, String> {
    Scene::parse(text, origin).map_err(|e| e.to_string())?.run_to_end().map_err(|e| e.to_string())
}

/// The dipole problem's error: separation error relative to the distance travelled.
fn dipoles_error(sim: &crate::core::simulation::Simulation, reference: f64) -> f64 {
    (separation(sim) - reference).abs() / (6.6e-5 - reference)
}

/// The observed order of one scheme on one problem, from its stable points.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Order {
    /// Least-squares slope of log error on log dt with its CI95, over the points above round-off;
    /// `rises`: the steps at which the error grew although dt was halved (empty: monotone).
    Fitted { mean: f64, ci95: f64, points: usize, rises: Vec<f64> },
    /// Errors at round-off on at least [`MIN_POINTS`] stable points.
    Exact { points: usize },
    /// Fewer than [`MIN_POINTS`] runs stayed stable.
    TooFewStable { stable: usize, of: usize },
    /// Enough stable runs, but too few of them both above and at round-off.
    TooFewAboveRoundOff { above: usize, of: usize },
}

impl Order {
    /// The order from the stable points `(dt, error)` of `attempted` runs.
    pub fn of(points: &[(f64, f64)], attempted: usize) -> Order {
        if points.len() < MIN_POINTS {
            return Order::TooFewStable { stable: points.len(), of: attempted };
        }
        let mut fit: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1 > ROUND_OFF).collect();
        let round_off = points.len() - fit.len();
        if fit.len() < MIN_POINTS {
            return if round_off >= MIN_POINTS {
                Order::Exact { points: round_off }
            } else {
                Order::TooFewAboveRoundOff { above: fit.len(), of: points.len() }
            };
        }
        fit.sort_by(|a, b| b.0.total_cmp(&a.0));
        let rises = fit.windows(2).filter(|w| w[1].1 >= w[0].1).map(|w| w[1].0).collect();
        let logs: Vec<(f64, f64)> = fit.iter().map(|p| (p.0.ln(), p.1.ln())).collect();
        let (mean, ci95) = slope_ci95(&logs);
        Order::Fitted { mean, ci95, points: fit.len(), rises }
    }

    /// The table's "observed order" and "± CI95" cells.
    fn cells(&self) -> (String, String) {
        match self {
            Order::Fitted { mean, ci95, .. } => (format!("{mean:.2}"), format!("{ci95:.2}")),
            Order::Exact { .. } => ("exact".into(), "–".into()),
            Order::TooFewStable { stable, of } => (format!("too few stable points ({stable} of {of})"), "–".into()),
            Order::TooFewAboveRoundOff { above, of } => {
                (format!("too few points above round-off ({above} of {of})"), "–".into())
            }
        }
    }

    /// The figure's legend entry.
    fn legend(&self) -> String {
        match self {
            Order::Fitted { mean, ci95, .. } => format!("{mean:.2} ± {ci95:.2}"),
            other => other.cells().0,
        }
    }
}

/// Least-squares slope of log error on log dt.
pub fn fitted_order(points: &[(f64, f64)]) -> f64 {
    let pts: Vec<(f64, f64)> = points.iter().filter(|p| p.1 > 0.0).map(|p| (p.0.ln(), p.1.ln())).collect();
    slope_ci95(&pts).0
}

/// Smallest and largest ratio `a / b` of two schemes' errors at the steps both ran stably.
pub fn ratio_range(a: &[(f64, f64)], b: &[(f64, f64)]) -> Option<(f64, f64)> {
    let ratios: Vec<f64> = a
        .iter()
        .filter_map(|&(dt, ea)| b.iter().find(|q| q.0 == dt).map(|q| ea / q.1))
        .filter(|r| r.is_finite())
        .collect();
    (!ratios.is_empty())
        .then(|| (ratios.iter().copied().fold(f64::INFINITY, f64::min), ratios.iter().copied().fold(0.0, f64::max)))
}

/// Two schemes' errors agree when they are stable at the same steps and differ by at most this,
/// relative.
pub const SAME_TOLERANCE: f64 = 1e-6;

fn same_errors(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| p.0 == q.0 && (p.1 - q.1).abs() <= SAME_TOLERANCE * q.1.abs().max(p.1.abs()))
}

/// A (min, max) pair for the template.
fn range((lo, hi): (f64, f64)) -> minijinja::Value {
    context! { min => lo, max => hi }
}

/// One timed point of the work–precision study.
#[derive(Clone, Serialize)]
struct Timed {
    scheme: String,
    setting: f64,
    error: f64,
    median: f64,
    min: f64,
    max: f64,
}

/// Error against run time on the two-dipole approach (`reference`: its reference separation):
/// each integrator over its dt range, and the adaptive integrator over [`TOLERANCES`] at a largest
/// step [`ADAPTIVE_DT`]; median of [`TIMING_RUNS`] runs, the spread (min–max) in the table.
fn work_precision(dir: &Path, problem: &Problem, reference: f64) -> Result<minijinja::Value, Error> {
    let mut table =
        String::from("| scheme | dt or tolerance | error | run time, median (min–max) |\n|---|---|---|---|\n");
    let mut series = vec![];
    let mut all: Vec<Timed> = vec![];
    let adaptive = Scheme::AdaptiveVerlet(AdaptiveVerletSpec::default());
    for scheme in schemes().into_iter().chain([adaptive]) {
        let settings: Vec<f64> = if scheme == adaptive { TOLERANCES.to_vec() } else { problem.dts.clone() };
        let mut line = vec![];
        for value in settings {
            let (result, spread) = timed(TIMING_RUNS, || {
                if scheme == adaptive {
                    let text =
                        dipoles_scene(Scheme::AdaptiveVerlet(AdaptiveVerletSpec { tolerance: value }), ADAPTIVE_DT);
                    run_text(&text, adaptive.name()).map(|sim| dipoles_error(&sim, reference))
                } else {
                    run_problem(problem, scheme, value, Some(reference))
                }
            });
            let (median, lo, hi) = (spread.median, spread.min, spread.max);
            if let Ok(err) = result {
                let label =
                    if scheme == adaptive { format!("tolerance {value:.0e}") } else { format!("dt {value:.1e}") };
                let _ = writeln!(table, "| {scheme} | {label} | {err:.2e} | {median:.4} s ({lo:.4}–{hi:.4}) |");
                if err > 0.0 && median > 0.0 {
                    line.push((median.log10(), err.log10()));
                }
                all.push(Timed { scheme: scheme.name().into(), setting: value, error: err, median, min: lo, max: hi });
            }
        }
        let color = colour(scheme);
        series.push(Series::markers(scheme.name(), line.clone(), color, 4));
        series.push(Series::line("", line, color));
    }
    let figure = "work-precision-dipoles.png";
    line_chart_with_legend(
        &dir.join(figure),
        "Work–precision: two-dipole approach",
        &format!("log10 run time (s, median of {TIMING_RUNS})"),
        "log10 error",
        &series,
        SeriesLabelPosition::UpperRight,
    )?;
    let of = |name: &str| all.iter().filter(|t| t.scheme == name).cloned().collect::<Vec<_>>();
    let by_error = |a: &&Timed, b: &&Timed| a.error.total_cmp(&b.error);
    let exponential = of(EXPONENTIAL.name());
    let ev_worst = exponential.iter().max_by(by_error).cloned();
    let others_best = all.iter().filter(|t| t.scheme != EXPONENTIAL.name()).min_by(by_error).cloned();
    let (respa, verlet) = (of(RESPA.name()), of(VERLET.name()));
    let pairs: Vec<(&Timed, &Timed)> =
        respa.iter().filter_map(|r| verlet.iter().find(|v| v.setting == r.setting).map(|v| (r, v))).collect();
    let fold = |xs: &mut dyn Iterator<Item = f64>| {
        xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
    };
    let respa_time = fold(&mut pairs.iter().map(|(r, v)| r.median / v.median));
    let respa_error = fold(&mut pairs.iter().map(|(r, v)| (r.error / v.error - 1.0).abs() * 100.0));
    let adaptive_points = of(adaptive.name());
    let adaptive_error = fold(&mut adaptive_points.iter().map(|t| t.error));
    Ok(context! {
        table => table,
        figure => figure,
        runs => TIMING_RUNS,
        tolerances => TOLERANCES.iter().map(|t| format!("{t:.0e}")).collect::<Vec<_>>(),
        tightening => TOLERANCES[0] / TOLERANCES[TOLERANCES.len() - 1],
        adaptive_dt => ADAPTIVE_DT,
        ev_worst => ev_worst,
        others_best => others_best,
        ev_ahead => matches!((&ev_worst, &others_best), (Some(e), Some(o)) if e.error < o.error),
        speedup => match (&ev_worst, &others_best) { (Some(e), Some(o)) => o.median / e.median, _ => f64::NAN },
        respa_k => RESPA_K,
        respa_time => range(respa_time),
        respa_error_pct => range(respa_error),
        adaptive_error => range(adaptive_error),
        adaptive_spread => adaptive_error.1 / adaptive_error.0,
    })
}

/// One of the paper's observables, measured per run, and the experiment that runs it per
/// integrator and step against a reference ensemble (run separately; read when present).
struct Observable {
    /// The template's name for it.
    key: &'static str,
    experiment: &'static str,
    /// Column heading of the value, with its unit.
    quantity: &'static str,
    minutes: u32,
    figure: &'static str,
    value: fn(&crate::report::runs::Run) -> f64,
}

const OBSERVABLES: [Observable; 2] = [
    Observable {
        key: "case1",
        experiment: "experiments/accuracy/case1-observable.toml",
        quantity: "mean length (µm)",
        minutes: 11,
        figure: "work-precision-case1.png",
        value: |r| r.mean_length_um(),
    },
    Observable {
        key: "case2",
        experiment: "experiments/accuracy/case2-observable.toml",
        quantity: "mean velocity (µm/s)",
        minutes: 30,
        figure: "work-precision-case2.png",
        value: |r| crate::analysis::stats::summary(&r.free_velocities_um_per_s(1)).mean,
    },
];

/// Aggregate gap tolerance of the observables (fraction of the smaller radius), the paper report's.
const OBSERVABLE_GAP: f64 = 1e-3;

/// The resolution the "seeds needed" column asks for (% of the reference value).
pub const RESOLVE_PCT: f64 = 1.0;

/// Work–precision on one observable from the runs of its experiment: per variant the paired
/// relative difference to the reference run of the same seed, its CI95 over seeds, and the
/// median wall time per run.
fn observable_section(dir: &Path, o: &Observable) -> Result<minijinja::Value, Error> {
    use crate::analysis::stats::{ci95_half_width, summary};
    // Runs whose trajectories are not here are read from the report's digests, where every
    // finished run read here is recorded (`reports/accuracy/digests/`).
    let runs = crate::report::digest::load_runs_digested(
        &[std::path::PathBuf::from(o.experiment)],
        OBSERVABLE_GAP,
        &dir.join("digests"),
    )?;
    let reference: Vec<_> = runs.iter().filter(|r| r.variant == "reference" && r.completed()).collect();
    let Some(first) = reference.first() else {
        return Ok(context! { ran => false, experiment => o.experiment, minutes => o.minutes });
    };
    let setting = Scene::parse(&first.scene_text, &first.id)?;
    let mut table = format!(
        "| variant | integrator, dt | runs | {} ± CI95 | paired difference to the reference (%) ± CI95 | per seed (%) | seeds needed to resolve {RESOLVE_PCT}% | wall time per run (s) |\n|---|---|---|---|---|---|---|---|\n",
        o.quantity
    );
    let mut variants: Vec<&str> = vec![];
    for r in &runs {
        if !variants.contains(&r.variant.as_str()) {
            variants.push(&r.variant);
        }
    }
    let mut points = vec![];
    let mut all_zero = vec![];
    let mut failed = vec![];
    let mut resolved = vec![];
    for variant in variants {
        let mine: Vec<_> = runs.iter().filter(|r| r.variant == variant).collect();
        let done: Vec<_> = mine.iter().filter(|r| r.completed()).collect();
        let setting = mine.first().map_or(String::new(), |r| integration_label(&r.scene_text, &r.id));
        if done.is_empty() {
            let why = failure_cell(&mine.iter().map(|r| r.message.as_str()).collect::<Vec<_>>());
            let _ = writeln!(table, "| {variant} | {setting} | 0 of {} | – | – | – | – | {why} |", mine.len());
            failed.push(format!("`{variant}` ({setting})"));
            continue;
        }
        let values: Vec<f64> = done.iter().map(|r| (o.value)(r)).collect();
        let paired: Vec<f64> = done
            .iter()
            .filter_map(|r| {
                reference
                    .iter()
                    .find(|q| q.seed == r.seed)
                    .map(|q| 100.0 * ((o.value)(r) - (o.value)(q)) / (o.value)(q))
            })
            .collect();
        let times: Vec<f64> = done.iter().map(|r| r.wall_time).filter(|t| t.is_finite()).collect();
        let wall = crate::analysis::timing::Spread::of(&times);
        let (diff, ci) = (summary(&paired).mean, ci95_half_width(&paired));
        let is_reference = variant == "reference";
        let needed = if is_reference {
            "–".to_string()
        } else {
            format!("{:.0}", (1.96 * summary(&paired).sample_std / RESOLVE_PCT).powi(2).ceil())
        };
        let _ = writeln!(
            table,
            "| {variant} | {setting} | {} of {} | {:.1} ± {:.1} | {} | {} | {needed} | {:.1} ({:.1}–{:.1}) |",
            done.len(),
            mine.len(),
            summary(&values).mean,
            ci95_half_width(&values),
            if is_reference { "0 (by definition)".to_string() } else { format!("{diff:+.1} ± {ci:.1}") },
            if is_reference {
                "–".to_string()
            } else {
                paired.iter().map(|d| format!("{d:+.1}")).collect::<Vec<_>>().join(", ")
            },
            wall.median,
            wall.min,
            wall.max
        );
        if !is_reference {
            if !paired.is_empty() && paired.iter().all(|d| d.abs() < 0.05) {
                all_zero.push(variant.to_string());
            }
            if diff.abs() > ci && !all_zero.iter().any(|v| v == variant) {
                resolved.push(variant.to_string());
            }
            points.push((variant.to_string(), wall.median, diff, ci));
        }
    }
    let series: Vec<Series> = points
        .iter()
        .enumerate()
        .map(|(k, (v, t, d, ci))| {
            Series::markers(v.clone(), vec![(t.log10(), *d)], crate::plot::palette(k), 6).with_errors(vec![*ci])
        })
        .collect();
    line_chart_with_legend(
        &dir.join(o.figure),
        &format!("Work–precision: the {} observable", o.key),
        "log10 wall time per run (s)",
        "paired difference to the reference (%), CI95",
        &series,
        SeriesLabelPosition::UpperRight,
    )?;
    let integration = &setting.spec.integration;
    Ok(context! {
        ran => true,
        experiment => o.experiment,
        minutes => o.minutes,
        table => table,
        figure => o.figure,
        seeds => reference.iter().map(|r| r.seed).collect::<Vec<_>>(),
        concentration => first.concentration,
        particles => first.particles,
        diameter_um => setting.species[0].radius * 2e6,
        end_time => integration.end_time,
        reference_scheme => integration.scheme.name(),
        reference_dt => integration.dt,
        reference_k => integration.slow_every(),
        resolve_pct => RESOLVE_PCT,
        unchanged => all_zero,
        failed => failed,
        resolved => resolved,
        compared => points.len(),
        smallest_diff => points.iter().map(|p| p.2).fold(f64::INFINITY, f64::min),
        largest_diff => points.iter().map(|p| p.2).fold(f64::NEG_INFINITY, f64::max),
        largest_ci => points.iter().map(|p| p.3).fold(0.0, f64::max),
    })
}

/// "scheme, dt 5.0e-8 s" (with K for multiple time stepping) of a run's scene.
fn integration_label(scene_text: &str, id: &str) -> String {
    match Scene::parse(scene_text, id) {
        Ok(scene) => {
            let i = &scene.spec.integration;
            let k = if i.slow_every() > 1 { format!(", K = {}", i.slow_every()) } else { String::new() };
            format!("{}, dt {:.2e} s{k}", i.scheme.name(), i.dt)
        }
        Err(e) => e.to_string(),
    }
}

/// What became of a variant none of whose runs completed: how many went unstable, the earliest
/// time, and the stable step the solver estimated.
fn failure_cell(messages: &[&str]) -> String {
    let after = |m: &str, key: &str| {
        m.find(key).and_then(|k| m[k + key.len()..].split_whitespace().next().and_then(|v| v.parse::<f64>().ok()))
    };
    let unstable: Vec<&&str> = messages.iter().filter(|m| m.starts_with("unstable")).collect();
    if unstable.is_empty() {
        return messages.iter().find(|m| !m.is_empty()).map_or("not run".into(), |m| m.to_string());
    }
    let earliest = unstable.iter().filter_map(|m| after(m, "(t = ")).fold(f64::INFINITY, f64::min);
    let estimate = unstable.iter().find_map(|m| after(m, "Estimated stable dt "));
    format!(
        "unstable in {} of {} runs, the first at t = {earliest:.1e} s{}",
        unstable.len(),
        messages.len(),
        estimate.map_or(String::new(), |dt| format!(" (estimated stable dt {dt:.1e} s)"))
    )
}

/// One problem's results: its table, figure, orders by scheme, and errors by scheme.
struct Solved {
    table: String,
    orders: BTreeMap<String, Order>,
    errors: BTreeMap<String, Vec<(f64, f64)>>,
}

fn solve(dir: &Path, problem: &Problem, reference: Option<f64>) -> Result<Solved, Error> {
    let mut table = String::from("| scheme | observed order | ± CI95 | errors (dt: error) |\n|---|---|---|---|\n");
    let mut series = vec![];
    let (mut orders, mut errors) = (BTreeMap::new(), BTreeMap::new());
    for scheme in schemes() {
        // Without a magnetic force respa is velocity Verlet (and would sample the overlap only
        // every K steps).
        if matches!(scheme, Scheme::Respa(_)) && problem.name == "hertz" {
            continue;
        }
        // Unstable runs (the solver stopped them) leave no point.
        let points: Vec<(f64, f64)> = problem
            .dts
            .iter()
            .filter_map(|&dt| run_problem(problem, scheme, dt, reference).ok().map(|e| (dt, e)))
            .collect();
        let order = Order::of(&points, problem.dts.len());
        let (cell, ci) = order.cells();
        let _ = writeln!(
            table,
            "| {scheme} | {cell} | {ci} | {} |",
            points.iter().map(|(dt, e)| format!("{dt:.2e}: {e:.2e}")).collect::<Vec<_>>().join(", ")
        );
        series.push(Series {
            label: format!("{scheme} ({})", order.legend()),
            points: points.iter().filter(|p| p.1 > 0.0).map(|(dt, e)| (dt.log10(), e.log10())).collect(),
            color: colour(scheme),
            markers: if matches!(scheme, Scheme::ExponentialVerlet(_) | Scheme::Respa(_)) { Some(4) } else { None },
            errors: vec![],
        });
        orders.insert(scheme.name().to_string(), order);
        errors.insert(scheme.name().to_string(), points);
    }
    line_chart_with_legend(
        &dir.join(format!("convergence-{}.png", problem.name)),
        &format!("Error against time step: {}", problem.name),
        "log10 dt (s)",
        "log10 error",
        &series,
        SeriesLabelPosition::LowerRight,
    )?;
    Ok(Solved { table, orders, errors })
}

/// Every problem × scheme × dt, then the observables' work–precision; writes `dir/README.md` (from
/// `templates/accuracy/README.md`) and one figure per problem and observable.
pub fn study(dir: &Path) -> Result<String, Error> {
    std::fs::create_dir_all(dir)?;
    let mut solved = BTreeMap::new();
    let mut work = None;
    let mut dipole_time = f64::NAN;
    for problem in problems() {
        let reference = if problem.name == "dipoles" {
            let text = dipoles_scene(EXPONENTIAL, REFERENCE_DT);
            dipole_time = Scene::parse(&text, "reference")?.spec.integration.end_time;
            Some(separation(&run_text(&text, "reference")?))
        } else {
            None
        };
        solved.insert(problem.name, solve(dir, &problem, reference)?);
        if let Some(reference) = reference {
            work = Some(work_precision(dir, &problem, reference)?);
        }
    }
    let errors = |problem: &str, scheme: Scheme| solved[problem].errors[scheme.name()].clone();
    let (ev, vv, ee) = (EXPONENTIAL, VERLET, EULER);
    // Explicit Euler against each symplectic scheme on the Hertz impact.
    let euler_vs_symplectic = [SEMI_IMPLICIT, vv, ev]
        .iter()
        .filter_map(|&s| ratio_range(&errors("hertz", ee), &errors("hertz", s)))
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)));
    let problems: BTreeMap<&str, minijinja::Value> = problems()
        .iter()
        .map(|p| {
            let s = &solved[p.name];
            let dts = (p.dts.iter().copied().fold(f64::INFINITY, f64::min), p.dts.iter().copied().fold(0.0, f64::max));
            (
                p.name,
                context! {
                    table => s.table,
                    figure => format!("convergence-{}.png", p.name),
                    orders => s.orders,
                    dts => range(dts),
                    runs => p.dts.len(),
                },
            )
        })
        .collect();
    let observables: BTreeMap<&str, minijinja::Value> =
        OBSERVABLES.iter().map(|o| Ok((o.key, observable_section(dir, o)?))).collect::<Result<_, Error>>()?;
    let md = crate::report::template::render(
        "accuracy/README.md",
        &context! {
            version => env!("CARGO_PKG_VERSION"),
            commit => env!("MAGDEM_GIT_COMMIT"),
            respa_k => RESPA_K,
            round_off => ROUND_OFF,
            min_points => MIN_POINTS,
            hertz_speed => HERTZ_SPEED,
            terminal_taus => TERMINAL_TAUS,
            dipole_time_us => dipole_time * 1e6,
            reference_dt => REFERENCE_DT,
            same_tolerance => SAME_TOLERANCE,
            problems => problems,
            ev_vs_verlet => ratio_range(&errors("dipoles", vv), &errors("dipoles", ev)).map(range),
            euler_vs_symplectic => euler_vs_symplectic.map(range),
            hertz_same_as_verlet => [SEMI_IMPLICIT, ev]
                .iter()
                .filter(|&&s| same_errors(&errors("hertz", s), &errors("hertz", vv)))
                .map(|s| s.name())
                .collect::<Vec<_>>(),
            work => work,
            observables => observables,
        },
    )?;
    std::fs::write(dir.join("README.md"), &md)?;
    Ok(md)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_order_needs_three_stable_points() {
        let dts = [8e-9, 4e-9, 2e-9, 1e-9];
        // Second order, monotone.
        let second: Vec<(f64, f64)> = dts.iter().map(|&dt| (dt, 1e10 * dt * dt)).collect();
        match Order::of(&second, 4) {
            Order::Fitted { mean, ci95, points, rises } => {
                assert!((mean - 2.0).abs() < 1e-9 && ci95.abs() < 1e-6 && points == 4 && rises.is_empty())
            }
            other => panic!("{other:?}"),
        }
        // Round-off everywhere: exact.
        let exact: Vec<(f64, f64)> = dts.iter().map(|&dt| (dt, 1e-15)).collect();
        assert_eq!(Order::of(&exact, 4), Order::Exact { points: 4 });
        // Always unstable, or stable at two steps only: not "exact".
        assert_eq!(Order::of(&[], 4), Order::TooFewStable { stable: 0, of: 4 });
        assert_eq!(Order::of(&exact[..2], 4), Order::TooFewStable { stable: 2, of: 4 });
        assert_eq!(
            Order::of(&[exact[0], exact[1], second[2], second[3]], 4),
            Order::TooFewAboveRoundOff { above: 2, of: 4 }
        );
        assert_eq!(Order::TooFewStable { stable: 1, of: 7 }.cells().0, "too few stable points (1 of 7)");
        // A zigzag is fitted, and the rise is reported.
        let zigzag = [(8e-9, 1e-3), (4e-9, 1e-4), (2e-9, 1e-6), (1e-9, 1e-5)];
        match Order::of(&zigzag, 4) {
            Order::Fitted { rises, ci95, .. } => assert!(rises == vec![1e-9] && ci95 > 0.5),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn ratios_over_common_steps() {
        let a = [(2.0, 10.0), (1.0, 4.0), (0.5, 1.0)];
        let b = [(2.0, 1.0), (1.0, 2.0)];
        assert_eq!(ratio_range(&a, &b), Some((2.0, 10.0)));
        assert_eq!(ratio_range(&a, &[]), None);
    }
}
