//! Stable time-step estimates (before the run) and the instability monitor (during it).
//!
//! Bounds, for the linearised problem:
//! - Rayleigh time T_R = π a √(ρ/G) / (0.1631 ν + 0.8766) (as LIGGGHTS prints it); DEM practice
//!   keeps dt below ~0.2 T_R. Reported, not enforced.
//! - Contact oscillator at the largest expected overlap: ω = √(k/m*), k = dδ/dF = 2E*√(R*δ),
//!   damping ratio ζ = −√(5/6) β. Central-difference schemes (Verlet, semi-implicit Euler) are
//!   stable for dt < (2/ω)(√(1+ζ²) − ζ); explicit Euler only for dt < 2ζ/ω (never when e = 1).
//! - Drag relaxation τ = m/(6π μ a): explicit schemes are stable for dt < 2τ.
//! - Magnetic forces held over K steps (r-RESPA, sub-cycled Euler): the dipole attraction at
//!   contact, F = 3μ0 m²/(2π d⁴), is a spring of stiffness |dF/dr| = 4F/d between touching
//!   particles, integrated with the outer step K·dt: stable for K·dt < 2/ω_m, ω_m = √(k_m/m*)
//!   (the Verlet bound on that spring, for r-RESPA; sub-cycled Euler holds the force as forward
//!   Euler does and is bounded more tightly; the stability map measures r-RESPA).
//!
//! The largest expected overlap comes from the fastest expected impact: the relative speed at
//! which two touching dipoles meet when all the magnetic energy μ0 m²/(2π d³) goes into motion,
//! capped by the drag-limited closing speed 2F/(6π μ a) under the contact attraction
//! F = 3μ0 m²/(2π d⁴), or the fastest initial speed if larger; Hertz theory gives the overlap.

use super::forces::contact::law::{restitution_beta, ContactLaw, Normal};
use super::forces::drag::Drag;
use super::integrators::Scheme;
use super::magnetisation::MU0;
use super::state::{Particles, Species, State, Vec3};
use std::f64::consts::PI;

/// What the estimate needs to know about the scene.
#[derive(Debug, Clone)]
pub struct StepEstimateInput<'a> {
    pub species: &'a [Species],
    pub scheme: Scheme,
    /// The contact law, if contacts are included.
    pub contact: Option<ContactLaw>,
    /// Viscosity if drag is included.
    pub drag_viscosity: Option<f64>,
    /// Largest isolated moment magnitude per species (A·m²), if magnetic terms are included.
    pub moments: Vec<f64>,
    pub max_initial_speed: f64,
    /// Steps over which the magnetic forces are held (K of r-RESPA; 1 otherwise).
    pub slow_every: u64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct StepEstimate {
    pub rayleigh_time: f64,
    /// Fastest expected impact speed (m/s).
    pub impact_speed: f64,
    /// Hertz contact duration at that speed.
    pub contact_duration: Option<f64>,
    /// Stability bound of the contact oscillator for this integrator.
    pub contact_bound: Option<f64>,
    /// Bound on dt from the magnetic contact spring held over K steps (K > 1 only).
    pub magnetic_bound: Option<f64>,
    pub drag_relaxation_time: Option<f64>,
    /// The smallest of the hard bounds, and what sets it.
    pub stable_dt: f64,
    pub limited_by: &'static str,
}

