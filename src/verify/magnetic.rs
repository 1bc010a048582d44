//! `magdem verify magnetic`: magnetic scenes in magdem and, in lock step with magdem's magnetic
//! forces, in LIGGGHTS and LAMMPS — a two-particle approach and the paper's case 1 at 4.5 mg/ml
//! (307 particles) over a short time — with the per-particle position difference against time.
//!
//! The reference decks cannot express the paper's drag (Schiller–Naumann with shielding and
//! rotational drag), so the case-1 scene is run here with Stokes drag, no shielding and no
//! rotational drag in all three engines; everything else is the shipped scene.

use crate::io::trajectory::Trajectory;
use crate::plot::{engine_colour, line_chart, Series};
use crate::reference::{self, Engine};
use crate::report::template::render;
use crate::run::{run, RunOptions};
use crate::scene::Scene;
use minijinja::{context, Value};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;

/// The shipped case-1 scene of the lock-step comparison.
const CASE1: &str = "case1-c4.5";
/// The files-route study: the pair approach at this dt to this time (before contact), exchanging
/// every K steps for each K here.
const FILES_ROUTE_DT: f64 = 1.0e-8;
const FILES_ROUTE_END: f64 = 9.0e-5;
const FILES_ROUTE_KS: [u64; 5] = [3, 10, 30, 100, 300];
/// Position differences below this (m) are drawn at it on the log axis (exactly equal positions).
const LOG_FLOOR: f64 = 1e-22;
/// Coulomb's constant k_e (N m²/C²) as LAMMPS' dipole pair style takes it.
const COULOMB: f64 = 8.9876e9;

/// Two dipoles closing with exact induction, touching at about 0.1 ms (the lock-step check).
pub const PAIR: &str = r#"# Two 11 um Fe3O4 spheres 6 diameters apart, slightly off the field axis, exact induction.
version = 1
name = "pair-approach"
[domain]
lo = [-1.0e-4, -5.0e-5, -5.0e-5]
hi = [1.0e-4, 5.0e-5, 5.0e-5]
[fluid]
density = 1000.0
viscosity = 1.0e-3
[field]
b0 = [0.4, 0.0, 0.0]
[[species]]
name = "p"
diameter = 11.0e-6
density = 1087.0
youngs_modulus = 1.0e9
poisson_ratio = 0.5
friction = 0.5
restitution = 0.5
relative_permeability = 12.3
[[particles]]
species = "p"
positions = [[-3.3e-5, 0.0, 0.0], [3.3e-5, 1.0e-6, 0.0]]
[forces.contact]
[forces.dipole]
induction = "exact"
[forces.drag]
law = "stokes"
shielding = "none"
rotational = false
[integration]
dt = 1.0e-9
end_time = 2.0e-4
[output]
interval = 2.0e-6
"#;

/// A shipped case-1 scene with `edits` (text replacements, each of which must apply).
fn edited_scene(name: &str, edits: &[(&str, String)]) -> Result<String, String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("experiments/scenes/{name}.toml"));
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    edits.iter().try_fold(text, |text, (from, to)| {
        if text.contains(from) {
            Ok(text.replacen(from, to, 1))
        } else {
            Err(format!("{} lacks {from:?}", path.display()))
        }
    })
}

/// The drag edits that make a case-1 scene expressible in the reference decks.
const STOKES: (&str, &str) =
    ("law = \"schiller-naumann\"\nshielding = \"paper\"", "law = \"stokes\"\nshielding = \"none\"\nrotational = false");

/// The shipped case-1 scene at 4.5 mg/ml with the drag the reference codes can express, run for
/// `end_time` seconds.
pub fn case1_scene(end_time: f64) -> Result<String, String> {
    let text = edited_scene(
        CASE1,
        &[
            (STOKES.0, STOKES.1.into()),
            ("end_time = 5.0e-3", format!("end_time = {end_time:e}")),
            ("interval = 5.0e-5", format!("interval = {:e}", end_time / 50.0)),
            (&format!("name = \"{CASE1}\""), format!("name = \"{CASE1}-stokes\"")),
        ],
    )?;
    Ok(format!("# verify magnetic: {CASE1}.toml with Stokes drag, no shielding, no rotational drag\n{text}"))
}

