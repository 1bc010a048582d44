//! `magdem report hydrodynamics`: the paper's shielded-area drag (A_eff) held against Stokes flow
//! with hydrodynamic interactions (the RPY mobility), in `reports/hydrodynamics/README.md`: the
//! drag of straight chains, the cost of the dense mobility, the error of refactorising it every K
//! steps, and case 1 and case 2 under each drag model from the runs of
//! `experiments/hydrodynamics/*.toml`. The numbers, tables and figures are computed here; the words
//! are `templates/hydrodynamics/README.md`.

use super::digest::load_runs_digested;
use super::estimate::{log_slope, sizes_and_velocities};
use super::runs::{experiment_files, Run};
use super::tables::{col, floats, frame, markdown, read_csv, scol, write};
use super::template::render;
use crate::analysis::aggregates::BOX_LIMITED_FRACTION;
use crate::analysis::stats::{ci95_half_width, summary};
use crate::analysis::timing::timed;
use crate::core::forces::hydrodynamics::Resistance;
use crate::core::forces::wall_drag::{parallel_factor, PlaneWall};
use crate::core::integrators::Scheme;
use crate::core::state::Vec3;
use crate::plot::{chart, palette, Legend, RGBColor, Scale, Series, SeriesLabelPosition};
use crate::scene::Scene;
use minijinja::{context, Value};
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

type Error = Box<dyn std::error::Error>;

pub struct HydrodynamicsReportOptions {
    /// Directory of the experiment files (`experiments/hydrodynamics`).
    pub experiments: PathBuf,
    /// The case-2 scene the refactorisation study shortens (`experiments/scenes/case2.toml`).
    pub case2_scene: PathBuf,
    /// The paper's tables (`reference/paper`): Table 2's experiment row, Table 3's lengths.
    pub reference: PathBuf,
    /// Report directory (`reports/hydrodynamics`).
    pub out: PathBuf,
    /// Aggregate gap tolerance (fraction of the smaller radius).
    pub gap: f64,
}

/// The drag models and size spreads of the case-2 experiments, by variant name, in the report's
/// order (the opt-in files' variants appear once their runs exist).
const MODELS: [(&str, &str); 13] = [
    ("a-eff", "Schiller–Naumann with the paper's A_eff"),
    ("no-shielding", "Schiller–Naumann, every sphere its own drag"),
    ("rpy", "Stokes flow with hydrodynamic interactions (RPY)"),
    ("a-eff-wall", "A_eff, substrate drag, M re-derived"),
    ("no-shielding-wall", "no shielding, substrate drag, M re-derived"),
    ("rpy-wall", "RPY above the substrate (Blake), M re-derived"),
    ("a-eff-wall-scene-m", "A_eff, substrate drag, the scene's M"),
    ("no-shielding-wall-scene-m", "no shielding, substrate drag, the scene's M"),
    ("rpy-wall-scene-m", "RPY above the substrate (Blake), the scene's M"),
    ("cv-0", "A_eff, equal diameters, gravity, raised lid"),
    ("cv-5", "A_eff, diameters with cv 5 %"),
    ("cv-10", "A_eff, diameters with cv 10 %"),
    ("cv-20", "A_eff, diameters with cv 20 %"),
];

/// The free-fluid, equal-diameter drag models of case 2 (the first rows of [`MODELS`]).
const FREE_FLUID: usize = 3;

/// Chains: spheres of this diameter (m) translating at this speed (m/s) in water, up to the
/// longest of these chains.
const CHAIN_DIAMETER: f64 = 5.5e-6;
const CHAIN_SPEED: f64 = 1.0e-5;
const CHAIN_SIZES: [usize; 9] = [1, 2, 3, 4, 5, 7, 10, 15, 20];
const WATER: (f64, f64) = (1000.0, 1.0e-3);
/// Stimson & Jeffery's exact drag on each of two touching spheres moving along their line of
/// centres, as a fraction of a lone sphere's Stokes drag.
const STIMSON_JEFFERY: f64 = 0.6452;
/// The gap a sphere resting on the substrate keeps, as a fraction of its radius (the wall drag's
/// `min_gap`).
const WALL_GAP: f64 = 0.01;
/// The cost study: particle counts, timing repeats (fewer above [`COST_FEW_ABOVE`] particles), and
/// the renewal intervals of the per-step cost.
const COST_SIZES: [usize; 3] = [55, 300, 1000];
const COST_REPEATS: (usize, usize, usize) = (3, 7, 15);
const COST_FEW_ABOVE: usize = 500;
const COST_RENEWALS: [f64; 2] = [10.0, 1000.0];
/// Particles of the quoted per-step cost (the case-1 scale).
const COST_QUOTED: usize = 300;
/// Memory of the dense mobility and resistance: two 3N × 3N matrices of f64.
const BYTES_PER_PAIR: f64 = 2.0 * 9.0 * 8.0;
/// The refactorisation study: case 2 with RPY under r-RESPA, for this long, at these intervals.
const REFACTOR_END: f64 = 1.0e-2;
const REFACTOR_SLOW_EVERY: u64 = 10;
const REFACTOR_INTERVALS: [u64; 4] = [1, 10, 100, 1000];
/// Case 1's early-growth comparison is at the frame nearest this time (s).
const EARLY: f64 = 1.0e-3;
/// Velocity classes: aggregates of at least this many particles are "large".
const LARGE: usize = 5;
/// Sizes with fewer aggregates than this (pooled over seeds) are left out of the fit of α.
const MIN_AGGREGATES: usize = 3;
/// The spread variants draw diameters from a normal law truncated at this many σ.
const TRUNCATION_SIGMAS: f64 = 3.0;
/// Case 1's concentration in the drag study (mg/ml), its row of the paper's Table 3.
const CASE1_CONCENTRATION: f64 = 2.25;
/// A run's scale for a report that estimates case 1 under RPY before its runs exist: steps of a
/// case-1 run (5 ms at 1e-8 s) and the renewal interval.
const CASE1_STEPS: f64 = 5.0e5;

/// The source of the wall's screening of the flow a sphere drives along it.
const BLAKE: &str = "Blake 1971";

/// Schiller–Naumann's correction to Stokes drag, `0.15 Re^0.687`.
fn schiller_naumann_correction(re: f64) -> f64 {
    0.15 * re.powf(0.687)
}

/// What the report quotes of a scene.
#[derive(Serialize)]
struct SceneFacts {
    particles: usize,
    diameter_um: f64,
    b0: f64,
    gradient: f64,
    end_time: f64,
    dt: f64,
    scheme: &'static str,
    slow_every: u64,
    box_um: f64,
    seed: u64,
    fluid_density: f64,
    viscosity: f64,
}

