//! Independent references for the force terms (issue 65): every expectation here is a closed form
//! or a hand computation written out in the test, never one of the crate's own force functions.
//! Each tolerance sits within about 10× the deviation measured when the test was written; the
//! comment beside it states that deviation. The coverage table is docs/testing.md.

use magdem::core::simulation::Simulation;
use magdem::scene::Scene;
use nalgebra::Vector3;
use std::f64::consts::PI;

type V = Vector3<f64>;

/// μ0 written out (not the crate's constant).
const MU0: f64 = 4.0e-7 * PI;
const WATER: &str = "[fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n";

fn species(name: &str, diameter: f64, extra: &str) -> String {
    format!(
        "[[species]]\nname = \"{name}\"\ndiameter = {diameter:e}\ndensity = 1087.0\nyoungs_modulus = 1.0e9\n\
         poisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\n{extra}\n"
    )
}

fn particle(species: &str, x: V, v: V, w: V) -> String {
    format!(
        "[[particles]]\nspecies = \"{species}\"\npositions = [[{:e}, {:e}, {:e}]]\nvelocities = [[{:e}, {:e}, {:e}]]\n\
         angular_velocities = [[{:e}, {:e}, {:e}]]\n",
        x.x, x.y, x.z, v.x, v.y, v.z, w.x, w.y, w.z
    )
}

fn simulation(body: &str) -> (Scene, Simulation) {
    let text = format!("version = 1\n[domain]\nlo = [-4e-4, -4e-4, -4e-4]\nhi = [4e-4, 4e-4, 4e-4]\n{body}");
    let s = Scene::parse(&text, "independent").unwrap_or_else(|e| panic!("{e}\n{text}"));
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    (s, sim)
}

fn rel(a: &V, b: &V) -> f64 {
    (a - b).norm() / b.norm()
}

fn volume(a: f64) -> f64 {
    4.0 / 3.0 * PI * a.powi(3)
}

/// Clausius–Mossotti factor of a sphere of relative permeability μr.
fn chi_eff(mu_r: f64) -> f64 {
    3.0 * (mu_r - 1.0) / (mu_r + 2.0)
}

/// Force on dipole `mi` at x_i from dipole `mj` at x_j, r = x_i − x_j, written in r (not r̂):
/// F = 3μ0/(4π r⁵) [ (mi·r) mj + (mj·r) mi + (mi·mj) r − 5 (mi·r)(mj·r) r / r² ].
fn dipole_force(mi: &V, mj: &V, r: &V) -> V {
    let r2 = r.norm_squared();
    let (a, b) = (mi.dot(r), mj.dot(r));
    3.0 * MU0 / (4.0 * PI * r2 * r2 * r2.sqrt()) * (a * mj + b * mi + mi.dot(mj) * r - 5.0 * a * b / r2 * r)
}

/// B of a point dipole `m` at displacement r from it: μ0/(4π) [3 (m·r) r / r⁵ − m / r³].
fn dipole_b(m: &V, r: &V) -> V {
    let rn = r.norm();
    MU0 / (4.0 * PI) * (3.0 * m.dot(r) * r / rn.powi(5) - m / rn.powi(3))
}

/// −∇ of the energy U(x_i) = −m_i·B_j(x_i) by central differences (moments held).
fn energy_gradient_force(mi: &V, mj: &V, r: &V) -> V {
    let h = 1e-4 * r.norm();
    let u = |r: V| -mi.dot(&dipole_b(mj, &r));
    V::from_fn(|k, _| {
        let e = V::from_fn(|l, _| if l == k { h } else { 0.0 });
        -(u(r + e) - u(r - e)) / (2.0 * h)
    })
}

