//! `magdem` command line: run, validate and inspect scenes and trajectories.

use clap::{Parser, Subcommand};
use magdem::io::trajectory::Trajectory;
use magdem::reference::{self, Engine as ReferenceEngine};
use magdem::run::{run, RunFailure, RunOptions, INTERRUPTED};
use magdem::scene::Scene;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The system allocator, counting heap bytes only for `magdem bench`'s memory per particle.
#[global_allocator]
static GLOBAL: magdem::bench::SwitchableCounter = magdem::bench::SwitchableCounter;

/// Magnetic particle DEM research harness.
#[derive(Parser)]
#[command(name = "magdem", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum EngineChoice {
    Magdem,
    Liggghts,
    Lammps,
}

#[derive(Subcommand)]
enum SolverStudy {
    /// Error against dt and against run time per integrator on problems with known answers; writes reports/accuracy/.
    Accuracy {
        #[arg(long, default_value = "reports/accuracy")]
        report: PathBuf,
    },
    /// Largest stable dt against Young's modulus and field per integrator (measured and
    /// estimated), stiff and extreme cases, dipole cut-off error; writes reports/accuracy/stability.md.
    Stability {
        #[arg(long, default_value = "reports/accuracy")]
        report: PathBuf,
    },
}

#[derive(Subcommand)]
enum Study {
    /// Chung & Ooi single-contact benchmarks in magdem, LIGGGHTS and LAMMPS; writes the report.
    Contacts {
        /// Report directory.
        #[arg(long, default_value = "reports")]
        report: PathBuf,
        /// Directory for the runs' trajectories and decks.
        #[arg(long, default_value = "runs/verify-contacts")]
        work: PathBuf,
    },
    /// Magnetic scenes in lock step (two-particle approach, case 1 at 4.5 mg/ml); writes the report.
    Magnetic {
        #[arg(long, default_value = "reports")]
        report: PathBuf,
        #[arg(long, default_value = "runs/verify-magnetic")]
        work: PathBuf,
        /// Simulated time of the case-1 comparison (s).
        #[arg(long, default_value_t = 2.0e-4)]
        case1_time: f64,
    },
}

