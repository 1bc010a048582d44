//! Trajectories in the tools of the field: ParaView (pvpython, pvbatch) reads the XDMF sidecar
//! that `run` writes, and OVITO's Python module reads `magdem export --format lammps-dump`; both
//! give the HDF5 file's points, frames and positions. `make setup` installs both programs and
//! Xvfb: a test whose program is absent fails, unless MAGDEM_NO_REFERENCE=1 makes them optional
//! (tests/common/absent.rs).

#[path = "common/absent.rs"]
mod absent;
mod common;

use magdem::io::trajectory::Trajectory;
use std::path::Path;
use std::process::Command;

/// 40 magnetic particles with contacts, drag and gravity; six frames.
fn scene() -> String {
    common::scene(
        r#"version = 1
name = "export-test"
seed = 3
[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.2e-4, 1.2e-4, 1.2e-4]
boundary = { x = "periodic", y = "wall", z = "wall" }
"#,
        r#"[[particles]]
species = "p"
count = 40
[forces.contact]
[forces.dipole]
induction = "paper"
cutoff_diameters = 4.0
paper_radius_diameters = 4.0
[forces.drag]
[forces.gravity]
[integration]
dt = 1.0e-8
end_time = 5.0e-5
[output]
interval = 1.0e-5
"#,
    )
}

fn has(program: &str, probe: &[&str]) -> bool {
    Command::new(program).args(probe).output().is_ok_and(|o| o.status.success())
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A finished run in a fresh directory: (guard, trajectory).
fn run() -> (tempfile::TempDir, std::path::PathBuf) {
    let work = tempfile::Builder::new().prefix("magdem-export-").tempdir().unwrap();
    let scene_file = work.path().join("scene.toml");
    std::fs::write(&scene_file, scene()).unwrap();
    let h5 = work.path().join("run.h5");
    let out = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["run", path(&scene_file), "-q", "-o", path(&h5)])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    (work, h5)
}

/// Particle count, frame count, and the last frame's position of particle 7 (HDF5).
fn truth(h5: &Path) -> (usize, usize, [f64; 3]) {
    let t = Trajectory::open(h5).unwrap();
    let frames = t.frames().unwrap();
    let x = t.frame_vectors("position", frames - 1).unwrap();
    (x.len(), frames, [x[7].x, x[7].y, x[7].z])
}

fn numbers(stdout: &[u8], key: &str) -> Vec<f64> {
    let text = String::from_utf8_lossy(stdout);
    let line = text.lines().find(|l| l.starts_with(key)).unwrap_or_else(|| panic!("no {key} in {text}"));
    line[key.len()..].split_whitespace().map(|v| v.parse().unwrap()).collect()
}

#[test]
fn paraview_reads_the_xdmf_sidecar_and_renders_a_frame() {
    if !absent::present(has("pvpython", &["--version"]), "pvpython", "run scripts/setup.sh as root (Debian's paraview)")
    {
        return;
    }
    let (_work, h5) = run();
    let xdmf = h5.with_extension("xdmf");
    assert!(xdmf.exists(), "run writes the sidecar beside the file");
    let (n, frames, x7) = truth(&h5);
    // ParaView's default reader for the file (`OpenDataFile`, Xdmf3ReaderS) and the legacy one.
    let script = r#"
import os, sys
from paraview.simple import OpenDataFile, XDMFReader
from paraview import servermanager
path = os.path.abspath(sys.argv[1])
r = OpenDataFile(path) if sys.argv[2] == "default" else XDMFReader(FileNames=[path])
print("reader", r.GetXMLName())
r.UpdatePipelineInformation()
times = r.TimestepValues
points = []
for t in times:
    r.UpdatePipeline(t)
    points.append(servermanager.Fetch(r).GetNumberOfPoints())
data = servermanager.Fetch(r)
print("frames", len(times))
print("points", min(points), max(points))
print("x7", *data.GetPoint(7))
names = [data.GetPointData().GetArrayName(i) for i in range(data.GetPointData().GetNumberOfArrays())]
print("arrays", len(names), " ".join(names))
"#;
    let work = h5.parent().unwrap();
    std::fs::write(work.join("check.py"), script).unwrap();
    for (reader, name) in [("default", "Xdmf3ReaderS"), ("legacy", "XdmfReader")] {
        let out = Command::new("pvpython").args([path(&work.join("check.py")), path(&xdmf), reader]).output().unwrap();
        assert!(out.status.success(), "{reader}: {}", String::from_utf8_lossy(&out.stderr));
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains(&format!("reader {name}")), "{reader}: {text}");
        assert_eq!(numbers(&out.stdout, "frames ")[0] as usize, frames, "{reader}");
        assert_eq!(numbers(&out.stdout, "points "), [n as f64, n as f64], "{reader}: every frame's points");
        let x = numbers(&out.stdout, "x7 ");
        for k in 0..3 {
            assert!((x[k] - x7[k]).abs() <= 1e-12 * x7[k].abs().max(1e-9), "{reader}: {x:?} against HDF5 {x7:?}");
        }
        for array in ["radius", "species", "velocity", "angular_velocity", "moment"] {
            assert!(text.contains(array), "{reader}: {array} in {text}");
        }
    }
    if !absent::present(has("Xvfb", &["-help"]), "Xvfb", "run scripts/setup.sh as root (Debian's xvfb)") {
        return;
    }
    let png = work.join("frame.png");
    let out = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["export", path(&h5), "--format", "png", "-o", path(&png)])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // A white image compresses to a few kB; spheres on it do not.
    let size = std::fs::metadata(&png).map(|m| m.len()).unwrap_or(0);
    assert!(size > 15_000, "rendered PNG of {size} bytes");
}