/// Two induced dipoles (`induction = "none"`: moments χ_eff V B0/μ0), unequal sizes, at a general
/// offset not along a general field: force on each against the closed form and against the
/// finite-difference gradient of −m_i·B_j.
#[test]
fn induced_dipoles_at_a_general_angle_match_the_closed_form_and_the_energy_gradient() {
    let b0 = V::new(0.3, -0.15, 0.2);
    let (x0, x1) = (V::zeros(), V::new(14.0e-6, 9.0e-6, -6.0e-6));
    let (a0, a1) = (5.5e-6, 4.0e-6);
    let (_, sim) = simulation(&format!(
        "{WATER}[field]\nb0 = [{}, {}, {}]\n{}{}{}{}[forces.dipole]\ninduction = \"none\"\n\
         [integration]\ndt = 1.0e-9\nend_time = 1.0e-6\n",
        b0.x,
        b0.y,
        b0.z,
        species("p", 2.0 * a0, "relative_permeability = 12.3"),
        species("q", 2.0 * a1, "relative_permeability = 5.0"),
        particle("p", x0, V::zeros(), V::zeros()),
        particle("q", x1, V::zeros(), V::zeros()),
    ));
    let m0 = chi_eff(12.3) * volume(a0) * b0 / MU0;
    let m1 = chi_eff(5.0) * volume(a1) * b0 / MU0;
    let (moment, force) = (&sim.state.fields.moment, &sim.state.fields.force);
    println!("moments: {:.2e} {:.2e}", rel(&moment[0], &m0), rel(&moment[1], &m1));
    // Round-off: measured 1.1e-16 and 0.
    assert!(rel(&moment[0], &m0) < 1e-15 && rel(&moment[1], &m1) < 1e-15, "{:?} {:?}", moment[0], m0);
    let r = x0 - x1;
    let closed = dipole_force(&m0, &m1, &r);
    let fd = energy_gradient_force(&m0, &m1, &r);
    let (e_closed, e_fd, e_sum) =
        (rel(&force[0], &closed), rel(&closed, &fd), (force[0] + force[1]).norm() / closed.norm());
    println!(
        "induced: F0 {:?}, closed form {:?}: {e_closed:.2e}; closed vs FD gradient {e_fd:.2e}; F0 + F1 {e_sum:.2e}",
        force[0], closed
    );
    // The force is not along r: the offset is off the field's line, so the test sees every term.
    assert!(closed.normalize().dot(&r.normalize()).abs() < 0.99);
    // Measured: 4.8e-17 (closed form, round-off), 1.8e-8 (finite differences at h = 1e-4 r:
    // truncation ~h²/r² and cancellation), 0 (Newton's third law).
    assert!(e_closed < 1e-15, "force {:?} vs closed form {closed:?}", force[0]);
    assert!(e_fd < 1e-7, "closed form {closed:?} vs energy gradient {fd:?}");
    assert!(e_sum < 1e-15);
}

/// Two permanent dipoles (susceptibility 0) at general orientations to each other, to the offset
/// and to an applied field: force against the closed form and the energy gradient, and the torque
/// T_i = m_i × (B0 + B_j(x_i)) against its closed form.
#[test]
fn permanent_dipoles_at_general_orientations_match_force_torque_and_energy_gradient() {
    let b0 = V::new(0.1, 0.05, -0.2);
    let (x0, x1) = (V::new(-3.0e-6, 2.0e-6, 1.0e-6), V::new(9.0e-6, -7.0e-6, 11.0e-6));
    let (p0, p1) = (V::new(2.0e-10, -1.0e-10, 3.0e-10), V::new(-1.5e-10, 4.0e-10, 0.5e-10));
    let (_, sim) = simulation(&format!(
        "{WATER}[field]\nb0 = [{}, {}, {}]\n{}{}{}{}[forces.dipole]\ninduction = \"none\"\n\
         [integration]\ndt = 1.0e-9\nend_time = 1.0e-6\n",
        b0.x,
        b0.y,
        b0.z,
        species(
            "p",
            11.0e-6,
            &format!("susceptibility = 0.0\npermanent_moment = [{:e}, {:e}, {:e}]", p0.x, p0.y, p0.z)
        ),
        species("q", 8.0e-6, &format!("susceptibility = 0.0\npermanent_moment = [{:e}, {:e}, {:e}]", p1.x, p1.y, p1.z)),
        particle("p", x0, V::zeros(), V::zeros()),
        particle("q", x1, V::zeros(), V::zeros()),
    ));
    let r = x0 - x1;
    let closed = dipole_force(&p0, &p1, &r);
    let fd = energy_gradient_force(&p0, &p1, &r);
    let f = &sim.state.fields.force;
    let t = &sim.state.fields.torque;
    let t0 = p0.cross(&(b0 + dipole_b(&p1, &r)));
    let t1 = p1.cross(&(b0 + dipole_b(&p0, &(-r))));
    let errors = [rel(&f[0], &closed), rel(&f[1], &(-closed)), rel(&closed, &fd), rel(&t[0], &t0), rel(&t[1], &t1)];
    println!("permanent: F0 {:?} closed {closed:?}; T0 {:?} closed {t0:?}; errors {errors:?}", f[0], t[0]);
    // Measured: 3.6e-16, 3.6e-16 (round-off), 2.0e-8 (finite differences), 0, 0.
    assert!(errors[0] < 3e-15 && errors[1] < 3e-15, "force {:?} vs {closed:?}", f[0]);
    assert!(errors[2] < 1e-7);
    assert!(errors[3] < 1e-15 && errors[4] < 1e-15, "torques {:?} {:?} vs {t0:?} {t1:?}", t[0], t[1]);
}

