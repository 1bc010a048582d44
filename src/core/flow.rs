//! Blood flow in a straight cylindrical vessel: steady Poiseuille flow and pulsatile Womersley
//! flow given by the harmonics of its flow rate. Each gives the fluid velocity u(x, t) that the
//! drag laws take the particle's velocity relative to.

use super::vector::Vec3;
use nalgebra::{Complex, Unit};
use std::f64::consts::PI;
use std::sync::Arc;

/// A straight cylindrical vessel: its axis through `centre` along `axis`, and its `radius` (m).
#[derive(Debug, Clone, Copy)]
pub struct Vessel {
    pub centre: Vec3,
    pub axis: Unit<Vec3>,
    pub radius: f64,
}

impl Vessel {
    /// Distance from the axis.
    pub fn radial(&self, at: Vec3) -> f64 {
        let d = at - self.centre;
        (d - d.dot(&self.axis) * self.axis.into_inner()).norm()
    }
}

/// One harmonic of the flow rate, Q(t) = Re[q e^{i n ω t}] (m³/s, complex amplitude).
#[derive(Debug, Clone, Copy)]
pub struct Harmonic {
    pub n: u32,
    pub q: Complex<f64>,
}

/// Flow along a vessel: steady Poiseuille (`period` none, the mean flow rate alone) or
/// Womersley's pulsatile flow of the given flow-rate harmonics.
#[derive(Debug, Clone)]
pub struct VesselFlow {
    pub vessel: Vessel,
    /// Mean flow rate (m³/s).
    pub mean_flow: f64,
    /// Period of the pulse (s) and its harmonics n ≥ 1; empty for steady flow.
    pub period: f64,
    pub harmonics: Vec<Harmonic>,
    /// Fluid density (kg/m³) and viscosity (Pa s).
    pub density: f64,
    pub viscosity: f64,
}

impl VesselFlow {
    /// Steady Poiseuille flow of mean speed `mean_speed` (m/s): u = 2 ū (1 − r²/R²) along the axis.
    pub fn poiseuille(vessel: Vessel, mean_speed: f64, density: f64, viscosity: f64) -> Self {
        let mean_flow = mean_speed * PI * vessel.radius * vessel.radius;
        VesselFlow { vessel, mean_flow, period: f64::INFINITY, harmonics: vec![], density, viscosity }
    }

    /// The steady flow's speed on the axis, 2 Q̄/(πR²) = 2ū (the LIGGGHTS and LAMMPS decks
    /// write it as a number, so that their u(r) rounds as [`Self::axial_speed`] does).
    pub fn centreline_speed(&self) -> f64 {
        let big_r = self.vessel.radius;
        2.0 * self.mean_flow / (PI * big_r * big_r)
    }

    /// Womersley's number of harmonic `n`: α = R √(n ω ρ / μ).
    pub fn womersley_number(&self, n: u32) -> f64 {
        let omega = 2.0 * PI * n as f64 / self.period;
        self.vessel.radius * (omega * self.density / self.viscosity).sqrt()
    }

    /// The axial speed at distance `r` from the axis at time `t` (zero outside the vessel):
    /// the Poiseuille term 2 Q̄/(πR²)(1 − r²/R²) plus, per harmonic (Womersley 1955),
    /// Re[ q/(πR²) · (1 − J0(Λ r/R)/J0(Λ)) / (1 − 2 J1(Λ)/(Λ J0(Λ))) · e^{i n ω t} ], Λ = i^{3/2} α.
    pub fn axial_speed(&self, r: f64, t: f64) -> f64 {
        let big_r = self.vessel.radius;
        if r >= big_r {
            return 0.0;
        }
        let area = PI * big_r * big_r;
        let s = r / big_r;
        let mut u = self.centreline_speed() * (1.0 - s * s);
        for h in &self.harmonics {
            let lambda = Complex::new(-1.0, 1.0) / 2f64.sqrt() * self.womersley_number(h.n);
            let j0 = bessel_j0(lambda);
            let shape = (Complex::new(1.0, 0.0) - bessel_j0(lambda * s) / j0)
                / (Complex::new(1.0, 0.0) - 2.0 * bessel_j1(lambda) / (lambda * j0));
            let phase = Complex::from_polar(1.0, 2.0 * PI * h.n as f64 * t / self.period);
            u += (h.q / area * shape * phase).re;
        }
        u
    }

    /// The fluid velocity at `at` and time `t`.
    pub fn velocity(&self, at: Vec3, t: f64) -> Vec3 {
        self.axial_speed(self.vessel.radial(at), t) * self.vessel.axis.into_inner()
    }

    /// The flow rate at time `t`: Q̄ + Σ Re[q e^{i n ω t}].
    pub fn flow_rate(&self, t: f64) -> f64 {
        self.mean_flow
            + self
                .harmonics
                .iter()
                .map(|h| (h.q * Complex::from_polar(1.0, 2.0 * PI * h.n as f64 * t / self.period)).re)
                .sum::<f64>()
    }
}

/// The fluid's velocity field u(x, t), which the drag laws take each particle's velocity relative
/// to.
#[derive(Debug, Clone)]
pub enum Flow {
    /// The same velocity everywhere and always (zero: the fluid at rest).
    Uniform(Vec3),
    /// Poiseuille or Womersley flow along a straight vessel, zero outside it.
    Vessel(VesselFlow),
    /// Velocities on a grid (a CFD solution), trilinear in space and linear in time.
    Grid(Arc<GriddedFlow>),
}

