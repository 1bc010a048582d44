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

use super::dialect::{Axis, CylinderWall};
use super::lammps::electric_per_magnetic;
use super::{Engine, ReferenceError};
use crate::core::flow::Flow;
use crate::scene::{
    Boundary, BoundarySpec, ContactSpec, DipoleSpec, DomainSpec, DragLawSpec, DragSpec, FieldSpec, FluidSpec,
    ForcesSpec, GradientSpec, GravitySpec, IntegrationSpec, NormalSpec, OutputSpec, ParticleGroupSpec, Scene,
    SceneSpec, ShieldingSpec, SpeciesSpec, StabilitySpec, TangentialSpec, VesselSpec,
};
use nalgebra::Matrix3;
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

fn unsupported(engine: Engine, term: &str, why: &str) -> ReferenceError {
    ReferenceError::Unsupported { engine: engine.name(), term: term.into(), why: why.into() }
}

/// Refuses what the engine cannot express, naming the term.
///
/// Every field of the scene spec is named here, without `..`, with what the deck does with it: a
/// field or term added to the spec fails to compile here until the deck writes it or refuses it.
/// The refusals come in a fixed order (vessel, exits, drag, thermal, gravity, species, contact); the
/// first one is reported.
pub fn check(engine: Engine, scene: &Scene) -> Result<(), ReferenceError> {
    let SceneSpec {
        // Metadata; the name heads the deck.
        version: _,
        name: _,
        description: _,
        // Placement: the data file holds the placed particles (`scene.initial`): positions,
        // velocities, angular velocities, and each species' type, diameter and density.
        seed: _,
        particles,
        // A started scene's particles are in `scene.initial` like placed ones; its contact
        // history is not (a data file cannot carry springs): the deck says so.
        start: _,
        // The box: the data file's bounds, the `boundary` line, granular walls on wall faces.
        domain: DomainSpec { lo: _, hi: _, boundary: BoundarySpec { x, y, z } },
        fluid,
        field,
        species,
        forces: ForcesSpec { contact, dipole, gradient, drag, gravity, thermal },
        integration,
        output,
        stability,
        exits,
    } = &scene.spec;
    for group in particles {
        let ParticleGroupSpec {
            species: _,
            positions: _,
            velocities: _,
            angular_velocities: _,
            count: _,
            concentration: _,
            lattice: _,
            region: _,
            order: _,
            // Placement inside the vessel: the data file holds the placed particles.
            in_vessel: _,
        } = group;
    }
    for boundary in [x, y, z] {
        match boundary {
            Boundary::Wall | Boundary::Periodic => {} // `f` or `p` in the `boundary` line
        }
    }
    // Density: the buoyancy in fix gravity; viscosity: fix viscous (or the vessel's fix addforce);
    // velocity: refused with drag (without drag it acts on nothing); vessel: its wall and flow.
    let fluid_velocity =
        fluid.as_ref().map(|FluidSpec { density: _, viscosity: _, velocity, vessel: _, grid: _ }| velocity);
    if fluid.as_ref().is_some_and(|f| f.grid.is_some()) {
        return Err(unsupported(engine, "fluid.grid", "the decks write no flow field read from a grid"));
    }
    let vessel = match fluid.as_ref().and_then(|f| f.vessel.as_ref()) {
        Some(v) => Some(check_vessel(engine, scene, v)?),
        None => None,
    };
    if exits.is_some() {
        return Err(unsupported(engine, "exits", "the decks remove no particles (outlets and capture are magdem's)"));
    }
    // Magnetic terms: magdem computes the moments (from the applied field, with the induction,
    // cut-off and iteration settings) and the dipole and gradient forces, and hands them to
    // fix.magnetic (`fix external` in process, `fix addforce` by the files route). A linear
    // field (`gradient` or `gradient_mri`) is magdem's alone, as are coils and a waveform; but
    // the exchanges evaluate the field at t = 0, and the native deck holds fixed moments: both
    // are refused until the couplings carry the time and the coils.
    if let Some(FieldSpec { b0: _, gradient: _, gradient_mri: _, coils, waveform }) = field {
        if !coils.is_empty() {
            return Err(unsupported(
                engine,
                "field.coils",
                "the couplings are verified with a linear field only; a coil field is not handed to the engines yet",
            ));
        }
        if waveform.is_some() {
            return Err(unsupported(
                engine,
                "field.waveform",
                "the couplings evaluate the magnetic forces without the simulated time",
            ));
        }
    }
    if let Some(DipoleSpec {
        induction: _,
        cutoff_diameters: _,
        paper_radius_diameters: _,
        tolerance: _,
        max_iterations: _,
        dense_max: _,
    }) = dipole
    {}
    if let Some(GradientSpec {}) = gradient {}
    // The engines integrate with nve/sphere (velocity Verlet) at dt up to end_time whatever the
    // scheme; their trajectories' `integrator` attribute says so. They order their atoms
    // themselves (LAMMPS' atom_modify sort), whatever renumber_every says.
    let IntegrationSpec { scheme: _, dt: _, end_time: _, renumber_every: _ } = integration;
    // A full-precision dump (with forces) every output interval; the engines record no contact lists.
    let OutputSpec { interval: _, forces: _, contacts: _ } = output;
    // on_unstable_dt applied when the scene was built; the engines have no stability monitor.
    let StabilitySpec { on_unstable_dt: _, max_overlap: _, max_step_fraction: _ } = stability;

    if let Some(drag) = drag {
        check_drag(engine, drag, fluid_velocity)?;
    }
    // LAMMPS' fix langevin (with omega yes) would express it for Stokes drag: not written yet.
    if thermal.is_some() {
        return Err(unsupported(engine, "forces.thermal", "the decks write no thermal forces"));
    }
    if let Some(GravitySpec { g: _ }) = gravity {
        // fix gravity: |g| (1 − ρ_f/ρ_p) along g, one ρ_p for all.
        if species.iter().any(|s| s.density != species[0].density) {
            return Err(unsupported(
                engine,
                "forces.gravity with species of different densities",
                "fix gravity applies one buoyancy-reduced g to all",
            ));
        }
    }
    let walls = scene.domain.walls().next().is_some();
    let vessel_wall = vessel.is_some_and(|v| v.wall.is_some());
    check_species(engine, species, contact.is_some() && walls || vessel_wall)?;
    if let Some(ContactSpec { particles, walls: with_walls, normal, stiffness: _, tangential }) = contact {
        if !particles {
            return Err(unsupported(
                engine,
                "forces.contact.particles = false",
                "the decks write one granular pair style for every pair",
            ));
        }
        // The decks write Hertz–Mindlin with history (§10.2 of docs/model.md) only.
        match normal {
            NormalSpec::Hertz => {}
            NormalSpec::Hooke => {
                return Err(unsupported(
                    engine,
                    "forces.contact.normal = \"hooke\"",
                    "the decks write the Hertz law calibrated against magdem's",
                ))
            }
        }
        match tangential {
            TangentialSpec::Mindlin => {}
            TangentialSpec::None => {
                return Err(unsupported(
                    engine,
                    "forces.contact.tangential = \"none\"",
                    "the decks write Mindlin's spring with history",
                ))
            }
        }
        if !with_walls && walls {
            return Err(unsupported(
                engine,
                "forces.contact.walls = false",
                "the decks always put granular walls on wall faces",
            ));
        }
    }
    Ok(())
}