/// The paper's scheme (`induction = "paper"`): each evaluation sweeps once with the moments of the
/// previous evaluation, starting from zero. For two equal spheres the moments stay equal, and the
/// coupling T = (3 r̂r̂ᵀ − I)/(4π r³) has eigenvalue 2/(4π r³) along r̂ and −1/(4π r³) across it,
/// so after k sweeps with κ = χ_eff V/(4π r³):
///   m∥ = m0∥ Σ_{n≤k} (2κ)ⁿ,   m⊥ = m0⊥ Σ_{n≤k} (−κ)ⁿ,   m0 = χ_eff V B0/μ0.
/// The step is so short (1e-15 s) that the spheres do not move (by 1e-23 m in five steps).
#[test]
fn paper_induction_two_spheres_follow_the_closed_form_sweep_by_sweep() {
    let a: f64 = 5.5e-6;
    let b0 = V::new(0.4, 0.0, 0.0);
    // The line of centres at 50° to the field, 2.2 diameters apart.
    let (theta, r) = (50.0_f64.to_radians(), 2.2 * 2.0 * a);
    let rhat = V::new(theta.cos(), theta.sin(), 0.0);
    let (_, mut sim) = simulation(&format!(
        "{WATER}[field]\nb0 = [0.4, 0, 0]\n{}{}{}[forces.dipole]\ninduction = \"paper\"\n\
         [integration]\ndt = 1.0e-15\nend_time = 1.0e-12\n",
        species("p", 2.0 * a, "relative_permeability = 12.3"),
        particle("p", -0.5 * r * rhat, V::zeros(), V::zeros()),
        particle("p", 0.5 * r * rhat, V::zeros(), V::zeros()),
    ));
    let chi_v = chi_eff(12.3) * volume(a);
    let m0 = chi_v * b0 / MU0;
    let kappa = chi_v / (4.0 * PI * r.powi(3));
    let (m0_par, m0_perp) = (m0.dot(&rhat) * rhat, m0 - m0.dot(&rhat) * rhat);
    let mut worst = 0.0_f64;
    for k in 0..6 {
        if k > 0 {
            sim.step().unwrap();
        }
        let (s_par, s_perp): (f64, f64) =
            (0..=k).fold((0.0, 0.0), |(p, q), n| (p + (2.0 * kappa).powi(n), q + (-kappa).powi(n)));
        let expected = s_par * m0_par + s_perp * m0_perp;
        for i in 0..2 {
            let e = rel(&sim.state.fields.moment[i], &expected);
            println!("sweep {k}, sphere {i}: {:?} vs {expected:?} ({e:.2e})", sim.state.fields.moment[i]);
            worst = worst.max(e);
        }
    }
    // The sweeps change the moment by the first-order amount 2κ ≈ 0.077 along r̂: a lagged scheme
    // that skipped or doubled a sweep would miss by that much. Measured: 2.2e-16 (round-off).
    assert!(worst < 2e-15, "worst relative deviation {worst:e}");
}

/// Three spheres off a line, paper induction: five evaluations against a hand Jacobi iteration
/// m_i ← χ_eff V (H0 + Σ_j H_dip(m_j^prev)) written out here.
#[test]
fn paper_induction_three_spheres_match_a_hand_jacobi_iteration() {
    let a: f64 = 5.5e-6;
    let b0 = V::new(0.25, 0.1, -0.3);
    let x = [V::new(0.0, 0.0, 0.0), V::new(12.0e-6, 3.0e-6, 0.0), V::new(5.0e-6, 14.0e-6, 4.0e-6)];
    let (_, mut sim) = simulation(&format!(
        "{WATER}[field]\nb0 = [{}, {}, {}]\n{}{}{}{}[forces.dipole]\ninduction = \"paper\"\n\
         [integration]\ndt = 1.0e-15\nend_time = 1.0e-12\n",
        b0.x,
        b0.y,
        b0.z,
        species("p", 2.0 * a, "relative_permeability = 12.3"),
        particle("p", x[0], V::zeros(), V::zeros()),
        particle("p", x[1], V::zeros(), V::zeros()),
        particle("p", x[2], V::zeros(), V::zeros()),
    ));
    let chi_v = chi_eff(12.3) * volume(a);
    let h0 = b0 / MU0;
    let mut hand = [V::zeros(); 3];
    let mut worst = 0.0_f64;
    for k in 0..5 {
        if k > 0 {
            sim.step().unwrap();
        }
        let prev = hand;
        for i in 0..3 {
            let mut h = h0;
            for j in (0..3).filter(|&j| j != i) {
                h += dipole_b(&prev[j], &(x[i] - x[j])) / MU0;
            }
            hand[i] = chi_v * h;
        }
        for (m, expected) in sim.state.fields.moment.iter().zip(&hand) {
            worst = worst.max(rel(m, expected));
        }
    }
    println!("three spheres, five sweeps: worst relative deviation {worst:.2e}");
    // Measured: 1.4e-16 (round-off).
    assert!(worst < 2e-15, "worst relative deviation {worst:e}");
}

