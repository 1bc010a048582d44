//! Input decks for LIGGGHTS and LAMMPS, equivalent to a magdem scene term by term.
//!
//! Contact calibration (DESIGN.md §2, REFERENCE-CODES.md):
//! - LIGGGHTS `hertz tangential history` with `coefficientRestitution` is magdem's contact law.
//! - LAMMPS `granular hertz/material … damping tsuji` damps with α(e_in) √(m* · 4/3 E* a)
//!   (a = √(R*δ)), LIGGGHTS with 2√(5/6)|β(e)| √(m* · 2E* a); they are equal when
//!   α(e_in) = √5 |β(e)|, which magdem solves for e_in (tsuji's polynomial is monotonic on
//!   (0, 1]). Mindlin's tangential damping is x_t times the normal one; LIGGGHTS' ratio is
//!   √(kt/Sn) = 2√(G*/E*), which sets x_t. Remaining differences: LAMMPS keeps the magnitude of
//!   the shear history when projecting it and includes damping in its Coulomb check.

use super::{Engine, ReferenceError};
use crate::core::forces::contact::PairMaterial;
use crate::scene::{Boundary, DragLawSpec, Scene, ShieldingSpec};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Files of a written deck, relative to its directory.
#[derive(Debug)]
pub struct WrittenDeck {
    pub input: PathBuf,
    pub data: PathBuf,
    /// Name of the dump file the deck writes.
    pub dump: String,
}

/// Tsuji's damping coefficient α(e) as LAMMPS evaluates it (pair_granular.cpp).
pub fn tsuji_alpha(e: f64) -> f64 {
    let c = [1.2728, -4.2783, 11.087, -22.348, 27.467, -18.022, 4.8218];
    c.iter().rev().fold(0.0, |acc, k| acc * e + k)
}