impl Flow {
    /// u(x, t).
    #[inline]
    pub fn velocity(&self, at: Vec3, t: f64) -> Vec3 {
        match self {
            Flow::Uniform(u) => *u,
            Flow::Vessel(flow) => flow.velocity(at, t),
            Flow::Grid(grid) => grid.velocity(at, t),
        }
    }

    /// The vessel the flow runs along, if any.
    pub fn vessel(&self) -> Option<&Vessel> {
        match self {
            Flow::Uniform(_) | Flow::Grid(_) => None,
            Flow::Vessel(flow) => Some(&flow.vessel),
        }
    }

    /// The velocity of a uniform flow, `None` for one that varies in space or time.
    pub fn uniform(&self) -> Option<Vec3> {
        match self {
            Flow::Uniform(u) => Some(*u),
            Flow::Vessel(_) | Flow::Grid(_) => None,
        }
    }
}

/// A velocity field sampled on a regular grid at one or more times: node (i, j, k) of frame f
/// sits at origin + (i, j, k) ∘ spacing and time `times[f]`. Between nodes the velocity is
/// trilinear, between frames linear; before the first frame and after the last it holds the
/// end frame, unless the frames repeat with `period`.
#[derive(Debug, Clone, PartialEq)]
pub struct GriddedFlow {
    pub origin: Vec3,
    pub spacing: Vec3,
    /// Nodes along x, y and z (at least 2 each).
    pub shape: [usize; 3],
    /// Ascending frame times (s).
    pub times: Vec<f64>,
    /// The frames repeat with this period (s): frame f also stands at times[f] + n period.
    pub period: Option<f64>,
    /// Frame by frame, node (i, j, k) at `((f nx + i) ny + j) nz + k` (z fastest).
    pub velocity: Vec<Vec3>,
}

impl GriddedFlow {
    /// The grid's far corner.
    pub fn end(&self) -> Vec3 {
        self.origin + self.spacing.component_mul(&Vec3::from_fn(|k, _| (self.shape[k] - 1) as f64))
    }

    /// Node (i, j, k) of frame f.
    #[inline]
    fn node(&self, f: usize, i: usize, j: usize, k: usize) -> Vec3 {
        let [nx, ny, nz] = self.shape;
        self.velocity[((f * nx + i) * ny + j) * nz + k]
    }

    /// Trilinear interpolation in frame f: with s = (x − origin)/spacing, cell c = ⌊s⌋ (kept
    /// inside the grid) and weights w = s − c, the sum over the cell's corners of
    /// Π (w or 1 − w) u_corner. Exact at the nodes and linear along each axis between them.
    fn in_frame(&self, f: usize, at: Vec3) -> Vec3 {
        let mut cell = [0usize; 3];
        let mut w = [0.0; 3];
        for a in 0..3 {
            let s = (at[a] - self.origin[a]) / self.spacing[a];
            let c = (s.floor().max(0.0) as usize).min(self.shape[a] - 2);
            cell[a] = c;
            w[a] = (s - c as f64).clamp(0.0, 1.0);
        }
        let [i, j, k] = cell;
        let mut u = Vec3::zeros();
        for (di, wi) in [(0, 1.0 - w[0]), (1, w[0])] {
            for (dj, wj) in [(0, 1.0 - w[1]), (1, w[1])] {
                for (dk, wk) in [(0, 1.0 - w[2]), (1, w[2])] {
                    u += wi * wj * wk * self.node(f, i + di, j + dj, k + dk);
                }
            }
        }
        u
    }

    /// u(x, t): trilinear in the frames either side of t, linear between them.
    pub fn velocity(&self, at: Vec3, t: f64) -> Vec3 {
        let last = self.times.len() - 1;
        let t0 = self.times[0];
        let t = match self.period {
            Some(p) => t0 + (t - t0).rem_euclid(p),
            None => t.clamp(t0, self.times[last]),
        };
        // The frame at or before t, and the one after (the first again, a period on, if they repeat).
        let f = self.times.partition_point(|&s| s <= t).saturating_sub(1);
        let (g, t_next) = match (f < last, self.period) {
            (true, _) => (f + 1, self.times[f + 1]),
            (false, Some(p)) => (0, t0 + p),
            (false, None) => return self.in_frame(f, at),
        };
        let w = (t - self.times[f]) / (t_next - self.times[f]);
        (1.0 - w) * self.in_frame(f, at) + w * self.in_frame(g, at)
    }
}

/// The largest Womersley number the series below hold to about 1e-8 (their terms grow to
/// e^α / α before they cancel); arteries reach about 20 in the aorta.
pub const MAX_WOMERSLEY: f64 = 25.0;

/// J0(z) = Σ (−z²/4)^k / (k!)², summed until the terms fall below round-off.
pub fn bessel_j0(z: Complex<f64>) -> Complex<f64> {
    let q = -z * z / 4.0;
    let (mut term, mut sum) = (Complex::new(1.0, 0.0), Complex::new(1.0, 0.0));
    for k in 1..200 {
        term *= q / (k * k) as f64;
        sum += term;
        if term.norm() < 1e-17 * sum.norm() {
            break;
        }
    }
    sum
}

/// J1(z) = (z/2) Σ (−z²/4)^k / (k! (k+1)!).
pub fn bessel_j1(z: Complex<f64>) -> Complex<f64> {
    let q = -z * z / 4.0;
    let (mut term, mut sum) = (Complex::new(1.0, 0.0), Complex::new(1.0, 0.0));
    for k in 1..200 {
        term *= q / (k * (k + 1)) as f64;
        sum += term;
        if term.norm() < 1e-17 * sum.norm() {
            break;
        }
    }
    z / 2.0 * sum
}
