//! `[field]`: the applied magnetic field. The scanner's B0 plus a gradient part: a constant
//! gradient tensor (`gradient`), an MRI gradient (`gradient_mri`, ∇ of the component along B0,
//! with its concomitant terms), or real coils (`[[field.coils]]`); a `[field.waveform]` switches
//! the gradient part on and off. Its checks and the field the force terms read.

use super::{invalid, positive, SceneError};
use crate::core::coils::{scanner_gradient, Coil, Loop, Path, Segment};
use crate::core::field::{AppliedField, Gradient, Waveform};
use crate::core::state::{Particles, Vec3};
use nalgebra::{Matrix3, Unit};
use serde::Deserialize;

/// `[field]`: B_ext(x, t) = b0 + w(t) B_g(x), x in scene coordinates.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldSpec {
    /// Uniform field B0 (T): with a linear gradient the field at the origin.
    pub b0: [f64; 3],
    /// B_g = G x: gradient[a][b] = ∂B_a/∂x_b (T/m); default zero.
    pub gradient: Option<[[f64; 3]; 3]>,
    /// Or [Gx, Gy, Gz] = ∇B_∥ (T/m), the gradient of the field's component along B0 in scene
    /// axes, as MRI gives it; the other components follow from ∇·B = 0 and ∇×B = 0.
    pub gradient_mri: Option<[f64; 3]>,
    /// Or B_g = the coils' Biot–Savart field.
    #[serde(default)]
    pub coils: Vec<CoilSpec>,
    /// Switches B_g on and off (default: always on).
    pub waveform: Option<WaveformSpec>,
}

/// `[[field.coils]]`: one coil, by `kind`. Currents in A, positive counter-clockwise about the
/// axis (loops and pairs) or from `from` to `to` (segments).
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum CoilSpec {
    /// A circular loop (closed form with elliptic integrals).
    Loop { centre: [f64; 3], axis: [f64; 3], radius: f64, current: f64 },
    /// A straight wire (Biot–Savart).
    Segment { from: [f64; 3], to: [f64; 3], current: f64 },
    /// Two coaxial loops √3 radius apart with opposed currents: a gradient along the axis.
    Maxwell { centre: [f64; 3], axis: [f64; 3], radius: f64, current: f64 },
    /// Two coaxial loops one radius apart with equal currents: a uniform field.
    Helmholtz { centre: [f64; 3], axis: [f64; 3], radius: f64, current: f64 },
    /// A Golay saddle pair on a cylinder about z through `centre` (default the origin), each
    /// 120° arc drawn as `arc_segments` straight wires: ∂B_z/∂x at its centre.
    Golay {
        #[serde(default)]
        centre: [f64; 3],
        radius: f64,
        current: f64,
        arc_segments: usize,
    },
}

/// `[field.waveform]`: an on/off duty cycle of the gradient part.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaveformSpec {
    /// s
    pub period: f64,
    /// The fraction of each period the gradient is on, in (0, 1].
    pub duty: f64,
    /// Where each on-phase starts, as a fraction of the period, in [0, 1) (default 0).
    #[serde(default)]
    pub phase: f64,
}

/// The most straight wires a Golay arc is drawn with: each costs seven field evaluations per
/// particle and force evaluation.
const MAX_ARC_SEGMENTS: usize = 10_000;

impl FieldSpec {
    /// The constant gradient tensor: `gradient`, or `gradient_mri` with its concomitant terms
    /// about B0's direction (z when B0 is zero), or zero.
    pub fn linear_gradient(&self) -> Matrix3<f64> {
        if let Some(g) = self.gradient_mri {
            let b0 = Vec3::from(self.b0);
            let axis = if b0 == Vec3::zeros() { Vec3::z_axis() } else { Unit::new_normalize(b0) };
            return scanner_gradient(Vec3::from(g), axis);
        }
        let g = self.gradient.unwrap_or_default();
        Matrix3::from_fn(|r, c| g[r][c])
    }

    /// The applied field.
    pub fn applied(&self) -> AppliedField {
        let gradient = match self.coils.is_empty() {
            true => Gradient::Linear(self.linear_gradient()),
            false => Gradient::Coils(Coil { paths: self.coils.iter().flat_map(|c| c.coil().paths).collect() }),
        };
        let waveform = self.waveform.as_ref().map(|w| Waveform { period: w.period, duty: w.duty, phase: w.phase });
        AppliedField { b0: Vec3::from(self.b0), gradient, waveform }
    }
}

