//! `reports/performance.md` and `performance-scaling.png`, written from a [`BenchRecord`] alone
//! (`magdem bench`, or `magdem bench --redraw` from a saved `performance.json`) with
//! `templates/performance/README.md`.

use crate::analysis::timing::Spread;
use crate::bench::record::*;
use crate::plot::{line_chart_with_legend, palette, Legend, RGBColor, Series};
use serde::Serialize;
use std::path::{Path, PathBuf};

type Error = Box<dyn std::error::Error + Send + Sync>;

pub const FIGURE: &str = "performance-scaling.png";
pub const REPORT: &str = "performance.md";

/// The targets: magdem on one thread against LIGGGHTS on one process (packed beds),
/// against LAMMPS (dipole sums), and two threads against one (packed bed of 30 000).
const AGAINST_LIGGGHTS: f64 = 2.0;
const AGAINST_LAMMPS: f64 = 5.0;
const TWO_THREADS: f64 = 1.7;
const PACKED_CASES: [&str; 2] = ["contact packed 3000", "contact packed 30000"];
const TWO_THREAD_CASE: &str = "contact packed 30000";
/// The beds whose both-core gains are set side by side.
const BOTH_CORES_CASES: [&str; 2] = ["contact loose 30000", "contact packed 30000"];

/// The scaling study's cases, one row per (case, threads) in the cost table.
const SCALING_ROWS: [(&str, usize); 6] = [
    ("scaling contact dilute", 1),
    ("scaling contact loose", 1),
    ("scaling contact packed", 1),
    ("scaling contact packed", 2),
    ("scaling dipole cut-off 15 d", 1),
    ("scaling dipole cut-off 15 d", 2),
];
const SCALING_DIPOLES: &str = "scaling dipole cut-off 15 d";

/// Neighbours of a site in the bulk of a face-centred cubic lattice.
const FCC_COORDINATION: usize = 12;
/// Bytes of a three-vector of f64.
const VECTOR_BYTES: f64 = 24.0;
/// A run of the paper's length (s), and the cluster run the native deck's cost is scaled to:
/// particles, and the cores and atoms per process it is spread over.
const PAPER_RUN: f64 = 5e-3;
const CLUSTER_PARTICLES: f64 = 1e6;
const CLUSTER_CORES: [usize; 2] = [256, 1024];
const ATOMS_PER_PROCESS: f64 = 4000.0;

/// A verdict against a target: the ratio and whether it reaches it.
#[derive(Serialize)]
struct Verdict {
    ratio: f64,
    met: bool,
}

impl Verdict {
    fn of(ratio: f64, target: f64) -> Self {
        Verdict { ratio, met: ratio >= target }
    }
}

#[derive(Serialize)]
struct AgainstEngine {
    case: String,
    particles: usize,
    coordination: Option<f64>,
    verdict: Verdict,
}

#[derive(Serialize)]
struct TwoThreads {
    case: String,
    particles: usize,
    /// Turn by turn (when the record holds the turns' ratio) or of the medians.
    verdict: Verdict,
    paired: Option<PairedSpeedup>,
    of_medians: f64,
    liggghts: Option<f64>,
    lammps: Option<f64>,
    ceilings: Option<Ceilings>,
}

/// Cost at the largest N ÷ at the smallest, per particle-step or (dipoles) per pair.
#[derive(Serialize)]
struct Growth {
    case: String,
    per_pair: bool,
    small: usize,
    large: usize,
    ratio: f64,
}

#[derive(Serialize)]
struct ContactRow {
    case: String,
    particles: usize,
    steps: u64,
    coordination: Option<f64>,
    walls: Option<f64>,
    contact_share: Option<f64>,
    one: Option<Spread>,
    two: Option<Spread>,
    liggghts: Option<Spread>,
    lammps: Option<Spread>,
    vs_liggghts: Option<f64>,
    vs_lammps: Option<f64>,
    two_over_one: Option<f64>,
    bitwise: Option<bool>,
}

