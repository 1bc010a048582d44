//! Time integrators. An integrator does not own the state: it advances a [`State`] by one step,
//! calling back into the force pipeline. On entry and on exit `force`/`torque` belong to the
//! current state, so each step costs one force evaluation.
//!
//! Each scheme is one file: the integrator behind [`Integrator`] and its `[integration]` keys
//! behind [`IntegratorSpec`]. The registry below (one line per scheme) makes [`Scheme`], the
//! tagged choice a scene holds: `integration.scheme` names the variant, and the variant's own
//! keys sit beside it in the same table.

mod adaptive_verlet;
mod brownian;
mod explicit_euler;
mod exponential_verlet;
mod respa;
mod semi_implicit_euler;
mod subcycled_euler;
mod velocity_verlet;

pub use adaptive_verlet::{AdaptiveVerlet, AdaptiveVerletSpec};
pub use brownian::{Brownian, BrownianSpec};
pub use explicit_euler::{ExplicitEuler, ExplicitEulerSpec};
pub use exponential_verlet::{ExponentialVerlet, ExponentialVerletSpec};
pub use respa::{Respa, RespaSpec};
pub use semi_implicit_euler::{SemiImplicitEuler, SemiImplicitEulerSpec};
pub use subcycled_euler::{SubcycledEuler, SubcycledEulerSpec};
pub use velocity_verlet::{VelocityVerlet, VelocityVerletSpec};

use super::checks::Invalid;
pub use super::forces::ForceGroup;
use super::parallel;
use super::renumber::Renumbering;
use super::state::{InverseMasses, Particles, State, Vec3};
use std::sync::atomic::{AtomicU64, Ordering};

/// Re-evaluates one group of forces and torques for the state as it stands, at the end of a
/// step of the given length (the contact model integrates its tangential history over it).
pub type Evaluate<'a> = dyn FnMut(&mut State, ForceGroup, f64) + 'a;

pub trait Integrator: Send {
    /// Steps of `dt` one call of `step` advances (more than one for multiple time stepping).
    fn steps_per_call(&self) -> u64 {
        1
    }
    /// Whether the integrator keeps slow forces apart (in `slow_force`/`slow_torque`).
    fn splits_forces(&self) -> bool {
        false
    }
    fn step(&mut self, state: &mut State, dt: f64, evaluate: &mut Evaluate);
    /// The particles were renumbered between two calls: per-particle values the integrator
    /// holds follow `r`. Required, as for force terms.
    fn renumber(&mut self, r: &Renumbering);
}

/// What an integrator may need of the scene to build itself.
pub struct IntegratorContext<'a> {
    /// Linear (Stokes) drag coefficient 6π μ a per particle (kg/s); zeros without drag.
    pub linear_drag: &'a [f64],
    /// Rotational drag coefficient 8π μ a³ per particle (kg m²/s); zeros without it.
    pub rotational_drag: &'a [f64],
    /// u_f (m/s), uniform; zero without a fluid.
    pub fluid_velocity: Vec3,
    /// μ (Pa s) of the drag; zero without drag.
    pub viscosity: f64,
    /// T (K) of `[forces.thermal]`; zero without it.
    pub temperature: f64,
    /// The scene's seed (the key of the noise).
    pub seed: u64,
}

