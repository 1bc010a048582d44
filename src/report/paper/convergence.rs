//! The paper report's convergence sections: whether its case-1 numbers are converged against
//! seeds, integration, box size, stopping time and magnetisation, what the experiment's image
//! measurement would make of them, and a ranking of why the paper, the experiment and magdem
//! differ. Every number comes from the runs; a section whose runs do not exist says so.

use super::Inputs;
use crate::analysis::stats::{ci95_half_width, slope_ci95, summary};
use crate::core::forces::magnetisation::MU0;
use crate::plot::{chart, palette, Legend, RGBColor, Scale, Series, SeriesLabelPosition};
use crate::report::estimate::{paired, unpaired};
pub use crate::report::estimate::{paired_change, Estimate};
use crate::report::runs::Run;
use crate::report::tables::{col, frame, markdown, same, scol, ucol, write};
use minijinja::{context, Value};
use rand::{RngExt, SeedableRng};
use std::collections::BTreeMap;
use std::path::Path;

type Error = Box<dyn std::error::Error>;

pub use crate::report::runs::TABLE3;

/// What the paper and the experiment report per concentration (Table 3).
pub struct Targets {
    pub concentration: Vec<f64>,
    pub paper: Vec<f64>,
    pub experiment: Vec<f64>,
}

/// Why magdem's answer, the paper's and the experiment's may differ: what the ranking weighs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Explanation {
    Box,
    StoppingTime,
    Magnetisation,
    Measurement,
    Induction,
    Shielding,
    Restitution,
    Integration,
    /// Not a cause: the statistical uncertainty of magdem's mean, which the others must clear.
    Seeds,
}

impl Explanation {
    /// Every explanation; each concentration's block names those it has no measurement of.
    pub const ALL: [Explanation; 9] = [
        Explanation::Box,
        Explanation::StoppingTime,
        Explanation::Magnetisation,
        Explanation::Measurement,
        Explanation::Induction,
        Explanation::Shielding,
        Explanation::Restitution,
        Explanation::Integration,
        Explanation::Seeds,
    ];

    /// The name the report and the `explanations` table give it.
    pub fn name(self) -> &'static str {
        match self {
            Explanation::Box => "box",
            Explanation::StoppingTime => "stopping time",
            Explanation::Magnetisation => "magnetisation",
            Explanation::Measurement => "measurement",
            Explanation::Induction => "induction",
            Explanation::Shielding => "shielding",
            Explanation::Restitution => "restitution",
            Explanation::Integration => "integration",
            Explanation::Seeds => "seeds",
        }
    }
}

/// One explanation's effect on the mean length at one concentration (%).
pub struct Effect {
    pub concentration: f64,
    pub explanation: Explanation,
    pub what: String,
    pub change: Estimate,
}

/// Completed runs of `experiments` with `variant` at concentration `c`, by seed (one per seed).
pub(crate) fn select<'a>(runs: &'a [Run], experiments: &[&str], variant: &str, c: f64) -> Vec<&'a Run> {
    let mut by_seed: BTreeMap<u64, &Run> = BTreeMap::new();
    for r in runs.iter().filter(|r| {
        r.completed()
            && experiments.contains(&r.experiment.as_str())
            && r.variant == variant
            && same(r.concentration, c)
    }) {
        by_seed.entry(r.seed).or_insert(r);
    }
    by_seed.into_values().collect()
}

/// The Table 3 ensemble at concentration `c` (velocity Verlet).
pub fn table3_runs(runs: &[Run], c: f64) -> Vec<&Run> {
    select(runs, &TABLE3, "", c)
}

fn lengths(runs: &[&Run]) -> Vec<f64> {
    runs.iter().map(|r| r.mean_length_um()).collect()
}

/// Mean of `value` over `runs` (its finite values).
fn mean_over(runs: &[&Run], value: impl Fn(&Run) -> f64) -> f64 {
    Estimate::of(&runs.iter().map(|r| value(r)).collect::<Vec<_>>()).mean
}

fn box_limited(runs: &[&Run]) -> f64 {
    mean_over(runs, Run::box_limited_fraction)
}

/// Mean over runs of the mean length (µm) at each frame, with the frame times (s).
fn mean_series(runs: &[&Run]) -> Vec<(f64, f64)> {
    let Some(first) = runs.first() else { return vec![] };
    (0..first.times.len())
        .filter(|&k| runs.iter().all(|r| r.mean_length.len() > k))
        .map(|k| (first.times[k], 1e6 * Estimate::of(&runs.iter().map(|r| r.mean_length[k]).collect::<Vec<_>>()).mean))
        .collect()
}

/// A horizontal reference drawn as a dotted line of small markers from `x0` to `x1` (log-spaced).
fn level(label: impl Into<String>, y: f64, (x0, x1): (f64, f64), color: RGBColor) -> Series {
    let points = (0..=24).map(|k| (x0 * (x1 / x0).powf(k as f64 / 24.0), y)).collect();
    Series::markers(label, points, color, 2)
}

/// The paper's walled box at concentration `c` under r-RESPA K = 10 (the magnetisation sweep's
/// linear law and the sensitivity study's reference), one run per seed.
pub fn respa_runs(runs: &[Run], c: f64) -> Vec<&Run> {
    let mut here = select(runs, &["paper-magnetisation"], "linear", c);
    for r in select(runs, &["paper-sensitivity"], "respa", c) {
        if !here.iter().any(|h| h.seed == r.seed) {
            here.push(r);
        }
    }
    here.sort_by_key(|r| r.seed);
    here
}

/// Bulk magnetite's saturation magnetisation at room temperature, ≈ 4.8e5 A/m (about 92 A·m²/kg
/// at 5 200 kg/m³; Cornell & Schwertmann, *The Iron Oxides*, Wiley-VCH, 2nd ed., 2003): the most
/// a bead of magnetite can hold, and the top of the magnetisation sweep.
pub const BULK_MAGNETITE_MS: f64 = 4.8e5;

/// The magnetisation sweep's variant at [`BULK_MAGNETITE_MS`], and its unsaturated linear law.
const SATURATED_VARIANT: &str = "ms-4.8e5";
const LINEAR_VARIANT: &str = "linear";

/// The paper's stopping time (s): every case-1 length is read there unless stated.
pub const PAPER_TIME: f64 = 5e-3;

/// Growth exponents are fitted from this time on (s): before it most particles are still single.
pub const GROWTH_FROM: f64 = 1e-3;

/// Room temperature for the dipolar coupling constant λ (K).
pub const ROOM_TEMPERATURE: f64 = 293.15;

/// Boltzmann's constant (J/K).
const BOLTZMANN: f64 = 1.380649e-23;

/// The seed counts at which the seeds table gives the CI95 of the Table 3 mean (besides all).
pub const SEED_SUBSETS: [usize; 2] = [5, 10];

/// The concentration at which the magnetisation sweep's curves are set against t/τ (mg/ml).
pub const COLLAPSE_CONCENTRATION: f64 = 2.25;