/// A straight vessel as the decks write it: the cylinder wall (with wall contacts) and the
/// steady flow along a coordinate axis.
#[derive(Debug, Clone, Copy)]
struct DeckVessel {
    wall: Option<CylinderWall>,
    /// The axis and the flow's sign along it.
    axis: Axis,
    sign: f64,
}

/// A `[fluid.vessel]`: steady Poiseuille flow only (`fix addforce` of atom-style variables
/// writes u(x) = 2ū(1 − r²/R²) along the axis), along x, y or z, with the engine's cylinder
/// primitive as its wall when the contact term has walls.
fn check_vessel(engine: Engine, scene: &Scene, spec: &VesselSpec) -> Result<DeckVessel, ReferenceError> {
    let VesselSpec { centre: _, axis: _, radius: _, mean_speed: _, period, harmonics } = spec;
    if period.is_some() || !harmonics.is_empty() {
        return Err(unsupported(
            engine,
            "fluid.vessel.period (pulsatile flow)",
            "the decks write steady Poiseuille flow; Womersley's profile needs Bessel functions of complex argument",
        ));
    }
    let geometry = crate::scene::fluid::vessel(spec);
    let (axis, sign) = Axis::of(&geometry.axis).ok_or_else(|| {
        unsupported(
            engine,
            "fluid.vessel.axis not along x, y or z",
            "the engines' cylinder walls and the decks' flow variables lie along a coordinate axis",
        )
    })?;
    let with_walls = scene.spec.forces.contact.as_ref().is_some_and(|c| c.walls);
    let wall = with_walls.then_some(CylinderWall {
        axis,
        centre: geometry.centre,
        radius: geometry.radius,
        periodic: scene.domain.periodic,
    });
    if let Some(wall) = &wall {
        engine
            .dialect()
            .cylinder_wall(wall, &scene.species[0])
            .map_err(|(term, why)| unsupported(engine, term, why))?;
    }
    Ok(DeckVessel { wall, axis, sign })
}

/// fix viscous: linear drag towards rest, 6π μ a per type.
fn check_drag(engine: Engine, drag: &DragSpec, fluid_velocity: Option<&[f64; 3]>) -> Result<(), ReferenceError> {
    // The touch tolerance only serves the shielding, the refactorisation interval the RPY law.
    let DragSpec { law, shielding, rotational, touch_tolerance: _, refactor_every: _, wall } = drag;
    if wall.is_some() {
        return Err(unsupported(
            engine,
            "forces.drag.wall",
            "fix viscous applies one isotropic coefficient per type, not a wall factor per particle and direction",
        ));
    }
    match law {
        DragLawSpec::Stokes => {}
        DragLawSpec::SchillerNaumann => {
            return Err(unsupported(
                engine,
                "forces.drag.law = \"schiller-naumann\"",
                "fix viscous applies linear (Stokes) drag only",
            ))
        }
        DragLawSpec::Rpy => {
            return Err(unsupported(
                engine,
                "forces.drag.law = \"rpy\"",
                "fix viscous drags each sphere alone (no hydrodynamic interactions)",
            ))
        }
    }
    match shielding {
        ShieldingSpec::None => {}
        ShieldingSpec::Paper => {
            return Err(unsupported(
                engine,
                "forces.drag.shielding = \"paper\"",
                "fix viscous has no per-particle shielded area",
            ))
        }
    }
    if *rotational {
        return Err(unsupported(
            engine,
            "forces.drag.rotational = true",
            "neither build can apply a torque from a fix (no addtorque)",
        ));
    }
    if fluid_velocity.is_some_and(|v| *v != [0.0; 3]) {
        return Err(unsupported(engine, "fluid.velocity", "fix viscous drags towards rest only"));
    }
    Ok(())
}

