//! `[forces.contact]`: the contact law's keys, checks, step bound and construction.

use super::law::{restitution_beta, ContactLaw, Normal, Tangential};
use super::Contact;
use crate::core::forces::setup::{
    invalid, positive, Collision, Invalid, SceneContext, StepBound, StepContext, TermSpec,
};
use crate::core::forces::ForceTerm;
use serde::Deserialize;
use std::f64::consts::PI;

/// The contact law: by default Hertz–Mindlin with history and restitution damping (LIGGGHTS'
/// `hertz tangential history`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Contacts between particles (default true); false leaves the walls only: particles that
    /// do not touch each other, as in a deposition study of independent particles.
    #[serde(default = "default_true")]
    pub particles: bool,
    /// Particle–wall contacts on the wall faces, and on a `[fluid.vessel]`'s surface (default
    /// true).
    #[serde(default = "default_true")]
    pub walls: bool,
    /// Normal force: `hertz` (default) or `hooke` (a linear spring of `stiffness`).
    #[serde(default)]
    pub normal: NormalSpec,
    /// Hooke's spring stiffness (N/m); only with `normal = "hooke"`.
    pub stiffness: Option<f64>,
    /// Tangential force: `mindlin` (default: spring with history, Coulomb limit) or `none`
    /// (frictionless spheres).
    #[serde(default)]
    pub tangential: TangentialSpec,
}

fn default_true() -> bool {
    true
}

#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum NormalSpec {
    #[default]
    Hertz,
    Hooke,
}

#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum TangentialSpec {
    #[default]
    Mindlin,
    None,
}

impl ContactSpec {
    /// The law the table chooses (checked: Hooke has its stiffness).
    pub fn law(&self) -> ContactLaw {
        let normal = match self.normal {
            NormalSpec::Hertz => Normal::Hertz,
            NormalSpec::Hooke => Normal::Hooke { stiffness: self.stiffness.unwrap_or(f64::NAN) },
        };
        let tangential = match self.tangential {
            TangentialSpec::Mindlin => Tangential::Mindlin,
            TangentialSpec::None => Tangential::None,
        };
        ContactLaw { normal, tangential }
    }
}

impl TermSpec for ContactSpec {
    fn check(&self, _ctx: &SceneContext) -> Result<(), Invalid> {
        match (self.normal, self.stiffness) {
            (NormalSpec::Hooke, Some(k)) => positive("forces.contact.stiffness", k),
            (NormalSpec::Hooke, None) => {
                Err(invalid("forces.contact.normal", "hooke", "needs forces.contact.stiffness (N/m)"))
            }
            (NormalSpec::Hertz, Some(k)) => Err(invalid(
                "forces.contact.stiffness",
                k,
                "applies to normal = \"hooke\" only (Hertz's stiffness follows from the species)",
            )),
            (NormalSpec::Hertz, None) => Ok(()),
        }
    }

    /// The contact oscillator at the largest expected overlap, from the fastest impact
    /// ([`StepContext::impact_speeds`]) of each species against itself (m* = m/2, R* = a/2,
    /// E* = E/(2(1 − ν²))). Hertz: overlap δ = (15 m* v²/(16 E* √R*))^(2/5), contact duration
    /// 2.87 (m*²/(R* E*² v))^(1/5), ω = √(2E*√(R*δ)/m*), damping ratio ζ = −√(5/6) β; Hooke:
    /// ω = √(k/m*), ζ = −β, half a damped period. Central-difference schemes (Verlet,
    /// semi-implicit Euler) are stable for dt < (2/ω)(√(1+ζ²) − ζ), explicit Euler only for
    /// dt < 2ζ/ω (never when e = 1).
    fn stable_dt(&self, ctx: &StepContext) -> Option<StepBound> {
        let law = self.law();
        let (mut speed, mut duration, mut bound) = (ctx.max_initial_speed, f64::INFINITY, f64::INFINITY);
        for (k, s) in ctx.species.iter().enumerate() {
            let m_eff = 0.5 * s.mass();
            let r_eff = 0.5 * s.radius;
            let e_star = s.youngs_modulus / (2.0 * (1.0 - s.poisson_ratio.powi(2)));
            let v = ctx.impact_speeds[k];
            speed = speed.max(v);
            let ln_e = s.restitution.ln();
            let (t, omega, zeta) = match law.normal {
                Normal::Hertz => {
                    let overlap = (15.0 * m_eff * v * v / (16.0 * e_star * r_eff.sqrt())).powf(0.4);
                    let t = 2.87 * (m_eff * m_eff / (r_eff * e_star * e_star * v)).powf(0.2);
                    let omega = (2.0 * e_star * (r_eff * overlap).sqrt() / m_eff).sqrt();
                    (t, omega, -(5.0_f64 / 6.0).sqrt() * ln_e / (ln_e * ln_e + PI * PI).sqrt())
                }
                Normal::Hooke { stiffness } => {
                    let beta = restitution_beta(s.restitution);
                    let omega = (stiffness / m_eff).sqrt();
                    (PI / (omega * (1.0 - beta * beta).sqrt()), omega, -beta)
                }
            };
            let b = if ctx.scheme.spec().forward_euler_in_contact() {
                2.0 * zeta / omega
            } else {
                2.0 / omega * ((1.0 + zeta * zeta).sqrt() - zeta)
            };
            duration = if k == 0 { t } else { duration.min(t) };
            bound = if k == 0 { b } else { bound.min(b) };
        }
        Some(StepBound {
            term: "contact",
            dt: Some(bound),
            limited_by: "contact oscillator",
            collision: Some(Collision { speed, duration }),
            summary: format!(
                "; impact speed up to {speed:.3e} m/s: Hertz contact {duration:.3e} s, stability bound {bound:.3e} s"
            ),
        })
    }

    fn build(&self, ctx: &SceneContext) -> Box<dyn ForceTerm> {
        let vessel = ctx.fluid.as_ref().and_then(|f| f.flow.vessel()).copied();
        let contact = Contact::new(ctx.species, self.law(), self.walls, ctx.pairs.near).with_vessel(vessel);
        Box::new(if self.particles { contact } else { contact.walls_only() })
    }
}
