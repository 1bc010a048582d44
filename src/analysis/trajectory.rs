//! Aggregates of stored trajectory frames (the trajectory carries its scene, so the domain and
//! field direction come with it).

use super::aggregates::{aggregates, Aggregate, Frame};
use crate::core::domain::Domain;
use crate::core::state::Vec3;
use crate::io::trajectory::Trajectory;
use crate::scene::Scene;

type Error = Box<dyn std::error::Error>;

/// What every frame of a trajectory shares: domain, field direction, radii, masses, times.
pub struct FrameReader<'a> {
    trajectory: &'a Trajectory,
    domain: Domain,
    field: Vec3,
    radius: Vec<f64>,
    mass: Vec<f64>,
    pub times: Vec<f64>,
}

impl<'a> FrameReader<'a> {
    pub fn new(t: &'a Trajectory) -> Result<Self, Error> {
        let (spec, domain) = Scene::layout(&t.scene_text()?, &t.path)?;
        let field = spec.field.as_ref().map_or(Vec3::x(), |f| Vec3::from(f.b0));
        Ok(Self {
            trajectory: t,
            domain,
            field,
            radius: t.file.dataset("particles/radius")?.read_raw()?,
            mass: t.file.dataset("particles/mass")?.read_raw()?,
            times: t.times()?,
        })
    }

    pub fn domain(&self) -> &Domain {
        &self.domain
    }

    /// The applied field at the origin (its direction orients the analysis).
    pub fn field(&self) -> &Vec3 {
        &self.field
    }

    /// The box's extent along the field (m): what caps a chain along it.
    pub fn box_extent(&self) -> f64 {
        super::aggregates::box_extent_along(&self.domain, &self.field)
    }

    pub fn radius(&self) -> &[f64] {
        &self.radius
    }

    /// Aggregates of frame `k` (negative: from the end) at `gap_tolerance`, with its time.
    pub fn aggregates(&self, k: isize, gap_tolerance: f64) -> Result<(f64, Vec<Aggregate>), Error> {
        let frames = self.times.len() as isize;
        let k = if k < 0 { frames + k } else { k };
        if !(0..frames).contains(&k) {
            return Err(format!("frame {k} outside 0..{frames}").into());
        }
        let k = k as usize;
        let position = self.trajectory.frame_vectors("position", k)?;
        let velocity = self.trajectory.frame_vectors("velocity", k)?;
        // The particles in the run at this frame: those that left it have NaN rows. Members
        // are given as particle ids.
        let present: Vec<usize> = (0..position.len()).filter(|&i| !position[i].x.is_nan()).collect();
        if present.len() == position.len() {
            let frame = Frame { position: &position, velocity: &velocity, radius: &self.radius, mass: &self.mass };
            return Ok((self.times[k], aggregates(&frame, &self.domain, &self.field, gap_tolerance)));
        }
        let pick = |v: &[Vec3]| present.iter().map(|&i| v[i]).collect::<Vec<_>>();
        let (radius, mass): (Vec<f64>, Vec<f64>) = present.iter().map(|&i| (self.radius[i], self.mass[i])).unzip();
        let (position, velocity) = (pick(&position), pick(&velocity));
        let frame = Frame { position: &position, velocity: &velocity, radius: &radius, mass: &mass };
        let mut found = aggregates(&frame, &self.domain, &self.field, gap_tolerance);
        for a in &mut found {
            a.members.iter_mut().for_each(|m| *m = present[*m]);
        }
        Ok((self.times[k], found))
    }
}

/// Aggregates of frame `k` (negative: from the end) of `t` at `gap_tolerance`.
pub fn frame_aggregates(t: &Trajectory, k: isize, gap_tolerance: f64) -> Result<(f64, Vec<Aggregate>), Error> {
    FrameReader::new(t)?.aggregates(k, gap_tolerance)
}
