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
use super::parallel;
use super::state::{InverseMasses, Particles, State, Vec3};
use rayon::prelude::*;

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
    kick_by(&mut p.velocity, &mut p.angular_velocity, &p.force, &p.torque, &p.inverse_masses, h);
}

/// v += F_slow/m h, ω += T_slow/I h.
fn slow_kick(p: &mut Particles, h: f64) {
    kick_by(&mut p.velocity, &mut p.angular_velocity, &p.slow_force, &p.slow_torque, &p.inverse_masses, h);
}

fn kick_by(velocity: &mut [Vec3], spin: &mut [Vec3], force: &[Vec3], torque: &[Vec3], inverse: &InverseMasses, h: f64) {
    match inverse {
        InverseMasses::Uniform { mass, inertia } => {
            add_scaled(components_mut(velocity), components(force), h * mass);
            add_scaled(components_mut(spin), components(torque), h * inertia);
        }
        InverseMasses::PerParticle { mass, inertia } => {
            let kick = |((v, w), (f, t)): ((&mut Vec3, &mut Vec3), (&Vec3, &Vec3)), inv_m: f64, inv_i: f64| {
                *v += f * (h * inv_m);
                *w += t * (h * inv_i);
            };
            if parallel::worth_it(velocity.len()) {
                let state = velocity.par_iter_mut().zip(spin).zip(force.par_iter().zip(torque));
                state.zip(mass.par_iter().zip(inertia)).with_min_len(parallel::share(mass.len())).for_each(|(s, (m, i))| kick(s, *m, *i))
            } else {
                let state = velocity.iter_mut().zip(spin).zip(force.iter().zip(torque));
                state.zip(mass.iter().zip(inertia)).for_each(|(s, (m, i))| kick(s, *m, *i))
            }
        }
    }
}

/// The components of vectors as one slice (x₀, y₀, z₀, x₁, …): a loop over it is SIMD across
/// particles, where a loop over the vectors works on one particle's three components at a time.
fn components(v: &[Vec3]) -> &[f64] {
    bytemuck::cast_slice(v)
}

fn components_mut(v: &mut [Vec3]) -> &mut [f64] {
    bytemuck::cast_slice_mut(v)
}

/// a += b c, componentwise (the same arithmetic as `a += b * c` on the vectors).
fn add_scaled(a: &mut [f64], b: &[f64], c: f64) {
    let add = |(a, b): (&mut f64, &f64)| *a += b * c;
    if parallel::worth_it(a.len() / 3) {
        a.par_iter_mut().zip(b).with_min_len(parallel::share(b.len())).for_each(add);
    } else {
        a.iter_mut().zip(b).for_each(add);
    }
}

/// x += v h, and permanent moments turn with the particle by ω h (Rodrigues rotation).
fn drift(p: &mut Particles, h: f64) {
    kick_drift(p, 0.0, h);
}

