//! Writes `contact-verification.md` and its figures from the outcomes of `verify contacts`.

use super::contact_cases::{relative, Case, Geometry, Metrics, Outcome, DIAMETER, DT, FRAME_STEPS};
use crate::plot::{engine_colour, line_chart, Series};
use crate::reference::Engine;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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

/// The figures' captions and how to read the differences between the engines.
const READING: &str = concat!(
    "![Normal force against overlap](contact-force-overlap.png)\n\n",
    "Force–overlap loops of the restitution cases (line: magdem; large circles: LIGGGHTS; small circles: \
LAMMPS). The damping term is proportional to √δ and to the normal velocity, so each loop starts at zero \
force, is open, and encloses the dissipated energy; the lower the restitution, the wider the loop. The \
force turns attractive near separation because the viscous term is not clipped (LIGGGHTS' default).\n\n",
    "![Rebound angle against incident angle](contact-oblique.png)\n\n",
    "Rebound angle of the sphere's centre from the wall normal against the incident angle (constant speed \
0.1 m/s, e = 0.5, μ = 0.5).\n\n",
    "## Reading the differences\n\n",
    "- **magdem against LIGGGHTS**: the same contact law in both, so every quantity agrees to the last printed \
digit; the residual is floating-point rounding.\n",
    "- **LAMMPS, normal quantities**: agree once its inputs are mapped: the tsuji input is solved from \
α(e_in) = √5|β(e)|, and the wall's and unlike pairs' (E, ν) are solved so that LAMMPS' effective moduli equal \
magdem's E* and G* — the 2021 build forms a wall's E* as E/(2(1 − ν)) instead of E/(2(1 − ν²)), and its \
automatic mixing of unlike types is broken. For e = 1 magdem gives LAMMPS zero viscoelastic damping, because \
tsuji's polynomial is 3e-4, not 0, at e = 1 (it would cost the elastic cases 0.04% of restitution).\n",
    "- **LAMMPS, tangential quantities**: differ by several per cent up to a factor of several in the spin \
cases. The inputs match (same kt = 8G*a, same damping ratio); the Mindlin implementations do not: after \
projecting the shear history onto the new tangent plane LAMMPS rescales it to its old length (LIGGGHTS does \
not), and LAMMPS tests the Coulomb limit on the elastic plus damping force and keeps the damping part in the \
capped force and in the reset history, where LIGGGHTS tests the elastic part alone and applies no damping while \
sliding. The differences are largest where a contact passes between sliding and sticking (small incident \
angles, spin); which of the two causes dominates each case is not separated here.\n"
);

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
    line_chart(
        &fig1,
        "Normal force against overlap, sphere–sphere, e = 0.3, 0.5, 0.7, 0.9",
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
        "Oblique sphere–wall impact, 0.1 m/s, e = 0.5, μ = 0.5",
        "incident angle (°)",
        "rebound angle (°)",
        &series,
    )?;
    figures.push(fig2);
    Ok(figures)
}

pub fn write(dir: &Path, all: &[Outcome], engines: &[Engine]) -> Result<Report, Box<dyn std::error::Error>> {
    let mut md = String::new();
    let names: Vec<&str> = engines.iter().map(|e| e.name()).collect();
    let _ = writeln!(md, "# Contact cross-verification: magdem against LIGGGHTS and LAMMPS\n");
    let _ = writeln!(
        md,
        "Generated by `magdem verify contacts` (magdem {}, commit {}). Engines: magdem{}.\n",
        env!("CARGO_PKG_VERSION"),
        env!("MAGDEM_GIT_COMMIT"),
        names.iter().map(|n| format!(", {n}")).collect::<String>()
    );
    md += "The single-contact benchmark types of Chung & Ooi (2011) — elastic normal impact of equal spheres \
and against a wall, restitution, oblique impacts over a range of angles, impacts with spin, unequal \
sizes — with the paper's material (11 µm spheres, E = 1e9 Pa, ν = 0.5, μ = 0.5, ρ = 1087 kg/m³). \
Each case is one magdem scene; `magdem run` and `magdem run --engine liggghts|lammps` run it, all \
three write the same HDF5 schema, and one analysis reads the three files. Velocity Verlet in all \
three (LIGGGHTS/LAMMPS `nve/sphere`), ";
    let _ = writeln!(md, "dt = {DT:e} s, a frame every {FRAME_STEPS} steps; contact start and end are the linearly interpolated zero crossings of the overlap.\n");
    md += "Contact models: magdem's is LIGGGHTS' `hertz tangential history` with `coefficientRestitution` \
(formulas in `src/core/forces/contact.rs`). LAMMPS runs `pair_style granular hertz/material … tangential \
mindlin NULL x_t μ damping tsuji` with the tsuji input e_in solved from α(e_in) = √5 |β(e)| and \
x_t = 2√(G*/E*), which makes its damping equal to LIGGGHTS' by construction (`src/reference/deck.rs`). \
Walls are planes with the sphere's own material. Closed forms (elastic cases): \
δ = (15 m* v²/(16 E* √R*))^(2/5), t_c = 2.87 (m*²/(R* E*² v))^(1/5) (DESIGN.md §5).\n\n";
    md += "Δ columns: magdem / reference − 1 (for quantities near zero, the difference over the case's speed \
scale). Target: 0.5% on normal quantities, 1% on tangential ones against LIGGGHTS.\n\n";

    let mut header = "| case | quantity | closed form | magdem |".to_string();
    let mut rule = "|---|---|---|---|".to_string();
    for n in &names {
        header += &format!(" {n} | Δ {n} |");
        rule += "---|---|";
    }
    let _ = writeln!(md, "{header}\n{rule}");
    let (mut worst_normal, mut worst_tangential) = (0.0_f64, 0.0_f64);
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
            for n in &names {
                match runs.iter().find(|o| o.engine == *n) {
                    Some(o) => {
                        let rv = (q.get)(&o.metrics);
                        let d = relative(mv, rv, q.scale);
                        row += &format!(" {} | {} |", sci(rv), pct(d));
                        let _ = writeln!(csv, "\"{}\",\"{}\",\"{}\",{n},{rv:e},", case.name, case.group, q.name);
                        if *n == "liggghts" {
                            if q.normal {
                                worst_normal = worst_normal.max(d.abs());
                            } else {
                                worst_tangential = worst_tangential.max(d.abs());
                            }
                        }
                    }
                    None => row += " – | – |",
                }
            }
            let _ = writeln!(md, "{row}");
        }
    }
    std::fs::write(dir.join("contact-verification.csv"), csv)?;
    let _ = writeln!(
        md,
        "\nLargest |Δ| against LIGGGHTS: {:.4}% on normal quantities, {:.4}% on tangential ones.\n",
        100.0 * worst_normal,
        100.0 * worst_tangential
    );

    let figures = figures(dir, all, &names)?;
    md += READING;
    std::fs::write(dir.join("contact-verification.md"), &md)?;
    Ok(Report { markdown: md, figures, worst_normal, worst_tangential })
}