fn scene_facts(scene: &Scene) -> SceneFacts {
    let spec = &scene.spec;
    let field = spec.field.as_ref();
    let fluid = spec.fluid.as_ref();
    SceneFacts {
        particles: scene.initial.position.len(),
        diameter_um: 1e6 * spec.species.first().map_or(f64::NAN, |s| s.diameter),
        b0: field.map_or(f64::NAN, |f| f.b0.iter().map(|b| b * b).sum::<f64>().sqrt()),
        gradient: field.map_or(f64::NAN, |f| f.linear_gradient()[(0, 0)]),
        end_time: spec.integration.end_time,
        dt: spec.integration.dt,
        scheme: match spec.integration.scheme {
            Scheme::Respa(_) => "r-RESPA",
            Scheme::VelocityVerlet(_) => "velocity Verlet",
            _ => "another scheme",
        },
        slow_every: spec.integration.slow_every(),
        box_um: 1e6 * (spec.domain.hi[0] - spec.domain.lo[0]),
        seed: spec.seed,
        fluid_density: fluid.map_or(f64::NAN, |f| f.density),
        viscosity: fluid.map_or(f64::NAN, |f| f.viscosity),
    }
}

/// The scene of the first of `runs` with `variant`, parsed.
fn scene_of(runs: &[&Run], variant: &str) -> Result<Option<Scene>, Error> {
    match runs.iter().find(|r| r.variant == variant) {
        Some(r) => Ok(Some(Scene::parse(&r.scene_text, &r.id)?)),
        None => Ok(None),
    }
}

/// A variant override's value (`key = value`) among the runs of `variant`.
fn override_of<'a>(runs: &[&'a Run], variant: &str, key: &str) -> Option<&'a str> {
    let prefix = format!("{key} = ");
    runs.iter()
        .filter(|r| r.variant == variant)
        .find_map(|r| r.variant_overrides.iter().find_map(|o| o.strip_prefix(prefix.as_str())))
}

pub fn write_report(options: &HydrodynamicsReportOptions) -> Result<PathBuf, Error> {
    let out = &options.out;
    std::fs::create_dir_all(out)?;
    let tables = out.join("tables");
    let files = experiment_files(&options.experiments, true)?;
    let runs = load_runs_digested(&files, options.gap, &out.join("digests"))?;
    let chain = chain_section(out, &tables)?;
    let cost = cost_section(&tables)?;
    let refactor = refactor_section(&options.case2_scene, &tables)?;
    let case2 = case2_section(&runs, &options.reference.join("table2_case2.csv"), out, &tables)?;
    let case1 = case1_section(&runs, &options.reference.join("table3_case1_lengths.csv"), out, &tables)?;
    let ran = |variant: &str| {
        runs.iter().any(|r| r.completed() && r.experiment.starts_with("hydro-case2") && r.variant == variant)
    };
    let per_step = cost.per_step_quoted;
    let md = render(
        "hydrodynamics/README.md",
        &context! {
            version => env!("CARGO_PKG_VERSION"),
            commit => env!("MAGDEM_GIT_COMMIT"),
            blake => BLAKE,
            files => files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            chain => chain,
            cost => cost.value,
            refactor => refactor,
            case2 => case2,
            case1 => case1,
            missing => context! {
                wall => !ran("a-eff-wall"),
                rpy_wall => !ran("rpy-wall"),
                spread => !ran("cv-10"),
                case1 => !runs.iter().any(|r| r.completed() && r.experiment == "hydro-case1"),
                case1_per_step_ms => 1e3 * per_step,
                case1_run_minutes => CASE1_STEPS * per_step / 60.0,
                case1_steps => CASE1_STEPS,
            },
        },
    )?;
    let path = out.join("README.md");
    std::fs::write(&path, md)?;
    Ok(path)
}

/// The scene text of `n` touching spheres of diameter `d` on the x axis, all moving at `u`.
fn chain_scene(n: usize, d: f64, u: Vec3, drag: &str) -> String {
    let positions = (0..n).map(|k| format!("[{:e}, 0.0, 0.0]", d * k as f64)).collect::<Vec<_>>().join(", ");
    let velocities = vec![format!("[{:e}, {:e}, {:e}]", u.x, u.y, u.z); n].join(", ");
    format!(
        "version = 1\n[domain]\nlo = [-1e-3, -1e-3, -1e-3]\nhi = [1e-3, 1e-3, 1e-3]\n\
         [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n\
         [[species]]\nname = \"p\"\ndiameter = {d:e}\ndensity = 1050.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
         friction = 0.5\nrestitution = 0.5\n\
         [[particles]]\nspecies = \"p\"\npositions = [{positions}]\nvelocities = [{velocities}]\n\
         [forces.drag]\n{drag}\n[integration]\ndt = 1.0e-9\nend_time = 1.0e-8\n"
    )
}

/// Drag per sphere of a chain of `n` touching spheres moving along (`axis` 0) or across it, as
/// a fraction of a lone sphere's Stokes drag, through magdem's scene and force field.
fn chain_drag(n: usize, axis: usize, drag: &str) -> Result<f64, Error> {
    let (d, mu, speed) = (CHAIN_DIAMETER, WATER.1, CHAIN_SPEED);
    let mut u = Vec3::zeros();
    u[axis] = speed;
    let scene = Scene::parse(&chain_scene(n, d, u, drag), "chain")?;
    let mut sim = scene.simulation(None);
    sim.initialise()?;
    let total: f64 = sim.state.fields.force.iter().map(|f| -f[axis]).sum();
    Ok(total / n as f64 / (3.0 * PI * mu * d * speed))
}

/// The axial drag per sphere of a chain of `n` touching spheres resting on a wall (along it, at
/// the [`WALL_GAP`]) under RPY above the wall (N).
fn wall_chain_axial(n: usize) -> Result<f64, Error> {
    let (a, mu, speed) = (0.5 * CHAIN_DIAMETER, WATER.1, CHAIN_SPEED);
    let wall = PlaneWall { axis: 2, position: 0.0, side: 1.0, min_gap: WALL_GAP };
    let x: Vec<Vec3> = (0..n).map(|i| Vec3::new(2.0 * a * i as f64, 0.0, a)).collect();
    let r = Resistance::new(&x, &vec![a; n], mu, Some(&wall))?;
    Ok(-r.drag(&vec![Vec3::new(speed, 0.0, 0.0); n], |_| Vec3::zeros()).iter().map(|f| f.x).sum::<f64>() / n as f64)
}

