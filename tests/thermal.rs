//! Thermal forces (`[forces.thermal]`) against the statistics they must give, each with a
//! tolerance of four standard errors measured across independent particles: equipartition of
//! translation and rotation, and the mean-squared displacement of free Brownian particles. The
//! noise's bits do not depend on the thread count or on restarting from a state.

use magdem::core::forces::thermal::BOLTZMANN;
use magdem::core::simulation::Simulation;
use magdem::core::state::State;
use magdem::scene::Scene;
use std::f64::consts::PI;

const A: f64 = 0.5e-6;
const RHO: f64 = 5000.0;
const MU: f64 = 1.0e-3;
const T: f64 = 300.0;
const N: usize = 2000;

fn mass() -> f64 {
    RHO * 4.0 / 3.0 * PI * A.powi(3)
}

/// τ = m/γ, γ = 6π μ a.
fn tau() -> f64 {
    mass() / (6.0 * PI * MU * A)
}

/// N free spheres (no contact) in water at T, Stokes drag with its rotational part, dt = τ/20.
fn scene() -> Scene {
    let dt = tau() / 20.0;
    let text = format!(
        "version = 1\nseed = 11\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [4.0e-4, 4.0e-4, 4.0e-4]\n\
         [fluid]\ndensity = 1000.0\nviscosity = {MU:e}\n\
         [[species]]\nname = \"p\"\ndiameter = {:e}\ndensity = {RHO}\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.3\n\
         friction = 0.5\nrestitution = 0.5\n[[particles]]\nspecies = \"p\"\ncount = {N}\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\nrotational = true\n[forces.thermal]\ntemperature = {T}\n\
         [integration]\ndt = {dt:e}\nend_time = 1.0\n",
        2.0 * A
    );
    Scene::parse(&text, "thermal").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn started(scene: &Scene) -> Simulation {
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    sim
}

/// Mean and standard error of per-particle values (independent particles).
fn mean_and_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// After 20 τ from rest, over the next 20 τ: each particle's time-averaged ½ m v² and ½ I ω² is
/// 3/2 kT. For velocity Verlet with the noise held over the step, the free particle's stationary
/// ⟨v²⟩ is kT/m per component at any dt/τ (the recurrence's variance, docs/model.md §13), so the
/// only tolerance is statistical. The mean-squared displacement over the 20 τ follows the same
/// recurrence's exact variance, h² Var(Σ s_k) for the AR(1) s_{k+1} = (1 − h/τ) s_k + noise, which
/// is within 0.2 % of the continuous 6D[t − τ(1 − e^(−t/τ))], D = kT/γ.
#[test]
fn free_brownian_spheres_share_kt_and_diffuse_at_kt_over_gamma() {
    let scene = scene();
    let mut sim = started(&scene);
    let (m, kt, tau) = (mass(), BOLTZMANN * T, tau());
    let inertia = 0.4 * m * A * A;
    let steps = 400;
    for _ in 0..steps {
        sim.step().unwrap();
    }
    let start: Vec<_> = sim.state.particles.position.iter().copied().collect();
    let (mut kinetic, mut rotational) = (vec![0.0; N], vec![0.0; N]);
    for _ in 0..steps {
        sim.step().unwrap();
        let p = &sim.state.particles;
        for i in 0..N {
            kinetic[i] += 0.5 * m * p.velocity[i].norm_squared() / steps as f64;
            rotational[i] += 0.5 * inertia * p.angular_velocity[i].norm_squared() / steps as f64;
        }
    }
    let displacement: Vec<f64> =
        sim.state.particles.position.iter().zip(&start).map(|(x, x0)| (x - x0).norm_squared()).collect();
    let (ke, ke_err) = mean_and_error(&kinetic);
    let (re, re_err) = mean_and_error(&rotational);
    let (msd, msd_err) = mean_and_error(&displacement);
    // The discrete MSD: 3 h² σ_s² [n(1+λ)/(1−λ) − 2λ(1−λⁿ)/(1−λ)²], λ = 1 − h/τ, σ_s² = (kT/m)/(1 − h/(2τ)).
    let h = tau / 20.0;
    let (lambda, n) = (1.0 - h / tau, steps as f64);
    let sigma2 = kt / m / (1.0 - h / (2.0 * tau));
    let discrete = 3.0
        * h
        * h
        * sigma2
        * (n * (1.0 + lambda) / (1.0 - lambda) - 2.0 * lambda * (1.0 - lambda.powf(n)) / (1.0 - lambda).powi(2));
    let t = n * h;
    let d = kt / (6.0 * PI * MU * A);
    let continuous = 6.0 * d * (t - tau * (1.0 - (-t / tau).exp()));
    println!(
        "½m⟨v²⟩/(3/2 kT) = {:.4} ± {:.4}; ½I⟨ω²⟩/(3/2 kT) = {:.4} ± {:.4}; MSD/discrete = {:.4} ± {:.4} (discrete/continuous {:.5})",
        ke / (1.5 * kt),
        ke_err / (1.5 * kt),
        re / (1.5 * kt),
        re_err / (1.5 * kt),
        msd / discrete,
        msd_err / discrete,
        discrete / continuous
    );
    assert!((ke - 1.5 * kt).abs() < 4.0 * ke_err, "translation: {ke:e} ± {ke_err:e} against {:e}", 1.5 * kt);
    assert!((re - 1.5 * kt).abs() < 4.0 * re_err, "rotation: {re:e} ± {re_err:e} against {:e}", 1.5 * kt);
    assert!((msd - discrete).abs() < 4.0 * msd_err, "MSD: {msd:e} ± {msd_err:e} against {discrete:e}");
    assert!(
        (discrete / continuous - 1.0).abs() < 2e-3,
        "the discrete MSD is the continuous one to O(h/τ) in the transient"
    );
}

fn run(scene: &Scene, state: Option<State>, steps: usize, threads: usize) -> State {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let mut sim = scene.simulation(state);
        if sim.state.step == 0 {
            sim.initialise().unwrap();
        }
        for _ in 0..steps {
            sim.step().unwrap();
        }
        sim.state
    })
}

/// The noise is a function of (seed, step, particle id): one and two threads give the same bits,
/// and a simulation rebuilt from the state halfway (as `--resume` does) goes on to the same bits.
#[test]
fn thermal_noise_is_the_same_on_any_thread_count_and_after_a_restart() {
    let scene = scene();
    let one = run(&scene, None, 60, 1);
    let two = run(&scene, None, 60, 2);
    assert_eq!(one, two, "one and two threads");
    let half = run(&scene, None, 30, 2);
    let resumed = run(&scene, Some(half), 30, 1);
    assert_eq!(one, resumed, "restarted halfway");
    assert_ne!(one.particles.velocity[0], scene.initial_state().particles.velocity[0], "the noise moved them");
}
