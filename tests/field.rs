//! The applied field of scenes: coils' Jacobians against closed forms and Richardson-extrapolated
//! differences, Maxwell's equations, the Maxwell pair's force on a moment through a scene, the
//! duty-cycle waveform's impulse, the MRI gradient key, and the linear field's formula bit for bit.

use magdem::core::coils::{mri_gradient, Coil, Loop, Path, Segment, MU0};
use magdem::core::field::{AppliedField, FieldAt, Gradient, Waveform};
use magdem::core::Vec3;
use magdem::scene::Scene;
use nalgebra::{Matrix3, Unit};
use std::f64::consts::PI;

const A: f64 = 0.3; // coil radius (m)
const I: f64 = 100.0; // current (A)

/// (4 G(h/2) − G(h))/3 of central differences with h = 1e-3 of the distance to the wire: error
/// O(h⁴) ≈ 1e-12 and round-off ε d/h ≈ 1e-12 of |G|, independent of the Jacobian's own step.
fn richardson(coil: &Coil, at: Vec3) -> Matrix3<f64> {
    let h = 1e-3 * coil.distance(at);
    (4.0 * coil.gradient(at, 0.5 * h) - coil.gradient(at, h)) / 3.0
}

fn coils() -> Vec<(&'static str, Coil)> {
    let tilted = Unit::new_normalize(Vec3::new(1.0, 2.0, 3.0));
    vec![
        (
            "loop",
            Coil {
                paths: vec![Path::Loop(Loop { centre: Vec3::new(0.1, 0.0, 0.0), axis: tilted, radius: A, current: I })],
            },
        ),
        ("maxwell", Coil::maxwell(Vec3::zeros(), Vec3::x_axis(), A, I)),
        ("helmholtz", Coil::helmholtz(Vec3::new(0.0, 0.05, 0.0), Vec3::z_axis(), A, I)),
        ("golay", Coil::golay(A, I, 64)),
    ]
}

const POINTS: [[f64; 3]; 4] = [[0.05, -0.1, 0.07], [-0.2, 0.1, 0.3], [0.0, 0.0, 0.6], [1e-3, 2e-3, -1e-3]];

/// The Jacobian agrees with Richardson-extrapolated differences of B, and is traceless and
/// symmetric (∇·B = 0, ∇×B = 0 for closed circuits), to 1e-9 of the field's gradient scale
/// max(|G|, |B|/d), d the distance to the nearest wire: `Coil::jacobian`'s error estimate is
/// about 2e-10 of |B|/d (the round-off of differences of B; measured ≤ 2.2e-10), which near a
/// Helmholtz pair's centre, where G nearly vanishes, exceeds |G|.
#[test]
fn coil_jacobians_agree_with_differences_and_maxwells_equations() {
    let (mut worst_fd, mut worst_div, mut worst_curl) = (0.0_f64, 0.0_f64, 0.0_f64);
    for (name, coil) in coils() {
        for p in POINTS {
            let at = Vec3::from(p);
            let g = coil.jacobian(at);
            let scale = g.norm().max(coil.field(at).norm() / coil.distance(at));
            let fd = (g - richardson(&coil, at)).norm() / scale;
            let div = g.trace().abs() / scale;
            let curl = (g - g.transpose()).norm() / scale;
            assert!(fd < 1e-9 && div < 1e-9 && curl < 1e-9, "{name} at {at:?}: fd {fd:e}, div {div:e}, curl {curl:e}");
            (worst_fd, worst_div, worst_curl) = (worst_fd.max(fd), worst_div.max(div), worst_curl.max(curl));
        }
    }
    println!("worst relative deviation: differences {worst_fd:.1e}, divergence {worst_div:.1e}, curl {worst_curl:.1e}");
}

/// A loop on its axis: ∂B_z/∂z = −3 μ0 I a² z / (2 (a² + z²)^{5/2}), ∂B_x/∂x = ∂B_y/∂y = −½ of it
/// (∇·B = 0 and symmetry about the axis), the rest zero. Within 1e-9 of |G| (measured ≤ 7e-11).
#[test]
fn a_loop_jacobian_on_its_axis_is_the_closed_form() {
    let coil =
        Coil { paths: vec![Path::Loop(Loop { centre: Vec3::zeros(), axis: Vec3::z_axis(), radius: A, current: I })] };
    for z in [0.05, 0.2, -0.4] {
        let gzz = -3.0 * MU0 * I * A * A * z / (2.0 * (A * A + z * z).powf(2.5));
        let exact = mri_gradient(Vec3::new(0.0, 0.0, gzz));
        let g = coil.jacobian(Vec3::new(0.0, 0.0, z));
        let deviation = (g - exact).norm() / exact.norm();
        println!("z = {z}: {deviation:.1e}");
        assert!(deviation < 1e-9, "z = {z}: {g} against {exact}");
    }
}

