//! Results do not depend on the thread count, and the parallel algorithms (used from 4096
//! particles on) compute the same forces as a direct sum.

mod common;

use magdem::core::forces::dipole::dipole_pair_force;
use magdem::core::parallel::MIN_PARALLEL_LEN;
use magdem::core::Vec3;
use magdem::scene::Scene;

/// `n` particles at the case-1 concentration of 4.5 mg/ml (box scaled from the paper's 307),
/// walls, contact, drag with shielding, gravity, and the dipole term with `dipole` settings.
fn crowd(n: usize, dipole: &str, steps: u64) -> Scene {
    crowd_in(n, dipole, steps, "placement", "")
}

/// [`crowd`] with the particles numbered by `order` (`placement` or `spatial`) and the domain's
/// `boundary` line (empty: walls all round).
fn crowd_in(n: usize, dipole: &str, steps: u64, order: &str, boundary: &str) -> Scene {
    let scale = (n as f64 / 307.0).cbrt();
    let (l, h) = (3.96e-4 * scale, 3.3e-4 * scale);
    let end = steps as f64 * 1e-8;
    let text = common::scene(
        &format!("version = 1\nseed = 5\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{l:e}, {l:e}, {h:e}]\n{boundary}\n"),
        &format!(
            "[[particles]]\nspecies = \"p\"\ncount = {n}\norder = \"{order}\"\n[forces.contact]\nwalls = true\n[forces.dipole]\n{dipole}\n\
             [forces.drag]\nlaw = \"schiller-naumann\"\nshielding = \"paper\"\n[forces.gravity]\ng = [0.0, 0.0, -9.81]\n\
             [integration]\nscheme = \"velocity-verlet\"\ndt = 1.0e-8\nend_time = {end:e}\n[output]\ninterval = {end:e}\n"
        ),
    );
    Scene::parse(&text, "parallel test").unwrap()
}

fn run_on(scene: &Scene, threads: usize) -> magdem::core::state::State {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let mut sim = scene.simulation(None);
        sim.initialise().unwrap();
        for _ in 0..scene.total_steps() {
            sim.step().unwrap();
        }
        sim.state
    })
}

#[test]
fn one_and_two_threads_give_identical_bits() {
    // Above the parallel threshold, with the paper's induction (listed pairs), with a plain
    // cut-off (neighbour rows) and over all pairs (bands weighted by their partners); 60 steps
    // let contacts form and springs build up (all pairs: 3 steps, for time).
    let cases = [
        ("induction = \"paper\"\ncutoff_diameters = 15.0", 60),
        ("induction = \"none\"\ncutoff_diameters = 10.0", 60),
        ("induction = \"none\"", 3),
    ];
    for (dipole, steps) in cases {
        let scene = crowd(MIN_PARALLEL_LEN + 500, dipole, steps);
        let (one, two) = (run_on(&scene, 1), run_on(&scene, 2));
        assert!(steps < 60 || !one.history.pairs.is_empty(), "the test should exercise contacts");
        assert_eq!(one, two, "{dipole}: states differ between 1 and 2 threads");
    }
}

/// Two threads whose shares split the particles unevenly (the balance moves the split as a run
/// goes, by how long each share takes) give the bits of one thread: a third and two thirds
/// either way, with the paper's induction (listed pairs, the near list's crossing pairs read by
/// the contact) and with contacts formed.
#[test]
fn uneven_shares_give_the_bits_of_one_thread() {
    let scene = crowd(MIN_PARALLEL_LEN + 500, "induction = \"paper\"\ncutoff_diameters = 15.0", 60);
    let one = run_on(&scene, 1);
    assert!(!one.history.pairs.is_empty(), "the test should exercise contacts");
    for first in [0.3, 0.7] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let two = pool.install(|| {
            let mut sim = scene.simulation(None);
            sim.balance = magdem::core::parallel::Balance::starting_at(first);
            sim.initialise().unwrap();
            for _ in 0..scene.total_steps() {
                sim.step().unwrap();
            }
            sim.state
        });
        assert_eq!(one, two, "first share {first}: states differ from one thread's");
    }
}

