//! What `magdem bench` measured: the record it saves as `performance.json` (and, for polars and
//! pandas, its measurements as `performance.csv`); the report is written from this record alone.
//!
//! Seconds are loop times; an absent value (an engine not installed, a check not run) is `null`.

use super::Error;
use crate::analysis::timing::Spread;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// The record's file name in the report directory.
pub const JSON: &str = "performance.json";
/// The measurements' table in the report directory.
pub const CSV: &str = "performance.csv";

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BenchRecord {
    pub provenance: Provenance,
    pub setup: Setup,
    pub measurements: Vec<Measurement>,
    /// Speed-ups taken turn by turn (each turn's runs seconds apart).
    pub paired_speedups: Vec<PairedSpeedup>,
    /// Phase shares of magdem's single-thread loop per case.
    pub profiles: Vec<Profile>,
    /// Per case: whether the 1- and 2-thread runs ended bit for bit equal.
    pub bitwise: Vec<Bitwise>,
    /// Per case: contacts per particle at the end of magdem's one-thread run.
    pub contacts: Vec<Contacts>,
    pub memory: Vec<Memory>,
    /// Per size of the dipole scaling scene: partners within the cut-off.
    pub dipole_pairs: Vec<DipolePairs>,
    /// Per dipole case: magdem's forces against LAMMPS' at the initial configuration.
    pub force_agreement: Vec<ForceAgreement>,
    /// First lines of the engines' logs.
    pub engine_versions: Vec<String>,
    pub mpi: Vec<MpiRun>,
    pub native: Vec<NativeRun>,
    pub native_bulk: Vec<NativeBulk>,
    /// Per case: the machine's own two-core gains, run in turns with the case.
    pub ceilings: Vec<Ceilings>,
    /// Per case: each phase's median seconds per step on one thread and on two.
    pub phases_on_both_cores: Vec<PhasesOnBothCores>,
    /// Engines and checks that failed, with their error.
    pub notes: Vec<String>,
}

/// Which build measured, where, and how often.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Provenance {
    pub magdem_version: String,
    pub commit: String,
    /// UTC day the bench finished (YYYY-MM-DD).
    pub date: Option<String>,
    pub machine: Machine,
    /// Runs per measurement.
    pub repeats: usize,
    /// Runs, at least, of the cases a target judges.
    pub target_turns: usize,
    /// Directory of the scenes, decks and logs.
    pub work: String,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Machine {
    pub cpu: String,
    /// Vector extensions among avx512f, avx2 and fma.
    pub simd: Vec<String>,
    pub cores: usize,
    /// The first core's data and unified caches ("L2 512K", "L3 32768K shared by 2 cores").
    pub caches: Vec<String>,
    pub memory_gib: f64,
    pub kernel: String,
}

/// The scenes' parameters (docs/model.md §10.6 and `bench`'s scene builders).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Setup {
    pub dt_s: f64,
    pub diameter_um: f64,
    pub youngs_modulus_pa: f64,
    pub restitution: f64,
    pub friction: f64,
    /// Particle-steps per run of a contact case.
    pub contact_particle_steps: f64,
    /// The packed bed's overlap between lattice neighbours, in diameters.
    pub packed_prestrain: f64,
    pub loose_solid_fraction: f64,
    pub dilute_solid_fraction: f64,
    /// The dipole cases' concentration (mg/ml), box (µm) and field (T).
    pub dipole_concentration: f64,
    pub dipole_box_um: [f64; 3],
    pub field_t: f64,
    pub cutoff_diameters: f64,
    /// The paper-physics scene: concentration, particles per chain, magnetic forces every
    /// `slow_every` steps, particle-steps per run and its least number of steps.
    pub paper_concentration: f64,
    pub paper_chain: usize,
    pub paper_slow_every: u64,
    pub paper_particle_steps: f64,
    pub paper_min_steps: u64,
    pub paper_cases: Vec<PaperCase>,
    /// The scaling study's N, particle-steps per contact run and force evaluations times
    /// particles per dipole run, each with its least number of steps.
    pub scaling_sizes: Vec<usize>,
    pub scaling_particle_steps: f64,
    pub scaling_min_steps: u64,
    pub scaling_dipole_evaluations: f64,
    pub scaling_dipole_min_steps: u64,
    /// The MPI demonstration: the reference point's concentration and duration, and the files
    /// route's exchange interval (steps).
    pub mpi_concentration: f64,
    pub mpi_duration_ms: Option<f64>,
    pub mpi_exchange_every: u64,
    /// The native-deck comparison's duration, and the steps of its bulk run.
    pub native_duration_ms: f64,
    pub native_bulk_steps: u64,
    /// Aggregate gap tolerance, as a fraction of the radius.
    pub gap_tolerance: f64,
    /// Lanes of the arithmetic try.
    pub arithmetic_lanes: usize,
    /// Passes over arrays of three-vectors the velocity-Verlet kicks and drift make per step.
    pub integrate_passes: usize,
}

/// One paper-physics case: its size and how often its drag coefficients are renewed.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PaperCase {
    pub case: String,
    pub particles: usize,
    pub drag_every: u64,
}

/// One measured case: who ran it, on how many threads, and the loop times.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Measurement {
    pub case: String,
    pub engine: String,
    pub threads: usize,
    pub particles: usize,
    pub steps: u64,
    pub seconds: Spread,
    /// The runs' seconds in turn order.
    #[serde(default)]
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

