//! The overdamped Brownian-dynamics scheme (`scheme = "brownian"`) against the statistics it must
//! give, each with a tolerance of four standard errors measured across independent particles:
//! the mean-squared displacement 6Dt, the orientation autocorrelation exp(−2 D_r t), the
//! Langevin orientation ⟨cos θ⟩ = L(mB/kT) of permanent dipoles in a field, and the barometric
//! profile between two walls. Its noise's bits do not depend on the thread count or on restarting
//! from a state, and scenes it cannot run are refused by key.

use magdem::core::forces::thermal::BOLTZMANN;
use magdem::core::simulation::Simulation;
use magdem::core::state::{State, Vec3};
use magdem::scene::Scene;
use std::f64::consts::PI;

const A: f64 = 0.5e-6;
const MU: f64 = 1.0e-3;
const T: f64 = 300.0;
/// Below the noise bound (a/10)²/(6D) = 9.48e-4 s of these spheres.
const DT: f64 = 9.0e-4;
const N: usize = 2000;

fn kt() -> f64 {
    BOLTZMANN * T
}

/// D_t = kT/(6π μ a).
fn diffusion() -> f64 {
    kt() / (6.0 * PI * MU * A)
}

/// D_r = kT/(8π μ a³).
fn rotational_diffusion() -> f64 {
    kt() / (8.0 * PI * MU * A.powi(3))
}

/// A scene in water at T with the Stokes drag, the thermal table and the brownian scheme; `head`
/// holds the domain, `species` the species' extra keys, `tail` further tables.
fn scene_text(domain: &str, species: &str, particles: &str, tail: &str) -> String {
    format!(
        "version = 1\nseed = 7\n{domain}\n[fluid]\ndensity = 1000.0\nviscosity = {MU:e}\n\
         [[species]]\nname = \"p\"\ndiameter = {d:e}\npoisson_ratio = 0.3\nfriction = 0.5\nrestitution = 0.5\n{species}\n\
         {particles}\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[forces.thermal]\ntemperature = {T}\n{tail}\n\
         [integration]\nscheme = \"brownian\"\ndt = {DT:e}\nend_time = 100.0\n",
        d = 2.0 * A
    )
}

