//! Aggregates of a stored trajectory frame (the trajectory carries its scene, so the domain and
//! field direction come with it).

use super::aggregates::{aggregates, Aggregate, Frame};
use crate::io::trajectory::Trajectory;
use crate::scene::Scene;

/// Aggregates of frame `k` (negative: from the end) of `t` at `gap_tolerance`.
pub fn frame_aggregates(t: &Trajectory, k: isize, gap_tolerance: f64) -> Result<(f64, Vec<Aggregate>), Box<dyn std::error::Error>> {
    let scene = Scene::parse(&t.scene_text()?, &t.path)?;
    let frames = t.frames()? as isize;
    let k = if k < 0 { frames + k } else { k };
    if !(0..frames).contains(&k) {
        return Err(format!("frame {k} outside 0..{frames}").into());
    }
    let k = k as usize;
    let position = t.frame_vectors("position", k)?;
    let velocity = t.frame_vectors("velocity", k)?;
    let radius: Vec<f64> = t.file.dataset("particles/radius")?.read_raw()?;
    let mass: Vec<f64> = t.file.dataset("particles/mass")?.read_raw()?;
    let field = scene.spec.field.as_ref().map_or(nalgebra::Vector3::x(), |f| nalgebra::Vector3::from(f.b0));
    let frame = Frame { position: &position, velocity: &velocity, radius: &radius, mass: &mass };
    Ok((t.times()?[k], aggregates(&frame, &scene.domain, &field, gap_tolerance)))
}
