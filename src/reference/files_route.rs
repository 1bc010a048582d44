//! magdem's side of the files route: `magdem magnetic-forces SCENE POSITIONS PREFIX`, called by
//! the deck through `shell` at every exchange. Reads the engine's positions dump, computes the
//! magnetic forces with the scene's induction level (moments carried between calls in
//! PREFIX.moments, so `paper` induction keeps its memory), and writes PREFIX.x/.y/.z atomfiles.

use super::ReferenceError;
use crate::core::state::Vec3;
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;

fn parse_rows(text: &str, columns: usize) -> Vec<Vec<f64>> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().filter_map(|t| t.parse().ok()).collect::<Vec<f64>>())
        .filter(|v| v.len() == columns)
        .collect()
}

pub fn magnetic_forces(scene: &Scene, positions: &Path, prefix: &Path) -> Result<(), ReferenceError> {
    let fail = |message: String| ReferenceError::Dump {
        engine: "files route",
        path: positions.display().to_string(),
        message,
    };
    let mut field = scene.magnetic_force_field().ok_or_else(|| fail("the scene has no magnetic term".into()))?;
    let mut state = scene.initial_state();
    let n = state.particles.len();
    let text = std::fs::read_to_string(positions)?;
    let atoms = text.rsplit("ITEM: ATOMS").next().ok_or_else(|| fail("no ATOMS section".into()))?;
    let rows = parse_rows(atoms.split_once('\n').map_or("", |(_, rest)| rest), 4);
    if rows.len() != n {
        return Err(fail(format!("{} atoms in the dump, {n} in the scene", rows.len())));
    }
    for r in &rows {
        state.particles.position[r[0] as usize - 1] = Vec3::new(r[1], r[2], r[3]);
    }
    let moments = prefix.with_extension("moments");
    if let Ok(text) = std::fs::read_to_string(&moments) {
        for r in parse_rows(&text, 4) {
            state.fields.moment[r[0] as usize - 1] = Vec3::new(r[1], r[2], r[3]);
        }
    }
    field.evaluate(&mut state, scene.dt());
    let p = &state.fields;
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let mut out = format!("# magdem magnetic force, {axis} component (N)\n{n}\n");
        for i in 0..n {
            let _ = writeln!(out, "{} {:.17e}", i + 1, p.force[i][k]);
        }
        std::fs::write(prefix.with_extension(axis), out)?;
    }
    let mut out = String::from("# magdem moments carried between exchanges (A m^2)\n");
    for i in 0..n {
        let m = p.moment[i];
        let _ = writeln!(out, "{} {:.17e} {:.17e} {:.17e}", i + 1, m.x, m.y, m.z);
    }
    std::fs::write(moments, out)?;
    Ok(())
}