#[derive(Serialize)]
struct BothCoresRow {
    case: String,
    magdem: Option<f64>,
    liggghts: Option<f64>,
    lammps: Option<f64>,
    vs_liggghts: Option<f64>,
    vs_lammps: Option<f64>,
    arithmetic: Option<f64>,
    two_runs: Option<f64>,
    /// magdem's two-thread gain ÷ two runs' gain.
    efficiency: Option<f64>,
}

/// A phase's median µs per step on one thread and on two.
#[derive(Serialize)]
struct PhaseRow {
    case: String,
    phase: Option<String>,
    one_us: f64,
    two_us: f64,
    gain: f64,
}

/// The integrator's streaming: MB per step, and GB/s on one thread and on two.
#[derive(Serialize)]
struct Bandwidth {
    case: String,
    megabytes: f64,
    one: f64,
    two: f64,
}

#[derive(Serialize)]
struct DipoleRow {
    case: String,
    magdem: Option<Spread>,
    lammps: Option<Spread>,
    speedup: Option<f64>,
    agreement: Option<f64>,
}

#[derive(Serialize)]
struct PaperRow {
    particles: usize,
    drag_every: u64,
    steps: u64,
    coordination: Option<f64>,
    walls: Option<f64>,
    one_ns: f64,
    two_ns: f64,
    gain: f64,
    bitwise: Option<bool>,
    memory: Option<f64>,
    run_minutes: f64,
}

/// A row of the scaling table: one cell per N, with `digits` decimals and `unit`.
#[derive(Serialize)]
struct Row {
    label: String,
    threads: usize,
    cells: Vec<Option<f64>>,
    digits: usize,
    unit: &'static str,
}

#[derive(Serialize)]
struct ProfileRow {
    case: String,
    shares: Vec<Share>,
}

/// A 10⁶-particle run of the paper's length on a cluster, at the native deck's bulk cost.
#[derive(Serialize)]
struct Cluster {
    particles: f64,
    run_ms: f64,
    steps: f64,
    core_hours: f64,
    ns: f64,
    efficiency: f64,
    hours: Vec<CoresHours>,
    shell_mm: f64,
    atoms: f64,
    subdomain_mm: f64,
    ghosts: f64,
}

/// Wall-clock hours on `cores` cores at the measured parallel efficiency.
#[derive(Serialize)]
struct CoresHours {
    cores: usize,
    hours: f64,
}

/// Mutual induction's effect in the committed paper report's sensitivity study.
#[derive(Serialize)]
struct Induction {
    concentration: f64,
    mean: f64,
    ci95: f64,
    seeds: f64,
}

#[derive(Serialize)]
struct Context<'a> {
    provenance: &'a Provenance,
    setup: &'a Setup,
    engine_versions: &'a [String],
    notes: &'a [String],
    figure: &'static str,
    targets: Targets,
    contact_sizes: Vec<usize>,
    packed_sizes: Vec<usize>,
    fcc_coordination: usize,
    contacts: Vec<ContactRow>,
    both_cores: Vec<BothCoresRow>,
    phases: Vec<PhaseRow>,
    bandwidth: Vec<Bandwidth>,
    dipoles: Vec<DipoleRow>,
    dipole_particles: Option<usize>,
    dipole_evaluations: Option<u64>,
    paper: Vec<PaperRow>,
    chain_contacts: f64,
    run_ms: f64,
    run_steps: f64,
    scaling: Vec<Row>,
    profiles: Vec<ProfileRow>,
    mpi: &'a [MpiRun],
    mpi_hold_us: f64,
    /// Whether every run on two processes ended where the one-process run did.
    mpi_same: bool,
    callback_rows: bool,
    native: &'a [NativeRun],
    native_bulk: &'a [NativeBulk],
    cluster: Option<Cluster>,
    induction: Option<Induction>,
    reproduce_seconds: Option<f64>,
    reproduce_minutes: Option<f64>,
}

#[derive(Serialize)]
struct Targets {
    against_liggghts: f64,
    against_lammps: f64,
    two_threads: f64,
    packed: Vec<AgainstEngine>,
    dipoles: Vec<AgainstEngine>,
    threads: Option<TwoThreads>,
    growth: Vec<Growth>,
}

