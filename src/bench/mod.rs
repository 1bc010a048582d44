//! `magdem bench`: magdem against LIGGGHTS and LAMMPS on the same scenes, the cost per particle
//! as N grows, and what a second thread buys. [`measure`] runs the cases into a [`record`];
//! `report::performance` writes `reports/performance.md` from it. Outside the physics core.
//!
//! Every case is a scene (TOML, written beside the runs so that it can be rerun by hand). magdem
//! is timed around its step loop only (no output), like the "Loop time" LIGGGHTS and LAMMPS
//! print; the engines run their generated decks as separate processes.

pub mod measure;
pub mod record;

pub use crate::analysis::timing::Spread;
use crate::core::parallel;
use crate::core::simulation::Simulation;
use crate::core::timers::PhaseTimers;
use crate::reference::{deck, dipole_check, Engine};
use crate::scene::Scene;
use stats_alloc::INSTRUMENTED_SYSTEM;
use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Barrier;
use std::time::Instant;

pub type Error = Box<dyn std::error::Error + Send + Sync>;

#[derive(Debug, Clone)]
pub struct Options {
    /// Report directory (`performance.md`, the figure and CSV go here).
    pub out: PathBuf,
    /// Directory for scenes, decks and engine logs.
    pub work: PathBuf,
    /// Runs per measurement (min, median and max are reported).
    pub repeats: usize,
    /// Largest N of the scaling study.
    pub max_particles: usize,
    /// Run the MPI demonstration (the reference experiment's LIGGGHTS and LAMMPS points by the
    /// files route under 1 and 2 MPI processes).
    pub mpi: bool,
}

/// The contact-only packings of 11 µm spheres in a walled box under gravity.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Packing {
    /// Random placement, a 0.5 mm cube per 300 particles (solid fraction 0.0017): free flight,
    /// almost no contact. It times the streaming of free particles.
    Dilute,
    /// Random placement, a 0.1 mm cube per 300 particles (solid fraction 0.21): the particles
    /// would settle into contact, but a bench run's 10 µs leaves almost none (0.00 per particle at
    /// its end); it times free particles among more neighbours.
    Loose,
    /// A face-centred cubic block filling its box, pre-compressed by [`PACKED_PRESTRAIN`] of a
    /// diameter: 12 contacts per particle in its bulk, the work a DEM code exists for.
    Packed,
}

/// The packed bed's overlap between lattice neighbours, as a fraction of the diameter (its
/// contact force, 5e-8 N, is 7 000 weights: gravity does not open a contact).
pub const PACKED_PRESTRAIN: f64 = 1e-4;

impl Packing {
    pub fn name(self) -> &'static str {
        match self {
            Packing::Dilute => "dilute",
            Packing::Loose => "loose",
            Packing::Packed => "packed",
        }
    }
}

/// Time step of every bench scene (s).
pub const DT: f64 = 1.0e-8;
/// The Fe₃O₄ spheres of every bench scene: diameter (m), Young's modulus (Pa), restitution and
/// friction.
pub const DIAMETER: f64 = 11.0e-6;
pub const YOUNGS_MODULUS: f64 = 1.0e9;
pub const RESTITUTION: f64 = 0.5;
pub const FRICTION: f64 = 0.5;
/// The magnetic scenes' field along x (T).
pub const FIELD: f64 = 0.4;
/// The paper's dipole cut-off (diameters).
pub const CUTOFF_DIAMETERS: f64 = 15.0;
/// The paper-physics scene's r-RESPA interval of the magnetic forces (steps).
pub const PAPER_SLOW_EVERY: u64 = 10;

fn species() -> String {
    format!(
        "[[species]]\nname = \"fe3o4\"\ndiameter = {DIAMETER:e}\ndensity = 1087.0\nyoungs_modulus = {YOUNGS_MODULUS:e}\n\
         poisson_ratio = 0.5\nfriction = {FRICTION:e}\nrestitution = {RESTITUTION:e}\nrelative_permeability = 12.3\n"
    )
}

/// Edge of the random packings' box for 300 particles (m).
fn edge_for_300(packing: Packing) -> f64 {
    if packing == Packing::Dilute {
        5.0e-4
    } else {
        1.0e-4
    }
}

/// Solid fraction of a random packing (the packed bed's is the lattice's).
pub fn solid_fraction(packing: Packing) -> f64 {
    300.0 * std::f64::consts::PI / 6.0 * DIAMETER.powi(3) / edge_for_300(packing).powi(3)
}

