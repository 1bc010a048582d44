//! An independent check of magdem's dipole–dipole force: LAMMPS' own `lj/cut/dipole/cut` (with
//! ε = 0, so only the dipole terms) evaluates the forces between the same moments at the same
//! positions. LAMMPS works with electric dipoles in SI units (Coulomb constant
//! k_e = 8.9876e9); a magnetic moment m gives the same force as an electric dipole
//! p = m √(μ0/(4π k_e)) = m √(1e-7/k_e) (REFERENCE-CODES.md).

use super::{Engine, ReferenceError};
use crate::core::domain::Domain;
use crate::core::state::{largest_diameter, sphere_volume, State, Vec3};
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

/// The cut-off radius LAMMPS needs for magdem's dipole sum: the scene's cut-off, or for all
/// pairs one beyond the box diagonal (walls only: a periodic box uses magdem's minimum image,
/// which LAMMPS matches only with a cut-off below half the box).
pub fn lammps_cutoff(scene: &Scene, cutoff_diameters: Option<f64>) -> Result<f64, String> {
    let d = &scene.domain;
    let largest_d = largest_diameter(&scene.species);
    match cutoff_diameters {
        Some(c) => Ok(c * largest_d),
        None if d.periodic.iter().any(|&p| p) => {
            Err("all-pairs dipole sums in a periodic box have no LAMMPS equivalent".into())
        }
        None => Ok(1.01 * d.length().norm()),
    }
}

/// Writes `in.dipole` and `data.dipole` into `dir`: the particles with their moments as LAMMPS
/// dipoles under `lj/cut/dipole/cut` (ε = 0). With `run = None` the deck evaluates the forces
/// once and dumps them; with `run = Some((steps, dt))` it evaluates them `steps` times with the
/// particles held still (no integrating fix) and dumps nothing (a timing run).
pub fn write_deck(
    state: &State,
    d: &Domain,
    rc: f64,
    dir: &Path,
    origin: &str,
    run: Option<(u64, f64)>,
) -> Result<(), ReferenceError> {
    std::fs::create_dir_all(dir)?;
    let p = &state.particles;
    let largest_d = p.radius.iter().fold(0.0_f64, |a, r| a.max(2.0 * r));
    let scale = super::lammps::electric_per_magnetic();
    let mut data = format!("magdem dipole deck (scene sha256 {origin})\n\n{} atoms\n1 atom types\n\n", p.len());
    for k in 0..3 {
        let _ = writeln!(data, "{:.17e} {:.17e} {}lo {}hi", d.lo[k], d.hi[k], ["x", "y", "z"][k], ["x", "y", "z"][k]);
    }
    data += "\nAtoms\n\n";
    for i in 0..p.len() {
        let (x, m) = (p.position[i], state.fields.moment[i] * scale);
        let density = p.mass[i] / sphere_volume(p.radius[i]);
        let _ = writeln!(
            data,
            "{} 1 {:.17e} {:.17e} {:.17e} {:.17e} {density:.17e} 0.0 {:.17e} {:.17e} {:.17e}",
            i + 1,
            x.x,
            x.y,
            x.z,
            2.0 * p.radius[i],
            m.x,
            m.y,
            m.z
        );
    }
    std::fs::write(dir.join("data.dipole"), data)?;
    let bflag = |k: usize| if d.periodic[k] { "p" } else { "f" };
    let tail = match run {
        None => "dump forces all custom 1 dump.dipole id fx fy fz\ndump_modify forces sort id format line \"%d %.17g %.17g %.17g\"\nrun 0\n".to_string(),
        Some((steps, dt)) => format!("timestep {dt:.17e}\nthermo {steps}\nrun {steps}\n"),
    };
    let deck = format!(
        "# magdem: dipole forces by LAMMPS' lj/cut/dipole/cut (epsilon 0).\n\
         units si\natom_style hybrid sphere dipole\natom_modify map array sort 0 0\nboundary {} {} {}\n\
         read_data data.dipole\npair_style lj/cut/dipole/cut {rc:.17e}\npair_coeff * * 0.0 {largest_d:e} {rc:.17e}\n\
         neighbor {:e} bin\nneigh_modify one 100000 page 1000000\n{tail}",
        bflag(0),
        bflag(1),
        bflag(2),
        0.2 * largest_d
    );
    std::fs::write(dir.join("in.dipole"), deck)?;
    Ok(())
}