/// Spin decay under rotational drag: I dω/dt = −8π μ a³ ω, so ω = ω0 exp(−t/τ_r),
/// τ_r = I/(8π μ a³) = ρ a²/(15 μ) (= 2.19 µs for 11 µm in water). Velocity Verlet at τ_r/10⁴
/// (first order with velocity-dependent forces: error ≈ t dt/(2 τ_r²)) and exponential Verlet at
/// τ_r/5 (exact).
#[test]
fn spin_decays_with_the_rotational_stokes_time() {
    let (a, mu, rho): (f64, f64, f64) = (5.5e-6, 1.0e-3, 1087.0);
    let tau = rho * a * a / (15.0 * mu);
    let w0 = V::new(300.0, -200.0, 1000.0);
    for (scheme, steps_per_tau, tolerance) in [("velocity-verlet", 10_000u32, 5e-4), ("exponential-verlet", 5, 1e-14)] {
        let (_, mut sim) = simulation(&format!(
            "{WATER}{}{}[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\nrotational = true\n\
             [integration]\nscheme = \"{scheme}\"\ndt = {:e}\nend_time = 1.0e-3\n",
            species("p", 2.0 * a, "relative_permeability = 12.3"),
            particle("p", V::zeros(), V::zeros(), w0),
            tau / steps_per_tau as f64,
        ));
        for _ in 0..2 * steps_per_tau {
            sim.step().unwrap();
        }
        let t = sim.state.time;
        let expected = w0 * (-t / tau).exp();
        let e = rel(&sim.state.particles.angular_velocity[0], &expected);
        println!(
            "{scheme}: ω({t:.3e}) = {:?}, ω0 exp(−t/τ_r) = {expected:?} ({e:.2e})",
            sim.state.particles.angular_velocity[0]
        );
        // Measured at t = 2τ_r: velocity Verlet 1.00e-4 (= t dt/(2τ_r²): its half-step drag
        // decays as explicit Euler does, (1 − dt/τ_r)ⁿ), exponential Verlet 1.1e-15.
        assert!(e < tolerance, "{scheme}: {e:e}");
    }
}

/// A permanent moment tilted by θ0 = 0.02 rad from the field aligns as a damped pendulum:
/// I θ'' = −m B sin θ − 8π μ a³ θ', small-angle frequency ω0 = √(mB/I), damping rate
/// 1/(2τ_r), so the angle crosses zero every π/ω_d, ω_d = √(ω0² − 1/(4τ_r²)), and its extrema
/// shrink by exp(−π/(2 τ_r ω_d)) per half period.
#[test]
fn a_permanent_moment_aligns_as_a_damped_pendulum() {
    let (a, mu, rho): (f64, f64, f64) = (5.5e-6, 1.0e-3, 1087.0);
    let (m_mag, b): (f64, f64) = (5.0e-10, 2.0);
    let theta0: f64 = 0.02;
    let mass = rho * volume(a);
    let inertia = 0.4 * mass * a * a;
    let tau = inertia / (8.0 * PI * mu * a.powi(3));
    let w0 = (m_mag * b / inertia).sqrt();
    let wd = (w0 * w0 - 0.25 / (tau * tau)).sqrt();
    let period = 2.0 * PI / wd;
    let dt = period / 4000.0;
    let p = m_mag * V::new(theta0.cos(), theta0.sin(), 0.0);
    let (_, mut sim) = simulation(&format!(
        "{WATER}[field]\nb0 = [{b}, 0, 0]\n{}{}[forces.dipole]\ninduction = \"none\"\n\
         [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\nrotational = true\n\
         [integration]\ndt = {dt:e}\nend_time = 1.0\n",
        species("p", 2.0 * a, &format!("susceptibility = 0.0\npermanent_moment = [{:e}, {:e}, 0]", p.x, p.y)),
        particle("p", V::zeros(), V::zeros(), V::zeros()),
    ));
    let angle = |sim: &Simulation| {
        let m = sim.state.particles.permanent_moment[0];
        m.y.atan2(m.x)
    };
    let (mut crossings, mut extrema) = (Vec::new(), Vec::new());
    let (mut prev_t, mut prev) = (0.0, angle(&sim));
    let mut peak = prev.abs();
    while crossings.len() < 6 {
        sim.step().unwrap();
        let th = angle(&sim);
        if th.signum() != prev.signum() {
            crossings.push(prev_t + (sim.state.time - prev_t) * prev / (prev - th));
            extrema.push(peak);
            peak = 0.0;
        }
        peak = peak.max(th.abs());
        (prev_t, prev) = (sim.state.time, th);
    }
    let half_periods: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    let measured_half = (crossings[5] - crossings[1]) / 4.0;
    let e_freq = measured_half / (PI / wd) - 1.0;
    // Extrema between crossings 1..5: each ratio exp(−π/(2 τ_r ω_d)).
    let ratio = (extrema[5] / extrema[1]).powf(0.25);
    let expected_ratio = (-PI / (2.0 * tau * wd)).exp();
    let e_decay = ratio / expected_ratio - 1.0;
    println!(
        "ω0 τ_r = {:.2}; half periods {half_periods:?} (π/ω_d = {:.4e}): {e_freq:.2e}; decay per half period {ratio:.5} ({expected_ratio:.5}): {e_decay:.2e}",
        w0 * tau,
        PI / wd
    );
    // Measured (ω0 τ_r = 22.9, velocity Verlet at T/4000): frequency −1.6e-6 (a pendulum's
    // θ²/16 shift is below 2.5e-5 here), decay −3.3e-6.
    assert!(e_freq.abs() < 2e-5, "half period {measured_half:e} vs {:e}", PI / wd);
    assert!(e_decay.abs() < 3e-5, "decay per half period {ratio} vs {expected_ratio}");
}