/// The axial drag per sphere of a chain of `n` touching spheres resting on a wall under RPY above
/// the wall, as a fraction of a lone sphere's there.
fn wall_chain_drag(n: usize) -> Result<f64, Error> {
    Ok(wall_chain_axial(n)? / wall_chain_axial(1)?)
}

/// A lone sphere's drag along the wall under RPY above it, as a fraction of its free Stokes drag.
fn rpy_wall_factor() -> Result<f64, Error> {
    Ok(wall_chain_axial(1)? / (3.0 * PI * WATER.1 * CHAIN_DIAMETER * CHAIN_SPEED))
}

fn chain_section(out: &Path, tables: &Path) -> Result<Value, Error> {
    let sizes = CHAIN_SIZES;
    let (rpy, stokes_paper) = ("law = \"rpy\"\nshielding = \"none\"", "law = \"stokes\"\nshielding = \"paper\"");
    let mut cols: [Vec<f64>; 5] = Default::default();
    for &n in &sizes {
        cols[4].push(wall_chain_drag(n)?);
        cols[0].push(chain_drag(n, 0, rpy)?);
        cols[1].push(chain_drag(n, 1, rpy)?);
        cols[2].push(chain_drag(n, 0, stokes_paper)?);
        cols[3].push(chain_drag(n, 1, stokes_paper)?);
    }
    let n_col: Vec<f64> = sizes.iter().map(|&n| n as f64).collect();
    let mut df = frame(vec![
        col("spheres", n_col.clone()),
        col("rpy_axial_per_sphere", cols[0].clone()),
        col("rpy_broadside_per_sphere", cols[1].clone()),
        col("a_eff_axial_per_sphere", cols[2].clone()),
        col("a_eff_broadside_per_sphere", cols[3].clone()),
        col("rpy_on_wall_axial_per_sphere", cols[4].clone()),
    ])?;
    write(&mut df, tables, "chain_drag")?;
    let at = |v: &[f64], n: usize| v[sizes.iter().position(|&s| s == n).expect("listed size")];
    let longest = sizes[sizes.len() - 1];
    let series = vec![
        Series::line("RPY, along the axis", n_col.iter().copied().zip(cols[0].clone()).collect(), palette(1)),
        Series::line("RPY, broadside", n_col.iter().copied().zip(cols[1].clone()).collect(), palette(5)),
        Series::line("A_eff, along the axis", n_col.iter().copied().zip(cols[2].clone()).collect(), palette(0)),
        Series::line("A_eff, broadside", n_col.iter().copied().zip(cols[3].clone()).collect(), palette(3)),
        Series::line(
            "RPY on the substrate, along the axis (÷ a lone sphere there)",
            n_col.iter().copied().zip(cols[4].clone()).collect(),
            palette(2),
        ),
        Series::markers("Stimson & Jeffery, exact (n = 2, axial)", vec![(2.0, STIMSON_JEFFERY)], RGBColor(0, 0, 0), 5),
    ];
    chart(
        &out.join("chain-drag.png"),
        "Drag per sphere of a straight chain of touching spheres",
        ("spheres in the chain", "drag per sphere ÷ lone sphere's Stokes drag"),
        &series,
        SeriesLabelPosition::LowerLeft,
        (Scale::Log, Scale::Log),
    )?;
    let table = markdown(
        &df,
        &[
            "n",
            "RPY axial, per sphere",
            "RPY broadside",
            "A_eff axial",
            "A_eff broadside",
            "RPY on the substrate, axial",
        ],
        &[0, 3, 3, 3, 3, 3],
    )?;
    let re = WATER.0 * CHAIN_SPEED * CHAIN_DIAMETER / WATER.1;
    Ok(context! {
        diameter_um => 1e6 * CHAIN_DIAMETER,
        speed_um => 1e6 * CHAIN_SPEED,
        re => re,
        sn_correction => schiller_naumann_correction(re),
        longest => longest,
        rpy_axial => at(&cols[0], longest),
        a_eff_axial => at(&cols[2], longest),
        excess => at(&cols[0], longest) / at(&cols[2], longest),
        rpy_broadside => at(&cols[1], longest),
        a_eff_broadside => at(&cols[3], longest),
        rpy_total => longest as f64 * at(&cols[0], longest),
        pair_rpy => at(&cols[0], 2),
        pair_a_eff => at(&cols[2], 2),
        stimson_jeffery => STIMSON_JEFFERY,
        pair_rpy_low => 100.0 * (1.0 - at(&cols[0], 2) / STIMSON_JEFFERY),
        wall_longest => at(&cols[4], longest),
        wall_pair => at(&cols[4], 2),
        wall_gap => 100.0 * WALL_GAP,
        table => table,
    })
}

/// Spheres of diameter `d` on a jittered cubic lattice of spacing 2d (no overlaps).
fn lattice(n: usize, d: f64) -> Vec<Vec3> {
    let side = (n as f64).cbrt().ceil() as usize;
    (0..n)
        .map(|k| {
            let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
            let jitter = 0.3 * d * (((k * 7919) % 101) as f64 / 101.0 - 0.5);
            Vec3::new(2.0 * d * i as f64 + jitter, 2.0 * d * j as f64 - jitter, 2.0 * d * l as f64)
        })
        .collect()
}

/// The cost section, and the measured cost per step (s) at [`COST_QUOTED`] particles with the
/// factor renewed every 1000 steps.
struct Cost {
    value: Value,
    per_step_quoted: f64,
}

