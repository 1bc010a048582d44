//! Reads LAMMPS/LIGGGHTS `dump custom` text files (columns named in the ATOMS header) into states
//! on magdem's particles, so reference runs land in the same trajectory schema.

use super::{Engine, ReferenceError};
use crate::core::neighbours::CellList;
use crate::core::state::{State, Vec3};
use crate::scene::Scene;
use std::path::Path;

/// All frames of a dump, as states on the scene's particles (sorted by atom id). Contacts are
/// the geometric overlaps of each frame (the engines' shear history is not dumped).
pub fn read(engine: Engine, path: &Path, scene: &Scene) -> Result<Vec<State>, ReferenceError> {
    let fail =
        |message: String| ReferenceError::Dump { engine: engine.name(), path: path.display().to_string(), message };
    let text = std::fs::read_to_string(path)?;
    let mut lines = text.lines();
    let mut frames = vec![];
    let n = scene.initial.len();
    let mut cells = CellList::default();
    let mut pairs = vec![];
    let largest_d = crate::core::state::largest_diameter(&scene.species);
    while let Some(line) = lines.next() {
        if !line.starts_with("ITEM: TIMESTEP") {
            continue;
        }
        let step: u64 = lines.next().and_then(|l| l.trim().parse().ok()).ok_or_else(|| fail("bad TIMESTEP".into()))?;
        lines.next(); // ITEM: NUMBER OF ATOMS
        let count: usize =
            lines.next().and_then(|l| l.trim().parse().ok()).ok_or_else(|| fail("bad NUMBER OF ATOMS".into()))?;
        if count != n {
            return Err(fail(format!("frame at step {step} has {count} atoms, the scene {n}")));
        }
        lines.next(); // ITEM: BOX BOUNDS
        for _ in 0..3 {
            lines.next();
        }
        let header = lines.next().ok_or_else(|| fail("missing ATOMS header".into()))?;
        let columns: Vec<&str> = header.trim_start_matches("ITEM: ATOMS").split_whitespace().collect();
        let col = |name: &str| columns.iter().position(|c| *c == name).ok_or_else(|| fail(format!("no column {name}")));
        let id = col("id")?;
        let groups: Vec<[usize; 3]> =
            [["x", "y", "z"], ["vx", "vy", "vz"], ["omegax", "omegay", "omegaz"], ["fx", "fy", "fz"]]
                .iter()
                .map(|names| Ok([col(names[0])?, col(names[1])?, col(names[2])?]))
                .collect::<Result<_, ReferenceError>>()?;
        let mut state = State { step, time: step as f64 * scene.dt(), ..State::new(scene.initial.clone()) };
        for _ in 0..n {
            let row = lines.next().ok_or_else(|| fail(format!("frame at step {step} ends early")))?;
            let values: Vec<f64> = row
                .split_whitespace()
                .map(|v| v.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| fail(format!("{e} in {row:?}")))?;
            let i = values[id] as usize - 1;
            let v3 = |g: [usize; 3]| Vec3::new(values[g[0]], values[g[1]], values[g[2]]);
            let p = &mut state.particles;
            p.position.write()[i] = v3(groups[0]);
            p.velocity[i] = v3(groups[1]);
            p.angular_velocity[i] = v3(groups[2]);
            state.fields.force[i] = v3(groups[3]);
        }
        let p = &state.particles;
        cells.pairs_within(&p.position, &scene.domain, Some(largest_d), &mut pairs);
        let touching = pairs.iter().filter(|q| q.dist < p.radius[q.i as usize] + p.radius[q.j as usize]);
        state.history.pairs = touching.map(|q| ((q.i, q.j), Vec3::zeros())).collect::<Vec<_>>().into();
        frames.push(state);
    }
    if frames.is_empty() {
        return Err(fail("no frames".into()));
    }
    Ok(frames)
}
