//! Vessel flow against closed forms: Bessel functions at tabulated points, Poiseuille's profile,
//! Womersley's profile carrying its prescribed flow rate at every instant, its quasi-steady limit
//! at small Womersley number and its plug at large.

use magdem::core::flow::{bessel_j0, bessel_j1, Harmonic, Vessel, VesselFlow};
use magdem::core::Vec3;
use nalgebra::Complex;
use std::f64::consts::PI;

const R: f64 = 2e-3; // a 4 mm artery
const RHO: f64 = 1060.0; // blood
const MU: f64 = 3.5e-3;

fn vessel() -> Vessel {
    Vessel { centre: Vec3::zeros(), axis: Vec3::x_axis(), radius: R }
}

/// Flow rate through the cross-section by the midpoint rule in r (2 000 rings): error of order
/// 1e-7 of the integral for these smooth profiles.
fn integrated_flow(flow: &VesselFlow, t: f64) -> f64 {
    let n = 2000;
    let dr = R / n as f64;
    (0..n).map(|k| (k as f64 + 0.5) * dr).map(|r| flow.axial_speed(r, t) * 2.0 * PI * r * dr).sum()
}

/// J0 and J1 at real arguments against Abramowitz & Stegun table 9.1, and the Kelvin functions
/// ber and bei (J0 of x i^{3/2}) at x = 2 against table 9.12.
#[test]
fn bessel_functions_match_tables() {
    let real = |x: f64| Complex::new(x, 0.0);
    assert!((bessel_j0(real(1.0)).re - 0.765_197_686_557_966_6).abs() < 1e-15);
    assert!((bessel_j1(real(1.0)).re - 0.440_050_585_744_933_5).abs() < 1e-15);
    assert!((bessel_j0(real(5.0)).re + 0.177_596_771_314_338_3).abs() < 1e-14);
    let kelvin = bessel_j0(Complex::new(-1.0, 1.0) / 2f64.sqrt() * 2.0);
    assert!((kelvin.re - 0.751_734_182_6).abs() < 1e-9, "ber(2) = {}", kelvin.re);
    assert!((kelvin.im - 0.972_291_627_8).abs() < 1e-9, "bei(2) = {}", kelvin.im);
}

/// Poiseuille: u = 2 ū (1 − r²/R²), no slip at the wall, ū = Q/(πR²), and the velocity along
/// the axis wherever the point lies.
#[test]
fn poiseuille_is_the_parabola_of_its_mean_speed() {
    let flow = VesselFlow::poiseuille(vessel(), 0.2, RHO, MU);
    assert!((flow.axial_speed(0.0, 0.0) - 0.4).abs() < 1e-15);
    assert_eq!(flow.axial_speed(R, 0.0), 0.0);
    // The midpoint rule's error on this cubic integrand is (1/2000)²/4 of its 1/2: 1.25e-7.
    assert!((integrated_flow(&flow, 0.0) / (PI * R * R) - 0.2).abs() < 2e-7 * 0.2);
    let u = flow.velocity(Vec3::new(0.3, 0.5 * R, 0.0), 1.0);
    assert!((u - Vec3::new(0.4 * 0.75, 0.0, 0.0)).norm() < 1e-15, "{u:?}");
}

/// A pulse of three harmonics (period 1 s, α up to about 7 here): at every instant the profile
/// carries the prescribed flow rate, and it has no slip at the wall.
#[test]
fn womersley_carries_the_prescribed_flow_rate() {
    let mut flow = VesselFlow::poiseuille(vessel(), 0.15, RHO, MU);
    flow.period = 1.0;
    flow.harmonics = vec![
        Harmonic { n: 1, q: Complex::new(1.0e-6, -0.5e-6) },
        Harmonic { n: 2, q: Complex::new(-0.4e-6, 0.3e-6) },
        Harmonic { n: 5, q: Complex::new(0.1e-6, 0.0) },
    ];
    assert!(flow.womersley_number(5) > 6.0 && flow.womersley_number(5) < 8.0);
    for t in [0.0, 0.13, 0.5, 0.77] {
        let q = integrated_flow(&flow, t);
        assert!(
            (q - flow.flow_rate(t)).abs() < 1e-6 * flow.flow_rate(t).abs().max(1e-6),
            "t = {t}: {q} against {}",
            flow.flow_rate(t)
        );
        assert!(flow.axial_speed(R * (1.0 - 1e-9), t).abs() < 1e-6);
    }
}