fn cost_section(tables: &Path) -> Result<Cost, Error> {
    let (d, mu) = (CHAIN_DIAMETER, WATER.1);
    let mut rows: [Vec<f64>; 6] = Default::default();
    for n in COST_SIZES {
        let x = lattice(n, d);
        let radii = vec![0.5 * d; n];
        let velocity: Vec<Vec3> = (0..n).map(|k| Vec3::new(1e-5, 1e-6 * (k % 3) as f64, 0.0)).collect();
        let repeats = if n > COST_FEW_ABOVE { COST_REPEATS.0 } else { COST_REPEATS.1 };
        let factor = timed(repeats, || {
            std::hint::black_box(Resistance::new(&x, &radii, mu, None).expect("RPY is positive definite"));
        })
        .1
        .median;
        let r = Resistance::new(&x, &radii, mu, None)?;
        let solve = timed(COST_REPEATS.2, || {
            std::hint::black_box(r.drag(&velocity, |_| Vec3::zeros()));
        })
        .1
        .median;
        rows[0].push(n as f64);
        rows[1].push(1e3 * factor);
        rows[2].push(1e3 * solve);
        rows[3].push(1e3 * (solve + factor / COST_RENEWALS[0]));
        rows[4].push(1e3 * (solve + factor / COST_RENEWALS[1]));
        rows[5].push(BYTES_PER_PAIR * (n * n) as f64 / 1e6);
    }
    let mut df = frame(vec![
        col("particles", rows[0].clone()),
        col("build_factorise_invert_ms", rows[1].clone()),
        col("drag_ms", rows[2].clone()),
        col("per_step_refactor_every_10_ms", rows[3].clone()),
        col("per_step_refactor_every_1000_ms", rows[4].clone()),
        col("memory_mb", rows[5].clone()),
    ])?;
    write(&mut df, tables, "rpy_cost")?;
    let table = markdown(
        &df,
        &[
            "particles",
            "build, factorise, invert (ms)",
            "drag R·U (ms)",
            &format!("per step, K = {} (ms)", COST_RENEWALS[0]),
            &format!("per step, K = {} (ms)", COST_RENEWALS[1]),
            "memory (MB)",
        ],
        &[0, 3, 3, 3, 3, 1],
    )?;
    let quoted = COST_SIZES.iter().position(|&n| n == COST_QUOTED).expect("a listed size");
    let per_step_quoted = 1e-3 * rows[4][quoted];
    let value = context! {
        table => table,
        repeats_min => COST_REPEATS.0,
        repeats_max => COST_REPEATS.2,
        bytes_per_pair => BYTES_PER_PAIR,
        renewal => COST_RENEWALS[1],
        quoted => COST_QUOTED,
        per_step_quoted_ms => 1e3 * per_step_quoted,
    };
    Ok(Cost { value, per_step_quoted })
}

/// Case 2 with RPY for [`REFACTOR_END`] at each refactorisation interval: the largest position
/// error against refactorising every step, and the wall time.
fn refactor_section(case2: &Path, tables: &Path) -> Result<Value, Error> {
    let base = std::fs::read_to_string(case2)?;
    let end_time = REFACTOR_END;
    let text_for = |k: u64| {
        base.replace("shielding = \"paper\"", &format!("shielding = \"none\"\nrefactor_every = {k}"))
            .replace("law = \"schiller-naumann\"", "law = \"rpy\"")
            .replace("scheme = \"velocity-verlet\"", &format!("scheme = \"respa\"\nslow_every = {REFACTOR_SLOW_EVERY}"))
            .replace("end_time = 1.25", &format!("end_time = {end_time:e}"))
            .replace("interval = 1.0e-2", "interval = 1.0e-3")
    };
    let run = |k: u64| -> Result<(Vec<Vec3>, Vec<Vec3>, f64), Error> {
        let scene = Scene::parse(&text_for(k), "case 2, RPY")?;
        let t0 = Instant::now();
        let sim = scene.run_to_end()?;
        let wall = t0.elapsed().as_secs_f64();
        Ok((scene.initial.position.to_vec(), sim.state.in_id_order(&sim.state.particles.position), wall))
    };
    let facts = scene_facts(&Scene::parse(&text_for(1), "case 2, RPY")?);
    let (start, exact, exact_wall) = run(1)?;
    let moved = start.iter().zip(&exact).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    let mut cols: [Vec<f64>; 4] = Default::default();
    for k in REFACTOR_INTERVALS {
        let (positions, wall) = if k == 1 { (exact.clone(), exact_wall) } else { run(k).map(|r| (r.1, r.2))? };
        let error = positions.iter().zip(&exact).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        cols[0].push(k as f64);
        cols[1].push(error);
        cols[2].push(error / moved);
        cols[3].push(wall);
    }
    let mut df = frame(vec![
        col("refactor_every", cols[0].clone()),
        col("largest_position_error_m", cols[1].clone()),
        col("error_over_largest_displacement", cols[2].clone()),
        col("wall_time_s", cols[3].clone()),
    ])?;
    write(&mut df, tables, "rpy_refactor")?;
    let sci = |v: &[f64]| v.iter().map(|x| format!("{x:.2e}")).collect::<Vec<_>>();
    let shown = frame(vec![
        col("K", cols[0].clone()),
        scol("error", sci(&cols[1])),
        scol("relative", sci(&cols[2])),
        col("wall", cols[3].clone()),
    ])?;
    let table = markdown(
        &shown,
        &["K", "largest position error (m)", "÷ largest displacement", "wall time (s)"],
        &[0, 0, 0, 1],
    )?;
    let last = cols[2].len() - 1;
    Ok(context! {
        moved => moved,
        end_time => end_time,
        steps => end_time / facts.dt,
        scene => facts,
        table => table,
        largest_interval => cols[0][last],
        largest_relative => cols[2][last],
    })
}

/// One drag model of case 2 in words' reach: α, and where its aggregates of [`LARGE`]+ fall
/// against the experiment's band (`overlapping`, `clear` or `unknown` without a CI).
#[derive(Serialize)]
struct ModelVerdict {
    name: String,
    alpha: f64,
    fitted: bool,
    large: f64,
    large_ci: f64,
    band: &'static str,
}

