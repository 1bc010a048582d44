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

use super::timed;
use crate::core::integrators::Scheme;
use crate::plot::{line_chart_with_legend, Series};
use crate::scene::Scene;
use plotters::prelude::SeriesLabelPosition;
use plotters::style::RGBColor;
use std::fmt::Write as _;
use std::path::Path;

/// The fixed-step schemes of the stability map.
pub use super::stability::SCHEMES;

fn colour(scheme: Scheme) -> RGBColor {
    match scheme {
        Scheme::ExplicitEuler => RGBColor(200, 30, 30),
        Scheme::SemiImplicitEuler => RGBColor(230, 140, 20),
        Scheme::VelocityVerlet => RGBColor(20, 90, 200),
        Scheme::ExponentialVerlet => RGBColor(30, 150, 60),
        Scheme::AdaptiveVerlet => crate::plot::palette(6),
        Scheme::Respa | Scheme::SubcycledEuler => RGBColor(130, 60, 170),
    }
}

/// The case-1 species, elastic (restitution 1).
fn material(extra: &str) -> String {
    super::fe3o4(1.0e9, 1.0, extra)
}

const TAU: f64 = 1087.0 * 4.0 / 3.0 * std::f64::consts::PI * 5.5e-6 * 5.5e-6 / (6.0 * std::f64::consts::PI * 1.0e-3);

/// One problem: its scene for a scheme and dt, and the error of a finished simulation.
pub struct Problem {
    pub name: &'static str,
    pub description: &'static str,
    pub dts: Vec<f64>,
    scene: fn(Scheme, f64) -> String,
}

fn integration(scheme: Scheme, dt: f64, end: f64) -> String {
    let k = if scheme == Scheme::Respa { "slow_every = 4\n" } else { "" };
    format!("[integration]\nscheme = \"{scheme}\"\ndt = {dt:e}\nend_time = {end:e}\n{k}[output]\ninterval = {end:e}\n[stability]\nmax_step_fraction = 1.0\nmax_overlap = 0.5\n")
}

fn terminal_scene(scheme: Scheme, dt: f64) -> String {
    let material = material("saturation_magnetisation = 1.0e4\n");
    format!(
        "version = 1\n[domain]\nlo = [-1e-3, -1e-3, -1e-3]\nhi = [1e-3, 1e-3, 1e-3]\n[fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n\
         [field]\nb0 = [0.5, 0.0, 0.0]\ngradient = [[1.4, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n{material}\
         [[particles]]\nspecies = \"p\"\npositions = [[0.0, 0.0, 0.0]]\n[forces.gradient]\n[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n{}",
        integration(scheme, dt, 2.0 * TAU)
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
         [[particles]]\nspecies = \"p\"\npositions = [[-5.5005e-6, 0.0, 0.0], [5.5005e-6, 0.0, 0.0]]\nvelocities = [[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0]]\n\
         [forces.contact]\n{}",
        material(""),
        integration(scheme, dt, 1.28e-7)
    )
}

fn dipoles_scene(scheme: Scheme, dt: f64) -> String {
    let slow_every = if scheme == Scheme::Respa { 4 } else { 1 };
    crate::verify::magnetic::pair_before_contact(scheme, dt, slow_every) + "[stability]\nmax_step_fraction = 1.0\n"
}

fn separation(sim: &crate::core::simulation::Simulation) -> f64 {
    let p = &sim.state.particles;
    (p.position[1] - p.position[0]).norm()
}

