//! The paper's picture figures, drawn from the runs: case-1 particles at t = 0 and at the end in
//! 3-D and on the imaging plane, case-2 positions at the paper's four times, the shielded
//! fraction A_eff/πa² against the angle to the motion (from magdem's own shielding code), and a
//! ParaView render of one case-1 run through its XDMF sidecar.

use super::runs::Run;
use crate::core::forces::shielding::shadow_area;
use crate::core::state::Vec3;
use crate::io::trajectory::Trajectory;
use crate::plot::{chart, palette, Scale, Series, SeriesLabelPosition};
use plotters::prelude::*;
use std::path::Path;

type Error = Box<dyn std::error::Error>;

const GREEN: RGBColor = RGBColor(30, 150, 60);
const RED: RGBColor = RGBColor(200, 30, 30);

/// Positions of frames `frames` (indices) and the radii and box of a trajectory.
/// Positions per frame, radii, box, times.
type Frames = (Vec<Vec<Vec3>>, Vec<f64>, crate::core::domain::Domain, Vec<f64>);

fn read(file: &Path, frames: &[usize]) -> Result<Frames, Error> {
    let t = Trajectory::open(file)?;
    let reader = crate::analysis::trajectory::FrameReader::new(&t)?;
    let positions = frames.iter().map(|&k| t.frame_vectors("position", k)).collect::<Result<Vec<_>, _>>()?;
    Ok((positions, reader.radius().to_vec(), reader.domain().clone(), reader.times.clone()))
}

/// An orthographic view from azimuth −30° and elevation 25° (x, the field, runs across).
fn view(p: &Vec3) -> (f64, f64) {
    let (phi, eps) = ((-30f64).to_radians(), 25f64.to_radians());
    (p.x * phi.cos() - p.y * phi.sin(), (p.x * phi.sin() + p.y * phi.cos()) * eps.sin() + p.z * eps.cos())
}

/// One panel: particles as circles of their radius (to scale) in a projection, with optional
/// box edges, drawn over `area`.
struct Panel<'a> {
    title: String,
    layers: Vec<(&'a [Vec3], RGBColor)>,
    radius: &'a [f64],
    edges: Vec<((f64, f64), (f64, f64))>,
    project: &'a dyn Fn(&Vec3) -> (f64, f64),
    labels: (&'a str, &'a str),
}

fn draw_panel(area: &DrawingArea<BitMapBackend, plotters::coord::Shift>, panel: &Panel) -> Result<(), Error> {
    let pts: Vec<(f64, f64)> = panel
        .layers
        .iter()
        .flat_map(|(x, _)| x.iter().map(|p| (panel.project)(p)))
        .chain(panel.edges.iter().flat_map(|e| [e.0, e.1]))
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in &pts {
        (x0, x1, y0, y1) = (x0.min(*x), x1.max(*x), y0.min(*y), y1.max(*y));
    }
    let pad = 0.04 * (x1 - x0).max(y1 - y0);
    // Equal scales on both axes, so that circles are circles.
    let (w, h) = area.dim_in_pixel();
    let (plot_w, plot_h) = (w as f64 - 90.0, h as f64 - 90.0);
    let per_px = ((x1 - x0 + 2.0 * pad) / plot_w).max((y1 - y0 + 2.0 * pad) / plot_h);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let (hx, hy) = (0.5 * plot_w * per_px, 0.5 * plot_h * per_px);
    let mut c = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d((cx - hx) * 1e6..(cx + hx) * 1e6, (cy - hy) * 1e6..(cy + hy) * 1e6)?;
    c.configure_mesh()
        .disable_mesh()
        .x_desc(panel.labels.0)
        .y_desc(panel.labels.1)
        .label_style(("sans-serif", 13))
        .draw()?;
    for (a, b) in &panel.edges {
        c.draw_series(std::iter::once(PathElement::new(
            vec![(a.0 * 1e6, a.1 * 1e6), (b.0 * 1e6, b.1 * 1e6)],
            BLACK.mix(0.6).stroke_width(1),
        )))?;
    }
    for (x, color) in &panel.layers {
        c.draw_series(x.iter().zip(panel.radius).map(|(p, &r)| {
            let (u, v) = (panel.project)(p);
            Circle::new((u * 1e6, v * 1e6), ((r / per_px).round() as i32).max(1), color.stroke_width(1))
        }))?;
    }
    Ok(())
}