fn coordination(record: &BenchRecord, case: &str) -> Option<f64> {
    record.contacts.iter().find(|c| c.case == case).map(|c| 2.0 * c.pairs_per_particle)
}

fn walls(record: &BenchRecord, case: &str) -> Option<f64> {
    record.contacts.iter().find(|c| c.case == case).map(|c| c.walls_per_particle)
}

fn bitwise(record: &BenchRecord, case: &str) -> Option<bool> {
    record.bitwise.iter().find(|b| b.case == case).map(|b| b.equal)
}

fn memory(record: &BenchRecord, case: &str, particles: usize) -> Option<f64> {
    record
        .memory
        .iter()
        .find(|m| m.case == case && m.particles == particles && m.bytes_per_particle > 0.0)
        .map(|m| m.bytes_per_particle)
}

/// Nanoseconds per force evaluation and pair within the cut-off (each counted once) at the
/// median, for a run of the dipole scaling scene whose pairs were counted.
fn ns_per_pair(record: &BenchRecord, m: &Measurement) -> Option<f64> {
    let partners = record.dipole_pairs.iter().find(|p| p.particles == m.particles)?.partners_per_particle;
    let pairs = partners * m.particles as f64 / 2.0;
    Some(m.seconds.median / (m.steps as f64 * pairs) * 1e9)
}

/// The cases in the order first measured, of those starting with `prefix`.
fn cases_with(record: &BenchRecord, prefix: &str) -> Vec<String> {
    let mut cases: Vec<String> = vec![];
    for m in record.measurements.iter().filter(|m| m.case.starts_with(prefix)) {
        if !cases.contains(&m.case) {
            cases.push(m.case.clone());
        }
    }
    cases
}

fn targets(record: &BenchRecord) -> Targets {
    let against = |cases: Vec<String>, engine: &str, target: f64| -> Vec<AgainstEngine> {
        cases
            .iter()
            .filter_map(|case| {
                let ratio = record.speedup(case, ("magdem", 1), (engine, 1))?;
                Some(AgainstEngine {
                    case: case.clone(),
                    particles: record.find(case, "magdem", 1)?.particles,
                    coordination: coordination(record, case),
                    verdict: Verdict::of(ratio, target),
                })
            })
            .collect()
    };
    let threads = (|| {
        let case = TWO_THREAD_CASE;
        let of_medians = record.speedup(case, ("magdem", 2), ("magdem", 1))?;
        let magdem = |threads| Who { engine: "magdem".into(), threads };
        let paired = record
            .paired_speedups
            .iter()
            .find(|p| p.case == case && p.fast == magdem(2) && p.slow == magdem(1))
            .cloned();
        let ratio = paired.as_ref().map_or(of_medians, |p| p.ratio.median);
        Some(TwoThreads {
            case: case.into(),
            particles: record.find(case, "magdem", 1)?.particles,
            verdict: Verdict::of(ratio, TWO_THREADS),
            paired,
            of_medians,
            liggghts: record.speedup(case, ("liggghts", 2), ("liggghts", 1)),
            lammps: record.speedup(case, ("lammps", 2), ("lammps", 1)),
            ceilings: record.ceilings.iter().find(|c| c.case == case).cloned(),
        })
    })();
    let growth = ["scaling contact dilute", "scaling contact loose", "scaling contact packed", SCALING_DIPOLES]
        .into_iter()
        .filter_map(|case| {
            let runs: Vec<&Measurement> =
                record.measurements.iter().filter(|m| m.case == case && m.threads == 1).collect();
            let (small, large) = (runs.iter().min_by_key(|m| m.particles)?, runs.iter().max_by_key(|m| m.particles)?);
            let per_pair = case == SCALING_DIPOLES;
            let cost = |m: &Measurement| if per_pair { ns_per_pair(record, m) } else { Some(m.ns_per_particle_step()) };
            Some(Growth {
                case: case.trim_start_matches("scaling ").into(),
                per_pair,
                small: small.particles,
                large: large.particles,
                ratio: cost(large)? / cost(small)?,
            })
        })
        .collect();
    Targets {
        against_liggghts: AGAINST_LIGGGHTS,
        against_lammps: AGAINST_LAMMPS,
        two_threads: TWO_THREADS,
        packed: against(PACKED_CASES.map(String::from).to_vec(), "liggghts", AGAINST_LIGGGHTS),
        dipoles: against(cases_with(record, "dipole "), "lammps", AGAINST_LAMMPS),
        threads,
        growth,
    }
}

