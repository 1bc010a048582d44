//! Fields of real coils against closed forms written out here: a loop on its axis and far away
//! (a dipole), the same loop drawn as straight segments, a long wire, the Helmholtz field, the
//! Maxwell gradient, a Golay pair's transverse gradient, and Maxwell's equations everywhere.

use magdem::core::coils::{elliptic_ke, mri_gradient, rotate_gradient, Coil, Loop, Path, Segment, MU0};
use magdem::core::Vec3;
use nalgebra::{Matrix3, Unit};
use std::f64::consts::PI;

const A: f64 = 0.3; // coil radius (m), a gradient coil's size
const I: f64 = 100.0; // current (A)

fn z_loop(centre: Vec3) -> Loop {
    Loop { centre, axis: Vec3::z_axis(), radius: A, current: I }
}

fn relative(a: Vec3, b: Vec3) -> f64 {
    (a - b).norm() / b.norm()
}

/// K(0) = E(0) = π/2, and K(1/2), E(1/2) to 15 digits (Abramowitz & Stegun, table 17.1).
#[test]
fn elliptic_integrals_match_tabulated_values() {
    let (k0, e0) = elliptic_ke(0.0);
    assert!((k0 - PI / 2.0).abs() < 1e-15 && (e0 - PI / 2.0).abs() < 1e-15);
    let (k, e) = elliptic_ke(0.5);
    assert!((k - 1.854_074_677_301_372).abs() < 1e-14, "K(1/2) = {k}");
    assert!((e - 1.350_643_881_047_675).abs() < 1e-14, "E(1/2) = {e}");
}

/// On the axis, B_z = μ0 I a² / (2 (a² + z²)^{3/2}); measured agreement ~1e-16.
#[test]
fn a_loop_on_its_axis() {
    let l = z_loop(Vec3::zeros());
    for z in [0.0, 0.1, -0.25, 1.0] {
        let b = l.field(Vec3::new(0.0, 0.0, z));
        let exact = MU0 * I * A * A / (2.0 * (A * A + z * z).powf(1.5));
        assert!((b.z - exact).abs() <= 1e-13 * exact && b.xy().norm() <= 1e-13 * exact, "z = {z}: {b:?} vs {exact}");
    }
}

/// Far away the loop is a dipole m = I π a² ẑ: B = μ0/(4π r³) (3 (m·r̂) r̂ − m), with a
/// relative correction of order (a/r)²; at r = 100 a it is below 1e-3.
#[test]
fn a_loop_far_away_is_a_dipole() {
    let l = z_loop(Vec3::zeros());
    let m = Vec3::new(0.0, 0.0, I * PI * A * A);
    for dir in [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::new(0.0, 0.6, -0.8)] {
        let r = 100.0 * A * dir;
        let n = r.norm();
        let dipole = MU0 / (4.0 * PI * n.powi(3)) * (3.0 * m.dot(&dir) * dir - m);
        assert!(relative(l.field(r), dipole) < 1e-3, "{dir:?}");
    }
}

/// The loop drawn as N straight segments converges to the closed form as 1/N² off the axis:
/// N = 2 000 agrees to ~1e-6 at the points below.
#[test]
fn a_loop_of_straight_segments_converges_to_the_closed_form() {
    let l = z_loop(Vec3::zeros());
    let n = 2000;
    let corner = |k: usize| {
        let phi = 2.0 * PI * k as f64 / n as f64;
        Vec3::new(A * phi.cos(), A * phi.sin(), 0.0)
    };
    let polygon = Coil {
        paths: (0..n).map(|k| Path::Segment(Segment { from: corner(k), to: corner(k + 1), current: I })).collect(),
    };
    for at in [Vec3::new(0.1, 0.05, 0.2), Vec3::new(0.5, 0.0, -0.1), Vec3::new(-0.2, 0.25, 0.05)] {
        let err = relative(polygon.field(at), l.field(at));
        assert!(err < 1e-5, "{at:?}: relative difference {err:e}");
    }
}

/// A segment much longer than the distance is an infinite wire: B = μ0 I / (2π d), around it.
#[test]
fn a_long_segment_is_an_infinite_wire() {
    let s = Segment { from: Vec3::new(0.0, 0.0, -1e4), to: Vec3::new(0.0, 0.0, 1e4), current: I };
    let d = 0.05;
    let b = s.field(Vec3::new(d, 0.0, 0.0));
    let exact = MU0 * I / (2.0 * PI * d);
    // The finite length changes it by (d/L)²/2 ~ 1e-11.
    assert!((b.y - exact).abs() < 1e-10 * exact && b.x.abs() < 1e-12 * exact && b.z.abs() < 1e-12 * exact, "{b:?}");
}

