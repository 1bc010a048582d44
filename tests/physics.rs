//! Physics verification against closed forms and independent solutions (docs/model.md §11).

use magdem::core::field::AppliedField;
use magdem::core::flow::Flow;
use magdem::core::forces::drag::{Drag, DragLaw, Fluid, Shielding};
use magdem::core::forces::magnetisation::{Induction, Magnetisation, MU0};
use magdem::core::forces::shielding::lens_area;
use magdem::core::forces::ForceTerm;
use magdem::core::neighbours::{PairRange, Skins};
use magdem::core::simulation::ForceField;
use magdem::core::state::{Particles, Species, State, Vec3};
use magdem::scene::Scene;
use nalgebra::Matrix3;
use std::f64::consts::PI;

const WATER: &str = "[fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n";

fn species(extra: &str) -> String {
    format!(
        "[[species]]\nname = \"p\"\ndiameter = 11.0e-6\ndensity = 1087.0\nyoungs_modulus = 1.0e9\n\
         poisson_ratio = 0.5\nfriction = 0.5\n{extra}\n"
    )
}

fn scene(body: &str) -> Scene {
    let text = format!("version = 1\n[domain]\nlo = [-4e-4, -1e-4, -1e-4]\nhi = [4e-4, 1e-4, 1e-4]\n{body}");
    Scene::parse(&text, "test").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Steps a head-on impact of two spheres of radius `a` (particles 0 and 1 along x) through one
/// contact: its largest overlap and its duration, between the linearly interpolated crossings
/// of overlap = 0.
fn head_on_contact(sim: &mut magdem::core::simulation::Simulation, a: f64) -> (f64, f64) {
    let (mut max_overlap, mut t_start, mut t_end, mut prev_overlap) = (0.0_f64, None, None, 0.0);
    while t_end.is_none() {
        sim.step().unwrap();
        let p = &sim.state.particles;
        let overlap = 2.0 * a - (p.position[1] - p.position[0]).norm();
        let crossing = sim.state.time - sim.dt * overlap / (overlap - prev_overlap);
        if overlap > 0.0 && prev_overlap <= 0.0 {
            t_start = Some(crossing);
        }
        if overlap <= 0.0 && prev_overlap > 0.0 {
            t_end = Some(crossing);
        }
        max_overlap = max_overlap.max(overlap);
        prev_overlap = overlap;
    }
    (max_overlap, t_end.unwrap() - t_start.unwrap())
}

/// Hertz elastic head-on impact of two equal spheres: max overlap and contact duration against
/// δ = (15 m* v²/(16 E* √R*))^(2/5) and t_c = 2.87 (m*²/(R* E*² v))^(1/5).
#[test]
fn hertz_elastic_impact_matches_closed_form() {
    let (a, v_each): (f64, f64) = (5.5e-6, 0.05);
    let s = scene(&format!(
        "{}[[particles]]\nspecies = \"p\"\npositions = [[-{x:e}, 0, 0], [{x:e}, 0, 0]]\nvelocities = [[{v_each}, 0, 0], [-{v_each}, 0, 0]]\n\
         [forces.contact]\n[integration]\ndt = 1.0e-11\nend_time = 1.0\n",
        species("restitution = 1.0"),
        x = a + 1e-9
    ));
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    let (max_overlap, duration) = head_on_contact(&mut sim, a);
    let sp = &s.species[0];
    let (m_eff, r_eff) = (sp.mass() / 2.0, a / 2.0);
    let e_star = 1.0e9 / (2.0 * (1.0 - 0.25));
    let v = 2.0 * v_each;
    let delta = (15.0 * m_eff * v * v / (16.0 * e_star * r_eff.sqrt())).powf(0.4);
    // Johnson's 2.87 rounds the exact constant 2 ∫₀¹ (1 − x^(5/2))^(−1/2) dx (15/16)^(2/5)
    // = 2 (2/5) Γ(2/5) Γ(1/2)/Γ(9/10) (15/16)^(2/5) = 2.86827 (2.87 alone would leave 6e-4).
    let t_c = 2.868_265_699_195_33 * (m_eff * m_eff / (r_eff * e_star * e_star * v)).powf(0.2);
    let (e_overlap, e_duration) = (max_overlap / delta - 1.0, duration / t_c - 1.0);
    println!(
        "max overlap {max_overlap:.9e} (closed form {delta:.9e}, {e_overlap:.2e}); duration {duration:.9e} (closed form {t_c:.9e}, {e_duration:.2e})"
    );
    // Measured at dt = 1e-11 s: overlap −2.5e-9, duration −1.5e-9.
    assert!(e_overlap.abs() < 1e-8, "max overlap {max_overlap:e} vs {delta:e}");
    assert!(e_duration.abs() < 1e-8, "duration {duration:e} vs {t_c:e}");
    // Elastic: the rebound speed equals the impact speed.
    let rebound = (sim.state.particles.velocity[1] - sim.state.particles.velocity[0]).x;
    assert!((rebound / v - 1.0).abs() < 1e-3, "rebound {rebound} vs {v}");
}

/// Unlike spheres (densities 1087 and 5000 kg/m³) meeting head-on, elastic: each keeps its own
/// mass through the kicks, so the momentum is conserved to round-off and the rebound velocities
/// are those of a 1-D elastic collision, v1' = ((m1 − m2) v1 + 2 m2 v2)/(m1 + m2).
#[test]
fn unlike_spheres_rebound_as_an_elastic_collision_of_their_masses() {
    let (a, v1, v2): (f64, f64, f64) = (5.5e-6, 0.05, -0.02);
    let heavy = species("restitution = 1.0").replace("\"p\"", "\"q\"").replace("1087.0", "5000.0");
    let s = scene(&format!(
        "{}{heavy}[[particles]]\nspecies = \"p\"\npositions = [[-{x:e}, 0, 0]]\nvelocities = [[{v1}, 0, 0]]\n\
         [[particles]]\nspecies = \"q\"\npositions = [[{x:e}, 0, 0]]\nvelocities = [[{v2}, 0, 0]]\n\
         [forces.contact]\n[integration]\ndt = 1.0e-11\nend_time = 1.0\n",
        species("restitution = 1.0"),
        x = a + 1e-9
    ));
    let (m1, m2) = (s.species[0].mass(), s.species[1].mass());
    assert!(m2 > 4.0 * m1);
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    let separated = |p: &Particles| (p.position[1] - p.position[0]).norm() > 2.0 * a + 2e-9;
    let mut touched = false;
    while !(touched && separated(&sim.state.particles)) {
        sim.step().unwrap();
        touched |= !separated(&sim.state.particles);
    }
    let u = &sim.state.particles.velocity;
    let momentum = m1 * u[0].x + m2 * u[1].x;
    let before = m1 * v1 + m2 * v2;
    assert!((momentum / before - 1.0).abs() < 1e-9, "momentum {momentum:e} vs {before:e}");
    let expected = [((m1 - m2) * v1 + 2.0 * m2 * v2) / (m1 + m2), ((m2 - m1) * v2 + 2.0 * m1 * v1) / (m1 + m2)];
    println!("rebound {:.6} {:.6} m/s (elastic collision {:.6} {:.6})", u[0].x, u[1].x, expected[0], expected[1]);
    for k in 0..2 {
        assert!((u[k].x - expected[k]).abs() < 1e-3 * (v1 - v2), "particle {k}: {} vs {}", u[k].x, expected[k]);
    }
}

fn two_dipoles(induction: &str, r0: f64, density: f64) -> Scene {
    scene(&format!(
        "{WATER}[field]\nb0 = [0.4, 0, 0]\n{}[[particles]]\nspecies = \"p\"\npositions = [[-{h:e}, 0, 0], [{h:e}, 0, 0]]\n\
         [forces.dipole]\ninduction = \"{induction}\"\n[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n\
         [integration]\ndt = 1.0e-8\nend_time = 1.0\n",
        species("restitution = 0.5\nrelative_permeability = 12.3").replace("density = 1087.0", &format!("density = {density:?}")),
        h = r0 / 2.0
    ))
}

/// Time at which the centre distance first falls to one diameter (linear interpolation).
fn time_to_contact(s: &Scene) -> f64 {
    let d = 11.0e-6;
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    let mut prev = (0.0, (sim.state.particles.position[1] - sim.state.particles.position[0]).norm());
    loop {
        sim.step().unwrap();
        let r = (sim.state.particles.position[1] - sim.state.particles.position[0]).norm();
        if r <= d {
            return prev.0 + (sim.state.time - prev.0) * (prev.1 - d) / (prev.1 - r);
        }
        prev = (sim.state.time, r);
    }
}

/// Isolated moment χ_eff V H0 of the test species at 0.4 T.
fn isolated_moment() -> f64 {
    let chi_eff = 3.0 * 11.3 / 14.3;
    chi_eff * 4.0 / 3.0 * PI * 5.5e-6_f64.powi(3) * 0.4 / MU0
}

/// The closed form r⁵ = r0⁵ − 5Ct neglects inertia. With the paper's density (τ = m/6πμa =
/// 7.3 µs) inertia delays contact by 0.66% (the RK4 reference below shows it), so the closed form
/// is checked with the density lowered 100× (τ = 73 ns), where inertia is negligible, and the
/// paper's density against the inertial ODE.
#[test]
fn two_dipoles_close_in_the_closed_form_time_without_induction() {
    let (d, r0): (f64, f64) = (11.0e-6, 15.0 * 11.0e-6);
    let t = time_to_contact(&two_dipoles("none", r0, 10.87));
    let m = isolated_moment();
    let c = MU0 * m * m / (2.0 * PI * PI * 1.0e-3 * 5.5e-6);
    let closed = (r0.powi(5) - d.powi(5)) / (5.0 * c);
    println!("time to contact {t:.6e} s, closed form {closed:.6e} s (ratio {:.5})", t / closed);
    // Measured: 9.1e-5 (inertia at τ = 73 ns and the step).
    assert!((t / closed - 1.0).abs() < 1e-3);

    let t_inertial = time_to_contact(&two_dipoles("none", r0, 1087.0));
    let reference = pair_ode_contact_time(r0, false);
    println!("paper density: {t_inertial:.6e} s, RK4 with inertia {reference:.6e} s, closed form {closed:.6e} s");
    // Measured: −3.9e-6.
    assert!((t_inertial / reference - 1.0).abs() < 4e-5);
}

/// Independent solution of the collinear pair with self-consistent moments: the relative
/// coordinate r obeys m_p r'' = −2F(r) − 6π μ a r', F = 3μ0 m(r)²/(2π r⁴),
/// m(r) = χ_eff V H0 / (1 − χ_eff V/(2π r³)); classical RK4 at 1e-10 s.
fn pair_ode_contact_time(r0: f64, induction: bool) -> f64 {
    let (a, mu): (f64, f64) = (5.5e-6, 1.0e-3);
    let volume = 4.0 / 3.0 * PI * a.powi(3);
    let mass = 1087.0 * volume;
    let chi_v = 3.0 * 11.3 / 14.3 * volume;
    let h0 = 0.4 / MU0;
    let gamma = 6.0 * PI * mu * a;
    let accel = |r: f64, v: f64| {
        let enhancement = if induction { 1.0 / (1.0 - chi_v / (2.0 * PI * r.powi(3))) } else { 1.0 };
        let m = chi_v * h0 * enhancement;
        let f = 3.0 * MU0 * m * m / (2.0 * PI * r.powi(4));
        (-2.0 * f - gamma * v) / mass
    };
    let (mut r, mut v, mut t, h) = (r0, 0.0_f64, 0.0_f64, 1.0e-10);
    loop {
        let (k1r, k1v) = (v, accel(r, v));
        let (k2r, k2v) = (v + 0.5 * h * k1v, accel(r + 0.5 * h * k1r, v + 0.5 * h * k1v));
        let (k3r, k3v) = (v + 0.5 * h * k2v, accel(r + 0.5 * h * k2r, v + 0.5 * h * k2v));
        let (k4r, k4v) = (v + h * k3v, accel(r + h * k3r, v + h * k3v));
        let r_next = r + h / 6.0 * (k1r + 2.0 * k2r + 2.0 * k3r + k4r);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if r_next <= 2.0 * a {
            return t + h * (r - 2.0 * a) / (r - r_next);
        }
        r = r_next;
        t += h;
    }
}

#[test]
fn two_dipoles_with_exact_induction_match_an_independent_ode_solution() {
    let r0 = 6.0 * 11.0e-6;
    let t = time_to_contact(&two_dipoles("exact", r0, 1087.0));
    let reference = pair_ode_contact_time(r0, true);
    println!(
        "exact induction: time to contact {t:.6e} s, RK4 reference {reference:.6e} s (ratio {:.6})",
        t / reference
    );
    assert!((t / reference - 1.0).abs() < 1e-3);
    // Induction shortens the approach: the no-induction reference is longer.
    let t_none = pair_ode_contact_time(r0, false);
    println!("without induction the RK4 reference is {t_none:.6e} s");
    assert!(t_none > t * 1.001, "none {t_none:e} vs exact {t:e}");
}

/// One saturated particle (M = Ms) under ∂Bx/∂x = G moves at V Ms G/(6π μ a).
#[test]
fn terminal_velocity_under_a_gradient() {
    let (ms, g) = (1.0e4, 1.4);
    let s = scene(&format!(
        "{WATER}[field]\nb0 = [0.5, 0, 0]\ngradient = [[{g}, 0, 0], [0, 0, 0], [0, 0, 0]]\n{}\
         [[particles]]\nspecies = \"p\"\npositions = [[0, 0, 0]]\n[forces.gradient]\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[integration]\ndt = 1.0e-7\nend_time = 2.0e-4\n",
        species(&format!("restitution = 0.5\nrelative_permeability = 12.3\nsaturation_magnetisation = {ms}"))
    ));
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    for _ in 0..s.total_steps() {
        sim.step().unwrap();
    }
    let a: f64 = 5.5e-6;
    let expected = 4.0 / 3.0 * PI * a.powi(3) * ms * g / (6.0 * PI * 1.0e-3 * a);
    let v = sim.state.particles.velocity[0].x;
    println!("terminal velocity {v:.9e} m/s, V M G/(6π μ a) = {expected:.9e} m/s ({:.2e})", v / expected - 1.0);
    // Measured: −1.1e-12 (27 relaxation times: e^(−27) = 2e-12 of the start remains).
    assert!((v / expected - 1.0).abs() < 1e-11);
}

/// The Fröhlich–Kennelly law: an isolated particle's moment is χ_eff H Ms/(Ms + χ_eff H) V, so
/// under a gradient it moves at V M G/(6π μ a) with that M (half the linear one here).
#[test]
fn frohlich_kennelly_terminal_velocity() {
    let (ms, g, b0) = (1.0e6, 1.4, 0.5);
    let s = scene(&format!(
        "{WATER}[field]\nb0 = [{b0}, 0, 0]\ngradient = [[{g}, 0, 0], [0, 0, 0], [0, 0, 0]]\n{}\
         [[particles]]\nspecies = \"p\"\npositions = [[0, 0, 0]]\n[forces.gradient]\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[integration]\ndt = 1.0e-7\nend_time = 2.0e-4\n",
        species(&format!("restitution = 0.5\nrelative_permeability = 12.3\nsaturation_magnetisation = {ms}\nsaturation_law = \"frohlich-kennelly\""))
    ));
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    for _ in 0..s.total_steps() {
        sim.step().unwrap();
    }
    let a: f64 = 5.5e-6;
    let chi_eff = 3.0 * 11.3 / 14.3;
    let linear = chi_eff * (b0 + g * sim.state.particles.position[0].x) / magdem::core::forces::magnetisation::MU0;
    let m = linear * ms / (ms + linear);
    // The law bends here: M is about half the linear χ_eff H (b0 and Ms chosen for it).
    let expected = 4.0 / 3.0 * PI * a.powi(3) * m * g / (6.0 * PI * 1.0e-3 * a);
    let v = sim.state.particles.velocity[0].x;
    println!(
        "terminal velocity {v:.9e} m/s, V M G/(6π μ a) = {expected:.9e} m/s (M = {m:.4e} A/m, {:.2e})",
        v / expected - 1.0
    );
    // Measured: −4.8e-8 (the moment follows the field along the path; the drag lags it by τ).
    assert!((v / expected - 1.0).abs() < 5e-7);
}

fn chain(n: usize, mu_r: f64) -> (Particles, Species) {
    let sp = Species {
        name: "p".into(),
        radius: 5.5e-6,
        density: 1087.0,
        youngs_modulus: 1e9,
        poisson_ratio: 0.5,
        friction: 0.5,
        restitution: 0.5,
        susceptibility: 3.0 * (mu_r - 1.0) / (mu_r + 2.0),
        saturation: None,
        permanent_moment: None,
        size: None,
    };
    let mut p = Particles::default();
    for k in 0..n {
        p.push(0, &sp, Vec3::new(k as f64 * 11.0e-6, 0.0, 0.0), Vec3::zeros());
    }
    (p, sp)
}

/// Independent direct solve of (I − χV T) m = χV H0 with nalgebra's LU.
fn direct_chain_moments(p: &Particles, chi_v: f64, h0: Vec3) -> Vec<Vec3> {
    let n = p.len();
    let mut a = nalgebra::DMatrix::<f64>::identity(3 * n, 3 * n);
    let mut b = nalgebra::DVector::<f64>::zeros(3 * n);
    for i in 0..n {
        for k in 0..3 {
            b[3 * i + k] = chi_v * h0[k];
        }
        for j in 0..n {
            if i == j {
                continue;
            }
            let r = p.position[i] - p.position[j];
            let d = r.norm();
            let rhat = r / d;
            for (row, col) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                let delta = if row == col { 1.0 } else { 0.0 };
                a[(3 * i + row, 3 * j + col)] = -chi_v * (3.0 * rhat[row] * rhat[col] - delta) / (4.0 * PI * d.powi(3));
            }
        }
    }
    let m = a.lu().solve(&b).unwrap();
    (0..n).map(|i| Vec3::new(m[3 * i], m[3 * i + 1], m[3 * i + 2])).collect()
}

