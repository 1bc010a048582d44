//! `magdem study stability`: how large a step each integrator survives, measured, against the
//! estimates (Rayleigh time, 2/ω of the contact oscillator, drag relaxation time); stiff and
//! extreme cases, each run to its end or to the solver's own stop; and the error of the dipole
//! sum's cut-off and induction levels.
//!
//! Stability map: two 11 µm Fe3O4 spheres in water one diameter apart along the field, closing
//! at the impact speed the estimate expects for that field (so weak fields still collide within
//! the run), Stokes drag, exact induction, restitution 0.5. A step dt is stable when the run
//! reaches its end (a gap's travel plus 20 contact durations) without a non-finite value or an
//! overlap above half a diameter, and the final relative speed does not exceed the impact speed
//! (a dissipative collision cannot gain energy). dt is scanned on a grid of factor √2 upward
//! from 1/32 of the estimate; the largest stable dt is the last one before the first failure.

use crate::core::integrators::{
    ExplicitEulerSpec, ExponentialVerletSpec, RespaSpec, Scheme, SemiImplicitEulerSpec, VelocityVerletSpec,
};
use crate::plot::{line_chart_with_legend, palette, Legend, RGBColor, Series};
use crate::scene::spec::scheme_lines;
use crate::scene::Scene;
use minijinja::context;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// The fixed-step integrators. `adaptive-verlet` is not mapped: its dt is only a cap that its
/// error control splits into substeps, so a largest stable dt is not a property of it.
pub const SCHEMES: [Scheme; 5] = [
    Scheme::ExplicitEuler(ExplicitEulerSpec {}),
    Scheme::SemiImplicitEuler(SemiImplicitEulerSpec {}),
    Scheme::VelocityVerlet(VelocityVerletSpec {}),
    Scheme::ExponentialVerlet(ExponentialVerletSpec {}),
    Scheme::Respa(RespaSpec { slow_every: RESPA_K }),
];
/// `respa` in the map evaluates the moments and dipole forces every `RESPA_K` steps (the
/// paper-scene setting).
const RESPA_K: u64 = 10;
pub const MODULI: [f64; 6] = [1e6, 1e7, 1e8, 1e9, 1e10, 1e11];
pub const FIELDS: [f64; 4] = [0.005, 0.05, 0.4, 1.5];
/// The map's restitution coefficient.
pub const RESTITUTION: f64 = 0.5;
/// A run lasts a gap's travel plus this many contact durations.
pub const CONTACT_DURATIONS: f64 = 20.0;
/// Physical bounds of a stable collision: closing speed below `SPEED_MARGIN` × the expected
/// impact speed, overlap below `OVERLAP_MARGIN` × Hertz's at that speed.
pub const SPEED_MARGIN: f64 = 1.5;
pub const OVERLAP_MARGIN: f64 = 2.0;
/// The dt scan: `GRID_POINTS` steps by factors of √2 from 1/`START_DIVISOR` of the estimate,
/// below 1/`RUN_DIVISOR` of the run.
pub const START_DIVISOR: f64 = 32.0;
pub const GRID_POINTS: i32 = 24;
pub const RUN_DIVISOR: f64 = 4.0;
/// A dt that needs more steps than this is counted stable without a run.
pub const MAX_STEPS: f64 = 2e6;
/// The solver's overlap limit in the map's scenes (of the smaller diameter).
pub const MAX_OVERLAP: f64 = 0.5;
/// Slowest closing speed the map starts a pair at (m/s).
pub const MIN_SPEED: f64 = 1e-3;
/// The paper's setting: explicit Euler with E = `PAPER_E` (Pa) at dt = `PAPER_DT` (s).
pub const PAPER_E: f64 = 1e9;
pub const PAPER_DT: f64 = 1e-6;
/// The cut-off study's scene (case 1) at this concentration (mg/ml) and field (T).
pub const CUTOFF_CONCENTRATION: f64 = 4.5;
pub const CUTOFF_FIELD: f64 = 0.4;

type Error = Box<dyn std::error::Error>;

/// The case-1 species with restitution [`RESTITUTION`].
fn species(youngs_modulus: f64, extra: &str) -> String {
    super::fe3o4(youngs_modulus, RESTITUTION, extra)
}

const WATER: &str = "[fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n";