/// The 2.25 mg/ml case-1 scene as LAMMPS' native deck can hold it (`--native`): fixed moments
/// (induction "none"), Stokes drag without shielding or rotational drag, and friction 0 (LAMMPS
/// turns its fixed dipoles' torque into spin, which friction would couple into the contacts;
/// magdem's induced moments feel no torque), to `end_time` with frames every `interval`.
pub fn case1_fixed_moments(end_time: f64, interval: f64) -> Result<String, String> {
    let text = edited_scene(
        "case1-c2.25",
        &[
            ("induction = \"paper\"", "induction = \"none\"".into()),
            (STOKES.0, STOKES.1.into()),
            ("friction = 0.5", "friction = 0.0".into()),
            ("end_time = 5.0e-3", format!("end_time = {end_time:e}")),
            ("interval = 5.0e-5", format!("interval = {interval:e}")),
            ("name = \"case1-c2.25\"", "name = \"case1-c2.25-fixed-moments\"".into()),
        ],
    )?;
    Ok(format!(
        "# case1-c2.25.toml with fixed moments, Stokes drag, no shielding or rotational drag, friction 0\n{text}"
    ))
}

/// Per-frame maximum and median over particles of |x_engine − x_magdem|.
pub struct Difference {
    pub engine: &'static str,
    pub times: Vec<f64>,
    pub max: Vec<f64>,
    pub median: Vec<f64>,
}

fn difference(engine: &'static str, native: &Path, other: &Path) -> hdf5::Result<Difference> {
    let a = Trajectory::open(native).map_err(|e| e.to_string())?;
    let b = Trajectory::open(other).map_err(|e| e.to_string())?;
    let (x, y) = (a.all_vectors("position")?, b.all_vectors("position")?);
    let times = a.times()?;
    let (frames, n) = (x.shape()[0], x.shape()[1]);
    let (mut max, mut median) = (vec![], vec![]);
    for k in 0..frames {
        let mut d: Vec<f64> =
            (0..n).map(|i| (0..3).map(|c| (x[[k, i, c]] - y[[k, i, c]]).powi(2)).sum::<f64>().sqrt()).collect();
        d.sort_by(f64::total_cmp);
        max.push(d[n - 1]);
        median.push(d[n / 2]);
    }
    Ok(Difference { engine, times, max, median })
}

/// Position differences per engine and wall time per engine (magdem first).
pub type Comparison = (Vec<Difference>, Vec<(String, f64)>);

/// Runs one scene in magdem and the engines; returns the differences and the wall times.
pub fn compare(
    text: &str,
    name: &str,
    work: &Path,
    engines: &[Engine],
) -> Result<Comparison, Box<dyn std::error::Error>> {
    let scene = Scene::parse(text, name)?;
    std::fs::create_dir_all(work)?;
    let native = work.join(format!("{name}.magdem.h5"));
    let start = std::time::Instant::now();
    run(&scene, &native, &RunOptions { overwrite: true, ..Default::default() })?;
    let mut times = vec![("magdem".to_string(), start.elapsed().as_secs_f64())];
    let mut diffs = vec![];
    for &engine in engines {
        let out = work.join(format!("{name}.{}.h5", engine.name()));
        let r = reference::run(engine, &scene, &work.join(format!("{name}.{}", engine.name())), &out)?;
        times.push((engine.name().to_string(), r.wall_time.as_secs_f64()));
        diffs.push(difference(engine.name(), &native, &out)?);
    }
    Ok((diffs, times))
}

