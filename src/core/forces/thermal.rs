//! Thermal forces consistent with the Stokes drag (fluctuation–dissipation, inertial Langevin):
//! on each particle F = √(2 kT γ/dt) ξ and, with the rotational drag, T = √(2 kT γ_r/dt) ξ_r,
//! γ = 6π μ a, γ_r = 8π μ a³, ξ standard normal and held over the step. ξ is drawn by the
//! counter-based generator of [`crate::core::noise`] from the scene's seed, the step and the
//! particle's id, so a run gives the same bits on any number of threads and after `--resume`.
//! With velocity Verlet the free particle's ⟨v²⟩ is 3kT/m at any dt/τ and its long-time diffusion
//! coefficient kT/γ (docs/model.md §13).

use super::drag::DragLawSpec;
use super::setup::{invalid, positive, Invalid, SceneContext, StepBound, StepContext, TermSpec};
use super::{Context, ForceTerm, Forces, Renumbering, TermError};
use crate::core::noise::{Noise, Stream};
use crate::core::parallel;
use crate::core::state::{Particles, Species, State, Vec3};
use std::f64::consts::PI;

/// Boltzmann's constant (J/K), exact in the SI since 2019.
pub const BOLTZMANN: f64 = 1.380_649e-23;

/// The largest rms displacement √(6 D h) of an overdamped step, as a fraction of the radius.
pub const BROWNIAN_STEP: f64 = 0.1;

#[derive(Debug, Clone)]
pub struct Thermal {
    /// kT (J).
    pub kt: f64,
    /// μ (Pa s) of the drag the noise balances.
    pub viscosity: f64,
    /// Rotational noise, balancing the rotational drag.
    pub rotational: bool,
    pub noise: Noise,
    /// The overdamped scheme draws the noise itself (`scheme = "brownian"`): the term adds nothing.
    pub in_integrator: bool,
    /// This evaluation's force and torque per slot (zero at dt = 0, the setup evaluation).
    force: Vec<Vec3>,
    torque: Vec<Vec3>,
}

impl Thermal {
    pub fn new(temperature: f64, viscosity: f64, rotational: bool, seed: u64) -> Self {
        let kt = BOLTZMANN * temperature;
        Self { kt, viscosity, rotational, noise: Noise { seed }, in_integrator: false, force: vec![], torque: vec![] }
    }
}

impl ForceTerm for Thermal {
    fn name(&self) -> &'static str {
        "thermal"
    }
    /// Draws each particle's force (and torque) for the state's step.
    fn prepare(&mut self, ctx: &Context, state: &State) -> Result<(), TermError> {
        if self.in_integrator {
            return Ok(());
        }
        let p = &state.particles;
        let (kt, mu, dt, step, noise) = (self.kt, self.viscosity, ctx.dt, state.step, self.noise);
        let scale = |gamma: f64| if dt > 0.0 { (2.0 * kt * gamma / dt).sqrt() } else { 0.0 };
        let draw = |stream: Stream, gamma: &(dyn Fn(f64) -> f64 + Sync), out: &mut Vec<Vec3>| {
            out.resize(p.len(), Vec3::zeros());
            parallel::for_each_share(&mut out[..], |first, share| {
                for (k, f) in share.iter_mut().enumerate() {
                    let slot = first + k;
                    let id = state.id(slot) as u32;
                    *f = scale(gamma(p.radius[slot])) * Vec3::from(noise.normal3(step, id, stream));
                }
            });
        };
        draw(Stream::Translation, &|a| 6.0 * PI * mu * a, &mut self.force);
        if self.rotational {
            draw(Stream::Rotation, &|a| 8.0 * PI * mu * a.powi(3), &mut self.torque);
        }
        Ok(())
    }
    fn apply(&mut self, _ctx: &Context, _p: &Particles, out: &mut Forces) {
        if self.in_integrator {
            return;
        }
        parallel::for_each_share((&mut *out.force, &self.force[..]), |_, (f, n)| {
            f.iter_mut().zip(n).for_each(|(f, n)| *f += n)
        });
        if self.rotational {
            parallel::for_each_share((&mut *out.torque, &self.torque[..]), |_, (t, n)| {
                t.iter_mut().zip(n).for_each(|(t, n)| *t += n)
            });
        }
    }
    /// The draws are redone at every evaluation, by particle id.
    fn renumber(&mut self, _r: &Renumbering) {
        self.force.clear();
        self.torque.clear();
    }
}