/// Helmholtz: B = (4/5)^{3/2} μ0 I / a at the centre, flat to fourth order: along the axis
/// B(z) = B(0) (1 − (144/125)(z/a)⁴ + O(z⁶)).
#[test]
fn a_helmholtz_pair_is_uniform() {
    let c = Coil::helmholtz(Vec3::zeros(), Vec3::z_axis(), A, I);
    let b0 = c.field(Vec3::zeros());
    let exact = 0.8f64.powf(1.5) * MU0 * I / A;
    assert!((b0.z - exact).abs() < 1e-13 * exact, "{} vs {exact}", b0.z);
    for z in [0.05, 0.1] {
        let change = 1.0 - c.field(Vec3::new(0.0, 0.0, z * A)).z / b0.z;
        let fourth = 144.0 / 125.0 * z.powi(4);
        // The sixth-order term is (z/a)² ≈ 1 % of the fourth at these heights.
        assert!((change - fourth).abs() < 0.05 * fourth, "z = {z} a: {change:e} against {fourth:e}");
    }
}

/// Maxwell pair: ∂B_z/∂z = 48√3 / 7^{5/2} μ0 I / a² at the centre, and the gradient tensor is
/// traceless and symmetric there, diag(−G/2, −G/2, G).
#[test]
fn a_maxwell_pair_gives_the_textbook_gradient() {
    let c = Coil::maxwell(Vec3::zeros(), Vec3::z_axis(), A, I);
    let g = c.gradient(Vec3::zeros(), 1e-4 * A);
    let exact = 48.0 * 3f64.sqrt() / 7f64.powf(2.5) * MU0 * I / (A * A);
    assert!((g[(2, 2)].abs() - exact).abs() < 1e-7 * exact, "{} vs {exact}", g[(2, 2)]);
    let expected = mri_gradient(Vec3::new(0.0, 0.0, g[(2, 2)]));
    assert!((g - expected).norm() < 1e-7 * exact, "{g}");
}

/// A Golay pair: at its centre B_z is odd in x (zero at x = 0), ∂B_z/∂x dominates the tensor,
/// and B_z stays linear in x within 1 % over ±a/4.
#[test]
fn a_golay_pair_gives_a_transverse_gradient() {
    let c = Coil::golay(A, I, 400);
    let g = c.gradient(Vec3::zeros(), 1e-4 * A);
    let gx = g[(2, 0)];
    assert!(gx.abs() > 0.1 * MU0 * I / (A * A), "G = {g}");
    assert!((g[(0, 2)] - gx).abs() < 1e-6 * gx.abs(), "curl-free: ∂Bx/∂z = ∂Bz/∂x; {g}");
    let others = g - mri_gradient(Vec3::new(gx, 0.0, 0.0));
    assert!(others.norm() < 1e-3 * gx.abs(), "only the x gradient at the centre: {g}");
    assert!(c.field(Vec3::zeros()).z.abs() < 1e-9 * gx.abs() * A);
    for x in [0.05 * A, 0.15 * A, 0.25 * A] {
        let bz = c.field(Vec3::new(x, 0.0, 0.0)).z;
        assert!((bz - gx * x).abs() < 1e-2 * (gx * x).abs(), "x = {x}: {bz} against {}", gx * x);
    }
}

/// ∇·B = 0 and ∇×B = 0 away from the wires, for every coil (the gradient is a symmetric,
/// traceless tensor), to the central-difference error.
#[test]
fn every_coil_is_divergence_and_curl_free() {
    let coils = [
        Coil {
            paths: vec![Path::Loop(Loop {
                axis: Unit::new_normalize(Vec3::new(1.0, 2.0, 3.0)),
                ..z_loop(Vec3::new(0.1, 0.0, 0.0))
            })],
        },
        Coil::maxwell(Vec3::zeros(), Vec3::x_axis(), A, I),
        Coil::golay(A, I, 200),
    ];
    for (k, c) in coils.iter().enumerate() {
        for at in [Vec3::new(0.05, -0.1, 0.07), Vec3::new(-0.2, 0.1, 0.3), Vec3::new(0.0, 0.0, 0.6)] {
            let g = c.gradient(at, 1e-5);
            let scale = g.norm();
            assert!(g.trace().abs() < 1e-6 * scale, "coil {k} at {at:?}: div {}", g.trace());
            assert!((g - g.transpose()).norm() < 1e-6 * scale, "coil {k} at {at:?}: curl {g}");
        }
    }
}

/// An MRI gradient (Gx, Gy, Gz) is ∇B_z, symmetric and traceless; rotating it to a scanner
/// whose B0 lies along x keeps both and moves Gz to ∂B_x/∂x.
#[test]
fn an_mri_gradient_carries_its_concomitant_terms() {
    let g = mri_gradient(Vec3::new(0.02, -0.01, 0.04));
    assert_eq!(g.row(2).transpose(), Vec3::new(0.02, -0.01, 0.04));
    assert!(g.trace().abs() < 1e-18 && (g - g.transpose()).norm() < 1e-18);
    let r = rotate_gradient(&g, Vec3::x_axis());
    assert!((r[(0, 0)] - 0.04).abs() < 1e-15, "{r}");
    assert!(r.trace().abs() < 1e-15 && (r - r.transpose()).norm() < 1e-15);
    let zero: Matrix3<f64> = rotate_gradient(&Matrix3::zeros(), -Vec3::z_axis());
    assert_eq!(zero, Matrix3::zeros());
}