/// A scheme's `[integration]` keys (plain serde data, in the scheme's own file): its checks, what
/// the scene and the force terms must know of it before it runs, and its construction.
pub trait IntegratorSpec {
    /// Refuses a value of the scheme's own keys, naming the key (`integration.<key>`).
    fn check(&self) -> Result<(), Invalid> {
        Ok(())
    }
    /// K: steps over which the slow (magnetic) forces are held (multiple time stepping); 1 when
    /// every step evaluates them.
    fn slow_every(&self) -> u64 {
        1
    }
    /// dt is only the largest step (error control splits it), so no stable-step bound applies.
    fn dt_is_a_cap(&self) -> bool {
        false
    }
    /// Evaluates the forces more than once per step and compares the results (step doubling):
    /// forces must be functions of the state alone.
    fn compares_evaluations(&self) -> bool {
        false
    }
    /// Integrates the linear (Stokes) drag itself, so the drag term leaves it out and the drag
    /// relaxation time does not bound dt.
    fn integrates_linear_drag(&self) -> bool {
        false
    }
    /// Forward Euler in the contact force: stable only for dt < 2ζ/ω (central-difference
    /// schemes for dt < (2/ω)(√(1+ζ²) − ζ)).
    fn forward_euler_in_contact(&self) -> bool {
        false
    }
    /// Overdamped (Brownian) dynamics: positions move with the mobility times the force plus the
    /// noise, with no inertia. The thermal term's noise is then drawn by the integrator (which
    /// needs `[forces.thermal]` and the Stokes drag), and the contact's step bound is the
    /// overdamped relaxation of the contact.
    fn overdamped(&self) -> bool {
        false
    }
    fn build(&self, ctx: &IntegratorContext) -> Box<dyn Integrator>;
}

/// `slow_every`'s default: the slow forces every step.
fn every_step() -> u64 {
    1
}

/// Refuses K = 0 (`integration.slow_every`) for the multiple-time-stepping schemes.
fn check_slow_every(k: u64) -> Result<(), Invalid> {
    if k == 0 {
        return Err(super::checks::invalid("integration.slow_every", 0, "must be at least 1"));
    }
    Ok(())
}

macro_rules! schemes {
    ($($variant:ident($spec:ident) = $name:literal,)*) => {
        /// The time-integration scheme of a scene, with its own parameters: `integration.scheme`
        /// names the variant.
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum Scheme {
            $($variant($spec),)*
        }

        impl Scheme {
            /// Every scheme's name, in registry order.
            pub const NAMES: &[&str] = &[$($name),*];

            /// The name a scene gives (`integration.scheme`).
            pub fn name(&self) -> &'static str {
                match self {
                    $(Scheme::$variant(_) => $name,)*
                }
            }

            /// The scheme's spec, behind its trait.
            pub fn spec(&self) -> &dyn IntegratorSpec {
                match self {
                    $(Scheme::$variant(spec) => spec,)*
                }
            }

            /// The scheme's own keys as serde data (what a scene writes beside `scheme`).
            pub fn keys<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                match self {
                    $(Scheme::$variant(spec) => serde::Serialize::serialize(spec, serializer),)*
                }
            }

            /// The scheme `name` with its keys read from `keys` (the `[integration]` keys other
            /// than the common ones), or `None` for a name the registry does not hold.
            pub fn deserialize_named<'de, D: serde::Deserializer<'de>>(
                name: &str,
                keys: D,
            ) -> Result<Option<Self>, D::Error> {
                match name {
                    $($name => <$spec as serde::Deserialize>::deserialize(keys).map(|s| Some(Scheme::$variant(s))),)*
                    _ => Ok(None),
                }
            }
        }
    };
}

// The registry of time-integration schemes.
schemes! {
    ExplicitEuler(ExplicitEulerSpec) = "explicit-euler",
    SemiImplicitEuler(SemiImplicitEulerSpec) = "semi-implicit-euler",
    VelocityVerlet(VelocityVerletSpec) = "velocity-verlet",
    Respa(RespaSpec) = "respa",
    ExponentialVerlet(ExponentialVerletSpec) = "exponential-verlet",
    AdaptiveVerlet(AdaptiveVerletSpec) = "adaptive-verlet",
    SubcycledEuler(SubcycledEulerSpec) = "subcycled-euler",
    Brownian(BrownianSpec) = "brownian",
}

impl Default for Scheme {
    fn default() -> Self {
        Scheme::VelocityVerlet(VelocityVerletSpec {})
    }
}

