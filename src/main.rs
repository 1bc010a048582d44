//! `magdem` command line: run, validate and inspect scenes and trajectories.

mod cli;

use clap::{Parser, Subcommand};
use cli::run::EngineChoice;
use cli::trajectory::ExportFormat;
use magdem::reference::Engine as ReferenceEngine;
use magdem::run::RunOptions;
use std::path::PathBuf;
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
        /// The hydrodynamics study's experiment files (case 2's twenty-seed ensemble).
        #[arg(long, default_value = "experiments/hydrodynamics")]
        hydrodynamics_experiments: PathBuf,
        /// The hydrodynamics report directory, whose digests/ hold that study's runs.
        #[arg(long, default_value = "reports/hydrodynamics")]
        hydrodynamics: PathBuf,
    },
    /// The paper's shielded-area drag against Stokes flow with hydrodynamic interactions (RPY):
    /// chain drag, the mobility's cost and refactorisation error (computed here, about three
    /// minutes), and case 2 under each drag model from the runs of experiments/hydrodynamics/*.toml.
    Hydrodynamics {
        /// Directory of the experiment files (its opt-in/ folder is read too).
        #[arg(long, default_value = "experiments/hydrodynamics")]
        experiments: PathBuf,
        /// The case-2 scene of the refactorisation study.
        #[arg(long, default_value = "experiments/scenes/case2.toml")]
        case2_scene: PathBuf,
        /// The paper's tables (table2_case2.csv, whose first row is the experiment, and
        /// table3_case1_lengths.csv).
        #[arg(long, default_value = "reference/paper")]
        reference: PathBuf,
        /// Report directory.
        #[arg(long, default_value = "reports/hydrodynamics")]
        out: PathBuf,
        /// Aggregate gap tolerance, as a fraction of the smaller radius.
        #[arg(long, default_value_t = 1e-3)]
        gap: f64,
    },
    /// Bring the finished runs on this machine into a report's digests (reports/REPORT/digests/)
    /// without rewriting the report: an ensemble run in parts on several machines is written up
    /// once all of it is digested.
    Digests {
        #[arg(value_enum)]
        report: DigestedReport,
        /// Aggregate gap tolerance, as a fraction of the smaller radius (the report's).
        #[arg(long, default_value_t = 1e-3)]
        gap: f64,
    },
}

/// The reports that keep digests, with their experiment and report directories.
#[derive(Clone, Copy, clap::ValueEnum)]
enum DigestedReport {
    /// experiments/paper → reports/paper/digests
    Paper,
    /// experiments/hydrodynamics → reports/hydrodynamics/digests
    Hydrodynamics,
}

impl DigestedReport {
    fn name(self) -> &'static str {
        match self {
            DigestedReport::Paper => "paper",
            DigestedReport::Hydrodynamics => "hydrodynamics",
        }
    }
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
        /// LAMMPS: the fixed-moment model in LAMMPS' own dipole pair style, no magdem in the loop
        /// (induction "none", a dipole cut-off, no gradient; runs under --mpi N).
        #[arg(long, conflicts_with = "exchange_every")]
        native: bool,
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
        /// LAMMPS: the fixed-moment model in LAMMPS' own dipole pair style, for `mpirun -np N lmp`
        /// without magdem (induction "none", a dipole cut-off, no gradient).
        #[arg(long)]
        native: bool,
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
    Validate { scene: PathBuf },
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
        /// A report's digest directory: a run it records as finished with the same scene is not
        /// run again (repeatable; default: every reports/*/digests under the current directory).
        #[arg(long, value_name = "DIR")]
        digests: Vec<PathBuf>,
        /// Run every point whose trajectory is not here, whatever the digests record.
        #[arg(long, conflicts_with = "digests")]
        no_digests: bool,
    },
    /// Write a report from experiment runs.
    #[command(subcommand)]
    Report(Report),
    /// Describe a trajectory file.
    Info { file: PathBuf },
    /// Export trajectories for ParaView (an XDMF sidecar beside each file, referencing its HDF5
    /// datasets in place), OVITO and LAMMPS' tools (a LAMMPS text dump of every frame), or as a
    /// picture of the last frame rendered by ParaView (needs pvbatch and Xvfb).
    Export {
        #[arg(required = true)]
        files: Vec<PathBuf>,
        #[arg(long, value_enum, default_value = "xdmf")]
        format: ExportFormat,
        /// Dump or picture (lammps-dump or png, one trajectory; default FILE.dump or FILE.png
        /// beside it).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Time magdem against LIGGGHTS and LAMMPS on the same scenes (contact forces alone in packed,
    /// loose and dilute beds of 300–30 000 particles, dipole forces at case-1 parameters), the
    /// paper's physics at 10³–10⁵ particles, the cost per particle against N and the second
    /// thread; saves the measurements as performance.json and writes reports/performance.md from
    /// them (30–60 minutes on a 2-core machine with the default repeats, the MPI demonstration
    /// included).
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
        /// Largest particle count of the scaling study (1 000 … 300 000; the paper-physics scene
        /// stops at 100 000).
        #[arg(long, default_value_t = 300_000)]
        max_particles: usize,
        /// Skip the MPI demonstration (LIGGGHTS and LAMMPS by the files route under
        /// `mpirun -np 1` and `-np 2`, about 5 minutes).
        #[arg(long)]
        no_mpi: bool,
        /// Only rewrite performance.md and performance-scaling.png from the performance.json in
        /// --out (no timing).
        #[arg(long)]
        redraw: bool,
    },
}