fn case2_section(runs: &[Run], reference: &Path, out: &Path, tables: &Path) -> Result<Value, Error> {
    let here: Vec<&Run> = runs.iter().filter(|r| r.experiment.starts_with("hydro-case2") && r.completed()).collect();
    if here.is_empty() {
        return Ok(context! { present => false });
    }
    // The experiment is the first row of the paper's Table 2.
    let table2 = read_csv(reference)?;
    let first = |key: &str| floats(&table2, key).map(|v| v.first().copied().unwrap_or(f64::NAN));
    let (exp_size, exp_velocity, exp_velocity_std) =
        (first("mean_size_particles")?, first("mean_velocity_um_per_s")?, first("std_velocity_um_per_s")?);
    let (mut names, mut variants) = (vec![], vec![]);
    let mut cols: [Vec<f64>; 10] = Default::default();
    let mut series = vec![];
    for (k, (variant, label)) in MODELS.iter().enumerate() {
        let group: Vec<&&Run> = here.iter().filter(|r| r.variant == *variant).collect();
        if group.is_empty() {
            continue;
        }
        let per_run: Vec<(f64, Vec<(usize, f64)>)> = group.iter().map(|r| sizes_and_velocities(r)).collect();
        let sizes: Vec<f64> = per_run.iter().map(|r| r.0).collect();
        let velocity: Vec<f64> =
            per_run.iter().map(|r| summary(&r.1.iter().map(|p| p.1).collect::<Vec<_>>()).mean).collect();
        let class_mean = |run: &(f64, Vec<(usize, f64)>), keep: &dyn Fn(usize) -> bool| {
            summary(&run.1.iter().filter(|p| keep(p.0)).map(|p| p.1).collect::<Vec<_>>()).mean
        };
        let singles: Vec<f64> = per_run.iter().map(|r| class_mean(r, &|n| n == 1)).filter(|v| v.is_finite()).collect();
        let large: Vec<f64> =
            per_run.iter().map(|r| class_mean(r, &|n| n >= LARGE)).filter(|v| v.is_finite()).collect();
        let mut by_size: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
        for (n, v) in per_run.iter().flat_map(|r| r.1.iter().copied()) {
            by_size.entry(n).or_default().push(v);
        }
        names.push(label.to_string());
        variants.push(*variant);
        cols[0].push(group.len() as f64);
        cols[1].push(summary(&group.iter().map(|r| r.last.len() as f64).collect::<Vec<_>>()).mean);
        cols[2].push(summary(&sizes).mean);
        cols[3].push(ci95_half_width(&sizes));
        cols[4].push(summary(&velocity).mean);
        cols[5].push(ci95_half_width(&velocity));
        cols[6].push(summary(&singles).mean);
        cols[7].push(summary(&large).mean);
        cols[8].push(ci95_half_width(&large));
        cols[9].push(log_slope(&by_size));
        let classes: Vec<(usize, &Vec<f64>)> =
            by_size.iter().filter(|(_, v)| v.len() >= MIN_AGGREGATES).map(|(&n, v)| (n, v)).collect();
        // The figure shows the drag models and their substrate variants with M re-derived (six
        // marks); the substrate with the scene's M and the spreads are in the table.
        if variant.starts_with("cv-") || variant.ends_with("-scene-m") {
            continue;
        }
        series.push(
            Series::markers(
                format!("{label} (mean per size ± CI95 over its aggregates)"),
                classes.iter().map(|(n, v)| (*n as f64 * (1.0 + 0.03 * (k as f64 - 1.0)), summary(v).mean)).collect(),
                palette([0, 3, 1, 4, 5, 2][k]),
                5,
            )
            .with_errors(classes.iter().map(|(_, v)| ci95_half_width(v)).collect()),
        );
    }
    let largest = series.iter().flat_map(|s| s.points.iter().map(|p| p.0)).fold(1.0, f64::max);
    for (band, label) in [
        (
            exp_velocity + exp_velocity_std,
            format!("experiment {exp_velocity} ± {exp_velocity_std} µm/s (its std over aggregates)"),
        ),
        (exp_velocity - exp_velocity_std, String::new()),
    ] {
        series.push(Series::line(label, vec![(1.0, band), (largest, band)], RGBColor(0, 0, 0)));
    }
    chart(
        &out.join("case2-velocity-by-size.png"),
        "Case 2: velocity along the gradient against aggregate size",
        ("particles in the aggregate", "tracked velocity (µm/s)"),
        &series,
        Legend::above_data(0.6),
        (Scale::Log, Scale::Log),
    )?;
    let mut df = model_table(
        &names,
        &[
            ("seeds", &cols[0]),
            ("aggregates_per_run", &cols[1]),
            ("mean_size_particles", &cols[2]),
            ("ci95_size", &cols[3]),
            ("mean_velocity_um_per_s", &cols[4]),
            ("ci95_velocity", &cols[5]),
            ("single_particle_velocity_um_per_s", &cols[6]),
            ("velocity_5_plus_um_per_s", &cols[7]),
            ("ci95_velocity_5_plus", &cols[8]),
            ("log_slope_velocity_vs_size", &cols[9]),
        ],
    )?;
    write(&mut df, tables, "case2_drag_models")?;
    let rpy_every = override_of(&here, "rpy", "forces.drag.refactor_every").unwrap_or("1").to_string();
    let table = markdown(
        &df,
        &[
            "drag model",
            "seeds",
            "aggregates/run",
            "mean size",
            "± CI95",
            "velocity (µm/s)",
            "± CI95",
            "singles",
            &format!("{LARGE}+"),
            "± CI95",
            "slope α",
        ],
        &[0, 0, 1, 2, 2, 2, 2, 2, 2, 2, 2],
    )?;
    let verdicts: Vec<ModelVerdict> = names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let (v, ci) = (cols[7][k], cols[8][k]);
            let overlaps = v - ci <= exp_velocity + exp_velocity_std && v + ci >= exp_velocity - exp_velocity_std;
            ModelVerdict {
                name: name.clone(),
                alpha: cols[9][k],
                fitted: cols[9][k].is_finite(),
                large: v,
                large_ci: ci,
                band: if !ci.is_finite() {
                    "unknown"
                } else if overlaps {
                    "overlapping"
                } else {
                    "clear"
                },
            }
        })
        .collect();
    // The scene as the paper's model runs it (the a-eff variant) and its Reynolds numbers: a lone
    // sphere at the calibrated velocity, and the fastest tracked aggregate of any case-2 run.
    let scene = scene_of(&here, "a-eff")?.or(scene_of(&here, variants[0])?).expect("a case-2 run");
    let facts = scene_facts(&scene);
    let reynolds = |v_um: f64| facts.fluid_density * 1e-6 * v_um * 1e-6 * facts.diameter_um / facts.viscosity;
    let fastest = here
        .iter()
        .flat_map(|r| r.last.iter().map(|a| 1e6 * a.tracked_vx.abs()))
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let free: Vec<&ModelVerdict> = verdicts
        .iter()
        .zip(&variants)
        .filter(|(_, v)| MODELS[..FREE_FLUID].iter().any(|(m, _)| m == *v))
        .map(|(m, _)| m)
        .collect();
    let rpy = variants.iter().position(|v| *v == "rpy");
    let alone = variants.iter().position(|v| *v == "no-shielding");
    let together = match (rpy, alone) {
        (Some(r), Some(a)) => Some(context! {
            rpy => cols[6][r],
            alone => cols[6][a],
            ratio => cols[6][r] / cols[6][a],
            particles => facts.particles,
        }),
        _ => None,
    };
    let closest = free.iter().min_by(|a, b| a.alpha.abs().total_cmp(&b.alpha.abs())).map(|m| m.name.clone());
    let dt_of =
        |variant: &str| -> Result<Option<f64>, Error> { Ok(scene_of(&here, variant)?.map(|s| s.spec.integration.dt)) };
    let (gap_value, variations_list) =
        (spread_against_the_gap(&variants, &cols, exp_size), variations(&variants, &cols));
    Ok(context! {
        present => true,
        scene => facts,
        rpy_every => rpy_every,
        experiment => context! { size => exp_size, velocity => exp_velocity, std => exp_velocity_std },
        table => table,
        models => &verdicts,
        free => free,
        closest => closest,
        together => together,
        reynolds => context! {
            lone => reynolds(exp_velocity),
            lone_correction => schiller_naumann_correction(reynolds(exp_velocity)),
            fastest_velocity => fastest,
            fastest => reynolds(fastest),
        },
        large => LARGE,
        min_aggregates => MIN_AGGREGATES,
        variations => variations_list,
        wall => context! {
            gap => 100.0 * WALL_GAP,
            factor => parallel_factor(1.0 + WALL_GAP),
            rpy_factor => rpy_wall_factor()?,
            dt => dt_of("a-eff-wall")?,
            spread_dt => dt_of("cv-0")?,
            sigmas => TRUNCATION_SIGMAS,
        },
        gap => gap_value,
    })
}

