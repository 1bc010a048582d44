//! Integrators against each other: multiple time stepping (RESPA) reduces to velocity Verlet at
//! K = 1 and converges at second order in the outer step K·dt; the paper's pipeline (magnetic
//! forces held over an explicit-Euler outer step, the rest sub-stepped) at first order. Their
//! closed-form references are in tests/independent_integrators.rs.

use magdem::core::integrators::{ExponentialVerletSpec, RespaSpec, Scheme, SubcycledEulerSpec, VelocityVerletSpec};
use magdem::scene::Scene;

/// Two dipoles 6 diameters apart closing under Stokes drag with exact induction, stopped before
/// they touch (contact at ~0.1 ms).
fn pair(scheme: &str, dt: f64, slow_every: u64) -> Scene {
    let scheme = match scheme {
        "respa" => Scheme::Respa(RespaSpec { slow_every }),
        "subcycled-euler" => Scheme::SubcycledEuler(SubcycledEulerSpec { slow_every }),
        "velocity-verlet" if slow_every == 1 => Scheme::VelocityVerlet(VelocityVerletSpec {}),
        "exponential-verlet" if slow_every == 1 => Scheme::ExponentialVerlet(ExponentialVerletSpec {}),
        other => panic!("no pair scene for {other} with slow_every = {slow_every}"),
    };
    Scene::parse(&magdem::verify::magnetic::pair_before_contact(scheme, dt), "pair").unwrap()
}

fn final_separation(scene: &Scene) -> f64 {
    let sim = scene.run_to_end().unwrap();
    let p = &sim.state.particles;
    (p.position[1] - p.position[0]).norm()
}

#[test]
fn respa_with_k_1_is_velocity_verlet() {
    let a = final_separation(&pair("velocity-verlet", 1e-9, 1));
    let b = final_separation(&pair("respa", 1e-9, 1));
    println!("separation: verlet {a:.15e}, respa(1) {b:.15e}");
    // Measured: 6.1e-15 relative (the split kicks round differently).
    assert!((a - b).abs() < 5e-14 * a);
}

#[test]
fn respa_converges_at_second_order_in_the_outer_step() {
    let reference = final_separation(&pair("velocity-verlet", 1e-9, 1));
    let errors: Vec<(u64, f64)> =
        [16, 32, 64].iter().map(|&k| (k, (final_separation(&pair("respa", 1e-9, k)) - reference).abs())).collect();
    println!("reference separation {reference:.9e} m; |error| by K: {errors:?}");
    // Measured ratios: 4.012, 4.003.
    for w in errors.windows(2) {
        let ratio = w[1].1 / w[0].1;
        assert!((ratio - 4.0).abs() < 0.1, "doubling K should multiply the error by 4: {errors:?}");
    }
}

#[test]
fn subcycled_euler_converges_at_first_order_in_the_outer_step() {
    let reference = final_separation(&pair("velocity-verlet", 1e-9, 1));
    let errors: Vec<(u64, f64)> = [16, 32, 64]
        .iter()
        .map(|&k| (k, (final_separation(&pair("subcycled-euler", 1e-9, k)) - reference).abs()))
        .collect();
    println!("reference separation {reference:.9e} m; |error| by K: {errors:?}");
    // Measured ratios: 1.995, 1.991.
    for w in errors.windows(2) {
        let ratio = w[1].1 / w[0].1;
        assert!((ratio - 2.0).abs() < 0.1, "doubling K should double the error: {errors:?}");
    }
}

#[test]
fn slow_every_must_divide_the_frames() {
    let text = magdem::verify::magnetic::PAIR.replace("dt = 1.0e-9", "scheme = \"respa\"\ndt = 1.0e-9\nslow_every = 7");
    let err = Scene::parse(&text, "pair").unwrap_err().to_string();
    assert!(err.contains("integration.slow_every = 7") && err.contains("must divide"), "{err}");
    let text = magdem::verify::magnetic::PAIR.replace("dt = 1.0e-9", "dt = 1.0e-9\nslow_every = 4");
    let err = Scene::parse(&text, "pair").unwrap_err().to_string();
    assert!(err.contains("respa"), "{err}");
}