fn contact_rows(record: &BenchRecord) -> Vec<ContactRow> {
    cases_with(record, "contact ")
        .into_iter()
        .map(|case| {
            let at = |engine: &str, threads| record.find(&case, engine, threads);
            let seconds = |engine: &str, threads| at(engine, threads).map(|m| m.seconds);
            let contact_share = record
                .profiles
                .iter()
                .find(|p| p.case == case)
                .and_then(|p| p.shares.iter().find(|s| s.phase == "contact"))
                .map(|s| s.fraction);
            ContactRow {
                particles: at("magdem", 1).map_or(0, |m| m.particles),
                steps: at("magdem", 1).map_or(0, |m| m.steps),
                coordination: coordination(record, &case),
                walls: walls(record, &case),
                contact_share,
                one: seconds("magdem", 1),
                two: seconds("magdem", 2),
                liggghts: seconds("liggghts", 1),
                lammps: seconds("lammps", 1),
                vs_liggghts: record.speedup(&case, ("magdem", 1), ("liggghts", 1)),
                vs_lammps: record.speedup(&case, ("magdem", 1), ("lammps", 1)),
                two_over_one: record.speedup(&case, ("magdem", 2), ("magdem", 1)),
                bitwise: bitwise(record, &case),
                case,
            }
        })
        .collect()
}

fn both_cores_rows(record: &BenchRecord) -> Vec<BothCoresRow> {
    BOTH_CORES_CASES
        .iter()
        .map(|&case| {
            let gain = |engine| record.speedup(case, (engine, 2), (engine, 1));
            let ceilings = record.ceilings.iter().find(|c| c.case == case);
            let magdem = gain("magdem");
            BothCoresRow {
                case: case.into(),
                magdem,
                liggghts: gain("liggghts"),
                lammps: gain("lammps"),
                vs_liggghts: record.speedup(case, ("magdem", 2), ("liggghts", 2)),
                vs_lammps: record.speedup(case, ("magdem", 2), ("lammps", 2)),
                arithmetic: ceilings.map(|c| c.arithmetic_gain),
                two_runs: ceilings.map(|c| c.two_runs_gain),
                efficiency: magdem.zip(ceilings).map(|(g, c)| g / c.two_runs_gain),
            }
        })
        .collect()
}

/// The phase table's rows (each case's phases, then their sum) and the integrator's bandwidth.
fn phase_rows(record: &BenchRecord) -> (Vec<PhaseRow>, Vec<Bandwidth>) {
    let (mut rows, mut bandwidth) = (vec![], vec![]);
    for p in &record.phases_on_both_cores {
        let row = |phase: Option<&str>, t: &Times| PhaseRow {
            case: p.case.clone(),
            phase: phase.map(String::from),
            one_us: t.one_thread_s * 1e6,
            two_us: t.two_threads_s * 1e6,
            gain: t.gain,
        };
        rows.extend(p.phases.iter().map(|ph| row(Some(&ph.phase), &ph.times)));
        rows.push(row(None, &p.total));
        let particles = record.measurements.iter().find(|m| m.case == p.case).map_or(0, |m| m.particles);
        if let Some(integrate) = p.phases.iter().find(|ph| ph.phase == "integrate") {
            let bytes = record.setup.integrate_passes as f64 * VECTOR_BYTES * particles as f64;
            bandwidth.push(Bandwidth {
                case: p.case.clone(),
                megabytes: bytes / 1e6,
                one: bytes / integrate.times.one_thread_s / 1e9,
                two: bytes / integrate.times.two_threads_s / 1e9,
            });
        }
    }
    (rows, bandwidth)
}