/// The contact-only scene of docs/model.md §10.6 (11 µm Hertz spheres, walls, gravity,
/// dt = 1e-8 s) for about `n` particles over `steps` steps: `n` at random for the dilute and
/// loose packings; for the packed bed the largest FCC block of c cubic cells per edge (sites on
/// its faces included: 4c³ + 6c² + 3c + 1 particles) with 4c³ ≤ n.
pub fn contact_scene(packing: Packing, n: usize, steps: u64) -> String {
    let d = DIAMETER;
    let (edge, placement) = match packing {
        Packing::Dilute | Packing::Loose => {
            (edge_for_300(packing) * (n as f64 / 300.0).cbrt(), format!("count = {n}\norder = \"spatial\"\n"))
        }
        Packing::Packed => {
            let cells = ((n as f64 / 4.0).cbrt() * (1.0 + 1e-12)).floor().max(1.0);
            let spacing = d * (1.0 - PACKED_PRESTRAIN);
            (
                cells * std::f64::consts::SQRT_2 * spacing + d,
                format!("lattice = {{ kind = \"fcc\", spacing = {spacing:e} }}\n"),
            )
        }
    };
    let (end, species) = (steps as f64 * DT, species());
    format!(
        "version = 1\nname = \"bench-contact-{}-{n}\"\nseed = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{edge:e}, {edge:e}, {edge:e}]\n\
         [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n{species}[[particles]]\nspecies = \"fe3o4\"\n{placement}\
         [forces.contact]\nwalls = true\n[forces.gravity]\ng = [0.0, 0.0, -9.81]\n\
         [integration]\nscheme = \"velocity-verlet\"\ndt = {DT:e}\nend_time = {end:e}\n[output]\ninterval = {end:e}\n",
        packing.name()
    )
}

/// The case-1 magnetic scene at 4.5 mg/ml (307 particles in the paper's box; a box scaled by
/// (n/307)^(1/3) for other `n`) with only the dipole force, induced moments without mutual
/// induction (fixed dipoles, as LAMMPS holds them), over all pairs or within `cutoff` diameters.
/// Without contact forces its particles cannot be stepped for long: it is timed as force
/// evaluations ([`Work::Forces`]).
pub fn magnetic_scene(n: usize, cutoff: Option<f64>, steps: u64) -> String {
    let [lx, _, lz] = magnetic_box(n);
    let (end, species) = (steps as f64 * DT, species());
    let cutoff = cutoff.map_or(String::new(), |c| format!("cutoff_diameters = {c:?}\n"));
    format!(
        "version = 1\nname = \"bench-dipole-{n}\"\nseed = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{lx:e}, {lx:e}, {lz:e}]\n\
         [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n[field]\nb0 = [{FIELD:e}, 0.0, 0.0]\n{species}[[particles]]\nspecies = \"fe3o4\"\ncount = {n}\norder = \"spatial\"\n\
         [forces.dipole]\ninduction = \"none\"\n{cutoff}\
         [integration]\nscheme = \"velocity-verlet\"\ndt = {DT:e}\nend_time = {end:e}\n[output]\ninterval = {end:e}\n"
    )
}

/// The box of [`magnetic_scene`] for `n` particles (m).
pub fn magnetic_box(n: usize) -> [f64; 3] {
    let scale = (n as f64 / 307.0).cbrt();
    [3.96e-4 * scale, 3.96e-4 * scale, 3.3e-4 * scale]
}

/// Particles per chain of the paper-physics scene ([`paper_scene`]).
pub const PAPER_CHAIN: usize = 10;

/// Overlap of neighbours in the paper-physics scene's chains, as a fraction of the diameter:
/// about where the dipole attraction of two touching 11 µm spheres at 0.4 T (≈ 1e-5 N) holds the
/// Hertz contact (3e-3 d), so the chains start near rest.
pub const PAPER_CHAIN_OVERLAP: f64 = 1e-3;