/// The twelve edges of the box, projected.
fn box_edges(d: &crate::core::domain::Domain, project: &dyn Fn(&Vec3) -> (f64, f64)) -> Vec<((f64, f64), (f64, f64))> {
    let corner = |k: usize| {
        Vec3::new(
            if k & 1 == 0 { d.lo.x } else { d.hi.x },
            if k & 2 == 0 { d.lo.y } else { d.hi.y },
            if k & 4 == 0 { d.lo.z } else { d.hi.z },
        )
    };
    let mut edges = vec![];
    for a in 0..8 {
        for bit in [1, 2, 4] {
            if a & bit == 0 {
                edges.push((project(&corner(a)), project(&corner(a | bit))));
            }
        }
    }
    edges
}

/// The case-1 chain figure: every Table 3 seed-1 run at t = 0 (green) and at its end (red), in
/// 3-D (`chains-3d.png`) and on the imaging plane x–y (`chains-xy.png`). Returns the section.
pub fn chain_figures(runs: &[&Run], out: &Path) -> Result<String, Error> {
    if runs.is_empty() {
        return Ok(String::new());
    }
    for (name, three_d) in [("chains-3d.png", true), ("chains-xy.png", false)] {
        let path = out.join(name);
        let root = BitMapBackend::new(&path, (1400, 1250)).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, body) = root.split_vertically(50);
        let title = if three_d {
            "Case 1, seed 1: particles at t = 0 (green) and at 5 ms (red); field B along x; box edges in grey"
        } else {
            "Case 1, seed 1, the imaging plane x-y (the field along x): t = 0 (green) and 5 ms (red)"
        };
        top.titled(title, ("sans-serif", 22))?;
        for (area, r) in body.split_evenly((2, 2)).iter().zip(runs) {
            let (frames, radius, domain, times) = read(&r.file, &[0, r.times.len() - 1])?;
            let xy = |p: &Vec3| (p.x, p.y);
            let project: &dyn Fn(&Vec3) -> (f64, f64) = if three_d { &view } else { &xy };
            let edges = if three_d { box_edges(&domain, project) } else { box_edges(&domain, &xy) };
            let panel = Panel {
                title: format!(
                    "{} mg/ml, {} particles, t = {:.0} ms",
                    r.concentration,
                    radius.len(),
                    times[times.len() - 1] * 1e3
                ),
                layers: vec![(&frames[0], GREEN), (&frames[1], RED)],
                radius: &radius,
                edges,
                project,
                labels: if three_d { ("projected x (µm)", "projected height (µm)") } else { ("x (µm)", "y (µm)") },
            };
            draw_panel(area, &panel)?;
        }
        root.present()?;
    }
    Ok("## The paper's chain figure\n\nThe seed-1 Table 3 runs at t = 0 (green) and at 5 ms (red), circles of the particles' radius to scale: in 3-D \
        (orthographic, from azimuth −30° and elevation 25°; the field B along x runs across) and on the imaging plane x–y, \
        as a microscope looking along gravity would see them.\n\n![Chains in 3-D](chains-3d.png)\n\n![Chains on the imaging plane](chains-xy.png)\n\n"
        .into())
}

/// The case-2 figure: starting positions (red) and positions at 0.12, 0.51, 0.94 and 1.25 s
/// (green) of the seed-1 run, x–y, to scale in its box.
pub fn case2_figure(run: Option<&Run>, out: &Path) -> Result<String, Error> {
    let Some(r) = run else { return Ok(String::new()) };
    let times = [0.12, 0.51, 0.94, 1.25];
    let frames: Vec<usize> = times
        .iter()
        .map(|&t| {
            r.times.iter().enumerate().min_by(|a, b| (a.1 - t).abs().total_cmp(&(b.1 - t).abs())).map_or(0, |(k, _)| k)
        })
        .collect();
    let mut wanted = vec![0];
    wanted.extend(&frames);
    let (positions, radius, domain, stored) = read(&r.file, &wanted)?;
    let path = out.join("case2-positions.png");
    let root = BitMapBackend::new(&path, (1400, 1250)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, body) = root.split_vertically(50);
    top.titled(
        "Case 2, seed 1: starting positions (red) and positions at time t (green), gradient along x",
        ("sans-serif", 22),
    )?;
    let xy = |p: &Vec3| (p.x, p.y);
    for (k, area) in body.split_evenly((2, 2)).iter().enumerate() {
        let panel = Panel {
            title: format!("t = {:.2} s", stored[frames[k]]),
            layers: vec![(&positions[0], RED), (&positions[k + 1], GREEN)],
            radius: &radius,
            edges: box_edges(&domain, &xy),
            project: &xy,
            labels: ("x (µm)", "y (µm)"),
        };
        draw_panel(area, &panel)?;
    }
    root.present()?;
    Ok(format!(
        "The paper's case-2 figure from the seed-1 run: starting positions (red) and the positions at {} s (green), circles to \
         scale in the {:.0} µm box.\n\n![Case 2 positions](case2-positions.png)\n\n",
        frames.iter().map(|&k| format!("{:.2}", stored[k])).collect::<Vec<_>>().join(", "),
        (domain.hi.x - domain.lo.x) * 1e6
    ))
}