#[derive(Subcommand)]
enum Report {
    /// The paper-reproduction report (Tables 2–4, box plots, approach, sensitivity, walls and
    /// particle count, reference engines) from the runs of experiments/paper/*.toml.
    Paper {
        /// Directory of the experiment files (its opt-in/ folder is read too).
        #[arg(long, default_value = "experiments/paper")]
        experiments: PathBuf,
        /// Directory of the paper's tables (CSV).
        #[arg(long, default_value = "reference/paper")]
        reference: PathBuf,
        /// Report directory.
        #[arg(long, default_value = "reports/paper")]
        out: PathBuf,
        /// Aggregate gap tolerance, as a fraction of the smaller radius.
        #[arg(long, default_value_t = 1e-3)]
        gap: f64,
        /// Wall time of the run that produced the trajectories (s), quoted in the report.
        #[arg(long)]
        wall_time: Option<f64>,
    },
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write its trajectory (HDF5).
    Run {
        /// Scene file (TOML).
        scene: PathBuf,
        /// Output trajectory file.
        #[arg(short, long, default_value = "runs/out.h5")]
        output: PathBuf,
        /// Solver: magdem's own, or a reference code run from a generated deck.
        #[arg(long, value_enum, default_value_t = EngineChoice::Magdem)]
        engine: EngineChoice,
        /// Reference codes, magnetic scenes: pass magdem's forces by file exchange every K steps
        /// through the engine's binary (no shared library needed; lags up to K steps) instead of
        /// the in-process callback every step.
        #[arg(long, value_name = "K")]
        exchange_every: Option<u64>,
        /// Reference codes: run the engine's binary under `mpirun -np N` (magnetic scenes need
        /// the files route, --exchange-every).
        #[arg(long, value_name = "N", default_value_t = 1)]
        mpi: usize,
        /// Continue an interrupted run from the output file's checkpoint.
        #[arg(long)]
        resume: bool,
        /// Replace an existing output file (without it an existing file is refused).
        #[arg(long, conflicts_with = "resume")]
        overwrite: bool,
        /// Print wall time per step phase at the end.
        #[arg(long)]
        timings: bool,
        /// No progress bar.
        #[arg(short, long)]
        quiet: bool,
        /// Testing aid: abort without clean-up right after writing frame K.
        #[arg(long, hide = true)]
        abort_after_frame: Option<usize>,
    },
    /// Write the scene as a LIGGGHTS or LAMMPS input deck (in.scene + data.scene).
    Deck {
        scene: PathBuf,
        #[arg(long, value_enum)]
        engine: ReferenceEngine,
        /// Directory for the deck.
        #[arg(short, long)]
        output: PathBuf,
    },
    /// Numerical studies of the solver: accuracy (error against dt and run time), stability.
    Study {
        #[command(subcommand)]
        study: SolverStudy,
    },
    /// Cross-verification studies against the reference codes.
    Verify {
        #[command(subcommand)]
        study: Study,
    },
    /// Files route of the reference codes: compute magnetic forces for a positions dump.
    #[command(hide = true)]
    MagneticForces { scene: PathBuf, positions: PathBuf, prefix: PathBuf },
    /// Check a scene without running it: prints its particles, terms and step estimates.
    Validate {
        scene: PathBuf,
    },
    /// Aggregates of a trajectory frame: sizes, lengths (mean, population and sample std),
    /// orientation, and how the result depends on the contact gap tolerance.
    Analyse {
        file: PathBuf,
        /// Frame index (negative counts from the end).
        #[arg(long, default_value_t = -1, allow_hyphen_values = true)]
        frame: isize,
        /// Largest gap, as a fraction of the smaller radius, at which two particles count as touching.
        #[arg(long, default_value_t = 1e-3)]
        gap: f64,
        /// One CSV line (with `--header`, the column names first) instead of the report.
        #[arg(long)]
        csv: bool,
        #[arg(long, requires = "csv")]
        header: bool,
    },
    /// Run every point of one or more experiment files (sweeps over scene parameters), in
    /// parallel, the longest runs first.
    Experiment {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Runs at once (default: the number of cores).
        #[arg(short, long)]
        jobs: Option<usize>,
        /// Replace finished runs whose scene changed (otherwise they are kept and reported).
        #[arg(long)]
        overwrite_changed: bool,
        /// List the points (id, particles, steps, engine) and check their scenes; run nothing.
        #[arg(long)]
        dry_run: bool,
        #[arg(short, long)]
        quiet: bool,
    },
    /// Write a report from experiment runs.
    #[command(subcommand)]
    Report(Report),
    /// Describe a trajectory file.
    Info {
        file: PathBuf,
    },
    /// Export trajectories for ParaView (an XDMF sidecar beside each file, referencing its HDF5
    /// datasets in place) or OVITO and LAMMPS' tools (a LAMMPS text dump of every frame).
    Export {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        #[arg(long, value_enum, default_value = "xdmf")]
        format: ExportFormat,
        /// Dump file (lammps-dump, one trajectory; default FILE.dump beside it).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Time magdem against LIGGGHTS and LAMMPS on the same scenes (contact only at 300–30 000
    /// particles, dipole forces at case-1 parameters), the cost per particle against N and the
    /// second thread; writes reports/performance.md (about 10 minutes with the default repeats).
    Bench {
        /// Report directory.
        #[arg(long, default_value = "reports")]
        out: PathBuf,
        /// Directory for the scenes, decks and engine logs.
        #[arg(long, default_value = "runs/bench")]
        work: PathBuf,
        /// Runs per measurement (the report gives min, median and max).
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Largest particle count of the scaling study.
        #[arg(long, default_value_t = 100_000)]
        max_particles: usize,
        /// Skip the MPI demonstration (LIGGGHTS and LAMMPS by the files route under
        /// `mpirun -np 1` and `-np 2`, about 5 minutes).
        #[arg(long)]
        no_mpi: bool,
    },
}

/// `magdem export --format`.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum ExportFormat {
    /// An XDMF sidecar (FILE.xdmf) for ParaView.
    Xdmf,
    /// A LAMMPS text dump for OVITO: id type x y z vx vy vz radius mux muy muz.
    LammpsDump,
}

