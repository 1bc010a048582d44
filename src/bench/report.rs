//! The measurements of `magdem bench` and `reports/performance.md`.

use super::*;
use crate::plot::{line_chart_with_legend, palette, Legend, RGBColor, Series};
use crate::reference::dipole_check;
use std::fmt::Write as _;

/// One measured case: who ran it, on how many threads, and the loop times.
#[derive(Debug, Clone)]
pub struct Measurement {
    pub case: String,
    pub engine: &'static str,
    pub threads: usize,
    pub particles: usize,
    pub steps: u64,
    pub seconds: Spread,
    /// The runs' seconds in turn order (none when read back from `performance.csv`).
    pub turns: Vec<f64>,
}

impl Measurement {
    /// Nanoseconds per particle-step at the median.
    pub fn ns_per_particle_step(&self) -> f64 {
        self.seconds.median / (self.particles as f64 * self.steps as f64) * 1e9
    }
    pub fn particle_steps_per_second(&self) -> f64 {
        self.particles as f64 * self.steps as f64 / self.seconds.median
    }
}

/// Steps of a contact-only case with `n` particles: 3e7 particle-steps, at least 1000 steps.
fn contact_steps(n: usize) -> u64 {
    (3e7 / n as f64).round().max(1000.0) as u64
}

struct Bench<'a> {
    options: &'a Options,
    measurements: Vec<Measurement>,
    /// Phase shares (name, fraction) of magdem's single-thread run per case.
    profiles: Vec<(String, Vec<(&'static str, f64)>)>,
    /// Per case: whether the 1- and 2-thread runs ended bit for bit equal.
    bitwise: Vec<(String, bool)>,
    /// Per case: pair contacts and wall contacts per particle at the end of the run (the
    /// coordination number is twice the first).
    contacts: Vec<(String, f64, f64)>,
    /// (case, particles, bytes per particle)
    memory: Vec<(String, usize, f64)>,
    /// Dipole scaling: (particles, pairs within the cut-off).
    dipole_pairs: Vec<(usize, usize)>,
    engine_versions: Vec<String>,
    mpi: Vec<MpiRun>,
    /// The native LAMMPS deck beside magdem on the same fixed-moment scene.
    native: Vec<NativeRun>,
    /// The native deck's cost in bulk: (engine, threads or processes, particles, ns per particle-step).
    native_bulk: Vec<(&'static str, usize, usize, f64)>,
    /// Per case: the machine's own two-core gains, run in turns with the case.
    ceilings: Vec<(String, Ceilings)>,
    /// Per case: each phase's median seconds per step on one thread and on two.
    phases_on_both_cores: Vec<(String, Vec<PhaseOnBothCores>)>,
    notes: Vec<String>,
}

/// One run of the MPI demonstration and the statistics of its last frame.
struct MpiRun {
    engine: String,
    /// How the magnetic forces arrived ("files every 100 steps", "callback every step").
    route: &'static str,
    procs: usize,
    wall_time: Option<f64>,
    /// Fastest particle at the last frame (m/s).
    fastest: f64,
    aggregates: usize,
    mean_length: f64,
    std_length: f64,
    largest: usize,
    /// Largest position difference to the 1-process run of the same engine (m).
    max_difference: Option<f64>,
}

/// One run of the native-deck comparison: its last frame's statistics, how far its positions are
/// from magdem's, and its cost (loop seconds per particle-step, and for LAMMPS, `Loop time`).
struct NativeRun {
    stats: MpiRun,
    /// Largest position difference to magdem's run over all frames (m).
    to_magdem: Option<f64>,
    /// Loop time per particle-step (ns) over the comparison's steps.
    ns_per_particle_step: f64,
}

/// What the machine itself gains from a second core, measured in the same minutes as a case:
/// seconds of arithmetic alone on one core and on two, and the loop seconds of two one-thread
/// runs of the case at once (the slower of the pair).
struct Ceilings {
    arithmetic: (Spread, Spread),
    two_runs: Spread,
}

impl Ceilings {
    /// How many times the throughput of one one-thread run two such runs at once give, given
    /// one run's time alone.
    fn two_runs_gain(&self, one_run: &Spread) -> f64 {
        2.0 * one_run.median / self.two_runs.median
    }
}

/// A phase's name and its median seconds per step on one thread and on two.
type PhaseOnBothCores = (&'static str, f64, f64);

/// What the runs of one magdem contender leave: the last run, and each timed run's seconds per
/// step by phase.
#[derive(Default)]
struct MagdemRuns {
    last: Option<MagdemRun>,
    phases: Vec<Vec<(&'static str, f64)>>,
}

impl MagdemRuns {
    /// Median seconds per step of phase `name` over the timed runs.
    fn median(&self, name: &str) -> f64 {
        let times: Vec<f64> =
            self.phases.iter().map(|run| run.iter().find(|(n, _)| *n == name).map_or(0.0, |(_, t)| *t)).collect();
        Spread::of(&times).median
    }
}

/// One contender of a case: who runs, on how many threads, and one timed run (seconds).
struct Contender<'a> {
    engine: &'static str,
    threads: usize,
    run: Box<dyn FnMut() -> Result<f64, Error> + 'a>,
}

impl<'a> Contender<'a> {
    /// magdem on `threads` threads, with its phase timers on if `timed`; what the runs leave
    /// goes to `runs`.
    fn magdem(scene: &'a Scene, threads: usize, work: Work, timed: bool, runs: &'a mut MagdemRuns) -> Self {
        let steps = scene.total_steps() as f64;
        let run = move || {
            let run = time_magdem(scene, threads, work, timed)?;
            if timed {
                runs.phases.push(
                    run.simulation.timers().phases().iter().map(|(name, d)| (*name, d.as_secs_f64() / steps)).collect(),
                );
            }
            let seconds = run.seconds;
            runs.last = Some(run);
            Ok(seconds)
        };
        Contender { engine: "magdem", threads, run: Box::new(run) }
    }

    /// The arithmetic try of [`arithmetic_seconds`] on `threads` cores, as a contender so that
    /// it sees the machine in the same minutes as the case it runs with.
    fn arithmetic(threads: usize) -> Self {
        Contender { engine: ARITHMETIC, threads, run: Box::new(move || Ok(arithmetic_seconds(threads))) }
    }

    /// Two one-thread magdem runs of `scene` at once, their loops started together: the slower
    /// loop's seconds. Two independent runs share nothing but the machine (no hand-off, no join,
    /// no data), so what they gain over one run is the most the case's own work can gain from a
    /// second core in those minutes, and what an ensemble of runs gains from it.
    fn two_runs_at_once(scene: &'a Scene, work: Work) -> Self {
        let run = move || {
            let barrier = Barrier::new(2);
            let runs = std::thread::scope(|scope| {
                // Both runs are the same scene: if one fails before the barrier, so does the other.
                let both =
                    [(); 2].map(|_| scope.spawn(|| time_magdem_from(scene, 1, work, false, Start::Together(&barrier))));
                both.map(|run| run.join().expect("a timed run does not panic"))
            });
            let [a, b] = runs;
            Ok(a?.seconds.max(b?.seconds))
        };
        Contender { engine: TWO_RUNS, threads: 2, run: Box::new(run) }
    }

    /// A reference engine on `procs` MPI processes (one: no `mpirun`), if installed.
    fn engine(engine: Engine, procs: usize, run: impl FnMut() -> Result<f64, Error> + 'a) -> Option<Self> {
        engine.available().then(|| Contender { engine: engine.name(), threads: procs, run: Box::new(run) })
    }
}

impl<'a> Bench<'a> {
    /// Nothing measured yet.
    fn new(options: &'a Options) -> Self {
        Bench {
            options,
            measurements: vec![],
            profiles: vec![],
            bitwise: vec![],
            contacts: vec![],
            memory: vec![],
            dipole_pairs: vec![],
            engine_versions: vec![],
            mpi: vec![],
            native: vec![],
            native_bulk: vec![],
            ceilings: vec![],
            phases_on_both_cores: vec![],
            notes: vec![],
        }
    }

    /// Times the contenders of `case` in turns, one run of each per turn, so that a shared
    /// machine's changing load falls on all of them alike rather than on whichever ran last. A
    /// reference engine that fails is noted and left out; a magdem failure ends the bench.
    fn compare(&mut self, case: &str, particles: usize, steps: u64, contenders: Vec<Contender>) -> Result<(), Error> {
        self.compare_in(self.options.repeats, case, particles, steps, contenders)
    }

    /// [`Self::compare`] in `turns` turns.
    fn compare_in(
        &mut self,
        turns: usize,
        case: &str,
        particles: usize,
        steps: u64,
        contenders: Vec<Contender>,
    ) -> Result<(), Error> {
        let mut contenders: Vec<(Contender, Vec<f64>)> = contenders.into_iter().map(|c| (c, vec![])).collect();
        for _ in 0..turns {
            let mut k = 0;
            while k < contenders.len() {
                let (contender, times) = &mut contenders[k];
                match (contender.run)() {
                    Ok(t) => times.push(t),
                    Err(e) if contender.engine == "magdem" => return Err(e),
                    Err(e) => {
                        self.notes.push(format!("{} on {case}: {e}", contender.engine));
                        contenders.remove(k);
                        continue;
                    }
                }
                k += 1;
            }
        }
        for (c, times) in contenders {
            self.measurements.push(Measurement {
                case: case.into(),
                engine: c.engine,
                threads: c.threads,
                particles,
                steps,
                seconds: Spread::of(&times),
                turns: times,
            });
        }
        Ok(())
    }

    /// magdem alone on `threads` threads (the scaling study), `repeats` runs; returns the last.
    fn magdem(&mut self, case: &str, scene: &Scene, threads: usize, work: Work) -> Result<MagdemRun, Error> {
        let mut runs = MagdemRuns::default();
        let contender = Contender::magdem(scene, threads, work, false, &mut runs);
        self.compare(case, scene.initial.len(), scene.total_steps(), vec![contender])?;
        Ok(runs.last.expect("at least one repeat"))
    }

    /// The phase shares of one more single-thread run with the phase timers on.
    fn profile(&mut self, case: &str, scene: &Scene, work: Work) -> Result<(), Error> {
        let profiled = time_magdem(scene, 1, work, true)?;
        let timers = profiled.simulation.timers();
        let total: f64 = timers.phases().iter().map(|(_, d)| d.as_secs_f64()).sum();
        let shares = timers.phases().iter().map(|(n, d)| (*n, d.as_secs_f64() / total)).collect();
        self.profiles.push((case.into(), shares));
        Ok(())
    }

    fn find(&self, case: &str, engine: &str, threads: usize) -> Option<&Measurement> {
        self.measurements.iter().find(|m| m.case == case && m.engine == engine && m.threads == threads)
    }

    /// How many times faster (medians) `fast` ran `case` than `slow`, each (engine, threads).
    fn speedup(&self, case: &str, fast: (&str, usize), slow: (&str, usize)) -> Option<f64> {
        Some(self.find(case, slow.0, slow.1)?.seconds.median / self.find(case, fast.0, fast.1)?.seconds.median)
    }

    /// How many times faster `fast` ran `case` than `slow` turn by turn (each turn's runs seconds
    /// apart, so that the machine's drift between turns cancels): min, median and max over the
    /// turns.
    fn paired_speedup(&self, case: &str, fast: (&str, usize), slow: (&str, usize)) -> Option<Spread> {
        let (fast, slow) = (&self.find(case, fast.0, fast.1)?.turns, &self.find(case, slow.0, slow.1)?.turns);
        let ratios: Vec<f64> = slow.iter().zip(fast).map(|(s, f)| s / f).collect();
        (!ratios.is_empty() && fast.len() == slow.len()).then(|| Spread::of(&ratios))
    }

    /// The machine's own two-core gains measured with `case`: arithmetic, and two one-thread
    /// runs at once (throughput over one magdem run alone).
    fn two_core_gains(&self, case: &str) -> Option<(f64, f64)> {
        let (_, ceilings) = self.ceilings.iter().find(|(c, _)| c == case)?;
        let one_run = self.find(case, "magdem", 1)?;
        Some((gain(&ceilings.arithmetic), ceilings.two_runs_gain(&one_run.seconds)))
    }

    /// Nanoseconds per force evaluation and pair within the cut-off (each counted once) at the
    /// median, for a run of the dipole scaling scene whose pairs were counted.
    fn ns_per_pair(&self, m: &Measurement) -> Option<f64> {
        let (_, pairs) = self.dipole_pairs.iter().find(|(n, _)| *n == m.particles)?;
        Some(m.seconds.median / (m.steps as f64 * *pairs as f64) * 1e9)
    }

    fn contact_cases(&mut self, progress: &indicatif::ProgressBar) -> Result<(), Error> {
        for packing in [Packing::Dilute, Packing::Loose, Packing::Packed] {
            for n in [300, 3000, 30000] {
                let case = format!("contact {} {n}", packing.name());
                progress.set_message(case.clone());
                let steps = contact_steps(n);
                let dir = self.options.work.join(format!("contact-{}-{n}", packing.name()));
                let scene = scene_in(&dir, "scene", &contact_scene(packing, n, steps))?;
                // At 30 000 (where two threads have a target) magdem's runs time their phases: a
                // clock read per phase, under a microsecond of a step of 100–400 µs.
                let timed = n == 30000;
                let (mut one, mut two) = (MagdemRuns::default(), MagdemRuns::default());
                let mut contenders = vec![
                    Contender::magdem(&scene, 1, Work::Steps, timed, &mut one),
                    Contender::magdem(&scene, 2, Work::Steps, timed, &mut two),
                ];
                // At 30 000 the engines also run on both cores (mpirun -np 2), beside magdem's threads.
                let procs = if n == 30000 && mpirun_available() { vec![1, 2] } else { vec![1] };
                for engine in [Engine::Liggghts, Engine::Lammps] {
                    for &np in &procs {
                        let (scene, engine_dir) = (
                            &scene,
                            dir.join(if np == 1 {
                                engine.name().to_string()
                            } else {
                                format!("{}-np{np}", engine.name())
                            }),
                        );
                        contenders.extend(Contender::engine(engine, np, move || {
                            time_engine_scene(engine, scene, &engine_dir, np)
                        }));
                    }
                }
                if timed {
                    contenders.extend([Contender::arithmetic(1), Contender::arithmetic(2)]);
                    contenders.push(Contender::two_runs_at_once(&scene, Work::Steps));
                }
                // More turns where a target is judged: the beds of 30 000, whose two-thread ratio is
                // taken turn by turn, and the packed bed of 3 000, whose median is held against
                // LIGGGHTS' (three runs on a busy machine put two in one slow minute).
                let targeted = timed || (packing == Packing::Packed && n == 3000);
                let turns = if targeted { self.options.repeats.max(TARGET_TURNS) } else { self.options.repeats };
                self.compare_in(turns, &case, scene.initial.len(), steps, contenders)?;
                if timed {
                    let (machine, others): (Vec<_>, _) = std::mem::take(&mut self.measurements)
                        .into_iter()
                        .partition(|m| [ARITHMETIC, TWO_RUNS].contains(&m.engine));
                    self.measurements = others;
                    let on = |engine, threads| {
                        machine
                            .iter()
                            .find(|m| m.engine == engine && m.threads == threads)
                            .map_or(Spread::of(&[f64::NAN]), |m| m.seconds)
                    };
                    let both = |engine| (on(engine, 1), on(engine, 2));
                    self.ceilings
                        .push((case.clone(), Ceilings { arithmetic: both(ARITHMETIC), two_runs: on(TWO_RUNS, 2) }));
                    let phases =
                        one.phases[0].iter().map(|(name, _)| (*name, one.median(name), two.median(name))).collect();
                    self.phases_on_both_cores.push((case.clone(), phases));
                }
                let (one, two) = (one.last.expect("one-thread runs"), two.last.expect("two-thread runs"));
                self.bitwise.push((case.clone(), bitwise_equal(&one.simulation, &two.simulation)));
                let (state, particles) = (&one.simulation.state, scene.initial.len() as f64);
                self.contacts.push((
                    case.clone(),
                    state.contacts.pairs.len() as f64 / particles,
                    state.contacts.walls.len() as f64 / particles,
                ));
                for engine in [Engine::Liggghts, Engine::Lammps] {
                    self.record_version(&dir.join(engine.name()));
                }
                self.profile(&case, &scene, Work::Steps)?;
                progress.inc(1);
            }
        }
        Ok(())
    }

    fn record_version(&mut self, dir: &Path) {
        let log = std::fs::read_to_string(dir.join("log.bench")).unwrap_or_default();
        if let Some(first) = log.lines().next().filter(|l| l.starts_with("LIGGGHTS") || l.starts_with("LAMMPS")) {
            if !self.engine_versions.iter().any(|v| v == first) {
                self.engine_versions.push(first.to_string());
            }
        }
    }

    /// Dipole forces at case-1 parameters, all pairs and with the paper's 15-diameter cut-off.
    fn magnetic_cases(&mut self, progress: &indicatif::ProgressBar) -> Result<Vec<(String, f64)>, Error> {
        let mut agreement = vec![];
        for (label, cutoff, steps) in [("all pairs", None, 2000), ("cut-off 15 d", Some(15.0), 2000)] {
            let case = format!("dipole {label} 307");
            progress.set_message(case.clone());
            let dir = self.options.work.join(format!("dipole-{}", label.replace(' ', "-")));
            let scene = scene_in(&dir, "scene", &magnetic_scene(307, cutoff, steps))?;
            let mut runs = MagdemRuns::default();
            let lammps_dir = dir.join("lammps");
            let mut contenders = vec![Contender::magdem(&scene, 1, Work::Forces, false, &mut runs)];
            contenders.extend(Contender::engine(Engine::Lammps, 1, || time_lammps_dipoles(&scene, &lammps_dir)));
            self.compare(&case, scene.initial.len(), steps, contenders)?;
            self.profile(&case, &scene, Work::Forces)?;
            if Engine::Lammps.available() {
                match dipole_check::check(&scene, &dir.join("force-check")) {
                    Ok(check) => agreement.push((case.clone(), check.max_relative_error)),
                    Err(e) => self.notes.push(format!("force check on {case}: {e}")),
                }
            }
            progress.inc(1);
        }
        Ok(agreement)
    }

    /// The paper's physics ([`paper_scene`]) at 10³, 10⁴ and 10⁵ particles (up to the scaling
    /// study's largest), 10⁷ particle-steps per run (at least 100 steps), one and two threads;
    /// the phase shares at the middle size.
    fn paper_cases(&mut self, progress: &indicatif::ProgressBar) -> Result<(), Error> {
        for (n, drag) in paper_variants(self.options.max_particles) {
            let case = drag.case(n);
            progress.set_message(case.clone());
            let steps = ((1e6 / n as f64).round() as u64).max(10) * 10;
            let dir = self.options.work.join(format!("paper-{n}-{}", drag.every()));
            let scene = scene_in(&dir, "scene", &paper_scene(n, steps, drag.every()))?;
            let one = self.magdem(&case, &scene, 1, Work::Steps)?;
            self.memory.push((case.clone(), n, one.memory as f64 / n as f64));
            let two = self.magdem(&case, &scene, 2, Work::Steps)?;
            self.bitwise.push((case.clone(), bitwise_equal(&one.simulation, &two.simulation)));
            let (state, particles) = (&one.simulation.state, n as f64);
            self.contacts.push((
                case.clone(),
                state.contacts.pairs.len() as f64 / particles,
                state.contacts.walls.len() as f64 / particles,
            ));
            drop((one, two));
            if n == 10_000 && drag == PaperDrag::EveryStep {
                self.profile(&case, &scene, Work::Steps)?;
            }
            progress.inc(1);
        }
        Ok(())
    }

    fn scaling(&mut self, progress: &indicatif::ProgressBar) -> Result<(), Error> {
        for n in scaling_sizes(self.options.max_particles) {
            progress.set_message(format!("scaling {n}"));
            let dir = self.options.work.join(format!("scaling-{n}"));
            for packing in [Packing::Dilute, Packing::Loose, Packing::Packed] {
                let steps = (1e7 / n as f64).round().max(100.0) as u64;
                let scene = scene_in(&dir, &format!("contact-{}", packing.name()), &contact_scene(packing, n, steps))?;
                let case = format!("scaling contact {}", packing.name());
                let run = self.magdem(&case, &scene, 1, Work::Steps)?;
                self.memory.push((case.clone(), n, run.memory as f64 / n as f64));
                drop(run);
                if packing == Packing::Packed {
                    self.magdem(&case, &scene, 2, Work::Steps)?;
                }
            }
            let steps = (2e6 / n as f64).round().max(20.0) as u64;
            let scene = scene_in(&dir, "dipole-cutoff", &magnetic_scene(n, Some(15.0), steps))?;
            let case = "scaling dipole cut-off 15 d".to_string();
            let mut pairs = vec![];
            let largest_d = scene.species.iter().map(|s| 2.0 * s.radius).fold(0.0, f64::max);
            crate::core::neighbours::CellList::default().pairs_within(
                &scene.initial.position,
                &scene.domain,
                Some(15.0 * largest_d),
                &mut pairs,
            );
            self.dipole_pairs.push((n, pairs.len()));
            drop(pairs);
            let run = self.magdem(&case, &scene, 1, Work::Forces)?;
            self.memory.push((case.clone(), n, run.memory as f64 / n as f64));
            drop(run);
            self.magdem(&case, &scene, 2, Work::Forces)?;
            progress.inc(1);
        }
        Ok(())
    }
}

/// The MPI demonstration: the case-1 reference point (0.563 mg/ml, Stokes drag, 5 ms) in
/// LIGGGHTS and LAMMPS by the files route (exchange every 100 steps) under `mpirun -np 1` and 2.
fn mpi_demo(bench: &mut Bench, progress: &indicatif::ProgressBar) -> Result<(), Error> {
    let experiment = crate::scene::experiment::Experiment::from_file(Path::new("experiments/paper/reference.toml"))?;
    let magdem = std::env::current_exe()?;
    for engine in [Engine::Liggghts, Engine::Lammps] {
        let Some(point) = experiment.points.iter().find(|p| p.engine == engine.name()) else { continue };
        if !engine.available() || !mpirun_available() {
            bench.notes.push(format!("MPI demonstration: {} or mpirun is not installed", engine.name()));
            continue;
        }
        let mut first: Option<ndarray::Array3<f64>> = None;
        for procs in [1, 2] {
            progress.set_message(format!("mpirun -np {procs} {}", engine.binary()));
            let dir = bench.options.work.join(format!("mpi-{}-np{procs}", engine.name()));
            let output = dir.join("trajectory.h5");
            let coupling = deck::Coupling::Files { magdem: magdem.clone(), every: 100 };
            let run = crate::reference::run_binary(engine, &point.scene, &dir.join("deck"), &output, &coupling, procs)?;
            let positions = crate::io::trajectory::Trajectory::open(&output)?.all_vectors("position")?;
            let max_difference = first.as_ref().map(|p1| (p1 - &positions).iter().fold(0.0_f64, |m, d| m.max(d.abs())));
            first.get_or_insert(positions);
            let mut r = last_frame(&output, engine.name(), "files every 100 steps", procs)?;
            r.wall_time = Some(run.wall_time.as_secs_f64());
            r.max_difference = max_difference;
            bench.mpi.push(r);
        }
        // The same point with the forces every step (the experiment's own run, if made).
        let callback = experiment.output.join(format!("{}.h5", point.id));
        if callback.exists() {
            bench.mpi.push(last_frame(&callback, engine.name(), "callback every step", 1)?);
        }
    }
    progress.inc(1);
    Ok(())
}

/// The native LAMMPS deck (`magdem run --engine lammps --native --mpi N`): the fixed-moment
/// case-1 scene at 2.25 mg/ml (`verify::magnetic::case1_fixed_moments`, 2 ms) in magdem and in
/// LAMMPS' own `lj/cut/dipole/cut` on one and two processes, no magdem in LAMMPS' loop.
fn native_demo(bench: &mut Bench, progress: &indicatif::ProgressBar) -> Result<(), Error> {
    if !Engine::Lammps.available() || !mpirun_available() {
        bench.notes.push("native LAMMPS deck: lmp or mpirun is not installed".into());
        return Ok(());
    }
    let dir = bench.options.work.join("mpi-native");
    let scene = scene_in(&dir, "scene", &crate::verify::magnetic::case1_fixed_moments(2e-3, 1e-4)?)?;
    let particle_steps = scene.initial.len() as f64 * scene.total_steps() as f64;
    progress.set_message("native LAMMPS deck: magdem".to_string());
    let reference = dir.join("magdem.h5");
    let options = crate::run::RunOptions { overwrite: true, ..Default::default() };
    crate::run::run(&scene, &reference, &options)?;
    let x = crate::io::trajectory::Trajectory::open(&reference)?.all_vectors("position")?;
    let seconds = time_magdem(&scene, 1, Work::Steps, false)?.seconds;
    bench.native.push(NativeRun {
        stats: last_frame(&reference, "magdem", "induced moments without induction", 1)?,
        to_magdem: None,
        ns_per_particle_step: seconds / particle_steps * 1e9,
    });
    for procs in [1, 2] {
        progress.set_message(format!("native LAMMPS deck: mpirun -np {procs} lmp"));
        let output = dir.join(format!("lammps-np{procs}.h5"));
        let coupling = deck::Coupling::Native;
        let run = crate::reference::run_binary(
            Engine::Lammps,
            &scene,
            &dir.join(format!("np{procs}")),
            &output,
            &coupling,
            procs,
        )?;
        let y = crate::io::trajectory::Trajectory::open(&output)?.all_vectors("position")?;
        let log = std::fs::read_to_string(&run.log).unwrap_or_default();
        bench.native.push(NativeRun {
            stats: last_frame(&output, "lammps", "fixed moments, lj/cut/dipole/cut", procs)?,
            to_magdem: Some((&x - &y).iter().fold(0.0_f64, |m, d| m.max(d.abs()))),
            ns_per_particle_step: loop_time(&log).map_or(f64::NAN, |t| t / particle_steps * 1e9),
        });
    }
    // Cost in bulk: the paper's box walls cut the 15-diameter neighbourhood of most particles;
    // the 100x box (33 675 particles, periodic sides) holds the bulk's partners, 200 steps.
    progress.set_message("native LAMMPS deck: cost at 33 675 particles".to_string());
    let text = crate::verify::magnetic::case1_fixed_moments(2e-6, 2e-6)?;
    let paper_box = "hi = [4.840000e-04, 4.840000e-04, 4.840000e-04]";
    let x100 =
        "hi = [2.24653e-3, 2.24653e-3, 2.24653e-3]\nboundary = { x = \"periodic\", y = \"periodic\", z = \"wall\" }";
    let bulk_dir = dir.join("bulk");
    let bulk = scene_in(&bulk_dir, "scene", &text.replacen(paper_box, x100, 1))?;
    let particle_steps = bulk.initial.len() as f64 * bulk.total_steps() as f64;
    for threads in [1, 2] {
        let seconds = time_magdem(&bulk, threads, Work::Steps, false)?.seconds;
        bench.native_bulk.push(("magdem", threads, bulk.initial.len(), seconds / particle_steps * 1e9));
    }
    for procs in [1, 2] {
        let deck_dir = bulk_dir.join(format!("np{procs}"));
        let written = deck::write_with(Engine::Lammps, &bulk, &deck_dir, &deck::Coupling::Native)?;
        let seconds = time_engine(Engine::Lammps, &deck_dir, &written.input.to_string_lossy(), procs)?;
        bench.native_bulk.push(("lammps", procs, bulk.initial.len(), seconds / particle_steps * 1e9));
    }
    progress.inc(1);
    Ok(())
}

/// Statistics of a trajectory's last frame (gap tolerance 1e-3 of the radius).
fn last_frame(path: &Path, engine: &str, route: &'static str, procs: usize) -> Result<MpiRun, Error> {
    let trajectory = crate::io::trajectory::Trajectory::open(path)?;
    let (_, aggregates) =
        crate::analysis::trajectory::frame_aggregates(&trajectory, -1, 1e-3).map_err(|e| e.to_string())?;
    let lengths: Vec<f64> = crate::analysis::aggregates::finite_lengths(&aggregates).iter().map(|l| l * 1e6).collect();
    let mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
    let std = (lengths.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lengths.len() as f64).sqrt();
    let velocity = trajectory.all_vectors("velocity")?;
    let last = velocity.index_axis(ndarray::Axis(0), velocity.shape()[0] - 1);
    let fastest = last.rows().into_iter().map(|v| v.dot(&v).sqrt()).fold(0.0, f64::max);
    Ok(MpiRun {
        engine: engine.to_string(),
        route,
        procs,
        wall_time: None,
        fastest,
        aggregates: aggregates.len(),
        mean_length: mean,
        std_length: std,
        largest: aggregates.iter().map(|a| a.members.len()).max().unwrap_or(0),
        max_difference: None,
    })
}

/// Contender names of the machine's own gains (kept out of the measurements table).
const ARITHMETIC: &str = "arithmetic";
const TWO_RUNS: &str = "two runs at once";

/// Multiply-add rounds of an arithmetic try, over 32 independent lanes (8 AVX2 registers: two
/// fused multiply-adds per cycle keep a Zen 3 or Skylake core's floating-point pipes full).
const ARITHMETIC_ROUNDS: usize = 40_000_000;

/// Seconds of one arithmetic try: [`ARITHMETIC_ROUNDS`] rounds of `a = a·m + c` on 32 lanes held
/// in registers, shared out among `threads` threads; no memory traffic, so it measures whether
/// the cores deliver their arithmetic (a shared machine's other tenants can take part of it).
fn arithmetic_seconds(threads: usize) -> f64 {
    let started = Instant::now();
    std::thread::scope(|scope| {
        for t in 0..threads {
            scope.spawn(move || {
                let mut lanes: [f64; 32] = std::array::from_fn(|k| (k + t) as f64);
                for _ in 0..ARITHMETIC_ROUNDS / threads {
                    lanes.iter_mut().for_each(|a| *a = a.mul_add(0.999_999, 1e-7));
                }
                std::hint::black_box(lanes);
            });
        }
    });
    started.elapsed().as_secs_f64()
}

fn mpirun_available() -> bool {
    Command::new("mpirun").arg("--version").output().is_ok()
}

/// How the paper-physics scene renews its shielded drag (`forces.drag.refactor_every`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PaperDrag {
    /// Every step, as the paper's runs.
    EveryStep,
    /// Once per r-RESPA outer step (10 steps), applied to each step's velocities.
    Held,
}

impl PaperDrag {
    const ALL: [PaperDrag; 2] = [PaperDrag::EveryStep, PaperDrag::Held];

    fn every(self) -> u64 {
        match self {
            PaperDrag::EveryStep => 1,
            PaperDrag::Held => 10,
        }
    }

    /// The case name: the size last, the drag before it.
    fn case(self, n: usize) -> String {
        match self {
            PaperDrag::EveryStep => format!("paper physics {n}"),
            PaperDrag::Held => format!("paper physics, drag held, {n}"),
        }
    }

    fn label(self) -> &'static str {
        match self {
            PaperDrag::EveryStep => "every step",
            PaperDrag::Held => "held 10 steps",
        }
    }
}

/// Sizes of the paper-physics cases: 10³, 10⁴, 10⁵ up to `max`.
fn paper_sizes(max: usize) -> Vec<usize> {
    [1_000, 10_000, 100_000].into_iter().filter(|&n| n <= max.max(1_000)).collect()
}

/// The paper-physics cases: each size of [`paper_sizes`] with each drag setting.
fn paper_variants(max: usize) -> Vec<(usize, PaperDrag)> {
    paper_sizes(max).into_iter().flat_map(|n| PaperDrag::ALL.map(|d| (n, d))).collect()
}

fn scaling_sizes(max: usize) -> Vec<usize> {
    [1000, 3000, 10000, 30000, 100000, 300000].into_iter().filter(|&n| n <= max).collect()
}

/// What this machine is (CPU model, cores, memory, kernel).
fn machine() -> String {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let model = cpuinfo
        .lines()
        .find_map(|l| l.strip_prefix("model name"))
        .map(|s| s.trim_start_matches([' ', '\t', ':']).to_string())
        .unwrap_or("unknown CPU".into());
    let flags = cpuinfo.lines().find_map(|l| l.strip_prefix("flags")).unwrap_or("");
    let simd: Vec<&str> =
        ["avx512f", "avx2", "fma"].into_iter().filter(|f| flags.split_whitespace().any(|x| x == *f)).collect();
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let memory_kb: f64 = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0.0);
    let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease").unwrap_or_default();
    format!(
        "{model} ({}), {} cores, {}, {:.1} GiB memory, Linux {}",
        simd.join(", "),
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        caches(),
        memory_kb / 1024.0 / 1024.0,
        kernel.trim()
    )
}

