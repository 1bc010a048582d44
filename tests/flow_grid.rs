//! Flow fields on a grid (`[fluid.grid]`): read back from HDF5 and legacy VTK, interpolated
//! exactly at the nodes and linearly between them and between frames, refused by key where they
//! cannot serve the run, and driving the drag as the closed-form flow they sample.

use magdem::core::flow::{Flow, GriddedFlow, Vessel, VesselFlow};
use magdem::core::Vec3;
use magdem::io::flow_grid;
use magdem::scene::Scene;
use std::path::Path;

/// A linear field u = A x + c + t d: trilinear interpolation and linear time interpolation
/// reproduce it everywhere, to round-off.
fn linear(x: Vec3, t: f64) -> Vec3 {
    let a = nalgebra::Matrix3::new(0.3, -1.2, 0.5, 2.0, 0.1, -0.7, -0.4, 0.9, 1.1);
    a * x + Vec3::new(0.01, -0.02, 0.03) + t * Vec3::new(0.5, 0.25, -1.0)
}

/// Writes `frames` of `field` sampled on a grid of `shape` nodes from `origin` at `spacing` to an
/// HDF5 file in the layout `[fluid.grid]` reads.
fn write_hdf5(
    path: &Path,
    origin: Vec3,
    spacing: Vec3,
    shape: [usize; 3],
    times: &[f64],
    field: impl Fn(Vec3, f64) -> Vec3,
) {
    let file = hdf5::File::create(path).unwrap();
    let [nx, ny, nz] = shape;
    let mut values: Vec<f64> = vec![];
    for &t in times {
        for i in 0..nx {
            for j in 0..ny {
                for k in 0..nz {
                    let x = origin + spacing.component_mul(&Vec3::new(i as f64, j as f64, k as f64));
                    values.extend(field(x, t).iter());
                }
            }
        }
    }
    let array = ndarray::Array::from_shape_vec((times.len(), nx, ny, nz, 3), values).unwrap();
    file.new_dataset_builder().with_data(&array).create("velocity").unwrap();
    file.new_dataset_builder().with_data(&ndarray::arr1(origin.as_slice())).create("origin").unwrap();
    file.new_dataset_builder().with_data(&ndarray::arr1(spacing.as_slice())).create("spacing").unwrap();
    file.new_dataset_builder().with_data(&ndarray::arr1(times)).create("time").unwrap();
}

/// A linear field in space and time, read back: at every node of every frame, between nodes
/// and between frames it equals the field to round-off (1e-15 of its value at nodes, 1e-14
/// anywhere).
#[test]
fn a_grid_reads_back_and_interpolates_linearly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flow.h5");
    let (origin, spacing, shape) = (Vec3::new(-1.0, 0.5, 2.0), Vec3::new(0.25, 0.5, 0.2), [5, 4, 6]);
    let times = [0.0, 0.4, 1.0];
    write_hdf5(&path, origin, spacing, shape, &times, linear);
    let grid = flow_grid::read(&path).unwrap();
    assert_eq!((grid.shape, grid.times.clone(), grid.origin, grid.spacing), (shape, times.to_vec(), origin, spacing));
    for (f, &t) in times.iter().enumerate() {
        for (i, j, k) in [(0, 0, 0), (4, 3, 5), (2, 1, 3)] {
            let x = origin + spacing.component_mul(&Vec3::new(i as f64, j as f64, k as f64));
            // Exact but for the rounding of (x − origin)/spacing to the node's index.
            let error = (grid.velocity(x, t) - linear(x, t)).norm();
            assert!(error <= 1e-15 * linear(x, t).norm(), "node ({i}, {j}, {k}) of frame {f}: {error:e}");
        }
    }
    let mut rng = 12345u64;
    let mut uniform = || {
        rng = rng.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let end = grid.end();
    for _ in 0..200 {
        let x = Vec3::from_fn(|a, _| origin[a] + (end[a] - origin[a]) * uniform());
        let t = uniform();
        let error = (grid.velocity(x, t) - linear(x, t)).norm();
        assert!(error < 1e-14, "at {x:?}, t = {t}: {error:e}");
    }
    // Outside the frames' span the end frames hold; with a period the frames repeat.
    let close = |a: Vec3, b: Vec3| (a - b).norm() <= 1e-15 * b.norm();
    assert!(close(grid.velocity(origin, 2.0), linear(origin, 1.0)));
    let periodic = GriddedFlow { period: Some(1.5), ..grid.clone() };
    assert!(close(periodic.velocity(origin, 1.5 + 0.4), linear(origin, 0.4)));
    let w = (1.25 - 1.0) / 0.5;
    let between = (1.0 - w) * linear(origin, 1.0) + w * linear(origin, 0.0);
    assert!(close(periodic.velocity(origin, 1.25), between));
}