/// A_eff/πa² of a sphere behind a touching equal neighbour against the angle between their line
/// of centres and the motion, from [`shadow_area`] (the paper's Figs. 1–3 as a curve).
pub fn shielding_figure(out: &Path) -> Result<String, Error> {
    let a = 5.5e-6;
    let curve: Vec<(f64, f64)> = (0..=180)
        .map(|deg| {
            let theta = (deg as f64).to_radians();
            let offset = Vec3::new(theta.cos(), theta.sin(), 0.0) * 2.0 * a;
            (deg as f64, 1.0 - shadow_area(a, a, &offset, &Vec3::x()) / (std::f64::consts::PI * a * a))
        })
        .collect();
    let at = |deg: usize| curve[deg].1;
    chart(
        &out.join("shielding.png"),
        "The paper's A_eff: a sphere behind a touching neighbour",
        ("angle between the line of centres and the motion (degrees)", "A_eff / (π a²)"),
        &[Series::line("magdem's shielding (lens area of the projected circles)", curve.clone(), palette(1))],
        SeriesLabelPosition::LowerRight,
        (Scale::Linear, Scale::Linear),
    )?;
    Ok(format!(
        "## The A_eff geometry\n\nThe drag area the paper gives a sphere whose touching neighbour lies upstream at an angle θ between \
         their line of centres and the motion: A_eff = π a² minus the lens common to the two circles projected on the plane normal \
         to the motion (`core::forces::shielding`). A_eff/πa² = {:.3} at 0° (directly behind), {:.3} at 30°, {:.3} at 60°, \
         {:.3} at 90° and beyond (the neighbour no longer upstream). In Stokes flow two touching spheres moving along their line \
         of centres each feel about 0.645 of a lone sphere's drag (Stimson & Jeffery 1926): the paper's 0 at 0° is its model, \
         not hydrodynamics.\n\n![A_eff against the angle](shielding.png)\n\n",
        at(0),
        at(30),
        at(60),
        at(90)
    ))
}

/// A ParaView render (`io::export::render_last_frame`, through the run's XDMF sidecar) of `run`'s
/// last frame into `paraview-case1.png`. Where ParaView or Xvfb is absent or the render fails, an
/// earlier render is kept and the report says why no new one was made.
pub fn paraview_section(run: Option<&Run>, out: &Path) -> Result<String, Error> {
    let Some(r) = run else { return Ok(String::new()) };
    let png = out.join("paraview-case1.png");
    let xdmf = crate::io::export::write_xdmf(&r.file)?;
    use crate::io::export::RenderError;
    let kept = match crate::io::export::render_last_frame(&xdmf, &png) {
        Ok(()) => String::new(),
        Err(why) => {
            eprintln!("ParaView render of {}: {why}", r.id);
            let why = match why {
                RenderError::Missing(program) => format!("{program} is not installed here"),
                RenderError::Failed(_) => "the render failed here (the reason is on stderr)".into(),
            };
            if !png.exists() {
                return Ok(format!("## In ParaView\n\nNo picture: {why}.\n\n"));
            }
            format!(" The picture is an earlier render: {why}.")
        }
    };
    Ok(format!(
        "## In ParaView and OVITO\n\nEvery run writes an XDMF sidecar beside its HDF5 file (`OUT.xdmf`, referencing the datasets in place), \
         which ParaView opens (`paraview runs/…/RUN.xdmf`, or `pvpython`/`pvbatch` scripts); `magdem export RUN.h5 --format \
         lammps-dump` writes a LAMMPS dump that OVITO opens. `{}` at 5 ms, rendered by pvbatch with the script \
         `io::export::PARAVIEW_RENDER` (spheres of their radius coloured by the moment along x, seen along −z).{kept}\n\n\
         ![ParaView render](paraview-case1.png)\n\n",
        r.id
    ))
}