/// The first core's data and unified caches, as Linux lists them ("L1d 32K, L2 512K, L3 32768K
/// shared by 2 cores").
fn caches() -> String {
    let read = |index: usize, name: &str| {
        std::fs::read_to_string(format!("/sys/devices/system/cpu/cpu0/cache/index{index}/{name}"))
            .ok()
            .map(|s| s.trim().to_string())
    };
    let levels: Vec<String> = (0..8)
        .filter_map(|i| {
            Some((
                read(i, "level")?,
                read(i, "type")?,
                read(i, "size")?,
                read(i, "shared_cpu_list").unwrap_or_default(),
            ))
        })
        .filter(|(_, kind, _, _)| kind != "Instruction")
        .map(|(level, kind, size, shared)| {
            let cores = shared
                .split(',')
                .map(|r| {
                    r.split_once('-')
                        .map_or(1, |(a, b)| b.parse::<usize>().unwrap_or(0) + 1 - a.parse::<usize>().unwrap_or(0))
                })
                .sum::<usize>();
            let name = if kind == "Data" { format!("L{level}d") } else { format!("L{level}") };
            if cores > 1 {
                format!("{name} {size} shared by {cores} cores")
            } else {
                format!("{name} {size}")
            }
        })
        .collect();
    if levels.is_empty() {
        "caches unknown".into()
    } else {
        format!("caches {}", levels.join(", "))
    }
}