/// The same frame as legacy VTK STRUCTURED_POINTS (x fastest, ASCII) reads as the HDF5 grid.
#[test]
fn a_legacy_vtk_grid_reads_as_the_hdf5_one() {
    let dir = tempfile::tempdir().unwrap();
    let (origin, spacing, shape) = (Vec3::new(0.0, -0.5, 0.1), Vec3::new(0.1, 0.2, 0.3), [3, 4, 2]);
    write_hdf5(&dir.path().join("flow.h5"), origin, spacing, shape, &[0.0], linear);
    let mut vtk = format!(
        "# vtk DataFile Version 3.0\nflow\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 3 4 2\n\
         ORIGIN {} {} {}\nSPACING {} {} {}\nPOINT_DATA 24\nVECTORS U double\n",
        origin.x, origin.y, origin.z, spacing.x, spacing.y, spacing.z
    );
    for k in 0..shape[2] {
        for j in 0..shape[1] {
            for i in 0..shape[0] {
                let u = linear(origin + spacing.component_mul(&Vec3::new(i as f64, j as f64, k as f64)), 0.0);
                vtk += &format!("{:e} {:e} {:e}\n", u.x, u.y, u.z);
            }
        }
    }
    std::fs::write(dir.path().join("flow.vtk"), vtk).unwrap();
    let (a, b) =
        (flow_grid::read(&dir.path().join("flow.h5")).unwrap(), flow_grid::read(&dir.path().join("flow.vtk")).unwrap());
    assert_eq!((a.shape, a.origin, a.spacing, a.times.clone()), (b.shape, b.origin, b.spacing, b.times.clone()));
    let worst = a.velocity.iter().zip(&b.velocity).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max);
    assert!(worst < 1e-15 * 10.0, "{worst:e}");
}