impl CoilSpec {
    /// The coil's current paths.
    pub fn coil(&self) -> Coil {
        let unit = |a: &[f64; 3]| Unit::new_normalize(Vec3::from(*a));
        match self {
            CoilSpec::Loop { centre, axis, radius, current } => Coil {
                paths: vec![Path::Loop(Loop {
                    centre: Vec3::from(*centre),
                    axis: unit(axis),
                    radius: *radius,
                    current: *current,
                })],
            },
            CoilSpec::Segment { from, to, current } => Coil {
                paths: vec![Path::Segment(Segment { from: Vec3::from(*from), to: Vec3::from(*to), current: *current })],
            },
            CoilSpec::Maxwell { centre, axis, radius, current } => {
                Coil::maxwell(Vec3::from(*centre), unit(axis), *radius, *current)
            }
            CoilSpec::Helmholtz { centre, axis, radius, current } => {
                Coil::helmholtz(Vec3::from(*centre), unit(axis), *radius, *current)
            }
            CoilSpec::Golay { centre, radius, current, arc_segments } => {
                Coil::golay(*radius, *current, *arc_segments).translated(Vec3::from(*centre))
            }
        }
    }
}

/// Refuses a `[field]` table the solver cannot use, naming the key.
pub fn check(f: &FieldSpec) -> Result<(), SceneError> {
    if let (Some(_), Some(g)) = (f.gradient, f.gradient_mri) {
        return Err(invalid(
            "field.gradient_mri",
            format!("{g:?}"),
            "give field.gradient or field.gradient_mri, not both",
        ));
    }
    if !f.coils.is_empty() {
        for (key, given) in [("field.gradient", f.gradient.is_some()), ("field.gradient_mri", f.gradient_mri.is_some())]
        {
            if given {
                return Err(invalid(key, "[...]", "[[field.coils]] give the gradient: leave it out"));
            }
        }
    }
    for (k, c) in f.coils.iter().enumerate() {
        check_coil(k, c)?;
    }
    if let Some(w) = &f.waveform {
        if f.gradient.is_none() && f.gradient_mri.is_none() && f.coils.is_empty() {
            return Err(invalid(
                "field.waveform.period",
                w.period,
                "the waveform switches the gradient, and the field has none (B0 is never switched)",
            ));
        }
        positive("field.waveform.period", w.period)?;
        if !(w.duty > 0.0 && w.duty <= 1.0) {
            return Err(invalid("field.waveform.duty", w.duty, "must lie in (0, 1]"));
        }
        if !(0.0..1.0).contains(&w.phase) {
            return Err(invalid("field.waveform.phase", w.phase, "must lie in [0, 1): a fraction of the period"));
        }
    }
    Ok(())
}

/// Refuses coil `k`'s values.
fn check_coil(k: usize, c: &CoilSpec) -> Result<(), SceneError> {
    let key = |name: &str| format!("field.coils[{k}].{name}");
    let direction = |name: &str, v: &[f64; 3]| match Vec3::from(*v).norm() > 0.0 {
        true => Ok(()),
        false => Err(invalid(key(name), format!("{v:?}"), "must be a non-zero direction")),
    };
    match c {
        CoilSpec::Loop { axis, radius, .. }
        | CoilSpec::Maxwell { axis, radius, .. }
        | CoilSpec::Helmholtz { axis, radius, .. } => {
            positive(&key("radius"), *radius)?;
            direction("axis", axis)?;
        }
        CoilSpec::Segment { from, to, .. } => {
            if from == to {
                return Err(invalid(
                    key("to"),
                    format!("{to:?}"),
                    "must differ from `from`: the segment has no length",
                ));
            }
        }
        CoilSpec::Golay { radius, arc_segments, .. } => {
            positive(&key("radius"), *radius)?;
            if !(1..=MAX_ARC_SEGMENTS).contains(arc_segments) {
                return Err(invalid(key("arc_segments"), arc_segments, format!("must lie in 1..={MAX_ARC_SEGMENTS}")));
            }
        }
    }
    Ok(())
}

/// Refuses a particle that starts within its radius of a coil's wire, where the wire's field
/// diverges (the coils lie outside the vessel).
pub fn check_particles(f: &FieldSpec, particles: &Particles) -> Result<(), SceneError> {
    for (k, c) in f.coils.iter().enumerate() {
        let coil = c.coil();
        for (i, (x, a)) in particles.position.iter().zip(&particles.radius).enumerate() {
            let d = coil.distance(*x);
            if d <= *a {
                return Err(invalid(
                    format!("field.coils[{k}]"),
                    kind(c),
                    format!("particle {i} (radius {a:.4e} m) starts {d:.4e} m from the coil's wire"),
                ));
            }
        }
    }
    Ok(())
}

/// The coil's `kind` as the scene writes it.
fn kind(c: &CoilSpec) -> &'static str {
    match c {
        CoilSpec::Loop { .. } => "loop",
        CoilSpec::Segment { .. } => "segment",
        CoilSpec::Maxwell { .. } => "maxwell",
        CoilSpec::Helmholtz { .. } => "helmholtz",
        CoilSpec::Golay { .. } => "golay",
    }
}