/// How many times faster two cores ran than one (medians).
fn gain((one, two): &(Spread, Spread)) -> f64 {
    one.median / two.median
}

/// How many times faster `a` is than `b` (medians), "–" without both.
fn ratio(a: Option<&Measurement>, b: Option<&Measurement>) -> String {
    match (a, b) {
        (Some(a), Some(b)) => format!("{:.2}×", b.seconds.median / a.seconds.median),
        _ => "–".into(),
    }
}

/// A measurement's min / median / max, "–" without one.
fn cell(m: Option<&Measurement>) -> String {
    m.map_or("–".into(), |m| seconds(&m.seconds))
}

fn seconds(s: &Spread) -> String {
    format!("{:.3} / {:.3} / {:.3}", s.min, s.median, s.max)
}

/// Runs every measurement and writes `performance.md`, `performance-scaling.png` and
/// `performance.csv` into `options.out`; returns the report's path.
pub fn write(options: &Options) -> Result<PathBuf, Error> {
    std::fs::create_dir_all(&options.out)?;
    let mut bench = Bench::new(options);
    let total = 6
        + 2
        + paper_variants(options.max_particles).len() as u64
        + scaling_sizes(options.max_particles).len() as u64
        + 2 * options.mpi as u64;
    let progress = indicatif::ProgressBar::new(total)
        .with_style(indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} cases {elapsed} {msg}")?);
    bench.contact_cases(&progress)?;
    let agreement = bench.magnetic_cases(&progress)?;
    bench.paper_cases(&progress)?;
    bench.scaling(&progress)?;
    if options.mpi {
        mpi_demo(&mut bench, &progress)?;
        native_demo(&mut bench, &progress)?;
    }
    progress.finish_and_clear();

    write_csv(&options.out.join("performance.csv"), &bench.measurements)?;
    scaling_figure(&options.out.join("performance-scaling.png"), &bench.measurements)?;
    let text = markdown(&bench, &agreement);
    let path = options.out.join("performance.md");
    std::fs::write(&path, text)?;
    Ok(path)
}

