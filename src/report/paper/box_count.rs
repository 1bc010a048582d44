//! Walls and particle count: periodic faces and larger boxes against the paper's.

use super::convergence;
use super::{mean, Inputs};
use crate::analysis::stats::ci95_half_width;
use crate::plot::{category_panels, palette, BarGroup, BarPanel, Mark};
use crate::report::runs::Run;
use crate::report::tables::{col, floats, frame, markdown, same, scol, ucol, write};
use minijinja::{context, Value};
use std::collections::BTreeMap;

type Error = Box<dyn std::error::Error>;

/// The experiments the section reads: the box study and the paper's box under r-RESPA.
pub const EXPERIMENTS: [&str; 6] = [
    "paper-box-c2.25",
    "paper-box-c4.5",
    "paper-box-c2.25-x100",
    "paper-box-c4.5-x100",
    "paper-magnetisation",
    "paper-sensitivity",
];

const PAPER_BOX: &str = "walls, paper's box";

/// Walls and particle count (`box-and-count.png`): the paper's walled box against periodic side
/// faces and 10× (100×) the particles at equal concentration, the same seeds under r-RESPA; the
/// changes paired by seed.
pub fn box_count(inp: &Inputs) -> Result<Value, Error> {
    let (runs, paper) = (inp.runs, inp.paper);
    let in_box_study = |r: &Run| {
        r.experiment.starts_with("paper-box") && !convergence::NUMERICAL_X100.contains(&r.experiment.as_str())
    };
    let box_runs: Vec<&Run> = runs.iter().filter(|r| in_box_study(r) && r.completed()).collect();
    if box_runs.is_empty() {
        return Ok(context! { ran => false });
    }
    let conc = floats(&paper.table3, "concentration_mg_per_ml")?;
    let exp = floats(&paper.table3, "exp_mean_length_um")?;
    let (mut c_col, mut v_col, mut n_col, mut p_col, mut m_col, mut ci_col, mut cap_col, mut e_col) =
        (vec![], vec![], vec![], vec![], vec![], vec![], vec![], vec![]);
    let (mut d_c, mut d_v, mut d_n, mut d_m, mut d_ci, mut d_longer) = (vec![], vec![], vec![], vec![], vec![], vec![]);
    let mut panels = vec![];
    let mut studied = vec![];
    for (k, &c) in conc.iter().enumerate() {
        let mut groups: BTreeMap<String, Vec<&Run>> = BTreeMap::new();
        for r in box_runs.iter().filter(|r| same(r.concentration, c)) {
            groups.entry(r.variant.clone()).or_default().push(r);
        }
        if groups.is_empty() {
            continue;
        }
        studied.push(c);
        // The paper's box under the same integrator (r-RESPA) and seeds.
        let seeds: Vec<u64> = groups.values().flatten().map(|r| r.seed).collect();
        groups.insert(
            PAPER_BOX.into(),
            convergence::respa_runs(runs, c).into_iter().filter(|r| seeds.contains(&r.seed)).collect(),
        );
        // The figure: a mean with its CI95 where a group has three seeds or more, else each seed.
        let few = groups.values().filter(|g| g.len() < FEW_SEEDS).map(Vec::len).max().unwrap_or(0);
        let mut cats = vec![];
        let (mut means, mut errs) = (vec![], vec![]);
        let mut each: Vec<Vec<f64>> = vec![vec![]; few];
        for (variant, group) in &groups {
            let m: Vec<f64> = group.iter().map(|r| r.mean_length_um()).collect();
            c_col.push(c);
            v_col.push(variant.clone());
            n_col.push(group.len() as u64);
            p_col.push(mean(&group.iter().map(|r| r.particles as f64).collect::<Vec<_>>()));
            m_col.push(mean(&m));
            ci_col.push(ci95_half_width(&m));
            cap_col.push(mean(&group.iter().map(|r| r.box_limited_fraction()).collect::<Vec<_>>()));
            e_col.push(exp[k]);
            cats.push(format!("{variant} (n = {})", group.len()));
            let enough = group.len() >= FEW_SEEDS;
            means.push(if enough { mean(&m) } else { f64::NAN });
            errs.push(if enough { ci95_half_width(&m) } else { f64::NAN });
            for (j, seed_values) in each.iter_mut().enumerate() {
                seed_values.push(if enough { f64::NAN } else { m.get(j).copied().unwrap_or(f64::NAN) });
            }
        }
        // Each larger or periodic box against the paper's, seed by seed.
        let paper_box = &groups[PAPER_BOX];
        for (variant, group) in groups.iter().filter(|(v, _)| v.as_str() != PAPER_BOX) {
            let d = convergence::paired_change(paper_box, group);
            if d.n == 0 {
                continue;
            }
            let longer = group
                .iter()
                .filter(|r| paper_box.iter().any(|w| w.seed == r.seed && r.mean_length_um() > w.mean_length_um()))
                .count();
            d_c.push(c);
            d_v.push(variant.clone());
            d_n.push(d.n as u64);
            d_m.push(d.mean);
            d_ci.push(d.ci95);
            d_longer.push(longer as u64);
        }
        cats.push("experiment".into());
        means.push(exp[k]);
        errs.push(f64::NAN);
        for seed_values in &mut each {
            seed_values.push(f64::NAN);
        }
        let mut bar_groups =
            vec![BarGroup { label: "mean, CI95 over seeds".into(), color: palette(1), values: means, errors: errs }];
        for (j, values) in each.into_iter().enumerate() {
            let label = if j == 0 { format!("each seed (fewer than {FEW_SEEDS})") } else { String::new() };
            bar_groups.push(BarGroup { label, color: palette(0), values, errors: vec![] });
        }
        panels.push(BarPanel {
            title: format!("{c} mg/ml"),
            y_label: "mean length (µm)".into(),
            categories: cats,
            groups: bar_groups,
        });
    }
    let mut df = frame(vec![
        col("concentration_mg_per_ml", c_col),
        scol("domain", v_col),
        ucol("runs", n_col.clone()),
        col("particles", p_col),
        col("mean_length_um", m_col),
        col("ci95_um", ci_col),
        col("box_limited_fraction", cap_col),
        col("experiment_mean_um", e_col),
    ])?;
    write(&mut df, &inp.tables, "box_and_count")?;
    let table = markdown(
        &df,
        &["c (mg/ml)", "domain", "runs", "particles", "mean length (µm)", "± CI95", "box-limited", "experiment (µm)"],
        &[3, 0, 0, 0, 1, 1, 3, 0],
    )?;
    let mut changes = frame(vec![
        col("concentration_mg_per_ml", d_c),
        scol("domain", d_v),
        ucol("paired_seeds", d_n),
        col("change_percent", d_m),
        col("ci95_percent", d_ci),
        ucol("longer_in_seeds", d_longer),
    ])?;
    write(&mut changes, &inp.tables, "box_and_count_paired")?;
    let changes_table = markdown(
        &changes,
        &["c (mg/ml)", "domain", "paired seeds", "change (%)", "± CI95", "longer in (seeds)"],
        &[3, 0, 0, 1, 1, 0],
    )?;
    category_panels(
        &inp.out.join("box-and-count.png"),
        "Case 1: the walls and the particle count",
        &panels,
        2,
        (760, 460),
        Mark::Dots,
    )?;
    let respa = box_runs.iter().map(|r| convergence::scene_number(r, "integration.slow_every")).find(|x| x.is_finite());
    Ok(context! {
        ran => true,
        table => table,
        changes => changes_table,
        concentrations => studied,
        paper_particles => floats(&paper.table3, "particles")?,
        slow_every => respa.unwrap_or(f64::NAN),
        few_seeds => FEW_SEEDS,
        min_seeds => n_col.iter().copied().min().unwrap_or(0),
    })
}

/// Groups with fewer seeds than this are drawn seed by seed, without a CI95.
const FEW_SEEDS: usize = 3;