/// The species' materials go into the contact section; their magnetic properties act through
/// magdem's magnetic forces; a permanent moment is refused.
fn check_species(engine: Engine, species: &[SpeciesSpec], wall_contacts: bool) -> Result<(), ReferenceError> {
    for s in species {
        let SpeciesSpec {
            name: _,
            diameter: _,
            density: _,
            youngs_modulus: _,
            poisson_ratio: _,
            friction: _,
            restitution: _,
            relative_permeability: _,
            susceptibility: _,
            saturation_magnetisation: _,
            saturation_law: _,
            // With the other magnetic keys: magdem's moments, handed over by the callback.
            core_diameter: _,
            temperature: _,
            permanent_moment,
            size,
        } = s;
        if permanent_moment.is_some() {
            return Err(unsupported(engine, "species.permanent_moment", "no dipole atom style is used"));
        }
        if size.is_some() {
            return Err(unsupported(
                engine,
                "species.size",
                "fix viscous gives one drag coefficient per atom type; drawn diameters need one per atom",
            ));
        }
    }
    let material = |s: &SpeciesSpec| (s.youngs_modulus, s.poisson_ratio, s.restitution, s.friction);
    if wall_contacts && species.iter().any(|s| material(s) != material(&species[0])) {
        return Err(unsupported(
            engine,
            "walls with species of different materials",
            "magdem gives each particle a wall of its own material; the decks' walls have one material",
        ));
    }
    match engine.dialect().refuse_species(species) {
        Some((term, why)) => Err(unsupported(engine, term, why)),
        None => Ok(()),
    }
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
    /// LAMMPS only, no magdem in the loop: the fixed-moment model (induction `none`, a dipole
    /// cut-off, no gradient) in LAMMPS' own `lj/cut/dipole/cut` (ε = 0) overlaid on the granular
    /// pair style, the moments magdem's at t = 0 as electric dipoles (docs/model.md §10.7). The
    /// deck runs unchanged under `mpirun -np N lmp`.
    Native,
}

/// Writes `in.scene` and `data.scene` for `engine` into `dir` (magnetic forces by callback).
pub fn write(engine: Engine, scene: &Scene, dir: &Path) -> Result<WrittenDeck, ReferenceError> {
    write_with(engine, scene, dir, &Coupling::Callback)
}