fn write_csv(path: &Path, rows: &[Measurement]) -> Result<(), Error> {
    let mut csv = String::from("case,engine,threads,particles,steps,min_s,median_s,max_s,particle_steps_per_s\n");
    for m in rows {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{:.6},{:.6},{:.6},{:.4e}",
            m.case,
            m.engine,
            m.threads,
            m.particles,
            m.steps,
            m.seconds.min,
            m.seconds.median,
            m.seconds.max,
            m.particle_steps_per_second()
        );
    }
    std::fs::write(path, csv)?;
    Ok(())
}

/// Redraws `performance-scaling.png` in `out` from the `performance.csv` there; returns the
/// figure's path.
pub fn redraw(out: &Path) -> Result<PathBuf, Error> {
    let csv = out.join("performance.csv");
    let text = std::fs::read_to_string(&csv).map_err(|e| format!("cannot read {}: {e}", csv.display()))?;
    let bad = |line: usize| format!("{}:{}: not a row of magdem bench's table", csv.display(), line + 1);
    let mut rows = vec![];
    for (k, line) in text.lines().enumerate().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let engine = ["magdem", "liggghts", "lammps"].into_iter().find(|e| f.get(1) == Some(e));
        let number = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok());
        let (Some(engine), Some(threads), Some(particles), Some(steps), Some(min), Some(median), Some(max)) =
            (engine, number(2), number(3), number(4), number(5), number(6), number(7))
        else {
            // Rows of the machine's own ceilings and other engines are not drawn.
            if f.len() == 9 {
                continue;
            }
            return Err(bad(k).into());
        };
        rows.push(Measurement {
            case: f[0].to_string(),
            engine,
            threads: threads as usize,
            particles: particles as usize,
            steps: steps as u64,
            seconds: Spread { min, median, max },
            turns: vec![],
        });
    }
    let path = out.join("performance-scaling.png");
    scaling_figure(&path, &rows)?;
    Ok(path)
}