#[test]
fn five_sphere_chain_moments_match_a_direct_solve() {
    let (p, sp) = chain(5, 12.3);
    let domain = magdem::core::domain::Domain { lo: Vec3::repeat(-1e-3), hi: Vec3::repeat(1e-3), periodic: [false; 3] };
    let b0 = Vec3::new(0.4, 0.0, 0.0);
    let h0 = b0 / MU0;
    let isolated = sp.susceptibility * sp.volume() * h0.x;
    let direct = direct_chain_moments(&p, sp.susceptibility * sp.volume(), h0);
    let expected = [1.39, 1.67, 1.73, 1.67, 1.39];
    for (label, induction) in [
        ("dense", Induction::Exact { tolerance: 1e-12, max_iterations: 500, dense_max: 150 }),
        ("iterative", Induction::Exact { tolerance: 1e-12, max_iterations: 500, dense_max: 0 }),
    ] {
        let mag = Magnetisation::new(
            induction,
            AppliedField::linear(b0, Matrix3::zeros()),
            std::slice::from_ref(&sp),
            Skins::default(),
        );
        let mut field = ForceField::new(domain.clone(), vec![Box::new(mag) as Box<dyn ForceTerm>]);
        let mut state = State::new(p.clone());
        field.evaluate(&mut state, 1e-8);
        assert!(field.take_term_error().is_none(), "{label}: the induction converged");
        let moment = &state.fields.moment;
        let ratios: Vec<f64> = moment.iter().map(|m| m.x / isolated).collect();
        println!("{label}: moments / isolated = {ratios:.4?}");
        for i in 0..5 {
            assert!((moment[i] - direct[i]).norm() <= 1e-9 * direct[i].norm(), "{label} particle {i}");
            assert!((ratios[i] - expected[i]).abs() < 0.005, "{label} particle {i}: {} vs {}", ratios[i], expected[i]);
        }
    }
}