/// The collision scene; `speed` is the closing speed (m/s), `end` the run time (s).
fn collision(scheme: Scheme, youngs_modulus: f64, b0: f64, dt: f64, speed: f64, end: f64) -> String {
    // respa runs whole slow steps: the run is rounded up to a multiple of K dt.
    let k = scheme.spec().slow_every();
    let end = if k > 1 { (end / (k as f64 * dt)).ceil() * k as f64 * dt } else { end };
    let scheme = scheme_lines(&scheme);
    format!(
        "version = 1\n[domain]\nlo = [-1e-4, -5e-5, -5e-5]\nhi = [1e-4, 5e-5, 5e-5]\n{WATER}[field]\nb0 = [{b0:e}, 0.0, 0.0]\n{}\
         [[particles]]\nspecies = \"p\"\npositions = [[-1.1e-5, 0.0, 0.0], [1.1e-5, 0.0, 0.0]]\n\
         velocities = [[{v:e}, 0.0, 0.0], [-{v:e}, 0.0, 0.0]]\n[forces.contact]\n[forces.dipole]\ninduction = \"exact\"\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[integration]\n{scheme}dt = {dt:e}\nend_time = {end:e}\n\
         [output]\ninterval = {end:e}\n[stability]\nmax_overlap = {MAX_OVERLAP:?}\nmax_step_fraction = 1.0\n",
        species(youngs_modulus, ""),
        v = 0.5 * speed
    )
}

/// One point of the map: the estimate and the measured largest stable dt (`at_grid_top`: the
/// scan's largest dt was still stable, so the bound is at least that).
pub struct MapPoint {
    pub scheme: Scheme,
    pub youngs_modulus: f64,
    pub b0: f64,
    pub impact_speed: f64,
    pub estimate: f64,
    pub rayleigh: f64,
    pub measured: f64,
    /// A dt above the first failure that was stable again (stability is not monotonic there).
    pub non_monotonic: bool,
    pub at_grid_top: bool,
}

/// Largest Hertz overlap of the pair at closing speed `v`: (15 m* v²/(16 E* √R*))^(2/5).
fn hertz_overlap(e: f64, v: f64) -> f64 {
    let (a, rho, nu) = (5.5e-6_f64, 1087.0, 0.5);
    let m_eff = rho * 4.0 / 3.0 * std::f64::consts::PI * a.powi(3) / 2.0;
    let e_eff = e / (2.0 * (1.0 - nu * nu));
    (15.0 * m_eff * v * v / (16.0 * e_eff * (a / 2.0).sqrt())).powf(0.4)
}

fn stable(scheme: Scheme, e: f64, b0: f64, dt: f64, speed: f64, end: f64) -> bool {
    let Ok(scene) = Scene::parse(&collision(scheme, e, b0, dt, speed, end), "stability map") else { return false };
    let mut sim = scene.simulation(None);
    if sim.initialise().is_err() {
        return false;
    }
    // Physical bounds of the collision: the closing speed cannot exceed what the field adds to
    // the initial speed (the estimate's impact speed is already that bound; 1.5× leaves room for
    // its approximations), and the overlap cannot exceed Hertz's at that speed by much.
    let (speed_limit, overlap_limit) = (SPEED_MARGIN * speed, OVERLAP_MARGIN * hertz_overlap(e, SPEED_MARGIN * speed));
    while sim.state.step < scene.total_steps() {
        if sim.step().is_err() {
            return false;
        }
        let p = &sim.state.particles;
        let gap = (p.position[1] - p.position[0]).norm() - 1.1e-5;
        if (p.velocity[1] - p.velocity[0]).norm() > speed_limit || -gap > overlap_limit {
            return false;
        }
    }
    true
}

