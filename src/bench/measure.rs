//! The measurements of `magdem bench`: runs every case in turns and saves a [`BenchRecord`].

use super::record::*;
use super::*;
use crate::reference::dipole_check;

/// Steps of a contact-only case with `n` particles: [`CONTACT_PARTICLE_STEPS`], at least 1000
/// steps.
fn contact_steps(n: usize) -> u64 {
    (CONTACT_PARTICLE_STEPS / n as f64).round().max(1000.0) as u64
}

const CONTACT_PARTICLE_STEPS: f64 = 3e7;
/// Particle-steps per run of a paper-physics case, and its least number of steps.
const PAPER_PARTICLE_STEPS: f64 = 1e7;
const PAPER_MIN_STEPS: u64 = 100;
/// Particle-steps per contact run of the scaling study, and its least number of steps.
const SCALING_PARTICLE_STEPS: f64 = 1e7;
const SCALING_MIN_STEPS: u64 = 100;
/// Force evaluations times particles per dipole run of the scaling study, and its least number
/// of evaluations.
const SCALING_DIPOLE_EVALUATIONS: f64 = 2e6;
const SCALING_DIPOLE_MIN_STEPS: u64 = 20;
/// Particles of the dipole cases (the paper's box at [`DIPOLE_CONCENTRATION`]).
const DIPOLE_PARTICLES: usize = 307;
/// Concentrations (mg/ml) of the paper's scenes the cases are built on: the dipole cases, the
/// paper-physics scene, and the reference point of the MPI demonstration
/// (`experiments/paper/reference.toml`).
const DIPOLE_CONCENTRATION: f64 = 4.5;
const PAPER_CONCENTRATION: f64 = 2.25;
const MPI_CONCENTRATION: f64 = 0.563;
/// The files route's exchange interval in the MPI demonstration (steps).
const MPI_EXCHANGE_EVERY: u64 = 100;
/// Duration (s) of the native-deck comparison, and the steps of its bulk run.
const NATIVE_DURATION: f64 = 2e-3;
const NATIVE_BULK_STEPS: u64 = 200;
/// Aggregate gap tolerance of the last-frame statistics (fraction of the radius).
const GAP_TOLERANCE: f64 = 1e-3;

/// Turns, at least, of the contact cases that judge a target (the beds of 30 000 and the packed
/// bed of 3 000).
const TARGET_TURNS: usize = 9;

/// Passes (reads and writes) over arrays of three-vectors the velocity-Verlet kicks and drift
/// make per step: half kick and drift read and write x, v, ω and read F, T; the closing half
/// kick reads and writes v, ω and reads F, T.
const INTEGRATE_PASSES: usize = 14;

/// Contender names of the machine's own gains (kept out of the measurements).
const ARITHMETIC: &str = "arithmetic";
const TWO_RUNS: &str = "two runs at once";

/// Lanes of the arithmetic try (8 AVX2 registers: two fused multiply-adds per cycle keep a Zen 3
/// or Skylake core's floating-point pipes full), and its multiply-add rounds.
const ARITHMETIC_LANES: usize = 32;
const ARITHMETIC_ROUNDS: usize = 40_000_000;

/// The cases' parameters, for the report.
fn setup(max_particles: usize) -> Setup {
    Setup {
        dt_s: DT,
        diameter_um: DIAMETER * 1e6,
        youngs_modulus_pa: YOUNGS_MODULUS,
        restitution: RESTITUTION,
        friction: FRICTION,
        contact_particle_steps: CONTACT_PARTICLE_STEPS,
        packed_prestrain: PACKED_PRESTRAIN,
        loose_solid_fraction: solid_fraction(Packing::Loose),
        dilute_solid_fraction: solid_fraction(Packing::Dilute),
        dipole_concentration: DIPOLE_CONCENTRATION,
        dipole_box_um: magnetic_box(DIPOLE_PARTICLES).map(|x| x * 1e6),
        field_t: FIELD,
        cutoff_diameters: CUTOFF_DIAMETERS,
        paper_concentration: PAPER_CONCENTRATION,
        paper_chain: PAPER_CHAIN,
        paper_slow_every: PAPER_SLOW_EVERY,
        paper_particle_steps: PAPER_PARTICLE_STEPS,
        paper_min_steps: PAPER_MIN_STEPS,
        paper_cases: paper_variants(max_particles)
            .into_iter()
            .map(|(n, drag)| PaperCase { case: drag.case(n), particles: n, drag_every: drag.every() })
            .collect(),
        scaling_sizes: scaling_sizes(max_particles),
        scaling_particle_steps: SCALING_PARTICLE_STEPS,
        scaling_min_steps: SCALING_MIN_STEPS,
        scaling_dipole_evaluations: SCALING_DIPOLE_EVALUATIONS,
        scaling_dipole_min_steps: SCALING_DIPOLE_MIN_STEPS,
        mpi_concentration: MPI_CONCENTRATION,
        mpi_duration_ms: None,
        mpi_exchange_every: MPI_EXCHANGE_EVERY,
        native_duration_ms: NATIVE_DURATION * 1e3,
        native_bulk_steps: NATIVE_BULK_STEPS,
        gap_tolerance: GAP_TOLERANCE,
        arithmetic_lanes: ARITHMETIC_LANES,
        integrate_passes: INTEGRATE_PASSES,
    }
}

