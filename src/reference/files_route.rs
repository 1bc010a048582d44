//! magdem's side of the files route: `magdem magnetic-forces SCENE POSITIONS PREFIX`, called by
//! the deck through `shell` at every exchange. Reads the engine's positions dump, computes the
//! magnetic forces with the scene's induction level (moments carried between calls in
//! PREFIX.moments, so `paper` induction keeps its memory), and writes PREFIX.x/.y/.z atomfiles.
//! The carried moments are stamped with the dump's timestep and read back only by a later one: a
//! run started again in the same directory (from step 0) does not inherit the last run's moments.

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

/// The lines after the last `header` line of a dump (`None` without one).
fn section<'a>(text: &'a str, header: &str) -> Option<&'a str> {
    let (_, rest) = text.rsplit_once(header)?;
    Some(rest.split_once('\n').map_or("", |(_, body)| body))
}

/// How the carried moments' first line names the timestep they were computed at.
const MOMENTS_STAMP: &str = ", timestep ";

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
    let step: u64 = section(&text, "ITEM: TIMESTEP")
        .and_then(|body| body.lines().next()?.trim().parse().ok())
        .ok_or_else(|| fail("no TIMESTEP section".into()))?;
    let atoms = section(&text, "ITEM: ATOMS").ok_or_else(|| fail("no ATOMS section".into()))?;
    let rows = parse_rows(atoms, 4);
    if rows.len() != n {
        return Err(fail(format!("{} atoms in the dump, {n} in the scene", rows.len())));
    }
    let positions = state.particles.position.write();
    for r in &rows {
        positions[r[0] as usize - 1] = Vec3::new(r[1], r[2], r[3]);
    }
    let moments = prefix.with_extension("moments");
    let carried = std::fs::read_to_string(&moments).ok().filter(|text| {
        let stamp =
            text.lines().next().and_then(|l| l.rsplit_once(MOMENTS_STAMP)).map(|(_, s)| s.trim().parse::<u64>());
        matches!(stamp, Some(Ok(at)) if at < step)
    });
    for r in carried.map_or(vec![], |text| parse_rows(&text, 4)) {
        state.fields.moment[r[0] as usize - 1] = Vec3::new(r[1], r[2], r[3]);
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
    let mut out = format!("# magdem moments carried between exchanges (A m^2){MOMENTS_STAMP}{step}\n");
    for i in 0..n {
        let m = p.moment[i];
        let _ = writeln!(out, "{} {:.17e} {:.17e} {:.17e}", i + 1, m.x, m.y, m.z);
    }
    std::fs::write(moments, out)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The two-sphere scene with the paper's lagged induction, whose forces depend on the moments
    /// carried from the exchange before.
    fn scene() -> Scene {
        let text = crate::verify::magnetic::PAIR.replace(r#"induction = "exact""#, r#"induction = "paper""#);
        Scene::parse(&text, "files-route").unwrap()
    }

    fn dump(step: u64, scene: &Scene) -> String {
        let x = scene.initial_state().particles.position;
        let atoms: String = x.iter().enumerate().map(|(i, p)| format!("{} {} {} {}\n", i + 1, p.x, p.y, p.z)).collect();
        format!("ITEM: TIMESTEP\n{step}\nITEM: NUMBER OF ATOMS\n{}\nITEM: ATOMS id x y z\n{atoms}", x.len())
    }

    /// Forces written for the dump at `step`, with the moments file as left by earlier calls.
    fn forces(dir: &Path, scene: &Scene, step: u64) -> String {
        let positions = dir.join("positions.dump");
        std::fs::write(&positions, dump(step, scene)).unwrap();
        magnetic_forces(scene, &positions, &dir.join("forces")).unwrap();
        ["x", "y", "z"].map(|a| std::fs::read_to_string(dir.join("forces").with_extension(a)).unwrap()).concat()
    }

    /// A run's first exchange ignores the moments a finished run left in the directory, and a
    /// later exchange reads those of the one before (the lagged induction's memory).
    #[test]
    fn carried_moments_are_read_only_by_a_later_exchange() {
        let (scene, dir) = (scene(), tempfile::tempdir().unwrap());
        let fresh = forces(dir.path(), &scene, 0);
        let moments = dir.path().join("forces.moments");
        let left = std::fs::read_to_string(&moments).unwrap();
        assert!(left.lines().next().unwrap().ends_with(", timestep 0"), "{left}");
        // A finished run's last moments, much larger than the applied field's.
        std::fs::write(
            &moments,
            "# magdem moments carried between exchanges (A m^2), timestep 500\n1 1e-6 0 0\n2 1e-6 0 0\n",
        )
        .unwrap();
        assert_eq!(forces(dir.path(), &scene, 0), fresh, "a run from step 0 starts afresh");
        let carried = forces(dir.path(), &scene, 100);
        std::fs::remove_file(&moments).unwrap();
        assert_ne!(forces(dir.path(), &scene, 100), carried, "step 100 reads step 0's moments");
    }
}
