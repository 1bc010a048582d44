//! Invalid scenes are refused with a one-line message naming the key, the value and why; the CLI
//! exits with code 2.

mod common;

use magdem::scene::Scene;
use std::process::Command;

fn good() -> String {
    common::scene(
        r#"version = 1
[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0e-4, 1.0e-4, 1.0e-4]
"#,
        r#"[[particles]]
species = "p"
positions = [[2.0e-5, 5.0e-5, 5.0e-5], [8.0e-5, 5.0e-5, 5.0e-5]]
[forces.contact]
[forces.dipole]
induction = "exact"
[forces.drag]
[integration]
dt = 1.0e-8
end_time = 1.0e-6
"#,
    )
}

fn edit(from: &str, to: &str) -> String {
    assert!(good().contains(from), "fixture lacks {from:?}");
    good().replacen(from, to, 1)
}

#[test]
fn the_fixture_itself_is_valid() {
    Scene::parse(&good(), "good.toml").unwrap();
}

#[test]
fn bad_scenes_are_refused_with_a_message_naming_the_cause() {
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("missing key", edit("diameter = 11.0e-6\n", ""), &["missing field `diameter`", "[[species]]"]),
        ("negative diameter", edit("diameter = 11.0e-6", "diameter = -11.0e-6"), &["species[0].diameter = -0.000011", "positive"]),
        (
            "overlapping explicit particles",
            edit("[8.0e-5, 5.0e-5, 5.0e-5]", "[2.5e-5, 5.0e-5, 5.0e-5]"),
            &["particles[0].positions[1]", "overlaps particle 0"],
        ),
        ("particle outside the box", edit("[8.0e-5, 5.0e-5, 5.0e-5]", "[2.0e-4, 5.0e-5, 5.0e-5]"), &["particles[0].positions[1]", "x is outside the box"]),
        ("particle through a wall", edit("[8.0e-5, 5.0e-5, 5.0e-5]", "[9.8e-5, 5.0e-5, 5.0e-5]"), &["overlaps a wall normal to x"]),
        ("unknown force term", edit("[forces.drag]", "[forces.magnetic]"), &["unknown field `magnetic`", "expected one of"]),
        ("misspelt key", edit("friction = 0.5", "frictoin = 0.5"), &["unknown field `frictoin`"]),
        ("dt zero", edit("dt = 1.0e-8", "dt = 0.0"), &["integration.dt = 0", "positive"]),
        ("dt negative", edit("dt = 1.0e-8", "dt = -1.0e-8"), &["integration.dt = -0.00000001", "positive"]),
        (
            "impossible induction tolerance",
            edit("induction = \"exact\"", "induction = \"exact\"\ntolerance = 1.0e-20"),
            &["forces.dipole.tolerance = 0.00000000000000000001", "impossible mutual-induction tolerance"],
        ),
        ("unknown induction level", edit("induction = \"exact\"", "induction = \"full\""), &["unknown variant `full`", "none", "paper", "exact"]),
        ("unknown integrator", edit("dt = 1.0e-8", "scheme = \"rk45\"\ndt = 1.0e-8"), &["integration.scheme = rk45", "velocity-verlet"]),
        ("poisson out of range", edit("poisson_ratio = 0.5", "poisson_ratio = 0.7"), &["species[0].poisson_ratio = 0.7", "[0, 0.5]"]),
        ("restitution zero", edit("restitution = 0.5", "restitution = 0.0"), &["species[0].restitution = 0", "(0, 1]"]),
        ("permeability below one", edit("relative_permeability = 12.3", "relative_permeability = 0.5"), &["relative_permeability = 0.5", "≥ 1"]),
        ("unknown species", edit("species = \"p\"", "species = \"q\""), &["particles[0].species = q", "no such species"]),
        ("numbering explicit particles", edit("species = \"p\"\npositions", "species = \"p\"\norder = \"spatial\"\npositions"), &["particles[0].order = spatial", "explicit positions"]),
        ("unknown numbering", edit("species = \"p\"\npositions", "species = \"p\"\norder = \"hilbert\"\npositions"), &["unknown variant `hilbert`", "placement", "spatial"]),
        ("empty box", edit("hi = [1.0e-4, 1.0e-4, 1.0e-4]", "hi = [1.0e-4, 0.0, 1.0e-4]"), &["domain.hi", "must exceed domain.lo"]),
        ("wrong version", edit("version = 1", "version = 2"), &["version = 2", "scene version 1"]),
        (
            "adaptive step with the lagged induction",
            edit("induction = \"exact\"", "induction = \"paper\"").replace("dt = 1.0e-8", "scheme = \"adaptive-verlet\"\ndt = 1.0e-8"),
            &["integration.scheme = adaptive-verlet", "depend on the state alone"],
        ),
        ("adaptive tolerance", edit("dt = 1.0e-8", "scheme = \"adaptive-verlet\"\ntolerance = 2.0\ndt = 1.0e-8"), &["integration.tolerance = 2", "(0, 1)"]),
        (
            "overfull random placement",
            edit("positions = [[2.0e-5, 5.0e-5, 5.0e-5], [8.0e-5, 5.0e-5, 5.0e-5]]", "count = 2000"),
            &["particles[0].count = 2000", "could not place particle"],
        ),
        ("drag without fluid", edit("[fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n", ""), &["forces.drag", "[fluid]"]),
        (
            "periodic cut-off longer than half the box",
            edit("[domain]\n", "[domain]\nboundary = { x = \"periodic\", y = \"wall\", z = \"wall\" }\n")
                .replace("induction = \"exact\"", "induction = \"paper\""),
            &["forces.dipole.paper_radius_diameters = 15", "half the periodic box"],
        ),
        (
            "unstable dt refused",
            edit("dt = 1.0e-8", "dt = 1.0e-6").replace("end_time = 1.0e-6", "end_time = 1.0e-5\n[stability]\non_unstable_dt = \"refuse\""),
            &["integration.dt = 0.000001", "exceeds the estimated stable step", "Rayleigh time"],
        ),
    ];
    for (label, text, expected) in &cases {
        let err = Scene::parse(text, "bad.toml").expect_err(label).to_string();
        println!("{label}: {err}");
        assert!(!err.contains('\n'), "{label}: message is not one line: {err}");
        for fragment in *expected {
            assert!(err.contains(fragment), "{label}: {err:?} lacks {fragment:?}");
        }
    }
}

#[test]
fn cli_exits_with_code_2_and_one_line_on_a_bad_scene() {
    let work = tempfile::Builder::new().prefix("magdem-bad-").tempdir().unwrap();
    let dir = work.path();
    let path = dir.join("bad.toml");
    std::fs::write(&path, edit("dt = 1.0e-8", "dt = 0.0")).unwrap();
    let (scene, output) = (path.to_str().unwrap(), dir.join("x.h5"));
    let runs: [(&str, Vec<&str>); 2] =
        [("validate", vec!["validate", scene]), ("run", vec!["run", scene, "-q", "-o", output.to_str().unwrap()])];
    for (sub, args) in runs {
        let out = Command::new(env!("CARGO_BIN_EXE_magdem")).args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{sub}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{sub}: {stderr}");
        assert!(stderr.contains("integration.dt = 0"), "{sub}: {stderr}");
    }
}
