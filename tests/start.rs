//! A scene that starts from a trajectory (`[start]`): the started run continues the run it
//! starts from, contact history included, and the deck writer writes the started positions.

mod common;

use magdem::core::state::State;
use magdem::reference::Engine;
use magdem::run::{run, RunOptions};
use magdem::scene::Scene;

/// An FCC block of touching 11 µm spheres, pre-compressed in its walled box and pushed sideways
/// by a body force of 3e3 weights, so that its springs build up and some contacts slide.
fn bed(placement: &str, end_time: f64) -> String {
    let (d, cells) = (11e-6, 3.0);
    let spacing = d * (1.0 - 1e-4);
    let edge = cells * std::f64::consts::SQRT_2 * spacing + d;
    common::scene(
        &format!("version = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{edge:e}, {edge:e}, {edge:e}]\n"),
        &format!(
            "{placement}[forces.contact]\nwalls = true\n[forces.gravity]\ng = [3.0e4, 1.0e4, -9.81]\n\
             [integration]\nscheme = \"velocity-verlet\"\ndt = 1.0e-8\nend_time = {end_time:e}\n[output]\ninterval = 1.0e-7\n"
        ),
    )
}

fn lattice() -> String {
    let spacing = 11e-6 * (1.0 - 1e-4);
    format!("[[particles]]\nspecies = \"p\"\nlattice = {{ kind = \"fcc\", spacing = {spacing:e} }}\n")
}

fn run_in_memory(scene: &Scene) -> State {
    let mut sim = scene.simulation(None);
    sim.initialise().unwrap();
    while sim.state.step < scene.total_steps() {
        sim.step().unwrap();
    }
    sim.state
}

/// Runs the bed to `end_time` into `dir`/first.h5, the trajectory the started scenes read.
fn first_run(dir: &std::path::Path, end_time: f64) -> State {
    let first = Scene::parse(&bed(&lattice(), end_time), "first").unwrap();
    run(&first, &dir.join("first.h5"), &RunOptions::default()).unwrap().simulation.state
}

/// Largest |Δx| over particles (m).
fn max_difference(a: &State, b: &State) -> f64 {
    a.particles.position.iter().zip(&b.particles.position).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max)
}

#[test]
fn a_started_run_takes_the_stored_state_and_its_springs() {
    let dir = tempfile::tempdir().unwrap();
    let (half, steps) = (3.0e-7, 30);
    let stored = first_run(dir.path(), half);
    let whole = run_in_memory(&Scene::parse(&bed(&lattice(), 2.0 * half), "whole").unwrap());

    let started =
        Scene::parse_in(&bed("[start]\ntrajectory = \"first.h5\"\n", half), "second half", dir.path()).unwrap();
    assert_eq!(started.total_steps(), steps);
    let (p, q) = (&started.initial, &stored.particles);
    assert_eq!((&p.position, &p.velocity, &p.angular_velocity), (&q.position, &q.velocity, &q.angular_velocity));
    assert_eq!((&p.radius, &p.mass, &p.inertia), (&q.radius, &q.mass, &q.inertia));
    assert_eq!(started.initial_history, stored.history, "the springs, bitwise");
    let springs = &started.initial_history;
    let coordination = 2.0 * springs.pairs.len() as f64 / p.len() as f64;
    assert!(coordination > 6.0, "coordination {coordination}: the bed should stay packed");
    assert!(!springs.walls.is_empty(), "the bed presses on its walls");
    let longest = springs.pairs.iter().map(|(_, s)| s.norm()).fold(0.0, f64::max);
    assert!(longest > 1e-10, "springs of {longest:e} m: the body force should shear the contacts");

    // The setup evaluation sees the stored full-step velocities; the stored run's last forces
    // saw the half-kicked ones, v − F dt / 2m. Given those, it gives the stored forces: springs
    // as stored (not advanced), the same damping. Round-off only: each spring is projected onto
    // its tangent plane once more.
    let dt = started.dt();
    let mut sim = started.simulation(None);
    let s = &mut sim.state;
    for i in 0..s.particles.len() {
        s.particles.velocity[i] -= stored.fields.force[i] * (0.5 * dt / q.mass[i]);
        s.particles.angular_velocity[i] -= stored.fields.torque[i] * (0.5 * dt / q.inertia[i]);
    }
    sim.initialise().unwrap();
    let largest = stored.fields.force.iter().map(|f| f.norm()).fold(0.0, f64::max);
    // Wall contacts are left out: the lattice's outer sites only just touch their walls, so
    // those springs sit at the Coulomb limit, where the re-evaluated stored spring may come out
    // one rounding below it and stick (gaining the tangential damping) instead of sliding.
    let off = (0..q.len())
        .filter(|&i| springs.walls.iter().all(|((j, _), _)| *j as usize != i))
        .map(|i| (sim.state.fields.force[i] - stored.fields.force[i]).norm())
        .fold(0.0, f64::max);
    assert!(off < 1e-9 * largest, "setup forces {off:e} N from the stored ones (largest {largest:e} N)");

    // So a started run departs from the uninterrupted one by its first step's forces (the half
    // kick's damping, the contacts at the limit), far less than by dropping the springs.
    let error = max_difference(&run_in_memory(&started), &whole);
    let mut forgetful = started.clone();
    forgetful.initial_history = Default::default();
    let without = max_difference(&run_in_memory(&forgetful), &whole);
    assert!(
        without > 50.0 * error,
        "{steps} steps: {error:e} m from the uninterrupted run, {without:e} m without springs"
    );
}

