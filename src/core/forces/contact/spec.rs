//! `[forces.contact]`: the contact law's keys, checks, step bound and construction.

use super::law::{restitution_beta, ContactLaw, Normal, Tangential};
use super::Contact;
use crate::core::forces::setup::{
    invalid, positive, Collision, Invalid, SceneContext, StepBound, StepContext, TermSpec,
};
use crate::core::forces::thermal::BOLTZMANN;
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
        if ctx.scheme.spec().overdamped() {
            return overdamped_bound(self.law(), ctx);
        }
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

/// The contact's step bound under overdamped dynamics (`scheme = "brownian"`), where a contact
/// has no oscillator: its overlap and its spring relax. Two touching spheres of one species (a,
/// mobilities μ = 1/(6πηa), μ_r = 1/(8πηa³)): Euler's overlap obeys δ ← δ − 2μ k_n δ h, k_n =
/// dF/dδ = 2E*√(R*δ) (Hertz, R* = a/2, E* = E/(2(1 − ν²))) or the Hooke stiffness; the Mindlin
/// spring s ← s − 2(μ + a²μ_r) k_t s h = s − 3.5 μ k_t s h, k_t = 8G*√(R*δ), G* = E/(4(2 − ν)(1 + ν)).
/// Each update is monotone (no overshoot through zero) for h ≤ 1/λ, λ the larger rate: the
/// bound is the contact's overdamped relaxation time 1/λ. The overlap is the deepest one a step
/// makes from touching: the drift closing speed times h ([`StepContext::impact_speeds`]) plus five
/// standard deviations √(4Dh) of the relative noise along the line of centres, D = kT μ. As δ
/// grows with h, h λ(δ(h)) = 1 is solved by bisection on ln h. A wall contact (R* = a, mobility
/// μ) relaxes 2^(3/4) times slower at the same noise (Hertz), so the pair bounds it.
fn overdamped_bound(law: ContactLaw, ctx: &StepContext) -> Option<StepBound> {
    let (Some(mu), Some(temperature)) = (ctx.drag_viscosity, ctx.temperature) else {
        return None;
    };
    let kt = BOLTZMANN * temperature;
    let (mut bound, mut deepest, mut speed) = (f64::INFINITY, 0.0, ctx.max_initial_speed);
    for (k, s) in ctx.species.iter().enumerate() {
        let a = s.radius;
        let mobility = 1.0 / (6.0 * PI * mu * a);
        let diffusion = kt * mobility;
        let e_star = s.youngs_modulus / (2.0 * (1.0 - s.poisson_ratio.powi(2)));
        let g_star = s.youngs_modulus / (4.0 * (2.0 - s.poisson_ratio) * (1.0 + s.poisson_ratio));
        let v = ctx.impact_speeds[k];
        speed = speed.max(v);
        let overlap = |h: f64| v * h + 5.0 * (4.0 * diffusion * h).sqrt();
        let rate = |h: f64| {
            let sq = (0.5 * a * overlap(h)).sqrt();
            let normal = match law.normal {
                Normal::Hertz => 2.0 * e_star * sq,
                Normal::Hooke { stiffness } => stiffness,
            };
            let tangential = match law.tangential {
                Tangential::Mindlin => 8.0 * g_star * sq,
                Tangential::None => 0.0,
            };
            (2.0 * mobility * normal).max(3.5 * mobility * tangential)
        };
        // h λ(δ(h)) grows with h: bisect ln h between 1e-24 s and 1e6 s.
        let (mut lo, mut hi) = (1e-24_f64.ln(), 1e6_f64.ln());
        if hi.exp() * rate(hi.exp()) <= 1.0 {
            lo = hi;
        } else {
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if mid.exp() * rate(mid.exp()) > 1.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
        }
        let h = lo.exp();
        if h < bound {
            (bound, deepest) = (h, overlap(h));
        }
    }
    Some(StepBound {
        term: "contact",
        dt: Some(bound),
        limited_by: "overdamped contact relaxation",
        collision: Some(Collision { speed, duration: bound }),
        summary: format!(
            "; overdamped contact: drift closing speed up to {speed:.3e} m/s and the noise give an overlap of \
             {deepest:.3e} m, relaxation bound {bound:.3e} s"
        ),
    })
}