/// One row per drag model: its name, then the named columns.
fn model_table(
    names: &[String],
    columns: &[(&str, &Vec<f64>)],
) -> polars::prelude::PolarsResult<polars::prelude::DataFrame> {
    let mut all = vec![scol("drag_model", names.to_vec())];
    all.extend(columns.iter().map(|(name, values)| col(name, values.to_vec())));
    frame(all)
}

/// The case-1 drag models, by variant name, in the report's order.
const CASE1_MODELS: [(&str, &str); 3] = [
    ("a-eff", "Schiller–Naumann with A_eff (the paper's)"),
    ("stokes", "Stokes on every sphere, no shielding"),
    ("rpy", "RPY (hydrodynamic interactions)"),
];

/// One case-1 drag model against A_eff: its paired change at the end and early, each ± CI95 over
/// seeds, and whether the CI95 excludes zero.
#[derive(Serialize)]
struct Case1Verdict {
    name: String,
    seeds: f64,
    mean: f64,
    mean_ci: f64,
    change: f64,
    change_ci: f64,
    moved: bool,
    early: f64,
    early_ci: f64,
    grows: bool,
}

/// Case 1 at [`CASE1_CONCENTRATION`] under each drag model: the mean aggregate length at the end
/// (Table 3's number) per model, its paired change against A_eff by seed, and L(t).
fn case1_section(runs: &[Run], reference: &Path, out: &Path, tables: &Path) -> Result<Value, Error> {
    let here: Vec<&Run> = runs.iter().filter(|r| r.experiment == "hydro-case1" && r.completed()).collect();
    if here.is_empty() {
        return Ok(context! { present => false });
    }
    let table3 = read_csv(reference)?;
    let row = floats(&table3, "concentration_mg_per_ml")?
        .iter()
        .position(|c| (c - CASE1_CONCENTRATION).abs() < 1e-9)
        .unwrap_or(2);
    let at = |key: &str| floats(&table3, key).map(|v| v.get(row).copied().unwrap_or(f64::NAN));
    let (paper, paper_std, exp, exp_std) =
        (at("sim_mean_length_um")?, at("sim_std_um")?, at("exp_mean_length_um")?, at("exp_std_um")?);
    let base: Vec<&Run> = here.iter().copied().filter(|r| r.variant == "a-eff").collect();
    let (mut names, mut cols): (Vec<String>, [Vec<f64>; 10]) = (vec![], Default::default());
    // Early growth: the frame nearest EARLY (runs of one scene share their frame times).
    let early = base.first().map_or(0, |r| {
        (0..r.times.len())
            .min_by(|&a, &b| (r.times[a] - EARLY).abs().total_cmp(&(r.times[b] - EARLY).abs()))
            .unwrap_or(0)
    });
    let at_early = |r: &Run| r.mean_length.get(early).copied().unwrap_or(f64::NAN);
    let scene = scene_of(&here, "a-eff")?.or(scene_of(&here, CASE1_MODELS[0].0)?).expect("a case-1 run");
    let facts = scene_facts(&scene);
    let end_ms = 1e3 * facts.end_time;
    let mut series = vec![];
    for (k, (variant, label)) in CASE1_MODELS.iter().enumerate() {
        let group: Vec<&Run> = here.iter().copied().filter(|r| r.variant == *variant).collect();
        if group.is_empty() {
            continue;
        }
        let lengths: Vec<f64> = group.iter().map(|r| r.mean_length_um()).collect();
        let spread: Vec<f64> = group.iter().map(|r| summary(&r.lengths_um()).population_std).collect();
        let change = super::estimate::paired_change(&base, &group);
        let early_change = super::estimate::Estimate::of(
            &group
                .iter()
                .filter_map(|r| {
                    base.iter().find(|b| b.seed == r.seed).map(|b| 100.0 * (at_early(r) / at_early(b) - 1.0))
                })
                .collect::<Vec<_>>(),
        );
        let mut wall: Vec<f64> = group.iter().map(|r| r.wall_time).collect();
        wall.sort_by(f64::total_cmp);
        names.push(label.to_string());
        cols[0].push(group.len() as f64);
        cols[1].push(summary(&lengths).mean);
        cols[2].push(ci95_half_width(&lengths));
        cols[3].push(summary(&spread).mean);
        cols[4].push(summary(&group.iter().map(|r| r.box_limited_fraction()).collect::<Vec<_>>()).mean);
        cols[5].push(if *variant == "a-eff" { 0.0 } else { change.mean });
        cols[6].push(if *variant == "a-eff" { 0.0 } else { change.ci95 });
        cols[7].push(wall[wall.len() / 2]);
        cols[8].push(if *variant == "a-eff" { 0.0 } else { early_change.mean });
        cols[9].push(if *variant == "a-eff" { 0.0 } else { early_change.ci95 });
        // L(t): the mean over seeds at each frame (runs of one scene share their frame times).
        let times = &group[0].times;
        let points = (0..times.len())
            .filter_map(|f| {
                let at_f: Vec<f64> = group
                    .iter()
                    .filter_map(|r| r.mean_length.get(f))
                    .map(|l| 1e6 * l)
                    .filter(|l| l.is_finite())
                    .collect();
                (at_f.len() == group.len()).then(|| (1e3 * times[f], summary(&at_f).mean))
            })
            .collect();
        series.push(Series::line(format!("{label}: mean over {} seeds", group.len()), points, palette([0, 1, 3][k])));
    }
    for (value, label, grey) in [
        (exp, format!("experiment {exp:.0} µm (Table 3; its time is not given)"), 0),
        (paper, format!("paper's simulation {paper:.1} µm at {end_ms} ms"), 140),
    ] {
        series.push(Series::line(label, vec![(0.0, value), (end_ms, value)], RGBColor(grey, grey, grey)));
    }
    chart(
        &out.join("case1-length-vs-time.png"),
        &format!("Case 1, {CASE1_CONCENTRATION} mg/ml: mean aggregate length under each drag model"),
        ("time (ms)", "mean aggregate length (µm)"),
        &series,
        Legend::above_data(0.45),
        (Scale::Linear, Scale::Linear),
    )?;
    let mut df = model_table(
        &names,
        &[
            ("seeds", &cols[0]),
            ("mean_length_um", &cols[1]),
            ("ci95_length_um", &cols[2]),
            ("within_run_std_um", &cols[3]),
            ("box_limited_fraction", &cols[4]),
            ("paired_change_vs_a_eff_percent", &cols[5]),
            ("ci95_paired_change_percent", &cols[6]),
            ("paired_change_at_1ms_percent", &cols[8]),
            ("ci95_paired_change_at_1ms_percent", &cols[9]),
            ("median_wall_time_s", &cols[7]),
        ],
    )?;
    write(&mut df, tables, "case1_drag_models")?;
    let early_ms = base.first().and_then(|r| r.times.get(early)).map_or(f64::NAN, |t| 1e3 * t);
    let table = markdown(
        &df,
        &[
            "drag model",
            "seeds",
            "mean length (µm)",
            "± CI95",
            "within-run std (µm)",
            "box-limited",
            "paired change vs A_eff (%)",
            "± CI95",
            &format!("paired change at {} ms (%)", (early_ms * 1e3).round() / 1e3),
            "± CI95",
            "wall time/run (s)",
        ],
        &[0, 0, 1, 1, 1, 3, 1, 1, 1, 1, 0],
    )?;
    let verdicts: Vec<Case1Verdict> = (1..names.len())
        .map(|k| Case1Verdict {
            name: names[k].clone(),
            seeds: cols[0][k],
            mean: cols[1][k],
            mean_ci: cols[2][k],
            change: cols[5][k],
            change_ci: cols[6][k],
            moved: cols[5][k].abs() > cols[6][k],
            early: cols[8][k],
            early_ci: cols[9][k],
            grows: cols[8][k].abs() > cols[9][k],
        })
        .collect();
    Ok(context! {
        present => true,
        concentration => CASE1_CONCENTRATION,
        scene => facts,
        end_ms => end_ms,
        early_ms => early_ms,
        rpy_every => override_of(&here, "rpy", "forces.drag.refactor_every").unwrap_or("1"),
        paper => context! { mean => paper, std => paper_std },
        experiment => context! { mean => exp, std => exp_std },
        box_fraction => BOX_LIMITED_FRACTION,
        table => table,
        stokes => verdicts.iter().find(|v| v.name == CASE1_MODELS[1].1),
        verdicts => &verdicts,
    })
}