/// A sphere released at rest in a uniformly moving fluid relaxes to it with the Stokes time
/// τ = m/(6π μ a): v = u_f (1 − e^(−t/τ)), x = u_f (t − τ (1 − e^(−t/τ))). Exponential Verlet
/// integrates the velocity exactly at any step; its drift, with the half-step velocity, is second
/// order (4.5e-3 at τ/4, 1.1e-3 at τ/8).
#[test]
fn a_sphere_in_a_moving_fluid_relaxes_to_its_velocity() {
    let (a, mu, rho): (f64, f64, f64) = (5.5e-6, 1.0e-3, 1087.0);
    let tau = rho * volume(a) / (6.0 * PI * mu * a);
    let uf = V::new(2.0e-4, -1.0e-4, 5.0e-5);
    for (scheme, steps_per_tau, tol_v, tol_x) in [
        ("velocity-verlet", 10_000u32, 2e-4, 2e-4),
        ("exponential-verlet", 4, 3e-15, 1e-2),
        ("exponential-verlet", 8, 3e-15, 2.5e-3),
    ] {
        let (_, mut sim) = simulation(&format!(
            "[fluid]\ndensity = 1000.0\nviscosity = {mu:e}\nvelocity = [{:e}, {:e}, {:e}]\n{}{}[forces.drag]\n\
             law = \"stokes\"\nshielding = \"none\"\n[integration]\nscheme = \"{scheme}\"\ndt = {:e}\nend_time = 1.0\n",
            uf.x,
            uf.y,
            uf.z,
            species("p", 2.0 * a, "relative_permeability = 12.3"),
            particle("p", V::zeros(), V::zeros(), V::zeros()),
            tau / steps_per_tau as f64
        ));
        for _ in 0..steps_per_tau {
            sim.step().unwrap();
        }
        let t = sim.state.time;
        let decay = (-t / tau).exp();
        let (v, x) = (sim.state.particles.velocity[0], sim.state.particles.position[0]);
        let (v_exp, x_exp) = (uf * (1.0 - decay), uf * (t - tau * (1.0 - decay)));
        let (ev, ex) = (rel(&v, &v_exp), rel(&x, &x_exp));
        println!("{scheme}: at t = τ = {t:.4e} s v {v:?} vs {v_exp:?} ({ev:.2e}); x {x:?} vs {x_exp:?} ({ex:.2e})");
        // Measured: velocity Verlet 2.9e-5 and 3.6e-5 (first order, half-step drag); exponential
        // Verlet at τ/4 2.1e-16 and 4.5e-3, at τ/8 4.3e-16 and 1.1e-3 (a quarter: second order).
        assert!(ev < tol_v && ex < tol_x, "{scheme}: {ev:e} {ex:e}");
    }
}

