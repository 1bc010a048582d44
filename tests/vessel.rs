//! A vessel's wall and its exits: a sphere rebounds from the cylindrical wall as from a mirror,
//! and independent particles drifting across Poiseuille flow deposit on the wall in the fraction
//! of Pich's closed form.

use magdem::core::state::Way;
use magdem::scene::Scene;
use std::f64::consts::PI;

/// One sphere fired at the wall of a vessel along x (radius 50 µm) from its axis, radially along
/// y with an axial part, no drag, no friction, restitution 1: Hertz's rebound is elastic, so the
/// radial velocity reverses and the axial one stays, to the integrator's error (measured 1.1e-11
/// of the speed at 1 000 steps per contact).
#[test]
fn a_sphere_rebounds_from_the_vessel_wall_as_from_a_mirror() {
    let text = r#"version = 1
[domain]
lo = [-1e-3, -6e-5, -6e-5]
hi = [1e-3, 6e-5, 6e-5]
[fluid]
density = 1000.0
viscosity = 1.0e-3
[fluid.vessel]
centre = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
radius = 5.0e-5
mean_speed = 0.0
[[species]]
name = "p"
diameter = 1.0e-5
density = 1000.0
youngs_modulus = 1.0e7
poisson_ratio = 0.3
friction = 0.0
restitution = 1.0
[[particles]]
species = "p"
positions = [[0.0, 4.4e-5, 0.0]]
velocities = [[0.02, 0.1, 0.0]]
[forces.contact]
tangential = "none"
[integration]
dt = 2.0e-10
end_time = 1.0e-4
"#;
    let scene = Scene::parse(text, "rebound").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    let mut touched = false;
    // Until the sphere is back where it started, well clear of the wall.
    while !(touched && sim.state.particles.position[0].y <= 4.4e-5) {
        sim.step().unwrap();
        touched |= !sim.state.history.walls.is_empty();
        assert!(sim.state.step < 2_000_000, "no rebound");
    }
    let v = sim.state.particles.velocity[0];
    let expected = magdem::core::Vec3::new(0.02, -0.1, 0.0);
    println!("rebound: {:.2e} of the speed", (v - expected).norm() / expected.norm());
    assert!((v - expected).norm() < 1e-9 * expected.norm(), "{v:?} against {expected:?}");
}

/// Pich's deposited fraction for a uniform drift v across laminar flow of mean speed ū in a tube
/// of diameter d and length L (Pich, J. Aerosol Sci. 3, 351, 1972; Fuchs, The Mechanics of
/// Aerosols, 1964): with ε = 3 L v / (4 d ū),
/// P = (2/π) [2ε √(1 − ε^{2/3}) − ε^{1/3} √(1 − ε^{2/3}) + arcsin ε^{1/3}], for ε ≤ 1.
fn pich(eps: f64) -> f64 {
    let c = eps.cbrt();
    let s = (1.0 - c * c).sqrt();
    2.0 / PI * (2.0 * eps * s - c * s + c.asin())
}

/// The vessel (radius R, along x from 0) and the particles of the deposition test.
const R: f64 = 2.5e-3;
const A: f64 = 5.0e-6;
const RHO_P: f64 = 5000.0;
const RHO_F: f64 = 1000.0;
const ETA: f64 = 1.0e-3;