fn scaling_figure(path: &Path, rows: &[Measurement]) -> Result<(), Error> {
    let line = |case: &str, engine: &str, threads: usize| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|m| m.case == case && m.engine == engine && m.threads == threads)
            .map(|m| ((m.particles as f64).log10(), m.ns_per_particle_step().log10()))
            .collect()
    };
    // The paper-physics cases carry their size in the case name; the figure shows the paper's drag.
    let paper = |threads: usize| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|m| m.case.strip_prefix("paper physics ").is_some_and(|n| n.parse::<usize>().is_ok()))
            .filter(|m| m.engine == "magdem" && m.threads == threads)
            .map(|m| ((m.particles as f64).log10(), m.ns_per_particle_step().log10()))
            .collect()
    };
    let points = |packing: &str, engine: &str| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|m| m.case.starts_with(&format!("contact {packing}")) && m.engine == engine && m.threads == 1)
            .map(|m| ((m.particles as f64).log10(), m.ns_per_particle_step().log10()))
            .collect()
    };
    let mut series = vec![
        Series::line("magdem contact dilute, 1 thread", line("scaling contact dilute", "magdem", 1), palette(0)),
        Series::line("magdem contact loose, 1 thread", line("scaling contact loose", "magdem", 1), palette(1)),
        Series::line("magdem packed bed, 1 thread", line("scaling contact packed", "magdem", 1), palette(2)),
        Series::line("magdem packed bed, 2 threads", line("scaling contact packed", "magdem", 2), palette(6)),
        Series::line(
            "magdem dipoles, 15 d cut-off, 1 thread",
            line("scaling dipole cut-off 15 d", "magdem", 1),
            palette(4),
        ),
        Series::line(
            "magdem dipoles, 15 d cut-off, 2 threads",
            line("scaling dipole cut-off 15 d", "magdem", 2),
            palette(7),
        ),
        Series::line("magdem paper physics (chains), 1 thread", paper(1), RGBColor(0, 0, 0)),
        Series::line("magdem paper physics (chains), 2 threads", paper(2), palette(5)),
    ];
    for engine in ["liggghts", "lammps"] {
        for (k, packing) in ["dilute", "loose", "packed"].into_iter().enumerate() {
            let colour = if engine == "liggghts" { RGBColor(30, 150, 60) } else { RGBColor(230, 140, 0) };
            let pts = points(packing, engine);
            if !pts.is_empty() {
                series.push(Series::markers(format!("{engine} contact {packing}"), pts, colour, [4, 7, 10][k]));
            }
        }
    }
    series.retain(|s| !s.points.is_empty());
    // The legend above the data: every other corner of this chart holds points.
    line_chart_with_legend(
        path,
        "Cost per particle and step against N (flat = linear in N)",
        "log10 N (particles)",
        "log10 ns per particle-step",
        &series,
        Legend::above_data(1.6),
    )
    .map_err(|e| e.to_string().into())
}

/// The wall time of the `make reproduce` runs, as the paper report recorded it in its tables.
fn reproduce_wall_time() -> Option<u64> {
    let path = Path::new("reports/paper/tables").join(format!("{}.csv", crate::report::paper::REPRODUCE_TABLE));
    let table = crate::report::tables::read_csv(&path).ok()?;
    let seconds = crate::report::tables::floats(&table, "experiments_wall_time_s").ok()?;
    seconds.first().filter(|s| s.is_finite()).map(|s| s.round() as u64)
}

/// What mutual induction changes in case 1 at 2.25 mg/ml, from the committed paper report's
/// ranking table (its sensitivity study's `no-induction` runs), or where to find it.
fn induction_effect() -> String {
    induction_effect_in(Path::new("reports/paper/tables/explanations.csv"))
}

fn induction_effect_in(explanations: &Path) -> String {
    let measured = || -> Option<String> {
        use crate::report::paper::convergence::Explanation;
        let table = crate::report::tables::read_csv(explanations).ok()?;
        let text = |name: &str| table.column(name).ok()?.str().ok().cloned();
        let number = |name: &str| crate::report::tables::floats(&table, name).ok();
        let (explanation, c) = (text("explanation")?, number("concentration_mg_per_ml")?);
        let (change, ci95, n) = (number("change_percent")?, number("ci95_percent")?, number("runs_or_pairs")?);
        let k = (0..c.len())
            .find(|&k| explanation.get(k) == Some(Explanation::Induction.name()) && (c[k] - 2.25).abs() < 1e-9)?;
        Some(format!(
            "the sensitivity study of `reports/paper/README.md` moves the 2.25 mg/ml mean length by {:+.1} ± {:.1} % ({} seeds, paired)",
            change[k], ci95[k], n[k]
        ))
    };
    measured().unwrap_or_else(|| {
        "the 2.25 mg/ml mean length moves by the sensitivity study's `no-induction` change in `reports/paper/README.md`".into()
    })
}

/// The targets against this run's medians: one line each, met or not.
fn targets(bench: &Bench) -> String {
    let verdict = |x: f64, target: f64| if x >= target { "met" } else { "not met" };
    let mut lines = vec![];
    for case in ["contact packed 3000", "contact packed 30000"] {
        if let Some(x) = bench.speedup(case, ("magdem", 1), ("liggghts", 1)) {
            let z = bench.contacts.iter().find(|(c, _, _)| c == case).map_or(f64::NAN, |(_, pairs, _)| 2.0 * pairs);
            lines.push(format!(
                "{case} (coordination {z:.1}), one thread ÷ LIGGGHTS one process ≥ 2×: {x:.2}× — {}",
                verdict(x, 2.0)
            ));
        }
    }
    for case in ["dipole all pairs 307", "dipole cut-off 15 d 307"] {
        if let Some(x) = bench.speedup(case, ("magdem", 1), ("lammps", 1)) {
            lines.push(format!("{case}, one thread ÷ LAMMPS ≥ 5×: {x:.2}× — {}", verdict(x, 5.0)));
        }
    }
    for case in ["contact packed 30000"] {
        if let Some(x) = bench.speedup(case, ("magdem", 2), ("magdem", 1)) {
            let engines: Vec<String> = [("liggghts", "LIGGGHTS"), ("lammps", "LAMMPS")]
                .iter()
                .filter_map(|(engine, name)| {
                    Some(format!("{name} {:.2}×", bench.speedup(case, (engine, 2), (engine, 1))?))
                })
                .collect();
            let machine = bench.two_core_gains(case).map(|(arithmetic, two_runs)| {
                format!("in the same minutes: arithmetic on two cores {arithmetic:.2}× one, two one-thread runs at once {two_runs:.2}× the throughput of one")
            });
            let context: Vec<String> =
                [(!engines.is_empty()).then(|| format!("two MPI processes ÷ one: {}", engines.join(", "))), machine]
                    .into_iter()
                    .flatten()
                    .collect();
            let context = if context.is_empty() {
                String::new()
            } else {
                format!(" ({}; see “Both cores”)", context.join("; "))
            };
            // The verdict takes the turns' ratios (each turn's one-thread run over its two-thread
            // run, seconds apart); the ratio of the medians mixes turns minutes apart.
            let (x, how) = match bench.paired_speedup(case, ("magdem", 2), ("magdem", 1)) {
                Some(r) => (
                    r.median,
                    format!(
                        "median over {} turns of each turn's one-thread ÷ two-thread time (turns {:.2}–{:.2}×; \
                         ratio of the medians {x:.3}×)",
                        bench.find(case, "magdem", 1).map_or(0, |m| m.turns.len()),
                        r.min,
                        r.max
                    ),
                ),
                None => (x, "ratio of the medians".to_string()),
            };
            lines.push(format!("{case}, two threads ÷ one ≥ 1.7×: {x:.3}×, {how} — {}{context}", verdict(x, 1.7)));
        }
    }
    for case in
        ["scaling contact dilute", "scaling contact loose", "scaling contact packed", "scaling dipole cut-off 15 d"]
    {
        let runs: Vec<&Measurement> = bench.measurements.iter().filter(|m| m.case == case && m.threads == 1).collect();
        let dipoles = case.contains("dipole");
        let cost = |m: &Measurement| if dipoles { bench.ns_per_pair(m) } else { Some(m.ns_per_particle_step()) };
        let (Some(small), Some(large)) =
            (runs.iter().min_by_key(|m| m.particles), runs.iter().max_by_key(|m| m.particles))
        else {
            continue;
        };
        if let (Some(small_cost), Some(large_cost)) = (cost(small), cost(large)) {
            let unit = if dipoles { "per pair" } else { "per particle-step" };
            lines.push(format!(
                "{}: cost {unit} at N = {} ÷ at N = {}: {:.2} (1 for exactly linear growth; see the table below)",
                case.trim_start_matches("scaling "),
                large.particles,
                small.particles,
                large_cost / small_cost
            ));
        }
    }
    if lines.is_empty() {
        return String::new();
    }
    format!(
        "## Against the targets

{}

",
        lines.iter().map(|l| format!("- {l}")).collect::<Vec<_>>().join("\n")
    )
}

