//! Pictures of particles to scale: the panels the chain and case-2 figures are drawn from.

use crate::core::state::Vec3;
use crate::io::trajectory::Trajectory;
use crate::report::runs::Run;
use plotters::prelude::*;
use std::path::Path;

type Error = Box<dyn std::error::Error>;

pub(crate) const GREEN: RGBColor = RGBColor(30, 150, 60);
pub(crate) const RED: RGBColor = RGBColor(200, 30, 30);

/// Positions of frames `frames` (indices) and the radii and box of a trajectory.
/// Positions per frame, radii, box, times.
pub(crate) type Frames = (Vec<Vec<Vec3>>, Vec<f64>, crate::core::domain::Domain, Vec<f64>);

pub(crate) fn read(file: &Path, frames: &[usize]) -> Result<Frames, Error> {
    let t = Trajectory::open(file)?;
    let reader = crate::analysis::trajectory::FrameReader::new(&t)?;
    let positions = frames.iter().map(|&k| t.frame_vectors("position", k)).collect::<Result<Vec<_>, _>>()?;
    Ok((positions, reader.radius().to_vec(), reader.domain().clone(), reader.times.clone()))
}

/// Azimuth and elevation of [`view`] (degrees).
pub(crate) const VIEW_DEG: (f64, f64) = (-30.0, 25.0);

/// An orthographic view from azimuth [`VIEW_DEG`].0 and elevation [`VIEW_DEG`].1 (x, the field,
/// runs across).
pub(crate) fn view(p: &Vec3) -> (f64, f64) {
    let (phi, eps) = (VIEW_DEG.0.to_radians(), VIEW_DEG.1.to_radians());
    (p.x * phi.cos() - p.y * phi.sin(), (p.x * phi.sin() + p.y * phi.cos()) * eps.sin() + p.z * eps.cos())
}

/// One panel: particles as circles of their radius (to scale) in a projection, with optional
/// box edges, drawn over `area`.
pub(crate) struct Panel<'a> {
    pub(crate) title: String,
    pub(crate) layers: Vec<(&'a [Vec3], RGBColor)>,
    pub(crate) radius: &'a [f64],
    pub(crate) edges: Vec<((f64, f64), (f64, f64))>,
    pub(crate) project: &'a dyn Fn(&Vec3) -> (f64, f64),
    pub(crate) labels: (&'a str, &'a str),
}

pub(crate) fn draw_panel(
    area: &DrawingArea<BitMapBackend, plotters::coord::Shift>,
    panel: &Panel,
) -> Result<(), Error> {
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
pub(crate) fn box_edges(
    d: &crate::core::domain::Domain,
    project: &dyn Fn(&Vec3) -> (f64, f64),
) -> Vec<((f64, f64), (f64, f64))> {
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

/// The times of the paper's case-2 figure (s).
pub(crate) const CASE2_FIGURE_TIMES: [f64; 4] = [0.12, 0.51, 0.94, 1.25];

/// The paper's case-2 figure from `r`: starting positions (red) and the positions nearest the
/// times of [`CASE2_FIGURE_TIMES`] (green), x–y, to scale in its box (`case2-positions.png`).
/// Returns the stored times drawn (s) and the box's length along x (µm).
pub(crate) fn case2_positions(r: &Run, out: &Path) -> Result<(Vec<f64>, f64), Error> {
    let frames: Vec<usize> = CASE2_FIGURE_TIMES
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
        &format!("Case 2, seed {}: starting positions (red) and positions at time t (green), gradient along x", r.seed),
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
    Ok((frames.iter().map(|&k| stored[k]).collect(), (domain.hi.x - domain.lo.x) * 1e6))
}