/// At small α the pulse is quasi-steady (each instant a Poiseuille parabola of that instant's
/// flow rate, to order α²); at large α the core moves as a plug, the centre speed tending to
/// the mean speed (ratio 1 + O(1/α)).
#[test]
fn womersley_tends_to_poiseuille_and_to_a_plug() {
    let harmonic = Harmonic { n: 1, q: Complex::new(1e-6, 0.0) };
    let mut slow = VesselFlow::poiseuille(vessel(), 0.0, RHO, MU);
    slow.period = 1e4; // α ≈ 1e-3
    slow.harmonics = vec![harmonic];
    for r in [0.0, 0.3 * R, 0.8 * R] {
        let parabola = 2.0 * 1e-6 / (PI * R * R) * (1.0 - (r / R).powi(2));
        assert!((slow.axial_speed(r, 0.0) - parabola).abs() < 1e-6 * parabola, "r = {r}");
    }
    let mut fast = slow.clone();
    fast.period = 1e-3; // α ≈ 22
    let alpha = fast.womersley_number(1);
    assert!(alpha > 20.0);
    // At t = 0 the flow rate is 1e-6 m³/s; the plug's speed is its mean speed.
    let centre = fast.axial_speed(0.0, 0.25 * fast.period).abs().max(fast.axial_speed(0.0, 0.0).abs());
    let mean = 1e-6 / (PI * R * R);
    assert!(centre < 1.2 * mean && centre > 0.9 * mean, "centre {centre} against mean {mean} at α = {alpha}");
}

/// A 5.5 µm bead in water inside a vessel of radius 50 µm along x, with Stokes drag and nothing
/// else; the scene's integration lines follow.
fn bead_in_vessel(y0: f64, vessel_extra: &str, integration: &str) -> magdem::core::simulation::Simulation {
    let text = format!(
        "version = 1\n[domain]\nlo = [-1e-3, -6e-5, -6e-5]\nhi = [1e-3, 6e-5, 6e-5]\n\
         [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n\
         [fluid.vessel]\ncentre = [0.0, 0.0, 0.0]\naxis = [1.0, 0.0, 0.0]\nradius = 5.0e-5\nmean_speed = 1.0e-3\n{vessel_extra}\
         [[species]]\nname = \"p\"\ndiameter = 11.0e-6\ndensity = 1087.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
         friction = 0.5\nrestitution = 1.0\n[[particles]]\nspecies = \"p\"\npositions = [[0.0, {y0:e}, 0.0]]\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\nrotational = false\n[integration]\n{integration}"
    );
    let scene = magdem::scene::Scene::parse(&text, "vessel").unwrap_or_else(|e| panic!("{e}\n{text}"));
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    sim
}

/// Drag relaxation time τ = m/(6π μ a) of the bead.
fn bead_tau() -> f64 {
    1087.0 * 4.0 / 3.0 * PI * 5.5e-6_f64.powi(3) / (6.0 * PI * 1.0e-3 * 5.5e-6)
}

/// Velocity Verlet on τ v' = u(t) − v, as the solver steps it, written out: a half kick with the
/// force of the last evaluation, a drift, the drag at the half-step velocity and the new time,
/// and the closing half kick. Returns (x, v) after each step, from rest at x = 0.
fn verlet_on_drag(u: impl Fn(f64) -> f64, tau: f64, h: f64, steps: usize) -> Vec<(f64, f64)> {
    let (mut x, mut v, mut f) = (0.0, 0.0, u(0.0) / tau);
    (1..=steps)
        .map(|n| {
            let w = v + 0.5 * h * f;
            x += h * w;
            f = (u(n as f64 * h) - w) / tau;
            v = w + 0.5 * h * f;
            (x, v)
        })
        .collect()
}