/// A difference of independent means ± the two CI95 in quadrature; `changed` when it exceeds
/// them, `measured` when the CI is defined.
#[derive(Serialize, Debug)]
struct Change {
    d: f64,
    ci: f64,
    measured: bool,
    changed: bool,
}

impl Change {
    fn of(d: f64, ci: f64) -> Self {
        Change { d, ci, measured: ci.is_finite(), changed: ci.is_finite() && d.abs() > ci }
    }
}

/// One opt-in variant against the run it varies.
#[derive(Serialize, Debug)]
struct Variation {
    label: &'static str,
    variant: &'static str,
    base: &'static str,
    seeds: f64,
    size: Change,
    velocity: Change,
    alpha: f64,
    base_alpha: f64,
}

/// The substrate-drag and diameter-spread variants against the free-fluid, equal-diameter runs
/// they vary: the change of the mean size and of the velocity of aggregates of [`LARGE`]+, each
/// ± the CI95 of a difference of independent means (the two CI95 half-widths in quadrature).
fn variations(variants: &[&str], cols: &[Vec<f64>; 10]) -> Vec<Variation> {
    let at = |v: &str| variants.iter().position(|&x| x == v);
    let pairs = [
        ("a-eff-wall", "a-eff", "A_eff with the substrate's drag"),
        ("no-shielding-wall", "no-shielding", "no shielding with the substrate's drag"),
        ("rpy-wall", "rpy", "RPY above the substrate"),
        ("a-eff-wall-scene-m", "a-eff-wall", "A_eff with the substrate's drag, the scene's M"),
        ("no-shielding-wall-scene-m", "no-shielding-wall", "no shielding with the substrate's drag, the scene's M"),
        ("rpy-wall-scene-m", "rpy-wall", "RPY above the substrate, the scene's M"),
        ("cv-5", "cv-0", "A_eff, cv 5 %"),
        ("cv-10", "cv-0", "A_eff, cv 10 %"),
        ("cv-20", "cv-0", "A_eff, cv 20 %"),
    ];
    pairs
        .iter()
        .filter_map(|&(v, base, label)| Some((at(v)?, at(base)?, v, base, label)))
        .map(|(k, b, variant, base, label)| {
            let change = |m: usize, c: usize| Change::of(cols[m][k] - cols[m][b], cols[c][k].hypot(cols[c][b]));
            Variation {
                label,
                variant,
                base,
                seeds: cols[0][k],
                size: change(2, 3),
                velocity: change(7, 8),
                alpha: cols[9][k],
                base_alpha: cols[9][b],
            }
        })
        .collect()
}

/// The paper's explanation of its case-2 gap (constant diameters, where the experiment's were
/// spread) against the gap itself.
#[derive(Serialize, Debug)]
struct SpreadGap {
    experiment: f64,
    equal: f64,
    equal_ci: f64,
    gap: f64,
    /// The largest change of the mean size the spread variants allow, in either direction (the
    /// far end of the CI95 of their difference to cv 0 %), and at which cv (%).
    bound: f64,
    cv: u32,
    share: f64,
    widest: u32,
    closes: bool,
}