#[test]
fn lens_area_matches_the_closed_form_at_several_offsets() {
    // Unequal and equal circles (two code paths): compare with numerical integration of the
    // overlap along the centre line.
    for (r1, r2, s) in
        [0.35, 0.6, 1.0, 1.4, 1.65].into_iter().map(|s| (1.0, 0.7, s)).chain([0.1, 0.9, 1.8].map(|s| (1.0, 1.0, s)))
    {
        let n = 200_000;
        let (lo, hi) = (s - r2, r1);
        let h = (hi - lo) / n as f64;
        let numeric: f64 = (0..n)
            .map(|k| {
                let x = lo + (k as f64 + 0.5) * h;
                let c1 = (r1 * r1 - x * x).max(0.0).sqrt();
                let c2 = (r2 * r2 - (x - s).powi(2)).max(0.0).sqrt();
                2.0 * c1.min(c2) * h
            })
            .sum();
        let area = lens_area(r1, r2, s);
        println!("offset {s}: lens {area:.8} numeric {numeric:.8}");
        assert!((area - numeric).abs() < 1e-6, "s = {s}");
    }
}

#[test]
fn chain_moving_along_its_axis_has_drag_only_on_its_leading_sphere() {
    let (mut p, _) = chain(3, 12.3);
    let u = Vec3::new(1e-4, 0.0, 0.0);
    p.velocity.iter_mut().for_each(|v| *v = u);
    let domain = magdem::core::domain::Domain { lo: Vec3::repeat(-1e-3), hi: Vec3::repeat(1e-3), periodic: [false; 3] };
    let near = PairRange::Within { range: 11.0e-6 * 1.001, skin: 0.0 };
    let paper = Shielding::Paper { touch_tolerance: 1e-3, near };
    for (shielding, expect_shielded) in [(paper, true), (Shielding::None, false)] {
        let mut state = State::new(p.clone());
        let water = Fluid { density: 1000.0, viscosity: 1.0e-3, flow: Flow::Uniform(Vec3::zeros()) };
        let drag = Drag::new(DragLaw::Stokes, shielding, false, water);
        ForceField::new(domain.clone(), vec![Box::new(drag)]).evaluate(&mut state, 1e-8);
        let stokes = -6.0 * PI * 1.0e-3 * 5.5e-6 * u.x;
        let f: Vec<f64> = state.fields.force.iter().map(|f| f.x).collect();
        println!("{shielding:?}: drag {f:?} N (Stokes {stokes:.4e} N)");
        // The leading sphere is the one furthest along +x (index 2).
        assert!((f[2] / stokes - 1.0).abs() < 1e-12);
        for &fi in &f[..2] {
            if expect_shielded {
                assert!(fi.abs() < 1e-12 * stokes.abs());
            } else {
                assert!((fi / stokes - 1.0).abs() < 1e-12);
            }
        }
    }
}

/// Head-on impact of two equal spheres on a Hooke spring with restitution damping: a linear
/// spring-dashpot with γ = −2β√(k m*) rebounds with exactly the restitution coefficient e after
/// half a damped period π/(ω√(1 − β²)), ω = √(k/m*). Velocity Verlet at ω dt = 5e-4: the error
/// of the velocity-dependent damping is first order, ~ζω dt ≈ 1e-4, inside the 1e-3 asserted.
#[test]
fn hooke_impact_rebounds_with_the_restitution_coefficient_after_half_a_damped_period() {
    let (a, v_each, k, e) = (5.5e-6_f64, 0.05, 1.0e3, 0.5_f64);
    let s = scene(&format!(
        "{}[[particles]]\nspecies = \"p\"\npositions = [[-{x:e}, 0, 0], [{x:e}, 0, 0]]\nvelocities = [[{v_each}, 0, 0], [-{v_each}, 0, 0]]\n\
         [forces.contact]\nnormal = \"hooke\"\nstiffness = {k:e}\n[integration]\ndt = 1.0e-11\nend_time = 1.0\n",
        species(&format!("restitution = {e}")),
        x = a + 1e-9
    ));
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    let (_, duration) = head_on_contact(&mut sim, a);
    let m_eff = s.species[0].mass() / 2.0;
    let beta = e.ln() / (e.ln().powi(2) + PI * PI).sqrt();
    let t_c = PI / ((k / m_eff).sqrt() * (1.0 - beta * beta).sqrt());
    let rebound = (sim.state.particles.velocity[1] - sim.state.particles.velocity[0]).x / (2.0 * v_each);
    println!("duration {duration:.6e} s (closed form {t_c:.6e}); restitution {rebound:.6} (scene {e})");
    assert!((duration / t_c - 1.0).abs() < 1e-3, "duration {duration:e} vs {t_c:e}");
    assert!((rebound / e - 1.0).abs() < 1e-3, "restitution {rebound} vs {e}");
}