/// A kick by `kick` then a drift by `drift` in one pass over the particles (the same arithmetic
/// as [`kick`] followed by [`drift`]).
fn kick_drift(p: &mut Particles, kick: f64, drift: f64) {
    match &p.inverse_masses {
        InverseMasses::Uniform { mass, inertia } => {
            // v += F/m kick, x += v drift, component by component; ω += T/I kick.
            let in_parallel = parallel::worth_it(p.position.len());
            let (x, v, f) = (components_mut(&mut p.position), components_mut(&mut p.velocity), components(&p.force));
            let c = kick * mass;
            let kick_and_drift = |((x, v), f): ((&mut f64, &mut f64), &f64)| {
                *v += f * c;
                *x += *v * drift;
            };
            let only_drift = |(x, v): (&mut f64, &mut f64)| *x += *v * drift;
            match (in_parallel, kick != 0.0) {
                (true, true) => x.par_iter_mut().zip(v).zip(f).with_min_len(parallel::share(f.len())).for_each(kick_and_drift),
                (true, false) => x.par_iter_mut().zip(v).with_min_len(parallel::share(f.len())).for_each(only_drift),
                (false, true) => x.iter_mut().zip(v).zip(f).for_each(kick_and_drift),
                (false, false) => x.iter_mut().zip(v).for_each(only_drift),
            }
            if kick != 0.0 {
                add_scaled(components_mut(&mut p.angular_velocity), components(&p.torque), kick * inertia);
            }
        }
        InverseMasses::PerParticle { mass, inertia } => {
            type Item<'a> = ((((&'a mut Vec3, &'a mut Vec3), &'a mut Vec3), &'a Vec3), &'a Vec3);
            let step = |((((x, v), w), f), t): Item, inv_m: f64, inv_i: f64| {
                if kick != 0.0 {
                    *v += f * (kick * inv_m);
                    *w += t * (kick * inv_i);
                }
                *x += *v * drift;
            };
            if parallel::worth_it(p.position.len()) {
                let arrays = p.position.par_iter_mut().zip(&mut p.velocity).zip(&mut p.angular_velocity).zip(&p.force).zip(&p.torque);
                arrays.zip(mass.par_iter().zip(inertia)).with_min_len(parallel::share(mass.len())).for_each(|(a, (m, i))| step(a, *m, *i))
            } else {
                let arrays = p.position.iter_mut().zip(&mut p.velocity).zip(&mut p.angular_velocity).zip(&p.force).zip(&p.torque);
                arrays.zip(mass.iter().zip(inertia)).for_each(|(a, (m, i))| step(a, *m, *i))
            }
        }
    }
    if p.has_permanent_moments {
        let turn = |(m, w): (&mut Vec3, &Vec3)| {
            if *m != Vec3::zeros() {
                *m = nalgebra::Rotation3::new(w * drift) * *m;
            }
        };
        p.permanent_moment.iter_mut().zip(&p.angular_velocity).for_each(turn);
    }
}

/// Advances the clock after a completed step.
fn tick(state: &mut State, dt: f64) {
    state.step += 1;
    state.time = state.step as f64 * dt;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Particles with pseudo-random state and one shared (or per-particle) 1/m and 1/I.
    fn particles(n: usize, per_particle: bool) -> Particles {
        let value = |k: usize| ((k as f64 * 0.618_033_988_75).fract() - 0.5) * 1e-3;
        let vectors = |offset: usize| (0..n).map(|i| Vec3::from_fn(|c, _| value(3 * (i + offset * n) + c))).collect::<Vec<_>>();
        let mut p = Particles::default();
        (p.position, p.velocity, p.angular_velocity, p.force, p.torque) = (vectors(0), vectors(1), vectors(2), vectors(3), vectors(4));
        let (inv_m, inv_i) = (3.7e11, 2.9e21);
        p.inverse_masses = if per_particle {
            InverseMasses::PerParticle { mass: vec![inv_m; n], inertia: vec![inv_i; n] }
        } else {
            InverseMasses::Uniform { mass: inv_m, inertia: inv_i }
        };
        p
    }

    /// The componentwise loops of shared inverse masses do the per-vector arithmetic of
    /// per-particle ones: the same bits, below and above the parallel threshold.
    #[test]
    fn kicks_give_the_same_bits_for_shared_and_per_particle_inverse_masses() {
        for n in [7, parallel::MIN_PARALLEL_LEN + 5] {
            let (mut shared, mut own) = (particles(n, false), particles(n, true));
            parallel::with_warm_pool(n, || {
                for p in [&mut shared, &mut own] {
                    kick_drift(p, 0.5e-8, 1e-8);
                    kick(p, 0.5e-8);
                    drift(p, 1e-8);
                }
            });
            assert_eq!(shared.position, own.position, "n = {n}");
            assert_eq!(shared.velocity, own.velocity, "n = {n}");
            assert_eq!(shared.angular_velocity, own.angular_velocity, "n = {n}");
            assert_ne!(shared.position, particles(n, false).position, "the particles moved");
        }
    }
}