/// An engine on a number of threads (MPI processes for LIGGGHTS and LAMMPS).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Who {
    pub engine: String,
    pub threads: usize,
}

/// How many times faster `fast` ran `case` than `slow`, turn by turn: min, median and max over
/// `turns` turns of slow ÷ fast.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PairedSpeedup {
    pub case: String,
    pub fast: Who,
    pub slow: Who,
    pub turns: usize,
    pub ratio: Spread,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Profile {
    pub case: String,
    pub shares: Vec<Share>,
}

/// A phase's fraction of the loop time.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Share {
    pub phase: String,
    pub fraction: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Bitwise {
    pub case: String,
    pub equal: bool,
}

/// Pair contacts per particle (the coordination number is twice this) and wall contacts per
/// particle.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Contacts {
    pub case: String,
    pub pairs_per_particle: f64,
    pub walls_per_particle: f64,
}

/// Heap bytes the simulation holds at the end of its one-thread run, per particle; `particles`
/// is the case's N (a packed bed's count is the lattice's nearest).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Memory {
    pub case: String,
    pub particles: usize,
    pub bytes_per_particle: f64,
}

/// Partners per particle within the cut-off (2 pairs / N).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DipolePairs {
    pub particles: usize,
    pub partners_per_particle: f64,
}

/// max |F_LAMMPS − F_magdem| over particles ÷ the largest force.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ForceAgreement {
    pub case: String,
    pub max_relative_error: f64,
}

/// How the magnetic forces reached a reference engine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Route {
    /// Through files every `every` steps.
    Files { every: u64 },
    /// Through the `fix external` callback every step.
    Callback,
}

/// Statistics of a trajectory's last frame.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LastFrame {
    pub aggregates: usize,
    pub mean_length_um: f64,
    /// Population standard deviation of the aggregate lengths.
    pub std_length_um: f64,
    /// Particles in the largest aggregate.
    pub largest: usize,
    /// Fastest particle (m/s).
    pub fastest_m_per_s: Option<f64>,
}

/// One run of the MPI demonstration.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MpiRun {
    pub engine: String,
    pub route: Route,
    pub procs: usize,
    pub wall_time_s: Option<f64>,
    pub last_frame: LastFrame,
    /// Largest position difference to the 1-process run of the same engine (m).
    pub max_difference_m: Option<f64>,
}

/// One run of the native-deck comparison (magdem, or LAMMPS' own pair styles).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct NativeRun {
    pub engine: String,
    pub procs: usize,
    pub last_frame: LastFrame,
    /// Largest position difference to magdem's run over all frames (m).
    pub to_magdem_m: Option<f64>,
    /// Loop time per particle-step.
    pub ns_per_particle_step: Option<f64>,
}

/// The native deck's cost in bulk.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct NativeBulk {
    pub engine: String,
    /// Threads for magdem, MPI processes for LAMMPS.
    pub threads: usize,
    pub particles: usize,
    pub ns_per_particle_step: f64,
}

/// What the machine gains from a second core in the minutes of `case`: arithmetic alone on two
/// cores ÷ one (medians), and two one-thread runs of the case at once, their throughput ÷ that
/// of one run alone.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Ceilings {
    pub case: String,
    pub arithmetic_gain: f64,
    pub two_runs_gain: f64,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PhasesOnBothCores {
    pub case: String,
    pub phases: Vec<PhaseTimes>,
    /// The sum of the phases.
    pub total: Times,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PhaseTimes {
    pub phase: String,
    #[serde(flatten)]
    pub times: Times,
}

/// Median seconds per step on one thread and on two, and one ÷ two.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct Times {
    pub one_thread_s: f64,
    pub two_threads_s: f64,
    pub gain: f64,
}

impl Times {
    pub fn new(one_thread_s: f64, two_threads_s: f64) -> Self {
        Times { one_thread_s, two_threads_s, gain: one_thread_s / two_threads_s }
    }
}

/// A CSV field, quoted when it holds a comma or a quote (RFC 4180).
fn quoted(field: &str) -> String {
    if field.contains([',', '"']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_string()
    }
}

impl BenchRecord {
    pub fn find(&self, case: &str, engine: &str, threads: usize) -> Option<&Measurement> {
        self.measurements.iter().find(|m| m.case == case && m.engine == engine && m.threads == threads)
    }

    /// How many times faster (medians) `fast` ran `case` than `slow`, each (engine, threads).
    pub fn speedup(&self, case: &str, fast: (&str, usize), slow: (&str, usize)) -> Option<f64> {
        Some(self.find(case, slow.0, slow.1)?.seconds.median / self.find(case, fast.0, fast.1)?.seconds.median)
    }

    /// Reads `dir/performance.json`.
    pub fn load(dir: &Path) -> Result<Self, Error> {
        let path = dir.join(JSON);
        let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()).into())
    }

    /// Writes `dir/performance.json` and `dir/performance.csv`.
    pub fn save(&self, dir: &Path) -> Result<(), Error> {
        std::fs::create_dir_all(dir)?;
        std::fs::write(dir.join(JSON), serde_json::to_string_pretty(self)? + "\n")?;
        let mut csv = String::from("case,engine,threads,particles,steps,min_s,median_s,max_s,particle_steps_per_s\n");
        for m in &self.measurements {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{:.6},{:.6},{:.6},{:.4e}",
                quoted(&m.case),
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
        std::fs::write(dir.join(CSV), csv)?;
        Ok(())
    }
}