/// An oblique elastic impact (30° off the line of centres) with `tangential = "none"`:
/// frictionless spheres exert no torque beyond round-off and keep their kinetic energy; the same
/// impact with Mindlin's spring spins them (the control).
#[test]
fn frictionless_oblique_impact_spins_nothing_and_keeps_its_energy() {
    let a = 5.5e-6_f64;
    let run = |tangential: &str| {
        let s = scene(&format!(
            "{}[[particles]]\nspecies = \"p\"\npositions = [[-{x:e}, -{y:e}, 0], [{x:e}, {y:e}, 0]]\nvelocities = [[0.05, 0, 0], [-0.05, 0, 0]]\n\
             [forces.contact]\ntangential = \"{tangential}\"\n[integration]\ndt = 1.0e-11\nend_time = 1.0e-6\n",
            species("restitution = 1.0"),
            // Centres just apart along 30° from the velocities: the impact is oblique.
            x = (a + 1e-9) * (PI / 6.0).cos(),
            y = (a + 1e-9) * (PI / 6.0).sin()
        ));
        let mut sim = s.simulation(None);
        sim.initialise().unwrap();
        let energy = sim.state.particles.kinetic_energy();
        // Orbital and spin angular momentum about the origin, Σ m x × v and Σ I ω (z components).
        let momenta = |p: &Particles| {
            (0..2).fold((0.0, 0.0), |(o, w), i| {
                (o + p.mass[i] * p.position[i].cross(&p.velocity[i]).z, w + p.inertia[i] * p.angular_velocity[i].z)
            })
        };
        let before = momenta(&sim.state.particles);
        let mut spin = 0.0_f64;
        while sim.state.time < 1.0e-6 {
            sim.step().unwrap();
            spin = sim.state.particles.angular_velocity.iter().fold(spin, |s, w| s.max(w.norm()));
        }
        let after = momenta(&sim.state.particles);
        // The spin taken from the orbit, relative to the spin's angular momentum.
        let balance = (after.0 + after.1 - before.0 - before.1).abs() / after.1.abs().max(f64::MIN_POSITIVE);
        (spin, sim.state.particles.kinetic_energy() / energy, after.1, balance)
    };
    let (spin, energy_ratio, _, _) = run("none");
    let (mindlin_spin, _, spin_momentum, balance) = run("mindlin");
    println!(
        "largest spin: none {spin:e} rad/s, mindlin {mindlin_spin:e} rad/s; energy after/before {energy_ratio:.6}; \
         Mindlin: spin angular momentum {spin_momentum:.4e}, total angular momentum changed by {balance:.2e} of it"
    );
    // Only round-off: the tangential part of a normal force, |F| ε, times the lever arm.
    assert!(spin < 1e-9 * mindlin_spin, "frictionless spheres do not spin ({spin:e} rad/s)");
    // The control spins, and the spin is what the tangential force took from the orbital angular
    // momentum: the contact torques −c_i n × F_t with c_0 + c_1 = r balance r × F_t, so the total is
    // conserved exactly by Verlet's kicks. Measured: 3.4e-11 (round-off). (The spin's size is checked against
    // Maw, Barber & Fawcett's gross-sliding closed form in tests/independent_forces.rs.)
    assert!(mindlin_spin > 1e3, "Mindlin's spring spins the spheres ({mindlin_spin:e} rad/s)");
    assert!(balance < 3e-10, "angular momentum changed by {balance:e} of the spin's");
    assert!((energy_ratio - 1.0).abs() < 1e-4, "kinetic energy after/before {energy_ratio}");
}

/// The RPY block between two spheres, written here from Zuk et al. (2014) independently of magdem.
fn rpy_block(ai: f64, aj: f64, r: [f64; 3], mu: f64) -> [[f64; 3]; 3] {
    let d = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    let (iso, aniso) = if d > ai + aj {
        let s = (ai * ai + aj * aj) / (d * d);
        ((1.0 + s / 3.0) / (8.0 * PI * mu * d), (1.0 - s) / (8.0 * PI * mu * d))
    } else {
        let (dd, d3) = ((ai - aj).powi(2), d * d * d);
        let k = 6.0 * PI * mu * ai * aj;
        (
            (16.0 * d3 * (ai + aj) - (dd + 3.0 * d * d).powi(2)) / (32.0 * d3) / k,
            3.0 * (dd - d * d).powi(2) / (32.0 * d3) / k,
        )
    };
    let mut b = [[0.0; 3]; 3];
    for (p, row) in b.iter_mut().enumerate() {
        for (q, v) in row.iter_mut().enumerate() {
            *v = if p == q { iso } else { 0.0 } + aniso * r[p] * r[q] / (d * d);
        }
    }
    b
}

/// Forces F with M F = U for spheres of radius `a` at `x` all moving at `u`: Gaussian elimination
/// with partial pivoting on the dense RPY mobility (the test's own solve).
fn rpy_forces(x: &[[f64; 3]], a: f64, mu: f64, u: [f64; 3]) -> Vec<[f64; 3]> {
    let n = 3 * x.len();
    let mut m = vec![vec![0.0; n + 1]; n];
    for i in 0..x.len() {
        for j in 0..x.len() {
            let b = if i == j {
                let s = 1.0 / (6.0 * PI * mu * a);
                [[s, 0.0, 0.0], [0.0, s, 0.0], [0.0, 0.0, s]]
            } else {
                rpy_block(a, a, [x[i][0] - x[j][0], x[i][1] - x[j][1], x[i][2] - x[j][2]], mu)
            };
            for p in 0..3 {
                for q in 0..3 {
                    m[3 * i + p][3 * j + q] = b[p][q];
                }
            }
        }
        for p in 0..3 {
            m[3 * i + p][n] = u[p];
        }
    }
    for c in 0..n {
        let pivot = (c..n).max_by(|&r, &s| m[r][c].abs().total_cmp(&m[s][c].abs())).unwrap();
        m.swap(c, pivot);
        let (top, rest) = m.split_at_mut(c + 1);
        let pivot_row = &top[c];
        for row in rest.iter_mut() {
            let f = row[c] / pivot_row[c];
            row.iter_mut().zip(pivot_row).skip(c).for_each(|(x, p)| *x -= f * p);
        }
    }
    let mut f = vec![0.0; n];
    for r in (0..n).rev() {
        f[r] = (m[r][n] - (r + 1..n).map(|k| m[r][k] * f[k]).sum::<f64>()) / m[r][r];
    }
    (0..x.len()).map(|i| [f[3 * i], f[3 * i + 1], f[3 * i + 2]]).collect()
}

/// A straight chain of n touching 11 µm spheres translating at 10 µm/s along its axis and
/// broadside, n = 1 … 20, with `forces.drag.law = "rpy"`: magdem's per-sphere drag (through the
/// scene and its force field) against the test's own dense solve, to 1e-9. Two touching spheres
/// moving along their line of centres: RPY gives 8/13 = 0.615 of a lone sphere's drag each, against
/// Stimson & Jeffery's exact 0.645 (RPY 4.6 % low); broadside RPY gives 16/23 = 0.696. The paper's
/// A_eff gives the axial chain the drag of one sphere in all (1/n each), printed for the record.
#[test]
fn rpy_chain_drag_matches_an_independent_dense_solve() {
    let (a, mu, speed) = (5.5e-6_f64, 1.0e-3, 1.0e-5);
    let lone = 6.0 * PI * mu * a * speed;
    println!("| n | axial, RPY per sphere ÷ lone | broadside | A_eff axial |");
    for n in [1usize, 2, 3, 5, 10, 20] {
        for (axis, label) in [(0usize, "axial"), (1, "broadside")] {
            let x: Vec<[f64; 3]> = (0..n).map(|k| [2.0 * a * k as f64, 0.0, 0.0]).collect();
            let mut u = [0.0; 3];
            u[axis] = speed;
            let positions = x.iter().map(|p| format!("[{:e}, 0, 0]", p[0])).collect::<Vec<_>>().join(", ");
            let velocities = vec![format!("[{:e}, {:e}, 0]", u[0], u[1]); n].join(", ");
            let s = Scene::parse(
                &format!(
                    "version = 1\n[domain]\nlo = [-1e-3, -1e-3, -1e-3]\nhi = [1e-3, 1e-3, 1e-3]\n{WATER}{}\
                     [[particles]]\nspecies = \"p\"\npositions = [{positions}]\nvelocities = [{velocities}]\n\
                     [forces.drag]\nlaw = \"rpy\"\nshielding = \"none\"\n[integration]\ndt = 1.0e-9\nend_time = 1.0e-8\n",
                    species("restitution = 0.5")
                ),
                "chain",
            )
            .unwrap();
            let mut sim = s.simulation(None);
            sim.initialise().unwrap();
            let expected = rpy_forces(&x, a, mu, u);
            for (i, (f, e)) in sim.state.fields.force.iter().zip(&expected).enumerate() {
                let e = Vec3::new(-e[0], -e[1], -e[2]);
                assert!((f - e).norm() <= 1e-9 * e.norm(), "n = {n} {label}, sphere {i}: {f:?} vs {e:?}");
            }
            let per_sphere = -sim.state.fields.force.iter().map(|f| f[axis]).sum::<f64>() / n as f64 / lone;
            if axis == 0 {
                print!("| {n} | {per_sphere:.4} |");
            } else {
                println!(" {per_sphere:.4} | {:.4} |", 1.0 / n as f64);
            }
            if n == 2 {
                let closed = if axis == 0 { 8.0 / 13.0 } else { 16.0 / 23.0 };
                assert!((per_sphere - closed).abs() < 1e-12, "n = 2 {label}: {per_sphere} vs {closed}");
            }
        }
    }
    // Stimson & Jeffery (1926) give 0.6452 each for two touching spheres along their line of
    // centres: RPY's 8/13 (asserted above) is 4.6 % below it, a property of the mobility.
}