fn paper_rows(record: &BenchRecord, run_steps: f64) -> Vec<PaperRow> {
    record
        .setup
        .paper_cases
        .iter()
        .filter_map(|p| {
            let (one, two) = (record.find(&p.case, "magdem", 1)?, record.find(&p.case, "magdem", 2)?);
            Some(PaperRow {
                particles: p.particles,
                drag_every: p.drag_every,
                steps: one.steps,
                coordination: coordination(record, &p.case),
                walls: walls(record, &p.case),
                one_ns: one.ns_per_particle_step(),
                two_ns: two.ns_per_particle_step(),
                gain: one.seconds.median / two.seconds.median,
                bitwise: bitwise(record, &p.case),
                memory: memory(record, &p.case, p.particles),
                run_minutes: two.ns_per_particle_step() * 1e-9 * p.particles as f64 * run_steps / 60.0,
            })
        })
        .collect()
}

/// The scaling table: ns per particle-step per N, the dipole scene's partners and ns per pair,
/// and the memory per particle.
fn scaling_rows(record: &BenchRecord) -> Vec<Row> {
    let sizes = &record.setup.scaling_sizes;
    let label = |case: &str| case.trim_start_matches("scaling ").to_string();
    let mut rows: Vec<Row> = SCALING_ROWS
        .iter()
        .map(|&(case, threads)| {
            // One measurement per size, in the order of the sizes (a packed bed's count is the
            // lattice's nearest to N).
            let mut runs = record.measurements.iter().filter(|m| m.case == case && m.threads == threads);
            let cells = sizes.iter().map(|_| runs.next().map(Measurement::ns_per_particle_step)).collect();
            Row { label: label(case), threads, cells, digits: 1, unit: "ns" }
        })
        .collect();
    let partners = sizes
        .iter()
        .map(|&n| record.dipole_pairs.iter().find(|p| p.particles == n).map(|p| p.partners_per_particle))
        .collect();
    let dipoles = label(SCALING_DIPOLES);
    rows.push(Row {
        label: format!("{dipoles}: partners per particle"),
        threads: 1,
        cells: partners,
        digits: 0,
        unit: "",
    });
    let per_pair = sizes
        .iter()
        .map(|&n| {
            let m =
                record.measurements.iter().find(|m| m.case == SCALING_DIPOLES && m.threads == 1 && m.particles == n);
            m.and_then(|m| ns_per_pair(record, m))
        })
        .collect();
    rows.push(Row { label: format!("{dipoles}: ns per pair"), threads: 1, cells: per_pair, digits: 1, unit: "ns" });
    for case in ["scaling contact dilute", "scaling contact loose", "scaling contact packed", SCALING_DIPOLES] {
        let cells = sizes.iter().map(|&n| memory(record, case, n)).collect();
        rows.push(Row { label: format!("memory, {}", label(case)), threads: 1, cells, digits: 0, unit: "B" });
    }
    rows
}

/// The cluster estimate from LAMMPS' bulk cost on one and two processes.
fn cluster(record: &BenchRecord, dipole_particles: Option<usize>) -> Option<Cluster> {
    let bulk = |threads: usize| {
        record.native_bulk.iter().find(|b| b.engine == "lammps" && b.threads == threads).map(|b| b.ns_per_particle_step)
    };
    let (one, two) = (bulk(1)?, bulk(2)?);
    let s = &record.setup;
    let steps = PAPER_RUN / s.dt_s;
    let core_hours = one * 1e-9 * CLUSTER_PARTICLES * steps / 3600.0;
    let efficiency = one / two / 2.0;
    // Atoms per m³ at the paper-physics concentration, from the dipole cases' box.
    let [x, y, z] = s.dipole_box_um.map(|l| l * 1e-6);
    let density = dipole_particles? as f64 / (x * y * z) * s.paper_concentration / s.dipole_concentration;
    let subdomain = (ATOMS_PER_PROCESS / density).cbrt();
    let shell = s.cutoff_diameters * s.diameter_um * 1e-6;
    Some(Cluster {
        particles: CLUSTER_PARTICLES,
        run_ms: PAPER_RUN * 1e3,
        steps,
        core_hours,
        ns: one,
        efficiency,
        hours: CLUSTER_CORES
            .iter()
            .map(|&cores| CoresHours { cores, hours: core_hours / (cores as f64 * efficiency) })
            .collect(),
        shell_mm: shell * 1e3,
        atoms: ATOMS_PER_PROCESS,
        subdomain_mm: subdomain * 1e3,
        ghosts: ((subdomain + 2.0 * shell) / subdomain).powi(3) - 1.0,
    })
}