/// The experiment's mean size less that of equal diameters, and the largest change of the mean
/// size the spread variants allow; `None` without cv 0 % or a spread with a finite bound.
fn spread_against_the_gap(variants: &[&str], cols: &[Vec<f64>; 10], experiment_size: f64) -> Option<SpreadGap> {
    let at = |v: &str| variants.iter().position(|&x| x == v);
    let base = at("cv-0")?;
    let allowed: Vec<(f64, u32)> = [5, 10, 20]
        .iter()
        .filter_map(|&cv| at(&format!("cv-{cv}")).map(|k| (cv, k)))
        .map(|(cv, k)| ((cols[2][k] - cols[2][base]).abs() + cols[3][k].hypot(cols[3][base]), cv))
        .filter(|(bound, _)| bound.is_finite())
        .collect();
    let &(bound, cv) = allowed.iter().max_by(|a, b| a.0.total_cmp(&b.0))?;
    let widest = allowed.iter().map(|&(_, cv)| cv).max().unwrap_or(cv);
    let gap = experiment_size - cols[2][base];
    Some(SpreadGap {
        experiment: experiment_size,
        equal: cols[2][base],
        equal_ci: cols[3][base],
        gap,
        bound,
        cv,
        share: 100.0 * bound / gap,
        widest,
        closes: bound >= gap,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each variant is set against the run it varies (the wall variants against their free-fluid
    /// model, the spreads against equal diameters in the same set-up), the difference ± the two
    /// CI95 in quadrature, and called a change only when the difference exceeds that.
    #[test]
    fn variations_compare_each_variant_with_the_runs_it_varies() {
        let variants = ["a-eff", "no-shielding", "a-eff-wall", "cv-0", "cv-10", "cv-20"];
        let mut cols: [Vec<f64>; 10] = Default::default();
        // seeds, aggregates, size, ± size, velocity, ±, singles, 5+, ± 5+, slope
        let rows = [
            [20.0, 21.0, 2.6, 0.3, 15.0, 2.0, 6.5, 37.0, 8.0, 0.9],
            [20.0, 23.0, 2.4, 0.2, 8.2, 0.3, 7.9, 8.6, 1.1, 0.05],
            [10.0, 22.0, 2.5, 0.4, 14.0, 2.0, 6.0, 13.0, 3.0, 0.4],
            [10.0, 21.0, 2.6, 0.3, 15.0, 2.0, 6.5, 37.0, 8.0, 0.9],
            [10.0, 21.0, 3.6, 0.4, 15.0, 2.0, 6.5, 36.0, 6.0, 0.8],
            // One seed with aggregates of 5+: their CI is not defined.
            [10.0, 21.0, 2.7, 0.4, 12.0, 2.0, 6.5, 25.0, f64::NAN, 0.1],
        ];
        for row in rows {
            row.iter().zip(cols.iter_mut()).for_each(|(v, c)| c.push(*v));
        }
        let list = variations(&variants, &cols);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        let wall = list.iter().find(|v| v.variant == "a-eff-wall").expect("the wall variant");
        assert_eq!((wall.base, wall.seeds), ("a-eff", 10.0));
        // Size: -0.1 ± 0.5 (no change); velocity of 5+: -24.0 ± 8.5 (a change).
        assert!(close(wall.size.d, -0.1) && close(wall.size.ci, 0.5) && !wall.size.changed, "{wall:?}");
        assert!(close(wall.velocity.d, -24.0) && close(wall.velocity.ci, 8.0f64.hypot(3.0)), "{wall:?}");
        assert!(wall.velocity.changed && wall.velocity.measured);
        let spread = list.iter().find(|v| v.variant == "cv-10").expect("the spread variant");
        assert_eq!(spread.base, "cv-0");
        assert!(close(spread.size.d, 1.0) && close(spread.size.ci, 0.5) && spread.size.changed, "{spread:?}");
        assert!(list.iter().all(|v| v.variant != "cv-5" && v.variant != "no-shielding-wall"), "no runs, no line");
        let unmeasured = list.iter().find(|v| v.variant == "cv-20").expect("the cv 20 % line");
        assert!(!unmeasured.velocity.measured && !unmeasured.velocity.changed, "{unmeasured:?}");
        assert!(variations(&variants[..2], &cols).is_empty());
        // Gap 7 − 2.6 = 4.4; cv 10 %: |3.6 − 2.6| + 0.5 = 1.5, cv 20 %: 0.1 + 0.5 = 0.6.
        let gap = spread_against_the_gap(&variants, &cols, 7.0).expect("cv 0 % and spreads");
        assert!(close(gap.gap, 4.4) && close(gap.bound, 1.5) && gap.cv == 10, "{gap:?}");
        assert!((gap.share - 34.09).abs() < 0.01 && gap.widest == 20 && !gap.closes, "{gap:?}");
        assert_eq!(spread_against_the_gap(&variants[..5], &cols, 7.0).map(|g| g.widest), Some(10));
        assert!(spread_against_the_gap(&variants, &cols, 2.5).is_some_and(|g| g.gap <= 0.0));
        assert!(spread_against_the_gap(&variants[..3], &cols, 7.0).is_none(), "no cv 0 %, no comparison");
    }

    /// The template renders the variants' words from their data: a change, no measurable change,
    /// and an unmeasured one.
    #[test]
    fn the_template_words_each_kind_of_change() {
        let env = crate::report::template::environment();
        let text = r#"{% from "hydrodynamics/macros.md" import change %}{{ change(a, 2, "particles") }}|{{ change(b, 1, "µm/s") }}|{{ change(c, 1, "µm/s") }}"#;
        let out = env
            .render_str(
                text,
                context! { a => Change::of(1.0, 0.5), b => Change::of(-0.1, 0.5), c => Change::of(3.0, f64::NAN) },
            )
            .unwrap();
        assert_eq!(
            out,
            "changes (+1.00 ± 0.50 particles)|does not change measurably (−0.1 ± 0.5 µm/s)|is not yet measured (fewer than two seeds with a value)"
        );
    }

    /// Velocities growing as n^0.7 give the exponent 0.7; a size seen fewer than three times is
    /// left out (here an outlier that would pull the fit).
    #[test]
    fn log_slope_recovers_a_power_law_from_well_sampled_sizes() {
        let mut by_size: BTreeMap<usize, Vec<f64>> = BTreeMap::new();
        for n in 1..=8usize {
            by_size.insert(n, vec![7.5 * (n as f64).powf(0.7); 3]);
        }
        by_size.insert(20, vec![1.0e3]);
        assert!((log_slope(&by_size) - 0.7).abs() < 1e-12, "{}", log_slope(&by_size));
        assert!(log_slope(&BTreeMap::new()).is_nan());
    }
}