impl std::fmt::Display for Scheme {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// v += F/m h, ω += T/I h.
fn kick(state: &mut State, h: f64) {
    advance(&mut state.particles, &state.fields.force, &state.fields.torque, Kick::Plain(h), 0.0);
}

/// v += F_slow/m h, ω += T_slow/I h.
fn slow_kick(state: &mut State, h: f64) {
    advance(&mut state.particles, &state.fields.slow_force, &state.fields.slow_torque, Kick::Plain(h), 0.0);
}

/// x += v h, and permanent moments turn with the particle by ω h (Rodrigues rotation).
fn drift(state: &mut State, h: f64) {
    advance(&mut state.particles, &state.fields.force, &state.fields.torque, Kick::Plain(0.0), h);
}

/// A kick by `kick` then a drift by `drift` in one pass over the particles (the same arithmetic
/// as [`kick`] followed by [`drift`]).
fn kick_drift(state: &mut State, kick: f64, drift: f64) {
    advance(&mut state.particles, &state.fields.force, &state.fields.torque, Kick::Plain(kick), drift);
}

/// v += F_slow/m `slow` (ω likewise), then a kick by `kick` and a drift by `drift`, in one pass
/// over the particles (the arithmetic of [`slow_kick`] followed by [`kick_drift`]).
fn slow_kick_then_kick_drift(state: &mut State, slow: f64, kick: f64, drift: f64) {
    let before = (&state.fields.slow_force[..], &state.fields.slow_torque[..], slow);
    advance(&mut state.particles, &state.fields.force, &state.fields.torque, Kick::After { before, h: kick }, drift);
}

/// Two kicks by `kick` with the same forces, then a drift by `drift`, in one pass over the
/// particles: a Verlet step's closing half kick and the next step's opening one (the arithmetic
/// of [`kick`] followed by [`kick_drift`]).
fn kick_twice_drift(state: &mut State, kick: f64, drift: f64) {
    let before = (&state.fields.force[..], &state.fields.torque[..], kick);
    advance(&mut state.particles, &state.fields.force, &state.fields.torque, Kick::After { before, h: kick }, drift);
}

/// How a kick changes the velocities.
#[derive(Clone, Copy)]
enum Kick<'a> {
    /// v += F/m h, ω += T/I h (skipped at h = 0).
    Plain(f64),
    /// v += F′/m h′, ω += T′/I h′ for `before` = (F′, T′, h′), then the plain kick by h: two kicks
    /// in one pass, each velocity updated as two passes would.
    After { before: (&'a [Vec3], &'a [Vec3], f64), h: f64 },
    /// The exact solution of m dv/dt = F − γ (v − u_f) over h with F held (see
    /// [`ExponentialVerlet`]), and likewise for ω with γ_r.
    Exponential { h: f64, gamma: &'a [f64], gamma_rotational: &'a [f64], fluid_velocity: Vec3 },
}

/// (1 − e^{−x})/x, accurate at small x.
fn phi(x: f64) -> f64 {
    if x < 1e-8 {
        1.0 - 0.5 * x
    } else {
        -(-x).exp_m1() / x
    }
}