struct Bench<'a> {
    options: &'a Options,
    record: BenchRecord,
}

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

/// slow ÷ fast turn by turn: min, median and max, if both ran the same turns.
fn paired_speedup(fast: &[f64], slow: &[f64]) -> Option<Spread> {
    let ratios: Vec<f64> = slow.iter().zip(fast).map(|(s, f)| s / f).collect();
    (!ratios.is_empty() && fast.len() == slow.len()).then(|| Spread::of(&ratios))
}

impl<'a> Bench<'a> {
    /// Nothing measured yet.
    fn new(options: &'a Options) -> Self {
        let provenance = Provenance {
            magdem_version: env!("CARGO_PKG_VERSION").into(),
            commit: env!("MAGDEM_GIT_COMMIT").into(),
            date: None,
            machine: machine(),
            repeats: options.repeats,
            target_turns: TARGET_TURNS,
            work: options.work.display().to_string(),
        };
        let record = BenchRecord {
            provenance,
            setup: setup(options.max_particles),
            measurements: vec![],
            paired_speedups: vec![],
            profiles: vec![],
            bitwise: vec![],
            contacts: vec![],
            memory: vec![],
            dipole_pairs: vec![],
            force_agreement: vec![],
            engine_versions: vec![],
            mpi: vec![],
            native: vec![],
            native_bulk: vec![],
            ceilings: vec![],
            phases_on_both_cores: vec![],
            notes: vec![],
        };
        Bench { options, record }
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
                        self.record.notes.push(format!("{} on {case}: {e}", contender.engine));
                        contenders.remove(k);
                        continue;
                    }
                }
                k += 1;
            }
        }
        for (c, times) in contenders {
            self.record.measurements.push(Measurement {
                case: case.into(),
                engine: c.engine.into(),
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
        let shares = timers
            .phases()
            .iter()
            .map(|(n, d)| Share { phase: n.to_string(), fraction: d.as_secs_f64() / total })
            .collect();
        self.record.profiles.push(Profile { case: case.into(), shares });
        Ok(())
    }

    /// Bitwise equality of the one- and two-thread runs, and the contacts at the end of the first.
    fn ends(&mut self, case: &str, one: &MagdemRun, two: &MagdemRun) {
        let record = &mut self.record;
        record.bitwise.push(Bitwise { case: case.into(), equal: bitwise_equal(&one.simulation, &two.simulation) });
        let state = &one.simulation.state;
        let particles = state.particles.len() as f64;
        record.contacts.push(Contacts {
            case: case.into(),
            pairs_per_particle: state.history.pairs.len() as f64 / particles,
            walls_per_particle: state.history.walls.len() as f64 / particles,
        });
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
                for engine in [Engine::LIGGGHTS, Engine::LAMMPS] {
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
                // LIGGGHTS'.
                let targeted = timed || (packing == Packing::Packed && n == 3000);
                let turns = if targeted { self.options.repeats.max(TARGET_TURNS) } else { self.options.repeats };
                self.compare_in(turns, &case, scene.initial.len(), steps, contenders)?;
                if timed {
                    self.machine_gains(&case, &one, &two);
                }
                let (one, two) = (one.last.expect("one-thread runs"), two.last.expect("two-thread runs"));
                self.ends(&case, &one, &two);
                for engine in [Engine::LIGGGHTS, Engine::LAMMPS] {
                    self.record_version(&dir.join(engine.name()));
                }
                self.profile(&case, &scene, Work::Steps)?;
                progress.inc(1);
            }
        }
        Ok(())
    }

    /// Takes the machine's own contenders out of the measurements of `case` into its ceilings,
    /// and keeps the turn-by-turn two-thread gain and the phases of magdem's runs.
    fn machine_gains(&mut self, case: &str, one: &MagdemRuns, two: &MagdemRuns) {
        let (machine, others): (Vec<_>, _) = std::mem::take(&mut self.record.measurements)
            .into_iter()
            .partition(|m| m.case == case && [ARITHMETIC, TWO_RUNS].contains(&m.engine.as_str()));
        self.record.measurements = others;
        let on = |engine: &str, threads| {
            machine.iter().find(|m| m.engine == engine && m.threads == threads).map(|m| m.seconds.median)
        };
        let one_run = self.record.find(case, "magdem", 1).map(|m| m.seconds.median);
        if let (Some(a1), Some(a2), Some(pair), Some(alone)) =
            (on(ARITHMETIC, 1), on(ARITHMETIC, 2), on(TWO_RUNS, 2), one_run)
        {
            self.record.ceilings.push(Ceilings {
                case: case.into(),
                arithmetic_gain: a1 / a2,
                two_runs_gain: 2.0 * alone / pair,
            });
        }
        let (fast, slow) = (self.record.find(case, "magdem", 2), self.record.find(case, "magdem", 1));
        if let (Some(fast), Some(slow)) = (fast, slow) {
            if let Some(ratio) = paired_speedup(&fast.turns, &slow.turns) {
                let who = |m: &Measurement| Who { engine: m.engine.clone(), threads: m.threads };
                let paired = PairedSpeedup {
                    case: case.into(),
                    fast: who(fast),
                    slow: who(slow),
                    turns: slow.turns.len(),
                    ratio,
                };
                self.record.paired_speedups.push(paired);
            }
        }
        let phases: Vec<PhaseTimes> = one.phases[0]
            .iter()
            .map(|(name, _)| PhaseTimes {
                phase: name.to_string(),
                times: Times::new(one.median(name), two.median(name)),
            })
            .collect();
        let sum = |f: fn(&Times) -> f64| phases.iter().map(|p| f(&p.times)).sum::<f64>();
        let total = Times::new(sum(|t| t.one_thread_s), sum(|t| t.two_threads_s));
        self.record.phases_on_both_cores.push(PhasesOnBothCores { case: case.into(), phases, total });
    }

    fn record_version(&mut self, dir: &Path) {
        let log = std::fs::read_to_string(dir.join("log.bench")).unwrap_or_default();
        if let Some(first) = log.lines().next().filter(|l| l.starts_with("LIGGGHTS") || l.starts_with("LAMMPS")) {
            if !self.record.engine_versions.iter().any(|v| v == first) {
                self.record.engine_versions.push(first.to_string());
            }
        }
    }

    /// Dipole forces at case-1 parameters, all pairs and with the paper's cut-off.
    fn magnetic_cases(&mut self, progress: &indicatif::ProgressBar) -> Result<(), Error> {
        for (label, cutoff, steps) in [("all pairs", None, 2000), ("cut-off 15 d", Some(CUTOFF_DIAMETERS), 2000)] {
            let case = format!("dipole {label} {DIPOLE_PARTICLES}");
            progress.set_message(case.clone());
            let dir = self.options.work.join(format!("dipole-{}", label.replace(' ', "-")));
            let scene = scene_in(&dir, "scene", &magnetic_scene(DIPOLE_PARTICLES, cutoff, steps))?;
            let mut runs = MagdemRuns::default();
            let lammps_dir = dir.join("lammps");
            let mut contenders = vec![Contender::magdem(&scene, 1, Work::Forces, false, &mut runs)];
            contenders.extend(Contender::engine(Engine::LAMMPS, 1, || time_lammps_dipoles(&scene, &lammps_dir)));
            self.compare(&case, scene.initial.len(), steps, contenders)?;
            self.profile(&case, &scene, Work::Forces)?;
            if Engine::LAMMPS.available() {
                match dipole_check::check(&scene, &dir.join("force-check")) {
                    Ok(check) => self
                        .record
                        .force_agreement
                        .push(ForceAgreement { case: case.clone(), max_relative_error: check.max_relative_error }),
                    Err(e) => self.record.notes.push(format!("force check on {case}: {e}")),
                }
            }
            progress.inc(1);
        }
        Ok(())
    }

    /// The paper's physics ([`paper_scene`]) at 10³, 10⁴ and 10⁵ particles (up to the scaling
    /// study's largest), one and two threads; the phase shares at the middle size.
    fn paper_cases(&mut self, progress: &indicatif::ProgressBar) -> Result<(), Error> {
        for (n, drag) in paper_variants(self.options.max_particles) {
            let case = drag.case(n);
            progress.set_message(case.clone());
            let outer = PAPER_SLOW_EVERY;
            let steps =
                ((PAPER_PARTICLE_STEPS / outer as f64 / n as f64).round() as u64).max(PAPER_MIN_STEPS / outer) * outer;
            let dir = self.options.work.join(format!("paper-{n}-{}", drag.every()));
            let scene = scene_in(&dir, "scene", &paper_scene(n, steps, drag.every()))?;
            let one = self.magdem(&case, &scene, 1, Work::Steps)?;
            self.record.memory.push(Memory {
                case: case.clone(),
                particles: n,
                bytes_per_particle: one.memory as f64 / n as f64,
            });
            let two = self.magdem(&case, &scene, 2, Work::Steps)?;
            self.ends(&case, &one, &two);
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
                let steps = (SCALING_PARTICLE_STEPS / n as f64).round().max(SCALING_MIN_STEPS as f64) as u64;
                let scene = scene_in(&dir, &format!("contact-{}", packing.name()), &contact_scene(packing, n, steps))?;
                let case = format!("scaling contact {}", packing.name());
                let run = self.magdem(&case, &scene, 1, Work::Steps)?;
                self.record.memory.push(Memory {
                    case: case.clone(),
                    particles: n,
                    bytes_per_particle: run.memory as f64 / n as f64,
                });
                drop(run);
                if packing == Packing::Packed {
                    self.magdem(&case, &scene, 2, Work::Steps)?;
                }
            }
            let steps = (SCALING_DIPOLE_EVALUATIONS / n as f64).round().max(SCALING_DIPOLE_MIN_STEPS as f64) as u64;
            let scene = scene_in(&dir, "dipole-cutoff", &magnetic_scene(n, Some(CUTOFF_DIAMETERS), steps))?;
            let case = "scaling dipole cut-off 15 d".to_string();
            let mut pairs = vec![];
            let largest_d = scene.species.iter().map(|s| 2.0 * s.radius).fold(0.0, f64::max);
            crate::core::neighbours::CellList::default().pairs_within(
                &scene.initial.position,
                &scene.domain,
                Some(CUTOFF_DIAMETERS * largest_d),
                &mut pairs,
            );
            let partners_per_particle = 2.0 * pairs.len() as f64 / n as f64;
            self.record.dipole_pairs.push(DipolePairs { particles: n, partners_per_particle });
            drop(pairs);
            let run = self.magdem(&case, &scene, 1, Work::Forces)?;
            self.record.memory.push(Memory {
                case: case.clone(),
                particles: n,
                bytes_per_particle: run.memory as f64 / n as f64,
            });
            drop(run);
            self.magdem(&case, &scene, 2, Work::Forces)?;
            progress.inc(1);
        }
        Ok(())
    }

    /// The MPI demonstration: the case-1 reference point in LIGGGHTS and LAMMPS by the files
    /// route under `mpirun -np 1` and 2.
    fn mpi_demo(&mut self, progress: &indicatif::ProgressBar) -> Result<(), Error> {
        let experiment =
            crate::scene::experiment::Experiment::from_file(Path::new("experiments/paper/reference.toml"))?;
        let magdem = std::env::current_exe()?;
        for engine in [Engine::LIGGGHTS, Engine::LAMMPS] {
            let Some(point) = experiment.points.iter().find(|p| p.engine == engine.name()) else { continue };
            self.record.setup.mpi_duration_ms = Some(point.scene.spec.integration.end_time * 1e3);
            if !engine.available() || !mpirun_available() {
                self.record.notes.push(format!("MPI demonstration: {} or mpirun is not installed", engine.name()));
                continue;
            }
            let mut first: Option<ndarray::Array3<f64>> = None;
            for procs in [1, 2] {
                progress.set_message(format!("mpirun -np {procs} {}", engine.binary()));
                let dir = self.options.work.join(format!("mpi-{}-np{procs}", engine.name()));
                let output = dir.join("trajectory.h5");
                let coupling = deck::Coupling::Files { magdem: magdem.clone(), every: MPI_EXCHANGE_EVERY };
                let run =
                    crate::reference::run_binary(engine, &point.scene, &dir.join("deck"), &output, &coupling, procs)?;
                let positions = crate::io::trajectory::Trajectory::open(&output)?.all_vectors("position")?;
                let max_difference_m =
                    first.as_ref().map(|p1| (p1 - &positions).iter().fold(0.0_f64, |m, d| m.max(d.abs())));
                first.get_or_insert(positions);
                self.record.mpi.push(MpiRun {
                    engine: engine.name().into(),
                    route: Route::Files { every: MPI_EXCHANGE_EVERY },
                    procs,
                    wall_time_s: Some(run.wall_time.as_secs_f64()),
                    last_frame: last_frame(&output)?,
                    max_difference_m,
                });
            }
            // The same point with the forces every step (the experiment's own run, if made).
            let callback = experiment.output.join(format!("{}.h5", point.id));
            if callback.exists() {
                self.record.mpi.push(MpiRun {
                    engine: engine.name().into(),
                    route: Route::Callback,
                    procs: 1,
                    wall_time_s: None,
                    last_frame: last_frame(&callback)?,
                    max_difference_m: None,
                });
            }
        }
        progress.inc(1);
        Ok(())
    }

    /// The native LAMMPS deck (`magdem run --engine lammps --native --mpi N`): the fixed-moment
    /// case-1 scene at 2.25 mg/ml (`verify::magnetic::case1_fixed_moments`) in magdem and in
    /// LAMMPS' own `lj/cut/dipole/cut` on one and two processes, no magdem in LAMMPS' loop.
    fn native_demo(&mut self, progress: &indicatif::ProgressBar) -> Result<(), Error> {
        if !Engine::LAMMPS.available() || !mpirun_available() {
            self.record.notes.push("native LAMMPS deck: lmp or mpirun is not installed".into());
            return Ok(());
        }
        let dir = self.options.work.join("mpi-native");
        let scene = scene_in(&dir, "scene", &crate::verify::magnetic::case1_fixed_moments(NATIVE_DURATION, 1e-4)?)?;
        let particle_steps = scene.initial.len() as f64 * scene.total_steps() as f64;
        progress.set_message("native LAMMPS deck: magdem".to_string());
        let reference = dir.join("magdem.h5");
        let options = crate::run::RunOptions { overwrite: true, ..Default::default() };
        crate::run::run(&scene, &reference, &options)?;
        let x = crate::io::trajectory::Trajectory::open(&reference)?.all_vectors("position")?;
        let seconds = time_magdem(&scene, 1, Work::Steps, false)?.seconds;
        self.record.native.push(NativeRun {
            engine: "magdem".into(),
            procs: 1,
            last_frame: last_frame(&reference)?,
            to_magdem_m: None,
            ns_per_particle_step: Some(seconds / particle_steps * 1e9),
        });
        for procs in [1, 2] {
            progress.set_message(format!("native LAMMPS deck: mpirun -np {procs} lmp"));
            let output = dir.join(format!("lammps-np{procs}.h5"));
            let run = crate::reference::run_binary(
                Engine::LAMMPS,
                &scene,
                &dir.join(format!("np{procs}")),
                &output,
                &deck::Coupling::Native,
                procs,
            )?;
            let y = crate::io::trajectory::Trajectory::open(&output)?.all_vectors("position")?;
            let log = std::fs::read_to_string(&run.log).unwrap_or_default();
            self.record.native.push(NativeRun {
                engine: "lammps".into(),
                procs,
                last_frame: last_frame(&output)?,
                to_magdem_m: Some((&x - &y).iter().fold(0.0_f64, |m, d| m.max(d.abs()))),
                ns_per_particle_step: loop_time(&log).map(|t| t / particle_steps * 1e9),
            });
        }
        // Cost in bulk: the paper's box walls cut the 15-diameter neighbourhood of most particles;
        // the 100x box (33 675 particles, periodic sides) holds the bulk's partners.
        progress.set_message("native LAMMPS deck: cost in bulk".to_string());
        let end = NATIVE_BULK_STEPS as f64 * DT;
        let text = crate::verify::magnetic::case1_fixed_moments(end, end)?;
        let paper_box = "hi = [4.840000e-04, 4.840000e-04, 4.840000e-04]";
        let x100 =
            "hi = [2.24653e-3, 2.24653e-3, 2.24653e-3]\nboundary = { x = \"periodic\", y = \"periodic\", z = \"wall\" }";
        let bulk_dir = dir.join("bulk");
        let bulk = scene_in(&bulk_dir, "scene", &text.replacen(paper_box, x100, 1))?;
        let (particles, particle_steps) = (bulk.initial.len(), bulk.initial.len() as f64 * bulk.total_steps() as f64);
        for threads in [1, 2] {
            let seconds = time_magdem(&bulk, threads, Work::Steps, false)?.seconds;
            let ns_per_particle_step = seconds / particle_steps * 1e9;
            self.record.native_bulk.push(NativeBulk {
                engine: "magdem".into(),
                threads,
                particles,
                ns_per_particle_step,
            });
        }
        for procs in [1, 2] {
            let deck_dir = bulk_dir.join(format!("np{procs}"));
            let written = deck::write_with(Engine::LAMMPS, &bulk, &deck_dir, &deck::Coupling::Native)?;
            let seconds = time_engine(Engine::LAMMPS, &deck_dir, &written.input.to_string_lossy(), procs)?;
            let ns_per_particle_step = seconds / particle_steps * 1e9;
            self.record.native_bulk.push(NativeBulk {
                engine: "lammps".into(),
                threads: procs,
                particles,
                ns_per_particle_step,
            });
        }
        progress.inc(1);
        Ok(())
    }
}