/// A packed bed (an FCC block of 4 631 particles pre-compressed in its walled box) driven sideways
/// by a body force of 3e4 weights, so that its contacts shear and slide: the pair pass splits into
/// one share of particles per thread, each adding the earlier shares' pairs that reach it first,
/// and one, two and three threads (three shares: pairs from two earlier shares) give the same
/// bits.
#[test]
fn a_sheared_packed_bed_gives_identical_bits_on_one_two_and_three_threads() {
    let (d, cells) = (11e-6, 10.0);
    let spacing = d * (1.0 - 1e-4);
    let edge = cells * std::f64::consts::SQRT_2 * spacing + d;
    let text = common::scene(
        &format!("version = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{edge:e}, {edge:e}, {edge:e}]\n"),
        &format!(
            "[[particles]]\nspecies = \"p\"\nlattice = {{ kind = \"fcc\", spacing = {spacing:e} }}\n[forces.contact]\nwalls = true\n\
             [forces.gravity]\ng = [3.0e5, 1.0e5, -9.81]\n[integration]\nscheme = \"velocity-verlet\"\ndt = 1.0e-8\nend_time = 4.0e-7\n"
        ),
    );
    let scene = Scene::parse(&text, "packed bed").unwrap();
    assert_eq!(scene.initial.len(), 4631);
    assert!(scene.initial.len() > MIN_PARALLEL_LEN);
    let one = run_on(&scene, 1);
    let coordination = 2.0 * one.history.pairs.len() as f64 / scene.initial.len() as f64;
    assert!(coordination > 9.0, "coordination {coordination}: the bed should stay packed");
    // With ν = 0.5, kt = kn: a spring at the Coulomb limit is about μ δ long (δ the lattice's
    // overlap, μ = 0.5); the longest springs reach it, so contacts slide.
    let overlap = d - spacing;
    let mut springs: Vec<f64> = one.history.pairs.iter().map(|(_, s)| s.norm()).collect();
    springs.sort_by(f64::total_cmp);
    let (median, longest) = (springs[springs.len() / 2], springs[springs.len() - 1]);
    assert!(median > 0.05 * overlap, "median spring {median:e} m: the bed should shear");
    assert!(longest > 0.4 * overlap, "longest spring {longest:e} m: some contacts should slide");
    for threads in [2, 3] {
        assert_eq!(one, run_on(&scene, threads), "states differ between 1 and {threads} threads");
    }
}

#[test]
fn the_row_sums_equal_a_direct_pair_sum() {
    // Half rows in 16 bands (above the threshold) and in one (below), in a walled box and in one
    // periodic sideways (minimum image), against a direct double loop over the pairs within the
    // cut-off; agreement to rounding (1e-12 of the largest force).
    let sideways = "boundary = { x = \"periodic\", y = \"periodic\", z = \"wall\" }";
    for (n, boundary) in [(600, ""), (MIN_PARALLEL_LEN + 200, ""), (601, sideways), (MIN_PARALLEL_LEN + 201, sideways)]
    {
        for cutoff in [Some(10.0), None] {
            let dipole = match cutoff {
                Some(c) => format!("induction = \"none\"\ncutoff_diameters = {c:?}"),
                None => "induction = \"none\"".to_string(),
            };
            let scene = crowd_in(n, &dipole, 1, "placement", boundary);
            let mut field = scene.magnetic_force_field().unwrap();
            field.terms.retain(|t| matches!(t.name(), "moments" | "dipole"));
            let mut state = scene.initial_state();
            field.evaluate(&mut state, scene.dt());
            let (p, moment) = (&state.particles, &state.fields.moment);
            let range = cutoff.map_or(f64::INFINITY, |c| c * 11.0e-6);
            let mut direct = vec![Vec3::zeros(); p.len()];
            for i in 0..p.len() {
                for j in i + 1..p.len() {
                    let r = scene.domain.displacement(&p.position[i], &p.position[j]);
                    if r.norm() < range {
                        let f = dipole_pair_force(&moment[i], &moment[j], &r, r.norm());
                        direct[i] += f;
                        direct[j] -= f;
                    }
                }
            }
            let largest = direct.iter().map(|f| f.norm()).fold(0.0, f64::max);
            let worst = direct.iter().zip(&state.fields.force).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            assert!(
                worst < 1e-12 * largest,
                "n = {n} {boundary}, cut-off {cutoff:?}: worst difference {worst:e} of {largest:e}"
            );
        }
    }
}