/// The paper's case-1 physics at scale, about `n` particles: the 2.25 mg/ml box scaled by
/// (n/336)^(1/3) per side, periodic along x and y, walls at the bottom and top; the paper's
/// induction within 15 diameters, dipole forces, Schiller–Naumann drag with the shielded area,
/// gravity, Hertz–Mindlin contacts; r-RESPA with the magnetic forces every 10 steps (as the 100×
/// runs). The particles start as the field leaves them: straight chains of [`PAPER_CHAIN`]
/// touching spheres along the field (x), placed at random without coming within two diameters of
/// another chain (the placement is seeded by `n`), so contacts, shielding and the dipole sums
/// all work from the first step: 2 (c − 1)/c contacts per particle in chains of c. `drag_every`
/// is the drag's `refactor_every` (1: coefficients renewed every step, as the paper's runs).
pub fn paper_scene(n: usize, steps: u64, drag_every: u64) -> String {
    use rand::{RngExt, SeedableRng};
    let d = DIAMETER;
    let edge = 4.84e-4 * (n as f64 / 336.0).cbrt();
    let spacing = d * (1.0 - PAPER_CHAIN_OVERLAP);
    let chains = n.div_ceil(PAPER_CHAIN);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(n as u64);
    // A chain is refused where it would come within 2 d of another, sideways (periodic in y)
    // and along x (periodic); chains are looked up in a grid of 2 d cells in y–z.
    let (gap, length) = (2.0 * d, (PAPER_CHAIN - 1) as f64 * spacing);
    let cells = ((edge / gap).floor() as i64).max(1);
    let mut grid: std::collections::HashMap<(i64, i64), Vec<[f64; 3]>> = Default::default();
    let apart = |a: &[f64; 3], b: &[f64; 3]| {
        let dy = (a[1] - b[1]) - edge * ((a[1] - b[1]) / edge).round();
        let dx = (b[0] - a[0]).rem_euclid(edge);
        dy * dy + (a[2] - b[2]).powi(2) >= gap * gap || (dx >= length + gap && dx <= edge - length - gap)
    };
    let mut positions = Vec::with_capacity(chains * PAPER_CHAIN);
    let mut attempts = 0;
    while positions.len() < chains * PAPER_CHAIN && attempts < 1000 * chains {
        attempts += 1;
        let chain =
            [rng.random::<f64>() * edge, rng.random::<f64>() * edge, d + rng.random::<f64>() * (edge - 2.0 * d)];
        let (cy, cz) = (((chain[1] / gap) as i64).min(cells - 1), (chain[2] / gap) as i64);
        let neighbours = (-1..=1).flat_map(|dy| (-1..=1).map(move |dz| ((cy + dy).rem_euclid(cells), cz + dz)));
        if !neighbours.flat_map(|c| grid.get(&c)).flatten().all(|other| apart(&chain, other)) {
            continue;
        }
        grid.entry((cy, cz)).or_default().push(chain);
        for k in 0..PAPER_CHAIN {
            let x = (chain[0] + k as f64 * spacing).rem_euclid(edge);
            positions.push(format!("[{x:e}, {:e}, {:e}]", chain[1], chain[2]));
        }
    }
    let (end, species) = (steps as f64 * DT, species());
    format!(
        "version = 1\nname = \"bench-paper-{n}\"\nseed = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{edge:e}, {edge:e}, {edge:e}]\n\
         boundary = {{ x = \"periodic\", y = \"periodic\", z = \"wall\" }}\n\
         [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n[field]\nb0 = [{FIELD:e}, 0.0, 0.0]\n{species}[[particles]]\nspecies = \"fe3o4\"\n\
         positions = [{}]\n[forces.contact]\nwalls = true\n[forces.dipole]\ninduction = \"paper\"\ncutoff_diameters = {CUTOFF_DIAMETERS:e}\n\
         [forces.drag]\nlaw = \"schiller-naumann\"\nshielding = \"paper\"\nrefactor_every = {drag_every}\n[forces.gravity]\ng = [0.0, 0.0, -9.81]\n\
         [integration]\nscheme = \"respa\"\nslow_every = {PAPER_SLOW_EVERY}\ndt = {DT:e}\nend_time = {end:e}\n[output]\ninterval = {end:e}\n",
        positions.join(", ")
    )
}

/// One timed magdem run: loop seconds, the finished simulation, and the heap memory the
/// simulation holds at its end (bytes: state, neighbour and pair lists, buffers).
pub struct MagdemRun {
    pub seconds: f64,
    pub simulation: Simulation,
    pub memory: u64,
}