/// Statistics of a trajectory's last frame (gap tolerance [`GAP_TOLERANCE`]).
fn last_frame(path: &Path) -> Result<LastFrame, Error> {
    let trajectory = crate::io::trajectory::Trajectory::open(path)?;
    let (_, aggregates) =
        crate::analysis::trajectory::frame_aggregates(&trajectory, -1, GAP_TOLERANCE).map_err(|e| e.to_string())?;
    let lengths: Vec<f64> = crate::analysis::aggregates::finite_lengths(&aggregates).iter().map(|l| l * 1e6).collect();
    let mean = lengths.iter().sum::<f64>() / lengths.len() as f64;
    let std = (lengths.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lengths.len() as f64).sqrt();
    let velocity = trajectory.all_vectors("velocity")?;
    let last = velocity.index_axis(ndarray::Axis(0), velocity.shape()[0] - 1);
    Ok(LastFrame {
        aggregates: aggregates.len(),
        mean_length_um: mean,
        std_length_um: std,
        largest: aggregates.iter().map(|a| a.members.len()).max().unwrap_or(0),
        fastest_m_per_s: Some(last.rows().into_iter().map(|v| v.dot(&v).sqrt()).fold(0.0, f64::max)),
    })
}

/// Seconds of one arithmetic try: [`ARITHMETIC_ROUNDS`] rounds of `a = a·m + c` on
/// [`ARITHMETIC_LANES`] lanes held in registers, shared out among `threads` threads; no memory
/// traffic, so it measures whether the cores deliver their arithmetic.
fn arithmetic_seconds(threads: usize) -> f64 {
    let started = Instant::now();
    std::thread::scope(|scope| {
        for t in 0..threads {
            scope.spawn(move || {
                let mut lanes: [f64; ARITHMETIC_LANES] = std::array::from_fn(|k| (k + t) as f64);
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
    /// Once per r-RESPA outer step, applied to each step's velocities.
    Held,
}

impl PaperDrag {
    const ALL: [PaperDrag; 2] = [PaperDrag::EveryStep, PaperDrag::Held];

    fn every(self) -> u64 {
        match self {
            PaperDrag::EveryStep => 1,
            PaperDrag::Held => PAPER_SLOW_EVERY,
        }
    }

    /// The case name: the size last, the drag before it.
    fn case(self, n: usize) -> String {
        match self {
            PaperDrag::EveryStep => format!("paper physics {n}"),
            PaperDrag::Held => format!("paper physics, drag held, {n}"),
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

/// What this machine is (CPU model, vector extensions, cores, caches, memory, kernel).
fn machine() -> Machine {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let cpu = cpuinfo
        .lines()
        .find_map(|l| l.strip_prefix("model name"))
        .map(|s| s.trim_start_matches([' ', '\t', ':']).to_string())
        .unwrap_or("unknown CPU".into());
    let flags = cpuinfo.lines().find_map(|l| l.strip_prefix("flags")).unwrap_or("");
    let simd = ["avx512f", "avx2", "fma"]
        .into_iter()
        .filter(|f| flags.split_whitespace().any(|x| x == *f))
        .map(String::from)
        .collect();
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let memory_kb: f64 = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemTotal:"))
        .and_then(|s| s.split_whitespace().next()?.parse().ok())
        .unwrap_or(0.0);
    let kernel = std::fs::read_to_string("/proc/sys/kernel/osrelease").unwrap_or_default();
    Machine {
        cpu,
        simd,
        cores: std::thread::available_parallelism().map_or(0, |n| n.get()),
        caches: caches(),
        memory_gib: memory_kb / 1024.0 / 1024.0,
        kernel: kernel.trim().to_string(),
    }
}

/// The first core's data and unified caches, as Linux lists them ("L1d 32K", "L2 512K",
/// "L3 32768K shared by 2 cores").
fn caches() -> Vec<String> {
    let read = |index: usize, name: &str| {
        std::fs::read_to_string(format!("/sys/devices/system/cpu/cpu0/cache/index{index}/{name}"))
            .ok()
            .map(|s| s.trim().to_string())
    };
    (0..8)
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
        .collect()
}

/// Today's UTC date, YYYY-MM-DD.
fn today() -> Option<String> {
    let seconds = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).ok()?.as_secs();
    Some(civil_date(seconds as i64 / 86_400))
}

/// The proleptic Gregorian date `days` after 1970-01-01 (Hinnant's `civil_from_days`).
fn civil_date(days: i64) -> String {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// Runs every measurement and saves the record (`performance.json`, `performance.csv`) in
/// `options.out`.
pub fn run(options: &Options) -> Result<BenchRecord, Error> {
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
    bench.magnetic_cases(&progress)?;
    bench.paper_cases(&progress)?;
    bench.scaling(&progress)?;
    if options.mpi {
        bench.mpi_demo(&progress)?;
        bench.native_demo(&progress)?;
    }
    progress.finish_and_clear();
    let mut record = bench.record;
    record.provenance.date = today();
    record.save(&options.out)?;
    Ok(record)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A speed-up taken turn by turn pairs each turn's runs: a machine that slows down between
    /// turns (here by 2×) moves the ratio of the medians, not the turns' ratios.
    #[test]
    fn a_paired_speedup_takes_each_turns_ratio() {
        let (one, two) = ([6.0, 12.0, 12.0], [3.0, 3.0, 6.0]);
        let paired = paired_speedup(&two, &one).unwrap();
        assert_eq!((paired.min, paired.median, paired.max), (2.0, 2.0, 4.0));
        assert_eq!(Spread::of(&one).median / Spread::of(&two).median, 4.0);
        assert!(paired_speedup(&two, &one[..2]).is_none());
        assert!(paired_speedup(&[], &[]).is_none());
    }

    /// The civil date of a day count: the epoch, a leap day and the day after it.
    #[test]
    fn days_count_into_the_civil_calendar() {
        assert_eq!(civil_date(0), "1970-01-01");
        assert_eq!(civil_date(11_016), "2000-02-29");
        assert_eq!(civil_date(11_017), "2000-03-01");
    }

    /// The setup names what the scenes hold: the random packings' solid fractions and the dipole
    /// box of 307 particles.
    #[test]
    fn the_setup_matches_the_scenes() {
        let s = setup(300_000);
        assert!((s.loose_solid_fraction - 0.209).abs() < 1e-3 && (s.dilute_solid_fraction - 0.00167).abs() < 1e-5);
        assert_eq!(s.dipole_box_um.map(|x| x.round()), [396.0, 396.0, 330.0]);
        assert_eq!(s.paper_cases.len(), 6);
        assert_eq!(s.scaling_sizes.last(), Some(&300_000));
    }
}
