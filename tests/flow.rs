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