/// In the mid-plane of a straight segment of half-length L along z, at distance r on x:
/// B = B_φ(r) ŷ with B_φ = μ0 I L / (2π r √(L² + r²)); so ∂B_y/∂x = B_φ'(r) =
/// −μ0 I L (L² + 2r²)/(2π r² (L² + r²)^{3/2}) and ∂B_x/∂y = −B_φ/r, the rest zero (an open
/// segment is not curl-free: the two differ). Within 1e-9 of |G| (measured ≤ 7e-11).
#[test]
fn a_segment_jacobian_in_its_mid_plane_is_the_closed_form() {
    let l = 0.2;
    let coil = Coil {
        paths: vec![Path::Segment(Segment { from: Vec3::new(0.0, 0.0, -l), to: Vec3::new(0.0, 0.0, l), current: I })],
    };
    for r in [0.01, 0.1, 0.5] {
        let s = (l * l + r * r).sqrt();
        let b_phi = MU0 * I * l / (2.0 * PI * r * s);
        let mut exact = Matrix3::zeros();
        exact[(1, 0)] = -MU0 * I * l * (l * l + 2.0 * r * r) / (2.0 * PI * r * r * s.powi(3));
        exact[(0, 1)] = -b_phi / r;
        let g = coil.jacobian(Vec3::new(r, 0.0, 0.0));
        let deviation = (g - exact).norm() / exact.norm();
        println!("r = {r}: {deviation:.1e}");
        assert!(deviation < 1e-9, "r = {r}: {g} against {exact}");
    }
}

/// A scene with one fixed moment m ẑ at the centre of a Maxwell pair on z: the gradient force is
/// F = G m = (48√3/7^{5/2}) μ0 I m / a² ẑ (the field is zero there, so no moment is induced
/// beyond the permanent one). Within 1e-9 (measured 1.2e-11).
#[test]
fn the_maxwell_pair_pulls_a_moment_at_its_centre_as_the_closed_form() {
    let m = 1e-12;
    let scene = Scene::parse(&fixed_moment_scene(m, "[[field.coils]]\nkind = \"maxwell\"\ncentre = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\nradius = 0.3\ncurrent = 100.0\n", ""), "maxwell").unwrap();
    let state = scene.initial_magnetic_state().unwrap();
    let f = state.fields.force[0];
    let exact = 48.0 * 3f64.sqrt() / 7f64.powf(2.5) * MU0 * I / (A * A) * m;
    let deviation = (f - Vec3::new(0.0, 0.0, exact)).norm() / exact;
    println!("F = {f:?}, closed form {exact:e} ẑ: deviation {deviation:.1e}");
    assert!(deviation < 1e-9);
}

/// A single sphere at the origin with permanent moment m ẑ, no susceptibility, no drag: only
/// the gradient force acts. `field` is the rest of the `[field]` table after b0, `more` follows
/// the integration table.
fn fixed_moment_scene(m: f64, field: &str, more: &str) -> String {
    format!(
        r#"version = 1
[domain]
lo = [-1.0e-4, -1.0e-4, -1.0e-4]
hi = [1.0e-4, 1.0e-4, 1.0e-4]
[field]
b0 = [0.0, 0.0, 0.1]
{field}
[[species]]
name = "p"
diameter = 10.0e-6
density = 1000.0
youngs_modulus = 1.0e9
poisson_ratio = 0.3
friction = 0.5
restitution = 0.5
permanent_moment = [0.0, 0.0, {m:e}]
[[particles]]
species = "p"
positions = [[0.0, 0.0, 0.0]]
[forces.gradient]
[integration]
dt = 1.0e-6
end_time = 3.5e-4
{more}"#
    )
}

/// Duty cycle T = 100 µs, D = 0.3, phase 0.205: on over [20.5, 50.5] µs and each 100 µs later.
/// The impulse is F ∫w dt: 30 µs per whole on-phase, and 29.5 µs of the last one, cut at
/// 350 µs. Velocity Verlet's trapezoid over samples that never fall on an edge gives the same
/// integral, so the velocity is F/m_p ∫w dt to round-off (1e-12 asserted, measured 5e-15): no
/// change while off, the on-phases summed.
#[test]
fn a_duty_cycle_gives_the_impulse_of_its_on_phases_only() {
    let (moment, gz) = (1e-12, 0.1);
    let field =
        format!("gradient_mri = [0.0, 0.0, {gz}]\n[field.waveform]\nperiod = 1.0e-4\nduty = 0.3\nphase = 0.205\n");
    let scene = Scene::parse(&fixed_moment_scene(moment, &field, ""), "duty").unwrap();
    let mass = scene.initial.mass[0];
    let acceleration = gz * moment / mass;
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    // (step, on-time up to it in µs)
    let checks = [(20, 0.0), (35, 14.5), (80, 30.0), (120, 30.0), (200, 60.0), (300, 90.0), (350, 119.5)];
    for (step, on_time) in checks {
        while sim.state.step < step {
            sim.step().unwrap();
        }
        let v = sim.state.particles.velocity[0];
        let expected = acceleration * on_time * 1e-6;
        let scale = acceleration * 119.5e-6;
        println!("step {step}: v_z = {:e}, closed form {expected:e}", v.z);
        assert!(
            (v.z - expected).abs() < 1e-12 * scale && v.xy().norm() == 0.0,
            "step {step}: {v:?} against {expected:e}"
        );
    }
}

