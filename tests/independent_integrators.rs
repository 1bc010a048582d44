//! Independent references for the integrators (issue 65): semi-implicit (symplectic) Euler's
//! discrete solution, order and stability bound, on problems whose answers are written out here.
//! Each tolerance sits within about 10× the deviation measured when the test was written.

use magdem::core::simulation::Simulation;
use magdem::scene::Scene;
use std::f64::consts::PI;

const A: f64 = 5.5e-6;
const RHO: f64 = 1087.0;

fn species() -> String {
    format!(
        "[[species]]\nname = \"p\"\ndiameter = {:e}\ndensity = {RHO}\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
         friction = 0.5\nrestitution = 1.0\nrelative_permeability = 12.3\n",
        2.0 * A
    )
}

fn simulation(body: &str) -> Simulation {
    let text = format!("version = 1\n[domain]\nlo = [-4e-4, -4e-4, -4e-4]\nhi = [4e-4, 4e-4, 4e-4]\n{body}");
    let s = Scene::parse(&text, "independent").unwrap_or_else(|e| panic!("{e}\n{text}"));
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    sim
}

fn mass() -> f64 {
    RHO * 4.0 / 3.0 * PI * A.powi(3)
}

/// A sphere at rest in fluid moving at u along x relaxes as v' = (u − v)/τ, τ = m/(6π μ a).
/// Semi-implicit Euler (v ← v + F(x, v) h/m, then x ← x + v h) gives exactly
/// v_n = u (1 − (1 − h/τ)ⁿ) and x_n = h Σ_{k=1..n} v_k, against the exact u (1 − e^(−t/τ)) at
/// first order: the fitted slope of log error against log h is 1.
fn relax(scheme: &str, steps_per_tau: u32) -> (f64, f64, f64) {
    let (mu, u) = (1.0e-3, 1.0e-3);
    let tau = mass() / (6.0 * PI * mu * A);
    let h = tau / steps_per_tau as f64;
    let mut sim = simulation(&format!(
        "[fluid]\ndensity = 1000.0\nviscosity = {mu:e}\nvelocity = [{u:e}, 0, 0]\n{}[[particles]]\nspecies = \"p\"\n\
         positions = [[0, 0, 0]]\n[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n\
         [integration]\nscheme = \"{scheme}\"\ndt = {h:e}\nend_time = 1.0\n",
        species()
    ));
    let (mut v_hand, mut x_hand, mut worst_hand) = (0.0_f64, 0.0_f64, 0.0_f64);
    for _ in 0..steps_per_tau {
        sim.step().unwrap();
        v_hand += (u - v_hand) * h / tau;
        x_hand += v_hand * h;
        let p = &sim.state.particles;
        worst_hand =
            worst_hand.max((p.velocity[0].x - v_hand).abs() / u).max((p.position[0].x - x_hand).abs() / (u * tau));
    }
    let exact = u * (1.0 - (-1.0_f64).exp());
    let closed_discrete = u * (1.0 - (1.0 - h / tau).powi(steps_per_tau as i32));
    let v = sim.state.particles.velocity[0].x;
    assert!((v - closed_discrete).abs() < 1e-12 * u, "{v:e} vs (1 − h/τ)ⁿ form {closed_discrete:e}");
    (h / tau, (v - exact).abs() / u, worst_hand)
}

#[test]
fn semi_implicit_euler_is_first_order_on_drag_relaxation() {
    let runs: Vec<(f64, f64, f64)> =
        [10u32, 20, 40, 80, 160].iter().map(|&n| relax("semi-implicit-euler", n)).collect();
    // Least-squares slope of ln(error) against ln(h).
    let pts: Vec<(f64, f64)> = runs.iter().map(|r| (r.0.ln(), r.1.ln())).collect();
    let n = pts.len() as f64;
    let (sx, sy) = (pts.iter().map(|p| p.0).sum::<f64>(), pts.iter().map(|p| p.1).sum::<f64>());
    let sxx = pts.iter().map(|p| p.0 * p.0).sum::<f64>();
    let sxy = pts.iter().map(|p| p.0 * p.1).sum::<f64>();
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let hand = runs.iter().map(|r| r.2).fold(0.0, f64::max);
    for r in &runs {
        println!("h/τ = {:.5}: |v − v_exact|/u = {:.4e}", r.0, r.1);
    }
    println!("fitted order {slope:.4}; worst deviation from the hand recurrence {hand:.2e}");
    // Measured: slope 1.0139 (the leading error e^(−1) h/(2τ) plus O(h²)); recurrence 5.4e-17.
    assert!((slope - 1.0).abs() < 0.05, "slope {slope}");
    assert!(hand < 1e-15, "semi-implicit Euler left its recurrence by {hand:e}");
    // The error constant: e^(−1)/2 per unit h/τ at t = τ.
    let c = runs[4].1 / runs[4].0;
    println!("error constant {c:.5} (e^(−1)/2 = {:.5})", 0.5 * (-1.0_f64).exp());
    // Measured: 0.18442 vs 0.18394, 2.6e-3 relative (the O(h²) term at h = τ/160).
    assert!((c / (0.5 * (-1.0_f64).exp()) - 1.0).abs() < 0.02);
}