#[test]
fn the_dipole_sum_does_not_depend_on_when_the_verlet_list_was_built() {
    // Above the threshold (16 bands), the same state evaluated by a fresh force field and by one
    // whose Verlet list was built at other positions (each particle 0.2 d away, less than half
    // the skin of d/1.5 at a 10 d cut-off, so the list is kept and holds other candidates): the
    // same bits, as a resumed run needs.
    let scene = crowd(MIN_PARALLEL_LEN + 300, "induction = \"none\"\ncutoff_diameters = 10.0", 1);
    let field = || {
        let mut field = scene.magnetic_force_field().unwrap();
        field.terms.retain(|t| matches!(t.name(), "moments" | "dipole"));
        field
    };
    let (mut fresh, mut aged) = (field(), field());
    let state = scene.initial_state();
    let mut elsewhere = state.clone();
    for (k, x) in elsewhere.particles.position.write().iter_mut().enumerate() {
        let angle = k as f64 * 2.399_963;
        *x += Vec3::new(angle.cos(), angle.sin(), 0.0) * 0.2 * 11.0e-6;
    }
    aged.evaluate(&mut elsewhere, scene.dt());
    let (mut a, mut b) = (state.clone(), state);
    aged.evaluate(&mut a, scene.dt());
    fresh.evaluate(&mut b, scene.dt());
    let bits = |s: &magdem::core::state::State| {
        s.fields.force.iter().flat_map(|f| f.iter().map(|c| c.to_bits())).collect::<Vec<_>>()
    };
    assert!(a.fields.force.iter().any(|f| f.norm() > 0.0), "the test should exercise the dipole sum");
    assert_eq!(bits(&a), bits(&b), "forces differ with the Verlet list's history");
}

#[test]
fn numbering_particles_in_space_changes_only_the_numbering() {
    // The same placed particles numbered along a Morton curve: each particle (matched by its
    // initial position) follows the same path after 60 steps with contacts, drag and the paper's
    // induction, to rounding (the sums run in another order): within 1e-9 of a radius.
    let dipole = "induction = \"paper\"\ncutoff_diameters = 15.0";
    let (placed, spatial) = (crowd_in(900, dipole, 60, "placement", ""), crowd_in(900, dipole, 60, "spatial", ""));
    let (x0, y0) = (placed.initial_state().particles.position, spatial.initial_state().particles.position);
    let matching: Vec<usize> = y0.iter().map(|y| x0.iter().position(|x| x == y).expect("the same positions")).collect();
    assert!(matching.iter().enumerate().any(|(k, &i)| k != i), "the spatial numbering should differ");
    let radius = 5.5e-6;
    let morton_neighbours = y0.windows(2).map(|w| (w[0] - w[1]).norm()).sum::<f64>();
    let placed_neighbours = x0.windows(2).map(|w| (w[0] - w[1]).norm()).sum::<f64>();
    assert!(
        morton_neighbours < 0.5 * placed_neighbours,
        "consecutive particles {morton_neighbours:e} m apart in all against {placed_neighbours:e}"
    );
    let (a, b) = (run_on(&placed, 1), run_on(&spatial, 1));
    assert!(!a.history.pairs.is_empty(), "the test should exercise contacts");
    let worst = matching
        .iter()
        .enumerate()
        .map(|(k, &i)| (a.particles.position[i] - b.particles.position[k]).norm())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9 * radius, "largest position difference {worst:e} m");
}