/// The wall time (s) of the `make reproduce` runs, as the paper report recorded it in its tables.
fn reproduce_wall_time() -> Option<f64> {
    let path = Path::new("reports/paper/tables").join(format!("{}.csv", crate::report::paper::REPRODUCE_TABLE));
    let table = crate::report::tables::read_csv(&path).ok()?;
    let seconds = crate::report::tables::floats(&table, "experiments_wall_time_s").ok()?;
    seconds.first().filter(|s| s.is_finite()).map(|s| s.round())
}

/// What mutual induction changes in case 1 at `concentration`, from the committed paper report's
/// ranking table (its sensitivity study's `no-induction` runs).
fn induction_effect_in(explanations: &Path, concentration: f64) -> Option<Induction> {
    use crate::report::paper::convergence::Explanation;
    let table = crate::report::tables::read_csv(explanations).ok()?;
    let text = |name: &str| table.column(name).ok()?.str().ok().cloned();
    let number = |name: &str| crate::report::tables::floats(&table, name).ok();
    let (explanation, c) = (text("explanation")?, number("concentration_mg_per_ml")?);
    let (change, ci95, n) = (number("change_percent")?, number("ci95_percent")?, number("runs_or_pairs")?);
    let k = (0..c.len()).find(|&k| {
        explanation.get(k) == Some(Explanation::Induction.name()) && crate::report::tables::same(c[k], concentration)
    })?;
    Some(Induction { concentration, mean: change[k], ci95: ci95[k], seeds: n[k] })
}

/// The report's text.
pub fn markdown(record: &BenchRecord) -> Result<String, Error> {
    let s = &record.setup;
    let run_steps = PAPER_RUN / s.dt_s;
    let dipole = record.measurements.iter().find(|m| m.case.starts_with("dipole ") && m.engine == "magdem");
    let (phases, bandwidth) = phase_rows(record);
    let sizes = |prefix: &str| -> Vec<usize> {
        cases_with(record, prefix).iter().filter_map(|c| record.find(c, "magdem", 1)).map(|m| m.particles).collect()
    };
    let mut profiles: Vec<ProfileRow> =
        record.profiles.iter().map(|p| ProfileRow { case: p.case.clone(), shares: p.shares.clone() }).collect();
    for p in &mut profiles {
        p.shares.sort_by(|a, b| b.fraction.total_cmp(&a.fraction));
    }
    let reproduce = reproduce_wall_time();
    let context = Context {
        provenance: &record.provenance,
        setup: s,
        engine_versions: &record.engine_versions,
        notes: &record.notes,
        figure: FIGURE,
        targets: targets(record),
        contact_sizes: sizes("contact dilute "),
        packed_sizes: sizes("contact packed "),
        fcc_coordination: FCC_COORDINATION,
        contacts: contact_rows(record),
        both_cores: both_cores_rows(record),
        phases,
        bandwidth,
        dipoles: cases_with(record, "dipole ")
            .into_iter()
            .map(|case| {
                let (one, lmp) = (record.find(&case, "magdem", 1), record.find(&case, "lammps", 1));
                DipoleRow {
                    magdem: one.map(|m| m.seconds),
                    lammps: lmp.map(|m| m.seconds),
                    speedup: record.speedup(&case, ("magdem", 1), ("lammps", 1)),
                    agreement: record.force_agreement.iter().find(|a| a.case == case).map(|a| a.max_relative_error),
                    case,
                }
            })
            .collect(),
        dipole_particles: dipole.map(|m| m.particles),
        dipole_evaluations: dipole.map(|m| m.steps),
        paper: paper_rows(record, run_steps),
        chain_contacts: 2.0 * (s.paper_chain as f64 - 1.0) / s.paper_chain as f64,
        run_ms: PAPER_RUN * 1e3,
        run_steps,
        scaling: scaling_rows(record),
        profiles,
        mpi: &record.mpi,
        mpi_hold_us: s.mpi_exchange_every as f64 * s.dt_s * 1e6,
        mpi_same: record.mpi.iter().filter_map(|r| r.max_difference_m).all(|d| d == 0.0)
            && record.mpi.iter().any(|r| r.max_difference_m.is_some()),
        callback_rows: record.mpi.iter().any(|r| r.route == Route::Callback),
        native: &record.native,
        native_bulk: &record.native_bulk,
        cluster: cluster(record, dipole.map(|m| m.particles)),
        induction: induction_effect_in(Path::new("reports/paper/tables/explanations.csv"), s.paper_concentration),
        reproduce_seconds: reproduce,
        reproduce_minutes: reproduce.map(|s| s / 60.0),
    };
    Ok(super::template::render("performance/README.md", &context).map_err(|e| e.to_string())?)
}