/// The pair approach without contact, stopped at 96 µs (before the spheres would touch), with
/// the given scheme (with its keys) and dt: the integrator convergence problem.
pub fn pair_before_contact(scheme: crate::core::integrators::Scheme, dt: f64) -> String {
    let scheme = crate::scene::spec::scheme_lines(&scheme);
    PAIR.replace("[forces.contact]\n", "")
        .replace("dt = 1.0e-9", &format!("{scheme}dt = {dt:e}"))
        .replace("end_time = 2.0e-4", "end_time = 9.6e-5")
        .replace("interval = 2.0e-6", "interval = 9.6e-5")
}

/// The pair approach run for [`FILES_ROUTE_END`] at [`FILES_ROUTE_DT`] (before contact), for the
/// files-route study.
pub fn files_route_scene() -> String {
    PAIR.replace("dt = 1.0e-9", &format!("dt = {FILES_ROUTE_DT:.1e}"))
        .replace("end_time = 2.0e-4", &format!("end_time = {FILES_ROUTE_END:.1e}"))
        .replace("interval = 2.0e-6", "interval = 1.0e-6")
}

/// One exchange interval K: (K, largest position difference to the in-process route (m), wall time (s)).
pub type LagRow = (u64, f64, f64);

/// The files route against the in-process route for exchange intervals `ks`.
pub fn files_route_lag(
    engine: Engine,
    text: &str,
    work: &Path,
    magdem: &Path,
    ks: &[u64],
) -> Result<Vec<LagRow>, Box<dyn std::error::Error>> {
    let scene = Scene::parse(text, "files-route")?;
    std::fs::create_dir_all(work)?;
    let callback = work.join(format!("callback.{}.h5", engine.name()));
    reference::run(engine, &scene, &work.join(format!("callback.{}", engine.name())), &callback)?;
    let reference_positions = Trajectory::open(&callback)?.all_vectors("position")?;
    let mut rows = vec![];
    for &k in ks {
        let out = work.join(format!("files-{k}.{}.h5", engine.name()));
        let coupling = reference::deck::Coupling::Files { magdem: magdem.to_path_buf(), every: k };
        let r = reference::run_binary(
            engine,
            &scene,
            &work.join(format!("files-{k}.{}", engine.name())),
            &out,
            &coupling,
            1,
        )?;
        let x = Trajectory::open(&out)?.all_vectors("position")?;
        let worst = x.iter().zip(reference_positions.iter()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        rows.push((k, worst, r.wall_time.as_secs_f64()));
    }
    Ok(rows)
}

/// One engine's position differences in a lock-step scene: the largest over the run, before and
/// from magdem's first contact, and the median over particles at the last frame (m).
#[derive(Serialize)]
struct EngineDifference {
    engine: &'static str,
    largest: f64,
    before_contact: f64,
    after_contact: f64,
    final_median: f64,
}

/// The time of the first frame in which two of the trajectory's particles overlap (s).
fn first_contact(path: &Path) -> Result<Option<f64>, Box<dyn std::error::Error>> {
    let t = Trajectory::open(path)?;
    let x = t.all_vectors("position")?;
    let radius = t.file.dataset("particles/radius")?.read_raw::<f64>()?;
    let times = t.times()?;
    let n = radius.len();
    for (k, &time) in times.iter().enumerate() {
        for i in 0..n {
            for j in i + 1..n {
                let d = (0..3).map(|c| (x[[k, i, c]] - x[[k, j, c]]).powi(2)).sum::<f64>().sqrt();
                if d < radius[i] + radius[j] {
                    return Ok(Some(time));
                }
            }
        }
    }
    Ok(None)
}

/// One scene run in lock step by each engine: the position differences per frame, their figure,
/// and what the summary quotes.
fn lock_step_section(
    dir: &Path,
    work: &Path,
    engines: &[Engine],
    name: &str,
    text: &str,
    title: &str,
) -> Result<Value, Box<dyn std::error::Error>> {
    let (diffs, times) = compare(text, name, work, engines)?;
    let contact = first_contact(&work.join(format!("{name}.magdem.h5")))?;
    let mut table = String::from("| time (s) |");
    let mut rule = String::from("|---|");
    for d in &diffs {
        table += &format!(" {} max (m) | {} median (m) |", d.engine, d.engine);
        rule += "---|---|";
    }
    let _ = writeln!(table, "\n{rule}");
    let frames = diffs.first().map_or(0, |d| d.times.len());
    let step = (frames / 10).max(1);
    let rows = (0..frames).step_by(step).chain((frames > 0 && (frames - 1) % step != 0).then(|| frames - 1));
    for k in rows {
        let _ = write!(table, "| {:.3e} |", diffs[0].times[k]);
        for d in &diffs {
            let _ = write!(table, " {:.3e} | {:.3e} |", d.max[k], d.median[k]);
        }
        table += "\n";
    }
    let floor = |v: f64| v.max(LOG_FLOOR).log10();
    let series: Vec<Series> = diffs
        .iter()
        .flat_map(|d| {
            [
                Series {
                    label: format!("{} max", d.engine),
                    points: d.times.iter().zip(&d.max).map(|(t, v)| (t * 1e3, floor(*v))).collect(),
                    color: engine_colour(d.engine),
                    markers: None,
                    errors: vec![],
                },
                Series {
                    label: format!("{} median", d.engine),
                    points: d.times.iter().zip(&d.median).map(|(t, v)| (t * 1e3, floor(*v))).collect(),
                    color: engine_colour(d.engine),
                    markers: Some(3),
                    errors: vec![],
                },
            ]
        })
        .collect();
    let figure = format!("magnetic-{name}.png");
    line_chart(&dir.join(&figure), title, "time (ms)", "log10 |x_engine − x_magdem| (m)", &series)?;
    let largest = |d: &Difference, keep: &dyn Fn(f64) -> bool| {
        d.times.iter().zip(&d.max).filter(|(t, _)| keep(**t)).map(|(_, v)| *v).fold(f64::NAN, f64::max)
    };
    let contact_time = contact.unwrap_or(f64::INFINITY);
    let engines: Vec<EngineDifference> = diffs
        .iter()
        .map(|d| EngineDifference {
            engine: d.engine,
            largest: largest(d, &|_| true),
            before_contact: largest(d, &|t| t < contact_time),
            after_contact: largest(d, &|t| t >= contact_time),
            final_median: d.median.last().copied().unwrap_or(f64::NAN),
        })
        .collect();
    Ok(context! {
        name => name,
        title => title,
        wall_times => times.iter().map(|(e, t)| context! { engine => e, seconds => t }).collect::<Vec<_>>(),
        table => table,
        figure => figure,
        contact_ms => contact.map(|t| 1e3 * t),
        end_ms => 1e3 * diffs.first().and_then(|d| d.times.last().copied()).unwrap_or(f64::NAN),
        engines => engines,
    })
}

/// The files route's lag error against the exchange interval K, in `engine`.
fn files_route_section(
    dir: &Path,
    work: &Path,
    engine: Engine,
    magdem: &Path,
) -> Result<Value, Box<dyn std::error::Error>> {
    let rows = files_route_lag(engine, &files_route_scene(), &work.join("files-route"), magdem, &FILES_ROUTE_KS)?;
    let (lx, ly): (Vec<f64>, Vec<f64>) = rows.iter().map(|r| ((r.0 as f64).ln(), r.1.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / lx.len() as f64, ly.iter().sum::<f64>() / ly.len() as f64);
    let slope = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
        / lx.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    let mut table = String::from("| K (steps) | largest position difference (m) | wall time (s) |\n|---|---|---|\n");
    for (k, err, wall) in &rows {
        let _ = writeln!(table, "| {k} | {err:.3e} | {wall:.2} |");
    }
    let steps = (FILES_ROUTE_END / FILES_ROUTE_DT).round();
    let series = vec![Series {
        label: format!("{} files route", engine.name()),
        points: rows.iter().map(|r| ((r.0 as f64).log10(), r.1.log10())).collect(),
        color: engine_colour(engine.name()),
        markers: Some(5),
        errors: vec![],
    }];
    line_chart(
        &dir.join("magnetic-files-route.png"),
        "Files route: lag error against exchange interval",
        "log10 K (steps)",
        "log10 max |x_files − x_callback| (m)",
        &series,
    )?;
    Ok(context! {
        engine => engine.name(),
        dt => FILES_ROUTE_DT,
        end_time => FILES_ROUTE_END,
        table => table,
        slope => slope,
        ms_per_exchange => 1e3 * rows[0].2 / (steps / rows[0].0 as f64),
    })
}

/// magdem's dipole forces against LAMMPS' `lj/cut/dipole/cut` on the shipped scenes.
fn dipole_check_section(work: &Path) -> Result<Value, Box<dyn std::error::Error>> {
    let mut table = String::from(
        "| scene | pair sum | particles | largest force (N) | max ‖F_lammps − F_magdem‖ / max ‖F‖ |\n|---|---|---|---|---|\n",
    );
    let mut worst = 0.0_f64;
    for (name, cutoff, label) in [(CASE1, "cutoff_diameters = 15.0", "15 diameters"), ("case1-c0.563", "", "all pairs")]
    {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("experiments/scenes/{name}.toml"));
        let text = std::fs::read_to_string(&path)?.replace("cutoff_diameters = 15.0", cutoff);
        let scene = Scene::parse(&text, name)?;
        let c = reference::dipole_check::check(&scene, &work.join(format!("dipole-{name}")))?;
        worst = worst.max(c.max_relative_error);
        let _ = writeln!(
            table,
            "| {name} | {label} | {} | {:.4e} | {:.2e} |",
            c.particles, c.largest_force, c.max_relative_error
        );
    }
    Ok(context! { table => table, worst => worst, coulomb => COULOMB })
}

/// Runs both scenes and writes `dir/magnetic-verification.md` with one figure per scene.
pub fn verify(
    dir: &Path,
    work: &Path,
    engines: &[Engine],
    case1_end: f64,
    magdem: &Path,
) -> Result<String, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let pair = Scene::parse(PAIR, "pair-approach")?;
    let case1 = case1_scene(case1_end)?;
    let case1_parsed = Scene::parse(&case1, CASE1)?;
    let b0 = pair.spec.field.as_ref().map_or(f64::NAN, |f| f.b0.iter().map(|b| b * b).sum::<f64>().sqrt());
    let concentration = case1_parsed.spec.particles.first().and_then(|p| p.concentration).unwrap_or(f64::NAN);
    let pair_title = format!("Two dipoles closing (exact induction), {b0} T");
    let case1_title =
        format!("Case 1, {concentration} mg/ml, {} particles, Stokes drag", case1_parsed.initial.position.len());
    let mut scenes = vec![];
    for (name, text, title) in [
        ("pair-approach", PAIR.to_string(), pair_title.as_str()),
        (&*format!("{CASE1}-stokes"), case1, case1_title.as_str()),
    ] {
        scenes.push(lock_step_section(dir, work, engines, name, &text, title)?);
    }
    let files_route = match engines.iter().find(|e| e.available()) {
        Some(&engine) => Some(files_route_section(dir, work, engine, magdem)?),
        None => None,
    };
    let dipole = if engines.contains(&Engine::LAMMPS) { Some(dipole_check_section(work)?) } else { None };
    let md = render(
        "verification/magnetic.md",
        &context! {
            version => env!("CARGO_PKG_VERSION"),
            commit => env!("MAGDEM_GIT_COMMIT"),
            engines => engines.iter().map(|e| e.name()).collect::<Vec<_>>(),
            diameter => pair.spec.species[0].diameter,
            diameter_um => 1e6 * pair.spec.species[0].diameter,
            log_floor => LOG_FLOOR.log10(),
            pair => scenes[0].clone(),
            case1 => scenes[1].clone(),
            case1_particles => case1_parsed.initial.position.len(),
            case1_concentration => concentration,
            files_route => files_route,
            dipole => dipole,
        },
    )?;
    std::fs::write(dir.join("magnetic-verification.md"), &md)?;
    Ok(md)
}