/// Measures one point of the map.
pub fn map_point(scheme: Scheme, e: f64, b0: f64) -> Result<MapPoint, String> {
    // The estimate at rest gives the impact speed the field produces; the scan then starts the
    // particles at that speed.
    let probe = Scene::parse(&collision(scheme, e, b0, 1e-9, 0.0, 1e-6), "stability map").map_err(|e| e.to_string())?;
    let speed = probe.estimate.impact_speed.max(MIN_SPEED);
    let scene =
        Scene::parse(&collision(scheme, e, b0, 1e-9, speed, 1e-6), "stability map").map_err(|e| e.to_string())?;
    let est = &scene.estimate;
    let contact = est.contact_duration.unwrap_or(est.rayleigh_time);
    let end = 1.1e-5 / speed + CONTACT_DURATIONS * contact;
    let start = est.stable_dt / START_DIVISOR;
    let grid: Vec<f64> =
        (0..GRID_POINTS).map(|k| start * 2f64.powf(k as f64 / 2.0)).filter(|&dt| dt < end / RUN_DIVISOR).collect();
    let results: Vec<bool> =
        grid.iter().map(|&dt| end / dt > MAX_STEPS || stable(scheme, e, b0, dt, speed, end)).collect();
    let first_failure = results.iter().position(|ok| !ok);
    let measured = match first_failure {
        Some(0) => {
            // Unstable already at 1/32 of the estimate: scan down.
            (1..12)
                .map(|k| start / 2f64.powf(k as f64 / 2.0))
                .find(|&dt| end / dt > MAX_STEPS || stable(scheme, e, b0, dt, speed, end))
                .unwrap_or(f64::NAN)
        }
        Some(k) => grid[k - 1],
        None => grid.last().copied().unwrap_or(f64::NAN),
    };
    let non_monotonic = first_failure.is_some_and(|k| results[k..].iter().any(|&ok| ok));
    let at_grid_top = first_failure.is_none();
    Ok(MapPoint {
        scheme,
        youngs_modulus: e,
        b0,
        impact_speed: speed,
        estimate: est.stable_dt,
        rayleigh: est.rayleigh_time,
        measured,
        non_monotonic,
        at_grid_top,
    })
}

/// One stiff or extreme case and what the solver did with it.
pub struct Extreme {
    pub name: &'static str,
    pub setting: String,
    pub outcome: String,
}

fn crowd(
    youngs_modulus: f64,
    b0: f64,
    extra_species: &str,
    particles: &str,
    forces: &str,
    integration: &str,
) -> String {
    format!(
        "version = 1\nseed = 3\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [1.5e-4, 1.5e-4, 1.5e-4]\n{WATER}[field]\nb0 = [{b0:e}, 0.0, 0.0]\n{}\
         {particles}[forces.contact]\nwalls = true\n{forces}[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n{integration}",
        species(youngs_modulus, extra_species)
    )
}

const CROWD: &str = "[[particles]]\nspecies = \"p\"\ncount = 60\n";
const PAPER_DIPOLE: &str = "[forces.dipole]\ninduction = \"paper\"\ncutoff_diameters = 15.0\n";
const VERLET_1E8: &str =
    "[integration]\nscheme = \"velocity-verlet\"\ndt = 1.0e-8\nend_time = 2.0e-4\n[output]\ninterval = 2.0e-5\n";

fn run_case(name: &'static str, setting: &str, text: &str) -> Extreme {
    let outcome = match Scene::parse(text, name) {
        Err(e) => format!("refused at load: {e}"),
        Ok(scene) => {
            let mut sim = scene.simulation(None);
            let mut result = sim.initialise();
            while result.is_ok() && sim.state.step < scene.total_steps() {
                result = sim.step();
            }
            let p = &sim.state.particles;
            let finite = p.position.iter().chain(&p.velocity).all(|v| v.iter().all(|c| c.is_finite()));
            match result {
                Ok(()) if finite => format!(
                    "completed {} steps; largest speed {:.3e} m/s; estimated stable dt {:.2e} s ({})",
                    sim.state.step,
                    p.velocity.iter().map(|v| v.norm()).fold(0.0, f64::max),
                    scene.estimate.stable_dt,
                    scene.estimate.limited_by
                ),
                Ok(()) => "completed with non-finite values (a solver bug)".into(),
                Err(e) => format!("stopped: {e}"),
            }
        }
    };
    Extreme { name, setting: setting.into(), outcome }
}