/// The waveform's timing: on at the phase, off after duty · period, periodic.
#[test]
fn the_waveform_switches_at_its_edges() {
    let w = Waveform { period: 2.0, duty: 0.25, phase: 0.5 };
    for (t, on) in [(0.0, 0.0), (0.99, 0.0), (1.01, 1.0), (1.49, 1.0), (1.51, 0.0), (3.2, 1.0), (-0.8, 1.0)] {
        assert_eq!(w.at(t), on, "t = {t}");
    }
    assert_eq!(Waveform { period: 1.0, duty: 1.0, phase: 0.0 }.at(0.7), 1.0);
}

/// The linear field computes B0 + G x and hands over G itself, bit for bit, with or without a
/// waveform (w = 1 exactly while on; B0 alone while off). Existing scenes' runs were compared
/// with the previous binary's HDF5 files and found identical (the commit message says which).
#[test]
fn the_linear_field_is_the_formula_it_always_was() {
    let b0 = Vec3::new(0.005, 1e-3, -2e-4);
    let g = Matrix3::new(1.4, 0.3, 0.0, 0.3, -0.5, 0.2, 0.0, 0.2, -0.9);
    let x = Vec3::new(1.7e-5, -3.3e-5, 2.9e-6);
    let bits = |v: Vec3| v.map(f64::to_bits);
    let plain = AppliedField::linear(b0, g);
    let switched = AppliedField { waveform: Some(Waveform { period: 1.0, duty: 0.5, phase: 0.0 }), ..plain.clone() };
    for (field, t) in [(&plain, 0.7), (&switched, 0.2)] {
        let at = field.at(t);
        assert!(matches!(at, FieldAt::Linear { .. }));
        assert_eq!(bits(at.field(&x)), bits(b0 + g * x));
        assert_eq!(at.jacobian(&x), g);
    }
    assert_eq!(bits(switched.at(0.7).field(&x)), bits(b0));
    assert_eq!(switched.at(0.7).jacobian(&x), Matrix3::zeros());
    let Gradient::Linear(kept) = plain.gradient else { panic!("linear") };
    assert_eq!(kept, g);
}

/// `gradient_mri` is ∇B_∥ in scene axes with its concomitant terms: along z exactly
/// `mri_gradient`; with B0 along x the row along B0 is the given vector, and the tensor stays
/// traceless and symmetric (to 1e-16 T/m).
#[test]
fn an_mri_gradient_key_carries_its_concomitant_terms() {
    let given = Vec3::new(0.02, -0.01, 0.04);
    let field = |b0: &str| {
        let text =
            fixed_moment_scene(1e-12, "gradient_mri = [0.02, -0.01, 0.04]", "").replace("b0 = [0.0, 0.0, 0.1]", b0);
        Scene::parse(&text, "mri").unwrap().spec.field.unwrap().linear_gradient()
    };
    assert_eq!(field("b0 = [0.0, 0.0, 0.1]"), mri_gradient(given));
    let g = field("b0 = [0.3, 0.0, 0.0]");
    assert!((g.row(0).transpose() - given).norm() < 1e-16, "{g}");
    assert!(g.trace().abs() < 1e-16 && (g - g.transpose()).norm() < 1e-16, "{g}");
}

/// A waveform switches the coils too: zero Jacobian while off, B0 alone.
#[test]
fn a_waveform_switches_coils_and_keeps_b0() {
    let field = AppliedField {
        b0: Vec3::new(0.0, 0.0, 1.5),
        gradient: Gradient::Coils(Coil::maxwell(Vec3::zeros(), Vec3::z_axis(), A, I)),
        waveform: Some(Waveform { period: 1.0, duty: 0.5, phase: 0.0 }),
    };
    let x = Vec3::new(0.01, 0.02, 0.03);
    assert_eq!(field.at(0.7).field(&x), field.b0);
    assert_eq!(field.at(0.7).jacobian(&x), Matrix3::zeros());
    assert!(field.at(0.2).jacobian(&x).norm() > 0.0);
}
