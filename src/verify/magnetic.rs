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
use crate::run::{run, RunOptions};
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;

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
        "case1-c4.5",
        &[
            (STOKES.0, STOKES.1.into()),
            ("end_time = 5.0e-3", format!("end_time = {end_time:e}")),
            ("interval = 5.0e-5", format!("interval = {:e}", end_time / 50.0)),
            ("name = \"case1-c4.5\"", "name = \"case1-c4.5-stokes\"".into()),
        ],
    )?;
    Ok(format!("# verify magnetic: case1-c4.5.toml with Stokes drag, no shielding, no rotational drag\n{text}"))
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
/// the given scheme, dt and multiple-time-stepping ratio: the integrator convergence problem.
pub fn pair_before_contact(scheme: crate::core::integrators::Scheme, dt: f64, slow_every: u64) -> String {
    PAIR.replace("[forces.contact]\n", "")
        .replace("dt = 1.0e-9", &format!("scheme = \"{scheme}\"\ndt = {dt:e}\nslow_every = {slow_every}"))
        .replace("end_time = 2.0e-4", "end_time = 9.6e-5")
        .replace("interval = 2.0e-6", "interval = 9.6e-5")
}

/// The pair approach run for 9e-5 s at dt = 1e-8 s (before contact), for the files-route study.
pub fn files_route_scene() -> String {
    PAIR.replace("dt = 1.0e-9", "dt = 1.0e-8")
        .replace("end_time = 2.0e-4", "end_time = 9.0e-5")
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

/// One scene run in lock step by each engine: the position differences per frame and their figure.
fn lock_step_section(
    dir: &Path,
    work: &Path,
    engines: &[Engine],
    name: &str,
    text: &str,
    title: &str,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut md = String::new();
    let (diffs, times) = compare(text, name, work, engines)?;
    let _ = writeln!(
        md,
        "## {title}\n\nScene `{name}` (its TOML is stored in each trajectory). Wall time: {}.\n",
        times.iter().map(|(e, t)| format!("{e} {t:.1} s")).collect::<Vec<_>>().join(", ")
    );
    md += "| time (s) |";
    let mut rule = String::from("|---|");
    for d in &diffs {
        md += &format!(" {} max (m) | {} median (m) |", d.engine, d.engine);
        rule += "---|---|";
    }
    let _ = writeln!(md, "\n{rule}");
    let frames = diffs.first().map_or(0, |d| d.times.len());
    let step = (frames / 10).max(1);
    let rows = (0..frames).step_by(step).chain((frames > 0 && (frames - 1) % step != 0).then(|| frames - 1));
    for k in rows {
        let _ = write!(md, "| {:.3e} |", diffs[0].times[k]);
        for d in &diffs {
            let _ = write!(md, " {:.3e} | {:.3e} |", d.max[k], d.median[k]);
        }
        md += "\n";
    }
    let floor = |v: f64| v.max(1e-22).log10();
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
    let _ = writeln!(md, "\n![{title}]({figure})\n");
    Ok(md)
}

/// The files route's lag error against the exchange interval K, in `engine`.
fn files_route_section(
    dir: &Path,
    work: &Path,
    engine: Engine,
    magdem: &Path,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut md = String::new();
    let ks = [3, 10, 30, 100, 300];
    let rows = files_route_lag(engine, &files_route_scene(), &work.join("files-route"), magdem, &ks)?;
    let (lx, ly): (Vec<f64>, Vec<f64>) = rows.iter().map(|r| ((r.0 as f64).ln(), r.1.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / lx.len() as f64, ly.iter().sum::<f64>() / ly.len() as f64);
    let slope = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
        / lx.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
    let _ = writeln!(
        md,
        "## The files route: lag error against the exchange interval\n\n\
         Without the shared library (a bare binary, or an MPI run) the deck exchanges files with magdem every K steps \
         (`magdem run --engine {e} --exchange-every K`): it writes the positions, calls `magdem magnetic-forces` through \
         `shell`, reads the forces as atomfile variables and applies them with `fix addforce` until the next exchange, so \
         they lag by up to K steps. Measured on the pair approach (dt = 1e-8 s, 9e-5 s, before contact) in {e}, against \
         the in-process route (every step):\n\n| K (steps) | largest position difference (m) | wall time (s) |\n|---|---|---|",
        e = engine.name()
    );
    for (k, err, wall) in &rows {
        let _ = writeln!(md, "| {k} | {err:.3e} | {wall:.2} |");
    }
    let _ = writeln!(
        md,
        "\nThe error grows as K^{slope:.2} (least-squares slope of log error on log K): first order in the lag, as a force \
         held constant over K steps predicts. The cost is about {:.0} ms per exchange (process start, scene parse, file I/O).\n",
        1e3 * rows[0].2 / (9000.0 / rows[0].0 as f64)
    );
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
    md += "![Files route lag error](magnetic-files-route.png)\n\n";
    Ok(md)
}

/// magdem's dipole forces against LAMMPS' `lj/cut/dipole/cut` on the shipped scenes.
fn dipole_check_section(work: &Path) -> Result<String, Box<dyn std::error::Error>> {
    let mut md = String::new();
    md += "## The dipole force against LAMMPS' own\n\n\
LAMMPS' `lj/cut/dipole/cut` (ε = 0; electric dipoles p = m √(1e-7/k_e), k_e = 8.9876e9) evaluates the dipole–dipole \
forces between the same moments (magdem's, at the initial positions of the shipped scenes) independently of magdem's \
code (`src/reference/dipole_check.rs`).\n\n| scene | pair sum | particles | largest force (N) | max ‖F_lammps − F_magdem‖ / max ‖F‖ |\n|---|---|---|---|---|\n";
    for (name, cutoff, label) in
        [("case1-c4.5", "cutoff_diameters = 15.0", "15 diameters"), ("case1-c0.563", "", "all pairs")]
    {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("experiments/scenes/{name}.toml"));
        let text = std::fs::read_to_string(&path)?.replace("cutoff_diameters = 15.0", cutoff);
        let scene = Scene::parse(&text, name)?;
        let c = reference::dipole_check::check(&scene, &work.join(format!("dipole-{name}")))?;
        let _ = writeln!(
            md,
            "| {name} | {label} | {} | {:.4e} | {:.2e} |",
            c.particles, c.largest_force, c.max_relative_error
        );
    }
    md += "\n";
    Ok(md)
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
    let mut md = String::from("# Magnetic forces in lock step: magdem, LIGGGHTS and LAMMPS\n\n");
    let _ = writeln!(
        md,
        "Generated by `magdem verify magnetic` (magdem {}, commit {}). LIGGGHTS and LAMMPS run in process from their \
         shared libraries; a `fix external pf/callback` hands magdem the positions every step and magdem's core returns \
         the magnetic forces (moments with the scene's mutual induction, dipole and gradient forces). Contact, drag and \
         integration are the reference code's own. The figures show the largest and the median distance between a \
         particle's position in the reference code and in magdem (log10 of metres; exactly equal positions are drawn at −22). The pair touches at about 0.1 ms.\n",
        env!("CARGO_PKG_VERSION"),
        env!("MAGDEM_GIT_COMMIT")
    );
    let case1 = case1_scene(case1_end)?;
    for (name, text, title) in [
        ("pair-approach", PAIR.to_string(), "Two dipoles closing (exact induction), 0.4 T"),
        ("case1-c4.5-stokes", case1, "Case 1, 4.5 mg/ml, 307 particles, Stokes drag"),
    ] {
        md += &lock_step_section(dir, work, engines, name, &text, title)?;
    }
    if let Some(&engine) = engines.iter().find(|e| e.available()) {
        md += &files_route_section(dir, work, engine, magdem)?;
    }
    if engines.contains(&Engine::Lammps) {
        md += &dipole_check_section(work)?;
    }
    md += "## Reading it\n\n\
- **LIGGGHTS** uses the same contact law as magdem (`reports/contact-verification.md`), so with the same magnetic \
forces the trajectories agree to round-off until contact chaos amplifies the last bits of the force sums, which are \
added in a different order.\n\
- **LAMMPS** agrees to round-off until the first contacts with tangential motion, where its Mindlin implementation \
differs from LIGGGHTS' (history rescaled after projection, damping inside the Coulomb check); from there the \
trajectories separate.\n\
- Over longer times differences of either kind grow, because aggregation is chaotic; over a full run the \
comparison that matters is statistical (aggregate size and length distributions, the reproduction report).\n";
    std::fs::write(dir.join("magnetic-verification.md"), &md)?;
    Ok(md)
}