/// The regularised RPY mobility is symmetric positive definite for random configurations with
/// overlaps and unequal radii (its Cholesky factor exists), and the drag it gives dissipates
/// energy: U · F_h < 0 for every non-zero velocity tried.
#[test]
fn rpy_mobility_is_positive_definite_with_overlaps_and_unequal_radii() {
    use magdem::core::forces::hydrodynamics::{mobility, Resistance};
    let value = |k: usize| (k as f64 * 0.618_033_988_75).fract();
    for trial in 0..20 {
        let n = 12 + trial;
        // Spheres of 1–3 µm packed into a 10 µm cube: many overlap, some lie inside others.
        let x: Vec<Vec3> = (0..n).map(|i| Vec3::from_fn(|c, _| 1e-5 * value(100 * trial + 3 * i + c))).collect();
        let radii: Vec<f64> = (0..n).map(|i| 1e-6 * (1.0 + 2.0 * value(7919 * trial + i))).collect();
        let m = mobility(&x, &radii, 1e-3, None);
        let asym = (0..3 * n)
            .flat_map(|r| (0..3 * n).map(move |c| (r, c)))
            .map(|(r, c)| (m[(r, c)] - m[(c, r)]).abs())
            .fold(0.0, f64::max);
        assert!(asym == 0.0, "trial {trial}: not symmetric ({asym:e})");
        let resistance = Resistance::new(&x, &radii, 1e-3, None).unwrap_or_else(|e| panic!("trial {trial}: {e}"));
        let u: Vec<Vec3> = (0..n).map(|i| Vec3::from_fn(|c, _| value(31 * trial + 3 * i + c) - 0.5)).collect();
        let power: f64 = resistance.drag(&u, |_| Vec3::zeros()).iter().zip(&u).map(|(f, v)| f.dot(v)).sum();
        assert!(power < 0.0, "trial {trial}: the drag does work {power:e}");
    }
}

/// RPY above a wall (Rotne–Prager–Blake, Swan & Brady 2007): a lone sphere's mobility along the
/// wall approaches the exact values (O'Neill 1964, tabulated by Goldman, Cox & Brenner 1967) as it
/// moves away from the wall — the far-field tensor misses lubrication near it — and two spheres
/// far apart along the wall couple as Blake's (1971) point force near a wall, written out here
/// (the image stokeslet, doublet and dipole, the dipole's derivative by finite differences): r⁻³
/// screening instead of the unbounded fluid's r⁻¹.
#[test]
fn rpy_above_a_wall_meets_the_exact_lone_sphere_drag_and_blakes_far_field() {
    use magdem::core::forces::hydrodynamics::mobility;
    use magdem::core::forces::wall_drag::PlaneWall;
    let (a, mu) = (1.0e-6_f64, 1.0e-3);
    let unit = 1.0 / (6.0 * PI * mu * a);
    let wall = PlaneWall { axis: 2, position: 0.0, side: 1.0, min_gap: 0.01 };
    // (h/a, exact f_∥, largest relative error allowed): the error shrinks like (a/h)⁴.
    for (h, exact, tolerance) in [(1.5431, 1.5675, 0.05), (2.3524, 1.3079, 0.01), (3.7622, 1.1738, 0.002)] {
        let m = mobility(&[Vec3::new(0.0, 0.0, h * a)], &[a], mu, Some(&wall));
        let f = unit / m[(0, 0)];
        assert!((f / exact - 1.0).abs() < tolerance, "h/a = {h}: f = {f} vs {exact}");
        assert!(m[(1, 1)] == m[(0, 0)] && m[(2, 2)] < m[(0, 0)], "h/a = {h}: normal motion is the more hindered");
    }
    // The same wall as the box's upper face (fluid below it) gives the mirrored mobility.
    let top = PlaneWall { axis: 2, position: 0.0, side: -1.0, min_gap: 0.01 };
    let (xi, xj) = (Vec3::new(0.0, 0.0, 3.0 * a), Vec3::new(4.0 * a, 1.0 * a, 2.0 * a));
    let low = mobility(&[xi, xj], &[a, a], mu, Some(&wall));
    let mirror = |v: Vec3| Vec3::new(v.x, v.y, -v.z);
    let high = mobility(&[mirror(xi), mirror(xj)], &[a, a], mu, Some(&top));
    for (r, c) in (0..6).flat_map(|r| (0..6).map(move |c| (r, c))) {
        let sign = if (r % 3 == 2) != (c % 3 == 2) { -1.0 } else { 1.0 };
        assert!((high[(r, c)] - sign * low[(r, c)]).abs() < 1e-12 * unit, "mirrored entry ({r}, {c})");
    }

    let stokeslet = |r: Vec3| -> Matrix3<f64> {
        let d = r.norm();
        (Matrix3::identity() / d + r * r.transpose() / d.powi(3)) / (8.0 * PI * mu)
    };
    // Blake: G_ij = S_ij(r) − S_ij(R) + 2h M_jk ∂_k [h R_i/R³ − (δ_i3/R + R_i R_3/R³)] / (8π μ),
    // r = x − y, R = x − ȳ (ȳ the image of the force point y at height h), M = diag(1, 1, −1).
    let blake = |x: Vec3, y: Vec3| -> Matrix3<f64> {
        let h = y.z;
        let image = Vec3::new(y.x, y.y, -h);
        let phi = |q: Vec3| -> Vec3 {
            let d = q.norm();
            Vec3::from_fn(|i, _| h * q[i] / d.powi(3) - (if i == 2 { 1.0 / d } else { 0.0 } + q[i] * q.z / d.powi(3)))
        };
        let big = x - image;
        let step = 1e-5 * big.norm();
        let mut grad = Matrix3::zeros(); // grad[(i, k)] = ∂φ_i/∂R_k
        for k in 0..3 {
            let mut e = Vec3::zeros();
            e[k] = step;
            let column = (phi(big + e) - phi(big - e)) / (2.0 * step);
            grad.set_column(k, &column);
        }
        let mirror = Matrix3::from_diagonal(&Vec3::new(1.0, 1.0, -1.0));
        stokeslet(x - y) - stokeslet(big) + grad * mirror * (2.0 * h / (8.0 * PI * mu))
    };
    for (xi, xj) in [
        (Vec3::new(0.0, 0.0, 20.0), Vec3::new(200.0, 0.0, 20.0)),
        (Vec3::new(0.0, 0.0, 15.0), Vec3::new(150.0, 80.0, 25.0)),
    ] {
        let (xi, xj) = (xi * a, xj * a);
        let m = mobility(&[xi, xj], &[a, a], mu, Some(&wall));
        let block = Matrix3::from_fn(|r, c| m[(r, 3 + c)]);
        let expected = blake(xi, xj);
        let error = (block - expected).norm() / expected.norm();
        assert!(error < 0.01, "{xi:?} {xj:?}: {block:?} vs Blake {expected:?} ({error:e})");
    }
    // Screening: twice as far apart along the wall, the coupling falls 8-fold (r⁻³), not 2-fold.
    let coupling = |rho: f64| {
        let m = mobility(&[Vec3::new(0.0, 0.0, 20.0 * a), Vec3::new(rho * a, 0.0, 20.0 * a)], &[a, a], mu, Some(&wall));
        m[(0, 3)]
    };
    let fall = coupling(200.0) / coupling(400.0);
    assert!((fall / 8.0 - 1.0).abs() < 0.1, "the coupling falls {fall}-fold from 200 a to 400 a");
}