/// LAMMPS tsuji input e_in whose damping equals LIGGGHTS' damping for restitution `e`; `None`
/// below e ≈ 0.11, where LIGGGHTS damps more than tsuji's α(0) = 1.2728 can.
pub fn lammps_tsuji_input(e: f64) -> Option<f64> {
    let ln_e = e.ln();
    let beta = ln_e / (ln_e * ln_e + std::f64::consts::PI.powi(2)).sqrt();
    let target = 5.0_f64.sqrt() * beta.abs();
    if target > tsuji_alpha(0.0) {
        return None;
    }
    // α decreases monotonically from α(0) = 1.27 to α(1) ≈ 0: bisection.
    let (mut lo, mut hi) = (1e-6, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tsuji_alpha(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

fn unsupported(engine: Engine, term: &str, why: &str) -> ReferenceError {
    ReferenceError::Unsupported { engine: engine.name(), term: term.into(), why: why.into() }
}

/// Refuses what the engine cannot express, naming the term.
pub fn check(engine: Engine, scene: &Scene) -> Result<(), ReferenceError> {
    let f = &scene.spec.forces;
    if let Some(d) = &f.drag {
        if d.law != DragLawSpec::Stokes {
            return Err(unsupported(engine, "forces.drag.law = \"schiller-naumann\"", "fix viscous applies linear (Stokes) drag only"));
        }
        if d.shielding != ShieldingSpec::None {
            return Err(unsupported(engine, "forces.drag.shielding = \"paper\"", "fix viscous has no per-particle shielded area"));
        }
        if d.rotational {
            return Err(unsupported(engine, "forces.drag.rotational = true", "neither build can apply a torque from a fix (no addtorque)"));
        }
        if scene.spec.fluid.as_ref().is_some_and(|fl| fl.velocity != [0.0; 3]) {
            return Err(unsupported(engine, "fluid.velocity", "fix viscous drags towards rest only"));
        }
    }
    if f.gravity.is_some() {
        let densities: Vec<f64> = scene.species.iter().map(|s| s.density).collect();
        if densities.iter().any(|&d| d != densities[0]) {
            return Err(unsupported(engine, "forces.gravity with species of different densities", "fix gravity applies one buoyancy-reduced g to all"));
        }
    }
    if scene.species.iter().any(|s| s.permanent_moment.is_some()) {
        return Err(unsupported(engine, "species.permanent_moment", "no dipole atom style is used"));
    }
    let material = |s: &crate::core::state::Species| (s.youngs_modulus, s.poisson_ratio, s.restitution, s.friction);
    let mixed = scene.species.iter().any(|s| material(s) != material(&scene.species[0]));
    if mixed && scene.spec.forces.contact.is_some() && scene.domain.walls().next().is_some() {
        return Err(unsupported(
            engine,
            "walls with species of different materials",
            "magdem gives each particle a wall of its own material; the decks' walls have one material",
        ));
    }
    if engine == Engine::Liggghts && scene.species.iter().any(|s| s.restitution <= 0.05) {
        return Err(unsupported(engine, "species.restitution ≤ 0.05", "LIGGGHTS requires 0.05 < e ≤ 1"));
    }
    if engine == Engine::Lammps && scene.species.iter().any(|s| s.restitution < 1.0 && lammps_tsuji_input(s.restitution).is_none()) {
        return Err(unsupported(engine, "species.restitution below 0.11", "LAMMPS' tsuji damping cannot reach LIGGGHTS' damping there"));
    }
    if scene.spec.forces.contact.as_ref().is_some_and(|c| !c.walls) && scene.domain.walls().next().is_some() {
        return Err(unsupported(engine, "forces.contact.walls = false", "the decks always put granular walls on wall faces"));
    }
    Ok(())
}

/// How magdem's magnetic forces reach the engine.
#[derive(Debug, Clone, PartialEq)]
pub enum Coupling {
    /// `fix external pf/callback`, set by magdem when it runs the engine in process.
    Callback,
    /// Files only (a bare binary, or MPI): every `every` steps the deck writes the positions,
    /// calls `magdem magnetic-forces` through `shell`, reads the forces as atomfile variables and
    /// applies them with `fix addforce` until the next exchange (a lag of up to `every` steps).
    Files { magdem: PathBuf, every: u64 },
}

/// Writes `in.scene` and `data.scene` for `engine` into `dir` (magnetic forces by callback).
pub fn write(engine: Engine, scene: &Scene, dir: &Path) -> Result<WrittenDeck, ReferenceError> {
    write_with(engine, scene, dir, &Coupling::Callback)
}

/// Writes the deck with the given coupling of the magnetic forces.
pub fn write_with(engine: Engine, scene: &Scene, dir: &Path, coupling: &Coupling) -> Result<WrittenDeck, ReferenceError> {
    check(engine, scene)?;
    std::fs::create_dir_all(dir)?;
    if let Coupling::Files { every, .. } = coupling {
        if *every == 0 || scene.total_steps() % every != 0 {
            return Err(unsupported(engine, "the files route", &format!("the exchange interval ({every} steps) must divide the run ({} steps)", scene.total_steps())));
        }
        std::fs::write(dir.join(SCENE_COPY), &scene.text)?;
    }
    let data = PathBuf::from("data.scene");
    std::fs::write(dir.join(&data), data_file(scene))?;
    let dump = "dump.scene".to_string();
    let input = PathBuf::from("in.scene");
    let deck = input_deck(engine, scene, &data, &dump, coupling);
    std::fs::write(dir.join(&input), deck.main)?;
    for (name, text) in &deck.includes {
        std::fs::write(dir.join(name), text)?;
    }
    Ok(WrittenDeck { input, data, dump })
}

/// The scene as the files route's `magdem magnetic-forces` reads it, beside the deck.
pub const SCENE_COPY: &str = "scene.toml";

/// Id of the fix that receives magdem's magnetic forces (`fix external` in process, `fix
/// addforce` by the files route); the in-process route finds the fix by it to set the callback.
pub const FIX_ID: &str = "magnetic";

/// The initial particles, in the `atom_style granular` / `sphere` data format (id type diameter
/// density x y z), and their velocities and angular velocities.
fn data_file(scene: &Scene) -> String {
    let p = &scene.initial;
    let d = &scene.domain;
    let mut s = format!(
        "magdem scene {} (sha256 {})\n\n{} atoms\n{} atom types\n\n",
        scene.spec.name.as_deref().unwrap_or("unnamed"),
        scene.hash,
        p.len(),
        scene.species.len()
    );
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let _ = writeln!(s, "{:.17e} {:.17e} {axis}lo {axis}hi", d.lo[k], d.hi[k]);
    }
    s += "\nAtoms\n\n";
    for i in 0..p.len() {
        let sp = &scene.species[p.species[i] as usize];
        let x = p.position[i];
        let _ = writeln!(s, "{} {} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}", i + 1, p.species[i] + 1, 2.0 * p.radius[i], sp.density, x.x, x.y, x.z);
    }
    s += "\nVelocities\n\n";
    for i in 0..p.len() {
        let (v, w) = (p.velocity[i], p.angular_velocity[i]);
        let _ = writeln!(s, "{} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}", i + 1, v.x, v.y, v.z, w.x, w.y, w.z);
    }
    s
}

/// The deck: `in.scene` (set-up, output, run control) and the fix files it includes.
struct DeckText {
    main: String,
    /// (file name, content), included in this order.
    includes: Vec<(&'static str, String)>,
}

fn input_deck(engine: Engine, scene: &Scene, data: &Path, dump: &str, coupling: &Coupling) -> DeckText {
    let spec = &scene.spec;
    let species = &scene.species;
    let largest_d = species.iter().map(|s| 2.0 * s.radius).fold(0.0, f64::max);
    let periodic = [spec.domain.boundary.x, spec.domain.boundary.y, spec.domain.boundary.z];
    let bflag = |b: Boundary| if b == Boundary::Periodic { "p" } else { "f" };
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# {} deck written by magdem {} ({}) for scene {} (sha256 {}).\n# Units SI. Edit the scene, not this file.\n",
        engine.name(),
        env!("CARGO_PKG_VERSION"),
        env!("MAGDEM_GIT_COMMIT"),
        spec.name.as_deref().unwrap_or("unnamed"),
        scene.hash
    );
    let atom_style = if engine == Engine::Liggghts { "granular" } else { "sphere" };
    let comm = if engine == Engine::Liggghts { "communicate single vel yes" } else { "comm_modify vel yes" };
    let _ = writeln!(s, "units si\natom_style {atom_style}\natom_modify map array sort 0 0");
    let _ = writeln!(s, "boundary {} {} {}\nnewton off\n{comm}", bflag(periodic[0]), bflag(periodic[1]), bflag(periodic[2]));
    if engine == Engine::Liggghts && species.iter().any(|s| s.youngs_modulus > 1e9 || s.youngs_modulus < 5e6) {
        s += "# LIGGGHTS checks 5e6 <= E <= 1e9 unless told otherwise\nhard_particles yes\n";
    }
    let _ = writeln!(s, "read_data {}", data.display());
    let _ = writeln!(s, "\n# Neighbour skin scaled to the particle size (0.2 diameters).\nneighbor {:.6e} bin", 0.2 * largest_d);
    match engine {
        // LIGGGHTS resets a pair's shear history only while the pair is within
        // contact_distance_factor x (r_i + r_j) but not touching; at its default 1.0 that never
        // happens, and a pair that separates and touches again within the neighbour list starts
        // with the stale history. magdem (and LAMMPS) reset it at separation; 1.1 makes LIGGGHTS do so.
        Engine::Liggghts => s += "neigh_modify delay 0 contact_distance_factor 1.1\n",
        Engine::Lammps => s += "neigh_modify delay 0\n",
    }
    let magnetic = spec.forces.dipole.is_some() || spec.forces.gradient.is_some();
    let includes: Vec<(&'static str, String)> = [
        ("fix.contact", Some(contact_section(engine, scene))),
        ("fix.gravity", gravity_section(scene)),
        ("fix.drag", drag_section(scene)),
        ("fix.magnetic", magnetic.then(|| magnetic_section(engine, coupling))),
    ]
    .into_iter()
    .filter_map(|(name, text)| text.map(|t| (name, t)))
    .collect();
    let _ = writeln!(s, "\ntimestep {:.17e}\nfix integrate all nve/sphere\n", scene.dt());
    for (name, _) in &includes {
        let _ = writeln!(s, "include {name}");
    }
    let every = scene.steps_per_frame();
    let cols = "id type x y z vx vy vz fx fy fz omegax omegay omegaz";
    let fmt = format!("%d %d{}", " %.17g".repeat(12));
    let _ = writeln!(s, "\n# Full-precision dump every {every} steps (one frame per magdem output interval).");
    let _ = writeln!(s, "dump trajectory all custom {every} {dump} {cols}");
    let _ = writeln!(s, "dump_modify trajectory sort id {} \"{fmt}\"", format_keyword(engine));
    let _ = writeln!(s, "thermo {}", every.max(1000));
    match coupling {
        Coupling::Files { magdem, every: k } if magnetic => {
            let _ = writeln!(
                s,
                "\n# Files route: every {k} steps the positions go out, magdem computes the magnetic forces\n\
                 # (moments carried in forces.moments), and fix.magnetic's atomfile variables read them back.\n\
                 variable exchange loop {}\nlabel exchange_loop\n\
                 write_dump all custom positions.dump id x y z modify sort id {} \"%d %.17g %.17g %.17g\"\n\
                 shell {} magnetic-forces {SCENE_COPY} positions.dump forces\n\
                 variable fx delete\nvariable fy delete\nvariable fz delete\n\
                 variable fx atomfile forces.x\nvariable fy atomfile forces.y\nvariable fz atomfile forces.z\n\
                 run {k}\nnext exchange\njump SELF exchange_loop",
                scene.total_steps() / k,
                format_keyword(engine),
                magdem.display()
            );
        }
        _ => {
            let _ = writeln!(s, "run {}", scene.total_steps());
        }
    }
    DeckText { main: s, includes }
}

fn format_keyword(engine: Engine) -> &'static str {
    if engine == Engine::Liggghts { "format" } else { "format line" }
}

/// Materials, pair style and walls.
fn contact_section(engine: Engine, scene: &Scene) -> String {
    let species = &scene.species;
    let n_types = species.len();
    let mut s = String::new();
    if scene.spec.forces.contact.is_none() {
        return "# No contact term in the scene.\npair_style none\n".into();
    }
    s += "# Contact: Hertz normal, Mindlin tangential with history and Coulomb limit, damping from restitution.\n";
    match engine {
        Engine::Liggghts => {
            let list = |f: &dyn Fn(usize) -> f64| (0..n_types).map(|k| format!("{:e}", f(k))).collect::<Vec<_>>().join(" ");
            let matrix = |f: &dyn Fn(usize, usize) -> f64| {
                (0..n_types * n_types).map(|k| format!("{:e}", f(k / n_types, k % n_types))).collect::<Vec<_>>().join(" ")
            };
            let _ = writeln!(s, "fix m1 all property/global youngsModulus peratomtype {}", list(&|k| species[k].youngs_modulus));
            let _ = writeln!(s, "fix m2 all property/global poissonsRatio peratomtype {}", list(&|k| species[k].poisson_ratio));
            let _ = writeln!(
                s,
                "fix m3 all property/global coefficientRestitution peratomtypepair {n_types} {}",
                matrix(&|a, b| 0.5 * (species[a].restitution + species[b].restitution))
            );
            let _ = writeln!(
                s,
                "fix m4 all property/global coefficientFriction peratomtypepair {n_types} {}",
                matrix(&|a, b| 0.5 * (species[a].friction + species[b].friction))
            );
            s += "pair_style gran model hertz tangential history\npair_coeff * *\n";
        }
        Engine::Lammps => {
            s += "# (E, nu) per pair solved so LAMMPS' effective moduli equal magdem's; tsuji input calibrated.\npair_style granular\n";
            for a in 0..n_types {
                for b in a..n_types {
                    let _ = writeln!(s, "pair_coeff {} {} {}", a + 1, b + 1, lammps_granular_model(&species[a], &species[b], false));
                }
            }
        }
    }
    let d = &scene.domain;
    let walls: Vec<(usize, &str)> = (0..3).filter(|&k| !d.periodic[k]).map(|k| (k, ["xplane", "yplane", "zplane"][k])).collect();
    if !walls.is_empty() {
        s += "# Walls: planes of infinite radius and mass, of the first species' material.\n";
    }
    for (k, plane) in walls {
        let (lo, hi) = (d.lo[k], d.hi[k]);
        match engine {
            Engine::Liggghts => {
                let _ = writeln!(s, "fix wall_{plane}_lo all wall/gran model hertz tangential history primitive type 1 {plane} {lo:.17e}");
                let _ = writeln!(s, "fix wall_{plane}_hi all wall/gran model hertz tangential history primitive type 1 {plane} {hi:.17e}");
            }
            Engine::Lammps => {
                let _ = writeln!(s, "fix wall_{plane} all wall/gran granular {} {plane} {lo:.17e} {hi:.17e}", lammps_granular_model(&species[0], &species[0], true));
            }
        }
    }
    s
}

fn gravity_section(scene: &Scene) -> Option<String> {
    let g = scene.spec.forces.gravity.as_ref()?;
    let rho_f = scene.spec.fluid.as_ref().map_or(0.0, |f| f.density);
    let gv = nalgebra::Vector3::from(g.g);
    let reduced = gv.norm() * (1.0 - rho_f / scene.species[0].density);
    let dir = gv / gv.norm();
    Some(format!(
        "# Weight minus buoyancy: |g| (1 - rho_f/rho_p).\nfix gravity all gravity {reduced:.17e} vector {:.17e} {:.17e} {:.17e}\n",
        dir.x, dir.y, dir.z
    ))
}

fn drag_section(scene: &Scene) -> Option<String> {
    scene.spec.forces.drag.as_ref()?;
    let mu = scene.spec.fluid.as_ref().map_or(0.0, |f| f.viscosity);
    let gamma = |k: usize| crate::core::forces::drag::Drag::stokes_coefficient(mu, scene.species[k].radius);
    let mut s = format!("# Stokes drag 6 pi mu a per type.\nfix drag all viscous {:.17e}", gamma(0));
    for k in 1..scene.species.len() {
        let _ = write!(s, " scale {} {:.17e}", k + 1, gamma(k) / gamma(0));
    }
    Some(s + "\n")
}

fn magnetic_section(engine: Engine, coupling: &Coupling) -> String {
    let id = FIX_ID;
    match coupling {
        Coupling::Callback => format!(
            "# Magnetic forces (moments with mutual induction, dipole and gradient forces) come from\n\
             # magdem's own code every step through this fix: run the deck with\n\
             # `magdem run --engine {}`, which sets the callback.\nfix {id} all external pf/callback 1 1\n",
            engine.name()
        ),
        Coupling::Files { .. } => format!(
            "# Magnetic forces from magdem by file exchange (see the loop in in.scene): per-atom\n\
             # variables read from atomfiles, applied by fix addforce until the next exchange.\n\
             variable fx atom 0.0\nvariable fy atom 0.0\nvariable fz atom 0.0\nfix {id} all addforce v_fx v_fy v_fz\n"
        ),
    }
}

/// Young's modulus and Poisson ratio to give LAMMPS so that its effective moduli equal magdem's
/// E* and G* for a pair of species, or for a particle against a wall.
///
/// LAMMPS 2021 forms them as E/(2(1 − ν²)) and E/(4(2 − ν)(1 + ν)) for an explicit pair
/// coefficient, and as E/(2(1 − ν)) and E/(4(2 − ν)(1 + ν)) in `fix wall/gran` (fix_wall_gran.cpp);
/// its automatic mixing of unlike types is not used (the 2021 build's mixing is broken). Solving
/// for (E, ν) with r = E*/G*: pair ν = (r − 4)/(r − 2); wall 2ν² − (2 + r)ν + (r − 4) = 0.
pub fn lammps_equivalent_moduli(m: &PairMaterial, wall: bool) -> (f64, f64) {
    let r = m.e_star / m.g_star;
    if wall {
        let b = 2.0 + r;
        let nu = (b - (b * b - 8.0 * (r - 4.0)).sqrt()) / 4.0;
        (2.0 * (1.0 - nu) * m.e_star, nu)
    } else {
        let nu = (r - 4.0) / (r - 2.0);
        (2.0 * (1.0 - nu * nu) * m.e_star, nu)
    }
}

/// `hertz/material E η ν tangential mindlin NULL x_t μ damping …` for a pair of species (or a
/// species against a wall): tsuji damping calibrated to LIGGGHTS, or no damping when e = 1
/// (tsuji's polynomial is 3e-4, not 0, at e = 1).
fn lammps_granular_model(a: &crate::core::state::Species, b: &crate::core::state::Species, wall: bool) -> String {
    let m = PairMaterial::new(a, b);
    let (e_mod, nu) = lammps_equivalent_moduli(&m, wall);
    let x_t = 2.0 * (m.g_star / m.e_star).sqrt();
    let restitution = 0.5 * (a.restitution + b.restitution);
    let damping = if restitution >= 1.0 {
        "0 {nu} tangential mindlin NULL 0 {mu} damping viscoelastic".to_string()
    } else {
        let e_in = lammps_tsuji_input(restitution).expect("checked by deck::check");
        format!("{e_in:.17e} {{nu}} tangential mindlin NULL {x_t:.17e} {{mu}} damping tsuji")
    };
    format!("hertz/material {e_mod:.17e} {}", damping.replace("{nu}", &format!("{nu:.17e}")).replace("{mu}", &m.friction.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lammps_moduli_reproduce_the_effective_ones() {
        let sp = crate::scene::Scene::parse(
            "version = 1\n[domain]\nlo = [0,0,0]\nhi = [1,1,1]\n[[species]]\nname = \"a\"\ndiameter = 0.1\ndensity = 1000.0\nyoungs_modulus = 2.0e9\npoisson_ratio = 0.3\nfriction = 0.5\nrestitution = 0.5\n\
             [[species]]\nname = \"b\"\ndiameter = 0.1\ndensity = 1000.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\n\
             [[particles]]\nspecies = \"a\"\npositions = [[0.5, 0.5, 0.5]]\n[integration]\ndt = 1e-6\nend_time = 1e-5\n",
            "t",
        )
        .unwrap()
        .species;
        for (a, b) in [(&sp[0], &sp[0]), (&sp[0], &sp[1]), (&sp[1], &sp[1])] {
            let m = PairMaterial::new(a, b);
            let (e, nu) = lammps_equivalent_moduli(&m, false);
            assert!((e / (2.0 * (1.0 - nu * nu)) / m.e_star - 1.0).abs() < 1e-12);
            assert!((e / (4.0 * (2.0 - nu) * (1.0 + nu)) / m.g_star - 1.0).abs() < 1e-12);
            let (e, nu) = lammps_equivalent_moduli(&m, true);
            assert!((e / (2.0 * (1.0 - nu)) / m.e_star - 1.0).abs() < 1e-12);
            assert!((e / (4.0 * (2.0 - nu) * (1.0 + nu)) / m.g_star - 1.0).abs() < 1e-12);
        }
        // Same material, pair: LAMMPS gets the material's own E and ν back.
        let (e, nu) = lammps_equivalent_moduli(&PairMaterial::new(&sp[1], &sp[1]), false);
        assert!((e / 1.0e9 - 1.0).abs() < 1e-12 && (nu - 0.5).abs() < 1e-12);
    }

    #[test]
    fn tsuji_calibration_matches_liggghts_damping() {
        assert_eq!(lammps_tsuji_input(0.1), None);
        for e in [0.12, 0.3, 0.5, 0.7, 0.9, 0.99] {
            let ln_e: f64 = f64::ln(e);
            let beta = ln_e / (ln_e * ln_e + std::f64::consts::PI.powi(2)).sqrt();
            let e_in = lammps_tsuji_input(e).unwrap();
            assert!((tsuji_alpha(e_in) - 5.0_f64.sqrt() * beta.abs()).abs() < 1e-12, "e = {e}");
        }
        // REFERENCE-CODES.md measured input 0.365 for e = 0.5.
        assert!((lammps_tsuji_input(0.5).unwrap() - 0.365).abs() < 0.003);
    }
}