/// A bead in a box-filling vessel, in Poiseuille flow given on a grid of 41 × 21 × 21 nodes
/// (the vessel's own closed form sampled) and in the closed form itself: the runs agree to the
/// trilinear interpolation's error, at most h²/8 |∂²u/∂y²| + h²/8 |∂²u/∂z²| = ū h²/R² (the
/// parabola's), relative to the local speed u(r0): 6.0e-3 here (measured 4.7e-3).
#[test]
fn a_bead_in_gridded_poiseuille_flow_follows_the_closed_form_flow() {
    let dir = tempfile::tempdir().unwrap();
    let (radius, mean_speed) = (6.0e-5, 1.0e-3);
    let vessel = Vessel { centre: Vec3::zeros(), axis: Vec3::x_axis(), radius };
    let poiseuille = VesselFlow::poiseuille(vessel, mean_speed, 1000.0, 1.0e-3);
    let (origin, h) = (Vec3::new(-1.0e-3, -6.0e-5, -6.0e-5), 6.0e-6);
    write_hdf5(&dir.path().join("flow.h5"), origin, Vec3::new(5.0e-5, h, h), [41, 21, 21], &[0.0], |x, t| {
        Flow::Vessel(poiseuille.clone()).velocity(x, t)
    });
    let scene = |fluid: &str| {
        let text = format!(
            "version = 1\n[domain]\nlo = [-1e-3, -6e-5, -6e-5]\nhi = [1e-3, 6e-5, 6e-5]\n\
             [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n{fluid}\
             [[species]]\nname = \"p\"\ndiameter = 11.0e-6\ndensity = 1087.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
             friction = 0.5\nrestitution = 1.0\n[[particles]]\nspecies = \"p\"\npositions = [[0.0, 2.1e-5, 1.3e-5]]\n\
             [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\nrotational = false\n\
             [integration]\ndt = 1.0e-6\nend_time = 5.0e-2\n"
        );
        std::fs::write(dir.path().join("scene.toml"), &text).unwrap();
        let scene = Scene::from_file(&dir.path().join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
        let mut sim = scene.simulation(None);
        sim.initialise().unwrap();
        for _ in 0..scene.total_steps() {
            sim.step().unwrap();
        }
        sim.state.particles.position[0]
    };
    let gridded = scene("[fluid.grid]\nfile = \"flow.h5\"\n");
    let closed = scene(&format!(
        "[fluid.vessel]\ncentre = [0.0, 0.0, 0.0]\naxis = [1.0, 0.0, 0.0]\nradius = {radius:e}\nmean_speed = {mean_speed:e}\n"
    ));
    let travel = closed.x;
    let error = (gridded - closed).norm() / travel;
    let r0 = (2.1e-5f64.powi(2) + 1.3e-5f64.powi(2)).sqrt();
    let bound = mean_speed * (h / radius).powi(2) / (2.0 * mean_speed * (1.0 - (r0 / radius).powi(2)));
    println!("gridded against closed-form Poiseuille: {error:.2e} of the {travel:.3e} m travelled (bound {bound:.2e})");
    assert!(travel > 1e-5 && error < bound, "{gridded:?} against {closed:?}");
}

/// A grid that does not cover the box, a missing file and frames that end before the run are
/// refused by key.
#[test]
fn grids_that_cannot_serve_the_run_are_refused_by_key() {
    let dir = tempfile::tempdir().unwrap();
    write_hdf5(&dir.path().join("small.h5"), Vec3::zeros(), Vec3::repeat(1e-5), [3, 3, 3], &[0.0], linear);
    write_hdf5(&dir.path().join("short.h5"), Vec3::repeat(-1e-3), Vec3::repeat(1e-3), [3, 3, 3], &[0.0, 1e-7], linear);
    let refused = |file: &str, extra: &str| {
        let text = format!(
            "version = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [1e-4, 1e-4, 1e-4]\n\
             [fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n[fluid.grid]\nfile = \"{file}\"\n{extra}\
             [[species]]\nname = \"p\"\ndiameter = 11.0e-6\ndensity = 1087.0\nyoungs_modulus = 1.0e9\npoisson_ratio = 0.5\n\
             friction = 0.5\nrestitution = 1.0\n[[particles]]\nspecies = \"p\"\npositions = [[5e-5, 5e-5, 5e-5]]\n\
             [forces.drag]\nlaw = \"stokes\"\nshielding = \"none\"\n[integration]\ndt = 1.0e-7\nend_time = 1.0e-6\n"
        );
        std::fs::write(dir.path().join("scene.toml"), &text).unwrap();
        Scene::from_file(&dir.path().join("scene.toml")).err().map(|e| e.to_string())
    };
    let cases = [
        ("small.h5", "", "does not cover the box"),
        ("absent.h5", "", "cannot read it"),
        ("short.h5", "", "set fluid.grid.period"),
    ];
    for (file, extra, why) in cases {
        let e = refused(file, extra).unwrap_or_else(|| panic!("accepted {file}"));
        assert!(e.contains("fluid.grid.file") && e.contains(why), "{file}: {e}");
    }
    assert!(refused("short.h5", "period = 1.0e-6\n").is_none(), "a period repeats the frames");
}