/// The paper's shielded area: sphere i moves at U at angle φ to the line of centres towards a
/// touching sphere j at rest ahead of it; j hides the lens of two circles of radius a whose
/// centres are s = 2a sin φ apart, E = 2a² acos(s/2a) − (s/2)√(4a² − s²), so
/// F_i = −6π μ a U f(Re) (1 − E/(π a²)) with Schiller–Naumann's f = 1 + 0.15 Re^0.687 of the full
/// diameter. j, at rest, feels nothing; with unequal radii the general lens formula is used.
#[test]
fn partial_shadows_reduce_the_drag_by_the_lens_area() {
    let (mu, rho_f): (f64, f64) = (1.0e-3, 1000.0);
    let lens = |ai: f64, aj: f64, s: f64| -> f64 {
        if s >= ai + aj {
            0.0
        } else if s <= (ai - aj).abs() {
            PI * ai.min(aj).powi(2)
        } else {
            let alpha = ((s * s + ai * ai - aj * aj) / (2.0 * s * ai)).acos();
            let beta = ((s * s + aj * aj - ai * ai) / (2.0 * s * aj)).acos();
            ai * ai * alpha + aj * aj * beta
                - 0.5 * ((-s + ai + aj) * (s + ai - aj) * (s - ai + aj) * (s + ai + aj)).sqrt()
        }
    };
    let mut worst = 0.0_f64;
    for (ai, aj) in [(5.5e-6, 5.5e-6), (5.5e-6, 3.5e-6)] {
        for phi_deg in [0.0, 20.0, 45.0, 60.0, 75.0, 85.0] {
            for (law, speed) in [("stokes", 1.0e-3), ("schiller-naumann", 0.05)] {
                let phi: f64 = f64::to_radians(phi_deg);
                let udir = V::new(1.0, 0.4, -0.3).normalize();
                // A unit vector across udir.
                let across = udir.cross(&V::new(0.0, 0.0, 1.0)).normalize();
                let r = ai + aj; // touching, gap 0
                let xj = r * (phi.cos() * udir + phi.sin() * across);
                let (_, sim) = simulation(&format!(
                    "[fluid]\ndensity = {rho_f}\nviscosity = {mu:e}\n{}{}{}{}[forces.drag]\nlaw = \"{law}\"\n\
                     shielding = \"paper\"\nrotational = false\n[integration]\ndt = 1.0e-9\nend_time = 1.0e-6\n",
                    species("i", 2.0 * ai, "relative_permeability = 12.3"),
                    species("j", 2.0 * aj, "relative_permeability = 12.3"),
                    particle("i", V::zeros(), speed * udir, V::zeros()),
                    particle("j", xj, V::zeros(), V::zeros()),
                ));
                // Lateral offset of j from i's path, from the geometry written above.
                let s = r * phi.sin();
                let hidden = if ai == aj {
                    let e_eq = 2.0 * ai * ai * (s / (2.0 * ai)).min(1.0).acos()
                        - 0.5 * s * (4.0 * ai * ai - s * s).max(0.0).sqrt();
                    // The equal-radius form and the general one agree.
                    assert!((e_eq - lens(ai, aj, s.max(1e-300))).abs() < 1e-12 * ai * ai, "{e_eq:e}");
                    e_eq
                } else {
                    lens(ai, aj, s)
                };
                let re = rho_f * speed * 2.0 * ai / mu;
                let f_re = if law == "stokes" { 1.0 } else { 1.0 + 0.15 * re.powf(0.687) };
                let expected = -6.0 * PI * mu * ai * speed * f_re * (1.0 - hidden / (PI * ai * ai)) * udir;
                let f = sim.state.fields.force[0];
                let e =
                    if expected.norm() > 0.0 { rel(&f, &expected) } else { f.norm() / (6.0 * PI * mu * ai * speed) };
                println!("a_j/a_i = {:.3}, φ = {phi_deg}°, {law} (Re {re:.3}): A_eff/πa² = {:.5}, F {:?} vs {expected:?} ({e:.2e})", aj / ai, 1.0 - hidden / (PI * ai * ai), f);
                assert!(sim.state.fields.force[1].norm() == 0.0, "j is at rest");
                worst = worst.max(e);
            }
        }
    }
    // Measured: 5.5e-16 (the expectation's acos and the code's differ in rounding only).
    assert!(worst < 5e-15, "worst relative deviation {worst:e}");
}

/// An oblique impact on a wall in gross sliding (Maw, Barber & Fawcett 1976): when the incidence
/// tangential speed exceeds what friction can stop, the contact slides throughout and the
/// tangential impulse is μ times the normal one. Elastic (e = 1, so the normal force never turns
/// tensile), v_t/v_n = 6 > 7μ(1 + e)/2: rebound v_n' = v_n, v_t' = v_t − 2μ v_n, spin
/// ω' = 5μ v_n/a (lever arm a; magdem's a − δ/2 lowers it by about δ_max/2a = 1.0e-4 at v_n = 0.01 m/s).
#[test]
fn oblique_impact_in_gross_sliding_has_tangential_impulse_mu_times_normal() {
    let (a, mu_f): (f64, f64) = (5.5e-6, 0.5);
    let mut worst = [0.0_f64; 3];
    for (vt, vn, dir_deg) in [(0.06, 0.01, 0.0), (0.03, 0.005, 35.0), (0.12, 0.01, 120.0)] {
        let dir: f64 = f64::to_radians(dir_deg);
        let t_hat = V::new(dir.cos(), dir.sin(), 0.0);
        let lo = -4e-4;
        let (_, mut sim) = simulation(&format!(
            "[[species]]\nname = \"p\"\ndiameter = {:e}\ndensity = 1087.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
             friction = {mu_f}\nrestitution = 1.0\nrelative_permeability = 12.3\n{}[forces.contact]\n\
             [integration]\ndt = 1.0e-11\nend_time = 1.0\n",
            2.0 * a,
            particle("p", V::new(0.0, 0.0, lo + a + 1.0e-10), vt * t_hat - V::new(0.0, 0.0, vn), V::zeros()),
        ));
        let mut touched = false;
        loop {
            sim.step().unwrap();
            let gap = sim.state.particles.position[0].z - lo - a;
            touched |= gap < 0.0;
            if touched && gap > 0.0 {
                break;
            }
        }
        let (v, w) = (sim.state.particles.velocity[0], sim.state.particles.angular_velocity[0]);
        let jn = v.z + vn; // per unit mass
        let jt = vt - v.dot(&t_hat);
        // Friction −F t̂ at the contact point −a ẑ: torque a F (ẑ × t̂), the rolling sense.
        let spin_axis = V::new(0.0, 0.0, 1.0).cross(&t_hat);
        let spin_expected = 5.0 * mu_f * vn / a;
        let errors = [
            (jt / jn / mu_f - 1.0).abs(),
            (v.dot(&t_hat) - (vt - 2.0 * mu_f * vn)).abs() / vt,
            (w.dot(&spin_axis) / spin_expected - 1.0).abs(),
        ];
        println!(
            "v_t {vt}, v_n {vn}, direction {dir_deg}°: J_t/(μ J_n) − 1 = {:.2e}; v_t' {:.6e} vs {:.6e}; v_n' {:.6e}; spin {w:?} vs {spin_expected:.5e}; errors {errors:?}",
            jt / jn / mu_f - 1.0,
            v.dot(&t_hat),
            vt - 2.0 * mu_f * vn,
            v.z
        );
        // Elastic rebound normal to the wall, and no spin or velocity out of the plane of incidence.
        assert!((v.z / vn - 1.0).abs() < 1e-3, "v_n' {} vs {vn}", v.z);
        assert!(w.dot(&t_hat).abs() < 1e-9 * spin_expected && w.z.abs() < 1e-9 * spin_expected);
        for k in 0..3 {
            worst[k] = worst[k].max(errors[k]);
        }
    }
    println!("worst: impulse ratio {:.2e}, tangential rebound {:.2e}, spin {:.2e}", worst[0], worst[1], worst[2]);
    // Measured: 1.6e-13 (impulse ratio), 1.3e-10 (tangential rebound), 8.6e-5 (spin, the lever arm).
    assert!(worst[0] < 1e-12 && worst[1] < 1e-9 && worst[2] < 5e-4, "{worst:?}");
}