/// The mobility above a wall is positive definite for spheres resting on it: straight chains of
/// n = 2 … 20 touching (and slightly overlapping, as Hertz contacts leave them) along the wall at
/// the smallest gap, and random configurations of spheres that overlap neither each other nor the
/// wall.
#[test]
fn rpy_above_a_wall_is_positive_definite_for_chains_on_it_and_random_spheres() {
    use magdem::core::forces::hydrodynamics::Resistance;
    use magdem::core::forces::wall_drag::PlaneWall;
    let (a, mu) = (2.75e-6_f64, 1.0e-3);
    let wall = PlaneWall { axis: 2, position: 0.0, side: 1.0, min_gap: 0.01 };
    for n in 2..=20 {
        for spacing in [2.0 * a, 2.0 * a * (1.0 - 1e-3)] {
            let x: Vec<Vec3> = (0..n).map(|i| Vec3::new(i as f64 * spacing, 0.0, a)).collect();
            Resistance::new(&x, &vec![a; n], mu, Some(&wall)).unwrap_or_else(|e| panic!("chain n = {n}: {e}"));
        }
    }
    // SplitMix64, to [0, 1).
    let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
    let mut value = move || {
        seed = seed.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = seed;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    for trial in 0..10 {
        let mut x: Vec<Vec3> = vec![];
        while x.len() < 25 {
            let c = Vec3::new(40.0 * value(), 40.0 * value(), 1.01 + 10.0 * value()) * a;
            if x.iter().all(|y| (y - c).norm() > 2.0 * a) {
                x.push(c);
            }
        }
        Resistance::new(&x, &vec![a; x.len()], mu, Some(&wall)).unwrap_or_else(|e| panic!("trial {trial}: {e}"));
    }
}

/// Two equal spheres translating together along and across their line of centres, apart or
/// touching: RPY gives each the drag 6π μ a U / (1 + 3a/(2r) − a³/r³) along the line and
/// 6π μ a U / (1 + 3a/(4r) + a³/(2r³)) across it (the closed forms of the far-field mobility).
#[test]
fn rpy_pair_drag_matches_its_closed_form_at_several_separations() {
    use magdem::core::forces::hydrodynamics::Resistance;
    let (a, mu, speed) = (5.5e-6_f64, 1.0e-3, 1.0e-5);
    for r_over_a in [2.0, 2.5, 4.0, 10.0] {
        let r = r_over_a * a;
        let x = [Vec3::zeros(), Vec3::new(r, 0.0, 0.0)];
        let resistance = Resistance::new(&x, &[a, a], mu, None).unwrap();
        for (axis, closed) in [
            (0, 1.0 / (1.0 + 1.5 / r_over_a - r_over_a.powi(-3))),
            (1, 1.0 / (1.0 + 0.75 / r_over_a + 0.5 * r_over_a.powi(-3))),
        ] {
            let mut u = Vec3::zeros();
            u[axis] = speed;
            let f = resistance.drag(&[u, u], |_| Vec3::zeros());
            for fi in &f {
                let ratio = -fi[axis] / (6.0 * PI * mu * a * speed);
                assert!((ratio - closed).abs() < 1e-12, "r = {r_over_a} a, axis {axis}: {ratio} vs {closed}");
            }
        }
    }
}

/// The RPY factor refreshed every K steps (`refactor_every`) lags the configuration by (K − 1)/2
/// steps on average, so its error is first order in K − 1. Two unequal dense spheres sediment side
/// by side 2.5 mean diameters apart (they separate vertically, so the coupling changes): after
/// 2 ms the position error against refactoring at every step grows as (K − 1) to within 15 %
/// from K = 10 to K = 40, and at K = 40 it is below the distance fallen times the configuration's
/// relative change over one refresh interval.
#[test]
fn rpy_refactorisation_every_k_steps_has_a_first_order_error_in_k() {
    let run = |k: u64| -> (Vec<Vec3>, f64) {
        let text = format!(
            "version = 1\n[domain]\nlo = [-1e-3, -1e-3, -1e-3]\nhi = [1e-3, 1e-3, 1e-3]\n{WATER}\
             [[species]]\nname = \"big\"\ndiameter = 10.0e-6\ndensity = 5000.0\nyoungs_modulus = 1.0e9\n\
             poisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\n\
             [[species]]\nname = \"small\"\ndiameter = 6.0e-6\ndensity = 5000.0\nyoungs_modulus = 1.0e9\n\
             poisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\n\
             [[particles]]\nspecies = \"big\"\npositions = [[0.0, 0.0, 0.0]]\n\
             [[particles]]\nspecies = \"small\"\npositions = [[2.0e-5, 0.0, 0.0]]\n\
             [forces.gravity]\n[forces.drag]\nlaw = \"rpy\"\nshielding = \"none\"\nrefactor_every = {k}\n\
             [integration]\ndt = 1.0e-7\nend_time = 2.0e-3\n[output]\ninterval = 2.0e-5\n"
        );
        let sim = Scene::parse(&text, "sediment").unwrap_or_else(|e| panic!("{e}")).run_to_end().unwrap();
        let fell = -sim.state.particles.position[0].z;
        (sim.state.particles.position.to_vec(), fell)
    };
    let (exact, fell) = run(1);
    let error = |k| run(k).0.iter().zip(&exact).map(|(x, e)| (x - e).norm()).fold(0.0, f64::max);
    let (e10, e40) = (error(10), error(40));
    let separation = exact[1].z - exact[0].z;
    println!("fell {fell:.3e} m, vertical separation {separation:.3e} m, error K=10 {e10:.3e} m, K=40 {e40:.3e} m");
    assert!(separation.abs() > 1e-3 * fell, "the spheres should fall at different speeds");
    let ratio = e40 / e10;
    assert!((ratio / (39.0 / 9.0) - 1.0).abs() < 0.15, "error ratio {ratio}, first order gives {}", 39.0 / 9.0);
    // Bound: the configuration's relative change over one refresh interval (40 steps of relative
    // motion against the 2e-5 m spacing) times the distance fallen.
    let relative_change = 40.0 * 1.0e-7 * separation.abs() / 2.0e-3 / 2.0e-5;
    assert!(e40 < relative_change * fell, "K = 40 error {e40:.3e} m, bound {:.3e} m", relative_change * fell);
}

/// The shielded Schiller–Naumann drag with its coefficients renewed every K steps
/// (`refactor_every`): two touching 100 µm spheres (ρ = 5000) sediment one above the other, the
/// upper one wholly in the lower one's shadow (A_eff = 0), pressed on it by contact. The pair's
/// terminal velocity solves 2 m g (1 − ρ_f/ρ) = 6π μ a V (1 + 0.15 Re^0.687), Re ≈ 3 (a steady
/// state: the held coefficients are renewed at it, so every K reaches the same V, to 1e-3 of it
/// after 9 relaxation times and to 1e-6 of each other). On the way the coefficient lags by
/// (K − 1)/2 steps on average: the position error against renewing at every step is first order
/// in K − 1, from K = 10 to K = 40 to within 15 %.
#[test]
fn drag_coefficients_renewed_every_k_steps_keep_the_terminal_velocity_with_a_first_order_lag() {
    let (a, rho, mu, rho_f) = (50.0e-6_f64, 5000.0, 1.0e-3, 1000.0);
    let run = |k: u64| -> (Vec<Vec3>, f64) {
        let text = format!(
            "version = 1\n[domain]\nlo = [-1e-2, -1e-2, -1e-2]\nhi = [1e-2, 1e-2, 1e-2]\n{WATER}\
             [[species]]\nname = \"p\"\ndiameter = {d:e}\ndensity = {rho}\nyoungs_modulus = 1.0e6\n\
             poisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\n\
             [[particles]]\nspecies = \"p\"\npositions = [[0.0, 0.0, 0.0], [0.0, 0.0, {d:e}]]\n\
             [forces.gravity]\n[forces.contact]\n[forces.drag]\nrefactor_every = {k}\n\
             [integration]\ndt = 5.0e-7\nend_time = 5.0e-2\n[output]\ninterval = 1.0e-3\n",
            d = 2.0 * a
        );
        let sim = Scene::parse(&text, "column").unwrap_or_else(|e| panic!("{e}")).run_to_end().unwrap();
        let v = sim.state.particles.velocity.iter().map(|v| -v.z).sum::<f64>() / 2.0;
        (sim.state.particles.position.to_vec(), v)
    };
    let weight = 2.0 * 4.0 / 3.0 * PI * a.powi(3) * (rho - rho_f) * 9.81;
    let mut terminal = weight / (6.0 * PI * mu * a);
    for _ in 0..100 {
        let re = rho_f * terminal * 2.0 * a / mu;
        terminal = weight / (6.0 * PI * mu * a * (1.0 + 0.15 * re.powf(0.687)));
    }
    let (exact, v1) = run(1);
    let ((x10, v10), (x40, v40)) = (run(10), run(40));
    let error = |x: &[Vec3]| x.iter().zip(&exact).map(|(x, e)| (x - e).norm()).fold(0.0, f64::max);
    let (e10, e40) = (error(&x10), error(&x40));
    println!("terminal {terminal:.6e} m/s; V(K=1) {v1:.6e}, V(K=10) {v10:.6e}, V(K=40) {v40:.6e}; error K=10 {e10:.3e} m, K=40 {e40:.3e} m");
    assert!((v1 / terminal - 1.0).abs() < 1e-3, "V(K=1) {v1} against the terminal {terminal}");
    for v in [v10, v40] {
        assert!((v / v1 - 1.0).abs() < 1e-6, "V {v} against V(K=1) {v1}");
    }
    assert!(e10 > 0.0, "renewing every 10 steps changed nothing: the coefficients were not held");
    let ratio = e40 / e10;
    assert!((ratio / (39.0 / 9.0) - 1.0).abs() < 0.15, "error ratio {ratio}, first order gives {}", 39.0 / 9.0);
}

/// A dense sphere sedimenting parallel to a plane wall (`forces.drag.wall`, face x-, gravity
/// along −z) reaches U∞ / f_∥ with f_∥ the exact values of O'Neill (1964) / Goldman, Cox & Brenner
/// (1967) at h/a = 1.1276 … 10.0677, to 1e-3 (the terminal velocity after 20 relaxation times).
/// Between the table's points, where the model interpolates, it is held to independent values:
/// Faxén's series at h/a = 3 (within 0.1 % of the exact values from h/a = 2.35 on) and Goldman,
/// Cox & Brenner's lubrication asymptote −(8/15) ln(δ/a) + 0.9588 at δ/a = 0.02. Settling with a
/// component towards the wall, the normal velocity keeps the free drag (no parallel factor); a
/// sphere closer than the scene's smallest gap (1e-2 a) moves as one at that gap.
#[test]
fn a_sphere_sedimenting_beside_a_wall_slows_by_the_published_factor() {
    let (a, rho, mu) = (5.0e-6_f64, 5000.0, 1.0e-3);
    let free = |g: f64| 2.0 / 9.0 * (rho - 1000.0) * g * a * a / mu;
    // (U_z/U∞, U_x/U∞,x) under gravity (g_x, 0, −9.81).
    let terminal = |h_over_a: f64, g_x: f64| -> (f64, f64) {
        let x = -1.0e-3 + h_over_a * a;
        let text = format!(
            "version = 1\n[domain]\nlo = [-1e-3, -1e-3, -1e-3]\nhi = [1e-3, 1e-3, 1e-3]\n{WATER}\
             [[species]]\nname = \"p\"\ndiameter = {:e}\ndensity = {rho}\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
             friction = 0.5\nrestitution = 0.5\n[[particles]]\nspecies = \"p\"\npositions = [[{x:e}, 0.0, 0.0]]\n\
             [forces.gravity]\ng = [{g_x:e}, 0, -9.81]\n[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[forces.drag.wall]\nface = \"x-\"\n\
             [integration]\ndt = 1.0e-7\nend_time = 6.0e-4\n",
            2.0 * a
        );
        let sim = Scene::parse(&text, "wall").unwrap_or_else(|e| panic!("{e}")).run_to_end().unwrap();
        let v = sim.state.particles.velocity[0];
        (-v.z / free(9.81), if g_x == 0.0 { 0.0 } else { v.x / free(g_x) })
    };
    for (h, f) in [(1.1276, 2.1514), (1.5431, 1.5675), (2.3524, 1.3079), (3.7622, 1.1738), (10.0677, 1.0591)] {
        let (ratio, _) = terminal(h, 0.0);
        println!("h/a = {h}: U/U∞ = {ratio:.5}, published 1/f = {:.5}", 1.0 / f);
        assert!((ratio * f - 1.0).abs() < 1e-3, "h/a = {h}: U/U∞ = {ratio}, published {}", 1.0 / f);
    }
    // Between the points: Faxén at h/a = 3 and the lubrication asymptote at δ/a = 0.02.
    let faxen = |l: f64| 1.0 / (1.0 - 9.0 / 16.0 * l + l.powi(3) / 8.0 - 45.0 / 256.0 * l.powi(4) - l.powi(5) / 16.0);
    let lubrication = |gap: f64| -8.0 / 15.0 * gap.ln() + 0.9588;
    for (h, f, tolerance) in [(3.0, faxen(1.0 / 3.0), 1e-2), (1.02, lubrication(0.02), 2e-2)] {
        let (ratio, _) = terminal(h, 0.0);
        let deviation = ratio * f - 1.0;
        println!(
            "h/a = {h} (between the table's points): U/U∞ = {ratio:.5}, independent 1/f = {:.5} ({deviation:.2e})",
            1.0 / f
        );
        // Measured: −4.2e-3 at h/a = 3, 7.3e-3 at 1.02 (the interpolation's error, docs/model.md
        // §7.2: about 1 %; the asymptote itself is a few 1e-3 below the exact value at 0.02).
        assert!(deviation.abs() < tolerance, "h/a = {h}: U/U∞ = {ratio} vs {}", 1.0 / f);
    }
    // Settling towards the wall as well: the normal component moves at the free speed.
    let (parallel, normal) = terminal(10.0677, -3.0);
    println!("towards the wall: U_z f_∥ − 1 = {:.2e}, U_x/U∞,x − 1 = {:.2e}", parallel * 1.0591 - 1.0, normal - 1.0);
    // Measured: −4.0e-10 (normal, 20 relaxation times), −5.4e-6 (parallel: 0.008 a closer).
    assert!((normal - 1.0).abs() < 4e-9, "normal velocity {normal} of the free one");
    assert!((parallel * 1.0591 - 1.0).abs() < 5e-5);
    assert_eq!(terminal(1.001, 0.0).0.to_bits(), terminal(1.01, 0.0).0.to_bits(), "the gap is not clamped at 1e-2 a");
}

/// A polydisperse scene of `count` particles (or a concentration) in a 2 mm box, diameters from
/// `size`, with contacts and a dipole term without induction (each moment is χ_eff V H).
fn polydisperse(size: &str, placement: &str) -> Scene {
    let text = format!(
        "version = 1\nseed = 3\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [2e-3, 2e-3, 2e-3]\n{WATER}[field]\nb0 = [0.1, 0.0, 0.0]\n\
         [[species]]\nname = \"p\"\ndiameter = 10.0e-6\ndensity = 1050.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
         friction = 0.5\nrestitution = 0.5\nsusceptibility = 1.0\nsize = {size}\n\
         [[particles]]\nspecies = \"p\"\n{placement}\n[forces.contact]\n[forces.dipole]\ninduction = \"none\"\ncutoff_diameters = 2.0\n\
         [integration]\ndt = 1.0e-8\nend_time = 1.0e-7\n"
    );
    Scene::parse(&text, "polydisperse").unwrap_or_else(|e| panic!("{e}"))
}

/// 10 000 particles with normal diameters (cv 0.1, the default truncation at ±3σ) reproduce the
/// mean to within 4 standard errors and the standard deviation of a normal truncated at ±3σ
/// (0.9866 σ) to 3 % (its standard error is 0.7 %); log-normal diameters (cv 0.2, truncation wide
/// enough to be negligible) their mean and standard deviation likewise. Each particle's mass is
/// ρ V, its inertia 2/5 m a², its moment χ_eff V H; a concentration gives that mass concentration
/// to 1.5 % (the sampling error of the mean volume is 0.3 %); and the stable-step estimate, taken
/// at the smallest diameter, is below the monodisperse one.
#[test]
fn a_polydisperse_placement_reproduces_its_distribution_and_masses() {
    let n = 10_000.0_f64;
    let d = 10.0e-6;
    let stats = |s: &Scene| {
        let x: Vec<f64> = s.initial.radius.iter().map(|a| 2.0 * a).collect();
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        let std = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (x.len() as f64 - 1.0)).sqrt();
        (mean, std)
    };
    let normal = polydisperse("{ law = \"normal\", cv = 0.1 }", "count = 10000");
    let (mean, std) = stats(&normal);
    assert_eq!(normal.initial.len(), 10_000);
    assert!((mean - d).abs() < 4.0 * 0.1 * d / n.sqrt(), "normal mean {mean:e}");
    assert!((std / (0.9866 * 0.1 * d) - 1.0).abs() < 0.03, "normal std {std:e}");
    assert!(normal.initial.radius.iter().all(|&a| (0.35 * d..=0.65 * d).contains(&a)), "truncation at ±3σ");

    let log = polydisperse(
        "{ law = \"log-normal\", cv = 0.2, min_diameter = 1.0e-6, max_diameter = 5.0e-5 }",
        "count = 10000",
    );
    let (mean, std) = stats(&log);
    assert!((mean - d).abs() < 4.0 * 0.2 * d / n.sqrt(), "log-normal mean {mean:e}");
    assert!((std / (0.2 * d) - 1.0).abs() < 0.05, "log-normal std {std:e}");

    let mut sim = normal.simulation(None);
    sim.initialise().unwrap();
    let (p, h) = (&sim.state.particles, 0.1 / magdem::core::forces::magnetisation::MU0);
    let chi_eff = 3.0 * 1.0 / (1.0 + 3.0);
    for i in 0..p.len() {
        let v = 4.0 / 3.0 * PI * p.radius[i].powi(3);
        assert!((p.mass[i] / (1050.0 * v) - 1.0).abs() < 1e-12);
        assert!((p.inertia[i] / (0.4 * p.mass[i] * p.radius[i].powi(2)) - 1.0).abs() < 1e-12);
        assert!((sim.state.fields.moment[i].x / (chi_eff * v * h) - 1.0).abs() < 1e-9, "moment {i}");
    }

    let by_mass = polydisperse("{ law = \"normal\", cv = 0.1 }", "concentration = 1.0");
    let total: f64 = by_mass.initial.mass.iter().sum();
    let c = total / 8e-9;
    assert!(by_mass.initial.len() > 5_000, "{} particles", by_mass.initial.len());
    assert!((c - 1.0).abs() < 0.015, "mass concentration {c} kg/m³ for 1.0");

    let mono = Scene::parse(
        &polydisperse("{ law = \"normal\", cv = 0.1 }", "count = 10")
            .text
            .replace("size = { law = \"normal\", cv = 0.1 }\n", ""),
        "mono",
    )
    .unwrap();
    assert!(
        normal.estimate.stable_dt < mono.estimate.stable_dt,
        "{} vs {}",
        normal.estimate.stable_dt,
        mono.estimate.stable_dt
    );
}

