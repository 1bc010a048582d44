//! `[fluid]`, `[fluid.vessel]` and `[fluid.grid]`: the carrier fluid, at rest, moving uniformly,
//! flowing along a straight cylindrical vessel (Poiseuille's steady flow, Womersley's pulsatile
//! one), or given on a grid by a CFD solution. Its checks and the flow the drag laws read.

use super::{invalid, positive, SceneError};
use crate::core::flow::{Flow, GriddedFlow, Harmonic, Vessel, VesselFlow, MAX_WOMERSLEY};
use crate::core::forces::setup::Fluid;
use crate::core::state::{Particles, Vec3};
use nalgebra::{Complex, Unit};
use serde::Deserialize;
use std::path::Path;
use std::sync::Arc;

/// `[fluid]`: the carrier fluid, still, moving uniformly, or flowing along a vessel.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidSpec {
    /// kg/m³
    pub density: f64,
    /// Dynamic viscosity, Pa·s
    pub viscosity: f64,
    /// m/s, uniform (default at rest)
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Flow along a straight cylindrical vessel instead ([`VesselSpec`]).
    pub vessel: Option<VesselSpec>,
    /// A flow field on a grid read from a file instead ([`GridSpec`]).
    pub grid: Option<GridSpec>,
}

/// `[fluid.grid]`: velocities on a regular grid, from HDF5 or legacy VTK (`io::flow_grid`),
/// trilinear in space and linear in time. The grid must cover the box.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// The file, relative to the scene file.
    pub file: String,
    /// The frames repeat with this period (s), a cardiac cycle; without it the last frame must
    /// reach `integration.end_time` (one frame: a steady flow).
    pub period: Option<f64>,
    /// The grid as read (filled when the scene is built).
    #[serde(skip)]
    pub loaded: Option<Arc<GriddedFlow>>,
}

/// `[fluid.vessel]`: flow along a straight cylindrical vessel, zero outside it. Steady Poiseuille
/// flow u = 2ū (1 − r²/R²) at the mean speed alone; with `period` and `harmonics`, Womersley's
/// pulsatile flow whose flow rate is Q(t) = Q̄ (1 + Σ A_n cos(2π n t/period + φ_n)).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VesselSpec {
    /// A point on the axis (m).
    pub centre: [f64; 3],
    /// The axis: the flow runs along it (any length, normalised).
    pub axis: [f64; 3],
    /// R (m).
    pub radius: f64,
    /// ū = Q̄/(πR²) (m/s): the centreline speed of steady flow is 2ū.
    pub mean_speed: f64,
    /// The pulse's period (s), with `harmonics`.
    pub period: Option<f64>,
    /// [n, A_n, φ_n] per harmonic of the flow rate: n ≥ 1 whole, A_n relative to Q̄, φ_n in rad.
    #[serde(default)]
    pub harmonics: Vec<[f64; 3]>,
}

/// Refuses a `[fluid]` table the solver cannot use, naming the key.
pub fn check(f: &FluidSpec) -> Result<(), SceneError> {
    positive("fluid.viscosity", f.viscosity)?;
    super::non_negative("fluid.density", f.density)?;
    if f.grid.is_some() && (f.vessel.is_some() || f.velocity != [0.0; 3]) {
        return Err(invalid("fluid.grid", "{…}", "sets the flow: leave out fluid.velocity and [fluid.vessel]"));
    }
    let Some(v) = &f.vessel else { return Ok(()) };
    if f.velocity != [0.0; 3] {
        return Err(invalid(
            "fluid.velocity",
            format!("{:?}", f.velocity),
            "a [fluid.vessel] sets the flow: leave fluid.velocity out",
        ));
    }
    positive("fluid.vessel.radius", v.radius)?;
    if Vec3::from(v.axis).norm() == 0.0 {
        return Err(invalid("fluid.vessel.axis", format!("{:?}", v.axis), "must be a non-zero direction"));
    }
    match (v.period, v.harmonics.is_empty()) {
        (None, false) => return Err(invalid("fluid.vessel.harmonics", v.harmonics.len(), "need fluid.vessel.period")),
        (Some(period), true) => {
            return Err(invalid("fluid.vessel.period", period, "needs fluid.vessel.harmonics (steady flow has none)"))
        }
        (Some(period), false) => positive("fluid.vessel.period", period)?,
        (None, true) => {}
    }
    for (k, &[n, amplitude, _]) in v.harmonics.iter().enumerate() {
        if !(n >= 1.0 && n.fract() == 0.0 && n <= u32::MAX as f64) {
            return Err(invalid(
                format!("fluid.vessel.harmonics[{k}][0]"),
                n,
                "the harmonic's order must be a whole number ≥ 1",
            ));
        }
        if amplitude < 0.0 {
            return Err(invalid(
                format!("fluid.vessel.harmonics[{k}][1]"),
                amplitude,
                "the amplitude must be ≥ 0 (a phase of π reverses it)",
            ));
        }
    }
    if let Flow::Vessel(flow) = flow(f) {
        for h in &flow.harmonics {
            let alpha = flow.womersley_number(h.n);
            if alpha > MAX_WOMERSLEY {
                return Err(invalid(
                    "fluid.vessel.period",
                    flow.period,
                    format!("gives harmonic {} a Womersley number {alpha:.1}, above the {MAX_WOMERSLEY} the Bessel series hold", h.n),
                ));
            }
        }
    }
    Ok(())
}

