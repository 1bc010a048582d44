//! `[exits]`: how particles leave a run: outlets (planes they cross) and capture by the vessel's
//! wall. Their checks and the rules the simulation applies.

use super::{invalid, non_negative, SceneError};
use crate::core::exits::{ExitRules, Outlet};
use crate::core::state::{Particles, Vec3};
use nalgebra::Unit;
use serde::Deserialize;

/// `[exits]`: particles that leave are removed from the run and listed in the trajectory's
/// `exits` group with their id, time, position and way out.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExitsSpec {
    /// A particle touching the `[fluid.vessel]`'s wall for at least this long (s) is captured;
    /// 0 captures at the first contact. Absent: no capture.
    pub capture_after: Option<f64>,
    /// `[[exits.outlets]]`, in order: a particle past several leaves through the first.
    #[serde(default)]
    pub outlets: Vec<OutletSpec>,
}

/// `[[exits.outlets]]`: the particles whose centre passes the plane through `point` along
/// `normal` leave through this outlet.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutletSpec {
    pub name: String,
    /// A point of the plane (m).
    pub point: [f64; 3],
    /// The way out (any length, normalised).
    pub normal: [f64; 3],
}

/// Refuses exits the run cannot apply, naming the key: capture needs a vessel and contact with
/// its wall (`vessel`, `wall_contact`).
pub fn check(exits: &ExitsSpec, vessel: bool, wall_contact: bool) -> Result<(), SceneError> {
    if let Some(after) = exits.capture_after {
        non_negative("exits.capture_after", after)?;
        if !vessel {
            return Err(invalid("exits.capture_after", after, "captures at a [fluid.vessel]'s wall: there is none"));
        }
        if !wall_contact {
            return Err(invalid(
                "exits.capture_after",
                after,
                "needs [forces.contact] with walls = true (contact with the vessel's wall decides the capture)",
            ));
        }
    }
    for (k, o) in exits.outlets.iter().enumerate() {
        if exits.outlets[..k].iter().any(|other| other.name == o.name) {
            return Err(invalid(format!("exits.outlets[{k}].name"), &o.name, "the name is used twice"));
        }
        if Vec3::from(o.normal).norm().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(invalid(
                format!("exits.outlets[{k}].normal"),
                format!("{:?}", o.normal),
                "must be a non-zero direction",
            ));
        }
    }
    Ok(())
}

/// Refuses particles that start past an outlet (they would leave at the first step).
pub fn check_particles(exits: Option<&ExitsSpec>, particles: &Particles) -> Result<(), SceneError> {
    let rules = rules(exits);
    for (k, o) in rules.outlets.iter().enumerate() {
        if let Some(i) = particles.position.iter().position(|x| (x - o.point).dot(&o.normal) > 0.0) {
            return Err(invalid(
                format!("exits.outlets[{k}].point"),
                format!("{:?}", o.point.as_slice()),
                format!("particle {i} starts past this outlet"),
            ));
        }
    }
    Ok(())
}

/// The rules the simulation applies.
pub fn rules(exits: Option<&ExitsSpec>) -> ExitRules {
    let Some(exits) = exits else { return ExitRules::default() };
    let outlet =
        |o: &OutletSpec| Outlet { point: Vec3::from(o.point), normal: Unit::new_normalize(Vec3::from(o.normal)) };
    ExitRules { outlets: exits.outlets.iter().map(outlet).collect(), capture_after: exits.capture_after }
}