#[test]
fn ovito_reads_the_lammps_dump_export() {
    if !absent::present(
        has("python3", &["-c", "import ovito"]),
        "the ovito Python module",
        "run `python3 -m pip install ovito` (scripts/setup.sh does)",
    ) {
        return;
    }
    let (_work, h5) = run();
    let dump = h5.with_extension("dump");
    let out = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["export", path(&h5), "--format", "lammps-dump"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (n, frames, x7) = truth(&h5);
    let script = r#"
import sys
from ovito.io import import_file
p = import_file(sys.argv[1])
print("frames", p.source.num_frames)
data = p.compute(p.source.num_frames - 1)
print("points", data.particles.count)
ids = list(data.particles.identifiers)
k = ids.index(8)
print("x7", *data.particles.positions[k])
print("r7", data.particles["Radius"][k])
"#;
    let work = h5.parent().unwrap();
    std::fs::write(work.join("check.py"), script).unwrap();
    let out = Command::new("python3").args([path(&work.join("check.py")), path(&dump)]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(numbers(&out.stdout, "frames ")[0] as usize, frames);
    assert_eq!(numbers(&out.stdout, "points ")[0] as usize, n);
    let x = numbers(&out.stdout, "x7 ");
    for k in 0..3 {
        assert!((x[k] - x7[k]).abs() <= 1e-12 * x7[k].abs().max(1e-9), "OVITO {x:?} against HDF5 {x7:?}");
    }
    assert!((numbers(&out.stdout, "r7 ")[0] - 5.5e-6).abs() < 1e-18);
}

#[test]
fn a_render_without_its_programs_exits_1_naming_one_and_keeps_the_earlier_picture() {
    let (_work, h5) = run();
    let png = h5.with_extension("png");
    let earlier = b"an earlier picture".to_vec();
    std::fs::write(&png, &earlier).unwrap();
    let empty = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["export", path(&h5), "--format", "png"])
        .env("PATH", empty.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("Xvfb is not installed"), "{stderr}");
    assert_eq!(std::fs::read(&png).unwrap(), earlier, "the earlier picture is untouched");
    let scratch: Vec<_> = std::fs::read_dir(h5.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with('.'))
        .collect();
    assert!(scratch.is_empty(), "scratch files left: {scratch:?}");
    let missing = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["export", path(&h5.with_file_name("absent.h5")), "--format", "png"])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2), "a missing trajectory is bad input");
}

/// A run whose particles leave through an outlet or are captured by the vessel's wall: the dump
/// lists the particles still in the run in each snapshot (HDF5 rows that are not NaN), and OVITO
/// reads those counts and ids frame by frame.
#[test]
fn ovito_reads_a_dump_whose_particles_leave() {
    if !absent::present(
        has("python3", &["-c", "import ovito"]),
        "the ovito Python module",
        "run `python3 -m pip install ovito` (scripts/setup.sh does)",
    ) {
        return;
    }
    let work = tempfile::tempdir().unwrap();
    let scene = work.path().join("leaving.toml");
    std::fs::write(
        &scene,
        r#"version = 1
[domain]
lo = [-1e-4, -2.5e-4, -2.5e-4]
hi = [1.1e-3, 2.5e-4, 2.5e-4]
[fluid]
density = 1000.0
viscosity = 1.0e-3
[fluid.vessel]
centre = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
radius = 2.5e-4
mean_speed = 0.05
[[species]]
name = "bead"
diameter = 1.0e-5
density = 5000.0
youngs_modulus = 1.0e5
poisson_ratio = 0.3
friction = 0.5
restitution = 0.5
[[particles]]
species = "bead"
count = 30
region = { lo = [0.0, -2.5e-4, -2.5e-4], hi = [1e-4, 2.5e-4, 2.5e-4] }
in_vessel = "flux"
[forces.contact]
[forces.drag]
law = "stokes"
shielding = "none"
[forces.gravity]
g = [0.0, -500.0, 0.0]
[exits]
capture_after = 0.0
[[exits.outlets]]
name = "end"
point = [1.0e-3, 0.0, 0.0]
normal = [1.0, 0.0, 0.0]
[integration]
dt = 2.0e-6
end_time = 4.0e-2
[output]
interval = 4.0e-3
"#,
    )
    .unwrap();
    let h5 = work.path().join("leaving.h5");
    let magdem = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_magdem")).args(args).output().unwrap();
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&h5)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = magdem(&["export", path(&h5), "--format", "lammps-dump"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // Per frame, the ids (1-based, as in the dump) of the rows that are not NaN.
    let t = magdem::io::trajectory::Trajectory::open(&h5).unwrap();
    let x = t.all_vectors("position").unwrap();
    let present: Vec<Vec<usize>> = (0..x.shape()[0])
        .map(|f| (0..x.shape()[1]).filter(|&i| !x[(f, i, 0)].is_nan()).map(|i| i + 1).collect())
        .collect();
    assert!(present[0].len() == 30 && present.last().unwrap().len() < 30, "particles leave: {present:?}");
    let script = r#"
import sys
from ovito.io import import_file
p = import_file(sys.argv[1])
for k in range(p.source.num_frames):
    print("frame", *sorted(p.compute(k).particles.identifiers))
"#;
    std::fs::write(work.path().join("check.py"), script).unwrap();
    let out = Command::new("python3")
        .args([path(&work.path().join("check.py")), path(&h5.with_extension("dump"))])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let read: Vec<Vec<usize>> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.strip_prefix("frame"))
        .map(|l| l.split_whitespace().map(|w| w.parse().unwrap()).collect())
        .collect();
    assert_eq!(read, present);
}