/// magdem's two threads against the engines' two MPI processes at 30 000 particles, phase by
/// phase, and what the machine itself gains from a second core in the same minutes.
fn both_cores(bench: &Bench) -> String {
    let mut s = "\n## Both cores\n\nThe reference engines on both cores (`mpirun -np 2`, the same decks; `performance.csv` lists them with 2 in its threads column), and what the machine itself gains from a second core, measured in turns with the case's contenders so that it sees the machine in the same minutes: *arithmetic*, fused multiply-adds on 32 lanes held in registers (no memory traffic: whether the two cores deliver two cores' arithmetic, which a shared machine's other tenants can take part of), and *two runs at once*, two independent one-thread magdem runs of the case side by side, their loops started together (the throughput of the pair, timed by the slower, over that of one run alone). The two runs share nothing but the machine: no hand-off, no join, no data. What they gain is the most the case's own work, with its own memory traffic, can gain from a second core in those minutes, and it is what an ensemble of runs (seeds, time steps, concentrations) gains by running two at a time. The last column sets magdem's two threads against it. Medians:\n\n".to_string();
    s += "| case | magdem 2 threads ÷ 1 | LIGGGHTS 2 processes ÷ 1 | LAMMPS 2 processes ÷ 1 | magdem 2 threads ÷ LIGGGHTS 2 processes speed | magdem 2 threads ÷ LAMMPS 2 processes speed | arithmetic, 2 cores ÷ 1 | two runs at once, throughput ÷ one run | magdem's 2-thread gain ÷ two runs' gain |\n|---|---|---|---|---|---|---|---|---|\n";
    for case in ["contact loose 30000", "contact packed 30000"] {
        let ratio = |fast, slow| bench.speedup(case, fast, slow).map_or("–".into(), |x| format!("{x:.2}×"));
        let gained = |engine| ratio((engine, 2), (engine, 1));
        let (against_liggghts, against_lammps) =
            (ratio(("magdem", 2), ("liggghts", 2)), ratio(("magdem", 2), ("lammps", 2)));
        let magdem_gain = bench.speedup(case, ("magdem", 2), ("magdem", 1));
        let machine = bench.two_core_gains(case).map(|(arithmetic, two_runs)| {
            let efficiency = magdem_gain.map_or("–".into(), |g| format!("{:.2}", g / two_runs));
            [format!("{arithmetic:.2}×"), format!("{two_runs:.2}×"), efficiency]
        });
        let machine = machine.unwrap_or_else(|| std::array::from_fn(|_| "–".to_string())).join(" | ");
        let _ = writeln!(
            s,
            "| {case} | {} | {} | {} | {against_liggghts} | {against_lammps} | {machine} |",
            gained("magdem"),
            gained("liggghts"),
            gained("lammps")
        );
    }
    if bench.phases_on_both_cores.is_empty() {
        return s;
    }
    s += "\nPhase by phase, from the same runs (the solver's timers; medians per step):\n\n| case | phase | 1 thread (µs) | 2 threads (µs) | 2 threads ÷ 1 |\n|---|---|---|---|---|\n";
    let mut integrate_bandwidth = vec![];
    for (case, phases) in &bench.phases_on_both_cores {
        for (name, t1, t2) in phases {
            let _ = writeln!(s, "| {case} | {name} | {:.1} | {:.1} | {:.2}× |", t1 * 1e6, t2 * 1e6, t1 / t2);
        }
        let (t1, t2): (f64, f64) = phases.iter().fold((0.0, 0.0), |(a, b), (_, t1, t2)| (a + t1, b + t2));
        let _ = writeln!(s, "| {case} | sum of the phases | {:.1} | {:.1} | {:.2}× |", t1 * 1e6, t2 * 1e6, t1 / t2);
        if let Some((_, t1, t2)) = phases.iter().find(|(name, _, _)| *name == "integrate") {
            let bytes = integrate_bytes_per_step(bench, case);
            integrate_bandwidth.push(format!(
                "{case}: {:.1} MB per step, {:.1} GB/s on one thread and {:.1} GB/s on two",
                bytes / 1e6,
                bytes / t1 / 1e9,
                bytes / t2 / 1e9
            ));
        }
    }
    let _ = write!(
        s,
        "\nThe integrator's share is pure streaming: velocity Verlet with one mass for all particles makes {INTEGRATE_PASSES} passes over arrays of N three-vectors per step (half kick and drift: x, v, ω read and written, F and T read; closing half kick: v, ω read and written, F and T read), each read and each write counted once: {}. The other phases pass over particle arrays of the same size (the neighbour filter also gathers the partners' positions), and the serial rest of the step comes on top: the hand-offs between the parallel loops, and the gathering of the shares' contact springs. The history ([performance-history.md](performance-history.md)) has the measurements behind this.\n",
        integrate_bandwidth.join("; ")
    );
    s
}

/// Turns, at least, of the contact cases that judge a target (the beds of 30 000 and the packed
/// bed of 3 000).
const TARGET_TURNS: usize = 9;

/// Passes (reads and writes) over arrays of three-vectors the velocity-Verlet kicks and drift
/// make per step (see [`both_cores`]).
const INTEGRATE_PASSES: usize = 14;

/// Bytes the velocity-Verlet kicks and drift move per step in `case` (24 per three-vector pass).
fn integrate_bytes_per_step(bench: &Bench, case: &str) -> f64 {
    let particles = bench.measurements.iter().find(|m| m.case == case).map_or(0, |m| m.particles);
    INTEGRATE_PASSES as f64 * 24.0 * particles as f64
}

/// The dipole-force comparison with LAMMPS.
fn dipole_section(bench: &Bench, agreement: &[(String, f64)]) -> String {
    let mut s = String::new();
    s += "\n## Dipole forces at case-1 parameters\n\n307 particles in the paper's 4.5 mg/ml box (396 × 396 × 330 µm), moments induced by 0.4 T without mutual induction (fixed dipoles, as LAMMPS holds them), dipole force only, 2 000 force evaluations with the particles held still (without contact forces the nearest pairs would collide within microseconds). LAMMPS runs its own `lj/cut/dipole/cut` (ε = 0) on the same positions and moments (docs/model.md §10.4: p = m √(1e-7/k_e)) as a `run` without an integrating fix; the force agreement is the largest |F_LAMMPS − F_magdem| over particles relative to the largest force, at the initial configuration (`reference::dipole_check`).\n\n";
    s += "| case | magdem 1 thread (s) | LAMMPS (s) | magdem ÷ LAMMPS speed | force agreement |\n|---|---|---|---|---|\n";
    for case in ["dipole all pairs 307", "dipole cut-off 15 d 307"] {
        let (one, lmp) = (bench.find(case, "magdem", 1), bench.find(case, "lammps", 1));
        let agree = agreement.iter().find(|(c, _)| c == case).map_or("–".into(), |(_, e)| format!("{e:.1e}"));
        let _ = writeln!(s, "| {case} | {} | {} | {} | {agree} |", cell(one), cell(lmp), ratio(one, lmp));
    }
    s
}

/// The native LAMMPS deck beside magdem, and what a 10⁶-particle run would need.
fn native_section(bench: &Bench) -> String {
    let mut s = String::new();
    if bench.native.is_empty() {
        return s;
    }
    s += &format!(
        "\n## Beyond one machine without magdem: LAMMPS' own dipoles\n\n`magdem run --engine lammps --native --mpi N` (or `magdem deck --engine lammps --native`, then `mpirun -np N lmp -in in.scene`) writes case 1 in LAMMPS' own pair styles: `pair_style hybrid/overlay granular lj/cut/dipole/cut` with ε = 0 and the 15-diameter cut-off, the moments magdem's at t = 0 as electric dipoles (`atom_style hybrid sphere dipole`, p = m √(1e-7/k_e)), `fix viscous`, `fix gravity`, `fix wall/gran`, `fix nve/sphere` without `update dipole` (the moments stay along the field). No magdem process is in the loop, so it runs unchanged on a cluster. It holds fixed moments only: mutual induction stays magdem's, and without it {}. LAMMPS also applies the torque p × E to its fixed dipoles, which magdem's induced moments do not feel; the comparison scene has friction 0, so that the spin this gives cannot reach the contacts. Scene: `case1-c2.25` with induction \"none\", Stokes drag without shielding or rotational drag, friction 0, 2 ms (`verify::magnetic::case1_fixed_moments`). Statistics of the last frame (gap tolerance 1e-3 of the radius); cost = loop time per particle-step (magdem's one-thread step loop; LAMMPS' `Loop time`).\n\n| engine | moments | processes | aggregates | mean length (µm) | std (µm) | largest (particles) | max position difference to magdem (m) | ns per particle-step |\n|---|---|---|---|---|---|---|---|---|\n",
        induction_effect()
    );
    for r in &bench.native {
        let m = &r.stats;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.2} | {:.2} | {} | {} | {:.0} |",
            m.engine,
            m.route,
            m.procs,
            m.aggregates,
            m.mean_length,
            m.std_length,
            m.largest,
            r.to_magdem.map_or("–".into(), |d| format!("{d:.1e}")),
            r.ns_per_particle_step
        );
    }
    if !bench.native_bulk.is_empty() {
        let n = bench.native_bulk[0].2;
        let _ = writeln!(
            s,
            "\nThe paper's box has walls on every face, which cut most particles' 15-diameter neighbourhood; in bulk the cost is higher. The same scene in the 100× box ({n} particles, periodic along x and y, 200 steps; loop time per particle-step):\n\n| engine | threads or processes | ns per particle-step |\n|---|---|---|"
        );
        for (engine, threads, _, ns) in &bench.native_bulk {
            let _ = writeln!(s, "| {engine} | {threads} | {ns:.0} |");
        }
    }
    let bulk = |engine: &str, threads: usize| {
        bench.native_bulk.iter().find(|(e, t, _, _)| *e == engine && *t == threads).map(|(_, _, _, ns)| *ns)
    };
    if let (Some(one), Some(two)) = (bulk("lammps", 1), bulk("lammps", 2)) {
        let efficiency = one / two / 2.0;
        let core_hours = one * 1e-9 * 1e6 * 5e5 / 3600.0;
        let _ = writeln!(
            s,
            "\nA 10⁶-particle, 5 ms run (500 000 steps at dt = 1e-8 s) at the bulk cost is {core_hours:.0} core-hours of LAMMPS on one process ({one:.0} ns per particle-step; with a cut-off pair style the cost per particle stays that of the bulk at any N of equal concentration). Two processes ran at {:.0} % parallel efficiency here; at that efficiency 256 cores would take {:.1} h and 1 024 cores {:.1} h. The efficiency on a cluster is not measured here: with the 15-diameter cut-off each process also holds the atoms of a 0.17 mm shell around its sub-domain, for sub-domains of 4 000 atoms (1.1 mm cubes at 2.25 mg/ml) 1.2 times as many ghosts as its own, so expect it to fall as the cores grow.",
            100.0 * efficiency,
            core_hours / (256.0 * efficiency),
            core_hours / (1024.0 * efficiency)
        );
    }
    s
}