#[test]
fn a_start_is_part_of_the_scene_hash_and_its_species_must_exist_here() {
    let dir = tempfile::tempdir().unwrap();
    for (name, end) in [("a", 1.0e-7), ("b", 2.0e-7)] {
        let sub = dir.path().join(name);
        std::fs::create_dir(&sub).unwrap();
        run(&Scene::parse(&bed(&lattice(), end), name).unwrap(), &sub.join("run.h5"), &RunOptions::default()).unwrap();
    }
    let text = bed("[start]\ntrajectory = \"run.h5\"\n", 1.0e-7);
    let (a, b) = (
        Scene::parse_in(&text, "a", &dir.path().join("a")).unwrap(),
        Scene::parse_in(&text, "b", &dir.path().join("b")).unwrap(),
    );
    assert_ne!(a.hash, b.hash, "the same text started from different states is a different scene");
    assert_ne!(a.initial.position, b.initial.position);

    let renamed = text.replace("name = \"p\"", "name = \"bead\"");
    let err = Scene::parse_in(&renamed, "renamed", &dir.path().join("a")).unwrap_err().to_string();
    assert!(err.contains("start.trajectory = run.h5") && err.contains("species `p` is not defined here"), "{err}");
    let bigger = text.replace("diameter = 11.0e-6", "diameter = 12.0e-6");
    let err = Scene::parse_in(&bigger, "bigger", &dir.path().join("a")).unwrap_err().to_string();
    assert!(err.contains("has radius 5.5e-6 m"), "{err}");
}

#[test]
fn the_deck_writes_the_started_positions_and_says_the_springs_start_at_zero() {
    let dir = tempfile::tempdir().unwrap();
    first_run(dir.path(), 1.0e-7);
    let started = Scene::parse_in(&bed("[start]\ntrajectory = \"first.h5\"\n", 1.0e-7), "started", dir.path()).unwrap();
    let out = dir.path().join("deck");
    let files = magdem::reference::deck::write(Engine::LIGGGHTS, &started, &out).unwrap();
    let deck = std::fs::read_to_string(out.join(&files.input)).unwrap();
    assert!(deck.contains("tangential\n# springs it held start at zero"), "{deck}");
    let data = std::fs::read_to_string(out.join(&files.data)).unwrap();
    // Every started centre appears in the data file as written (%.17g round-trips).
    for x in started.initial.position.iter().take(20) {
        let found = data.lines().any(|line| {
            let v: Vec<f64> = line.split_whitespace().filter_map(|w| w.parse().ok()).collect();
            v.windows(3).any(|w| w == [x.x, x.y, x.z])
        });
        assert!(found, "position {x:?} missing from {}", files.data.display());
    }
}

