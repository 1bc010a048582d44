//! Writes `contact-verification.md` and its figures from the outcomes of `verify contacts`.

use super::contact_cases::{
    relative, Case, Geometry, Metrics, Outcome, DENSITY, DIAMETER, DT, FRAME_STEPS, FRICTION, OBLIQUE_RESTITUTION,
    POISSON, RESTITUTIONS, SOURCE, WALL_SPEED, YOUNGS,
};
use crate::plot::{engine_colour, line_chart, Series};
use crate::reference::lammps::tsuji_alpha;
use crate::reference::Engine;
use crate::report::template::render;
use minijinja::context;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Targets against LIGGGHTS: largest |magdem/LIGGGHTS − 1| on normal and on tangential quantities.
pub const TARGET_NORMAL: f64 = 0.005;
pub const TARGET_TANGENTIAL: f64 = 0.01;

/// The written report and the numbers `magdem verify contacts` prints.
pub struct Report {
    pub markdown: String,
    pub figures: Vec<PathBuf>,
    /// Largest |magdem/LIGGGHTS − 1| over normal and tangential quantities.
    pub worst_normal: f64,
    pub worst_tangential: f64,
}

/// magdem draws lines; LIGGGHTS large circles, LAMMPS small ones, so coinciding points stay visible.
fn marker_size(engine: &str) -> Option<u32> {
    match engine {
        "liggghts" => Some(6),
        "lammps" => Some(3),
        _ => None,
    }
}

/// A compared quantity: name, whether normal (else tangential), value, closed form, scale for
/// near-zero comparisons.
struct Quantity {
    name: &'static str,
    normal: bool,
    get: fn(&Metrics) -> f64,
    closed: Option<f64>,
    scale: f64,
}

fn quantities(case: &Case) -> Vec<Quantity> {
    let (delta, t_c) = case.hertz();
    let elastic = case.restitution == 1.0;
    let speed = case.normal_speed.hypot(case.tangential_speed);
    let a = 0.5 * DIAMETER;
    let mut q = vec![Quantity {
        name: "restitution",
        normal: true,
        get: |m| m.restitution,
        closed: Some(case.restitution),
        scale: 1.0,
    }];
    let tangential = case.tangential_speed != 0.0 || case.spin != 0.0;
    if !tangential {
        q.push(Quantity {
            name: "duration (s)",
            normal: true,
            get: |m| m.duration,
            closed: elastic.then_some(t_c),
            scale: t_c,
        });
        q.push(Quantity {
            name: "max overlap (m)",
            normal: true,
            get: |m| m.max_overlap,
            closed: elastic.then_some(delta),
            scale: delta,
        });
    }
    if tangential {
        q.push(Quantity {
            name: "rebound v_t (m/s)",
            normal: false,
            get: |m| m.rebound_tangential,
            closed: None,
            scale: speed,
        });
        q.push(Quantity {
            name: "rebound ω_y (rad/s)",
            normal: false,
            get: |m| m.rebound_spin,
            closed: None,
            scale: speed / a,
        });
        if matches!(case.geometry, Geometry::Wall) && case.spin == 0.0 {
            q.push(Quantity {
                name: "rebound angle (°)",
                normal: false,
                get: |m| m.rebound_angle,
                closed: None,
                scale: 90.0,
            });
        }
    }
    q
}

fn sci(v: f64) -> String {
    if v.is_nan() {
        "–".into()
    } else if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e4) {
        format!("{v:.5e}")
    } else {
        format!("{v:.6}")
    }
}

fn pct(v: f64) -> String {
    if v.is_nan() {
        "–".into()
    } else {
        format!("{:+.4}%", 100.0 * v)
    }
}

/// Figure 1: force–overlap loops of the restitution cases; figure 2: rebound angle against
/// incident angle.
fn figures(dir: &Path, all: &[Outcome], names: &[&str]) -> Result<Vec<std::path::PathBuf>, Box<dyn std::error::Error>> {
    let mut figures = vec![];
    let mut series = vec![];
    let mut labelled: Vec<&str> = vec![];
    for o in all.iter().filter(|o| o.case.group.starts_with('3')) {
        let points: Vec<(f64, f64)> = o.force_overlap.iter().map(|&(d, f)| (d * 1e9, f * 1e6)).collect();
        let markers = marker_size(o.engine);
        let points = if markers.is_some() { points.iter().step_by(12).copied().collect() } else { points };
        let label = if labelled.contains(&o.engine) { String::new() } else { o.engine.to_string() };
        labelled.push(o.engine);
        series.push(Series { label, points, color: engine_colour(o.engine), markers, errors: vec![] });
    }
    let fig1 = dir.join("contact-force-overlap.png");
    let restitutions: Vec<String> = RESTITUTIONS.iter().map(|e| e.to_string()).collect();
    line_chart(
        &fig1,
        &format!("Normal force against overlap, sphere–sphere, e = {}", restitutions.join(", ")),
        "overlap δ (nm)",
        "normal force (µN)",
        &series,
    )?;
    figures.push(fig1);
    let mut series = vec![];
    for engine in std::iter::once("magdem").chain(names.iter().copied()) {
        let points: Vec<(f64, f64)> = all
            .iter()
            .filter(|o| o.engine == engine && o.case.group.starts_with('4'))
            .map(|o| (o.case.incident_angle(), o.metrics.rebound_angle))
            .collect();
        series.push(Series {
            label: engine.to_string(),
            points,
            color: engine_colour(engine),
            markers: marker_size(engine),
            errors: vec![],
        });
    }
    let fig2 = dir.join("contact-oblique.png");
    line_chart(
        &fig2,
        &format!("Oblique sphere–wall impact, {WALL_SPEED} m/s, e = {OBLIQUE_RESTITUTION}, μ = {FRICTION}"),
        "incident angle (°)",
        "rebound angle (°)",
        &series,
    )?;
    figures.push(fig2);
    Ok(figures)
}

