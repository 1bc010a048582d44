//! Superparamagnetic cores (`saturation_law = "langevin"`): an isolated particle's moment follows
//! the Langevin curve m = m_c L(m_c B/kT), and keys that contradict the law are refused.

use magdem::core::state::langevin;
use magdem::scene::Scene;
use std::f64::consts::PI;

const KB: f64 = 1.380_649e-23;

/// A 100 nm particle around one 20 nm magnetite core (Ms = 4.8e5 A/m) at 300 K, alone in a
/// uniform field b along x, its moment from the applied field (`induction = "none"`).
fn scene(b: f64, extra: &str) -> String {
    format!(
        r#"version = 1
[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0e-6, 1.0e-6, 1.0e-6]
[fluid]
density = 1000.0
viscosity = 1.0e-3
[field]
b0 = [{b:e}, 0.0, 0.0]
[[species]]
name = "core"
diameter = 1.0e-7
density = 2000.0
youngs_modulus = 1.0e9
poisson_ratio = 0.3
friction = 0.5
restitution = 0.5
saturation_magnetisation = 4.8e5
saturation_law = "langevin"
core_diameter = 2.0e-8
temperature = 300.0
{extra}[[particles]]
species = "core"
positions = [[5.0e-7, 5.0e-7, 5.0e-7]]
[forces.dipole]
induction = "none"
[integration]
dt = 1.0e-12
end_time = 1.0e-11
"#
    )
}

/// From ξ = 0.24 (linear) to ξ = 190 (saturated): the moment is m_c L(ξ), ξ = m_c B/kT, to
/// round-off (measured below 3e-16), along the field.
#[test]
fn an_isolated_core_follows_the_langevin_curve() {
    let m_c = 4.8e5 * PI / 6.0 * 2.0e-8f64.powi(3);
    for b in [5.0e-4, 2.0e-3, 1.0e-2, 0.4] {
        let scene = Scene::parse(&scene(b, ""), "langevin").unwrap_or_else(|e| panic!("{e}"));
        let mut sim = scene.simulation(None);
        sim.initialise().unwrap();
        let m = sim.state.fields.moment[0];
        let xi = m_c * b / (KB * 300.0);
        let expected = m_c * langevin(xi);
        let error = (m.x - expected).abs() / expected;
        println!("B = {b:e} T, ξ = {xi:.3}: m = {:.6e} against {expected:.6e} ({error:.1e})", m.x);
        assert!(error < 1e-14 && m.yz().norm() == 0.0, "ξ = {xi}: {m:?} against {expected:e}");
    }
    // L(ξ) against its closed form either side of the series' switch at 1e-2 (the closed form
    // loses about 1e-16/ξ² of L there to cancellation), and its small-ξ limit ξ/3.
    for xi in [9.99e-3, 1.001e-2, 0.5, 30.0] {
        let closed = 1.0 / f64::tanh(xi) - 1.0 / xi;
        assert!((langevin(xi) - closed).abs() <= 1e-9 * closed + 1e-16, "ξ = {xi}");
    }
    assert!((langevin(1e-8) - 1e-8 / 3.0).abs() < 1e-24);
}

/// A permeability beside the law, a core larger than the particle, a temperature against the
/// thermal term's, or a core diameter without the law: refused by key.
#[test]
fn keys_that_contradict_the_langevin_law_are_refused() {
    let cases = [
        (scene(0.1, "relative_permeability = 2.0\n"), "species[0].saturation_law = langevin", "leave out"),
        (
            scene(0.1, "").replace("core_diameter = 2.0e-8", "core_diameter = 2.0e-7"),
            "species[0].core_diameter",
            "exceeds",
        ),
        (scene(0.1, "").replace("temperature = 300.0\n", ""), "species[0].saturation_law = langevin", "temperature"),
        (
            scene(0.1, "").replace("saturation_law = \"langevin\"\n", "relative_permeability = 2.0\n"),
            "species[0].core_diameter",
            "applies to",
        ),
        (
            scene(0.1, "")
                + "[forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[forces.thermal]\ntemperature = 310.0\n",
            "species[0].temperature = 300",
            "forces.thermal.temperature = 310",
        ),
    ];
    for (text, key, why) in cases {
        let e = Scene::parse(&text, "bad").err().unwrap_or_else(|| panic!("accepted: {key}")).to_string();
        assert!(e.contains(key) && e.contains(why), "{key}: {e}");
    }
}
