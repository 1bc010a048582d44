//! Case 1's picture figures: the seed-1 runs' particles at the start and at the end (the paper's
//! chain figure) and a ParaView render of one of them.

use super::drawing::{box_edges, draw_panel, read, view, Panel, GREEN, RED, VIEW_DEG};
use super::{table3_ensemble, Inputs};
use crate::core::state::Vec3;
use crate::report::runs::Run;
use crate::report::tables::same;
use minijinja::{context, Value};
use plotters::prelude::*;

type Error = Box<dyn std::error::Error>;

/// The seed whose runs the pictures show.
const SEED: u64 = 1;

/// The runs of seed [`SEED`] of the Table 3 ensemble that have trajectories, by concentration.
fn pictured<'a>(inp: &Inputs<'a>) -> Vec<&'a Run> {
    let mut runs: Vec<&Run> =
        table3_ensemble(inp.runs).into_iter().filter(|r| r.seed == SEED && r.has_trajectory()).collect();
    runs.sort_by(|a, b| a.concentration.total_cmp(&b.concentration));
    runs
}

/// The case-1 chain figure: the seed-1 Table 3 runs at the start (green) and at their end (red),
/// in 3-D (`chains-3d.png`) and on the imaging plane x–y (`chains-xy.png`).
pub fn chains(inp: &Inputs) -> Result<Value, Error> {
    let runs = pictured(inp);
    if runs.is_empty() {
        return Ok(context! { run => false, seed => SEED });
    }
    let end_ms = runs.iter().filter_map(|r| r.times.last()).fold(f64::NAN, |a, &t| a.max(t)) * 1e3;
    for (name, three_d) in [("chains-3d.png", true), ("chains-xy.png", false)] {
        let path = inp.out.join(name);
        let root = BitMapBackend::new(&path, (1400, 1250)).into_drawing_area();
        root.fill(&WHITE)?;
        let (top, body) = root.split_vertically(50);
        let title = if three_d {
            format!("Case 1, seed {SEED}: particles at the start (green) and at {end_ms:.0} ms (red); field B along x; box edges in grey")
        } else {
            format!(
                "Case 1, seed 1, the imaging plane x-y (the field along x): the start (green) and {end_ms:.0} ms (red)"
            )
        };
        top.titled(&title, ("sans-serif", 22))?;
        for (area, r) in body.split_evenly((2, 2)).iter().zip(&runs) {
            let (frames, radius, domain, times) = read(&r.file, &[0, r.times.len() - 1])?;
            let xy = |p: &Vec3| (p.x, p.y);
            let project: &dyn Fn(&Vec3) -> (f64, f64) = if three_d { &view } else { &xy };
            let panel = Panel {
                title: format!(
                    "{} mg/ml, {} particles, t = {:.0} ms",
                    r.concentration,
                    radius.len(),
                    times[times.len() - 1] * 1e3
                ),
                layers: vec![(&frames[0], GREEN), (&frames[1], RED)],
                radius: &radius,
                edges: box_edges(&domain, project),
                project,
                labels: if three_d { ("projected x (µm)", "projected height (µm)") } else { ("x (µm)", "y (µm)") },
            };
            draw_panel(area, &panel)?;
        }
        root.present()?;
    }
    Ok(context! {
        run => true,
        seed => SEED,
        end_ms => end_ms,
        panels => runs.len().min(4),
        concentrations => runs.iter().take(4).map(|r| r.concentration).collect::<Vec<_>>(),
        azimuth_deg => VIEW_DEG.0,
        elevation_deg => VIEW_DEG.1,
    })
}

/// A ParaView render (`io::export::render_last_frame`, through the run's XDMF sidecar) of the last
/// frame of the seed-1 run at 2.25 mg/ml (else the first seed-1 run) into `paraview-case1.png`.
/// Where ParaView or Xvfb is absent or the render fails, an earlier render is kept and the
/// report says why no new one was made.
pub fn paraview(inp: &Inputs) -> Result<Value, Error> {
    use crate::io::export::RenderError;
    let runs = pictured(inp);
    let Some(r) = runs.iter().copied().find(|r| same(r.concentration, 2.25)).or(runs.first().copied()) else {
        return Ok(context! { run => false, seed => SEED });
    };
    let png = inp.out.join("paraview-case1.png");
    let xdmf = crate::io::export::write_xdmf(&r.file)?;
    // Whether a new picture was made, and which program is missing when none was.
    let (rendered, missing) = match crate::io::export::render_last_frame(&xdmf, &png) {
        Ok(()) => (true, None),
        Err(why) => {
            eprintln!("ParaView render of {}: {why}", r.id);
            match why {
                RenderError::Missing(program) => (false, Some(program)),
                RenderError::Failed(_) => (false, None),
            }
        }
    };
    Ok(context! {
        run => true,
        seed => SEED,
        id => r.id.clone(),
        concentration => r.concentration,
        end_ms => r.times.last().map_or(f64::NAN, |t| t * 1e3),
        rendered => rendered,
        missing => missing,
        picture => png.exists(),
    })
}