/// Largest |Δ| per engine and kind (normal, tangential), and where the largest tangential one is.
#[derive(Default, Clone)]
struct Worst {
    normal: f64,
    tangential: f64,
    tangential_min: f64,
    tangential_case: String,
}

pub fn write(dir: &Path, all: &[Outcome], engines: &[Engine]) -> Result<Report, Box<dyn std::error::Error>> {
    let names: Vec<&str> = engines.iter().map(|e| e.name()).collect();
    let mut header = "| case | quantity | closed form | magdem |".to_string();
    let mut rule = "|---|---|---|---|".to_string();
    for n in &names {
        header += &format!(" {n} | Δ {n} |");
        rule += "---|---|";
    }
    let mut table = format!("{header}\n{rule}\n");
    let mut worst: Vec<Worst> =
        names.iter().map(|_| Worst { tangential_min: f64::INFINITY, ..Default::default() }).collect();
    let mut closed_worst = 0.0_f64;
    let mut csv = String::from("case,group,quantity,engine,value,closed_form\n");
    let case_names: Vec<String> = {
        let mut v: Vec<String> = all.iter().map(|o| o.case.name.clone()).collect();
        v.dedup();
        v
    };
    for name in &case_names {
        let runs: Vec<&Outcome> = all.iter().filter(|o| &o.case.name == name).collect();
        let case = &runs[0].case;
        let magdem = runs.iter().find(|o| o.engine == "magdem").expect("magdem ran every case");
        for q in quantities(case) {
            let mv = (q.get)(&magdem.metrics);
            if let Some(c) = q.closed {
                closed_worst = closed_worst.max(relative(mv, c, q.scale).abs());
            }
            let mut row =
                format!("| {} | {} | {} | {} |", case.name, q.name, q.closed.map_or("–".into(), sci), sci(mv));
            let _ = writeln!(
                csv,
                "\"{}\",\"{}\",\"{}\",magdem,{mv:e},{}",
                case.name,
                case.group,
                q.name,
                q.closed.map_or(String::new(), |c| format!("{c:e}"))
            );
            for (k, n) in names.iter().enumerate() {
                match runs.iter().find(|o| o.engine == *n) {
                    Some(o) => {
                        let rv = (q.get)(&o.metrics);
                        let d = relative(mv, rv, q.scale);
                        row += &format!(" {} | {} |", sci(rv), pct(d));
                        let _ = writeln!(csv, "\"{}\",\"{}\",\"{}\",{n},{rv:e},", case.name, case.group, q.name);
                        let w = &mut worst[k];
                        if q.normal {
                            w.normal = w.normal.max(d.abs());
                        } else {
                            w.tangential_min = w.tangential_min.min(d.abs());
                            if d.abs() > w.tangential {
                                w.tangential = d.abs();
                                w.tangential_case = format!("the {} of {}", q.name, case.name);
                            }
                        }
                    }
                    None => row += " – | – |",
                }
            }
            table += &row;
            table += "\n";
        }
    }
    std::fs::write(dir.join("contact-verification.csv"), csv)?;
    let figures = figures(dir, all, &names)?;
    let of = |engine: &str| {
        names.iter().position(|n| *n == engine).map(|k| {
            let w = &worst[k];
            context! {
                normal => 100.0 * w.normal,
                tangential => 100.0 * w.tangential,
                tangential_min => 100.0 * w.tangential_min,
                tangential_case => w.tangential_case.clone(),
            }
        })
    };
    let md = render(
        "verification/contacts.md",
        &context! {
            version => env!("CARGO_PKG_VERSION"),
            commit => env!("MAGDEM_GIT_COMMIT"),
            engines => names.clone(),
            source => SOURCE,
            cases => case_names.len(),
            material => context! {
                diameter_um => 1e6 * DIAMETER,
                youngs => YOUNGS,
                poisson => POISSON,
                friction => FRICTION,
                density => DENSITY,
            },
            dt => DT,
            frame_steps => FRAME_STEPS,
            targets => context! { normal => 100.0 * TARGET_NORMAL, tangential => 100.0 * TARGET_TANGENTIAL },
            closed_worst => 100.0 * closed_worst,
            liggghts => of("liggghts"),
            lammps => of("lammps"),
            table => table,
            restitutions => RESTITUTIONS.to_vec(),
            oblique => context! { speed => WALL_SPEED, restitution => OBLIQUE_RESTITUTION, friction => FRICTION },
            tsuji_at_one => tsuji_alpha(1.0),
        },
    )?;
    std::fs::write(dir.join("contact-verification.md"), &md)?;
    let at = |engine: &str| names.iter().position(|n| *n == engine).map(|k| worst[k].clone()).unwrap_or_default();
    let liggghts = at("liggghts");
    Ok(Report { markdown: md, figures, worst_normal: liggghts.normal, worst_tangential: liggghts.tangential })
}