pub fn problems() -> Vec<Problem> {
    vec![
        Problem {
            name: "terminal",
            description: "gradient-driven particle from rest, |v(2τ) − v_exact| / v_T",
            dts: (2..=8).map(|k| TAU / f64::powi(2.0, k)).collect(),
            scene: terminal_scene,
        },
        Problem {
            name: "hertz",
            description: "elastic head-on impact at 0.1 m/s, relative error of the largest overlap",
            dts: (0..7).map(|k| 1.6e-8 / f64::powi(2.0, k)).collect(),
            scene: hertz_scene,
        },
        Problem {
            name: "dipoles",
            description:
                "two dipoles closing (exact induction) for 96 µs, error of the separation / distance travelled",
            dts: (0..6).map(|k| 6.4e-8 / f64::powi(2.0, k)).collect(),
            scene: dipoles_scene,
        },
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
            let (m_eff, r_eff, e_star, v) =
                (s.mass() / 2.0, s.radius / 2.0, s.youngs_modulus / (2.0 * (1.0 - s.poisson_ratio.powi(2))), 0.1);
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

/// Error against run time on the two-dipole approach (`reference`: its reference separation):
/// each integrator over its dt range, and the adaptive integrator over tolerances (largest step
/// 6.4e-8 s); median of 5 runs, the spread (min–max) in the table.
fn work_precision(dir: &Path, problem: &Problem, reference: f64) -> Result<String, Box<dyn std::error::Error>> {
    let mut md = String::from(
        "## Work–precision: error against run time\n\nThe two-dipole approach (a trajectory quantity before any contact, so \
         no chaos): error of the final separation against run time, median of 5 runs per point (min–max in brackets), one \
         line per integrator over its dt range; `adaptive-verlet` over tolerances 1e-4…1e-8 of a radius at a largest step \
         of 6.4e-8 s.\n\n| scheme | setting | error | run time, median (min–max) |\n|---|---|---|---|\n",
    );
    let mut series = vec![];
    let adaptive = Scheme::AdaptiveVerlet;
    for scheme in SCHEMES.into_iter().chain([adaptive]) {
        let settings: Vec<(String, f64)> = if scheme == adaptive {
            [1e-4, 1e-5, 1e-6, 1e-7, 1e-8].iter().map(|&tol| (format!("tolerance {tol:.0e}"), tol)).collect()
        } else {
            problem.dts.iter().map(|&dt| (format!("dt {dt:.1e}"), dt)).collect()
        };
        let mut line = vec![];
        for (label, value) in settings {
            let (result, median, lo, hi) = timed(5, || {
                if scheme == adaptive {
                    let text =
                        dipoles_scene(adaptive, 6.4e-8).replace("dt = ", &format!("tolerance = {value:e}\ndt = "));
                    run_text(&text, adaptive.name()).map(|sim| dipoles_error(&sim, reference))
                } else {
                    run_problem(problem, scheme, value, Some(reference))
                }
            });
            if let Ok(err) = result {
                let _ = writeln!(md, "| {scheme} | {label} | {err:.2e} | {median:.3} s ({lo:.3}–{hi:.3}) |");
                if err > 0.0 {
                    line.push((median.log10(), err.log10()));
                }
            }
        }
        let color = colour(scheme);
        series.push(Series::markers(scheme.name(), line.clone(), color, 4));
        series.push(Series::line("", line, color));
    }
    line_chart_with_legend(
        &dir.join("work-precision-dipoles.png"),
        "Work–precision: two-dipole approach",
        "log10 run time (s, median of 5)",
        "log10 error",
        &series,
        SeriesLabelPosition::UpperRight,
    )?;
    md += "\n![Work–precision](work-precision-dipoles.png)\n\n";
    Ok(md)
}

/// Least-squares slope of log error on log dt.
pub fn fitted_order(points: &[(f64, f64)]) -> f64 {
    let pts: Vec<(f64, f64)> = points.iter().filter(|p| p.1 > 0.0).map(|p| (p.0.ln(), p.1.ln())).collect();
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>()
}

/// One of the paper's observables, measured per run, and the experiment that runs it per
/// integrator and step against a reference ensemble (run separately; read when present).
struct Observable {
    experiment: &'static str,
    /// Section heading after "The paper's observable: ".
    title: &'static str,
    /// The runs' setting and the reference, after "From the runs of `experiment` (".
    setting: &'static str,
    /// Column heading of the value, with its unit.
    quantity: &'static str,
    minutes: u32,
    figure: &'static str,
    value: fn(&crate::report::runs::Run) -> f64,
}

const OBSERVABLES: [Observable; 2] = [
    Observable {
        experiment: "experiments/accuracy/case1-observable.toml",
        title: "case-1 mean aggregate length at 5 ms",
        setting: "0.563 mg/ml, every term of the paper; reference: exponential Verlet at dt = 2.5e-9 s, a quarter of the working step",
        quantity: "mean length (µm)",
        minutes: 11,
        figure: "work-precision-case1.png",
        value: |r| r.mean_length_um(),
    },
    Observable {
        experiment: "experiments/accuracy/case2-observable.toml",
        title: "case-2 mean aggregate velocity at 1.25 s",
        setting: "55 spheres of 5.5 µm, every term of the paper; velocity along the gradient tracked over the last tenth of the run, free aggregates only, as in the Table 2 reproduction; reference: r-RESPA K = 10 at dt = 1.25e-8 s, a quarter of the working step",
        quantity: "mean velocity (µm/s)",
        minutes: 30,
        figure: "work-precision-case2.png",
        value: |r| crate::analysis::stats::summary(&r.free_velocities_um_per_s(1)).mean,
    },
];

/// Work–precision on one observable from the runs of its experiment: per variant the paired
/// relative difference to the reference run of the same seed, its CI95 over seeds, and the
/// median wall time per run.
fn observable_section(dir: &Path, o: &Observable) -> Result<String, Box<dyn std::error::Error>> {
    use crate::analysis::stats::{ci95_half_width, summary};
    let runs = crate::report::runs::load_runs(&[std::path::PathBuf::from(o.experiment)], 1e-3)?;
    let reference: Vec<_> = runs.iter().filter(|r| r.variant == "reference" && r.completed()).collect();
    if reference.is_empty() {
        return Ok(format!(
            "## The paper's observable: {}\n\nNot run yet: `magdem experiment {}` (about {} minutes on 2 cores), then this study again.\n\n",
            o.title, o.experiment, o.minutes
        ));
    }
    let mut md = format!(
        "## The paper's observable: {}\n\nFrom the runs of `{}` ({}; seeds {}): each integrator at its working step against the reference ensemble. The observable varies from seed to seed, so the error is the **paired** difference (X − X_ref)/X_ref of runs with the same seed (the same initial positions), averaged over seeds with its 95% confidence interval; wall time is per run (median, min–max), both cores busy with two runs at a time.\n\n\
         | variant | integrator, dt | runs | {} ± CI95 | paired difference to the reference (%) ± CI95 | per seed (%) | seeds needed to resolve 1% | wall time per run (s) |\n|---|---|---|---|---|---|---|---|\n",
        o.title,
        o.experiment,
        o.setting,
        reference.iter().map(|r| r.seed.to_string()).collect::<Vec<_>>().join(", "),
        o.quantity
    );
    let mut variants: Vec<&str> = vec![];
    for r in &runs {
        if !variants.contains(&r.variant.as_str()) {
            variants.push(&r.variant);
        }
    }
    let mut points = vec![];
    for variant in variants {
        let mine: Vec<_> = runs.iter().filter(|r| r.variant == variant).collect();
        let done: Vec<_> = mine.iter().filter(|r| r.completed()).collect();
        let setting = mine.first().map_or(String::new(), |r| r.variant_overrides.join(", "));
        if done.is_empty() {
            let why = mine
                .iter()
                .find(|r| !r.message.is_empty())
                .map_or(mine.first().map_or("missing".into(), |r| r.status.clone()), |r| r.message.clone());
            let _ = writeln!(md, "| {variant} | {setting} | 0 of {} | – | – | – | – | {why} |", mine.len());
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
        let wall = crate::bench::Spread::of(&times);
        let (diff, ci) = (summary(&paired).mean, ci95_half_width(&paired));
        let needed = if variant == "reference" {
            "–".to_string()
        } else {
            format!("{:.0}", (1.96 * summary(&paired).sample_std / 1.0).powi(2).ceil())
        };
        let _ = writeln!(
            md,
            "| {variant} | {setting} | {} of {} | {:.1} ± {:.1} | {} | {} | {needed} | {:.1} ({:.1}–{:.1}) |",
            done.len(),
            mine.len(),
            summary(&values).mean,
            ci95_half_width(&values),
            if variant == "reference" { "0 (by definition)".to_string() } else { format!("{diff:+.1} ± {ci:.1}") },
            if variant == "reference" {
                "–".to_string()
            } else {
                paired.iter().map(|d| format!("{d:+.1}")).collect::<Vec<_>>().join(", ")
            },
            wall.median,
            wall.min,
            wall.max
        );
        if variant != "reference" {
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
        &format!("Work–precision: {}", o.title),
        "log10 wall time per run (s)",
        "paired difference to the reference (%), CI95",
        &series,
        SeriesLabelPosition::UpperRight,
    )?;
    let _ = writeln!(md, "\n![work-precision on the {}]({})\n", o.title, o.figure);
    md += "\"Seeds needed to resolve 1%\" is (1.96 s/1%)² with s the sample standard deviation of the paired differences: how many seeds a CI95 of ±1% on the difference would take. A difference whose CI contains 0 is not distinguishable from the reference at this ensemble size. A per-seed difference of exactly 0 means the run ended with the reference's aggregates: where that holds the observable does not hinge on small integration errors, and a few seeds measure an integrator's bias. Where per-seed differences scatter far beyond the mean difference, a change of integrator or step changes which aggregates form (the observable is chaotic seed by seed): paired runs then do not isolate a bias, and the settings can only be told apart by many more seeds.\n\n";
    Ok(md)
}

/// Every problem × scheme × dt, then the observables' work–precision; writes `dir/README.md` and
/// one figure per problem and observable.
pub fn study(dir: &Path) -> Result<String, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let mut md = String::from("# Accuracy against time step\n\n");
    let _ = writeln!(
        md,
        "Generated by `magdem study accuracy` (magdem {}, commit {}). Each problem runs at a range of time steps with \
         each integrator; the error is plotted on log–log axes and the observed order is the least-squares slope over \
         the stable points. `respa` uses K = 4 (magnetic forces every 4 steps); where a problem has no magnetic force it \
         is velocity Verlet, so it is left out of the Hertz problem. Missing points: the run went unstable (the solver stopped it).\n",
        env!("CARGO_PKG_VERSION"),
        env!("MAGDEM_GIT_COMMIT")
    );
    let mut work = None;
    for problem in problems() {
        let reference = if problem.name == "dipoles" {
            Some(separation(&run_text(&dipoles_scene(Scheme::ExponentialVerlet, 1e-10), "reference")?))
        } else {
            None
        };
        let _ = writeln!(
            md,
            "## {}: {}\n\n| scheme | observed order | errors (dt: error) |\n|---|---|---|",
            problem.name, problem.description
        );
        let mut series = vec![];
        for scheme in SCHEMES {
            // Without a magnetic force respa is velocity Verlet (and would sample the overlap only
            // every K steps).
            if scheme == Scheme::Respa && problem.name == "hertz" {
                continue;
            }
            let points: Vec<(f64, f64)> = problem
                .dts
                .iter()
                .filter_map(|&dt| run_problem(&problem, scheme, dt, reference).ok().map(|e| (dt, e)))
                .collect();
            // Errors at round-off level (the scheme is exact for the problem) carry no order.
            let fit: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1 > 1e-12).collect();
            let order = if fit.len() >= 3 { format!("{:.2}", fitted_order(&fit)) } else { "exact".into() };
            let _ = writeln!(
                md,
                "| {scheme} | {order} | {} |",
                points.iter().map(|(dt, e)| format!("{dt:.2e}: {e:.2e}")).collect::<Vec<_>>().join(", ")
            );
            series.push(Series {
                label: format!("{scheme} ({order})"),
                points: points.iter().filter(|p| p.1 > 0.0).map(|(dt, e)| (dt.log10(), e.log10())).collect(),
                color: colour(scheme),
                markers: if matches!(scheme, Scheme::ExponentialVerlet | Scheme::Respa) { Some(4) } else { None },
                errors: vec![],
            });
        }
        let figure = format!("convergence-{}.png", problem.name);
        line_chart_with_legend(
            &dir.join(&figure),
            &format!("Error against time step: {}", problem.name),
            "log10 dt (s)",
            "log10 error",
            &series,
            SeriesLabelPosition::LowerRight,
        )?;
        let _ = writeln!(md, "\n![{}]({figure})\n", problem.name);
        if let Some(reference) = reference {
            work = Some(work_precision(dir, &problem, reference)?);
        }
    }
    md += &work.unwrap_or_default();
    for observable in &OBSERVABLES {
        md += &observable_section(dir, observable)?;
    }
    md += "Cost per step against N, per force term (criterion: `cargo bench --bench kernels`) and against LIGGGHTS and LAMMPS: [../performance.md](../performance.md).\n\n";
    md += "## Reading it\n\n\
- **Velocity Verlet is first order here**, not second: the drag is evaluated with the half-step velocity (as \
LAMMPS' and LIGGGHTS' `nve/sphere` do with `fix viscous`), which is O(dt) off, and wherever drag matters — every \
scene of the paper — that error dominates. Without velocity-dependent forces (the Hertz impact) it is second order. \
`respa` inherits this.\n\
- **Exponential Verlet** solves the linear drag exactly: exact for the terminal velocity at any dt and second order \
on the magnetic approach, with errors 500× smaller than Verlet's at the same dt.\n\
- **Explicit Euler** (the paper's) is first order everywhere and, on the Hertz impact, 20 to 500 times less accurate \
than the symplectic schemes at the same dt; semi-implicit Euler equals Verlet on the Hertz overlap (without \
velocity-dependent forces they produce the same positions).\n\
- The Hertz orders are noisy because the largest overlap is sampled at the steps.\n\
- **Work–precision**: on the magnetic approach exponential Verlet reaches a given error 10–1000 times sooner than \
any other scheme; `respa` (K = 4 here) takes a third of Verlet's time at the same error. `adaptive-verlet` does \
not improve as its tolerance tightens: its step-doubling estimate compares Verlet with Verlet, and Verlet's \
first-order drag error is the same in both, so the controller never sees it (it does see contacts: the impact \
test in tests/integrators.rs).\n";
    std::fs::write(dir.join("README.md"), &md)?;
    Ok(md)
}