/// Writes the deck with the given coupling of the magnetic forces.
pub fn write_with(
    engine: Engine,
    scene: &Scene,
    dir: &Path,
    coupling: &Coupling,
) -> Result<WrittenDeck, ReferenceError> {
    check(engine, scene)?;
    let moments = match coupling {
        Coupling::Native => Some(native_moments(engine, scene)?),
        _ => None,
    };
    std::fs::create_dir_all(dir)?;
    if let Coupling::Files { every, .. } = coupling {
        if *every == 0 || !scene.total_steps().is_multiple_of(*every) {
            return Err(unsupported(
                engine,
                "the files route",
                &format!("the exchange interval ({every} steps) must divide the run ({} steps)", scene.total_steps()),
            ));
        }
        std::fs::write(dir.join(SCENE_COPY), &scene.text)?;
    }
    let data = PathBuf::from("data.scene");
    std::fs::write(dir.join(&data), data_file(scene, moments.as_deref()))?;
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

/// The moments of the native deck: magdem's at t = 0 (induction `none`: χ_eff V H_ext, capped
/// by any saturation law), refused for what LAMMPS' fixed dipoles cannot hold.
fn native_moments(engine: Engine, scene: &Scene) -> Result<Vec<crate::core::state::Vec3>, ReferenceError> {
    use crate::scene::InductionSpec;
    let native = |term: &str, why: &str| Err(unsupported(engine, term, why));
    if !engine.dialect().native_dipoles() {
        return native("a native magnetic deck", "the engine has no dipole pair style; only LAMMPS' deck is native");
    }
    let f = &scene.spec.forces;
    let Some(dipole) = &f.dipole else {
        return native("a native deck without forces.dipole", "there are no moments to give LAMMPS");
    };
    if dipole.induction != InductionSpec::None {
        return native(
            "forces.dipole.induction other than \"none\" in a native deck",
            "LAMMPS holds fixed dipoles; mutual induction is magdem's (run it by callback or files)",
        );
    }
    if dipole.cutoff_diameters.is_none() {
        return native("forces.dipole without cutoff_diameters in a native deck", "lj/cut/dipole/cut needs a cut-off");
    }
    if f.gradient.is_some() || scene.spec.field.as_ref().is_some_and(|fd| fd.linear_gradient() != Matrix3::zeros()) {
        return native(
            "a field gradient in a native deck",
            "the moments would vary with position and the gradient force has no LAMMPS equivalent",
        );
    }
    Ok(scene.initial_magnetic_state().expect("a scene with a dipole term has magnetic forces").fields.moment)
}

/// The initial particles, in the `atom_style granular` / `sphere` data format (id type diameter
/// density x y z), or with `moments` the `hybrid sphere dipole` one (id type x y z diameter
/// density q px py pz, the moments as electric dipoles p = m √(μ0/(4π k_e)), §10.4), and their
/// velocities and angular velocities.
fn data_file(scene: &Scene, moments: Option<&[crate::core::state::Vec3]>) -> String {
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
    s += if moments.is_some() { "\nAtoms # hybrid\n\n" } else { "\nAtoms\n\n" };
    let electric = electric_per_magnetic();
    for i in 0..p.len() {
        let sp = &scene.species[p.species[i] as usize];
        let (x, id, ty, d) = (p.position[i], i + 1, p.species[i] + 1, 2.0 * p.radius[i]);
        let _ = match moments {
            None => writeln!(s, "{id} {ty} {d:.17e} {:.17e} {:.17e} {:.17e} {:.17e}", sp.density, x.x, x.y, x.z),
            Some(m) => {
                let q = m[i] * electric;
                writeln!(
                    s,
                    "{id} {ty} {:.17e} {:.17e} {:.17e} {d:.17e} {:.17e} 0.0 {:.17e} {:.17e} {:.17e}",
                    x.x, x.y, x.z, sp.density, q.x, q.y, q.z
                )
            }
        };
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
    let native = *coupling == Coupling::Native;
    let dialect = engine.dialect();
    let atom_style = dialect.atom_style(native);
    let comm = dialect.communicate();
    // The callback and the files route exchange forces in atom order, so atoms stay unsorted; a
    // native deck lets LAMMPS sort them in space (2.4-2.7x faster at 34 000 atoms, §10.7).
    let sort = if native { "" } else { " sort 0 0" };
    let _ = writeln!(s, "units si\natom_style {atom_style}\natom_modify map array{sort}");
    let _ = writeln!(
        s,
        "boundary {} {} {}\nnewton off\n{comm}",
        bflag(periodic[0]),
        bflag(periodic[1]),
        bflag(periodic[2])
    );
    s += dialect.settings(species);
    let _ = writeln!(s, "read_data {}", data.display());
    if !scene.initial_history.pairs.is_empty() || !scene.initial_history.walls.is_empty() {
        let _ = writeln!(
            s,
            "# Started from a trajectory: positions and velocities as stored; the {} pair and {} wall tangential\n\
             # springs it held start at zero here (magdem keeps them).",
            scene.initial_history.pairs.len(),
            scene.initial_history.walls.len()
        );
    }
    let _ = writeln!(
        s,
        "\n# Neighbour skin scaled to the particle size (0.2 diameters).\nneighbor {:.6e} bin",
        0.2 * largest_d
    );
    s += dialect.neigh_modify();
    let magnetic = spec.forces.dipole.is_some() || spec.forces.gradient.is_some();
    let includes: Vec<(&'static str, String)> = [
        ("fix.contact", Some(contact_section(engine, scene, native))),
        ("fix.gravity", gravity_section(scene)),
        ("fix.drag", drag_section(scene, deck_vessel(engine, scene))),
        ("fix.magnetic", magnetic.then(|| magnetic_section(engine, coupling)).flatten()),
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
    let _ = writeln!(s, "dump_modify trajectory sort id {} \"{fmt}\"", dialect.dump_format());
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
                dialect.dump_format(),
                magdem.display()
            );
        }
        _ => {
            let _ = writeln!(s, "run {}", scene.total_steps());
        }
    }
    DeckText { main: s, includes }
}

/// Materials, pair style and walls; `native`: with LAMMPS' dipole pair style overlaid.
fn contact_section(engine: Engine, scene: &Scene, native: bool) -> String {
    let dialect = engine.dialect();
    if scene.spec.forces.contact.is_none() {
        return dialect.without_contact(scene, native);
    }
    let mut s = String::from(
        "# Contact: Hertz normal, Mindlin tangential with history and Coulomb limit, damping from restitution.\n",
    );
    s += &dialect.contact_pairs(scene, native);
    let d = &scene.domain;
    let walls: Vec<(usize, &str)> =
        (0..3).filter(|&k| !d.periodic[k]).map(|k| (k, ["xplane", "yplane", "zplane"][k])).collect();
    if !walls.is_empty() {
        s += "# Walls: planes of infinite radius and mass, of the first species' material.\n";
    }
    for (k, plane) in walls {
        s += &dialect.walls(plane, d.lo[k], d.hi[k], &scene.species[0]);
    }
    if let Some(wall) = deck_vessel(engine, scene).and_then(|v| v.wall) {
        s += "# The vessel's wall: a cylinder of infinite mass, of the first species' material, touched from inside.\n";
        s += &dialect.cylinder_wall(&wall, &scene.species[0]).expect("checked by deck::check");
    }
    s
}