/// Every built term reports its scene key as its name (the phase timers and a stopped run's
/// message name the key a user wrote), and the moments term joins the terms that read moments.
#[test]
fn every_term_is_named_by_its_scene_key() {
    // The Stokes drag with the thermal forces, and the RPY drag (which has no thermal forces yet).
    for (law, thermal) in [("stokes", "[forces.thermal]\ntemperature = 300.0\n"), ("rpy", "")] {
        let text = format!(
            "version = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [1.0e-4, 1.0e-4, 1.0e-4]\n\
             [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n[field]\nb0 = [0.4, 0.0, 0.0]\n\
             gradient = [[1.4, 0.0, 0.0], [0.0, -0.7, 0.0], [0.0, 0.0, -0.7]]\n\
             [[species]]\nname = \"p\"\ndiameter = 11.0e-6\ndensity = 1087.0\nyoungs_modulus = 1.0e9\n\
             poisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\nrelative_permeability = 12.3\n\
             [[particles]]\nspecies = \"p\"\npositions = [[2.0e-5, 5.0e-5, 5.0e-5], [8.0e-5, 5.0e-5, 5.0e-5]]\n\
             [forces.dipole]\ninduction = \"exact\"\n[forces.gradient]\n[forces.drag]\nlaw = \"{law}\"\nshielding = \"none\"\n\
             [forces.gravity]\n[forces.contact]\n{thermal}[integration]\ndt = 1.0e-9\nend_time = 1.0e-6\n"
        );
        let scene = Scene::parse(&text, "every term").unwrap_or_else(|e| panic!("{e}\n{text}"));
        let mut keys: Vec<&str> = scene.spec.forces.names();
        keys.push("moments");
        keys.sort_unstable();
        let sim = scene.simulation(None);
        let mut names: Vec<&str> = sim.field.terms.iter().map(|t| t.name()).collect();
        names.sort_unstable();
        assert_eq!(names, keys, "drag law {law}");
    }
}