/// `[forces.thermal]`: Brownian forces at `temperature`, balancing `[forces.drag]`.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalSpec {
    /// T (K).
    pub temperature: f64,
}

impl TermSpec for ThermalSpec {
    /// The noise balances a lone sphere's Stokes drag (Schiller–Naumann's at vanishing Re), so it
    /// needs that drag, unshielded and without a wall, and an integrator that evaluates each step
    /// once per time (not adaptive step doubling, which would reuse a step's draw) and does not
    /// integrate the drag itself (exponential Verlet would need the noise of its exact update).
    /// The overdamped scheme (`brownian`) takes the temperature and draws its own noise.
    fn check(&self, ctx: &SceneContext) -> Result<(), Invalid> {
        positive("forces.thermal.temperature", self.temperature)?;
        let Some(drag) = &ctx.forces.drag else {
            return Err(invalid("forces.thermal", "{…}", "thermal forces balance a drag: add [forces.drag]"));
        };
        if let Some((key, value, why)) = drag.unlike_stokes() {
            return Err(invalid(key, value, format!("the thermal forces balance a lone sphere's Stokes drag; {why}")));
        }
        let scheme = ctx.scheme.spec();
        if scheme.overdamped() {
            if drag.law != DragLawSpec::Stokes {
                return Err(invalid(
                    "forces.drag.law",
                    "schiller-naumann", // RPY is refused above
                    format!("the {} scheme moves each sphere with a lone sphere's Stokes mobility 1/(6πμa); use law = \"stokes\"", ctx.scheme),
                ));
            }
            if !drag.rotational {
                return Err(invalid(
                    "forces.drag.rotational",
                    false,
                    format!(
                        "the {} scheme turns the particles with the rotational mobility 1/(8πμa³); set it true",
                        ctx.scheme
                    ),
                ));
            }
        }
        if scheme.compares_evaluations() || (scheme.integrates_linear_drag() && !scheme.overdamped()) {
            return Err(invalid(
                "integration.scheme",
                ctx.scheme,
                "draws the noise once per step; use velocity-verlet (or respa) with dt well below m/γ",
            ));
        }
        Ok(())
    }
    /// The rms thermal speed √(3kT/m) may carry the lightest particle a tenth of its radius in a
    /// step (contacts then resolve as without noise). Overdamped, a step's rms displacement
    /// √(6 D h), D = kT/(6π μ a), may be a tenth of the smallest radius: h ≤ (a/10)²/(6D).
    fn stable_dt(&self, ctx: &StepContext) -> Option<StepBound> {
        let kt = BOLTZMANN * self.temperature;
        if let (true, Some(mu)) = (ctx.scheme.spec().overdamped(), ctx.drag_viscosity) {
            let bound = ctx
                .species
                .iter()
                .map(|s| (BROWNIAN_STEP * s.radius).powi(2) / (6.0 * kt / (6.0 * PI * mu * s.radius)))
                .fold(f64::INFINITY, f64::min);
            return Some(StepBound {
                term: "thermal",
                dt: Some(bound),
                limited_by: "Brownian displacement",
                collision: None,
                summary: format!("; Brownian rms displacement of a tenth of a radius {bound:.3e} s"),
            });
        }
        let bound =
            ctx.species.iter().map(|s| 0.1 * s.radius / (3.0 * kt / s.mass()).sqrt()).fold(f64::INFINITY, f64::min);
        Some(StepBound {
            term: "thermal",
            dt: Some(bound),
            limited_by: "thermal motion",
            collision: None,
            summary: format!("; thermal motion of a tenth of a radius {bound:.3e} s"),
        })
    }
    /// Five standard deviations of the relative speed of two particles along their line of
    /// centres, 5 √(2kT/m): the Maxwell tail a collision reaches about once in 10⁶ encounters.
    fn agitation_speed(&self, species: &Species) -> f64 {
        5.0 * (2.0 * BOLTZMANN * self.temperature / species.mass()).sqrt()
    }
    fn build(&self, ctx: &SceneContext) -> Box<dyn ForceTerm> {
        let viscosity = ctx.fluid.as_ref().expect("checked: the drag has a [fluid] table").viscosity;
        let rotational = ctx.forces.drag.as_ref().is_some_and(|d| d.rotational);
        let mut thermal = Thermal::new(self.temperature, viscosity, rotational, ctx.seed);
        thermal.in_integrator = ctx.scheme.spec().overdamped();
        Box::new(thermal)
    }
}