/// The one kick/drift kernel of every integrator: a kick, then x += v drift (a zero drift is
/// skipped), in one parallel loop in which each thread takes its share of the particles through
/// all of it (a parallel loop per array would hand out and join once per array). The drift
/// states its bound on any particle's displacement ([`Positions::drift`]): the largest change of
/// a coordinate, taken from the positions before and after, times √3.
///
/// [`Positions::drift`]: crate::core::state::Positions::drift
fn advance(p: &mut Particles, force: &[Vec3], torque: &[Vec3], kick: Kick, drift: f64) {
    let (v, w) = (&mut p.velocity[..], &mut p.angular_velocity[..]);
    // A kick before the plain one: another force's, or none (h′ = 0, skipped).
    let ((before_f, before_t, hb), h) = match kick {
        Kick::Plain(h) => ((force, torque, 0.0), h),
        Kick::After { before, h } => (before, h),
        Kick::Exponential { .. } => ((force, torque, 0.0), 0.0),
    };
    // The largest |Δx| of a coordinate over the shares, as the bits of a number ≥ 0 (which order
    // as the numbers do; a NaN orders above infinity and stays).
    let largest = AtomicU64::new(0);
    let inverse_masses = &p.inverse_masses;
    let (mass, inertia) = (&p.mass[..], &p.inertia[..]);
    p.position.drift(|x| {
        match (kick, inverse_masses) {
            (Kick::Plain(_) | Kick::After { .. }, InverseMasses::Uniform { mass, inertia }) => {
                let (c, ci, cb, cbi) = (h * mass, h * inertia, hb * mass, hb * inertia);
                // Component by component (SIMD across particles).
                let parts = (x, v, w, (force, torque), (before_f, before_t));
                parallel::for_each_share(parts, |_, (x, v, w, (f, t), (bf, bt))| {
                    let (x, v, w, f, t) =
                        (components_mut(x), components_mut(v), components_mut(w), components(f), components(t));
                    let (bf, bt) = (components(bf), components(bt));
                    let moved = match (hb != 0.0, h != 0.0, drift != 0.0) {
                        (true, true, true) => {
                            x.iter_mut().zip(v).zip(bf.iter().zip(f)).fold(0, |m, ((x, v), (bf, f))| {
                                *v += bf * cb;
                                *v += f * c;
                                step(m, x, *v * drift)
                            })
                        }
                        (true, true, false) => {
                            v.iter_mut().zip(bf.iter().zip(f)).for_each(|(v, (bf, f))| {
                                *v += bf * cb;
                                *v += f * c;
                            });
                            0
                        }
                        (false, true, true) => x.iter_mut().zip(v).zip(f).fold(0, |m, ((x, v), f)| {
                            *v += f * c;
                            step(m, x, *v * drift)
                        }),
                        (false, true, false) => {
                            v.iter_mut().zip(f).for_each(|(v, f)| *v += f * c);
                            0
                        }
                        (false, false, true) => x.iter_mut().zip(v).fold(0, |m, (x, v)| step(m, x, *v * drift)),
                        (false, false, false) => 0,
                        (true, false, _) => unreachable!("a kick before the plain one comes with it"),
                    };
                    if hb != 0.0 {
                        w.iter_mut().zip(bt).for_each(|(w, t)| *w += t * cbi);
                    }
                    if h != 0.0 {
                        w.iter_mut().zip(t).for_each(|(w, t)| *w += t * ci);
                    }
                    largest.fetch_max(moved, Ordering::Relaxed);
                });
            }
            (Kick::Plain(_) | Kick::After { .. }, InverseMasses::PerParticle { mass, inertia }) => {
                let parts = (x, v, w, (force, torque), (before_f, before_t), (&mass[..], &inertia[..]));
                parallel::for_each_share(parts, |_, (x, v, w, (f, t), (bf, bt), (m, i))| {
                    let mut moved = 0;
                    for (((x, v), w), (((f, t), (bf, bt)), (m, i))) in
                        x.iter_mut().zip(v).zip(w).zip(f.iter().zip(t).zip(bf.iter().zip(bt)).zip(m.iter().zip(i)))
                    {
                        if hb != 0.0 {
                            *v += bf * (hb * m);
                            *w += bt * (hb * i);
                        }
                        if h != 0.0 {
                            *v += f * (h * m);
                            *w += t * (h * i);
                        }
                        if drift != 0.0 {
                            moved = (0..3).fold(moved, |m, k| step(m, &mut x[k], v[k] * drift));
                        }
                    }
                    largest.fetch_max(moved, Ordering::Relaxed);
                });
            }
            (Kick::Exponential { h, gamma, gamma_rotational, fluid_velocity: u }, _) => {
                parallel::for_each_share(
                    (x, v, w, force, torque, (mass, inertia), (gamma, gamma_rotational)),
                    |_, (x, v, w, f, t, (m, i), (g, gr))| {
                        let mut moved = 0;
                        for k in 0..x.len() {
                            let e = g[k] * h / m[k];
                            v[k] = u + (v[k] - u) * (-e).exp() + f[k] * (h / m[k] * phi(e));
                            let er = gr[k] * h / i[k];
                            w[k] = w[k] * (-er).exp() + t[k] * (h / i[k] * phi(er));
                            if drift != 0.0 {
                                moved = (0..3).fold(moved, |m, c| step(m, &mut x[k][c], v[k][c] * drift));
                            }
                        }
                        largest.fetch_max(moved, Ordering::Relaxed);
                    },
                );
            }
        }
        displacement_bound(largest.into_inner())
    });
    if p.has_permanent_moments && drift != 0.0 {
        let turn = |(m, w): (&mut Vec3, &Vec3)| {
            if *m != Vec3::zeros() {
                *m = nalgebra::Rotation3::new(w * drift) * *m;
            }
        };
        p.permanent_moment.iter_mut().zip(&p.angular_velocity).for_each(turn);
    }
}