/// The paper's physics at scale: cost per particle-step, memory, two threads, and what a 5 ms run
/// of that size takes.
fn paper_section(bench: &Bench) -> String {
    let mut s = String::new();
    s += "\n## The paper's physics at scale\n\nCase 1 at 2.25 mg/ml with every term of the paper's model (`paper_scene` in `src/bench/mod.rs`): the paper's induction within 15 diameters, dipole forces, Schiller–Naumann drag with the shielded area, gravity, Hertz–Mindlin contacts and walls; the box scaled at equal concentration, periodic along x and y; r-RESPA with the magnetic forces every 10 steps, dt = 1e-8 s, as the 100× runs. The particles start as the field leaves them, in straight chains of ten touching spheres along the field placed at random (1.8 contacts per particle, 2 × (pairs) below), so contact, shielding and the dipole sums all work from the first step. 10⁷ particle-steps per run (at least 100 steps). The 5 ms column is the two-thread cost times the particles times 500 000 steps. The paper's own runs (about 300 particles) are cheaper per particle than these and run one per core: `make reproduce` runs its ensembles two at a time, one thread each.\n\n";
    s += "The drag's coefficients (shielded area, Reynolds factor) are renewed every step as in the paper's runs, or held over each 10-step outer step and applied to each step's velocities (`forces.drag.refactor_every = 10`); what holding them changes in case 1 is the sensitivity study's `drag-held` variant in `reports/paper/`.\n\n";
    s += "| particles | drag | steps | contacts per particle (pairs × 2 + walls) | 1 thread (ns per particle-step) | 2 threads (ns per particle-step) | 2 threads ÷ 1 | 1 and 2 threads bitwise equal | memory per particle | a 5 ms run on 2 threads |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (n, drag) in paper_variants(bench.options.max_particles) {
        let case = drag.case(n);
        let (Some(one), Some(two)) = (bench.find(&case, "magdem", 1), bench.find(&case, "magdem", 2)) else { continue };
        let contacts = bench
            .contacts
            .iter()
            .find(|(c, _, _)| *c == case)
            .map_or("–".into(), |(_, pairs, walls)| format!("{:.2} + {walls:.2}", 2.0 * pairs));
        let bitwise =
            bench.bitwise.iter().find(|(c, _)| *c == case).map_or("–", |(_, b)| if *b { "yes" } else { "no" });
        let memory =
            bench.memory.iter().find(|(c, _, _)| *c == case).map_or("–".into(), |(_, _, b)| format!("{b:.0} B"));
        let five_ms = two.ns_per_particle_step() * 1e-9 * n as f64 * 5e5;
        let _ = writeln!(
            s,
            "| {n} | {} | {} | {contacts} | {:.0} | {:.0} | {:.2}× | {bitwise} | {memory} | {:.0} min |",
            drag.label(),
            one.steps,
            one.ns_per_particle_step(),
            two.ns_per_particle_step(),
            one.seconds.median / two.seconds.median,
            five_ms / 60.0
        );
    }
    s
}

fn scaling_section(bench: &Bench) -> String {
    let o = bench.options;
    let mut s = String::new();
    s += "\n## Cost against N\n\n![scaling](performance-scaling.png)\n\nnanoseconds per particle-step (median), magdem; contact scenes at 1e7 particle-steps (at least 100 steps), the dipole scene (as above, box scaled at equal concentration) as force evaluations at 2e6 particle-evaluations (at least 20). Memory: heap bytes the simulation holds at the end of its run, per particle (state, contact history, neighbour and pair lists, buffers; counted by the binary's instrumented allocator).\n\nWhere the contact scenes' cost per particle rises with N, their particle arrays (memory rows below) have outgrown a cache level (the machine line above gives the sizes). The dipole sum's cost per particle follows its partners within the cut-off: a 15-diameter sphere is cut by the walls of the small boxes, so partners per particle grow with the box until it is much larger than the cut-off; from 4 096 particles on, the sum runs in 16 bands of rows, each with its own buffer for the reactions, the buffers then added in band order (the bands share the threads, and the order is the same on any thread count). The cost per pair (pairs within the cut-off, each counted once) separates the sum's own cost from the neighbourhood's size.\n\n";
    s += "| case | threads |";
    let sizes: Vec<usize> = scaling_sizes(o.max_particles);
    for n in &sizes {
        let _ = write!(s, " N = {n} |");
    }
    s += "\n|---|---|";
    s += &"---|".repeat(sizes.len());
    s += "\n";
    for (case, threads) in [
        ("scaling contact dilute", 1),
        ("scaling contact loose", 1),
        ("scaling contact packed", 1),
        ("scaling contact packed", 2),
        ("scaling dipole cut-off 15 d", 1),
        ("scaling dipole cut-off 15 d", 2),
    ] {
        let _ = write!(s, "| {} | {threads} |", case.trim_start_matches("scaling "));
        // One measurement per size, in the order of the sizes (a packed bed's count is the
        // lattice's nearest to N).
        let mut runs = bench.measurements.iter().filter(|m| m.case == case && m.threads == threads);
        for _ in &sizes {
            let m = runs.next();
            let _ = write!(s, " {} |", m.map_or("–".into(), |m| format!("{:.1} ns", m.ns_per_particle_step())));
        }
        s += "\n";
    }
    let _ = write!(s, "| dipole cut-off 15 d: partners per particle | 1 |");
    for n in &sizes {
        let pairs = bench.dipole_pairs.iter().find(|(k, _)| k == n);
        let _ = write!(s, " {} |", pairs.map_or("–".into(), |(k, p)| format!("{:.0}", 2.0 * *p as f64 / *k as f64)));
    }
    s += "\n";
    let _ = write!(s, "| dipole cut-off 15 d: ns per pair | 1 |");
    for n in &sizes {
        let m = bench
            .measurements
            .iter()
            .find(|m| m.case == "scaling dipole cut-off 15 d" && m.threads == 1 && m.particles == *n);
        let _ = write!(s, " {} |", m.and_then(|m| bench.ns_per_pair(m)).map_or("–".into(), |ns| format!("{ns:.1} ns")));
    }
    s += "\n";
    for (case, threads) in [
        ("scaling contact dilute", 1),
        ("scaling contact loose", 1),
        ("scaling contact packed", 1),
        ("scaling dipole cut-off 15 d", 1),
    ] {
        let _ = write!(s, "| memory, {} | {threads} |", case.trim_start_matches("scaling "));
        for n in &sizes {
            let m = bench.memory.iter().find(|(c, k, _)| c == case && k == n);
            let _ = write!(
                s,
                " {} |",
                m.filter(|(_, _, b)| *b > 0.0).map_or("–".into(), |(_, _, b)| format!("{:.0} B", b))
            );
        }
        s += "\n";
    }
    s
}

/// Where the time goes, phase by phase.
fn profile_section(bench: &Bench) -> String {
    let mut s = String::new();
    s += "\n## Where the time goes\n\nShare of magdem's single-thread loop time per step phase (the solver's own timers, `magdem run --timings`); `integrate` is the integrator's own work between force evaluations.\n\n| case | phases |\n|---|---|\n";
    for (case, shares) in &bench.profiles {
        let mut shares = shares.clone();
        shares.sort_by(|a, b| b.1.total_cmp(&a.1));
        let text: Vec<String> = shares.iter().map(|(n, f)| format!("{n} {:.0}%", 100.0 * f)).collect();
        let _ = writeln!(s, "| {case} | {} |", text.join(", "));
    }
    s += "\nThe profile-led history of the optimisations (what each bought, measured with `perf` and the phase timers at the commits named) is in [performance-history.md](performance-history.md).\n";
    s
}