/// Refuses particles that start outside the vessel or through its wall (r + a > R): the flow is
/// zero outside it, and its surface is a contact wall.
pub fn check_particles(f: &FluidSpec, particles: &Particles) -> Result<(), SceneError> {
    let Flow::Vessel(flow) = self::flow(f) else { return Ok(()) };
    for (i, (x, a)) in particles.position.iter().zip(&particles.radius).enumerate() {
        let r = flow.vessel.radial(*x);
        if r + a > flow.vessel.radius {
            return Err(invalid(
                "fluid.vessel.radius",
                flow.vessel.radius,
                format!("particle {i} at {r:.4e} m from the axis (radius {a:.4e} m) is not inside the vessel"),
            ));
        }
    }
    Ok(())
}

/// Reads `[fluid.grid]`'s file (relative to `dir`) into the spec, refusing by key a grid that
/// cannot serve the run: too few nodes, spacing not positive, values not finite, frames out of
/// order, not covering the box `[lo, hi]`, or ending before `end_time` without a period. Returns
/// the file's bytes, which the scene's hash includes.
pub fn load_grid(f: &mut FluidSpec, dir: &Path, (lo, hi): (Vec3, Vec3), end_time: f64) -> Result<Vec<u8>, SceneError> {
    let Some(spec) = &mut f.grid else { return Ok(vec![]) };
    let path = dir.join(&spec.file);
    let bytes =
        std::fs::read(&path).map_err(|e| invalid("fluid.grid.file", &spec.file, format!("cannot read it: {e}")))?;
    let refuse = |why: String| invalid("fluid.grid.file", &spec.file, why);
    let mut grid = crate::io::flow_grid::read(&path).map_err(refuse)?;
    if grid.shape.iter().any(|&n| n < 2) {
        return Err(refuse(format!("has {:?} nodes: at least 2 along each axis", grid.shape)));
    }
    if !grid.spacing.iter().all(|&h| h > 0.0 && h.is_finite()) || !grid.origin.iter().all(|x| x.is_finite()) {
        return Err(refuse(format!(
            "spacing {:?}, origin {:?}: must be finite, spacing positive",
            grid.spacing, grid.origin
        )));
    }
    if let Some(k) = grid.velocity.iter().position(|u| !u.iter().all(|c| c.is_finite())) {
        return Err(refuse(format!("velocity value {k} is not finite")));
    }
    if !grid.times.iter().all(|t| t.is_finite()) || grid.times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(refuse(format!("frame times {:?} must rise", grid.times)));
    }
    let end = grid.end();
    if (0..3).any(|k| grid.origin[k] > lo[k] || end[k] < hi[k]) {
        return Err(refuse(format!(
            "spans {:?} to {:?} m and does not cover the box {:?} to {:?} m",
            grid.origin.as_slice(),
            end.as_slice(),
            lo.as_slice(),
            hi.as_slice()
        )));
    }
    let (first, last) = (grid.times[0], grid.times[grid.times.len() - 1]);
    match spec.period {
        Some(p) => {
            positive("fluid.grid.period", p)?;
            if last - first >= p {
                return Err(invalid("fluid.grid.period", p, format!("is shorter than the frames' span {:e} s", last - first)));
            }
        }
        None if grid.times.len() > 1 && (first > 0.0 || last < end_time) => {
            return Err(refuse(format!(
                "its frames span {first:e} to {last:e} s, not the run's 0 to {end_time:e} s: set fluid.grid.period to repeat them"
            )))
        }
        None => {}
    }
    grid.period = spec.period;
    spec.loaded = Some(Arc::new(grid));
    Ok(bytes)
}

/// The vessel's geometry.
pub fn vessel(v: &VesselSpec) -> Vessel {
    Vessel { centre: Vec3::from(v.centre), axis: Unit::new_normalize(Vec3::from(v.axis)), radius: v.radius }
}

/// The fluid's velocity field.
pub fn flow(f: &FluidSpec) -> Flow {
    if let Some(grid) = f.grid.as_ref().and_then(|g| g.loaded.clone()) {
        return Flow::Grid(grid);
    }
    let Some(v) = &f.vessel else { return Flow::Uniform(Vec3::from(f.velocity)) };
    let vessel = vessel(v);
    let mut flow = VesselFlow::poiseuille(vessel, v.mean_speed, f.density, f.viscosity);
    if let Some(period) = v.period {
        flow.period = period;
        flow.harmonics = v
            .harmonics
            .iter()
            .map(|&[n, amplitude, phase]| Harmonic {
                n: n as u32,
                q: Complex::from_polar(amplitude * flow.mean_flow, phase),
            })
            .collect();
    }
    Flow::Vessel(flow)
}

/// The fluid the force terms see.
pub fn fluid(f: &FluidSpec) -> Fluid {
    Fluid { density: f.density, viscosity: f.viscosity, flow: flow(f) }
}