/// Writes `performance.md` and `performance-scaling.png` into `out` from `record`; returns the
/// report's path.
pub fn write(record: &BenchRecord, out: &Path) -> Result<PathBuf, Error> {
    std::fs::create_dir_all(out)?;
    scaling_figure(&out.join(FIGURE), record)?;
    let path = out.join(REPORT);
    std::fs::write(&path, markdown(record)?)?;
    Ok(path)
}

/// Rewrites the report and its figure from the `performance.json` in `out` (no timing).
pub fn redraw(out: &Path) -> Result<PathBuf, Error> {
    write(&BenchRecord::load(out)?, out)
}

fn scaling_figure(path: &Path, record: &BenchRecord) -> Result<(), Error> {
    let rows = &record.measurements;
    let point = |m: &Measurement| ((m.particles as f64).log10(), m.ns_per_particle_step().log10());
    let line = |case: &str, engine: &str, threads: usize| -> Vec<(f64, f64)> {
        rows.iter().filter(|m| m.case == case && m.engine == engine && m.threads == threads).map(point).collect()
    };
    // The paper-physics cases with the paper's drag (renewed every step).
    let paper = |threads: usize| -> Vec<(f64, f64)> {
        let cases = record.setup.paper_cases.iter().filter(|p| p.drag_every == 1);
        cases
            .filter_map(|p| rows.iter().find(|m| m.case == p.case && m.engine == "magdem" && m.threads == threads))
            .map(point)
            .collect()
    };
    let points = |packing: &str, engine: &str| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|m| m.case.starts_with(&format!("contact {packing}")) && m.engine == engine && m.threads == 1)
            .map(point)
            .collect()
    };
    let mut series = vec![
        Series::line("magdem contact dilute, 1 thread", line("scaling contact dilute", "magdem", 1), palette(0)),
        Series::line("magdem contact loose, 1 thread", line("scaling contact loose", "magdem", 1), palette(1)),
        Series::line("magdem packed bed, 1 thread", line("scaling contact packed", "magdem", 1), palette(2)),
        Series::line("magdem packed bed, 2 threads", line("scaling contact packed", "magdem", 2), palette(6)),
        Series::line("magdem dipoles, 15 d cut-off, 1 thread", line(SCALING_DIPOLES, "magdem", 1), palette(4)),
        Series::line("magdem dipoles, 15 d cut-off, 2 threads", line(SCALING_DIPOLES, "magdem", 2), palette(7)),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The induction effect is the 2.25 mg/ml `induction` row of the ranking table, and a
    /// missing table gives none.
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
        let effect = induction_effect_in(&table, 2.25).unwrap();
        assert_eq!((effect.mean, effect.ci95, effect.seeds), (-13.07, 13.47, 10.0));
        assert!(induction_effect_in(&dir.path().join("none.csv"), 2.25).is_none());
    }
}