/// Published growth exponents of field-induced chaining, with where they are stated (their
/// abstracts; the tables of those works were not checked).
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct GrowthLiterature {
    /// Smoluchowski kinetics for chains whose diffusivity falls as 1/s.
    pub smoluchowski_z: f64,
    pub smoluchowski_source: &'static str,
    /// Ising dipolar particles under thermal noise: z where the attraction dominates, and where
    /// diffusion does.
    pub dipolar_z_attraction: f64,
    pub dipolar_z_diffusion: f64,
    pub dipolar_source: &'static str,
    /// Floating millimetre dipoles (deterministic motion): Vicsek–Family scaling.
    pub floating_source: &'static str,
    /// Experiments on Brownian paramagnetic colloids, whose exponents are not quoted.
    pub colloid_sources: &'static str,
}

pub const GROWTH_EXPONENTS: GrowthLiterature = GrowthLiterature {
    smoluchowski_z: 0.5,
    smoluchowski_source: "a microflows text of Springer's Interdisciplinary Applied Mathematics series, \
                          chapter 13, on chains of paramagnetic beads",
    dipolar_z_attraction: 0.2,
    dipolar_z_diffusion: 0.5,
    dipolar_source: "Suzuki, Kun & Ito, Phys. Rev. E, 2009",
    floating_source: "Pál, Kun, Varga, Sohler & Sun, Phys. Rev. E 83, 061504, 2011",
    colloid_sources: "Fermigier & Gast 1992; Promislow, Gast & Fermigier 1995",
};

/// A number of a run's scene (`integration.dt`, `species.0.diameter`, `field.b0.0`), NaN where
/// the scene has none.
pub(crate) fn scene_number(r: &Run, key: &str) -> f64 {
    let Ok(table) = toml::from_str::<toml::Table>(&r.scene_text) else { return f64::NAN };
    let mut value = toml::Value::Table(table);
    for part in key.split('.') {
        let next = match value {
            toml::Value::Table(mut t) => t.remove(part),
            toml::Value::Array(mut a) => part.parse::<usize>().ok().filter(|&k| k < a.len()).map(|k| a.swap_remove(k)),
            _ => None,
        };
        let Some(next) = next else { return f64::NAN };
        value = next;
    }
    match value {
        toml::Value::Float(x) => x,
        toml::Value::Integer(k) => k as f64,
        _ => f64::NAN,
    }
}

/// The first finite value of `key` over `runs`' scenes.
fn scene_number_of(runs: &[&Run], key: &str) -> f64 {
    runs.iter().map(|r| scene_number(r, key)).find(|x| x.is_finite()).unwrap_or(f64::NAN)
}

/// The experiments the seeds section reads: Table 3 and the r-RESPA runs of its scenes.
pub const SEEDS_EXPERIMENTS: [&str; 4] = [TABLE3[0], TABLE3[1], "paper-magnetisation", "paper-sensitivity"];

/// One concentration of the seeds table.
#[derive(serde::Serialize)]
struct SeedsRow {
    c: f64,
    /// The Verlet mean (µm) over its seeds.
    length: Estimate,
    /// r-RESPA against Verlet, paired by seed (%).
    bias: Estimate,
}