/// `[start] order = "spatial"` numbers the stored particles along a Morton curve and renames their
/// springs with them: the same state (each particle found under its new number, each spring
/// under its renamed pair, negated where the pair's order flips), and a run from it follows the
/// run from the stored numbering to round-off, where dropping the springs would not.
#[test]
fn a_start_numbered_in_space_is_the_same_state_renamed() {
    let dir = tempfile::tempdir().unwrap();
    first_run(dir.path(), 3.0e-7);
    let start = |order: &str| {
        let text = bed(&format!("[start]\ntrajectory = \"first.h5\"\n{order}"), 3.0e-7);
        Scene::parse_in(&text, "started", dir.path()).unwrap()
    };
    let (kept, spatial) = (start(""), start("order = \"spatial\"\n"));
    assert_ne!(kept.hash, spatial.hash, "another numbering is another scene");
    let (p, q) = (&kept.initial, &spatial.initial);
    // new[i]: particle i's number in the spatial start, found by its position (all distinct).
    let new: Vec<usize> =
        p.position.iter().map(|x| q.position.iter().position(|y| y == x).expect("every particle kept")).collect();
    assert!(new.iter().enumerate().any(|(i, &k)| i != k), "an FCC block numbered row by row is renumbered");
    for (i, &k) in new.iter().enumerate() {
        assert_eq!(
            (p.velocity[i], p.angular_velocity[i], p.radius[i]),
            (q.velocity[k], q.angular_velocity[k], q.radius[k])
        );
    }
    let (a, b) = (&kept.initial_history, &spatial.initial_history);
    assert_eq!((a.pairs.len(), a.walls.len()), (b.pairs.len(), b.walls.len()));
    let mut flipped = 0;
    for ((i, j), spring) in &a.pairs {
        let (x, y) = (new[*i as usize] as u32, new[*j as usize] as u32);
        let key = (x.min(y), x.max(y));
        let (_, renamed) = b.pairs.iter().find(|(k, _)| *k == key).expect("every spring kept");
        assert_eq!(*renamed, if x < y { *spring } else { -*spring });
        flipped += (x > y) as usize;
    }
    assert!(
        flipped > 0 && b.pairs.iter().zip(b.pairs.iter().skip(1)).all(|(x, y)| x.0 < y.0),
        "flipped pairs, sorted again"
    );
    for ((i, face), spring) in &a.walls {
        let key = (new[*i as usize] as u32, *face);
        assert!(b.walls.iter().any(|(k, s)| *k == key && s == spring), "wall spring of {i} on face {face}");
    }
    assert!(b.walls.windows(2).all(|w| w[0].0 < w[1].0), "wall springs sorted again");

    // The same run, numbered two ways: apart by round-off, far less than without the springs.
    let (x, y) = (run_in_memory(&kept), run_in_memory(&spatial));
    let apart =
        (0..p.len()).map(|i| (x.particles.position[i] - y.particles.position[new[i]]).norm()).fold(0.0, f64::max);
    let mut forgetful = spatial.clone();
    forgetful.initial_history = Default::default();
    let z = run_in_memory(&forgetful);
    let without =
        (0..p.len()).map(|i| (x.particles.position[i] - z.particles.position[new[i]]).norm()).fold(0.0, f64::max);
    let moved = (0..p.len()).map(|i| (x.particles.position[i] - p.position[i]).norm()).fold(0.0, f64::max);
    // Summation order alone moves a position by a few of its last bits (edge × ε is 1e-20 m).
    let edge = kept.spec.domain.hi[0];
    assert!(moved > 1e-10, "the bed should move: {moved:e} m");
    assert!(apart < 1e3 * f64::EPSILON * edge, "{apart:e} m apart after moving up to {moved:e} m");
    assert!(without > 1e3 * apart.max(1e-25), "without springs {without:e} m against {apart:e} m");
}