/// The stiff and extreme cases the issue lists, each at the case-1 defaults otherwise (60
/// particles in a 150 µm box, 0.4 T, Verlet at dt = 1e-8 s, 0.2 ms).
pub fn extremes() -> Vec<Extreme> {
    let base = |e: f64, b0: f64| crowd(e, b0, "", CROWD, PAPER_DIPOLE, VERLET_1E8);
    let pair = |offset: f64| {
        format!(
            "version = 1\n[domain]\nlo = [-1e-4, -5e-5, -5e-5]\nhi = [1e-4, 5e-5, 5e-5]\n{WATER}[field]\nb0 = [0.4, 0.0, 0.0]\n{}\
             [[particles]]\nspecies = \"p\"\npositions = [[-{x:e}, 0.0, 0.0], [{x:e}, 0.0, 0.0]]\n[forces.contact]\n{PAPER_DIPOLE}\
             [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n{VERLET_1E8}",
            species(1e9, ""),
            x = 5.5e-6 * (1.0 - offset)
        )
    };
    // Settling under gravity alone (no field, no contact), so the drag relaxation time is the
    // only time scale that bounds dt.
    let tiny = |scheme: &str| {
        format!(
            "version = 1\nseed = 3\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [3.0e-6, 3.0e-6, 3.0e-6]\n{WATER}{}\
             [[particles]]\nspecies = \"p\"\ncount = 10\n[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[forces.gravity]\n\
             [integration]\nscheme = \"{scheme}\"\ndt = 1.0e-8\nend_time = 1.0e-5\n[output]\ninterval = 1.0e-6\n",
            species(1e9, "").replace("diameter = 11.0e-6", "diameter = 0.2e-6")
        )
    };
    vec![
        run_case("reference", "E = 1e9 Pa, 0.4 T (the case-1 material and field)", &base(1e9, 0.4)),
        run_case("stiff contact", "E = 1e11 Pa", &base(1e11, 0.4)),
        run_case("strong field", "B0 = 1.5 T (linear M = 2.8e6 A/m)", &base(1e9, 1.5)),
        run_case(
            "strong induction",
            "μr = 1000 (χ_eff → 3, the induction limit), exact induction",
            &crowd(1e9, 0.4, "", CROWD, "[forces.dipole]\ninduction = \"exact\"\n", VERLET_1E8)
                .replace("relative_permeability = 12.3", "relative_permeability = 1000.0"),
        ),
        run_case("starting in contact", "two spheres touching at t = 0", &pair(0.0)),
        run_case("starting overlapped", "two spheres overlapping by 5% of a diameter at t = 0", &pair(0.05)),
        run_case(
            "dense packing",
            "250 particles in a 100 µm box (solid fraction 0.17)",
            &base(1e9, 0.4)
                .replace("count = 60", "count = 250")
                .replace("hi = [1.5e-4, 1.5e-4, 1.5e-4]", "hi = [1.0e-4, 1.0e-4, 1.0e-4]"),
        ),
        run_case(
            "tiny particles, Verlet",
            "10 spheres of 0.2 µm settling under gravity (drag relaxation 2.4e-9 s), velocity Verlet at 1e-8 s",
            &tiny("velocity-verlet"),
        ),
        run_case(
            "tiny particles, exponential",
            "the same with exponential Verlet at 1e-8 s (drag exact)",
            &tiny("exponential-verlet"),
        ),
        run_case("very large step", "Verlet at dt = 1e-5 s", &base(1e9, 0.4).replace("dt = 1.0e-8", "dt = 1.0e-5")),
    ]
}

/// Dipole forces of one configuration under an induction level and cut-off, with the moments
/// iterated to the level's own fixed point (the paper's scheme converges over steps).
fn dipole_forces(
    positions: &[[f64; 3]],
    induction: &str,
    cutoff: Option<f64>,
) -> Result<Vec<nalgebra::Vector3<f64>>, Error> {
    let list = positions.iter().map(|x| format!("[{:e}, {:e}, {:e}]", x[0], x[1], x[2])).collect::<Vec<_>>().join(", ");
    let cut = cutoff.map_or(String::new(), |c| format!("cutoff_diameters = {c}\n"));
    let text = format!(
        "version = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [3.96e-4, 3.96e-4, 3.3e-4]\n[field]\nb0 = [{CUTOFF_FIELD:e}, 0.0, 0.0]\n{}\
         [[particles]]\nspecies = \"p\"\npositions = [{list}]\n[forces.dipole]\ninduction = \"{induction}\"\n{cut}\
         [integration]\ndt = 1.0e-8\nend_time = 1.0e-8\n",
        species(1e9, "")
    );
    let scene = Scene::parse(&text, "cut-off")?;
    let mut field = scene.magnetic_force_field().ok_or("no magnetic terms")?;
    let mut state = scene.initial_state();
    for _ in 0..if induction == "paper" { 60 } else { 1 } {
        field.evaluate(&mut state, 1e-8);
    }
    Ok(state.fields.force)
}

