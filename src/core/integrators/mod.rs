//! Time integrators. An integrator does not own the state: it advances a [`State`] by one step,
//! calling back into the force pipeline. On entry and on exit `force`/`torque` belong to the
//! current state, so each step costs one force evaluation.

mod adaptive_verlet;
mod explicit_euler;
mod exponential_verlet;
mod respa;
mod semi_implicit_euler;
mod velocity_verlet;

pub use adaptive_verlet::AdaptiveVerlet;
pub use explicit_euler::ExplicitEuler;
pub use exponential_verlet::ExponentialVerlet;
pub use respa::Respa;
pub use semi_implicit_euler::SemiImplicitEuler;
pub use velocity_verlet::VelocityVerlet;

use super::simulation::ForceGroup;
use super::state::{Particles, State, Vec3};

/// Re-evaluates one group of forces and torques for the state as it stands, at the end of a
/// step of the given length (the contact model integrates its tangential history over it).
pub type Evaluate<'a> = dyn FnMut(&mut State, ForceGroup, f64) + 'a;

pub trait Integrator: Send {
    fn name(&self) -> &'static str;
    /// Global order of accuracy for smooth forces.
    fn order(&self) -> u32;
    /// Steps of `dt` one call of `step` advances (more than one for multiple time stepping).
    fn steps_per_call(&self) -> u64 {
        1
    }
    /// Whether the integrator keeps slow forces apart (in `slow_force`/`slow_torque`).
    fn splits_forces(&self) -> bool {
        false
    }
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate);
}

/// Scheme names a scene may give (`exponential-verlet` is built by the scene layer, which knows
/// the drag coefficients).
pub const NAMES: [&str; 6] = ["explicit-euler", "semi-implicit-euler", "velocity-verlet", "respa", "exponential-verlet", "adaptive-verlet"];

/// The integrator `name`; `slow_every` is the multiple-time-stepping ratio (RESPA only),
/// `tolerance` the adaptive integrator's local error per substep (fraction of a radius).
pub fn by_name(name: &str, slow_every: u64, tolerance: f64) -> Option<Box<dyn Integrator>> {
    match name {
        "adaptive-verlet" => Some(Box::new(AdaptiveVerlet::new(tolerance))),
        "explicit-euler" => Some(Box::new(ExplicitEuler)),
        "semi-implicit-euler" => Some(Box::new(SemiImplicitEuler)),
        "velocity-verlet" => Some(Box::new(VelocityVerlet)),
        "respa" => Some(Box::new(Respa { slow_every })),
        _ => None,
    }
}

/// v += F/m h, ω += T/I h.
fn kick(p: &mut Particles, h: f64) {
    for i in 0..p.len() {
        p.velocity[i] += p.force[i] * (h / p.mass[i]);
        p.angular_velocity[i] += p.torque[i] * (h / p.inertia[i]);
    }
}

/// v += F_slow/m h, ω += T_slow/I h.
fn slow_kick(p: &mut Particles, h: f64) {
    for i in 0..p.len() {
        p.velocity[i] += p.slow_force[i] * (h / p.mass[i]);
        p.angular_velocity[i] += p.slow_torque[i] * (h / p.inertia[i]);
    }
}

/// x += v h, and permanent moments turn with the particle by ω h (Rodrigues rotation).
fn drift(p: &mut Particles, h: f64) {
    for i in 0..p.len() {
        p.position[i] += p.velocity[i] * h;
        let m = p.permanent_moment[i];
        if m != Vec3::zeros() {
            let angle = p.angular_velocity[i] * h;
            p.permanent_moment[i] = nalgebra::Rotation3::new(angle) * m;
        }
    }
}

/// Advances the clock after a completed step.
fn tick(state: &mut State, dt: f64) {
    state.step += 1;
    state.time = state.step as f64 * dt;
}