/// One saturated particle under a gradient (terminal velocity V Ms G/(6π μ a)) at dt = 5 drag
/// relaxation times: the exponential integrator is exact for the linear drag and lands on the
/// terminal velocity; velocity Verlet is beyond its bound 2τ and blows up.
fn gradient_particle(scheme: &str, dt: f64) -> Scene {
    let text = format!(
        r#"version = 1
[domain]
lo = [-1e-3, -1e-3, -1e-3]
hi = [1e-3, 1e-3, 1e-3]
[fluid]
density = 1000.0
viscosity = 1.0e-3
[field]
b0 = [0.5, 0.0, 0.0]
gradient = [[1.4, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]
[[species]]
name = "p"
diameter = 11.0e-6
density = 1087.0
youngs_modulus = 1.0e9
poisson_ratio = 0.5
friction = 0.5
restitution = 0.5
relative_permeability = 12.3
saturation_magnetisation = 1.0e4
[[particles]]
species = "p"
positions = [[0.0, 0.0, 0.0]]
[forces.gradient]
[forces.drag]
law = "stokes"
shielding = "none"
[integration]
scheme = "{scheme}"
dt = {dt:e}
end_time = {end:e}
[output]
interval = {end:e}
"#,
        end = 200.0 * dt
    );
    Scene::parse(&text, "gradient").unwrap()
}

#[test]
fn exponential_verlet_is_exact_for_linear_drag_far_beyond_the_drag_time() {
    let tau =
        1087.0 * 4.0 / 3.0 * std::f64::consts::PI * 5.5e-6_f64.powi(3) / (6.0 * std::f64::consts::PI * 1.0e-3 * 5.5e-6);
    let dt = 5.0 * tau;
    let expected = 4.0 / 3.0 * std::f64::consts::PI * 5.5e-6_f64.powi(3) * 1.0e4 * 1.4
        / (6.0 * std::f64::consts::PI * 1.0e-3 * 5.5e-6);
    let scene = gradient_particle("exponential-verlet", dt);
    assert!(scene.estimate.stable_dt > dt, "{}", scene.estimate.summary(dt));
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    for _ in 0..scene.total_steps() {
        sim.step().unwrap();
    }
    let v = sim.state.particles.velocity[0].x;
    println!("dt = {dt:.3e} s (5 tau): exponential-verlet {v:.9e} m/s, expected {expected:.9e}");
    assert!((v / expected - 1.0).abs() < 1e-9);

    let verlet = gradient_particle("velocity-verlet", dt);
    assert!(verlet.estimate.stable_dt < dt);
    let mut sim = verlet.simulation(None);
    sim.initialise().unwrap();
    let blew_up = (0..verlet.total_steps()).any(|_| sim.step().is_err());
    assert!(blew_up, "Verlet at 5 tau should go unstable");
}

#[test]
fn exponential_verlet_converges_at_second_order() {
    let run = |scheme: &str, dt: f64| final_separation(&pair(scheme, dt, 1));
    let reference = run("exponential-verlet", 2.5e-10);
    let errors: Vec<(f64, f64)> =
        [4e-9, 8e-9, 16e-9].iter().map(|&dt| (dt, (run("exponential-verlet", dt) - reference).abs())).collect();
    println!("|error| by dt: {errors:?}");
    // Measured ratios: 4.012, 4.003.
    for w in errors.windows(2) {
        let ratio = w[1].1 / w[0].1;
        assert!((ratio - 4.0).abs() < 0.1, "halving dt should divide the error by 4: {errors:?}");
    }
}

/// The accuracy study's observed orders: with drag, velocity Verlet (half-step velocity in the
/// drag, as LAMMPS/LIGGGHTS) is first order and exponential Verlet second; explicit Euler first.
#[test]
fn accuracy_study_observes_the_orders() {
    let work = tempfile::Builder::new().prefix("magdem-accuracy-").tempdir().unwrap();
    let dir = work.path();
    let md = magdem::study::accuracy::study(dir).unwrap();
    let order = |section: &str, scheme: &str| -> String {
        let part = md.split("## ").find(|s| s.starts_with(section)).unwrap();
        let row = part.lines().find(|l| l.starts_with(&format!("| {scheme} |"))).unwrap();
        row.split('|').nth(2).unwrap().trim().to_string()
    };
    let num = |s: String| s.parse::<f64>().unwrap();
    assert!((num(order("Two dipoles", "velocity-verlet")) - 1.0).abs() < 0.1);
    assert!((num(order("Two dipoles", "exponential-verlet")) - 2.0).abs() < 0.1);
    assert!((num(order("Two dipoles", "explicit-euler")) - 1.0).abs() < 0.1);
    assert_eq!(order("Terminal velocity", "exponential-verlet"), "exact");
    assert!(num(order("Hertz impact", "velocity-verlet")) > 1.8);
    assert!(dir.join("convergence-dipoles.png").exists());
}

/// Two equal spheres meeting head-on at 0.1 m/s, elastic (contact 1.9e-7 s), integrated with
/// the scheme `scheme` (and `extra` integration keys) at a largest step of 1e-6 s; returns the
/// relative rebound speed, or None when the run stops.
fn elastic_impact_rebound(scheme: &str, extra: &str) -> Option<f64> {
    let a = 5.5e-6_f64;
    let text = format!(
        "version = 1\n[domain]\nlo = [-4e-4, -1e-4, -1e-4]\nhi = [4e-4, 1e-4, 1e-4]\n[[species]]\nname = \"p\"\ndiameter = 11.0e-6\n\
         density = 1087.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\nfriction = 0.5\nrestitution = 1.0\n\
         [[particles]]\nspecies = \"p\"\npositions = [[-{x:e}, 0, 0], [{x:e}, 0, 0]]\nvelocities = [[0.05, 0, 0], [-0.05, 0, 0]]\n\
         [forces.contact]\n[integration]\nscheme = \"{scheme}\"\n{extra}dt = 1.0e-6\nend_time = 2.0e-5\n[output]\ninterval = 1.0e-6\n",
        x = a + 2e-7
    );
    let scene = Scene::parse(&text, "impact").unwrap();
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    while sim.state.step < scene.total_steps() {
        sim.step().ok()?;
    }
    let p = &sim.state.particles;
    Some((p.velocity[1] - p.velocity[0]).x)
}

/// With a largest step five contact durations long, the controller shortens the substeps
/// through the impact: the elastic rebound speed is recovered, with an error that falls with the
/// tolerance. Plain Verlet at the same step loses the impact.
#[test]
fn adaptive_verlet_resolves_an_impact_and_its_error_follows_the_tolerance() {
    let errors: Vec<(f64, f64)> = [1e-5, 1e-7, 1e-9]
        .iter()
        .map(|&tol| {
            (
                tol,
                (elastic_impact_rebound("adaptive-verlet", &format!("tolerance = {tol:e}\n")).expect("stable") / 0.1
                    - 1.0)
                    .abs(),
            )
        })
        .collect();
    println!("relative rebound error by tolerance: {errors:?}");
    assert!(errors[0].1 < 1e-2, "{errors:?}");
    assert!(errors[1].1 < errors[0].1 / 5.0 && errors[2].1 < errors[1].1 / 5.0, "{errors:?}");
    let verlet = elastic_impact_rebound("velocity-verlet", "");
    println!("velocity Verlet at 1e-6 s: {verlet:?}");
    assert!(verlet.is_none_or(|v| (v / 0.1 - 1.0).abs() > 0.1), "Verlet at 1e-6 s: rebound {verlet:?}");
}