fn main() -> ExitCode {
    // Output piped into `head` and closed: end quietly as other command-line tools do, not with
    // a panic in println!. SAFETY: restoring the default disposition of SIGPIPE before any
    // thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    match Cli::parse().command {
        Command::Run {
            scene,
            output,
            engine,
            exchange_every,
            mpi,
            native,
            resume,
            overwrite,
            timings,
            quiet,
            abort_after_frame,
        } => {
            let options = RunOptions { resume, overwrite, progress: !quiet, timings, abort_after_frame };
            let coupling = cli::run::CouplingChoice { exchange_every, mpi, native };
            cli::run::run(&scene, &output, engine, coupling, &options)
        }
        Command::Deck { scene, engine, output, native } => cli::scene::deck(&scene, engine, &output, native),
        Command::Study { study: SolverStudy::Accuracy { report } } => cli::verify::accuracy(&report),
        Command::Study { study: SolverStudy::Stability { report } } => cli::verify::stability(&report),
        Command::Verify { study: Study::Contacts { report, work } } => cli::verify::contacts(&report, &work),
        Command::Verify { study: Study::Magnetic { report, work, case1_time } } => {
            cli::verify::magnetic(&report, &work, case1_time)
        }
        Command::MagneticForces { scene, positions, prefix } => {
            cli::scene::magnetic_forces(&scene, &positions, &prefix)
        }
        Command::Validate { scene } => cli::scene::validate(&scene),
        Command::Analyse { file, frame, gap, csv, header } => cli::trajectory::analyse(&file, frame, gap, csv, header),
        Command::Experiment { files, jobs, overwrite_changed, dry_run, quiet, digests, no_digests } => {
            let digests = match (no_digests, digests.is_empty()) {
                (true, _) => vec![],
                (false, true) => cli::experiment::report_digests(),
                (false, false) => digests,
            };
            let options = magdem::experiment::ExperimentOptions { jobs, overwrite_changed, progress: !quiet, digests };
            cli::experiment::experiment(&files, &options, dry_run)
        }
        Command::Report(Report::Digests { report, gap }) => {
            let name = report.name();
            let (experiments, dir) = (PathBuf::from("experiments").join(name), PathBuf::from("reports").join(name));
            cli::report::digests(&experiments, &dir.join("digests"), gap)
        }
        Command::Report(Report::Paper {
            experiments,
            reference,
            out,
            gap,
            wall_time,
            hydrodynamics_experiments,
            hydrodynamics,
        }) => cli::report::paper(&magdem::report::paper::PaperReportOptions {
            experiments,
            reference,
            out,
            gap,
            wall_time,
            hydrodynamics_experiments,
            hydrodynamics,
        }),
        Command::Report(Report::Hydrodynamics { experiments, case2_scene, reference, out, gap }) => {
            cli::report::hydrodynamics(&magdem::report::hydrodynamics::HydrodynamicsReportOptions {
                experiments,
                case2_scene,
                reference,
                out,
                gap,
            })
        }
        Command::Info { file } => cli::trajectory::info(&file),
        Command::Export { files, format, output } => cli::trajectory::export(&files, format, output.as_deref()),
        Command::Bench { out, redraw: true, .. } => cli::report::redraw_bench(&out),
        Command::Bench { out, work, repeats, max_particles, no_mpi, redraw: false } => {
            cli::report::bench(magdem::bench::Options { out, work, repeats, max_particles, mpi: !no_mpi })
        }
    }
}