/// A bead released at rest at r0 = 20 µm from the axis of steady Poiseuille flow moves along the
/// axis (the flow has no radial part), so its drag sees the fixed local speed u(r0) = 2ū(1 − r0²/R²).
/// Its steps follow velocity Verlet's recurrence to round-off, and the closed form
/// v = u(r0)(1 − e^(−t/τ)), x = u(r0)(t − τ(1 − e^(−t/τ))) to the scheme's first-order error.
#[test]
fn a_bead_in_poiseuille_flow_relaxes_to_the_local_speed() {
    let (r0, tau) = (2e-5, bead_tau());
    let u = 2.0 * 1e-3 * (1.0 - (r0 / 5e-5_f64).powi(2));
    let dt = tau / 200.0;
    let mut sim = bead_in_vessel(r0, "", &format!("scheme = \"velocity-verlet\"\ndt = {dt:e}\nend_time = 1.0\n"));
    let steps = verlet_on_drag(|_| u, tau, dt, 1000);
    let (mut recurrence, mut worst_v, mut worst_x) = (0.0_f64, 0.0_f64, 0.0_f64);
    for &(x, v) in &steps {
        sim.step().unwrap();
        let (t, p) = (sim.state.time, &sim.state.particles);
        recurrence = recurrence.max((p.velocity[0].x - v).abs() / u).max((p.position[0].x - x).abs() / (u * tau));
        let e = (-t / tau).exp();
        worst_v = worst_v.max((p.velocity[0].x - u * (1.0 - e)).abs() / u);
        worst_x = worst_x.max((p.position[0].x - u * (t - tau * (1.0 - e))).abs() / (u * tau));
        assert_eq!((p.position[0].y, p.position[0].z), (r0, 0.0), "the bead stays at r0");
    }
    println!(
        "u(r0) = {u:e} m/s; over 5 τ at dt = τ/200: recurrence {recurrence:.1e}; closed form: velocity {worst_v:.2e}, \
         position {worst_x:.2e} (of u τ)"
    );
    // Round-off (measured 1.6e-15).
    assert!(recurrence < 2e-14, "{recurrence:e}");
    // First order in dt/τ = 5e-3 (the drag sees the half-step velocity): measured 9.2e-4 and
    // 2.4e-3 (the position lags by about half a step).
    assert!(worst_v < 2e-3 && worst_x < 5e-3, "{worst_v:e}, {worst_x:e}");
}

/// On the axis of a pulsatile flow of one harmonic, u(0, t) = U0 + Re[Û e^(iωt)], the bead's
/// velocity obeys τ v' = u(0, t) − v: once the start has decayed (10 τ), v = U0 + Re[Û e^(iωt)/(1 + iωτ)],
/// amplitude cut by √(1 + ω²τ²) and lagging by atan(ωτ). Here ωτ = 1. The steps follow velocity
/// Verlet's recurrence with the flow taken at each evaluation's time to round-off, and the
/// filtered pulse to the scheme's first-order error.
#[test]
fn a_bead_on_the_axis_of_pulsatile_flow_follows_it_as_a_first_order_filter() {
    let tau = bead_tau();
    let period = 2.0 * PI * tau;
    let (steps, dt) = (8000, tau / 400.0);
    let pulse = format!("period = {period:e}\nharmonics = [[1, 0.5, 0.3]]\n");
    let mut sim = bead_in_vessel(0.0, &pulse, &format!("scheme = \"velocity-verlet\"\ndt = {dt:e}\nend_time = 1.0\n"));
    // The flow on the axis (its profile is held to Womersley's in the tests above).
    let steady_flow = VesselFlow::poiseuille(
        Vessel { centre: Vec3::zeros(), axis: Vec3::x_axis(), radius: 5e-5 },
        1e-3,
        1000.0,
        1e-3,
    );
    let harmonic = Harmonic { n: 1, q: Complex::from_polar(0.5 * steady_flow.mean_flow, 0.3) };
    let flow = VesselFlow { period, harmonics: vec![harmonic], ..steady_flow };
    let on_axis = |t: f64| flow.axial_speed(0.0, t);
    let steady = 2.0 * 1e-3;
    // u(0, t) − U0 = Re[Û e^(iωt)]: Re Û at t = 0, −Im Û at a quarter period.
    let hat = Complex::new(on_axis(0.0) - steady, -(on_axis(period / 4.0) - steady));
    let omega = 2.0 * PI / period;
    let expected = verlet_on_drag(on_axis, tau, dt, steps);
    let (mut recurrence, mut worst) = (0.0_f64, 0.0_f64);
    for (k, &(_, v)) in expected.iter().enumerate() {
        sim.step().unwrap();
        let vx = sim.state.particles.velocity[0].x;
        recurrence = recurrence.max((vx - v).abs() / steady);
        if k >= steps / 2 {
            let t = sim.state.time;
            let filtered = steady + (hat * Complex::from_polar(1.0, omega * t) / Complex::new(1.0, omega * tau)).re;
            worst = worst.max((vx - filtered).abs() / hat.norm());
        }
    }
    println!(
        "|Û| = {:.3e} m/s; over 20 τ at dt = τ/400: recurrence {recurrence:.1e}; filtered pulse (last 10 τ): {worst:.2e} of |Û|",
        hat.norm()
    );
    // Round-off (measured 4.3e-16).
    assert!(recurrence < 5e-15, "{recurrence:e}");
    // First order in dt/τ = 2.5e-3 (measured 6.3e-4); the start has decayed to e^(−10) = 4.5e-5.
    assert!(worst < 1.5e-3, "{worst:e}");
}