/// The scene's vessel as the deck writes it (after [`check`]).
fn deck_vessel(engine: Engine, scene: &Scene) -> Option<DeckVessel> {
    let spec = scene.spec.fluid.as_ref()?.vessel.as_ref()?;
    Some(check_vessel(engine, scene, spec).expect("checked by deck::check"))
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

fn drag_section(scene: &Scene, vessel: Option<DeckVessel>) -> Option<String> {
    scene.spec.forces.drag.as_ref()?;
    let mu = scene.spec.fluid.as_ref().map_or(0.0, |f| f.viscosity);
    let gamma = |k: usize| crate::core::forces::drag::Drag::stokes_coefficient(mu, scene.species[k].radius);
    if let Some(vessel) = vessel {
        return Some(vessel_drag(scene, vessel, &gamma));
    }
    let mut s = format!("# Stokes drag 6 pi mu a per type.\nfix drag all viscous {:.17e}", gamma(0));
    for k in 1..scene.species.len() {
        let _ = write!(s, " scale {} {:.17e}", k + 1, gamma(k) / gamma(0));
    }
    Some(s + "\n")
}

/// Stokes drag towards the vessel's steady flow, F = 6π μ a (u(x) − v) with u = 2ū(1 − r²/R²)
/// along the axis and zero outside (docs/model.md §3.6, src/core/flow.rs), as `fix addforce` of
/// atom-style variables. Each variable rounds as magdem's [`crate::core::flow::VesselFlow::axial_speed`]
/// and drag do: r from the two transverse offsets, s = r/R, u = (2ū)(1 − s s). fix addforce
/// acts in post_force, after the first half kick and the drift (LAMMPS' and LIGGGHTS' verlet.cpp),
/// so it sees the new positions and the half-step velocities, as magdem's drag in velocity Verlet.
fn vessel_drag(scene: &Scene, vessel: DeckVessel, gamma: &dyn Fn(usize) -> f64) -> String {
    let fluid = scene.spec.fluid.as_ref().expect("a vessel is in [fluid]");
    let Flow::Vessel(flow) = crate::scene::fluid::flow(fluid) else { unreachable!("a [fluid.vessel] flows along it") };
    let radius = flow.vessel.radius;
    let [(t1, c1), (t2, c2)] = vessel.axis.transverse().map(|a| (a.name(), flow.vessel.centre[a.index()]));
    let gammas = (0..scene.species.len())
        .map(|k| match scene.species.len() {
            1 => format!("{:.17e}", gamma(k)),
            _ => format!("{:.17e}*(type=={})", gamma(k), k + 1),
        })
        .collect::<Vec<_>>()
        .join("+");
    let mut s = format!(
        "# Stokes drag towards the vessel's steady Poiseuille flow, 6 pi mu a (u - v) per type, with\n\
         # u = 2 u_mean (1 - r^2/R^2) along the axis ({}{}), zero outside. fix addforce acts after the first\n\
         # half kick and the drift: at the new positions and the half-step velocities, as magdem's drag.\n\
         variable vessel_r atom sqrt(({t1}-({c1:.17e}))*({t1}-({c1:.17e}))+({t2}-({c2:.17e}))*({t2}-({c2:.17e})))\n\
         variable vessel_s atom v_vessel_r/{radius:.17e}\n\
         variable vessel_u atom {:.17e}*(1-v_vessel_s*v_vessel_s)*(v_vessel_r<{radius:.17e})\n\
         variable drag_gamma atom {gammas}\n",
        if vessel.sign < 0.0 { "-" } else { "+" },
        vessel.axis.name(),
        vessel.sign * flow.centreline_speed(),
    );
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let v = format!("v{}", axis.name());
        let _ = match axis == vessel.axis {
            true => writeln!(s, "variable drag_{} atom v_drag_gamma*(v_vessel_u-{v})", axis.name()),
            false => writeln!(s, "variable drag_{} atom -v_drag_gamma*{v}", axis.name()),
        };
    }
    s + "fix drag all addforce v_drag_x v_drag_y v_drag_z\n"
}