/// Seeds and integration: the Table 3 mean's confidence against the number of seeds, and
/// r-RESPA's paired bias against velocity Verlet.
pub fn seeds(inp: &Inputs) -> Result<Value, Error> {
    let (runs, t) = (inp.runs, inp.targets);
    let mut effects = inp.effects.borrow_mut();
    let (mut rel_a, mut rel_b, mut rel_all) = (vec![], vec![], vec![]);
    let mut rows = vec![];
    let (mut verlet_all, mut respa_all) = (vec![], vec![]);
    for &c in &t.concentration {
        let verlet = table3_runs(runs, c);
        if verlet.is_empty() {
            continue;
        }
        let l = lengths(&verlet);
        let e = Estimate::of(&l);
        let rel =
            |n: usize| if l.len() >= n { 100.0 * ci95_half_width(&l[..n]) / summary(&l[..n]).mean } else { f64::NAN };
        let respa = respa_runs(runs, c);
        let b = paired(&verlet, &respa, |r| r.mean_length_um());
        rel_a.push(rel(SEED_SUBSETS[0]));
        rel_b.push(rel(SEED_SUBSETS[1]));
        rel_all.push(100.0 * e.ci95 / e.mean);
        effects.push(Effect {
            concentration: c,
            explanation: Explanation::Seeds,
            what: format!("CI95 of the {}-seed mean", l.len()),
            change: Estimate { n: l.len(), mean: 0.0, ci95: 100.0 * e.ci95 / e.mean },
        });
        if b.n > 0 {
            effects.push(Effect {
                concentration: c,
                explanation: Explanation::Integration,
                what: format!(
                    "r-RESPA K = {:.0} against velocity Verlet, paired over {} seeds",
                    scene_number_of(&respa, "integration.slow_every"),
                    b.n
                ),
                change: b,
            });
        }
        verlet_all.extend(verlet);
        respa_all.extend(respa);
        rows.push(SeedsRow { c, length: e, bias: b });
    }
    if rows.is_empty() {
        return Ok(context! { ran => false });
    }
    let column = |f: &dyn Fn(&SeedsRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let mut df = frame(vec![
        col("concentration_mg_per_ml", column(&|r| r.c)),
        col("seeds", column(&|r| r.length.n as f64)),
        col("mean_length_um", column(&|r| r.length.mean)),
        col("ci95_um", column(&|r| r.length.ci95)),
        col(&format!("ci95_percent_{}_seeds", SEED_SUBSETS[0]), rel_a),
        col(&format!("ci95_percent_{}_seeds", SEED_SUBSETS[1]), rel_b),
        col("ci95_percent_all_seeds", rel_all),
        col("respa_paired_bias_percent", column(&|r| r.bias.mean)),
        col("respa_bias_ci95_percent", column(&|r| r.bias.ci95)),
        col("respa_bias_seeds", column(&|r| r.bias.n as f64)),
    ])?;
    write(&mut df, &inp.tables, "seeds_and_integration")?;
    let (first, second) = (format!("CI95 % ({} seeds)", SEED_SUBSETS[0]), format!("CI95 % ({})", SEED_SUBSETS[1]));
    let table = markdown(
        &df,
        &[
            "c (mg/ml)",
            "seeds",
            "mean length (µm)",
            "± CI95",
            &first,
            &second,
            "CI95 % (all)",
            "r-RESPA bias (%)",
            "± CI95",
            "paired seeds",
        ],
        &[3, 0, 1, 1, 1, 1, 1, 1, 1, 0],
    )?;
    Ok(context! {
        ran => true,
        table => table,
        dt => scene_number_of(&verlet_all, "integration.dt"),
        respa_dt => scene_number_of(&respa_all, "integration.dt"),
        slow_every => scene_number_of(&respa_all, "integration.slow_every"),
        subsets => SEED_SUBSETS,
        paired => rows.iter().any(|r| r.bias.n > 0),
        rows => rows,
    })
}

/// `x{f}-periodic` → f.
fn box_factor(variant: &str) -> Option<f64> {
    variant.strip_prefix('x')?.strip_suffix("-periodic")?.parse().ok()
}

/// One box size of the finite-size study at one concentration.
#[derive(serde::Serialize)]
struct SizeRow {
    factor: u64,
    particles: f64,
    /// Mean length over seeds (µm).
    length: Estimate,
    box_limited: f64,
    /// Percolating aggregates summed over the seeds.
    percolating: usize,
}

/// What the next size of the series would cost per run, at the largest size's fastest wall time
/// per particle, taken as linear in the particles.
#[derive(serde::Serialize)]
struct NextSize {
    factor: u64,
    particles: f64,
    hours: f64,
    /// The size whose fastest run sets the rate, its wall time (s) and particles.
    from_factor: u64,
    from_wall_s: f64,
    from_particles: f64,
    ms_per_particle: f64,
}

/// One concentration's finite-size law L ∝ N^β.
#[derive(serde::Serialize)]
struct SizeLaw {
    c: f64,
    /// β ± CI95 over every run (n: the runs).
    beta: Estimate,
    from: u64,
    to: u64,
    particles_from: f64,
    particles_to: f64,
    sizes: Vec<SizeRow>,
    percolating: usize,
    /// The largest size against the one below it (%, unpaired), and their factors.
    largest: Estimate,
    below: u64,
    /// The two largest sizes agree within their CI95 and β's CI95 includes 0.
    converged: bool,
    /// Periodic side faces against walls at the paper's size (%, paired over seeds).
    walls: Estimate,
    next: Option<NextSize>,
}

/// The finite-size series' sizes (multiples of the paper's particle count).
const SIZE_SERIES: [u64; 9] = [1, 2, 4, 10, 30, 100, 300, 1000, 3000];

/// The size law at concentration `c` from its runs by size factor; pushes the box effect for the
/// ranking where the law is converged (the paired change from the paper's walled box to the
/// largest periodic box with two seeds or more).
fn size_law(runs: &[Run], c: f64, by_factor: &BTreeMap<u64, Vec<&Run>>, effects: &mut Vec<Effect>) -> Option<SizeLaw> {
    let points: Vec<(f64, f64)> = by_factor
        .values()
        .flatten()
        .map(|r| (r.particles as f64, r.mean_length_um()))
        .filter(|&(n, l)| n > 0.0 && l > 0.0 && l.is_finite())
        .map(|(n, l)| (n.ln(), l.ln()))
        .collect();
    let (beta, beta_ci) = slope_ci95(&points);
    let beta = Estimate { n: points.len(), mean: beta, ci95: beta_ci };
    let sizes: Vec<SizeRow> = by_factor
        .iter()
        .map(|(&f, group)| SizeRow {
            factor: f,
            particles: mean_over(group, |r| r.particles as f64),
            length: Estimate::of(&lengths(group)),
            box_limited: box_limited(group),
            percolating: group.iter().map(|r| r.percolating()).sum(),
        })
        .collect();
    let groups: Vec<(&u64, &Vec<&Run>)> = by_factor.iter().collect();
    let (&f_max, largest) = *groups.last()?;
    let (below, largest_change) = match groups.len() {
        n if n >= 2 => (*groups[n - 2].0, unpaired(&lengths(groups[n - 2].1), &lengths(largest))),
        _ => (f_max, Estimate { n: 0, mean: f64::NAN, ci95: f64::NAN }),
    };
    let within = |e: &Estimate| e.ci95.is_finite() && e.mean.abs() <= e.ci95;
    let converged = within(&largest_change) && within(&beta);
    let walls = by_factor.get(&1).map_or(Estimate { n: 0, mean: f64::NAN, ci95: f64::NAN }, |x1| {
        paired(&respa_runs(runs, c), x1, |r| r.mean_length_um())
    });
    if converged {
        // The largest box with a CI (two seeds or more), so that the ranking has one.
        let (f_big, big) = groups.iter().rev().find(|(_, g)| g.len() >= 2).copied().unwrap_or((&f_max, largest));
        let change = paired_change(&respa_runs(runs, c), big);
        effects.push(Effect {
            concentration: c,
            explanation: Explanation::Box,
            what: format!(
                "periodic {f_big}× the particles against the paper's box with walls, paired over {} seeds",
                change.n
            ),
            change,
        });
    }
    let particles = mean_over(largest, |r| r.particles as f64);
    let next = largest
        .iter()
        .filter(|r| r.wall_time.is_finite() && r.particles > 0)
        .min_by(|a, b| (a.wall_time / a.particles as f64).total_cmp(&(b.wall_time / b.particles as f64)))
        .map(|fastest| {
            let factor = SIZE_SERIES.into_iter().find(|&f| f > f_max).unwrap_or(3 * f_max);
            let rate = fastest.wall_time / fastest.particles as f64;
            let next_particles = particles * factor as f64 / f_max as f64;
            NextSize {
                factor,
                particles: next_particles,
                hours: rate * next_particles / 3600.0,
                from_factor: f_max,
                from_wall_s: fastest.wall_time,
                from_particles: fastest.particles as f64,
                ms_per_particle: 1e3 * rate,
            }
        });
    Some(SizeLaw {
        c,
        beta,
        from: *groups[0].0,
        to: f_max,
        particles_from: sizes[0].particles,
        particles_to: particles,
        percolating: sizes.iter().map(|s| s.percolating).sum(),
        sizes,
        largest: largest_change,
        below,
        converged,
        walls,
        next,
    })
}

/// Finite size: the mean length at the paper's time against the particle count at equal
/// concentration, and the size law L ∝ N^β at each concentration; figure `finite-size.png`.
pub fn finite_size(inp: &Inputs) -> Result<Value, Error> {
    let (runs, t) = (inp.runs, inp.targets);
    let mine = |r: &&Run| {
        r.completed()
            && (r.experiment.starts_with("paper-finite-size-c") || r.experiment.ends_with("-x100"))
            && box_factor(&r.variant).is_some()
    };
    let sized: Vec<&Run> = runs.iter().filter(mine).collect();
    if sized.is_empty() {
        return Ok(context! { ran => false });
    }
    let mut effects = inp.effects.borrow_mut();
    let (mut c_col, mut f_col, mut p_col, mut n_col, mut m_col, mut ci_col, mut cap_col, mut perc_col, mut wall_col) =
        (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut threads_col = vec![];
    let mut series = vec![];
    let mut laws = vec![];
    // The x range of the data, over every concentration: the experiment's levels span it.
    let counts = sized.iter().map(|r| r.particles as f64).filter(|&n| n > 0.0);
    let x_range = (counts.clone().fold(f64::INFINITY, f64::min), counts.fold(0.0, f64::max));
    for (k, (&c, &exp)) in t.concentration.iter().zip(&t.experiment).enumerate() {
        let mut by_factor: BTreeMap<u64, Vec<&Run>> = BTreeMap::new();
        for r in sized.iter().filter(|r| same(r.concentration, c)) {
            by_factor.entry(box_factor(&r.variant).unwrap_or(0.0) as u64).or_default().push(r);
        }
        if by_factor.is_empty() {
            continue;
        }
        let (mut pts, mut errs, mut edge) = (vec![], vec![], vec![]);
        for (&f, group) in &by_factor {
            let e = Estimate::of(&lengths(group));
            let particles = mean_over(group, |r| r.particles as f64);
            c_col.push(c);
            f_col.push(f as f64);
            p_col.push(particles);
            n_col.push(group.len() as f64);
            m_col.push(e.mean);
            ci_col.push(e.ci95);
            cap_col.push(box_limited(group));
            perc_col.push(group.iter().map(|r| r.percolating() as f64).sum::<f64>());
            wall_col.push(mean_over(group, |r| r.wall_time));
            threads_col.push(thread_counts(group));
            pts.push((particles, e.mean));
            errs.push(e.ci95);
            edge.push((particles, 1e6 * mean_over(group, |r| r.box_extent)));
        }
        series.push(Series::markers(format!("{c} mg/ml"), pts, palette(k), 6).with_errors(errs));
        series.push(Series::line("", edge, palette(k)));
        series.push(level("", exp, x_range, palette(k)));
        laws.extend(size_law(runs, c, &by_factor, &mut effects));
    }
    let mut df = frame(vec![
        col("concentration_mg_per_ml", c_col),
        col("particle_factor", f_col),
        col("particles", p_col),
        col("seeds", n_col),
        col("mean_length_um", m_col),
        col("ci95_um", ci_col),
        col("box_limited_fraction", cap_col),
        col("percolating_aggregates", perc_col),
        col("wall_time_per_run_s", wall_col),
        scol("threads_per_run", threads_col),
    ])?;
    write(&mut df, &inp.tables, "finite_size")?;
    let shown = df.select([
        "concentration_mg_per_ml",
        "particle_factor",
        "particles",
        "seeds",
        "mean_length_um",
        "ci95_um",
        "box_limited_fraction",
        "percolating_aggregates",
    ])?;
    let table = markdown(
        &shown,
        &[
            "c (mg/ml)",
            "× particles",
            "particles",
            "seeds",
            "mean length (µm)",
            "± CI95",
            "box-limited",
            "percolating (all seeds)",
        ],
        &[3, 0, 0, 0, 1, 1, 3, 0],
    )?;
    chart(
        &inp.out.join("finite-size.png"),
        "Case 1: mean length against the particle count",
        ("particles (log)", "mean length (µm, log)"),
        &series,
        Legend::above_data(0.3),
        (Scale::Log, Scale::Log),
    )?;
    let end = scene_number_of(&sized, "integration.end_time");
    let (table_numerics, held, renumbered) = numerics_at_scale(runs)?;
    let values = context! {
        ran => true,
        table => table,
        end_ms => 1e3 * end,
        box_limited_percent => 100.0 * crate::analysis::aggregates::BOX_LIMITED_FRACTION,
        edge_exponent => 1.0 / 3.0,
        slow_every => scene_number_of(&sized, "integration.slow_every"),
        unconverged => laws.iter().filter(|l| !l.converged).map(|l| l.c).collect::<Vec<_>>(),
        laws => laws,
        numerics => context! {
            table => table_numerics,
            held => HELD_DRAG_X100,
            renumbered => RENUMBERED_X100,
            refactor_every => held,
            renumber_every => renumbered,
        },
    };
    Ok(values)
}

/// The distinct thread counts of a group's runs ("1", "1, 2"; "–" where not recorded).
fn thread_counts(group: &[&Run]) -> String {
    let mut counts: Vec<u64> = group.iter().filter(|r| r.threads.is_finite()).map(|r| r.threads as u64).collect();
    counts.sort_unstable();
    counts.dedup();
    let mut cells: Vec<String> = counts.iter().map(u64::to_string).collect();
    if group.iter().any(|r| !r.threads.is_finite()) {
        cells.push("–".into());
    }
    cells.join(", ")
}

/// The experiment of the 100× runs with the shielded drag held over each outer step: a change of
/// the numerics, not of the box, set against its every-step seed here and nowhere else.
pub const HELD_DRAG_X100: &str = "paper-box-c2.25-x100-drag-held";

/// The experiment of the drag-held 100× runs renumbered every 1 000 steps: set against the
/// drag-held run of the same seed, here and nowhere else.
pub const RENUMBERED_X100: &str = "paper-box-c2.25-x100-renumbered";

/// The 100× experiments that change the numerics, not the box (kept out of the box study).
pub const NUMERICAL_X100: [&str; 2] = [HELD_DRAG_X100, RENUMBERED_X100];

/// The experiments the finite-size section reads: the size series, the 100× boxes and the
/// paper's box under r-RESPA ([`respa_runs`]).
pub const FINITE_SIZE_EXPERIMENTS: [&str; 14] = [
    "paper-finite-size-c0.563",
    "paper-finite-size-c1.125",
    "paper-finite-size-c2.25",
    "paper-finite-size-c2.25-x10",
    "paper-finite-size-c2.25-x30",
    "paper-finite-size-c4.5",
    "paper-finite-size-c4.5-x10",
    "paper-finite-size-c4.5-x30",
    "paper-box-c2.25-x100",
    "paper-box-c4.5-x100",
    HELD_DRAG_X100,
    RENUMBERED_X100,
    "paper-magnetisation",
    "paper-sensitivity",
];

/// The 100× runs that change the numerics against the run of the same seed they change: the
/// drag held over each outer step against every step, and the renumbered drag-held run against
/// the drag-held one. Returns the Markdown table (empty without such runs), the drag's
/// `refactor_every` and the `renumber_every` of those runs.
fn numerics_at_scale(runs: &[Run]) -> Result<(String, f64, f64), Error> {
    fn done<'a>(runs: &'a [Run], experiment: &'a str) -> impl Iterator<Item = &'a Run> {
        runs.iter().filter(move |r| r.completed() && r.experiment == experiment)
    }
    let (mut what, mut against, mut seed, mut a_col, mut b_col, mut change) =
        (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut pair = |x: &Run, y: &Run| {
        let (a, b) = (x.mean_length_um(), y.mean_length_um());
        what.push(x.experiment.clone());
        against.push(y.experiment.clone());
        seed.push(x.seed);
        a_col.push(a);
        b_col.push(b);
        change.push(100.0 * (a / b - 1.0));
    };
    for h in done(runs, HELD_DRAG_X100) {
        let every = done(runs, "paper-box-c2.25-x100").find(|r| r.variant == "x100-periodic" && r.seed == h.seed);
        if let Some(every) = every {
            pair(h, every);
        }
    }
    for n in done(runs, RENUMBERED_X100) {
        if let Some(held) = done(runs, HELD_DRAG_X100).find(|h| h.seed == n.seed) {
            pair(n, held);
        }
    }
    let held: Vec<&Run> = done(runs, HELD_DRAG_X100).chain(done(runs, RENUMBERED_X100)).collect();
    let (refactor, renumber) =
        (scene_number_of(&held, "forces.drag.refactor_every"), scene_number_of(&held, "integration.renumber_every"));
    if what.is_empty() {
        return Ok((String::new(), refactor, renumber));
    }
    let df = frame(vec![
        scol("experiment", what.iter().map(|w| format!("`{w}`")).collect()),
        scol("against", against.iter().map(|w| format!("`{w}`")).collect()),
        ucol("seed", seed),
        col("mean length (µm)", a_col),
        col("against (µm)", b_col),
        col("change (%)", change),
    ])?;
    let table = markdown(
        &df,
        &["experiment", "against", "seed", "mean length (µm)", "against (µm)", "change (%)"],
        &[0, 0, 0, 0, 0, 1],
    )?;
    Ok((table, refactor, renumber))
}

/// Least-squares slope of ln L against ln t over the frames with `from ≤ t ≤ to` (s).
fn growth_exponent(r: &Run, from: f64, to: f64) -> f64 {
    let pts: Vec<(f64, f64)> = r
        .times
        .iter()
        .zip(&r.mean_length)
        .filter(|(&t, &l)| t >= from - 1e-12 && t <= to + 1e-12 && l > 0.0)
        .map(|(t, l)| (t.ln(), l.ln()))
        .collect();
    slope_ci95(&pts).0
}

/// Mean length of a run at time `t` (µm), from the first frame at or after it.
fn length_at(r: &Run, t: f64) -> f64 {
    r.times.iter().position(|&x| x >= t - 1e-12).map_or(f64::NAN, |k| r.mean_length[k] * 1e6)
}

/// One concentration's row of the growth table (NaN where the runs end at the paper's time).
struct GrowthRow {
    c: f64,
    seeds: f64,
    z_all: f64,
    z_all_ci: f64,
    z_early: f64,
    z_late: f64,
    l5: f64,
    lend: f64,
    growth: f64,
    growth_ci: f64,
    cap5: f64,
    capend: f64,
    reach: f64,
}

/// The growth row of the runs `here` at concentration `c` (experiment's mean `exp`, runs ending
/// at `end`), and the paired growth after the paper's time (%).
fn growth_row(here: &[&Run], c: f64, exp: f64, end: f64) -> (GrowthRow, Estimate) {
    let z = |a: f64, b: f64| Estimate::of(&here.iter().map(|r| growth_exponent(r, a, b)).collect::<Vec<_>>());
    // Quantities after the paper's time exist only for runs that go on past it.
    let later = |v: f64| if end > 1.1 * PAPER_TIME { v } else { f64::NAN };
    let zz = z(GROWTH_FROM, end);
    let g = Estimate::of(
        &here.iter().map(|r| 100.0 * (length_at(r, end) / length_at(r, PAPER_TIME) - 1.0)).collect::<Vec<_>>(),
    );
    let crossing = mean_series(here).iter().find(|p| p.1 >= exp).map_or(f64::NAN, |p| p.0 * 1e3);
    let cap_at = |time: f64| {
        Estimate::of(
            &here
                .iter()
                .map(|r| r.times.iter().position(|&x| x >= time - 1e-12).map_or(f64::NAN, |i| r.box_limited[i]))
                .collect::<Vec<_>>(),
        )
        .mean
    };
    let row = GrowthRow {
        c,
        seeds: here.len() as f64,
        z_all: zz.mean,
        z_all_ci: zz.ci95,
        z_early: z(GROWTH_FROM, PAPER_TIME).mean,
        z_late: later(z(PAPER_TIME, end).mean),
        l5: Estimate::of(&here.iter().map(|r| length_at(r, PAPER_TIME)).collect::<Vec<_>>()).mean,
        lend: later(Estimate::of(&here.iter().map(|r| length_at(r, end)).collect::<Vec<_>>()).mean),
        growth: later(g.mean),
        growth_ci: later(g.ci95),
        cap5: cap_at(PAPER_TIME),
        capend: later(cap_at(end)),
        reach: crossing,
    };
    (row, g)
}

/// The dipolar coupling constant λ = μ0 m²/(2π d³ kT) of one of `runs`' beads at room temperature
/// (m = M π d³/6), with the bead diameter (m).
fn dipolar_coupling(runs: &[&Run]) -> (f64, f64) {
    let d = scene_number_of(runs, "species.0.diameter");
    let m_field = runs.iter().map(|r| r.magnetisation).find(|m| m.is_finite()).unwrap_or(f64::NAN);
    let moment = m_field * std::f64::consts::PI * d.powi(3) / 6.0;
    let lambda = MU0 * moment * moment / (2.0 * std::f64::consts::PI * d.powi(3) * BOLTZMANN * ROOM_TEMPERATURE);
    (lambda, d)
}

/// Stopping time: L(t) to the runs' end on log–log axes and its growth exponent; figure
/// `length-vs-time.png`.
pub fn growth(inp: &Inputs) -> Result<Value, Error> {
    let (runs, t) = (inp.runs, inp.targets);
    let mut long: Vec<&Run> = runs.iter().filter(|r| r.experiment == "paper-long" && r.completed()).collect();
    let from_long = !long.is_empty();
    if long.is_empty() {
        long = runs.iter().filter(|r| TABLE3.contains(&r.experiment.as_str()) && r.completed()).collect();
    }
    if long.is_empty() {
        return Ok(context! { ran => false });
    }
    let end = long.iter().filter_map(|r| r.times.last().copied()).fold(f64::INFINITY, f64::min);
    let mut effects = inp.effects.borrow_mut();
    let mut rows: Vec<GrowthRow> = vec![];
    let mut series = vec![];
    for (k, (&c, &exp)) in t.concentration.iter().zip(&t.experiment).enumerate() {
        let here: Vec<&Run> = long.iter().copied().filter(|r| same(r.concentration, c)).collect();
        if here.is_empty() {
            continue;
        }
        let (row, paired) = growth_row(&here, c, exp, end);
        if end > 1.1 * PAPER_TIME {
            effects.push(Effect {
                concentration: c,
                explanation: Explanation::StoppingTime,
                what: format!("{:.0} ms against {:.0} ms, paired over {} seeds", end * 1e3, PAPER_TIME * 1e3, paired.n),
                change: paired,
            });
        }
        let pts: Vec<(f64, f64)> =
            mean_series(&here).iter().filter(|p| p.0 > 0.0).map(|&(t, l)| (t * 1e3, l)).collect();
        series.push(Series::line(format!("{c} mg/ml"), pts, palette(k)));
        series.push(level("", exp, (0.05, end * 1e3), palette(k)));
        rows.push(row);
    }
    let column = |f: fn(&GrowthRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    let mut df = frame(vec![
        col("concentration_mg_per_ml", column(|r| r.c)),
        col("seeds", column(|r| r.seeds)),
        col("z_1ms_to_end", column(|r| r.z_all)),
        col("z_ci95", column(|r| r.z_all_ci)),
        col("z_1_to_5ms", column(|r| r.z_early)),
        col("z_5ms_to_end", column(|r| r.z_late)),
        col("length_5ms_um", column(|r| r.l5)),
        col("length_end_um", column(|r| r.lend)),
        col("growth_after_5ms_percent", column(|r| r.growth)),
        col("growth_ci95_percent", column(|r| r.growth_ci)),
        col("box_limited_5ms", column(|r| r.cap5)),
        col("box_limited_end", column(|r| r.capend)),
        col("time_reaching_experiment_ms", column(|r| r.reach)),
    ])?;
    write(&mut df, &inp.tables, "growth")?;
    let (from, paper) = (format!("{:.0} ms", GROWTH_FROM * 1e3), format!("{:.0} ms", PAPER_TIME * 1e3));
    let headers = [
        "c (mg/ml)".to_string(),
        "seeds".into(),
        format!("z ({from}–end)"),
        "± CI95".into(),
        format!("z ({:.0}–{paper})", GROWTH_FROM * 1e3),
        format!("z ({paper}–end)"),
        format!("L at {paper} (µm)"),
        "L at end (µm)".into(),
        format!("growth after {paper} (%)"),
        "± CI95".into(),
        format!("box-limited at {paper}"),
        "at end".into(),
        "reaches experiment (ms)".into(),
    ];
    let table = markdown(
        &df,
        &headers.iter().map(String::as_str).collect::<Vec<_>>(),
        &[3, 0, 2, 2, 2, 2, 1, 1, 0, 0, 3, 3, 2],
    )?;
    let legend = Legend { position: SeriesLabelPosition::UpperLeft, headroom: 0.35 };
    chart(
        &inp.out.join("length-vs-time.png"),
        "Case 1: mean aggregate length against time",
        ("time (ms, log)", "mean length (µm, log)"),
        &series,
        legend,
        (Scale::Log, Scale::Log),
    )?;
    let (lambda, diameter) = dipolar_coupling(&long);
    Ok(context! {
        ran => true,
        long => from_long,
        table => table,
        end_ms => 1e3 * end,
        from_ms => 1e3 * GROWTH_FROM,
        paper_ms => 1e3 * PAPER_TIME,
        slow_every => scene_number_of(&long, "integration.slow_every"),
        literature => GROWTH_EXPONENTS,
        lambda => lambda,
        lambda_decade => lambda.log10().floor(),
        diameter_um => 1e6 * diameter,
        temperature => ROOM_TEMPERATURE,
    })
}

/// Log–log linear interpolation of x where the curve (x, y) (sorted by x) reaches `target`.
fn crossing(curve: &[(f64, f64)], target: f64) -> Option<f64> {
    curve.windows(2).find_map(|w| {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        let (lo, hi) = (y0.min(y1), y0.max(y1));
        (target >= lo && target <= hi && y0 != y1).then(|| {
            let s = (target.ln() - y0.ln()) / (y1.ln() - y0.ln());
            (x0.ln() + s * (x1.ln() - x0.ln())).exp()
        })
    })
}

/// The magnetisation at which the mean length meets `target`, and its bootstrap 95 % interval
/// (seeds resampled with replacement at every M; 2 000 resamples). A resample whose curve never
/// meets the target counts at the end of the range it falls off: 0 below the smallest M (the
/// target is shorter than every length), infinity above the largest; an interval bound there is
/// open-ended.
fn infer_m(points: &[(f64, Vec<f64>)], target: f64) -> (Option<f64>, f64, f64) {
    let curve: Vec<(f64, f64)> = points.iter().map(|(m, l)| (*m, summary(l).mean)).collect();
    let best = crossing(&curve, target);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20);
    let resamples = 2000;
    let mut found: Vec<f64> = (0..resamples)
        .map(|_| {
            let curve: Vec<(f64, f64)> = points
                .iter()
                .map(|(m, l)| (*m, (0..l.len()).map(|_| l[rng.random_range(0..l.len())]).sum::<f64>() / l.len() as f64))
                .collect();
            crossing(&curve, target).unwrap_or_else(|| {
                if curve.iter().all(|p| p.1 > target) {
                    0.0
                } else {
                    f64::INFINITY
                }
            })
        })
        .collect();
    found.sort_by(f64::total_cmp);
    let q = |p: f64| found[((p * found.len() as f64) as usize).min(found.len() - 1)];
    (best, q(0.025), q(0.975))
}

/// An interval bound of [`infer_m`] as text (`< M₀` or `> M₁` where it falls off the range).
fn bound(m: f64, (m0, m1): (f64, f64)) -> String {
    if m == 0.0 {
        format!("< {m0:.1e}")
    } else if m.is_infinite() {
        format!("> {m1:.1e}")
    } else {
        format!("{m:.2e}")
    }
}

/// One concentration's mean length at one magnetisation variant.
#[derive(serde::Serialize)]
struct AtVariant {
    c: f64,
    length: Estimate,
}

/// Magnetisation: the mean length against M at every concentration, the M that meets each
/// target, and how far the lengths collapse against t/τ, τ = μ/(μ0 M²); figures
/// `magnetisation.png` and `magnetisation-collapse.png`.
pub fn magnetisation(inp: &Inputs) -> Result<Value, Error> {
    let (runs, t) = (inp.runs, inp.targets);
    let sweep: Vec<&Run> = runs.iter().filter(|r| r.experiment == "paper-magnetisation" && r.completed()).collect();
    if sweep.is_empty() {
        return Ok(context! { ran => false });
    }
    let mut effects = inp.effects.borrow_mut();
    let mut variants: Vec<(String, f64)> = vec![];
    for r in &sweep {
        if !variants.iter().any(|v| v.0 == r.variant) {
            variants.push((r.variant.clone(), r.magnetisation));
        }
    }
    variants.sort_by(|a, b| a.1.total_cmp(&b.1));
    let m_of = |name: &str| variants.iter().find(|v| v.0 == name).map_or(f64::NAN, |v| v.1);
    let (linear_m, bulk_m) = (m_of(LINEAR_VARIANT), m_of(SATURATED_VARIANT));
    let (mut v_col, mut m_col, mut c_col, mut n_col, mut l_col, mut ci_col, mut cap_col) =
        (vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut inferred = Inferred::default();
    let (mut at_bulk, mut at_linear) = (vec![], vec![]);
    let mut series = vec![];
    for (k, (&c, (&exp, &paper))) in t.concentration.iter().zip(t.experiment.iter().zip(&t.paper)).enumerate() {
        let mut points = vec![];
        let (mut pts, mut errs) = (vec![], vec![]);
        for (name, m) in &variants {
            let here = select(runs, &["paper-magnetisation"], name, c);
            if here.is_empty() {
                continue;
            }
            let e = Estimate::of(&lengths(&here));
            v_col.push(name.clone());
            m_col.push(*m);
            c_col.push(c);
            n_col.push(here.len() as f64);
            l_col.push(e.mean);
            ci_col.push(e.ci95);
            cap_col.push(box_limited(&here));
            points.push((*m, lengths(&here), name.clone()));
            pts.push((*m, e.mean));
            errs.push(e.ci95);
            if name == SATURATED_VARIANT {
                at_bulk.push(AtVariant { c, length: e });
            }
            if name == LINEAR_VARIANT {
                at_linear.push(AtVariant { c, length: e });
            }
        }
        if points.is_empty() {
            continue;
        }
        inferred_rows(&mut inferred, &points, c, exp, paper);
        let (a, b) = (
            select(runs, &["paper-magnetisation"], LINEAR_VARIANT, c),
            select(runs, &["paper-magnetisation"], SATURATED_VARIANT, c),
        );
        if !a.is_empty() && !b.is_empty() {
            effects.push(Effect {
                concentration: c,
                explanation: Explanation::Magnetisation,
                what: format!("Ms = {bulk_m:.1e} A/m (bulk magnetite) against the linear law's {linear_m:.1e}, paired"),
                change: paired(&a, &b, |r| r.mean_length_um()),
            });
        }
        series.push(Series::markers(format!("{c} mg/ml"), pts, palette(k), 6).with_errors(errs));
        series.push(level("", exp, (variants[0].1, variants[variants.len() - 1].1), palette(k)));
    }
    let mut df = frame(vec![
        scol("variant", v_col),
        col("magnetisation_a_per_m", m_col),
        col("concentration_mg_per_ml", c_col),
        col("seeds", n_col),
        col("mean_length_um", l_col),
        col("ci95_um", ci_col),
        col("box_limited_fraction", cap_col),
    ])?;
    write(&mut df, &inp.tables, "magnetisation")?;
    let table = markdown(
        &df,
        &["variant", "M (A/m)", "c (mg/ml)", "seeds", "mean length (µm)", "± CI95", "box-limited"],
        &[0, 0, 3, 0, 1, 1, 3],
    )?;
    let mut inferred_df = frame(vec![
        col("concentration_mg_per_ml", inferred.c),
        scol("target", inferred.target),
        col("target_length_um", inferred.length),
        scol("magnetisation_a_per_m", inferred.m),
        scol("interval_95", inferred.interval),
    ])?;
    write(&mut inferred_df, &inp.tables, "magnetisation_inferred")?;
    let inferred_table = markdown(
        &inferred_df,
        &["c (mg/ml)", "target", "length (µm)", "M that meets it (A/m)", "95 % interval (bootstrap over seeds)"],
        &[3, 0, 0, 0, 0],
    )?;
    chart(
        &inp.out.join("magnetisation.png"),
        "Case 1: mean length against magnetisation",
        ("M (A/m, log)", "mean length (µm, log)"),
        &series,
        Legend { position: SeriesLabelPosition::UpperLeft, headroom: 0.5 },
        (Scale::Log, Scale::Log),
    )?;
    let saturation: Vec<f64> = variants
        .iter()
        .filter(|(name, _)| name.starts_with("ms-"))
        .filter_map(|(name, _)| name.strip_prefix("ms-")?.parse().ok())
        .collect();
    let field = scene_number_of(&sweep, "field.b0.0");
    Ok(context! {
        ran => true,
        table => table,
        inferred => inferred_table,
        end_ms => 1e3 * scene_number_of(&sweep, "integration.end_time"),
        slow_every => scene_number_of(&sweep, "integration.slow_every"),
        ms_from => saturation.iter().copied().fold(f64::INFINITY, f64::min),
        ms_to => saturation.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        fk_m => m_of("fk-4.8e5"),
        linear_m => linear_m,
        bulk_variant_m => bulk_m,
        bulk_ms => BULK_MAGNETITE_MS,
        linear_over_bulk => linear_m / BULK_MAGNETITE_MS,
        field_t => field,
        relative_permeability => scene_number_of(&sweep, "species.0.relative_permeability"),
        at_bulk => at_bulk,
        at_linear => at_linear,
        collapse => collapse(runs, &variants, inp.out)?,
    })
}

/// The inferred-M table's columns.
#[derive(Default)]
struct Inferred {
    c: Vec<f64>,
    target: Vec<String>,
    length: Vec<f64>,
    m: Vec<String>,
    interval: Vec<String>,
}

/// The rows of the inferred-M table at concentration `c`: the saturation-cap curve of `points`
/// (magnetisation, the seeds' lengths, variant) met at the paper's and the experiment's means; the
/// Fröhlich–Kennelly point is another law, shown but not interpolated through.
fn inferred_rows(rows: &mut Inferred, points: &[(f64, Vec<f64>, String)], c: f64, exp: f64, paper: f64) {
    let by_m: Vec<(f64, Vec<f64>)> = {
        let mut p: Vec<(f64, Vec<f64>)> =
            points.iter().filter(|(_, _, name)| !name.starts_with("fk-")).map(|(m, l, _)| (*m, l.clone())).collect();
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p
    };
    for (label, target) in [("paper simulation", paper), ("experiment", exp)] {
        let (best, lo, hi) = infer_m(&by_m, target);
        let range = (by_m[0].0, by_m[by_m.len() - 1].0);
        let below = by_m.iter().all(|p| summary(&p.1).mean > target);
        let cell = best.map_or_else(
            || if below { format!("below {:.1e}", range.0) } else { format!("above {:.1e}", range.1) },
            |m| format!("{m:.2e}"),
        );
        rows.c.push(c);
        rows.target.push(label.into());
        rows.length.push(target);
        rows.m.push(cell);
        rows.interval.push(format!("{} to {}", bound(lo, range), bound(hi, range)));
    }
}

/// Two neighbouring magnetisations' curves against t/τ: the mean distance between them over the
/// t/τ both cover (%), NaN without a common range.
#[derive(serde::Serialize)]
struct Overlap {
    m_a: f64,
    m_b: f64,
    percent: f64,
    from: f64,
    to: f64,
}

/// L(t) of each magnetisation at [`COLLAPSE_CONCENTRATION`] against t/τ, τ = μ/(μ0 M²): the
/// overdamped time for dipoles to close a gap of one diameter, up to a constant (the dipole force
/// ∝ μ0 M² d², the drag ∝ μ d, the distance ∝ d). Writes `magnetisation-collapse.png`.
fn collapse(runs: &[Run], variants: &[(String, f64)], out: &Path) -> Result<Value, Error> {
    let c = COLLAPSE_CONCENTRATION;
    let mut curves: Vec<(f64, Vec<(f64, f64)>)> = vec![];
    let mut series = vec![];
    for (k, (name, m)) in variants.iter().enumerate() {
        let here = select(runs, &["paper-magnetisation"], name, c);
        let Some(first) = here.first() else { continue };
        let tau = first.viscosity / (MU0 * m * m);
        let pts: Vec<(f64, f64)> =
            mean_series(&here).into_iter().filter(|p| p.0 > 0.0).map(|(t, l)| (t / tau, l)).collect();
        if pts.len() < 2 {
            continue;
        }
        series.push(Series::line(format!("{name}: M = {m:.2e} A/m"), pts.clone(), palette(k)));
        curves.push((*m, pts));
    }
    if curves.len() < 2 {
        return Ok(context! { ran => false, c => c });
    }
    // Neighbouring magnetisations: mean |ln(L_a/L_b)| over the t/τ both cover.
    let mut overlaps = vec![];
    for w in curves.windows(2) {
        let (a, b) = (&w[0].1, &w[1].1);
        let (lo, hi) = (a[0].0.max(b[0].0), a[a.len() - 1].0.min(b[b.len() - 1].0));
        let at = |curve: &[(f64, f64)], x: f64| -> f64 {
            let k = curve.iter().position(|p| p.0 >= x).unwrap_or(curve.len() - 1).max(1);
            let ((x0, y0), (x1, y1)) = (curve[k - 1], curve[k]);
            (y0.ln() + (x.ln() - x0.ln()) / (x1.ln() - x0.ln()) * (y1.ln() - y0.ln())).exp()
        };
        let percent = if lo < hi {
            let xs: Vec<f64> = (0..=20).map(|k| lo * (hi / lo).powf(k as f64 / 20.0)).collect();
            100.0 * (xs.iter().map(|&x| (at(a, x) / at(b, x)).ln().abs()).sum::<f64>() / xs.len() as f64).exp_m1()
        } else {
            f64::NAN
        };
        overlaps.push(Overlap { m_a: w[0].0, m_b: w[1].0, percent, from: lo, to: hi });
    }
    chart(
        &out.join("magnetisation-collapse.png"),
        &format!("Case 1, {c} mg/ml: mean length against t/τ, τ = μ/(μ0 M²)"),
        ("t/τ (log)", "mean length (µm, log)"),
        &series,
        SeriesLabelPosition::UpperLeft,
        (Scale::Log, Scale::Log),
    )?;
    let largest = overlaps.iter().map(|o| o.percent).filter(|p| p.is_finite()).fold(f64::NAN, f64::max);
    Ok(context! { ran => true, c => c, overlaps => overlaps, largest => largest })
}

/// The measures of the measurement table, by name (as its column headers give them).
const MEASURES: [&str; 6] = ["3-D, all", "3-D, 2+", "projected, all", "projected, 2+", "image, all", "image, 2+"];

/// The experiment's length measurement emulated on the Table 3 runs' last frames.
pub fn measurement(inp: &Inputs) -> Result<Value, Error> {
    let (runs, t) = (inp.runs, inp.targets);
    let mut effects = inp.effects.borrow_mut();
    let mut table: Vec<Vec<Estimate>> = vec![];
    let mut done = vec![];
    let mut unimaged = 0;
    let mut imaged: Vec<&Run> = vec![];
    for (&c, &exp) in t.concentration.iter().zip(&t.experiment) {
        // The runs imaged where their trajectories were read (here, or where a digest was made).
        let (here, missing): (Vec<&Run>, Vec<&Run>) = table3_runs(runs, c).into_iter().partition(|r| r.image.is_some());
        unimaged += missing.len();
        if here.is_empty() {
            continue;
        }
        let per_run: Vec<[f64; 6]> = here.iter().map(|r| measures(r)).collect();
        let column = |k: usize| Estimate::of(&per_run.iter().map(|m| m[k]).collect::<Vec<_>>());
        table.push((0..6).map(column).collect());
        done.push((c, exp, here.len()));
        let change = Estimate::of(&per_run.iter().map(|m| 100.0 * (m[2] / m[0] - 1.0)).collect::<Vec<_>>());
        effects.push(Effect {
            concentration: c,
            explanation: Explanation::Measurement,
            what: "each run's mean projected MajorAxisLength against its mean 3-D length, mean over runs".into(),
            change,
        });
        imaged.extend(here);
    }
    if done.is_empty() {
        return Ok(context! { ran => false, unimaged => unimaged });
    }
    let mut columns = vec![
        col("concentration_mg_per_ml", done.iter().map(|d| d.0).collect()),
        col("runs", done.iter().map(|d| d.2 as f64).collect()),
    ];
    let mut cells = vec![
        col("concentration_mg_per_ml", done.iter().map(|d| d.0).collect()),
        ucol("runs", done.iter().map(|d| d.2 as u64).collect()),
    ];
    for (k, name) in MEASURES.iter().enumerate() {
        let key = name.replace([',', '+'], "").replace(' ', "_").replace("__", "_");
        columns.push(col(&format!("{key}_um"), table.iter().map(|row| row[k].mean).collect()));
        columns.push(col(&format!("{key}_ci95_um"), table.iter().map(|row| row[k].ci95).collect()));
        cells.push(scol(&key, table.iter().map(|row| row[k].cell(1)).collect()));
    }
    columns.push(col("experiment_um", done.iter().map(|d| d.1).collect()));
    cells.push(col("experiment_um", done.iter().map(|d| d.1).collect()));
    let mut df = frame(columns)?;
    write(&mut df, &inp.tables, "measurement")?;
    let headers: Vec<&str> = ["c (mg/ml)", "runs"].into_iter().chain(MEASURES).chain(["experiment"]).collect();
    let md = markdown(&frame(cells)?, &headers, &[3, 0, 1, 1, 1, 1, 1, 1, 0])?;
    let imaging = crate::report::runs::IMAGING;
    Ok(context! {
        ran => true,
        table => md,
        unimaged => unimaged,
        paper_ms => 1e3 * scene_number_of(&imaged, "integration.end_time"),
        pixel_um => 1e6 * imaging.pixel,
        // MajorAxisLength of a long straight chain over n d.
        chain_limit => crate::analysis::image::chain_major_axis(1_000_000, 1.0) / 1e6,
    })
}

/// The six measures of one run's last frame (µm): 3-D, projected and image lengths, each over
/// all aggregates and over those of two or more particles.
fn measures(r: &Run) -> [f64; 6] {
    let m = |v: Vec<f64>| crate::report::runs::mean_um(&v);
    let finite = || r.last.iter().filter(|a| !a.percolating);
    let [projected, projected_2, image, image_2] = r.image.unwrap_or([f64::NAN; 4]);
    [
        m(finite().map(|a| a.length).collect()),
        m(finite().filter(|a| a.size > 1).map(|a| a.length).collect()),
        projected,
        projected_2,
        image,
        image_2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_interpolates_log_linearly_and_misses_outside() {
        let curve = [(1e5, 50.0), (4e5, 200.0)];
        // L ∝ M on this segment: L = 100 at M = 2e5.
        assert!((crossing(&curve, 100.0).unwrap() / 2e5 - 1.0).abs() < 1e-12);
        assert!(crossing(&curve, 300.0).is_none());
    }

    #[test]
    fn growth_exponent_recovers_a_power_law() {
        let times: Vec<f64> = (1..=100).map(|k| k as f64 * 2e-4).collect();
        let mean_length = times.iter().map(|t: &f64| 1e-5 * (t / 1e-3).powf(0.6)).collect();
        let run = Run { times, mean_length, ..Default::default() };
        assert!((growth_exponent(&run, 1e-3, 2e-2) - 0.6).abs() < 1e-12);
    }
}