/// The no-slip rebound of an elastic Hertz impact under the law's spring Ft = −kt(δ) s,
/// s = ∫ v_c dt: the contact-point velocity v_c leaves at ρ(χ) times its incident value.
/// With kt = 8G*√(R*δ), Sn = dFn/dδ = 2E*√(R*δ) and the effective mass m/(1 + 1/K), K = I/(m a²),
/// s'' = −2χ (Sn/m) s, χ = (1 − ν)/(2 − ν)(1 + 1/K) (Maw, Barber & Fawcett 1976's parameter).
/// In w = (δ/δ_max)^(5/2) this is Gauss's equation with c = 3/5, a + b = 1/10, ab = −3χ/5; the
/// solution starting as w^(2/5) continues through w = 1 by Abramowitz & Stegun 15.3.6, giving
/// ρ = 2P − 1, P = −π Γ(7/5) Γ(−2/5)/(Γ(a + 2/5) Γ(b + 2/5) Γ(a + 1/2) Γ(b + 1/2)).
fn sticking_rebound_ratio(chi: f64) -> f64 {
    use statrs::function::gamma::gamma;
    let root = (0.01 + 2.4 * chi).sqrt();
    let (a, b) = (0.5 * (0.1 + root), 0.5 * (0.1 - root));
    let p = -PI * gamma(1.4) * gamma(-0.4) / (gamma(a + 0.4) * gamma(b + 0.4) * gamma(a + 0.5) * gamma(b + 0.5));
    2.0 * p - 1.0
}

/// ρ(χ) against RK4 of δ'' = −δ^(3/2), s'' = −3χ δ^(1/2) s (units v0 = 1, (4/3)E*√R*/m = 1)
/// from δ = s = 0, δ' = s' = 1 to the exit δ = 0 (linearly interpolated).
fn sticking_rebound_ratio_rk4(chi: f64, h: f64) -> f64 {
    let f = |y: [f64; 4]| {
        let d = y[0].max(0.0);
        [y[1], -d.powf(1.5), y[3], -3.0 * chi * d.sqrt() * y[2]]
    };
    let mut y = [0.0, 1.0, 0.0, 1.0];
    loop {
        let add = |y: [f64; 4], k: [f64; 4], c: f64| std::array::from_fn(|i| y[i] + c * k[i]);
        let k1 = f(y);
        let k2 = f(add(y, k1, 0.5 * h));
        let k3 = f(add(y, k2, 0.5 * h));
        let k4 = f(add(y, k3, h));
        let next: [f64; 4] = std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
        if next[0] < 0.0 && next[1] < 0.0 {
            return y[3] + y[0] / (y[0] - next[0]) * (next[3] - y[3]);
        }
        y = next;
    }
}