fn markdown(bench: &Bench, agreement: &[(String, f64)]) -> String {
    let o = bench.options;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Performance: magdem against LIGGGHTS and LAMMPS\n\nGenerated by `magdem bench --repeats {}` (magdem {}, commit {}). Machine: {}.{}\n",
        o.repeats,
        env!("CARGO_PKG_VERSION"),
        env!("MAGDEM_GIT_COMMIT"),
        machine(),
        if bench.engine_versions.is_empty() { String::new() } else { format!(" Engines: {}.", bench.engine_versions.join("; ")) }
    );
    let _ = writeln!(
        s,
        "Times are loop times in seconds, min / median / max of {} runs (at least {TARGET_TURNS} for the beds of 30 000, whose two-thread ratio is taken turn by turn, and for the packed bed of 3 000, whose median is held against LIGGGHTS'): magdem around its step loop (no output), LIGGGHTS and LAMMPS as the `Loop time` of their logs, each engine a separate process running the deck `magdem deck` writes for the same scene (same particles, dt = 1e-8 s, same output interval). The contenders of a case run in turns (one run of each, then the next round), so that a shared machine's changing load falls on all of them alike. Ratios compare medians (particle-steps per second). The scenes, decks and logs are under `{}`; the numbers are in `performance.csv`.\n",
        o.repeats,
        o.work.display()
    );

    s += &targets(bench);
    s += "## Contact only: Hertz + history + walls + gravity\n\n11 µm spheres (E = 1e9 Pa, e = 0.5, μ = 0.5) in a walled box under gravity, about 300 / 3 000 / 30 000 of them, 3e7 particle-steps per run, in three packings. *Packed*: a face-centred cubic block filling its box (`lattice = { kind = \"fcc\" }`, c cubic cells per edge with the sites on its faces, 4c³ + 6c² + 3c + 1 particles: 365, 3 430, 29 660), neighbours pre-compressed by 1e-4 of a diameter (a contact force of 7 000 weights, so that gravity opens none): 12 contacts per particle in the bulk, the work a DEM code exists for. *Loose*: placed at random, solid fraction 0.21 (0.1 mm cube for 300). *Dilute*: placed at random, solid fraction 0.0017 (0.5 mm cube for 300): free flight, it times the streaming of free particles, not contacts. Random placements are numbered along a Morton curve (`order = \"spatial\"`), the lattice row by row; the engines read the particles from the deck's data file in the same order, so all start from the same positions. The contacts column counts, at the end of magdem's one-thread run, pair contacts per particle times two (the coordination number) and wall contacts per particle; the contact share is that of the contact phase in magdem's one-thread step (the phase timers, below).\n\n";
    s += "| case | particles | steps | contacts per particle (pairs × 2 + walls) | contact share of the step | magdem 1 thread (s) | magdem 2 threads (s) | LIGGGHTS (s) | LAMMPS (s) | magdem ÷ LIGGGHTS speed | magdem ÷ LAMMPS speed | 2 threads ÷ 1 | 1 and 2 threads bitwise equal |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    let cases: Vec<String> =
        bench.measurements.iter().filter(|m| m.case.starts_with("contact ")).map(|m| m.case.clone()).fold(
            vec![],
            |mut v, c| {
                if !v.contains(&c) {
                    v.push(c);
                }
                v
            },
        );
    for case in &cases {
        let (one, two) = (bench.find(case, "magdem", 1), bench.find(case, "magdem", 2));
        let (lig, lmp) = (bench.find(case, "liggghts", 1), bench.find(case, "lammps", 1));
        let bitwise = bench.bitwise.iter().find(|(c, _)| c == case).map_or("–", |(_, b)| if *b { "yes" } else { "no" });
        let contacts = bench
            .contacts
            .iter()
            .find(|(c, _, _)| c == case)
            .map_or("–".into(), |(_, pairs, walls)| format!("{:.2} + {walls:.2}", 2.0 * pairs));
        let share = bench
            .profiles
            .iter()
            .find(|(c, _)| c == case)
            .and_then(|(_, shares)| shares.iter().find(|(name, _)| *name == "contact"))
            .map_or("–".into(), |(_, f)| format!("{:.0} %", 100.0 * f));
        let _ = writeln!(
            s,
            "| {case} | {} | {} | {contacts} | {share} | {} | {} | {} | {} | {} | {} | {} | {bitwise} |",
            one.map_or(0, |m| m.particles),
            one.map_or(0, |m| m.steps),
            cell(one),
            cell(two),
            cell(lig),
            cell(lmp),
            ratio(one, lig),
            ratio(one, lmp),
            ratio(two, one)
        );
    }

    s += &both_cores(bench);
    s += &dipole_section(bench, agreement);
    s += &paper_section(bench);
    s += &scaling_section(bench);
    s += &profile_section(bench);
    if !bench.mpi.is_empty() {
        s += "\n## Beyond one machine: the decks under MPI\n\nThe reference point of `experiments/paper/reference.toml` (case 1 at 0.563 mg/ml, Stokes drag, seed 1, 5 ms) run by `magdem run --engine ENGINE --exchange-every 100 --mpi N`: the deck `magdem deck` writes, unchanged, under `mpirun -np N`, with magdem's magnetic forces exchanged through files every 100 steps (the callback route sees only one process's atoms), beside the experiment's own run of the point with the forces every step. Statistics of the last frame (gap tolerance 1e-3 of the radius; length std over aggregates, population):\n\n| engine | magnetic forces | MPI processes | wall time (s) | aggregates | mean length (µm) | std (µm) | largest (particles) | fastest particle (m/s) | max position difference to 1 process (m) |\n|---|---|---|---|---|---|---|---|---|---|\n";
        for r in &bench.mpi {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {:.2} | {:.2} | {} | {:.3} | {} |",
                r.engine,
                r.route,
                r.procs,
                r.wall_time.map_or("–".into(), |t| format!("{t:.1}")),
                r.aggregates,
                r.mean_length,
                r.std_length,
                r.largest,
                r.fastest,
                r.max_difference.map_or("–".into(), |d| format!("{d:.1e}"))
            );
        }
        s += "\nOne and two processes give the same trajectory: the decks move to an MPI cluster unchanged. What the files route costs is the exchange interval, not the process count: an exchange (a `shell` call of `magdem magnetic-forces` on the first process, the forces read back as atomfile variables) takes milliseconds, so exchanging every step is out of reach, and holding the magnetic force for 100 steps (1 µs, about twice the Hertz contact duration) pumps energy into the contacts of case 1. A cluster study by files needs an interval well below the contact duration, or its own gather of the positions into the callback.\n";
        if !bench.mpi.iter().any(|r| r.route == "callback every step") {
            s += "\nThe callback rows (the same point with the forces every step, for comparison) come from the experiment's own runs, which are not in `runs/` here: `magdem experiment experiments/paper/reference.toml` (or `make reproduce`) adds them.\n";
        }
    }
    s += &native_section(bench);
    if let Some(t) = reproduce_wall_time() {
        let _ = writeln!(s, "\n## The default `make reproduce` ensemble\n\nThe committed paper report (`reports/paper/README.md`) was produced by a `make reproduce` whose runs took {t} s of wall time ({:.1} min) when it was generated (that report names its commit; this bench does not rerun the ensemble); the time before this work is in the history.", t as f64 / 60.0);
    }
    if !bench.notes.is_empty() {
        s += "\n## Notes\n\n";
        for n in &bench.notes {
            let _ = writeln!(s, "- {n}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The induction effect is the 2.25 mg/ml `induction` row of the ranking table, and a
    /// missing table gives a pointer instead of a number.
    #[test]
    fn the_induction_effect_comes_from_the_ranking_table() {
        let dir = tempfile::tempdir().unwrap();
        let table = dir.path().join("explanations.csv");
        std::fs::write(
            &table,
            "concentration_mg_per_ml,explanation,what,change_percent,ci95_percent,runs_or_pairs\n\
             1.125,induction,x,-22.1,19.9,3.0\n2.25,shielding,y,-12.8,7.2,10.0\n2.25,induction,z,-13.07,13.47,10.0\n",
        )
        .unwrap();
        let text = induction_effect_in(&table);
        assert!(text.contains("-13.1 ± 13.5 % (10 seeds, paired)"), "{text}");
        assert!(induction_effect_in(&dir.path().join("none.csv")).contains("`no-induction`"));
    }

    /// A speed-up taken turn by turn pairs each turn's runs: a machine that slows down between
    /// turns (here by 2×) moves the ratio of the medians, not the turns' ratios.
    #[test]
    fn a_paired_speedup_takes_each_turns_ratio() {
        let options = Options { out: "o".into(), work: "w".into(), repeats: 3, max_particles: 1000, mpi: false };
        let mut bench = Bench::new(&options);
        let run = |threads, turns: [f64; 3]| Measurement {
            case: "c".into(),
            engine: "magdem",
            threads,
            particles: 1,
            steps: 1,
            seconds: Spread::of(&turns),
            turns: turns.to_vec(),
        };
        bench.measurements = vec![run(1, [6.0, 12.0, 12.0]), run(2, [3.0, 3.0, 6.0])];
        let paired = bench.paired_speedup("c", ("magdem", 2), ("magdem", 1)).unwrap();
        assert_eq!((paired.min, paired.median, paired.max), (2.0, 2.0, 4.0));
        assert_eq!(bench.speedup("c", ("magdem", 2), ("magdem", 1)), Some(4.0));
        assert!(bench.paired_speedup("c", ("magdem", 2), ("liggghts", 1)).is_none());
    }

    /// The figure is redrawn from the bench's own table, its ceiling rows skipped, and a table
    /// that is not the bench's is refused with the file and line named.
    #[test]
    fn the_scaling_figure_is_redrawn_from_the_table() {
        let dir = tempfile::tempdir().unwrap();
        let header = "case,engine,threads,particles,steps,min_s,median_s,max_s,particle_steps_per_s\n";
        let rows = "scaling contact packed,magdem,1,1099,9099,1.6,1.7,1.8,5.9e6\n\
                    scaling contact packed,magdem,1,3430,2915,1.4,1.5,1.6,6.7e6\n\
                    contact packed 3000,arithmetic,1,3430,10000,1.0,1.0,1.0,1e7\n";
        std::fs::write(dir.path().join("performance.csv"), format!("{header}{rows}")).unwrap();
        let path = super::redraw(dir.path()).unwrap();
        assert!(std::fs::metadata(&path).unwrap().len() > 10_000, "a drawn PNG");
        std::fs::write(dir.path().join("performance.csv"), format!("{header}not,a,row\n")).unwrap();
        let e = super::redraw(dir.path()).unwrap_err().to_string();
        assert!(e.contains("performance.csv:2"), "{e}");
    }
}