fn load(scene: &Path) -> Result<Scene, ExitCode> {
    Scene::from_file(scene).map_err(|e| {
        eprintln!("error: {e}");
        ExitCode::from(2)
    })
}

fn describe(scene: &Scene) {
    let s = &scene.spec;
    println!("scene {} ({})", s.name.as_deref().unwrap_or("unnamed"), &scene.hash[..12]);
    println!("  particles: {}  box: {:?} .. {:?}", scene.initial.len(), s.domain.lo, s.domain.hi);
    let f = &s.forces;
    let terms: Vec<&str> = [
        ("contact", f.contact.is_some()),
        ("dipole", f.dipole.is_some()),
        ("gradient", f.gradient.is_some()),
        ("drag", f.drag.is_some()),
        ("gravity", f.gravity.is_some()),
    ]
    .iter()
    .filter(|t| t.1)
    .map(|t| t.0)
    .collect();
    println!("  terms: {}", terms.join(", "));
    println!(
        "  integrator {}: {} steps, a frame every {} steps",
        s.integration.scheme,
        scene.total_steps(),
        scene.steps_per_frame()
    );
    println!("  {}", scene.estimate.summary(scene.dt()));
    for w in &scene.warnings {
        println!("  warning: {w}");
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Validate { scene } => {
            let scene = match load(&scene) {
                Ok(s) => s,
                Err(code) => return code,
            };
            describe(&scene);
            ExitCode::SUCCESS
        }
        Command::Deck { scene, engine, output } => {
            let scene = match load(&scene) {
                Ok(s) => s,
                Err(code) => return code,
            };
            match reference::deck::write(engine, &scene, &output) {
                Ok(deck) => {
                    println!("wrote {}, its fix.* include files and {} in {}", deck.input.display(), deck.data.display(), output.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Command::Run { scene, output, engine, exchange_every, mpi, resume, overwrite, timings, quiet, abort_after_frame } => {
            let scene = match load(&scene) {
                Ok(s) => s,
                Err(code) => return code,
            };
            let reference_engine = match engine {
                EngineChoice::Magdem => None,
                EngineChoice::Liggghts => Some(ReferenceEngine::Liggghts),
                EngineChoice::Lammps => Some(ReferenceEngine::Lammps),
            };
            if let Some(engine) = reference_engine {
                let dir = output.with_extension(format!("{}.deck", engine.name()));
                let result = match exchange_every {
                    Some(every) => {
                        let magdem = std::env::current_exe().unwrap_or_else(|_| PathBuf::from("magdem"));
                        reference::run_binary(engine, &scene, &dir, &output, &reference::deck::Coupling::Files { magdem, every }, mpi)
                    }
                    None if mpi > 1 && scene.magnetic_force_field().is_some() => {
                        eprintln!("error: --mpi {mpi}: magnetic forces reach MPI processes only by the files route; add --exchange-every K");
                        return ExitCode::from(2);
                    }
                    None if mpi > 1 => reference::run_binary(engine, &scene, &dir, &output, &reference::deck::Coupling::Callback, mpi),
                    None => reference::run(engine, &scene, &dir, &output),
                };
                return match result {
                    Ok(r) => {
                        println!("{}: {} frames from {} in {:.2} s (deck and dump in {}, log {})", output.display(), r.frames, engine.name(), r.wall_time.as_secs_f64(), dir.display(), r.log.display());
                        ExitCode::SUCCESS
                    }
                    Err(e) => {
                        eprintln!("error: {e}");
                        match e {
                            reference::ReferenceError::Unsupported { .. } | reference::ReferenceError::NotInstalled { .. } => ExitCode::from(2),
                            _ => ExitCode::from(1),
                        }
                    }
                };
            }
            for w in &scene.warnings {
                eprintln!("warning: {w}");
            }
            if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
                if let Err(e) = std::fs::create_dir_all(dir) {
                    eprintln!("error: cannot create {}: {e}", dir.display());
                    return ExitCode::from(2);
                }
            }
            let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed));
            let options = RunOptions { resume, overwrite, progress: !quiet, timings, abort_after_frame };
            match run(&scene, &output, &options) {
                Ok(summary) => {
                    if summary.already_complete {
                        println!("{} is already complete ({} frames); nothing to do", output.display(), summary.frames);
                    } else {
                        let secs = summary.wall_time.as_secs_f64();
                        println!(
                            "{}: {} steps, {} frames in {:.2} s ({:.0} steps/s)",
                            output.display(),
                            summary.steps,
                            summary.frames,
                            secs,
                            summary.steps as f64 / secs.max(1e-9)
                        );
                    }
                    if timings {
                        let total: f64 = summary.simulation.timers().phases().iter().map(|p| p.1.as_secs_f64()).sum();
                        println!("phase timings:");
                        for (name, d) in summary.simulation.timers().phases() {
                            println!("  {name:<12} {:>9.3} s  {:>5.1}%", d.as_secs_f64(), 100.0 * d.as_secs_f64() / total.max(1e-12));
                        }
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    match e {
                        RunFailure::Interrupted { .. } => ExitCode::from(130),
                        RunFailure::Unstable(_) => ExitCode::from(3),
                        RunFailure::Trajectory(_) => ExitCode::from(1),
                        RunFailure::Refused(_) => ExitCode::from(2),
                        RunFailure::DiskFull { .. } => ExitCode::from(1),
                    }
                }
            }
        }
        Command::Verify { study: Study::Contacts { report, work } } => {
            let engines: Vec<ReferenceEngine> = [ReferenceEngine::Liggghts, ReferenceEngine::Lammps].into_iter().filter(|e| e.available()).collect();
            if engines.len() < 2 {
                eprintln!("note: reference engines missing ({}); their columns stay empty. `make setup` installs them.", [ReferenceEngine::Liggghts, ReferenceEngine::Lammps].iter().filter(|e| !e.available()).map(|e| e.name()).collect::<Vec<_>>().join(", "));
            }
            match magdem::verify::contacts::verify(&report, &work, &engines) {
                Ok(r) => {
                    println!(
                        "wrote {} and {} figures; largest difference to LIGGGHTS: {:.4}% normal, {:.4}% tangential",
                        report.join("contact-verification.md").display(),
                        r.figures.len(),
                        100.0 * r.worst_normal,
                        100.0 * r.worst_tangential
                    );
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Verify { study: Study::Magnetic { report, work, case1_time } } => {
            let engines: Vec<ReferenceEngine> = [ReferenceEngine::Liggghts, ReferenceEngine::Lammps]
                .into_iter()
                .filter(|e| match reference::library::available(*e) {
                    Ok(()) => true,
                    Err(why) => {
                        eprintln!("note: {} skipped: {why}", e.name());
                        false
                    }
                })
                .collect();
            let magdem = std::env::current_exe().unwrap_or_else(|_| PathBuf::from("magdem"));
            match magdem::verify::magnetic::verify(&report, &work, &engines, case1_time, &magdem) {
                Ok(_) => {
                    println!("wrote {}", report.join("magnetic-verification.md").display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::MagneticForces { scene, positions, prefix } => {
            let scene = match load(&scene) {
                Ok(s) => s,
                Err(code) => return code,
            };
            match reference::files_route::magnetic_forces(&scene, &positions, &prefix) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Experiment { files, jobs, overwrite_changed, dry_run, quiet } => {
            let mut experiments = vec![];
            for file in &files {
                match magdem::scene::experiment::Experiment::from_file(file) {
                    Ok(e) => experiments.push(e),
                    Err(e) => {
                        eprintln!("error: {}: {e}", file.display());
                        return ExitCode::from(2);
                    }
                }
            }
            if dry_run {
                for e in &experiments {
                    for p in &e.points {
                        println!("{}/{}.h5  {} particles  {} steps  {}", e.output.display(), p.id, p.scene.initial.len(), p.scene.total_steps(), p.engine);
                        for w in &p.scene.warnings {
                            println!("  warning: {w}");
                        }
                    }
                }
                return ExitCode::SUCCESS;
            }
            let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed));
            let options = magdem::experiment::ExperimentOptions { jobs, overwrite_changed, progress: !quiet };
            match magdem::experiment::run_experiments(&experiments, &options) {
                Ok(all) => {
                    use magdem::experiment::Outcome;
                    let mut failed = false;
                    for (experiment, results) in experiments.iter().zip(&all) {
                        for r in results {
                            match &r.outcome {
                                Outcome::Failed(_) | Outcome::KeptChanged { .. } | Outcome::Interrupted => {
                                    failed = true;
                                    eprintln!("{}: {}", r.id, r.outcome.label());
                                }
                                Outcome::Unstable(_) => eprintln!("{}: {}", r.id, r.outcome.label()),
                                _ => {}
                            }
                        }
                        println!("{}: {} runs in {} (manifest.csv)", experiment.spec.name, results.len(), experiment.output.display());
                    }
                    if failed { ExitCode::from(1) } else { ExitCode::SUCCESS }
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Analyse { file, frame, gap, csv, header } => match analyse(&file, frame, gap, csv, header) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {}: {e}", file.display());
                ExitCode::from(2)
            }
        },
        Command::Study { study } => {
            let (result, written) = match study {
                SolverStudy::Accuracy { report } => (magdem::study::accuracy::study(&report), report.join("README.md")),
                SolverStudy::Stability { report } => (magdem::study::stability::study(&report), report.join("stability.md")),
            };
            match result {
                Ok(_) => {
                    println!("wrote {}", written.display());
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Report(Report::Paper { experiments, reference, out, gap, wall_time }) => {
            let options = magdem::report::paper::PaperReportOptions { experiments, reference, out, gap, wall_time };
            report_written(magdem::report::paper::write_report(&options))
        }
        Command::Bench { out, work, repeats, max_particles, no_mpi } => {
            let options = magdem::bench::Options { out, work, repeats: repeats.max(1), max_particles, mpi: !no_mpi };
            report_written(magdem::bench::report::write(&options))
        }
        Command::Export { files, format, output } => {
            if output.is_some() && files.len() > 1 {
                eprintln!("error: --output names one file; {} trajectories given", files.len());
                return ExitCode::from(2);
            }
            for file in &files {
                let written = match format {
                    ExportFormat::Xdmf => magdem::io::export::write_xdmf(file),
                    ExportFormat::LammpsDump => {
                        let out = output.clone().unwrap_or_else(|| magdem::io::export::beside(file, "dump"));
                        magdem::io::export::write_lammps_dump(file, &out).map(|_| out)
                    }
                };
                match written {
                    Ok(out) => println!("{}: wrote {}", file.display(), out.display()),
                    Err(e) => {
                        eprintln!("error: {}: {}", file.display(), e.to_string().split_whitespace().collect::<Vec<_>>().join(" "));
                        return ExitCode::from(2);
                    }
                }
            }
            ExitCode::SUCCESS
        }
        Command::Info { file } => match info(&file) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {}: {e}", file.display());
                ExitCode::from(2)
            }
        },
    }
}

/// Exit status of a command that writes a report: its path on success, the error otherwise.
fn report_written<E: std::fmt::Display>(result: Result<PathBuf, E>) -> ExitCode {
    match result {
        Ok(path) => {
            println!("wrote {}", path.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}

fn analyse(path: &Path, frame: isize, gap: f64, csv: bool, header: bool) -> Result<(), Box<dyn std::error::Error>> {
    use magdem::analysis::{aggregates::finite_lengths, stats::summary, trajectory::FrameReader};
    let t = Trajectory::open(path)?;
    let reader = FrameReader::new(&t)?;
    let (time, aggs) = reader.aggregates(frame, gap)?;
    let lengths: Vec<f64> = finite_lengths(&aggs).iter().map(|l| l * 1e6).collect();
    let s = summary(&lengths);
    let box_extent = reader.box_extent();
    let capped = aggs.iter().filter(|a| a.box_limited(box_extent)).count();
    let percolating = aggs.iter().filter(|a| a.percolating).count();
    if csv {
        let sizes = summary(&aggs.iter().map(|a| a.size() as f64).collect::<Vec<_>>());
        let vx = summary(&aggs.iter().map(|a| a.com_velocity.x * 1e6).collect::<Vec<_>>());
        if header {
            println!(
                "file,time_s,aggregates,particles,mean_length_um,pop_std_length_um,sample_std_length_um,mean_size,pop_std_size,\
                 mean_vx_um_s,pop_std_vx_um_s,box_limited_fraction,percolating"
            );
        }
        println!(
            "{},{time:e},{},{},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.4},{percolating}",
            path.display(),
            aggs.len(),
            aggs.iter().map(|a| a.size()).sum::<usize>(),
            s.mean,
            s.population_std,
            s.sample_std,
            sizes.mean,
            sizes.population_std,
            vx.mean,
            vx.population_std,
            capped as f64 / aggs.len() as f64
        );
        return Ok(());
    }
    println!("t = {time:e} s: {} aggregates of {} particles (gap tolerance {gap:e} of the smaller radius)", aggs.len(), aggs.iter().map(|a| a.size()).sum::<usize>());
    println!("length (µm): mean {:.2}, population std {:.2}, sample std {:.2}", s.mean, s.population_std, s.sample_std);
    println!(
        "box-limited: {capped} of {} aggregates ({:.1} %) reach {:.0} % of the box's {:.1} µm along the field or percolate; \
         {percolating} percolate through a periodic face (no finite length, left out of the mean)",
        aggs.len(),
        100.0 * capped as f64 / aggs.len() as f64,
        100.0 * magdem::analysis::aggregates::BOX_LIMITED_FRACTION,
        box_extent * 1e6
    );
    let chains: Vec<f64> = aggs.iter().filter(|a| a.size() > 1).map(|a| a.orientation_deg).collect();
    if !chains.is_empty() {
        println!("orientation to the field (aggregates of 2+): mean {:.1}°", summary(&chains).mean);
    }
    let mut histogram = std::collections::BTreeMap::new();
    for a in &aggs {
        *histogram.entry(a.size()).or_insert(0) += 1;
    }
    println!("size: count  {}", histogram.iter().map(|(k, v)| format!("{k}:{v}")).collect::<Vec<_>>().join("  "));
    print!("gap tolerance sensitivity (mean length µm):");
    for g in [1e-4, 1e-3, 1e-2, 5e-2] {
        let (_, a) = reader.aggregates(frame, g)?;
        print!("  {g:e}: {:.2}", summary(&finite_lengths(&a)).mean * 1e6);
    }
    println!();
    Ok(())
}

fn info(path: &Path) -> Result<(), Box<dyn std::error::Error>> {
    let t = Trajectory::open(path)?;
    for key in ["format", "magdem_version", "git_commit", "engine", "integrator", "scene_name", "scene_sha256", "status", "status_message", "units"] {
        println!("{key:<16} {}", t.attr_string(key)?);
    }
    println!("{:<16} {}", "particles", t.attr::<u64>("n_particles")?);
    println!("{:<16} {:e} s", "dt", t.attr::<f64>("dt")?);
    let times = t.times()?;
    println!(
        "{:<16} {} ({} to {} s)",
        "frames",
        times.len(),
        times.first().map_or("-".into(), |v| format!("{v:e}")),
        times.last().map_or("-".into(), |v| format!("{v:e}"))
    );
    let (state, frames) = t.checkpoint()?;
    println!("{:<16} step {} (t = {:e} s) after frame {}, {} contacts", "checkpoint", state.step, state.time, frames, state.contacts.pairs.len());
    Ok(())
}
