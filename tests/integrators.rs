//! Integrators against each other: multiple time stepping (RESPA) reduces to velocity Verlet at
//! K = 1 and converges at second order in the outer step K·dt.

use magdem::scene::Scene;

/// Two dipoles 6 diameters apart closing under Stokes drag with exact induction, stopped before
/// they touch (contact at ~0.1 ms).
fn pair(scheme: &str, dt: f64, slow_every: u64) -> Scene {
    let text = magdem::verify::magnetic::PAIR
        .replace("[forces.contact]\n", "")
        .replace("dt = 1.0e-9", &format!("scheme = \"{scheme}\"\ndt = {dt:e}\nslow_every = {slow_every}"))
        .replace("end_time = 2.0e-4", "end_time = 9.6e-5")
        .replace("interval = 2.0e-6", "interval = 9.6e-5");
    Scene::parse(&text, "pair").unwrap()
}

fn final_separation(scene: &Scene) -> f64 {
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    while sim.state.step < scene.total_steps() {
        sim.step().unwrap();
    }
    let p = &sim.state.particles;
    (p.position[1] - p.position[0]).norm()
}

#[test]
fn respa_with_k_1_is_velocity_verlet() {
    let a = final_separation(&pair("velocity-verlet", 1e-9, 1));
    let b = final_separation(&pair("respa", 1e-9, 1));
    println!("separation: verlet {a:.15e}, respa(1) {b:.15e}");
    assert!((a - b).abs() < 1e-12 * a);
}

#[test]
fn respa_converges_at_second_order_in_the_outer_step() {
    let reference = final_separation(&pair("velocity-verlet", 1e-9, 1));
    let errors: Vec<(u64, f64)> = [16, 32, 64]
        .iter()
        .map(|&k| (k, (final_separation(&pair("respa", 1e-9, k)) - reference).abs()))
        .collect();
    println!("reference separation {reference:.9e} m; |error| by K: {errors:?}");
    for w in errors.windows(2) {
        let ratio = w[1].1 / w[0].1;
        assert!((3.0..5.5).contains(&ratio), "doubling K should multiply the error by ~4: {errors:?}");
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