/// The fix that applies magdem's magnetic forces (none in a native deck: its pair style does).
fn magnetic_section(engine: Engine, coupling: &Coupling) -> Option<String> {
    let id = FIX_ID;
    match coupling {
        Coupling::Callback => Some(format!(
            "# Magnetic forces (moments with mutual induction, dipole and gradient forces) come from\n\
             # magdem's own code every step through this fix: run the deck with\n\
             # `magdem run --engine {}`, which sets the callback.\nfix {id} all external pf/callback 1 1\n",
            engine.name()
        )),
        Coupling::Files { .. } => Some(format!(
            "# Magnetic forces from magdem by file exchange (see the loop in in.scene): per-atom\n\
             # variables read from atomfiles, applied by fix addforce until the next exchange.\n\
             variable fx atom 0.0\nvariable fy atom 0.0\nvariable fz atom 0.0\nfix {id} all addforce v_fx v_fy v_fz\n"
        )),
        Coupling::Native => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `table` with each dotted key set to its value, or removed for `None`. A number in the key
    /// indexes an array, a final `+` appends to one; missing tables are created.
    fn edited(table: &toml::Table, edits: &[(&str, Option<toml::Value>)]) -> toml::Table {
        let mut root = toml::Value::Table(table.clone());
        for (key, value) in edits {
            let parts: Vec<&str> = key.split('.').collect();
            let (last, path) = parts.split_last().expect("a key");
            let mut node = &mut root;
            for part in path {
                node = match node {
                    toml::Value::Table(t) => {
                        t.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()))
                    }
                    toml::Value::Array(a) => &mut a[part.parse::<usize>().expect("an index")],
                    other => panic!("{key}: {other} is neither a table nor an array"),
                };
            }
            match (node, value) {
                (toml::Value::Array(a), Some(v)) if *last == "+" => a.push(v.clone()),
                (toml::Value::Table(t), Some(v)) => drop(t.insert(last.to_string(), v.clone())),
                (toml::Value::Table(t), None) => drop(t.remove(*last)),
                (other, _) => panic!("{key}: cannot edit {other}"),
            }
        }
        match root {
            toml::Value::Table(t) => t,
            _ => unreachable!(),
        }
    }

    /// The deck's text: in.scene and every file it includes.
    fn deck_text(dir: &Path, deck: &WrittenDeck) -> String {
        let main = std::fs::read_to_string(dir.join(&deck.input)).unwrap();
        let includes = main
            .lines()
            .filter_map(|l| l.strip_prefix("include "))
            .map(|name| std::fs::read_to_string(dir.join(name)).unwrap());
        std::iter::once(main.clone()).chain(includes).collect::<Vec<_>>().join("\n")
    }

    /// Each term of the scene's `[forces]` has its fix or pair style in the deck, and none that is absent.
    fn assert_every_term_written(engine: Engine, scene: &Scene, coupling: &Coupling, text: &str, label: &str) {
        let ForcesSpec { contact, dipole, gradient, drag, gravity, thermal: _ } = &scene.spec.forces;
        let pair_style = engine.dialect().contact_pair_style();
        let magnetic_fix = match coupling {
            Coupling::Callback => "fix magnetic all external pf/callback 1 1",
            Coupling::Files { .. } => "fix magnetic all addforce v_fx v_fy v_fz",
            Coupling::Native => unreachable!("the native deck is checked against LAMMPS in tests/reference.rs"),
        };
        let walls = scene.domain.walls().next().is_some();
        let vessel = scene.spec.fluid.as_ref().is_some_and(|f| f.vessel.is_some());
        let vessel_wall = vessel && contact.as_ref().is_some_and(|c| c.walls);
        let lines = [
            ("forces.contact", contact.is_some(), pair_style),
            ("no forces.contact", contact.is_none(), "pair_style none"),
            ("forces.contact on wall faces", contact.is_some() && walls || vessel_wall, "all wall/gran"),
            ("forces.contact with a vessel's wall", vessel_wall, "fix wall_vessel all wall/gran"),
            ("forces.dipole or forces.gradient", dipole.is_some() || gradient.is_some(), magnetic_fix),
            ("forces.drag", drag.is_some() && !vessel, "fix drag all viscous"),
            ("forces.drag in a vessel", drag.is_some() && vessel, "fix drag all addforce v_drag_x v_drag_y v_drag_z"),
            ("forces.gravity", gravity.is_some(), "fix gravity all gravity"),
            ("integration", true, "fix integrate all nve/sphere"),
        ];
        for (term, present, line) in lines {
            assert_eq!(
                text.contains(line),
                present,
                "{label}, {}: {term} {} `{line}`",
                engine.name(),
                if present { "lacks" } else { "has" }
            );
        }
    }

    /// What changes, the edits, and the term each engine (LIGGGHTS, LAMMPS) refuses, or `None`
    /// when it writes the deck.
    type Variant = (&'static str, Vec<(&'static str, Option<toml::Value>)>, [Option<&'static str>; 2]);

    /// Per shipped scene, made expressible (Stokes drag without shielding or rotational drag, as
    /// experiments/paper/reference.toml runs it) and then with one term or option changed at a
    /// time: in both engines every term is either written into the deck (its fix or pair style)
    /// or refused with a message naming it.
    #[test]
    fn every_term_is_written_or_refused_by_name() {
        use toml::Value;
        let s = |v: &str| Some(Value::String(v.into()));
        let f = |v: f64| Some(Value::Float(v));
        let b = |v: bool| Some(Value::Boolean(v));
        let v3 = |v: [f64; 3]| Some(Value::Array(v.iter().map(|&x| Value::Float(x)).collect()));
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/scenes");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&scenes)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        assert!(!files.is_empty(), "no scenes in {}", scenes.display());
        for file in files {
            let shipped: toml::Table = toml::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
            let base = edited(
                &shipped,
                &[
                    ("forces.drag.law", s("stokes")),
                    ("forces.drag.shielding", s("none")),
                    ("forces.drag.rotational", b(false)),
                ],
            );
            let walls = Scene::parse(&toml::to_string(&base).unwrap(), "base").unwrap().domain.walls().next().is_some();
            let species = |edits: &[(&str, Option<Value>)]| {
                let mut other = edited(base["species"].as_array().unwrap()[0].as_table().unwrap(), edits);
                other.insert("name".into(), Value::String("other".into()));
                Some(Value::Table(other))
            };
            let on_walls = |term| if walls { Some(term) } else { None };
            // A vessel wider than any box (radius 1 m), with its flow.
            let vessel = |centre: [f64; 3], axis: [f64; 3]| {
                Some(Value::Table(
                    [
                        ("centre".to_string(), v3(centre).unwrap()),
                        ("axis".to_string(), v3(axis).unwrap()),
                        ("radius".to_string(), Value::Float(1.0)),
                        ("mean_speed".to_string(), Value::Float(1e-4)),
                    ]
                    .into_iter()
                    .collect(),
                ))
            };
            // LAMMPS' zcylinder: along z, in a box not periodic in x or y.
            let domain = Scene::parse(&toml::to_string(&base).unwrap(), "base").unwrap().domain;
            let lammps_x = Some("fluid.vessel.axis not along z");
            let lammps_y = lammps_x;
            let lammps_z = (domain.periodic[0] || domain.periodic[1]).then_some("fluid.vessel in a box periodic");
            // (Periodic variants drop the dipole term, whose ranges must stay below half the box.)
            let periodic = Some(Value::Table(
                ["x", "y", "z"].iter().map(|k| (k.to_string(), Value::String("periodic".into()))).collect(),
            ));
            let coils = Some(Value::Array(vec![Value::Table(
                [
                    ("kind".to_string(), Value::String("maxwell".into())),
                    ("centre".to_string(), v3([0.0; 3]).unwrap()),
                    ("axis".to_string(), v3([0.0, 0.0, 1.0]).unwrap()),
                    ("radius".to_string(), Value::Float(1.0)),
                    ("current".to_string(), Value::Float(100.0)),
                ]
                .into_iter()
                .collect(),
            )]));
            let waveform = Some(Value::Table(
                [("period".to_string(), Value::Float(1e-3)), ("duty".to_string(), Value::Float(0.5))]
                    .into_iter()
                    .collect(),
            ));
            let v3x3 = || {
                let row = |r: [f64; 3]| v3(r).unwrap();
                Some(Value::Array(vec![row([0.0, 0.0, 0.1]), row([0.0; 3]), row([0.1, 0.0, 0.0])]))
            };
            let variants: Vec<Variant> = vec![
                ("expressible", vec![], [None, None]),
                (
                    "Schiller-Naumann drag",
                    vec![("forces.drag.law", s("schiller-naumann"))],
                    [Some("forces.drag.law"); 2],
                ),
                ("shielded drag", vec![("forces.drag.shielding", s("paper"))], [Some("forces.drag.shielding"); 2]),
                ("RPY drag", vec![("forces.drag.law", s("rpy"))], [Some("forces.drag.law"); 2]),
                (
                    "wall drag",
                    vec![(
                        "forces.drag.wall",
                        Some(Value::Table([("face".into(), Value::String("z-".into()))].into_iter().collect())),
                    )],
                    [Some("forces.drag.wall"); 2],
                ),
                ("rotational drag", vec![("forces.drag.rotational", b(true))], [Some("forces.drag.rotational"); 2]),
                ("drag touch tolerance", vec![("forces.drag.touch_tolerance", f(1e-2))], [None, None]),
                ("no drag", vec![("forces.drag", None)], [None, None]),
                ("moving fluid", vec![("fluid.velocity", v3([1e-4, 0.0, 0.0]))], [Some("fluid.velocity"); 2]),
                ("vessel flow along x", vec![("fluid.vessel", vessel([0.0; 3], [1.0, 0.0, 0.0]))], [None, lammps_x]),
                (
                    "vessel flow along x, no drag",
                    vec![("fluid.vessel", vessel([0.0; 3], [1.0, 0.0, 0.0])), ("forces.drag", None)],
                    [None, lammps_x],
                ),
                (
                    "vessel flow along -y",
                    vec![("fluid.vessel", vessel([0.0, 0.0, 1e-3], [0.0, -2.0, 0.0]))],
                    [None, lammps_y],
                ),
                (
                    "vessel flow along z through the origin",
                    vec![("fluid.vessel", vessel([0.0; 3], [0.0, 0.0, 1.0]))],
                    [None, lammps_z],
                ),
                (
                    "vessel flow along z off the origin",
                    vec![("fluid.vessel", vessel([1e-3, 0.0, 0.0], [0.0, 0.0, 1.0]))],
                    [None, Some("fluid.vessel.centre")],
                ),
                (
                    "vessel flow along x, no wall contacts, periodic",
                    vec![
                        ("fluid.vessel", vessel([0.0; 3], [1.0, 0.0, 0.0])),
                        ("forces.contact.walls", b(false)),
                        ("domain.boundary", periodic.clone()),
                        ("forces.dipole", None),
                    ],
                    [None, None],
                ),
                (
                    "vessel flow along an oblique axis",
                    vec![("fluid.vessel", vessel([0.0; 3], [1.0, 1.0, 0.0]))],
                    [Some("fluid.vessel.axis"); 2],
                ),
                (
                    "pulsatile vessel flow",
                    vec![
                        ("fluid.vessel", vessel([0.0; 3], [0.0, 0.0, 1.0])),
                        ("fluid.vessel.period", f(1e5)),
                        ("fluid.vessel.harmonics", Some(Value::Array(vec![v3([1.0, 0.5, 0.0]).unwrap()]))),
                    ],
                    [Some("fluid.vessel.period"); 2],
                ),
                (
                    "particles touching the walls only",
                    vec![("forces.contact.particles", b(false))],
                    [Some("forces.contact.particles = false"); 2],
                ),
                (
                    "an outlet (beyond every box)",
                    vec![(
                        "exits.outlets",
                        Some(Value::Array(vec![Value::Table(
                            [
                                ("name".to_string(), Value::String("far".into())),
                                ("point".to_string(), v3([1e3, 0.0, 0.0]).unwrap()),
                                ("normal".to_string(), v3([1.0, 0.0, 0.0]).unwrap()),
                            ]
                            .into_iter()
                            .collect(),
                        )])),
                    )],
                    [Some("exits"); 2],
                ),
                (
                    "MRI gradient",
                    vec![("field.gradient", None), ("field.gradient_mri", v3([0.0, 0.0, 0.1]))],
                    [None, None],
                ),
                (
                    "coil field",
                    vec![("field.gradient", None), ("field.coils", coils.clone())],
                    [Some("field.coils"); 2],
                ),
                (
                    "gradient waveform",
                    vec![("field.gradient", v3x3()), ("field.waveform", waveform.clone())],
                    [Some("field.waveform"); 2],
                ),
                (
                    "moving fluid, no drag",
                    vec![("forces.drag", None), ("fluid.velocity", v3([1e-4, 0.0, 0.0]))],
                    [None, None],
                ),
                ("gravity along y", vec![("forces.gravity.g", v3([0.0, -9.81, 0.0]))], [None, None]),
                ("no gravity", vec![("forces.gravity", None)], [None, None]),
                (
                    "gravity, two densities",
                    vec![
                        ("forces.gravity.g", v3([0.0, 0.0, -9.81])),
                        ("species.+", species(&[("density", f(2000.0))])),
                    ],
                    [Some("forces.gravity"); 2],
                ),
                (
                    "two materials",
                    vec![("species.+", species(&[("youngs_modulus", f(2e9))]))],
                    [on_walls("walls with species of different materials"); 2],
                ),
                (
                    "two materials, periodic",
                    vec![
                        ("species.+", species(&[("youngs_modulus", f(2e9))])),
                        ("domain.boundary", periodic.clone()),
                        ("forces.dipole", None),
                    ],
                    [None, None],
                ),
                (
                    "permanent moment",
                    vec![("species.0.permanent_moment", v3([1e-15, 0.0, 0.0]))],
                    [Some("species.permanent_moment"); 2],
                ),
                ("restitution 0.04", vec![("species.0.restitution", f(0.04))], [Some("species.restitution"); 2]),
                ("restitution 0.08", vec![("species.0.restitution", f(0.08))], [None, Some("species.restitution")]),
                ("elastic", vec![("species.0.restitution", f(1.0))], [None, None]),
                (
                    "saturation",
                    vec![
                        ("species.0.saturation_magnetisation", f(4.8e5)),
                        ("species.0.saturation_law", s("frohlich-kennelly")),
                    ],
                    [None, None],
                ),
                ("no wall contacts", vec![("forces.contact.walls", b(false))], [on_walls("forces.contact.walls"); 2]),
                (
                    "no wall contacts, periodic",
                    vec![
                        ("forces.contact.walls", b(false)),
                        ("domain.boundary", periodic.clone()),
                        ("forces.dipole", None),
                    ],
                    [None, None],
                ),
                ("no contact", vec![("forces.contact", None)], [None, None]),
                (
                    "Hooke contact",
                    vec![("forces.contact.normal", s("hooke")), ("forces.contact.stiffness", f(1e3))],
                    [Some("forces.contact.normal"); 2],
                ),
                (
                    "frictionless contact",
                    vec![("forces.contact.tangential", s("none"))],
                    [Some("forces.contact.tangential"); 2],
                ),
                ("induction none", vec![("forces.dipole.induction", s("none"))], [None, None]),
                ("induction exact", vec![("forces.dipole.induction", s("exact"))], [None, None]),
                (
                    "gradient only",
                    vec![("forces.dipole", None), ("forces.gradient", Some(Value::Table(toml::Table::new())))],
                    [None, None],
                ),
                ("no magnetic term", vec![("forces.dipole", None), ("forces.gradient", None)], [None, None]),
                ("semi-implicit Euler", vec![("integration.scheme", s("semi-implicit-euler"))], [None, None]),
                (
                    "no forces or contacts stored",
                    vec![("output.forces", b(false)), ("output.contacts", b(false))],
                    [None, None],
                ),
            ];
            for (what, edits, refused) in &variants {
                let label = format!("{} ({what})", file.display());
                let scene = Scene::parse(&toml::to_string(&edited(&base, edits)).unwrap(), &label)
                    .unwrap_or_else(|e| panic!("{label}: {e}"));
                let magnetic = scene.spec.forces.dipole.is_some() || scene.spec.forces.gradient.is_some();
                let every = scene.steps_per_frame();
                let files_route = Coupling::Files { magdem: PathBuf::from("magdem"), every };
                for (engine, refused) in [Engine::LIGGGHTS, Engine::LAMMPS].into_iter().zip(refused) {
                    for coupling in
                        if magnetic { vec![Coupling::Callback, files_route.clone()] } else { vec![Coupling::Callback] }
                    {
                        let dir = tempfile::tempdir().unwrap();
                        match (write_with(engine, &scene, dir.path(), &coupling), refused) {
                            (Ok(deck), None) => assert_every_term_written(
                                engine,
                                &scene,
                                &coupling,
                                &deck_text(dir.path(), &deck),
                                &label,
                            ),
                            (Err(ReferenceError::Unsupported { term, .. }), Some(name)) => assert!(
                                term.contains(name),
                                "{label}, {}: refused {term:?}, not {name:?}",
                                engine.name()
                            ),
                            (Ok(_), Some(name)) => {
                                panic!("{label}, {}: written, though {name} should be refused", engine.name())
                            }
                            (Err(e), _) => panic!("{label}, {}: {e}", engine.name()),
                        }
                    }
                }
            }
            // The files route's exchange interval must divide the run.
            let scene = Scene::parse(&toml::to_string(&base).unwrap(), "base").unwrap();
            if scene.magnetic_force_field().is_some() && scene.total_steps() > 2 {
                let coupling = Coupling::Files { magdem: PathBuf::from("magdem"), every: scene.total_steps() - 1 };
                let err =
                    write_with(Engine::LAMMPS, &scene, tempfile::tempdir().unwrap().path(), &coupling).unwrap_err();
                assert!(matches!(&err, ReferenceError::Unsupported { term, .. } if term == "the files route"), "{err}");
            }
        }
    }
}