impl StepEstimate {
    pub fn new(input: &StepEstimateInput) -> Self {
        let rayleigh_time = input
            .species
            .iter()
            .map(|s| PI * s.radius * (s.density / s.shear_modulus()).sqrt() / (0.1631 * s.poisson_ratio + 0.8766))
            .fold(f64::INFINITY, f64::min);

        let mut impact_speed = input.max_initial_speed;
        let mut contact_duration: Option<f64> = None;
        let mut contact_bound: Option<f64> = None;
        if let Some(law) = input.contact {
            for (k, s) in input.species.iter().enumerate() {
                let m_eff = 0.5 * s.mass();
                let r_eff = 0.5 * s.radius;
                let e_star = s.youngs_modulus / (2.0 * (1.0 - s.poisson_ratio.powi(2)));
                let d = 2.0 * s.radius;
                let moment = input.moments.get(k).copied().unwrap_or(0.0);
                let magnetic_energy = MU0 * moment * moment / (2.0 * PI * d.powi(3));
                let mut v = (2.0 * magnetic_energy / m_eff).sqrt();
                if let Some(mu) = input.drag_viscosity {
                    // Drag-limited closing speed under the contact attraction 3μ0 m²/(2π d⁴).
                    let attraction = 3.0 * MU0 * moment * moment / (2.0 * PI * d.powi(4));
                    v = v.min(2.0 * attraction / Drag::stokes_coefficient(mu, s.radius));
                }
                let v = v.max(input.max_initial_speed).max(1e-6);
                impact_speed = impact_speed.max(v);
                let ln_e = s.restitution.ln();
                let (duration, omega, zeta) = match law.normal {
                    Normal::Hertz => {
                        let overlap = (15.0 * m_eff * v * v / (16.0 * e_star * r_eff.sqrt())).powf(0.4);
                        let duration = 2.87 * (m_eff * m_eff / (r_eff * e_star * e_star * v)).powf(0.2);
                        let omega = (2.0 * e_star * (r_eff * overlap).sqrt() / m_eff).sqrt();
                        (duration, omega, -(5.0_f64 / 6.0).sqrt() * ln_e / (ln_e * ln_e + PI * PI).sqrt())
                    }
                    // A linear spring-dashpot: ω = √(k/m*), ζ = −β, half a damped period.
                    Normal::Hooke { stiffness } => {
                        let beta = restitution_beta(s.restitution);
                        let omega = (stiffness / m_eff).sqrt();
                        (PI / (omega * (1.0 - beta * beta).sqrt()), omega, -beta)
                    }
                };
                let bound = if input.scheme.forward_euler_in_contact() {
                    2.0 * zeta / omega
                } else {
                    2.0 / omega * ((1.0 + zeta * zeta).sqrt() - zeta)
                };
                contact_duration = Some(contact_duration.map_or(duration, |t: f64| t.min(duration)));
                contact_bound = Some(contact_bound.map_or(bound, |t: f64| t.min(bound)));
            }
        }
        let magnetic_bound = (input.slow_every > 1)
            .then(|| {
                input
                    .species
                    .iter()
                    .zip(&input.moments)
                    .filter(|(_, &m)| m > 0.0)
                    .map(|(s, &m)| {
                        let d = 2.0 * s.radius;
                        let stiffness = 4.0 * 3.0 * MU0 * m * m / (2.0 * PI * d.powi(5));
                        let omega = (stiffness / (0.5 * s.mass())).sqrt();
                        2.0 / (omega * input.slow_every as f64)
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .filter(|b| b.is_finite());
        let drag_relaxation_time = input.drag_viscosity.map(|mu| {
            input
                .species
                .iter()
                .map(|s| s.mass() / Drag::stokes_coefficient(mu, s.radius))
                .fold(f64::INFINITY, f64::min)
        });
        let mut stable_dt = f64::INFINITY;
        let mut limited_by = "nothing (no stiff term)";
        if let Some(b) = contact_bound {
            stable_dt = b;
            limited_by = "contact oscillator";
        }
        if let Some(b) = magnetic_bound.filter(|&b| b < stable_dt) {
            stable_dt = b;
            limited_by = "magnetic contact spring held over slow_every steps";
        }
        if let Some(tau) = drag_relaxation_time.filter(|_| !input.scheme.integrates_linear_drag()) {
            if 2.0 * tau < stable_dt {
                stable_dt = 2.0 * tau;
                limited_by = "drag relaxation";
            }
        }
        Self {
            rayleigh_time,
            impact_speed,
            contact_duration,
            contact_bound,
            magnetic_bound,
            drag_relaxation_time,
            stable_dt,
            limited_by,
        }
    }

    pub fn summary(&self, dt: f64) -> String {
        let mut s = format!(
            "dt = {dt:.3e} s; Rayleigh time {:.3e} s (dt = {:.0}% of it)",
            self.rayleigh_time,
            100.0 * dt / self.rayleigh_time
        );
        if let (Some(tc), Some(b)) = (self.contact_duration, self.contact_bound) {
            s += &format!(
                "; impact speed up to {:.3e} m/s: Hertz contact {:.3e} s, stability bound {:.3e} s",
                self.impact_speed, tc, b
            );
        }
        if let Some(b) = self.magnetic_bound {
            s += &format!("; magnetic forces held over slow_every steps: bound {b:.3e} s");
        }
        if let Some(tau) = self.drag_relaxation_time {
            s += &format!("; drag relaxation {tau:.3e} s");
        }
        s + &format!("; estimated stable dt {:.3e} s ({})", self.stable_dt, self.limited_by)
    }
}

/// Why a run stopped early.
#[derive(Debug, Clone, thiserror::Error)]
pub enum Instability {
    #[error("{quantity} of particle {particle} is not finite")]
    NotFinite { quantity: &'static str, particle: usize },
    #[error(
        "runaway overlap: particles {i} and {j} overlap by {ratio:.3} of the smaller diameter \
         (limit {limit})"
    )]
    Overlap { i: u32, j: String, ratio: f64, limit: f64 },
    #[error(
        "energy blow-up: particle {particle} moves {fraction:.2} of its radius per step at \
         {speed:.3e} m/s (limit {limit}); kinetic energy {kinetic_energy:.3e} J"
    )]
    Runaway { particle: usize, speed: f64, fraction: f64, limit: f64, kinetic_energy: f64 },
    #[error("particle {particle} left the box through the {face} wall at {position:?}")]
    Escaped { particle: usize, face: String, position: [f64; 3] },
    #[error(transparent)]
    Induction(#[from] super::magnetisation::InductionError),
}

/// Thresholds checked after every step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Monitor {
    /// Largest overlap allowed, as a fraction of the smaller diameter.
    pub max_overlap: f64,
    /// Largest distance a particle may travel in one step, as a fraction of its radius.
    pub max_step_fraction: f64,
}

impl Default for Monitor {
    fn default() -> Self {
        Self { max_overlap: 0.1, max_step_fraction: 0.25 }
    }
}

/// The per-particle test of [`Monitor::check`]: finite, not faster than `travel` radii per
/// second, not more than a radius beyond a wall (`lo`/`hi` are infinite on periodic axes).
struct QuickTest {
    lo: Vec3,
    hi: Vec3,
    travel: f64,
}

impl QuickTest {
    #[inline(always)]
    fn fails(&self, x: &Vec3, v: &Vec3, a: f64) -> bool {
        // Every comparison with NaN is false, so a NaN velocity fails the speed test and a NaN
        // position the wall test (infinite bounds included); an infinite velocity fails the
        // speed test, and an infinite position needs one a step earlier.
        let limit = self.travel * a;
        let inside = (x.x >= self.lo.x - a)
            & (x.y >= self.lo.y - a)
            & (x.z >= self.lo.z - a)
            & (x.x <= self.hi.x + a)
            & (x.y <= self.hi.y + a)
            & (x.z <= self.hi.z + a);
        // Negated so that a NaN speed fails the test.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let too_fast = !(v.norm_squared() <= limit * limit);
        too_fast | !inside
    }
}

impl Monitor {
    pub fn check(&self, state: &State, domain: &super::domain::Domain, dt: f64) -> Result<(), Instability> {
        let p: &Particles = &state.particles;
        let d = state.diagnostics;
        if d.max_overlap_ratio > self.max_overlap {
            let j = d.max_overlap_pair.1.map_or("the wall".to_string(), |j| state.id(j as usize).to_string());
            return Err(Instability::Overlap {
                i: state.id(d.max_overlap_pair.0 as usize) as u32,
                j,
                ratio: d.max_overlap_ratio,
                limit: self.max_overlap,
            });
        }
        // A cheap test per particle; the failing particle (the first, for any thread count) is
        // then examined to say what went wrong.
        let bounds = QuickTest {
            lo: Vec3::from_fn(|k, _| if domain.periodic[k] { f64::NEG_INFINITY } else { domain.lo[k] }),
            hi: Vec3::from_fn(|k, _| if domain.periodic[k] { f64::INFINITY } else { domain.hi[k] }),
            travel: self.max_step_fraction / dt,
        };
        let suspect = |((x, v), a): ((&Vec3, &Vec3), &f64)| bounds.fails(x, v, *a);
        let particles = || p.position.iter().zip(&p.velocity).zip(&p.radius);
        // Branch-free test of all particles first; the first failing one is looked for only then.
        let parts = (&p.position[..], &p.velocity[..], &p.radius[..]);
        let any = super::parallel::any_share(parts, |(x, v, a)| {
            x.iter().zip(v).zip(a).fold(false, |out, item| out | suspect(item))
        });
        let first = if any { particles().position(suspect) } else { None };
        match first {
            Some(i) => Err(self.diagnose(state, i, domain, dt)),
            None => Ok(()),
        }
    }