fn parse(text: &str) -> Scene {
    Scene::parse(text, "brownian").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// A periodic box: free spheres placed near a face do not leave it.
const BIG_BOX: &str = "[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [4.0e-4, 4.0e-4, 4.0e-4]\n\
                       boundary = { x = \"periodic\", y = \"periodic\", z = \"periodic\" }";
const BOX_SIDE: f64 = 4.0e-4;

/// N free spheres (no contact, no field), with a permanent moment if `moment`.
fn free_scene(moment: bool) -> Scene {
    let species = format!(
        "density = 5000.0\nyoungs_modulus = 1.0e9\n{}",
        if moment { "permanent_moment = [1.0e-18, 0.0, 0.0]" } else { "" }
    );
    parse(&scene_text(BIG_BOX, &species, &format!("[[particles]]\nspecies = \"p\"\ncount = {N}"), ""))
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

/// The displacement d − L round(d/L) across the periodic faces (displacements here are ≪ L).
fn minimum_image(d: Vec3) -> Vec3 {
    d.map(|c| c - BOX_SIDE * (c / BOX_SIDE).round())
}

/// Euler–Maruyama is exact for a free particle: each component of x(t) − x(0) is normal with
/// variance 2Dt, so the MSD is 6Dt at every lag, D = kT/(6π μ a). Its relative standard error
/// over N particles is √(2/3)/√N = 1.8 % (measured from the spread); the tolerance is four.
#[test]
fn free_particles_spread_as_6dt() {
    let scene = free_scene(false);
    let mut sim = started(&scene);
    let start: Vec<Vec3> = sim.state.particles.position.iter().copied().collect();
    let d = diffusion();
    for lag in [25, 50, 100, 200, 400] {
        while sim.state.step < lag {
            sim.step().unwrap();
        }
        let squares: Vec<f64> = sim
            .state
            .particles
            .position
            .iter()
            .zip(&start)
            .map(|(x, x0)| minimum_image(x - x0).norm_squared())
            .collect();
        let (msd, err) = mean_and_error(&squares);
        let expected = 6.0 * d * lag as f64 * DT;
        println!("lag {lag}: MSD/6Dt = {:.4} ± {:.4}", msd / expected, err / expected);
        assert!((msd - expected).abs() < 4.0 * err, "lag {lag}: {msd:e} ± {err:e} against {expected:e}");
    }
    assert!(sim.state.particles.velocity.iter().all(|v| *v == Vec3::zeros()), "no force, no drift velocity");
}

/// A permanent moment without a field turns by independent isotropic rotations of variance
/// σ² = 2 D_r h per axis, so ⟨u(0)·u(t)⟩ = cⁿ, c = 1/3 + (2/3)(1 − σ²) e^(−σ²/2) = e^(−σ²) (1 −
/// σ⁴/12 + …): exp(−2 D_r t) to a relative n σ⁴/12 ≤ 3e-4 here, far below the statistical error.
/// The standard error is the spread of u(0)·u(t) across the N particles over √N; tolerance four.
#[test]
fn orientation_decorrelates_as_exp_minus_2_dr_t() {
    let scene = free_scene(true);
    let mut sim = started(&scene);
    let u0 = Vec3::x();
    let sigma2 = 2.0 * rotational_diffusion() * DT;
    for decay in [0.25, 0.5, 1.0, 2.0] {
        let lag = (decay / sigma2).round() as u64;
        while sim.state.step < lag {
            sim.step().unwrap();
        }
        let dots: Vec<f64> = sim.state.particles.permanent_moment.iter().map(|m| m.normalize().dot(&u0)).collect();
        let (c, err) = mean_and_error(&dots);
        let expected = (-sigma2 * lag as f64).exp();
        println!(
            "2 D_r t = {:.3}: ⟨u(0)·u(t)⟩ = {c:.4} ± {err:.4}, exp(−2 D_r t) = {expected:.4}",
            sigma2 * lag as f64
        );
        assert!((c - expected).abs() < 4.0 * err, "2 D_r t = {decay}: {c} ± {err} against {expected}");
    }
    let norms = sim.state.particles.permanent_moment.iter().map(|m| (m.norm() / 1e-18 - 1.0).abs());
    assert!(norms.fold(0.0, f64::max) < 1e-12, "the turn keeps |m|");
}

/// splitmix64: uniform numbers in [0, 1) for the tests' starting samples.
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// L(ξ) = coth ξ − 1/ξ.
fn langevin(xi: f64) -> f64 {
    1.0 / xi.tanh() - 1.0 / xi
}

const B: f64 = 1.0e-3;

/// Two species of permanent dipoles, m = ξ kT/B for ξ = 1 and 3, in a uniform B along z, N of
/// each. The dipole term gives the torque m × B (no susceptibility, so no induced moment); its
/// pair forces reach 2 diameters, where the dipolar coupling is 5e-4 kT and the spheres are
/// ~30 µm apart.
fn langevin_scene() -> Scene {
    let species = |name: &str, xi: f64| {
        format!(
            "[[species]]\nname = \"{name}\"\ndiameter = {d:e}\ndensity = 5000.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.3\n\
             friction = 0.5\nrestitution = 0.5\nsusceptibility = 0.0\npermanent_moment = [{m:e}, 0.0, 0.0]\n",
            d = 2.0 * A,
            m = xi * kt() / B
        )
    };
    let text = format!(
        "version = 1\nseed = 5\n{BIG_BOX}\n[fluid]\ndensity = 1000.0\nviscosity = {MU:e}\n[field]\nb0 = [0.0, 0.0, {B:e}]\n\
         {}{}[[particles]]\nspecies = \"one\"\ncount = {N}\n[[particles]]\nspecies = \"three\"\ncount = {N}\n\
         [forces.dipole]\ninduction = \"none\"\ncutoff_diameters = 2.0\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[forces.thermal]\ntemperature = {T}\n\
         [integration]\nscheme = \"brownian\"\ndt = {DT:e}\nend_time = 100.0\n",
        species("one", 1.0),
        species("three", 3.0)
    );
    parse(&text)
}

/// Each moment turned to a direction drawn from the Boltzmann distribution e^(ξ cos θ) about z.
fn boltzmann_orientations(state: &mut State, xi_of: impl Fn(usize) -> f64) {
    let mut u = Uniform(3);
    let p = &mut state.particles;
    for (i, m) in p.permanent_moment.iter_mut().enumerate() {
        let xi = xi_of(i);
        let cos = 1.0 + (1.0 - u.next() * (1.0 - (-2.0 * xi).exp())).ln() / xi;
        let (sin, phi) = ((1.0 - cos * cos).max(0.0).sqrt(), 2.0 * PI * u.next());
        *m = m.norm() * Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
    }
}

/// From the Boltzmann orientations, after 600 steps (1.4 rotational relaxation times 1/(2D_r),
/// time enough for a wrong drift or noise to move the distribution), each moment's cos θ is
/// averaged over 2 400 steps; the standard error is the spread of these time averages across the
/// N independent particles (2 % of L at ξ = 1, 0.4 % at ξ = 3). Euler–Maruyama's bias in the
/// stationary distribution is O(D_r h ξ), about 0.4 % at ξ = 3: within a standard error, so a
/// tolerance of four standard errors holds it.
#[test]
fn permanent_dipoles_align_as_the_langevin_function() {
    let scene = langevin_scene();
    let mut sim = scene.simulation(None);
    let species = sim.state.particles.species.clone();
    boltzmann_orientations(&mut sim.state, |i| if species[i] == 0 { 1.0 } else { 3.0 });
    sim.initialise().unwrap();
    for _ in 0..600 {
        sim.step().unwrap();
    }
    let steps = 2400;
    let mut mean_cos = vec![0.0; 2 * N];
    for _ in 0..steps {
        sim.step().unwrap();
        for (c, m) in mean_cos.iter_mut().zip(&sim.state.particles.permanent_moment) {
            *c += m.z / m.norm() / steps as f64;
        }
    }
    for (kind, xi) in [(0, 1.0), (1, 3.0)] {
        let of_kind: Vec<f64> = (0..2 * N).filter(|&i| species[i] == kind).map(|i| mean_cos[i]).collect();
        let (c, err) = mean_and_error(&of_kind);
        let expected = langevin(xi);
        println!(
            "ξ = {xi}: ⟨cos θ⟩ = {c:.4} ± {err:.4}, L(ξ) = {expected:.4} ({:+.2} standard errors)",
            (c - expected) / err
        );
        assert!((c - expected).abs() < 4.0 * err, "ξ = {xi}: {c} ± {err} against {expected}");
    }
}

/// The sedimentation scene: spheres of 2600 kg/m³ in water between walls at z = 0 and z = H,
/// periodic in x and y, with gravity and Hertz–Mindlin contacts. The Young's modulus (12 Pa) is
/// the stiffest the overdamped contact bound admits at this dt; such a wall lets a sphere in by
/// about 0.15 a at kT, so the overlap limit of the monitor is raised.
const RHO: f64 = 2600.0;
const H: f64 = 3.0e-6;
const SIDE: f64 = 8.5e-4;
const E: f64 = 12.0;
const SETTLING: usize = 800;

fn sedimentation_scene() -> Scene {
    let domain = format!(
        "[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{SIDE:e}, {SIDE:e}, {H:e}]\nboundary = {{ x = \"periodic\", y = \"periodic\", z = \"wall\" }}"
    );
    let species = format!("density = {RHO}\nyoungs_modulus = {E}");
    let particles = format!("[[particles]]\nspecies = \"p\"\ncount = {SETTLING}");
    let tail =
        "[forces.gravity]\ng = [0.0, 0.0, -9.81]\n[forces.contact]\nwalls = true\n[stability]\nmax_overlap = 0.5\n";
    parse(&scene_text(&domain, &species, &particles, tail))
}

/// The buoyant mass m_b = V (ρ_p − ρ_f) and the sedimentation length l = kT/(m_b g).
fn sedimentation_length() -> f64 {
    let volume = 4.0 / 3.0 * PI * A.powi(3);
    kt() / (volume * (RHO - 1000.0) * 9.81)
}

/// The Boltzmann mean height of a centre between the two Hertz walls under gravity, ∫ z e^(−U/kT)
/// / ∫ e^(−U/kT), U = m_b g z + (8/15) E* √a δ^(5/2) at a wall overlap δ (E* = E/(2(1 − ν²)), as
/// the wall contact takes it), by the midpoint rule on 2·10⁵ intervals.
fn soft_wall_mean_height() -> f64 {
    let l = sedimentation_length();
    let e_star = E / (2.0 * (1.0 - 0.09));
    let wall = |delta: f64| if delta > 0.0 { 8.0 / 15.0 * e_star * A.sqrt() * delta.powf(2.5) } else { 0.0 };
    let steps = 200_000;
    let (mut weight, mut moment) = (0.0, 0.0);
    for k in 0..steps {
        let z = (k as f64 + 0.5) * H / steps as f64;
        let w = (-(z / l) - (wall(A - z) + wall(A - (H - z))) / kt()).exp();
        weight += w;
        moment += z * w;
    }
    moment / weight
}

/// The hard-wall closed form: centres in [a, H − a], L = H − 2a, ⟨z⟩ = a + l − L/(e^(L/l) − 1).
fn hard_wall_mean_height() -> f64 {
    let (l, span) = (sedimentation_length(), H - 2.0 * A);
    A + l - span / ((span / l).exp() - 1.0)
}

/// Sedimentation equilibrium between two walls, l = kT/(m_b g) = 0.49 a (a slab of 4 l): the
/// spheres start at heights drawn from the hard-wall barometric profile, settle for 1 500 steps
/// (2 relaxation times l²/(D (π²l²/L² + 1/4))), then each one's height is averaged over 10 000
/// steps (14 relaxation times). The reference is the Boltzmann mean height with the walls' Hertz
/// potential (the soft walls let the spheres sink by about 0.15 a; the hard-wall closed form is
/// printed beside it). The standard error is the spread of the time averages across the 800
/// independent spheres, about 0.7 %; the contacts between the spheres (solid fraction 1e-3 at the
/// bottom) shift the mean by about 8φ of a layer's weight, below it. Tolerance four standard errors.
#[test]
fn sedimentation_between_walls_follows_the_barometric_profile() {
    let scene = sedimentation_scene();
    let mut sim = scene.simulation(None);
    let (l, span) = (sedimentation_length(), H - 2.0 * A);
    let mut u = Uniform(11);
    for x in sim.state.particles.position.write().iter_mut() {
        // The truncated exponential on [0, L] by inversion.
        x.z = A - l * (1.0 - u.next() * (1.0 - (-span / l).exp())).ln();
    }
    sim.initialise().unwrap();
    for _ in 0..1500 {
        sim.step().unwrap();
    }
    let (steps, every) = (10_000, 10);
    let mut height = vec![0.0; SETTLING];
    for k in 0..steps {
        sim.step().unwrap();
        if k % every == 0 {
            for (h, x) in height.iter_mut().zip(sim.state.particles.position.iter()) {
                *h += x.z / (steps / every) as f64;
            }
        }
    }
    let (z, err) = mean_and_error(&height);
    let (soft, hard) = (soft_wall_mean_height(), hard_wall_mean_height());
    println!(
        "l = {l:.4e} m; ⟨z⟩ = {z:.5e} ± {err:.2e} m; Boltzmann with the Hertz walls {soft:.5e} m ({:+.2} standard errors, {:+.2} %); \
         hard walls {hard:.5e} m",
        (z - soft) / err,
        100.0 * (z / soft - 1.0)
    );
    assert!((z - soft).abs() < 4.0 * err, "⟨z⟩ = {z:e} ± {err:e} against {soft:e}");
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

/// The noise is a function of (seed, step, particle id, stream): one and two threads give the same
/// bits, and a simulation rebuilt from the state halfway (as `--resume` does) goes on to the same
/// bits, positions and turned moments alike.
#[test]
fn brownian_noise_is_the_same_on_any_thread_count_and_after_a_restart() {
    let scene = langevin_scene();
    let one = run(&scene, None, 40, 1);
    let two = run(&scene, None, 40, 2);
    assert_eq!(one, two, "one and two threads");
    let half = run(&scene, None, 20, 2);
    let resumed = run(&scene, Some(half), 20, 1);
    assert_eq!(one, resumed, "restarted halfway");
    let initial = scene.initial_state();
    assert_ne!(one.particles.position[0], initial.particles.position[0], "the noise moved them");
    assert_ne!(one.particles.permanent_moment[0], initial.particles.permanent_moment[0], "and turned them");
}

const REFUSE: &str = "[stability]\non_unstable_dt = \"refuse\"\n";

/// What the scheme cannot run is refused by key: no temperature, no drag, a drag other than a
/// lone sphere's Stokes drag with its rotational part, a step whose noise moves a sphere more than
/// a tenth of its radius, and a Hertz contact too stiff for the step (these two, like every step
/// bound, warn by default and are refused with `stability.on_unstable_dt = "refuse"`).
#[test]
fn scenes_the_scheme_cannot_run_are_refused_by_key() {
    let free = "density = 5000.0\nyoungs_modulus = 1.0e9";
    let particles = "[[particles]]\nspecies = \"p\"\ncount = 10";
    let good = scene_text(BIG_BOX, free, particles, "");
    parse(&good);
    let cases = [
        (
            good.replace("[forces.thermal]\ntemperature = 300\n", ""),
            "integration.scheme = brownian",
            "[forces.thermal]",
        ),
        (
            good.replace("[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n", ""),
            "forces.thermal",
            "add [forces.drag]",
        ),
        (
            good.replace("law = \"stokes\"", "law = \"schiller-naumann\""),
            "forces.drag.law = schiller-naumann",
            "Stokes",
        ),
        (good.replace("law = \"stokes\"", "law = \"rpy\""), "law = \"rpy\"", "Stokes"),
        (
            good.replace("shielding = \"none\"\n", "shielding = \"none\"\nrotational = false\n"),
            "forces.drag.rotational = false",
            "rotational mobility",
        ),
        (good.replace("shielding = \"none\"", "shielding = \"paper\""), "forces.drag.shielding = paper", "neighbours"),
        (good.replace("dt = 9e-4", "dt = 2e-3") + REFUSE, "integration.dt", "Brownian rms displacement"),
        (scene_text(BIG_BOX, free, particles, "[forces.contact]\n") + REFUSE, "integration.dt", "overdamped contact"),
    ];
    // Like every step bound, the noise bound warns by default.
    let warned = parse(&good.replace("dt = 9e-4", "dt = 2e-3"));
    assert!(warned.warnings.iter().any(|w| w.contains("Brownian rms displacement")), "{:?}", warned.warnings);
    for (text, key, why) in cases {
        assert_ne!(text, good, "the case edits the scene ({key})");
        let e = Scene::parse(&text, "bad").err().unwrap_or_else(|| panic!("accepted: {key}\n{text}")).to_string();
        assert!(e.contains(key) && e.contains(why), "{key}: {e}");
    }
}