/// A sphere resting on the floor under gravity on a Hooke contact (k, e = 1, no tangential force)
/// is a linear undamped oscillator about δ_eq = m g/k with ω = √(k/m): symplectic Euler is stable
/// for ω h < 2 and grows by |λ| = ((w² − 2) + w √(w² − 4))/2, w = ω h, per step beyond it.
/// A scene cannot start overlapping a wall, so the sphere first settles from touching onto δ_eq
/// under a damped contact (e = 0.5, velocity Verlet, 2 000 radians of ω t); that state is then
/// given the speed ω A (A = 10⁻⁴ δ_eq) and stepped with the undamped contact: it stays in contact.
fn oscillate(w: f64, steps: u32) -> Result<(f64, Vec<f64>), String> {
    let (k, g) = (1.0e-3, 9.81);
    let m = mass();
    let omega = (k / m).sqrt();
    let delta_eq = m * g / k;
    let amplitude = 1e-4 * delta_eq;
    let lo = -4e-4;
    let scene = |restitution: f64, scheme: &str, dt: f64| {
        format!(
            "{}[[particles]]\nspecies = \"p\"\npositions = [[0, 0, {:e}]]\n[forces.contact]\nnormal = \"hooke\"\nstiffness = {k:e}\n\
             tangential = \"none\"\n[forces.gravity]\ng = [0, 0, {}]\n[integration]\nscheme = \"{scheme}\"\ndt = {dt:e}\nend_time = 1.0\n",
            species().replace("restitution = 1.0", &format!("restitution = {restitution}")),
            lo + A + 1e-12,
            -g,
        )
    };
    let mut settle = simulation(&scene(0.5, "velocity-verlet", 0.1 / omega));
    for _ in 0..20_000 {
        settle.step().unwrap();
    }
    let mut state = settle.state.clone();
    let settled = (lo + A - state.particles.position[0].z - delta_eq) / amplitude;
    assert!(
        settled.abs() < 1e-6 && state.particles.velocity[0].norm() < 1e-6 * omega * amplitude,
        "not settled: {settled}"
    );
    state.particles.velocity[0].z = -omega * amplitude;
    let text = format!(
        "version = 1\n[domain]\nlo = [-4e-4, -4e-4, -4e-4]\nhi = [4e-4, 4e-4, 4e-4]\n{}",
        scene(1.0, "semi-implicit-euler", w / omega)
    );
    let s = Scene::parse(&text, "independent").unwrap();
    let mut sim = s.simulation(Some(state));
    sim.initialise().unwrap();
    let mut deviations = Vec::new();
    for _ in 0..steps {
        if let Err(e) = sim.step() {
            return Err(format!("{e}"));
        }
        let overlap = lo + A - sim.state.particles.position[0].z;
        deviations.push((overlap - delta_eq) / amplitude);
    }
    Ok((omega, deviations))
}

#[test]
fn semi_implicit_euler_is_stable_below_two_over_omega_on_a_harmonic_contact() {
    // Below the bound: bounded. Symplectic Euler keeps ω²z² + v² − hω² z v, which from z = 0,
    // v = ωA bounds the deviation by A/√(1 − (w/2)²) (7.09 A at w = 1.98) and reaches it.
    let (omega, stable) = oscillate(1.98, 4000).unwrap();
    let largest = stable.iter().fold(0.0_f64, |m, d| m.max(d.abs()));
    let bound = 1.0 / (1.0 - 0.99_f64.powi(2)).sqrt();
    println!("ω h = 1.98: largest deviation {largest:.4} A (bound {bound:.4} A), ω = {omega:.4e} rad/s");
    // Measured: 7.0888 against the bound 7.0888 (reached to 4 digits).
    assert!(largest <= bound * (1.0 + 1e-6) && largest > 0.99 * bound, "{largest}");

    // Above it: the deviation grows by |λ| per step, sign alternating.
    let w: f64 = 2.02;
    let lambda = ((w * w - 2.0) + w * (w * w - 4.0).sqrt()) / 2.0;
    let (_, unstable) = oscillate(w, 40).unwrap();
    // Steps 15 to 25, while the sphere is still in contact (|deviation| < δ_eq = 10⁴ A), where the
    // other eigenvalue's share (|λ|⁻²)¹⁵ has faded.
    assert!(unstable[25].abs() < 1e4, "left the contact: {}", unstable[25]);
    let growth = (unstable[25].abs() / unstable[15].abs()).powf(1.0 / 10.0);
    // In contact every step obeys the scheme's recurrence z_{n+1} = (2 − w²) z_n − z_{n−1}.
    let recurrence = unstable[..26]
        .windows(3)
        .map(|z| (z[2] - (2.0 - w * w) * z[1] + z[0]).abs() / z[1].abs().max(z[2].abs()).max(1.0))
        .fold(0.0, f64::max);
    println!(
        "ω h = {w}: growth per step {growth:.6} (|λ| = {lambda:.6}); deviation after 26 steps {:.3e} A; recurrence {recurrence:.2e}",
        unstable[25]
    );
    // Measured: growth 1.2e-5 relative, recurrence 2.6e-8 (the round-off of 4e-4 m positions in
    // units of A = 7.5e-13 m).
    assert!((growth / lambda - 1.0).abs() < 1e-4, "growth {growth} vs {lambda}");
    assert!(recurrence < 3e-7, "recurrence {recurrence:e}");
    assert!(unstable[25].abs() > 1e3);

    // The discrete frequency in the stable range: cos(Ω h) = 1 − w²/2. The deviation changes sign
    // on average every π/(Ω h) steps.
    let w: f64 = 0.3;
    let (_, d) = oscillate(w, 20_000).unwrap();
    let crossings = d.windows(2).filter(|p| p[0].signum() != p[1].signum()).count();
    let expected = 20_000.0 / (PI / (1.0 - w * w / 2.0).acos());
    println!("ω h = {w}: {crossings} sign changes in 20 000 steps (discrete frequency gives {expected:.1})");
    assert!((crossings as f64 - expected).abs() <= 2.0);
}