    /// What is wrong with particle `i`, which failed the quick test.
    fn diagnose(&self, state: &State, i: usize, domain: &super::domain::Domain, dt: f64) -> Instability {
        let p = &state.particles;
        let force = state.fields.force.get(i).copied().unwrap_or_else(Vec3::zeros);
        for (q, v) in [("position", &p.position[i]), ("velocity", &p.velocity[i]), ("force", &force)] {
            if !v.iter().all(|c| c.is_finite()) {
                return Instability::NotFinite { quantity: q, particle: state.id(i) };
            }
        }
        let limit = self.max_step_fraction / dt * p.radius[i];
        if p.velocity[i].norm_squared() > limit * limit {
            let speed = p.velocity[i].norm();
            return Instability::Runaway {
                particle: state.id(i),
                speed,
                fraction: speed * dt / p.radius[i],
                limit: self.max_step_fraction,
                kinetic_energy: p.kinetic_energy(),
            };
        }
        let x = p.position[i];
        let (_, k, upper) = domain
            .walls()
            .find(
                |&(_, k, upper)| {
                    if upper {
                        x[k] - domain.hi[k] > p.radius[i]
                    } else {
                        domain.lo[k] - x[k] > p.radius[i]
                    }
                },
            )
            .expect("a particle that failed the check is outside a wall");
        let face = format!("{}-{}", ["x", "y", "z"][k], if upper { "hi" } else { "lo" });
        Instability::Escaped { particle: state.id(i), face, position: [x.x, x.y, x.z] }
    }
}