/// The `magdem` binary's allocator: the system allocator, counted by `stats_alloc` only while
/// [`count_allocations`] is on. The counters are atomics shared by all threads; counting always,
/// as a plain instrumented allocator does, made threads that allocate often (the dense induction
/// solve of `magdem study stability`) spend two thirds of their time on those cache lines.
pub struct SwitchableCounter;

static COUNTING: AtomicBool = AtomicBool::new(false);

/// Switches the heap counting of [`SwitchableCounter`] on or off.
pub fn count_allocations(on: bool) {
    COUNTING.store(on, Ordering::Relaxed);
}

// Both branches allocate from `System`, so a block may be freed by either.
unsafe impl GlobalAlloc for SwitchableCounter {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            INSTRUMENTED_SYSTEM.alloc(layout)
        } else {
            System.alloc(layout)
        }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            INSTRUMENTED_SYSTEM.alloc_zeroed(layout)
        } else {
            System.alloc_zeroed(layout)
        }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if COUNTING.load(Ordering::Relaxed) {
            INSTRUMENTED_SYSTEM.dealloc(ptr, layout)
        } else {
            System.dealloc(ptr, layout)
        }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            INSTRUMENTED_SYSTEM.realloc(ptr, layout, new_size)
        } else {
            System.realloc(ptr, layout, new_size)
        }
    }
}

/// Bytes live on the heap, as counted while [`count_allocations`] is on in a binary that
/// installs [`SwitchableCounter`] (the `magdem` binary does; elsewhere this stays 0).
fn heap_bytes() -> u64 {
    let s = INSTRUMENTED_SYSTEM.stats();
    (s.bytes_allocated as i64 - s.bytes_deallocated as i64 + s.bytes_reallocated as i64).max(0) as u64
}

/// What a timed magdem loop repeats.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Work {
    /// Full steps of the scene's integrator.
    Steps,
    /// Force evaluations of the initial state, the particles held still (a kernel timing, like
    /// a LAMMPS `run` without an integrating fix).
    Forces,
}

/// Runs `scene` in magdem on `threads` threads and times its loop of `work` over the scene's
/// number of steps; `timings` switches on the phase timers (for a profile; they cost a few per
/// cent, so timed runs leave them off).
pub fn time_magdem(scene: &Scene, threads: usize, work: Work, timings: bool) -> Result<MagdemRun, Error> {
    time_magdem_from(scene, threads, work, timings, Start::Alone)
}

/// How a timed magdem run starts its clock.
#[derive(Clone, Copy)]
pub enum Start<'a> {
    /// As soon as it is set up; its allocations are counted (its memory is measured on one
    /// thread: counting on two would time the counters' contention).
    Alone,
    /// When every run sharing the barrier is set up, so that their loops run at the same time;
    /// nothing is counted (the counters are shared by all threads).
    Together(&'a Barrier),
}

/// [`time_magdem`] with the clock started as `start` says.
pub fn time_magdem_from(
    scene: &Scene,
    threads: usize,
    work: Work,
    timings: bool,
    start: Start,
) -> Result<MagdemRun, Error> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    count_allocations(matches!(start, Start::Alone) && threads == 1);
    let result = pool.install(|| {
        let before = heap_bytes();
        let mut simulation = scene.simulation(None);
        simulation.initialise()?;
        if timings {
            // The loop's phases only (the initial evaluation builds the neighbour lists).
            simulation.field.timers = PhaseTimers::enabled();
        }
        if let Start::Together(barrier) = start {
            barrier.wait();
        }
        let start = Instant::now();
        match work {
            Work::Steps => {
                for _ in 0..scene.total_steps() / simulation.integrator.steps_per_call() {
                    simulation.step()?;
                }
            }
            Work::Forces => {
                // Each evaluation as a step runs it, in a warm pool.
                let (field, state, balance) = (&mut simulation.field, &mut simulation.state, &mut simulation.balance);
                for _ in 0..scene.total_steps() {
                    parallel::with_warm_pool(state.particles.len(), balance, || field.evaluate(state, scene.dt()));
                }
            }
        }
        let seconds = start.elapsed().as_secs_f64();
        let memory = heap_bytes().saturating_sub(before);
        Ok(MagdemRun { seconds, simulation, memory })
    });
    count_allocations(false);
    result
}

/// The "Loop time of X" a LIGGGHTS or LAMMPS log reports (s).
pub fn loop_time(log: &str) -> Option<f64> {
    log.lines().find_map(|l| l.strip_prefix("Loop time of ")?.split_whitespace().next()?.parse().ok())
}

