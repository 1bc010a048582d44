//! `magdem verify contacts`: every case of [`super::contact_cases`] (the Chung & Ooi (2011)
//! single-contact benchmark types with the paper's material) run in magdem, LIGGGHTS and LAMMPS
//! at the same dt. Every engine's run lands in an HDF5 trajectory, one measurement reads all
//! three, and [`super::contacts_report`] writes the comparison.

use super::contact_cases::{cases, Case, Geometry, Metrics, Outcome, DIAMETER};
use super::contacts_report::{self, Report};
use crate::io::trajectory::Trajectory;
use crate::reference::{self, Engine};
use crate::run::{run, RunOptions};
use crate::scene::Scene;
use std::path::Path;

/// Reads a case's trajectory: overlap crossings (linear interpolation) give the duration;
/// restitution is −v_n,after / v_n,before of the relative normal velocity.
pub fn measure(case: &Case, path: &Path) -> hdf5::Result<(Metrics, Vec<(f64, f64)>)> {
    let t = Trajectory::open(path).map_err(|e| e.to_string())?;
    let x = t.all_vectors("position")?;
    let v = t.all_vectors("velocity")?;
    let w = t.all_vectors("angular_velocity")?;
    let f = t.all_vectors("force")?;
    let times = t.times()?;
    let (a1, a2) = case.radii();
    let frames = times.len();
    let overlap = |k: usize| match case.geometry {
        Geometry::Pair { .. } => {
            let d = ((x[[k, 1, 0]] - x[[k, 0, 0]]).powi(2)
                + (x[[k, 1, 1]] - x[[k, 0, 1]]).powi(2)
                + (x[[k, 1, 2]] - x[[k, 0, 2]]).powi(2))
            .sqrt();
            a1 + a2 - d
        }
        Geometry::Wall => a1 - (x[[k, 0, 2]] + 4.0 * DIAMETER),
    };
    // Normal velocity (approach positive) and the normal force on sphere 1 (repulsion positive).
    let vn = |k: usize| match case.geometry {
        Geometry::Pair { .. } => v[[k, 0, 0]] - v[[k, 1, 0]],
        Geometry::Wall => -v[[k, 0, 2]],
    };
    let fn_ = |k: usize| match case.geometry {
        Geometry::Pair { .. } => -f[[k, 0, 0]],
        Geometry::Wall => f[[k, 0, 2]],
    };
    let (mut start, mut end, mut max_overlap) = (None, None, 0.0_f64);
    let mut curve = vec![];
    for k in 1..frames {
        let (o0, o1) = (overlap(k - 1), overlap(k));
        let cross = times[k - 1] + (times[k] - times[k - 1]) * o0 / (o0 - o1);
        if o0 <= 0.0 && o1 > 0.0 && start.is_none() {
            start = Some(cross);
        }
        if o0 > 0.0 && o1 <= 0.0 && end.is_none() {
            end = Some(cross);
        }
        max_overlap = max_overlap.max(o1);
        if o1 > 0.0 && end.is_none() {
            curve.push((o1, fn_(k)));
        }
    }
    let last = frames - 1;
    let m = Metrics {
        restitution: -vn(last) / vn(0),
        duration: match (start, end) {
            (Some(s), Some(e)) => e - s,
            _ => f64::NAN,
        },
        max_overlap,
        rebound_tangential: v[[last, 0, 0]],
        rebound_spin: w[[last, 0, 1]],
        rebound_angle: v[[last, 0, 0]].atan2(v[[last, 0, 2]].abs()).to_degrees(),
    };
    Ok((m, curve))
}

/// Runs `case` in magdem and in every available reference engine under `dir`.
pub fn run_case(case: &Case, dir: &Path, engines: &[Engine]) -> Result<Vec<Outcome>, Box<dyn std::error::Error>> {
    let slug: String = case.name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    let scene = Scene::parse(&case.scene_text(), &case.name)?;
    let mut outcomes = vec![];
    let native = dir.join(format!("{slug}.magdem.h5"));
    run(&scene, &native, &RunOptions { overwrite: true, ..Default::default() })?;
    let (metrics, force_overlap) = measure(case, &native)?;
    outcomes.push(Outcome { case: case.clone(), engine: "magdem", metrics, force_overlap });
    for &engine in engines {
        let out = dir.join(format!("{slug}.{}.h5", engine.name()));
        reference::run(engine, &scene, &dir.join(format!("{slug}.{}", engine.name())), &out)?;
        let (metrics, force_overlap) = measure(case, &out)?;
        outcomes.push(Outcome { case: case.clone(), engine: engine.name(), metrics, force_overlap });
    }
    Ok(outcomes)
}

/// Runs every case and writes `dir/contact-verification.md` and its figures.
pub fn verify(dir: &Path, work: &Path, engines: &[Engine]) -> Result<Report, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    std::fs::create_dir_all(work)?;
    let mut all = vec![];
    for case in cases() {
        all.extend(run_case(&case, work, engines)?);
    }
    contacts_report::write(dir, &all, engines)
}