/// The cut-off study's settings the report names.
const PAPER_SCHEME: &str = "paper induction, 15 d force cut-off (the paper's scheme)";
const EXACT_CUT: &str = "exact induction, 15 d force cut-off";
const NO_INDUCTION: &str = "no induction, all pairs";

/// Relative errors (RMS over particles of |F − F_ref| / RMS |F_ref|, and the largest per
/// particle relative to RMS |F_ref|) of induction/cut-off settings against exact induction over
/// all pairs, on the case-1 box at 4.5 mg/ml: random placement, and the same particles gathered
/// into chains along the field.
pub fn cutoff_errors() -> Result<Vec<(String, &'static str, f64, f64)>, Error> {
    let scene = Scene::parse(
        &std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR"))
                .join(format!("experiments/scenes/case1-c{CUTOFF_CONCENTRATION}.toml")),
        )?,
        "cut-off scene",
    )?;
    let random: Vec<[f64; 3]> = scene.initial.position.iter().map(|x| [x.x, x.y, x.z]).collect();
    // Chains of 10 touching spheres along x from the first tenth of the random positions.
    let d = 11.0e-6;
    let chained: Vec<[f64; 3]> = random
        .iter()
        .take(random.len() / 10)
        .flat_map(|x| {
            (0..10).map(move |k| {
                [
                    (x[0] % (3.96e-4 - 11.0 * d)) + d + k as f64 * d * 1.0001,
                    x[1].clamp(d, 3.96e-4 - d),
                    x[2].clamp(d, 3.3e-4 - d),
                ]
            })
        })
        .collect();
    let chained: Vec<[f64; 3]> = chained
        .iter()
        .enumerate()
        .filter(|(i, x)| {
            chained[..*i]
                .iter()
                .all(|y| ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt() > d * 1.00005)
        })
        .map(|(_, x)| *x)
        .collect();
    let mut rows = vec![];
    for (layout, positions) in [("random placement", &random), ("chains of up to 10", &chained)] {
        let reference = dipole_forces(positions, "exact", None)?;
        let scale = (reference.iter().map(|f| f.norm_squared()).sum::<f64>() / reference.len() as f64).sqrt();
        for (label, induction, cutoff) in [
            (PAPER_SCHEME, "paper", Some(15.0)),
            ("paper induction, 10 d force cut-off", "paper", Some(10.0)),
            ("paper induction, all pairs", "paper", None),
            (EXACT_CUT, "exact", Some(15.0)),
            (NO_INDUCTION, "none", None),
        ] {
            let forces = dipole_forces(positions, induction, cutoff)?;
            let diffs: Vec<f64> = forces.iter().zip(&reference).map(|(f, r)| (f - r).norm()).collect();
            let rms = (diffs.iter().map(|x| x * x).sum::<f64>() / diffs.len() as f64).sqrt() / scale;
            let max = diffs.iter().copied().fold(0.0, f64::max) / scale;
            rows.push((format!("{layout} ({} particles)", positions.len()), label, rms, max));
        }
    }
    Ok(rows)
}