/// Runs `in_file` in `dir` with the engine's binary (under `mpirun -np procs` when procs > 1)
/// and returns its loop time.
pub fn time_engine(engine: Engine, dir: &Path, in_file: &str, procs: usize) -> Result<f64, Error> {
    let mut command = crate::reference::engine_command(engine, procs);
    let out = command.args(["-in", in_file, "-log", "log.bench"]).current_dir(dir).output()?;
    let log = std::fs::read_to_string(dir.join("log.bench")).unwrap_or_default();
    match (out.status.success(), loop_time(&log)) {
        (true, Some(t)) => Ok(t),
        _ => Err(format!(
            "{} failed in {} (exit {:?}); see its log.bench",
            engine.name(),
            dir.display(),
            out.status.code()
        )
        .into()),
    }
}

/// Writes the engine's deck of `scene` into `dir` and times it on `procs` MPI processes.
pub fn time_engine_scene(engine: Engine, scene: &Scene, dir: &Path, procs: usize) -> Result<f64, Error> {
    let written = deck::write(engine, scene, dir)?;
    time_engine(engine, dir, &written.input.to_string_lossy(), procs)
}

/// Writes the LAMMPS `lj/cut/dipole/cut` deck of a dipole-only `scene` (its initial moments)
/// into `dir` and times its force evaluations over the scene's steps (no integrating fix: the
/// particles hold still, as in magdem's [`Work::Forces`]).
pub fn time_lammps_dipoles(scene: &Scene, dir: &Path) -> Result<f64, Error> {
    let cutoff = scene.spec.forces.dipole.as_ref().ok_or("the scene has no dipole term")?.cutoff_diameters;
    let state = scene.initial_magnetic_state().ok_or("the scene has no magnetic term")?;
    let rc = dipole_check::lammps_cutoff(scene, cutoff)?;
    dipole_check::write_deck(&state, &scene.domain, rc, dir, &scene.hash, Some((scene.total_steps(), scene.dt())))?;
    time_engine(Engine::LAMMPS, dir, "in.dipole", 1)
}

/// Writes `text` as `dir/name.toml` (for rerunning by hand) and parses it.
pub fn scene_in(dir: &Path, name: &str, text: &str) -> Result<Scene, Error> {
    std::fs::create_dir_all(dir)?;
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text)?;
    Ok(Scene::from_file(&path)?)
}

/// Whether two finished runs hold bit-identical positions and velocities.
pub fn bitwise_equal(a: &Simulation, b: &Simulation) -> bool {
    let (p, q) = (&a.state.particles, &b.state.particles);
    p.position == q.position && p.velocity == q.velocity && p.angular_velocity == q.angular_velocity
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper-physics scene holds ⌈n/10⌉ chains of ten touching spheres and nothing else that
    /// touches: exactly 9 contacts per chain (1.8 per particle), each overlapping by
    /// [`PAPER_CHAIN_OVERLAP`] of a diameter, and no two chains within a diameter of each other.
    #[test]
    fn the_paper_scene_starts_as_straight_chains_that_touch_only_themselves() {
        let n = 2000;
        let scene = Scene::parse(&paper_scene(n, 10, 10), "paper").unwrap();
        let p = &scene.initial;
        assert_eq!(p.len(), n);
        let d = 2.0 * p.radius[0];
        let mut pairs = vec![];
        crate::core::neighbours::CellList::default().pairs_within(
            &p.position,
            &scene.domain,
            Some(2.0 * d),
            &mut pairs,
        );
        let touching: Vec<_> = pairs.iter().filter(|q| q.dist < d).collect();
        assert_eq!(touching.len(), n / PAPER_CHAIN * (PAPER_CHAIN - 1));
        for q in &touching {
            assert!((d - q.dist - PAPER_CHAIN_OVERLAP * d).abs() < 1e-9 * d, "overlap {:e}", d - q.dist);
            assert_eq!(q.i / PAPER_CHAIN as u32, q.j / PAPER_CHAIN as u32, "a contact between chains");
        }
        let apart = pairs.iter().filter(|q| q.i / PAPER_CHAIN as u32 != q.j / PAPER_CHAIN as u32).map(|q| q.dist);
        assert!(apart.fold(f64::INFINITY, f64::min) >= d, "chains closer than a diameter");
    }
}