/// A box away from the origin on every axis: six spheres, each thrown at a different face, bounce
/// off it elastically (restitution 1, no drag), so each face's contact is found wherever the box
/// lies. Hertz's rebound is elastic: the speed comes back reversed, to the integrator's error.
#[test]
fn every_face_of_a_box_away_from_the_origin_rebounds_a_sphere() {
    let (lo, hi) = ([1.0e-4, -3.0e-4, 2.0e-4], [2.0e-4, -2.0e-4, 3.0e-4]);
    let (v, gap) = (0.05, 1.0e-8);
    let r = 5.5e-6;
    let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
    let mut positions = vec![];
    let mut velocities = vec![];
    for axis in 0..3 {
        for (side, wall) in [(-1.0, lo[axis]), (1.0, hi[axis])] {
            let mut x = centre;
            x[axis] = wall - side * (r + gap);
            // Spread the six spheres apart across the other axes so they never meet.
            let other = (axis + 1) % 3;
            x[other] += side * 2.5e-5 + (axis as f64 - 1.0) * 1.5e-5;
            let mut u = [0.0; 3];
            u[axis] = side * v;
            positions.push(format!("[{:e}, {:e}, {:e}]", x[0], x[1], x[2]));
            velocities.push(format!("[{:e}, {:e}, {:e}]", u[0], u[1], u[2]));
        }
    }
    let text = format!(
        "version = 1\n[domain]\nlo = [{:e}, {:e}, {:e}]\nhi = [{:e}, {:e}, {:e}]\n\
         [[species]]\nname = \"p\"\ndiameter = {:e}\ndensity = 1087.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
         friction = 0.5\nrestitution = 1.0\n[[particles]]\nspecies = \"p\"\npositions = [{}]\nvelocities = [{}]\n\
         [forces.contact]\n[integration]\ndt = 1.0e-10\nend_time = 2.0e-6\n",
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2],
        2.0 * r,
        positions.join(", "),
        velocities.join(", ")
    );
    let sim = Scene::parse(&text, "offset box").unwrap_or_else(|e| panic!("{e}\n{text}")).run_to_end().unwrap();
    let mut worst = 0.0_f64;
    for (k, w) in sim.state.particles.velocity.iter().enumerate() {
        let (axis, side) = (k / 2, if k % 2 == 0 { -1.0 } else { 1.0 });
        let back = -side * w[axis];
        worst = worst.max((back / v - 1.0).abs());
        // Velocity Verlet's energy error at dt = 1e-10 s over the contact: measured 2.8e-9.
        assert!(
            (back / v - 1.0).abs() < 1e-8,
            "sphere {k} at face {axis}{}: rebound {back:e} of {v:e}",
            ["-", "+"][k % 2]
        );
    }
    println!("largest rebound deviation over the six faces: {worst:.1e}");
}