/// One scheme's part of the stability map: its table and its figure (file name).
fn map_section(dir: &Path, points: &[MapPoint], scheme: Scheme) -> Result<minijinja::Value, Error> {
    let mut table = String::from("| E (Pa) | B0 (T) | impact speed (m/s) | Rayleigh time (s) | estimate (s) | measured (s) | measured / estimate |\n|---|---|---|---|---|---|---|\n");
    let mut series = vec![];
    let mut lower_bounds = vec![];
    for (k, &b) in FIELDS.iter().enumerate() {
        let here: Vec<&MapPoint> = points.iter().filter(|p| p.scheme == scheme && p.b0 == b).collect();
        for p in &here {
            let (measured, ratio) = if p.measured.is_nan() {
                ("none stable".to_string(), "–".to_string())
            } else {
                let bound = if p.at_grid_top { "≥ " } else { "" };
                (
                    format!("{bound}{:.2e}{}", p.measured, if p.non_monotonic { " ✱" } else { "" }),
                    format!("{bound}{:.2}", p.measured / p.estimate),
                )
            };
            let _ = writeln!(
                table,
                "| {:.0e} | {} | {:.2e} | {:.2e} | {:.2e} | {measured} | {ratio} |",
                p.youngs_modulus, p.b0, p.impact_speed, p.rayleigh, p.estimate
            );
        }
        series.push(Series::markers(
            format!("measured, {b} T"),
            here.iter()
                .filter(|p| p.measured.is_finite())
                .map(|p| (p.youngs_modulus.log10(), p.measured.log10()))
                .collect(),
            palette(k),
            5,
        ));
        series.push(Series::line(
            format!("estimate, {b} T"),
            here.iter().map(|p| (p.youngs_modulus.log10(), p.estimate.log10())).collect(),
            palette(k),
        ));
        lower_bounds
            .extend(here.iter().filter(|p| p.at_grid_top).map(|p| (p.youngs_modulus.log10(), p.measured.log10())));
    }
    series.push(Series::markers("lower bound (largest dt scanned was stable)", lower_bounds, RGBColor(0, 0, 0), 9));
    let rayleigh: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.scheme == scheme && p.b0 == FIELDS[0])
        .map(|p| (p.youngs_modulus.log10(), p.rayleigh.log10()))
        .collect();
    series.push(Series::line("Rayleigh time", rayleigh, palette(6)));
    if matches!(scheme, Scheme::ExplicitEuler(_)) {
        series.push(Series::markers(
            format!("the paper: E = {PAPER_E:.0e} Pa, dt = {PAPER_DT:.0e} s"),
            vec![(PAPER_E.log10(), PAPER_DT.log10())],
            RGBColor(0, 0, 0),
            4,
        ));
    }
    let figure = format!("stability-{scheme}.png");
    line_chart_with_legend(
        &dir.join(&figure),
        &format!("Largest stable dt: {scheme}"),
        "log10 Young's modulus (Pa)",
        "log10 dt (s)",
        &series,
        Legend::above_data(1.0),
    )?;
    Ok(context! { scheme => scheme.name(), table => table, figure => figure })
}

/// Where the paper's setting lies against one measured bound.
#[derive(Serialize)]
pub struct PaperPoint {
    pub b0: f64,
    pub measured: f64,
    /// The bound is only a lower bound: the scan's largest dt was stable.
    pub lower_bound: bool,
}

/// The paper's setting against the explicit-Euler map at E = [`PAPER_E`], by field: the fields
/// where `PAPER_DT` is above the measured bound, where no scanned dt was stable, where it is at or
/// below the bound, and where it is above a bound that is only a lower bound (undecided).
pub fn paper_setting(points: &[MapPoint]) -> (Vec<PaperPoint>, Vec<PaperPoint>, Vec<PaperPoint>, Vec<PaperPoint>) {
    let (mut above, mut none, mut below, mut undecided) = (vec![], vec![], vec![], vec![]);
    for p in points.iter().filter(|p| matches!(p.scheme, Scheme::ExplicitEuler(_)) && p.youngs_modulus == PAPER_E) {
        let point = PaperPoint { b0: p.b0, measured: p.measured, lower_bound: p.at_grid_top };
        if p.measured.is_nan() {
            none.push(point);
        } else if PAPER_DT <= p.measured {
            below.push(point);
        } else if p.at_grid_top {
            undecided.push(point);
        } else {
            above.push(point);
        }
    }
    (above, none, below, undecided)
}

fn min_max(xs: impl Iterator<Item = f64>) -> minijinja::Value {
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
    context! { min => lo, max => hi }
}