/// Runs `in.dipole` in `dir` with LAMMPS (log in `log.dipole`).
pub fn run_deck(dir: &Path) -> Result<(), ReferenceError> {
    let engine = Engine::LAMMPS;
    let out =
        Command::new(engine.binary()).args(["-in", "in.dipole", "-log", "log.dipole"]).current_dir(dir).output()?;
    if !out.status.success() {
        let text = String::from_utf8_lossy(&out.stdout);
        return Err(ReferenceError::Failed {
            engine: engine.name(),
            code: out.status.code(),
            log: dir.join("log.dipole").display().to_string(),
            tail: text.lines().rev().take(10).collect::<Vec<_>>().join("\n"),
        });
    }
    Ok(())
}

/// magdem's dipole force against LAMMPS' for one configuration.
#[derive(Debug, Clone)]
pub struct DipoleCheck {
    pub particles: usize,
    /// Largest |F_lammps − F_magdem| over particles, relative to the largest |F_magdem|.
    pub max_relative_error: f64,
    pub largest_force: f64,
}

/// Evaluates the dipole forces of `scene`'s initial configuration (moments from magdem's
/// induction model) in magdem and in LAMMPS, and compares them.
pub fn check(scene: &Scene, dir: &Path) -> Result<DipoleCheck, ReferenceError> {
    let engine = Engine::LAMMPS;
    if !engine.available() {
        return Err(ReferenceError::NotInstalled { engine: engine.name(), binary: engine.binary() });
    }
    let unsupported = |why: &str| ReferenceError::Unsupported {
        engine: engine.name(),
        term: "the dipole check".into(),
        why: why.into(),
    };
    let mut field = scene.magnetic_force_field().ok_or_else(|| unsupported("the scene has no magnetic term"))?;
    let cutoff =
        scene.spec.forces.dipole.as_ref().ok_or_else(|| unsupported("the scene has no dipole term"))?.cutoff_diameters;
    field.terms.retain(|t| matches!(t.name(), "moments" | "dipole"));
    let mut state = scene.initial_state();
    field.evaluate(&mut state, scene.dt());
    let p = &state.particles;

    let rc = lammps_cutoff(scene, cutoff).map_err(|why| unsupported(&why))?;
    write_deck(&state, &scene.domain, rc, dir, &scene.hash, None)?;
    run_deck(dir)?;
    let dump = std::fs::read_to_string(dir.join("dump.dipole"))?;
    let rows = dump.lines().skip_while(|l| !l.starts_with("ITEM: ATOMS")).skip(1);
    let force = &state.fields.force;
    let largest_force = force.iter().map(|f| f.norm()).fold(0.0, f64::max);
    let mut worst = 0.0_f64;
    let mut seen = 0;
    for row in rows {
        let v: Vec<f64> = row.split_whitespace().filter_map(|t| t.parse().ok()).collect();
        if v.len() != 4 {
            continue;
        }
        let i = v[0] as usize - 1;
        worst = worst.max((Vec3::new(v[1], v[2], v[3]) - force[i]).norm());
        seen += 1;
    }
    if seen != p.len() {
        return Err(ReferenceError::Dump {
            engine: engine.name(),
            path: dir.join("dump.dipole").display().to_string(),
            message: format!("{seen} rows for {} atoms", p.len()),
        });
    }
    Ok(DipoleCheck { particles: p.len(), max_relative_error: worst / largest_force, largest_force })
}