/// 10 000 independent 10 µm beads (contacts with the wall only), placed flux-weighted in a
/// slab [0, w] at the inlet of a vessel of radius 2.5 mm, carried by Poiseuille flow towards an
/// outlet at x = L = 4 R, and drifting across it at `drift` (m/s) under a uniform body force
/// (written as gravity's g along −y). A bead touching the wall is captured at once. Returns the
/// captured and outlet counts and the fraction's reference: Pich's P averaged over the slab.
fn deposition(eps: f64, n: usize, seed: u64) -> (usize, usize, f64) {
    let length = 4.0 * R;
    let tau = 2.0 * RHO_P * A * A / (9.0 * ETA);
    // A transit of 4 800 relaxation times: the beads lag the flow by about τū, 2e-4 of L, and
    // move at most 0.83 of a radius in a step of τ.
    let mean_speed = length / (4800.0 * tau);
    let drift = eps * 4.0 * 2.0 * R * mean_speed / (3.0 * length);
    // m_b g = 6π η a v: g = 6π η a v / ((ρp − ρf) V).
    let g = 6.0 * PI * ETA * A * drift / ((RHO_P - RHO_F) * 4.0 / 3.0 * PI * A.powi(3));
    let slab = 0.05 * length;
    let dt = tau;
    // Every bead has left once the drift has carried it across the vessel (2R/v), or through
    // the outlet at the slowest radial position's transit.
    let end = 1.05 * (2.0 * R / drift).max(length / mean_speed);
    let text = format!(
        r#"version = 1
seed = {seed}
[domain]
lo = [-1e-4, -{R:e}, -{R:e}]
hi = [{hi:e}, {R:e}, {R:e}]
[fluid]
density = {RHO_F:e}
viscosity = {ETA:e}
[fluid.vessel]
centre = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
radius = {R:e}
mean_speed = {mean_speed:e}
# Soft, so that the contact's step bound stays above dt: a bead is captured at its first touch,
# before the contact force acts.
[[species]]
name = "bead"
diameter = {d:e}
density = {RHO_P:e}
youngs_modulus = 1.0e3
poisson_ratio = 0.3
friction = 0.0
restitution = 0.5
[[particles]]
species = "bead"
count = {n}
region = {{ lo = [0.0, -{R:e}, -{R:e}], hi = [{slab:e}, {R:e}, {R:e}] }}
in_vessel = "flux"
[forces.contact]
particles = false
[forces.drag]
law = "stokes"
shielding = "none"
rotational = false
[forces.gravity]
g = [0.0, -{g:e}, 0.0]
[exits]
capture_after = 0.0
[[exits.outlets]]
name = "outlet"
point = [{length:e}, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[integration]
dt = {dt:e}
end_time = {end:e}
# A bead moves up to 0.83 of a radius along the axis in a step; its radial drift in a step, a
# small fraction of a radius, decides the capture.
[stability]
max_step_fraction = 1.0
"#,
        hi = length + 1e-4,
        d = 2.0 * A,
    );
    let scene = Scene::parse(&text, "deposition").unwrap_or_else(|e| panic!("{e}\n{text}"));
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    let steps = (end / dt).ceil() as u64;
    for _ in 0..steps {
        if sim.state.particles.is_empty() {
            break;
        }
        sim.step().unwrap();
    }
    assert!(sim.state.particles.is_empty(), "{} beads still in the vessel", sim.state.particles.len());
    let captured = sim.state.exits.iter().filter(|e| e.way == Way::Captured).count();
    let out = sim.state.exits.iter().filter(|e| e.way == Way::Outlet(0)).count();
    // Pich's P for the distance each bead travels, L − x0, averaged over x0 uniform in the slab
    // (Simpson's rule, 200 intervals: error far below 1e-6).
    let m = 200;
    let p = |k: usize| pich(eps * (1.0 - 0.05 * k as f64 / m as f64));
    let weight = |k: usize| {
        if k == 0 || k == m {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        }
    };
    let reference = (0..=m).map(|k| weight(k) * p(k)).sum::<f64>() / (3.0 * m as f64);
    (captured, out, reference)
}

/// At three drift speeds (ε = 0.1, 0.3, 0.6), the fraction of 10 000 beads captured by the wall
/// matches Pich's P within 3.5 binomial standard deviations √(P(1 − P)/N) (0.0037–0.0050). Beads
/// of radius 2e-3 R shift P by less than 1e-4 (a quadrature of the finite-size trajectories),
/// and their lag behind the flow by about 2e-4.
#[test]
fn independent_beads_deposit_in_pichs_fraction() {
    let n = 10_000;
    for (eps, seed) in [(0.1, 1), (0.3, 2), (0.6, 3)] {
        let (captured, out, reference) = deposition(eps, n, seed);
        assert_eq!(captured + out, n, "every bead leaves once");
        let fraction = captured as f64 / n as f64;
        let sigma = (reference * (1.0 - reference) / n as f64).sqrt();
        println!("ε = {eps}: captured {fraction:.4}, Pich {reference:.4} ± {sigma:.4} (N = {n})");
        assert!((fraction - reference).abs() < 3.5 * sigma, "ε = {eps}: {fraction} against {reference} ± {sigma}");
    }
}

/// A saturated magnetite bead (11 µm, Ms = 4.8e5 A/m, capped: its moment V Ms lies along the
/// 0.4 T field) in steady Poiseuille flow along x (R = 50 µm, ū = 1 mm/s) under the curl-free
/// gradient ∂B_y/∂x = ∂B_x/∂y = g: the force g V Ms along y drifts it across the flow at
/// v_d = g V Ms/(6π μ a) while the flow carries it along at u(y). With the drag's relaxation
/// time τ, y = y0 + v_d (t − τ(1 − e^(−t/τ))) in closed form, and x follows τ x'' = u(y(t)) − x',
/// integrated here by RK4 at τ/100. The solver's step is τ/10 (first order in it for the drag's
/// half-step velocity: 1e-4 of the displacement); the moment's tilt g x/B0 adds 4e-5.
#[test]
fn a_saturated_bead_drifts_across_poiseuille_flow_in_the_closed_form() {
    let (g, ms, b0, mean_speed, radius) = (-1.0, 4.8e5, 0.4, 1.0e-3, 5.0e-5);
    let (a, rho, mu): (f64, f64, f64) = (5.5e-6, 1087.0, 1.0e-3);
    let tau = 2.0 * rho * a * a / (9.0 * mu);
    let (dt, end) = (tau / 10.0, 5.0e-3);
    let y0 = 2.0e-5;
    let text = format!(
        r#"version = 1
[domain]
lo = [-1e-3, -6e-5, -6e-5]
hi = [1e-3, 6e-5, 6e-5]
[fluid]
density = 1000.0
viscosity = {mu:e}
[fluid.vessel]
centre = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
radius = {radius:e}
mean_speed = {mean_speed:e}
[field]
b0 = [{b0}, 0.0, 0.0]
gradient = [[0.0, {g}, 0.0], [{g}, 0.0, 0.0], [0.0, 0.0, 0.0]]
[[species]]
name = "p"
diameter = {d:e}
density = {rho}
youngs_modulus = 1.0e9
poisson_ratio = 0.5
friction = 0.5
restitution = 0.5
relative_permeability = 12.3
saturation_magnetisation = {ms:e}
[[particles]]
species = "p"
positions = [[0.0, {y0:e}, 0.0]]
[forces.gradient]
[forces.drag]
law = "stokes"
shielding = "none"
rotational = false
[integration]
dt = {dt:e}
end_time = {end:e}
"#,
        d = 2.0 * a
    );
    let scene = Scene::parse(&text, "drift").unwrap_or_else(|e| panic!("{e}"));
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    for _ in 0..scene.total_steps() {
        sim.step().unwrap();
    }
    let t = sim.state.time;
    let x = sim.state.particles.position[0];
    let drift = g * 4.0 / 3.0 * PI * a.powi(3) * ms / (6.0 * PI * mu * a);
    let y = y0 + drift * (t - tau * (1.0 - (-t / tau).exp()));
    // τ x'' = u(y(t)) − x' by RK4, (x, x') from rest.
    let u = |s: f64| {
        let ys = y0 + drift * (s - tau * (1.0 - (-s / tau).exp()));
        2.0 * mean_speed * (1.0 - ys * ys / (radius * radius))
    };
    let f = |s: f64, (_, v): (f64, f64)| (v, (u(s) - v) / tau);
    let (mut s, mut state, h) = (0.0, (0.0, 0.0), tau / 100.0);
    let n = (t / h).round() as usize;
    let h = t / n as f64;
    for _ in 0..n {
        let k1 = f(s, state);
        let k2 = f(s + h / 2.0, (state.0 + h / 2.0 * k1.0, state.1 + h / 2.0 * k1.1));
        let k3 = f(s + h / 2.0, (state.0 + h / 2.0 * k2.0, state.1 + h / 2.0 * k2.1));
        let k4 = f(s + h, (state.0 + h * k3.0, state.1 + h * k3.1));
        state.0 += h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
        state.1 += h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        s += h;
    }
    let (ex, ey) = ((x.x - state.0) / state.0, (x.y - y) / (y - y0));
    println!("drift across the flow: x {:.4e} m ({ex:.1e}), y {:.4e} m ({ey:.1e})", x.x, x.y);
    assert!(y - y0 < -1.0e-5 && state.0 > 5.0e-6, "the bead crossed a fifth of the vessel and moved along it");
    assert!(ex.abs() < 1e-3 && ey.abs() < 1e-3, "x {} against {}, y {} against {y}", x.x, state.0, x.y);
}
