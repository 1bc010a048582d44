//! Independent references for the integrators (issue 65): semi-implicit (symplectic) Euler's
//! discrete solution, order and stability bound; r-RESPA's and sub-cycled Euler's outer-step maps,
//! their traces, determinants and orders; adaptive Verlet against Hertz's closed forms. The
//! problems' answers are written out here. Each tolerance sits within about 10× the deviation
//! measured when the test was written.

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

/// A sphere on the floor (Hooke contact k, e = 1, under gravity g0: the fast forces) in a field
/// B = (B0, −G y, G z) (the slow force G m = κ z, κ = χ_eff V G²/μ0, pushing away from z = 0):
/// while it stays in contact every force is affine in z, so each integrator's step is an affine
/// map of (z, v). The floor is at z = −a, so the overlap is −z.
struct Linear {
    m: f64,
    k: f64,
    kappa: f64,
    g0: f64,
}

const MU0: f64 = 4.0e-7 * PI;
const GRADIENT: f64 = 500.0;

impl Linear {
    fn new() -> Self {
        let chi_eff = 3.0 * (12.3 - 1.0) / (12.3 + 2.0);
        let kappa = chi_eff * 4.0 / 3.0 * PI * A.powi(3) * GRADIENT * GRADIENT / MU0;
        Linear { m: mass(), k: 1.0e-3, kappa, g0: 100.0 }
    }
    fn omega_fast(&self) -> f64 {
        (self.k / self.m).sqrt()
    }
    /// The continuous system's equilibrium, −m g0/(k − κ).
    fn equilibrium(&self) -> f64 {
        -self.m * self.g0 / (self.k - self.kappa)
    }
    /// The continuous system's frequency, √((k − κ)/m).
    fn omega(&self) -> f64 {
        ((self.k - self.kappa) / self.m).sqrt()
    }
    /// (z, v) at the end of each of `calls` steps of `scheme` (an outer step each for the
    /// multiple-time-stepping schemes), from (z0, v0).
    fn run(&self, scheme: &str, dt: f64, slow_every: u64, calls: u64, z0: f64, v0: f64) -> Vec<(f64, f64)> {
        let end = dt * (slow_every * calls) as f64;
        let text = format!(
            "version = 1\n[domain]\nlo = [-4e-4, -4e-4, {lo:e}]\nhi = [4e-4, 4e-4, 4e-4]\n[field]\nb0 = [0.4, 0, 0]\n\
             gradient = [[0, 0, 0], [0, {g:e}, 0], [0, 0, {G:e}]]\n{}[[particles]]\nspecies = \"p\"\npositions = [[0, 0, 1e-9]]\n\
             [forces.contact]\nnormal = \"hooke\"\nstiffness = {k:e}\ntangential = \"none\"\n[forces.gradient]\n\
             [forces.gravity]\ng = [0, 0, {g0:e}]\n[integration]\nscheme = \"{scheme}\"\ndt = {dt:e}\nslow_every = {slow_every}\n\
             end_time = {end:e}\n[output]\ninterval = {end:e}\n",
            species(),
            lo = -A,
            g = -GRADIENT,
            G = GRADIENT,
            k = self.k,
            g0 = -self.g0,
        );
        let s = Scene::parse(&text, "linear").unwrap_or_else(|e| panic!("{e}\n{text}"));
        let mut sim = s.simulation(None);
        sim.state.particles.position.write()[0].z = z0;
        sim.state.particles.velocity[0].z = v0;
        sim.initialise().unwrap();
        (0..calls)
            .map(|n| {
                sim.step().unwrap();
                let t = dt * ((n + 1) * slow_every) as f64;
                assert!((sim.state.time - t).abs() < 1e-9 * t, "one call is one outer step");
                let p = &sim.state.particles;
                assert!(p.position[0].z < 0.0, "the sphere left the floor at call {n}: {:e}", p.position[0].z);
                (p.position[0].z, p.velocity[0].z)
            })
            .collect()
    }
    /// The exact solution of m z'' = −(k − κ) z − m g0 at time t.
    fn exact(&self, z0: f64, v0: f64, t: f64) -> (f64, f64) {
        let (ze, w) = (self.equilibrium(), self.omega());
        let (c, s) = ((w * t).cos(), (w * t).sin());
        (ze + (z0 - ze) * c + v0 / w * s, -(z0 - ze) * w * s + v0 * c)
    }
}