/// Runs the whole study and writes `dir/stability.md` (from `templates/accuracy/stability.md`)
/// with its figures.
pub fn study(dir: &Path) -> Result<String, Error> {
    use rayon::prelude::*;
    std::fs::create_dir_all(dir)?;
    let jobs: Vec<(Scheme, f64, f64)> = SCHEMES
        .iter()
        .flat_map(|&s| MODULI.iter().flat_map(move |&e| FIELDS.iter().map(move |&b| (s, e, b))))
        .collect();
    let points: Vec<MapPoint> = jobs
        .par_iter()
        .map(|&(s, e, b)| map_point(s, e, b))
        .collect::<Result<_, String>>()
        .map_err(|e| e.to_string())?;
    let sections: Vec<minijinja::Value> =
        SCHEMES.iter().map(|&s| map_section(dir, &points, s)).collect::<Result<_, Error>>()?;
    let found: Vec<&MapPoint> = points.iter().filter(|p| p.measured.is_finite() && !p.at_grid_top).collect();
    let bounded: Vec<&MapPoint> = points.iter().filter(|p| p.at_grid_top).collect();
    let none: Vec<&MapPoint> = points.iter().filter(|p| p.measured.is_nan()).collect();
    let unsafe_points: Vec<minijinja::Value> = found
        .iter()
        .filter(|p| p.measured < p.estimate)
        .map(|p| {
            context! { scheme => p.scheme.name(), e => p.youngs_modulus, b0 => p.b0, ratio => p.measured / p.estimate }
        })
        .collect();
    let (above, no_stable, below, undecided) = paper_setting(&points);
    let extremes = extremes();
    let mut extremes_table = String::from("| case | setting | outcome |\n|---|---|---|\n");
    for e in &extremes {
        let _ = writeln!(extremes_table, "| {} | {} | {} |", e.name, e.setting, e.outcome.replace('|', "/"));
    }
    let count = |prefix: &str| extremes.iter().filter(|e| e.outcome.starts_with(prefix)).count();
    let cutoff = cutoff_errors()?;
    let mut cutoff_table = String::from("| configuration | setting | RMS error | largest error |\n|---|---|---|---|\n");
    for (layout, label, rms, max) in &cutoff {
        let _ = writeln!(cutoff_table, "| {layout} | {label} | {rms:.2e} | {max:.2e} |");
    }
    let pick = |label: &str| {
        cutoff.iter().filter(|r| r.1 == label).map(|r| context! { rms => r.2, max => r.3 }).collect::<Vec<_>>()
    };
    let md = crate::report::template::render(
        "accuracy/stability.md",
        &context! {
            version => env!("CARGO_PKG_VERSION"),
            commit => env!("MAGDEM_GIT_COMMIT"),
            restitution => RESTITUTION,
            contact_durations => CONTACT_DURATIONS,
            speed_margin => SPEED_MARGIN,
            overlap_margin => OVERLAP_MARGIN,
            start_divisor => START_DIVISOR,
            grid_top => 2f64.powf((GRID_POINTS - 1) as f64 / 2.0) / START_DIVISOR,
            run_divisor => RUN_DIVISOR,
            down_divisor => START_DIVISOR * 2f64.powf(5.5),
            max_steps => MAX_STEPS,
            max_overlap => MAX_OVERLAP,
            respa_k => RESPA_K,
            moduli => MODULI.iter().map(|e| format!("{e:.0e}")).collect::<Vec<_>>(),
            fields => FIELDS,
            points => points.len(),
            sections => sections,
            found => found.len(),
            found_ratio => min_max(found.iter().map(|p| p.measured / p.estimate)),
            bounded => bounded.len(),
            bounded_ratio => min_max(bounded.iter().map(|p| p.measured / p.estimate)),
            no_stable => none.len(),
            no_stable_e_max => none.iter().map(|p| p.youngs_modulus).fold(0.0, f64::max),
            no_stable_b_min => none.iter().map(|p| p.b0).fold(f64::INFINITY, f64::min),
            no_stable_overlap => min_max(none.iter().map(|p| hertz_overlap(p.youngs_modulus, p.impact_speed) / 1.1e-5)),
            non_monotonic => points.iter().filter(|p| p.non_monotonic).count(),
            unsafe_points => unsafe_points,
            paper => context! {
                e => PAPER_E, dt => PAPER_DT,
                above => above, no_stable => no_stable, below => below, undecided => undecided,
            },
            extremes => extremes.len(),
            extremes_table => extremes_table,
            completed => count("completed "),
            stopped => count("stopped: "),
            refused => count("refused at load: "),
            cutoff_concentration => CUTOFF_CONCENTRATION,
            cutoff_field => CUTOFF_FIELD,
            cutoff_table => cutoff_table,
            paper_scheme => pick(PAPER_SCHEME),
            no_induction => pick(NO_INDUCTION),
            exact_cut => pick(EXACT_CUT),
        },
    )?;
    std::fs::write(dir.join("stability.md"), &md)?;
    Ok(md)
}