/// A bound on any particle's displacement from the bits of the largest change of a coordinate
/// (see [`step`]): that change times √3 rounded up, and the relative rounding of a difference
/// (half an ulp) on top.
fn displacement_bound(largest: u64) -> f64 {
    f64::from_bits(largest) * (1.732_050_807_568_878 * (1.0 + f64::EPSILON))
}

/// x += dx, folded into `moved`, the bits of the largest |Δx| so far (the change of x as the
/// positions store it, so that the bound holds for the rounded sum).
#[inline(always)]
fn step(moved: u64, x: &mut f64, dx: f64) -> u64 {
    let new = *x + dx;
    let change = (new - *x).abs().to_bits();
    *x = new;
    moved.max(change)
}

/// The components of vectors as one slice (x₀, y₀, z₀, x₁, …): a loop over it is SIMD across
/// particles, where a loop over the vectors works on one particle's three components at a time.
fn components(v: &[Vec3]) -> &[f64] {
    bytemuck::cast_slice(v)
}

fn components_mut(v: &mut [Vec3]) -> &mut [f64] {
    bytemuck::cast_slice_mut(v)
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
    fn particles(n: usize, per_particle: bool) -> State {
        let value = |k: usize| ((k as f64 * 0.618_033_988_75).fract() - 0.5) * 1e-3;
        let vectors =
            |offset: usize| (0..n).map(|i| Vec3::from_fn(|c, _| value(3 * (i + offset * n) + c))).collect::<Vec<_>>();
        let (mut p, mut f) = (Particles::default(), crate::core::state::Fields::default());
        (p.velocity, p.angular_velocity, f.force, f.torque) = (vectors(1), vectors(2), vectors(3), vectors(4));
        p.position = vectors(0).into();
        (f.slow_force, f.slow_torque) = (vectors(5), vectors(6));
        let (inv_m, inv_i) = (3.7e11, 2.9e21);
        p.inverse_masses = if per_particle {
            InverseMasses::PerParticle { mass: vec![inv_m; n], inertia: vec![inv_i; n] }
        } else {
            InverseMasses::Uniform { mass: inv_m, inertia: inv_i }
        };
        State { particles: p, fields: f, ..State::default() }
    }

    /// The bound a drift states for the neighbour lists holds every particle's displacement, and
    /// exceeds the largest by at most √3 (it bounds the norm by the largest component): shared
    /// and per-particle inverse masses and the exponential kick, below and above the parallel
    /// threshold. A kick without a drift states nothing.
    #[test]
    fn a_drift_bounds_every_displacement() {
        for n in [7, parallel::MIN_PARALLEL_LEN + 5] {
            for (case, per_particle) in [("shared", false), ("per particle", true), ("exponential", true)] {
                let mut state = particles(n, per_particle);
                state.particles.mass = vec![1e-12; n];
                state.particles.inertia = vec![1e-22; n];
                let (gamma, gamma_rotational) = (vec![3e-8; n], vec![2e-19; n]);
                let before = state.particles.position.to_vec();
                let motion = state.particles.position.motion();
                parallel::with_warm_pool(n, &mut parallel::Balance::default(), || {
                    let kick = match case {
                        "exponential" => Kick::Exponential {
                            h: 1e-8,
                            gamma: &gamma,
                            gamma_rotational: &gamma_rotational,
                            fluid_velocity: Vec3::new(1e-3, 0.0, 0.0),
                        },
                        _ => Kick::Plain(0.5e-8),
                    };
                    let (p, f) = (&mut state.particles, &state.fields);
                    advance(p, &f.force, &f.torque, kick, 1e-8);
                });
                let p = &state.particles;
                let moved = p.position.iter().zip(&before).map(|(x, x0)| (x - x0).norm()).fold(0.0, f64::max);
                let bound = p.position.motion().since(motion).expect("a drift, not a write");
                assert!(moved > 0.0 && bound >= moved && bound <= 1.75 * moved, "{case}, n = {n}: {bound} for {moved}");
                let still = p.position.motion();
                kick(&mut state, 1e-8);
                assert_eq!(state.particles.position.motion().since(still), Some(0.0), "{case}, n = {n}: a kick");
            }
        }
    }

    /// Two kicks and a drift in one pass give the bits of the passes one after the other, with
    /// shared and per-particle inverse masses, below and above the parallel threshold.
    #[test]
    fn fused_kicks_give_the_bits_of_separate_passes() {
        for per_particle in [false, true] {
            for n in [7, parallel::MIN_PARALLEL_LEN + 5] {
                let (mut apart, mut fused) = (particles(n, per_particle), particles(n, per_particle));
                parallel::with_warm_pool(n, &mut parallel::Balance::default(), || {
                    slow_kick(&mut apart, 2.5e-8);
                    kick_drift(&mut apart, 0.5e-8, 1e-8);
                    kick(&mut apart, 0.5e-8);
                    kick_drift(&mut apart, 0.5e-8, 1e-8);
                    slow_kick_then_kick_drift(&mut fused, 2.5e-8, 0.5e-8, 1e-8);
                    kick_twice_drift(&mut fused, 0.5e-8, 1e-8);
                });
                let (apart, fused) = (&apart.particles, &fused.particles);
                assert_eq!(apart.position, fused.position, "n = {n}");
                assert_eq!(apart.velocity, fused.velocity, "n = {n}");
                assert_eq!(apart.angular_velocity, fused.angular_velocity, "n = {n}");
            }
        }
    }

    /// The componentwise loops of shared inverse masses do the per-vector arithmetic of
    /// per-particle ones: the same bits, below and above the parallel threshold.
    #[test]
    fn kicks_give_the_same_bits_for_shared_and_per_particle_inverse_masses() {
        for n in [7, parallel::MIN_PARALLEL_LEN + 5] {
            let (mut shared, mut own) = (particles(n, false), particles(n, true));
            parallel::with_warm_pool(n, &mut parallel::Balance::default(), || {
                for p in [&mut shared, &mut own] {
                    kick_drift(p, 0.5e-8, 1e-8);
                    kick(p, 0.5e-8);
                    drift(p, 1e-8);
                    kick_twice_drift(p, 0.5e-8, 1e-8);
                    slow_kick_then_kick_drift(p, 2.5e-8, 0.5e-8, 1e-8);
                }
            });
            let (shared, own) = (&shared.particles, &own.particles);
            assert_eq!(shared.position, own.position, "n = {n}");
            assert_eq!(shared.velocity, own.velocity, "n = {n}");
            assert_eq!(shared.angular_velocity, own.angular_velocity, "n = {n}");
            assert_ne!(shared.position, particles(n, false).particles.position, "the particles moved");
        }
    }
}
