//! `[start]`: a scene's particles and contact history from the state a trajectory ends with.

use super::spec::ParticleOrder;
use super::{fmt3, invalid, SceneError, SceneSpec, StartSpec};
use crate::core::domain::Domain;
use crate::core::renumber::{morton_order, Renumbering};
use crate::core::state::{PairHistory, Particles, Species, Vec3};
use crate::io::trajectory::Trajectory;
use sha2::{Digest, Sha256};
use std::path::Path;

/// The started particles, their contact history, and a digest of both (the scene's hash covers
/// it, so a run started from another state is another scene).
pub(super) struct Started {
    pub particles: Particles,
    pub history: PairHistory,
    pub digest: Vec<u8>,
}

/// Loads `start.trajectory` (relative to `dir`) for a scene of `species` in `domain`; findings
/// that do not stop the run go to `warnings`.
pub(super) fn load(
    spec: &SceneSpec,
    start: &StartSpec,
    dir: &Path,
    domain: &Domain,
    species: &[Species],
    warnings: &mut Vec<String>,
) -> Result<Started, SceneError> {
    let shown = start.trajectory.display().to_string();
    let fail = |why: String| invalid("start.trajectory", &shown, why);
    if !spec.particles.is_empty() {
        return Err(fail("a scene places [[particles]] or starts from a trajectory, not both".into()));
    }
    let path = dir.join(&start.trajectory);
    let t = Trajectory::open(&path).map_err(|e| fail(format!("cannot be read: {e}")))?;
    let stored_text = t.scene_text().map_err(|e| fail(format!("holds no scene: {e}")))?;
    let stored: SceneSpec =
        toml::from_str(&stored_text).map_err(|e| fail(format!("its stored scene does not parse: {}", e.message())))?;
    let (state, _) = t.checkpoint().map_err(|e| fail(format!("has no readable checkpoint: {e}")))?;
    let old = &state.particles;

    // Species by name: the stored index → this scene's.
    let names: Vec<&str> = species.iter().map(|s| s.name.as_str()).collect();
    let map = stored
        .species
        .iter()
        .map(|s| {
            names.iter().position(|n| *n == s.name).ok_or_else(|| {
                fail(format!("its species `{}` is not defined here (defined: {})", s.name, names.join(", ")))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;

    // The stored particles in the order they are numbered here.
    let wrapped: Vec<Vec3> = old.position.iter().map(|x| wrapped(x, domain)).collect();
    let visit: Vec<usize> = match start.order {
        ParticleOrder::Placement => (0..old.len()).collect(),
        ParticleOrder::Spatial => {
            let smallest = old.radius.iter().copied().fold(f64::INFINITY, f64::min);
            morton_order(&wrapped, 2.0 * smallest, domain)
        }
    };

    let mut particles = Particles::default();
    for &i in &visit {
        let si = map[old.species[i] as usize];
        let s = &species[si];
        let radius = old.radius[i];
        if s.size.is_none() && (radius - s.radius).abs() > 1e-12 * s.radius {
            return Err(fail(format!(
                "particle {i} has radius {radius:e} m, species `{}` here {:e} m; give the species a `size` law to keep \
                 each particle's own radius",
                s.name, s.radius
            )));
        }
        let x = wrapped[i];
        // A settled bed presses on its floor: wall overlaps up to what the run monitor accepts.
        let allowed = spec.stability.max_overlap * 2.0 * radius;
        super::inside(x, radius, allowed, domain)
            .map_err(|why| fail(format!("particle {i} at {}: {why}", fmt3(&x.into()))))?;
        particles.push_sized(si as u16, s, radius, x, old.velocity[i]);
        *particles.angular_velocity.last_mut().expect("just pushed") = old.angular_velocity[i];
        // A permanent moment keeps the orientation it turned to, with this species' magnitude.
        let (turned, own) = (old.permanent_moment[i], *particles.permanent_moment.last().expect("just pushed"));
        if turned != Vec3::zeros() && own != Vec3::zeros() {
            *particles.permanent_moment.last_mut().expect("just pushed") = turned * (own.norm() / turned.norm());
        }
    }

    let mut contacts = state.history;
    if start.order != ParticleOrder::Placement {
        contacts.renumber(&Renumbering::new(visit.iter().map(|&i| i as u32).collect()));
    }
    let same_box = stored.domain.lo == spec.domain.lo
        && stored.domain.hi == spec.domain.hi
        && (0..3).all(|k| stored.domain.boundary.axis(k) == spec.domain.boundary.axis(k));
    if !same_box && !contacts.walls.is_empty() {
        warnings.push(format!(
            "start.trajectory = {shown}: the box differs from the trajectory's, so its {} wall springs start at zero",
            contacts.walls.len()
        ));
        contacts.walls.clear();
    }

    let mut h = Sha256::new();
    for name in &names {
        h.update(name.as_bytes());
        h.update([0]);
    }
    for i in 0..particles.len() {
        h.update(particles.species[i].to_le_bytes());
        h.update(particles.radius[i].to_le_bytes());
        for v in [particles.position[i], particles.velocity[i], particles.angular_velocity[i]] {
            v.iter().for_each(|c| h.update(c.to_le_bytes()));
        }
    }
    for ((i, j), s) in &contacts.pairs {
        h.update(i.to_le_bytes());
        h.update(j.to_le_bytes());
        s.iter().for_each(|c| h.update(c.to_le_bytes()));
    }
    for ((i, face), s) in &contacts.walls {
        h.update(i.to_le_bytes());
        h.update([*face]);
        s.iter().for_each(|c| h.update(c.to_le_bytes()));
    }
    Ok(Started { particles, history: contacts, digest: h.finalize().to_vec() })
}

fn wrapped(x: &Vec3, domain: &Domain) -> Vec3 {
    let mut x = *x;
    domain.wrap(&mut x);
    x
}
