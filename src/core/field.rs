//! The applied magnetic field B(x, t) and its Jacobian G_ab(x, t) = ∂B_a/∂x_b: the scanner's
//! uniform B0 plus a gradient part, a linear field G x or the Biot–Savart field of coils
//! ([`super::coils`]), switched on and off in time by a duty-cycle waveform. B0 is never switched:
//!
//!   B(x, t) = B0 + w(t) B_g(x),  G(x, t) = w(t) ∂B_g/∂x,  w(t) ∈ {0, 1}.
//!
//! The moments read B, the gradient force G (docs/model.md §4.4).

use super::coils::Coil;
use super::vector::Vec3;
use nalgebra::Matrix3;

/// An on/off duty cycle, as a scanner alternates imaging and propulsion: on while
/// frac(t/period − phase) < duty, so each on-phase starts at t = (k + phase) · period and lasts
/// duty · period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Waveform {
    /// T (s).
    pub period: f64,
    /// The fraction of each period the gradient is on, in (0, 1].
    pub duty: f64,
    /// Where the on-phase starts, as a fraction of the period, in [0, 1).
    pub phase: f64,
}

impl Waveform {
    /// w(t): 1 during an on-phase, 0 otherwise.
    pub fn at(&self, t: f64) -> f64 {
        let cycle = (t / self.period - self.phase).rem_euclid(1.0);
        if cycle < self.duty {
            1.0
        } else {
            0.0
        }
    }
}

/// The gradient part B_g(x).
#[derive(Debug, Clone)]
pub enum Gradient {
    /// B_g = G x with one constant G (T/m).
    Linear(Matrix3<f64>),
    /// The coils' fields, summed.
    Coils(Coil),
}

/// B(x, t) = B0 + w(t) B_g(x).
#[derive(Debug, Clone)]
pub struct AppliedField {
    /// B0 (T): for a linear gradient the field at the origin.
    pub b0: Vec3,
    pub gradient: Gradient,
    /// w(t); `None` is always on.
    pub waveform: Option<Waveform>,
}

/// The field at one time, for a loop over particles: the match on the kind is made once.
#[derive(Debug, Clone, Copy)]
pub enum FieldAt<'a> {
    /// B = b0 + g x, G = g (g already multiplied by w(t)).
    Linear { b0: Vec3, g: Matrix3<f64> },
    /// B = b0 + w coil(x), G = w ∂coil/∂x.
    Coils { b0: Vec3, coil: &'a Coil, w: f64 },
}

impl FieldAt<'_> {
    /// B(x) (T).
    #[inline]
    pub fn field(&self, x: &Vec3) -> Vec3 {
        match self {
            FieldAt::Linear { b0, g } => b0 + g * x,
            FieldAt::Coils { b0, coil, w } => b0 + *w * coil.field(*x),
        }
    }

    /// G(x) = ∂B_a/∂x_b (T/m); for coils by central differences ([`Coil::jacobian`]).
    #[inline]
    pub fn jacobian(&self, x: &Vec3) -> Matrix3<f64> {
        match self {
            FieldAt::Linear { g, .. } => *g,
            FieldAt::Coils { w, .. } if *w == 0.0 => Matrix3::zeros(),
            FieldAt::Coils { coil, w, .. } => *w * coil.jacobian(*x),
        }
    }
}

impl AppliedField {
    /// B0 + G x without a waveform.
    pub fn linear(b0: Vec3, g: Matrix3<f64>) -> Self {
        AppliedField { b0, gradient: Gradient::Linear(g), waveform: None }
    }

    /// No field at all.
    pub fn zero() -> Self {
        Self::linear(Vec3::zeros(), Matrix3::zeros())
    }

    /// The field at time `t`. A linear field without a waveform hands over its G unchanged, and
    /// with one w G, which is G or zero exactly: the same operations as B0 + G x.
    pub fn at(&self, t: f64) -> FieldAt<'_> {
        let w = self.waveform.map_or(1.0, |w| w.at(t));
        match &self.gradient {
            Gradient::Linear(g) if self.waveform.is_none() => FieldAt::Linear { b0: self.b0, g: *g },
            Gradient::Linear(g) => FieldAt::Linear { b0: self.b0, g: w * g },
            Gradient::Coils(coil) => FieldAt::Coils { b0: self.b0, coil, w },
        }
    }

    /// The field with the gradient switched on (for the largest field a run can see).
    pub fn on(&self) -> FieldAt<'_> {
        match &self.gradient {
            Gradient::Linear(g) => FieldAt::Linear { b0: self.b0, g: *g },
            Gradient::Coils(coil) => FieldAt::Coils { b0: self.b0, coil, w: 1.0 },
        }
    }

    /// The field B (T) the step estimate takes in the box `lo`..`hi`, gradient on: for a linear
    /// field B at the centre (the paper's boxes are small against the field's scale); for coils
    /// the largest |B| over the centre and the eight corners (a coil's field grows towards its
    /// wires, which lie outside the box, so it is largest on the box's boundary).
    pub fn largest_field(&self, lo: Vec3, hi: Vec3) -> Vec3 {
        let centre = 0.5 * (lo + hi);
        let on = self.on();
        match on {
            FieldAt::Linear { .. } => on.field(&centre),
            FieldAt::Coils { .. } => (0..8)
                .map(|k| Vec3::from_fn(|a, _| if k >> a & 1 == 1 { hi[a] } else { lo[a] }))
                .chain([centre])
                .map(|x| on.field(&x))
                .fold(Vec3::zeros(), |a, b| if b.norm() > a.norm() { b } else { a }),
        }
    }
}