type M3 = nalgebra::Matrix3<f64>;

/// The affine maps on (z, v, 1): a kick by the force α z + β over h, and a drift over h.
fn kick(alpha: f64, beta: f64, h: f64, m: f64) -> M3 {
    M3::new(1.0, 0.0, 0.0, h * alpha / m, 1.0, h * beta / m, 0.0, 0.0, 1.0)
}

fn drift(h: f64) -> M3 {
    M3::new(1.0, h, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
}

/// Trace and determinant of the map's linear part, fitted from the positions it produced: the
/// differences d_n = z_{n+1} − z_n obey d_{n+1} = T d_n − D d_{n−1} (Cayley–Hamilton).
fn fitted_trace_and_determinant(z: &[f64]) -> (f64, f64) {
    let d: Vec<f64> = z.windows(2).map(|p| p[1] - p[0]).collect();
    let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for w in d.windows(3) {
        let (x1, x2, y) = (w[1], -w[0], w[2]);
        a11 += x1 * x1;
        a12 += x1 * x2;
        a22 += x2 * x2;
        b1 += x1 * y;
        b2 += x2 * y;
    }
    let det = a11 * a22 - a12 * a12;
    ((b1 * a22 - b2 * a12) / det, (a11 * b2 - a12 * b1) / det)
}

/// The fixed point of an affine map on (z, v, 1).
fn fixed_point(map: &M3) -> (f64, f64) {
    let linear = nalgebra::Matrix2::new(map[(0, 0)], map[(0, 1)], map[(1, 0)], map[(1, 1)]);
    let offset = nalgebra::Vector2::new(map[(0, 2)], map[(1, 2)]);
    let y = (nalgebra::Matrix2::identity() - linear).try_inverse().unwrap() * offset;
    (y.x, y.y)
}

/// Largest deviation of the run from the predictions y_{n+1} = M y_n, in units of the largest
/// predicted distance from the fixed point (velocities scaled by ω).
fn worst_against_map(map: &M3, z0: f64, v0: f64, run: &[(f64, f64)], omega: f64) -> f64 {
    let (zf, vf) = fixed_point(map);
    let mut y = nalgebra::Vector3::new(z0, v0, 1.0);
    let mut predicted = Vec::new();
    for _ in run {
        y = map * y;
        predicted.push((y.x, y.y));
    }
    let scale =
        predicted.iter().chain([(z0, v0)].iter()).map(|p| (p.0 - zf).hypot((p.1 - vf) / omega)).fold(0.0, f64::max);
    run.iter()
        .zip(&predicted)
        .map(|(r, p)| (r.0 - p.0).abs().max((r.1 - p.1).abs() / omega) / scale)
        .fold(0.0, f64::max)
}

/// The affine map of one Verlet step of the fast forces (contact and gravity) over dt.
fn fast_verlet(lin: &Linear, dt: f64) -> M3 {
    let half = kick(-lin.k, -lin.m * lin.g0, 0.5 * dt, lin.m);
    half * drift(dt) * half
}

/// Trace and determinant of a map's linear part.
fn trace_and_determinant(map: &M3) -> (f64, f64) {
    (map[(0, 0)] + map[(1, 1)], map[(0, 0)] * map[(1, 1)] - map[(0, 1)] * map[(1, 0)])
}

/// dt for which the fast Verlet step turns by φ: cos φ = 1 − (ω_f dt)²/2.
fn dt_for_phase(lin: &Linear, phi: f64) -> f64 {
    (2.0 * (1.0 - phi.cos())).sqrt() / lin.omega_fast()
}

/// r-RESPA's outer step: M = S(H/2) V^K S(H/2), S the slow kick, V the fast step, H = K dt.
fn respa_map(lin: &Linear, dt: f64, k_slow: u64) -> M3 {
    let slow = kick(lin.kappa, 0.0, 0.5 * k_slow as f64 * dt, lin.m);
    slow * fast_verlet(lin, dt).pow(k_slow as u32) * slow
}

/// Sub-cycled Euler's outer step: K sub-steps, each a Verlet step of the fast forces between two
/// half kicks of the slow force held at its value at the outer step's start. Written on
/// (z, v, z_held, 1), with z_held = z on entry.
fn subcycled_map(lin: &Linear, dt: f64, k_slow: u64) -> M3 {
    type M4 = nalgebra::Matrix4<f64>;
    let index = |i: usize| if i == 2 { 3 } else { i };
    let fast = fast_verlet(lin, dt);
    let lifted = M4::from_fn(|i, j| match (i, j) {
        (2, _) | (_, 2) => f64::from(i == j),
        _ => fast[(if i == 3 { 2 } else { i }, if j == 3 { 2 } else { j })],
    });
    let mut held = M4::identity();
    held[(1, 2)] = 0.5 * dt * lin.kappa / lin.m;
    let outer = (held * lifted * held).pow(k_slow as u32);
    M3::from_fn(|i, j| outer[(index(i), index(j))] + if j == 0 { outer[(index(i), 2)] } else { 0.0 })
}

/// r-RESPA (impulse form) on the linear problem. Its map has determinant 1 (symplectic) and
/// trace, with cos φ = 1 − (ω_f dt)²/2,
///   T = 2 cos Kφ + K (ω_f dt)² (κ/k) sin Kφ / sin φ,
/// so it is unstable where |T| > 2: just above Kφ = π (the impulse scheme's resonance), where
/// deviations grow by |λ| = (|T| + √(T² − 4))/2 per outer step. The run follows the map to
/// round-off, and the trace and determinant fitted from its positions are the closed forms.
#[test]
fn respa_follows_its_propagator_and_resonates_where_the_trace_says() {
    let lin = Linear::new();
    let ze = lin.equilibrium();
    let amplitude = 0.1 * ze.abs();
    println!("κ/k = {:.4}, equilibrium overlap {:.3e} m", lin.kappa / lin.k, -ze);
    // Largest deviations: map against its closed form, stable runs against the map, the unstable
    // run against it, fitted trace and determinant, growth per outer step.
    let mut worst = [0.0_f64; 5];
    for (k_slow, k_phi, calls, start) in [
        (10u64, 1.0, 300u64, amplitude),
        (4, 0.5, 300, amplitude),
        (10, PI - 0.4, 300, amplitude),
        (10, PI + 0.4, 20, 1e-5 * amplitude),
    ] {
        let phi = k_phi / k_slow as f64;
        let dt = dt_for_phase(&lin, phi);
        let map = respa_map(&lin, dt, k_slow);
        let trace = 2.0 * k_phi.cos()
            + k_slow as f64 * (lin.omega_fast() * dt).powi(2) * lin.kappa / lin.k * k_phi.sin() / phi.sin();
        let (t_map, d_map) = trace_and_determinant(&map);
        // From near the map's fixed point: the slow kicks move it off the equilibrium and, near
        // the resonance, drive a fast oscillation of about 0.6 δ_eq within the outer step.
        let fixed = fixed_point(&map);
        let (z0, v0) = (fixed.0 + start, fixed.1 + 0.5 * lin.omega() * start);
        let run = lin.run("respa", dt, k_slow, calls, z0, v0);
        let e_run = worst_against_map(&map, z0, v0, &run, lin.omega());
        let e_map = (t_map - trace).abs().max((d_map - 1.0).abs());
        let z: Vec<f64> = std::iter::once(z0).chain(run.iter().map(|r| r.0)).collect();
        let e_dynamics = if trace.abs() < 2.0 {
            let (t_fit, d_fit) = fitted_trace_and_determinant(&z);
            println!("K = {k_slow}, Kφ = {k_phi:.4}: T = {trace:.12}, fitted {t_fit:.12}; D fitted {d_fit:.12}");
            (t_fit - trace).abs().max((d_fit - 1.0).abs())
        } else {
            let lambda = (trace.abs() + (trace * trace - 4.0).sqrt()) / 2.0;
            let n = calls as usize;
            let growth = ((z[n] - fixed.0).abs() / (z[n - 10] - fixed.0).abs()).powf(0.1);
            println!(
                "K = {k_slow}, Kφ = {k_phi:.4}: T = {trace:.12}; growth per outer step {growth:.9} (|λ| = {lambda:.9})"
            );
            worst[2] = worst[2].max(e_run);
            worst[4] = worst[4].max((growth / lambda - 1.0).abs());
            0.0
        };
        println!(
            "  map against the closed form {e_map:.1e}; run against the map {e_run:.1e}; fitted T, D {e_dynamics:.1e}"
        );
        worst[0] = worst[0].max(e_map);
        worst[3] = worst[3].max(e_dynamics);
        if trace.abs() < 2.0 {
            worst[1] = worst[1].max(e_run);
        }
    }
    println!(
        "worst: map {:.1e}; runs against the map {:.1e} (stable), {:.1e} (unstable); fitted T and D {:.1e}; growth {:.1e}",
        worst[0], worst[1], worst[2], worst[3], worst[4]
    );
    // Measured: 1.0e-14 (the map's trace and determinant: round-off of the products); 2.8e-13
    // (stable runs); 7.3e-10 (the unstable run starts 1e-13 m off its fixed point, at positions
    // of 1e-7 m, whose round-off then grows with it); 1.2e-14; 1.1e-6 (growth over outer steps
    // 10 to 20, where the decaying eigenvalue's share is still λ⁻²⁰ ≈ 2e-5).
    assert!(worst[0] < 1e-13, "{worst:?}");
    assert!(worst[1] < 3e-12, "{worst:?}");
    assert!(worst[2] < 5e-9, "{worst:?}");
    assert!(worst[3] < 1e-13, "{worst:?}");
    assert!(worst[4] < 1e-5, "{worst:?}");
}

/// Sub-cycled Euler on the linear problem: its map has trace T = 2 cos Kφ + (κ/k)(1 − cos Kφ)
/// and determinant D = 1 − (κ/k)(1 − cos Kφ) < 1, so it damps the oscillation by √D per outer
/// step (about exp(−κ H t/(4m)): first order in H). The run follows the map to round-off, and
/// the trace and determinant fitted from its positions are the closed forms.
#[test]
fn subcycled_euler_follows_its_recurrence_and_decays_by_its_determinant() {
    let lin = Linear::new();
    let amplitude = 0.1 * lin.equilibrium().abs();
    let r = lin.kappa / lin.k;
    let mut worst = [0.0_f64; 3];
    for (k_slow, k_phi) in [(10u64, 1.0), (4, 0.5), (20, 2.5)] {
        let dt = dt_for_phase(&lin, k_phi / k_slow as f64);
        let map = subcycled_map(&lin, dt, k_slow);
        let (trace, determinant) = (2.0 * k_phi.cos() + r * (1.0 - k_phi.cos()), 1.0 - r * (1.0 - k_phi.cos()));
        let (t_map, d_map) = trace_and_determinant(&map);
        let (z0, v0) = (lin.equilibrium() + amplitude, 0.0);
        let run = lin.run("subcycled-euler", dt, k_slow, 300, z0, v0);
        let e_run = worst_against_map(&map, z0, v0, &run, lin.omega());
        let z: Vec<f64> = std::iter::once(z0).chain(run.iter().map(|r| r.0)).collect();
        let (t_fit, d_fit) = fitted_trace_and_determinant(&z);
        let e_map = (t_map - trace).abs().max((d_map - determinant).abs());
        let e_fit = (t_fit - trace).abs().max((d_fit - determinant).abs());
        println!(
            "K = {k_slow}, Kφ = {k_phi}: T = {trace:.12}, fitted {t_fit:.12}; D = {determinant:.12}, fitted {d_fit:.12}; \
             map against the closed form {e_map:.1e}; run against the map {e_run:.1e}"
        );
        worst = [worst[0].max(e_map), worst[1].max(e_run), worst[2].max(e_fit)];
    }
    println!("worst: map {:.1e}, run {:.1e}, fitted T and D {:.1e}", worst[0], worst[1], worst[2]);
    // Measured: 8.0e-15, 6.4e-14, 2.1e-14 (round-off).
    assert!(worst[0] < 1e-13, "{worst:?}");
    assert!(worst[1] < 5e-13, "{worst:?}");
    assert!(worst[2] < 2e-13, "{worst:?}");
}

/// Against the exact solution of the linear problem over two periods 2π/Ω, Ω² = (k − κ)/m, at
/// K = 4: r-RESPA's largest error falls as H², sub-cycled Euler's as H (fitted slopes).
#[test]
fn respa_is_second_order_and_subcycled_euler_first_order_in_the_outer_step() {
    let lin = Linear::new();
    let amplitude = 0.1 * lin.equilibrium().abs();
    let (z0, v0) = (lin.equilibrium() + amplitude, 0.0);
    let span = 4.0 * PI / lin.omega();
    let k_slow = 4u64;
    for (scheme, order) in [("respa", 2.0), ("subcycled-euler", 1.0)] {
        let points: Vec<(f64, f64)> = [160u64, 320, 640, 1280]
            .iter()
            .map(|&outer| {
                let h = span / outer as f64;
                let run = lin.run(scheme, h / k_slow as f64, k_slow, outer, z0, v0);
                let error = run
                    .iter()
                    .enumerate()
                    .map(|(n, &(z, _))| (z - lin.exact(z0, v0, (n + 1) as f64 * h).0).abs() / amplitude)
                    .fold(0.0, f64::max);
                println!(
                    "{scheme}: H = {h:.4e} s (Ω H = {:.4}): largest error {error:.4e} of the amplitude",
                    lin.omega() * h
                );
                (h.ln(), error.ln())
            })
            .collect();
        let n = points.len() as f64;
        let (sx, sy) = (points.iter().map(|p| p.0).sum::<f64>(), points.iter().map(|p| p.1).sum::<f64>());
        let sxx = points.iter().map(|p| p.0 * p.0).sum::<f64>();
        let sxy = points.iter().map(|p| p.0 * p.1).sum::<f64>();
        let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
        println!("{scheme}: fitted order {slope:.4}");
        // Measured: 1.9998 and 0.9752 (the damping's second-order term at Ω H = 0.08).
        assert!((slope - order).abs() < if order == 2.0 { 5e-3 } else { 5e-2 }, "{scheme}: order {slope}");
        if scheme == "subcycled-euler" {
            // Its leading error is the damping: the amplitude falls by κ H t/(4m) over t.
            let h = span / 1280.0;
            let constant = points[3].1.exp() / (lin.kappa * h * span / (4.0 * lin.m));
            println!("{scheme}: largest error / (κ H t/(4m)) = {constant:.5}");
            // Measured: 0.9925 (the rest is the O(H²) phase error).
            assert!((constant - 1.0).abs() < 0.03, "{constant}");
        }
    }
}

/// A sphere falls at v onto the floor (Hertz, e = 1, no gravity) under adaptive Verlet with the
/// largest step dt = t_c/2, the free flight timed so that calls end at the contact's start, its
/// peak and its end. Hertz's closed forms (R* = a, m* = m, E* = E/(2(1 − ν²))):
///   δ_max = (15 m v²/(16 E* √a))^(2/5),  t_c = 2.86827 (m²/(a E*² v))^(1/5).
/// The controller holds each substep's local error to `tolerance` × a, so the substeps are
/// ∝ tolerance^(1/3) and the global error ∝ tolerance^(2/3). Returns the errors relative to
/// δ_max of the overlap at the peak and at the end, and of the rebound speed relative to v.
fn adaptive_hertz_impact(tolerance: f64) -> [f64; 3] {
    let v = 0.1;
    let e_star = 1.0e9 / (2.0 * (1.0 - 0.25));
    let m = mass();
    let delta_max = (15.0 * m * v * v / (16.0 * e_star * A.sqrt())).powf(0.4);
    let t_c = 2.868_265_699_195_33 * (m * m / (A * e_star * e_star * v)).powf(0.2);
    let dt = 0.5 * t_c;
    let text = format!(
        "version = 1\n[domain]\nlo = [-4e-4, -4e-4, {lo:e}]\nhi = [4e-4, 4e-4, 4e-4]\n{}[[particles]]\nspecies = \"p\"\n\
         positions = [[0, 0, {z:e}]]\nvelocities = [[0, 0, {vz:e}]]\n[forces.contact]\ntangential = \"none\"\n\
         [integration]\nscheme = \"adaptive-verlet\"\ntolerance = {tolerance:e}\ndt = {dt:e}\nend_time = {end:e}\n",
        species(),
        lo = -A,
        z = 2.0 * dt * v,
        vz = -v,
        end = 6.0 * dt,
    );
    let s = Scene::parse(&text, "adaptive").unwrap_or_else(|e| panic!("{e}\n{text}"));
    let mut sim = s.simulation(None);
    sim.initialise().unwrap();
    let mut overlaps = Vec::new();
    for _ in 0..6 {
        sim.step().unwrap();
        overlaps.push(-sim.state.particles.position[0].z);
    }
    let rebound = sim.state.particles.velocity[0].z;
    println!(
        "tolerance {tolerance:.0e}: overlap at the peak {:.9e} m (δ_max {delta_max:.9e} m), at the end {:.2e} m; rebound {rebound:.12} m/s",
        overlaps[2], overlaps[3]
    );
    [(overlaps[2] / delta_max - 1.0).abs(), overlaps[3].abs() / delta_max, (rebound / v - 1.0).abs()]
}

#[test]
fn adaptive_verlet_meets_hertz_closed_forms_with_errors_set_by_its_tolerance() {
    let tolerances = [1e-6, 1e-7, 1e-8, 1e-9];
    let errors: Vec<[f64; 3]> = tolerances.iter().map(|&t| adaptive_hertz_impact(t)).collect();
    for (t, e) in tolerances.iter().zip(&errors) {
        println!(
            "tolerance {t:.0e}: relative errors: peak overlap {:.3e}, overlap at t_c {:.3e}, rebound {:.3e}",
            e[0], e[1], e[2]
        );
    }
    // Least-squares slopes of ln(error) against ln(tolerance).
    let slope = |k: usize| {
        let pts: Vec<(f64, f64)> = tolerances.iter().zip(&errors).map(|(t, e)| (t.ln(), e[k].ln())).collect();
        let n = pts.len() as f64;
        let (sx, sy) = (pts.iter().map(|p| p.0).sum::<f64>(), pts.iter().map(|p| p.1).sum::<f64>());
        let sxx = pts.iter().map(|p| p.0 * p.0).sum::<f64>();
        let sxy = pts.iter().map(|p| p.0 * p.1).sum::<f64>();
        (n * sxy - sx * sy) / (n * sxx - sx * sx)
    };
    let slopes = [slope(0), slope(1), slope(2)];
    println!(
        "fitted exponents of the tolerance: peak {:.3}, overlap at t_c {:.3}, rebound {:.3}",
        slopes[0], slopes[1], slopes[2]
    );
    // Measured at 1e-9: 4.2e-6 (peak), 8.1e-6 (overlap at t_c, relative to δ_max), 6.1e-6
    // (rebound).
    let last = errors[3];
    assert!(last[0] < 4e-5 && last[1] < 8e-5 && last[2] < 6e-5, "{last:?}");
    // Measured: 0.712, 0.804, 0.699 against 2/3 (the error-per-step law as the tolerance falls; the
    // step-doubling estimate's own error steepens it at the larger tolerances).
    assert!((slopes[0] - 2.0 / 3.0).abs() < 0.1 && (slopes[2] - 2.0 / 3.0).abs() < 0.1, "{slopes:?}");
    assert!((slopes[1] - 2.0 / 3.0).abs() < 0.25, "{slopes:?}");
}
