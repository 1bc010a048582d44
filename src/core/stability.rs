//! Stable time-step estimates (before the run) and the instability monitor (during it).
//!
//! Each stiff term bounds the step itself, for the linearised problem
//! ([`super::forces::setup::TermSpec::stable_dt`]: the contact oscillator, the drag relaxation,
//! the magnetic forces held over K steps); the estimate is the smallest of these hard bounds.
//! The Rayleigh time T_R = π a √(ρ/G) / (0.1631 ν + 0.8766) (as LIGGGHTS prints it) is reported,
//! not enforced (DEM practice keeps dt below ~0.2 T_R).
//!
//! A contact's largest expected overlap comes from the fastest expected impact of two touching
//! dipoles ([`super::forces::magnetisation::impact_speed`]).

use super::forces::setup::{StepBound, StepContext};
use super::state::{Particles, State, Vec3};
use std::f64::consts::PI;

#[derive(Debug, Clone, PartialEq)]
pub struct StepEstimate {
    pub rayleigh_time: f64,
    /// Fastest expected impact speed (m/s).
    pub impact_speed: f64,
    /// Hertz contact duration at that speed.
    pub contact_duration: Option<f64>,
    /// Every term's bound: the contact laws', then the others in build order.
    pub bounds: Vec<StepBound>,
    /// The smallest of the hard bounds, and what sets it.
    pub stable_dt: f64,
    pub limited_by: &'static str,
}

impl StepEstimate {
    /// The estimate from the terms' `bounds`: the Rayleigh time T_R = π a √(ρ/G) / (0.1631 ν +
    /// 0.8766) of the species (reported, not enforced) and the smallest hard bound (the first on
    /// a tie). The contact laws' bounds come first (their clause names the impact speed), the
    /// others in the order given.
    pub fn new(ctx: &StepContext, mut bounds: Vec<StepBound>) -> Self {
        bounds.sort_by_key(|b| b.collision.is_none());
        let rayleigh_time = ctx
            .species
            .iter()
            .map(|s| PI * s.radius * (s.density / s.shear_modulus()).sqrt() / (0.1631 * s.poisson_ratio + 0.8766))
            .fold(f64::INFINITY, f64::min);
        let collisions = || bounds.iter().filter_map(|b| b.collision);
        let impact_speed = collisions().map(|c| c.speed).fold(ctx.max_initial_speed, f64::max);
        let contact_duration = collisions().map(|c| c.duration).reduce(f64::min);
        let mut stable_dt = f64::INFINITY;
        let mut limited_by = "nothing (no stiff term)";
        for b in &bounds {
            if let Some(dt) = b.dt.filter(|&dt| dt < stable_dt) {
                stable_dt = dt;
                limited_by = b.limited_by;
            }
        }
        Self { rayleigh_time, impact_speed, contact_duration, bounds, stable_dt, limited_by }
    }

    /// The hard bound of the term named `term`, if it has one.
    pub fn bound(&self, term: &str) -> Option<f64> {
        self.bounds.iter().find(|b| b.term == term).and_then(|b| b.dt)
    }

    pub fn summary(&self, dt: f64) -> String {
        let mut s = format!(
            "dt = {dt:.3e} s; Rayleigh time {:.3e} s (dt = {:.0}% of it)",
            self.rayleigh_time,
            100.0 * dt / self.rayleigh_time
        );
        for b in &self.bounds {
            s += &b.summary;
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
    Term(#[from] super::forces::TermError),
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