/// An elastic sphere strikes a wall at a small tangential-to-normal speed ratio without spin
/// (Maw, Barber & Fawcett's sticking regime). The spring then never slips but at the very end,
/// where Fn → 0 faster than kt s. With μ = 50 that slip is negligible: the rebound contact-point
/// velocity v_x − a ω_y meets ρ(χ) v_t, and translation takes 1/(1 + 1/K) = 2/7 of the change.
/// With μ = 0.5 the final slip begins at δ ∝ ψ = κ v_t/(μ v_n) δ_max and changes the impulse by
/// ∝ ψ^(5/2), so the deviation from ρ, relative to v_t, falls as ψ^(3/2).
#[test]
fn oblique_impact_in_the_sticking_regime_follows_the_stiffness_ratio() {
    for chi in [7.0 / 6.0, 1.4, 1.65] {
        let (closed, rk4) = (sticking_rebound_ratio(chi), sticking_rebound_ratio_rk4(chi, 1e-4));
        println!("χ = {chi:.4}: ρ closed form {closed:.12}, RK4 {rk4:.12}");
        // Measured: up to 1.7e-7 at h = 1e-4, falling about as h^1.5 (√δ at the ends of the contact
        // limits RK4's order): 5.5e-8 at h = 5e-5.
        assert!((closed - rk4).abs() < 1e-6, "χ = {chi}: {closed} vs {rk4}");
    }
    let a: f64 = 5.5e-6;
    let vn = 1.0e-3;
    let rebound = |nu: f64, mu_f: f64, vt: f64| {
        // The wall at z = −a, so that coordinates stay small against their increments.
        let text = format!(
            "version = 1\n[domain]\nlo = [-4e-4, -4e-4, {lo:e}]\nhi = [4e-4, 4e-4, 4e-4]\n\
             [[species]]\nname = \"p\"\ndiameter = {:e}\ndensity = 1087.0\nyoungs_modulus = 1.0e9\npoisson_ratio = {nu}\n\
             friction = {mu_f}\nrestitution = 1.0\nrelative_permeability = 12.3\n{}[forces.contact]\n\
             [integration]\ndt = 1.0e-11\nend_time = 1.0\n",
            2.0 * a,
            particle("p", V::new(0.0, 0.0, 1.0e-11), V::new(vt, 0.0, -vn), V::zeros()),
            lo = -a,
        );
        let s = Scene::parse(&text, "sticking").unwrap_or_else(|e| panic!("{e}\n{text}"));
        let mut sim = s.simulation(None);
        sim.initialise().unwrap();
        let mut touched = false;
        loop {
            sim.step().unwrap();
            let gap = sim.state.particles.position[0].z;
            touched |= gap < 0.0;
            if touched && gap > 0.0 {
                break;
            }
        }
        let (v, w) = (sim.state.particles.velocity[0], sim.state.particles.angular_velocity[0]);
        (v.x, (v.x - a * w.y) / vt)
    };
    let mut worst = [0.0_f64; 2];
    for nu in [0.5, 0.4, 0.2] {
        let chi = (1.0 - nu) / (2.0 - nu) * 3.5;
        let rho = sticking_rebound_ratio(chi);
        let vt = 0.05 * vn;
        let (vx, ratio) = rebound(nu, 50.0, vt);
        let vx_expected = vt * (1.0 + 2.0 / 7.0 * (rho - 1.0));
        let errors = [(ratio - rho).abs(), (vx - vx_expected).abs() / vt];
        println!(
            "ν = {nu} (χ = {chi:.4}), μ = 50: v_c'/v_c {ratio:.9} vs ρ {rho:.9}; v_x' {vx:.9e} vs {vx_expected:.9e}; errors {:.2e}, {:.2e}",
            errors[0],
            errors[1]
        );
        worst = [worst[0].max(errors[0]), worst[1].max(errors[1])];
    }
    // Measured: 5.4e-5 (v_c') and 1.8e-5 (v_x'), from the lever arm a − δ/2 the closed form takes
    // as a: they scale as δ_max/a ∝ v_n^(4/5) (3.1e-4 at v_n = 0.01 m/s).
    assert!(worst[0] < 5e-4 && worst[1] < 2e-4, "{worst:?}");
    let nu = 0.5;
    let rho = sticking_rebound_ratio((1.0 - nu) / (2.0 - nu) * 3.5);
    let no_slip = rebound(nu, 50.0, 0.05 * vn).1;
    let mut points = Vec::new();
    for ratio in [0.02, 0.01, 0.005] {
        let (_, measured) = rebound(nu, 0.5, ratio * vn);
        let psi = 2.0 * (1.0 - nu) / (2.0 - nu) * ratio / 0.5;
        println!(
            "μ = 0.5, v_t/v_n = {ratio} (ψ = {psi:.4}): v_c'/v_c {measured:.9}, ρ {rho:.9}, end slip {:.3e}",
            measured - no_slip
        );
        points.push((psi.ln(), (measured - no_slip).abs().ln()));
    }
    let slope = (points[2].1 - points[0].1) / (points[2].0 - points[0].0);
    println!("end slip against ψ: exponent {slope:.3}");
    // Measured: 1.538 (3/2 as ψ → 0); the slip is 1.7e-4 of v_t at ψ = 0.0067.
    assert!((slope - 1.5).abs() < 0.15, "end slip exponent {slope}");
    assert!(points.windows(2).all(|p| p[1].1 < p[0].1), "the slip shrinks with ψ");
}
