//! Trajectory files: readable by h5py (or h5dump) after a kill, and a resumed run ends bitwise
//! equal to an uninterrupted one.

mod common;

use magdem::io::trajectory::Trajectory;
use std::path::{Path, PathBuf};
use std::process::Command;
use tempfile::TempDir;

/// 60 magnetic particles at high concentration with contacts, walls, drag and gravity: contact
/// history, stored moments and forces all matter for the continuation.
fn scene_text() -> String {
    common::scene(
        r#"version = 1
name = "resume-test"
seed = 7
[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.2e-4, 1.2e-4, 1.2e-4]
"#,
        r#"[[particles]]
species = "p"
count = 60
[forces.contact]
[forces.dipole]
induction = "paper"
cutoff_diameters = 5.0
[forces.drag]
[forces.gravity]
[integration]
dt = 1.0e-8
end_time = 3.0e-4
[output]
interval = 2.0e-5
forces = true
"#,
    )
}

/// A fresh directory holding scene.toml, removed when the returned guard drops.
fn workdir(name: &str) -> TempDir {
    let work = tempfile::Builder::new().prefix(&format!("magdem-{name}-")).tempdir().unwrap();
    std::fs::write(work.path().join("scene.toml"), scene_text()).unwrap();
    work
}

/// [`workdir`] with its scene ending at `end_time` (as written in TOML, seconds): a short run.
fn workdir_ending_at(name: &str, end_time: &str) -> (TempDir, PathBuf) {
    let work = workdir(name);
    let scene = work.path().join("scene.toml");
    std::fs::write(&scene, scene_text().replace("end_time = 3.0e-4", &format!("end_time = {end_time}"))).unwrap();
    (work, scene)
}

fn magdem(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_magdem")).args(args).output().unwrap()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Bitwise comparison of the final checkpoint and every frame of two trajectories.
fn assert_identical(a: &Path, b: &Path) {
    let (ta, tb) = (Trajectory::open(a).unwrap(), Trajectory::open(b).unwrap());
    let (sa, fa) = ta.checkpoint().unwrap();
    let (sb, fb) = tb.checkpoint().unwrap();
    assert_eq!((sa.step, fa), (sb.step, fb));
    assert_eq!(sa.particles, sb.particles, "final particle state differs");
    assert_eq!(sa.history, sb.history, "final contact history differs");
    assert_eq!((&sa.exits, &sa.touching), (&sb.exits, &sb.touching), "exits differ");
    assert!(!sa.history.pairs.is_empty(), "the test scene should end with contacts");
    for name in ["position", "velocity", "angular_velocity", "moment", "force", "torque"] {
        let (x, y) = (ta.all_vectors(name).unwrap(), tb.all_vectors(name).unwrap());
        assert_eq!(x.shape(), y.shape(), "{name}");
        assert!(x.iter().zip(y.iter()).all(|(p, q)| p.to_bits() == q.to_bits()), "frames of {name} differ");
    }
    assert_eq!(ta.times().unwrap(), tb.times().unwrap());
    // The contact datasets, element by element (not only their shapes).
    let contacts = |t: &Trajectory, name: &str| t.file.dataset(&format!("contacts/{name}")).unwrap();
    let (pa, pb) = (contacts(&ta, "pair").read_raw::<u32>().unwrap(), contacts(&tb, "pair").read_raw::<u32>().unwrap());
    assert!(!pa.is_empty() && pa == pb, "contacts/pair differ");
    let (sa, sb) = (
        contacts(&ta, "frame_start").read_raw::<u64>().unwrap(),
        contacts(&tb, "frame_start").read_raw::<u64>().unwrap(),
    );
    assert_eq!(sa, sb, "contacts/frame_start differ");
    let (oa, ob) =
        (contacts(&ta, "overlap").read_raw::<f64>().unwrap(), contacts(&tb, "overlap").read_raw::<f64>().unwrap());
    assert!(
        oa.len() == ob.len() && oa.iter().zip(&ob).all(|(p, q)| p.to_bits() == q.to_bits()),
        "contacts/overlap differ"
    );
}

#[test]
fn resume_after_kill_is_bitwise_equal_to_an_uninterrupted_run() {
    resume_after_kill("resume", &scene_text());
}

/// The test scene in a vessel along z (Poiseuille flow, 0.3 m/s mean) whose wall captures the
/// particles it touches, with an outlet near the top: particles leave during both pieces of the
/// run, the frames keep every id (NaN rows for those gone), and the exits and the times since
/// first wall contact are in the checkpoint.
#[test]
fn resume_after_kill_is_bitwise_equal_with_particles_leaving() {
    let text = scene_text()
        .replace(
            "viscosity = 1.0e-3\n",
            "viscosity = 1.0e-3\n[fluid.vessel]\ncentre = [6.0e-5, 6.0e-5, 0.0]\naxis = [0.0, 0.0, 1.0]\n\
             radius = 6.0e-5\nmean_speed = 0.3\n",
        )
        .replace(
            "count = 60\n",
            "count = 60\nin_vessel = \"uniform\"\nregion = { lo = [0.0, 0.0, 0.0], hi = [1.2e-4, 1.2e-4, 9.0e-5] }\n",
        )
        .replace(
            "[integration]",
            "[exits]\ncapture_after = 2.0e-6\n[[exits.outlets]]\nname = \"top\"\npoint = [0.0, 0.0, 1.1e-4]\n\
             normal = [0.0, 0.0, 1.0]\n[integration]",
        );
    let dir = resume_after_kill("resume-exits", &text);
    let t = Trajectory::open(&dir.path().join("full.h5")).unwrap();
    let (state, _) = t.checkpoint().unwrap();
    let (mut early, mut late) = (0, 0);
    for e in &state.exits {
        if e.step <= 6 * 2000 {
            early += 1
        } else {
            late += 1
        }
    }
    let captured = state.exits.iter().filter(|e| e.way == magdem::core::state::Way::Captured).count();
    println!("{early} left before frame 6 and {late} after; {captured} captured");
    assert!(early > 0 && late > 0 && captured > 0 && captured < state.exits.len(), "{:?}", state.exits);
    assert_eq!(state.particles.len() + state.exits.len(), 60);
    // The last frame: a NaN row exactly for each particle gone.
    let x = t.all_vectors("position").unwrap();
    let last = x.shape()[0] - 1;
    let gone: Vec<usize> = (0..60).filter(|&id| x[(last, id, 0)].is_nan()).collect();
    let mut exited: Vec<usize> = state.exits.iter().map(|e| e.id as usize).collect();
    exited.sort_unstable();
    assert_eq!(gone, exited);
}

/// Multiple time stepping carries the slow forces between steps: they are in the checkpoint.
#[test]
fn resume_after_kill_is_bitwise_equal_with_multiple_time_stepping() {
    resume_after_kill(
        "resume-respa",
        &scene_text().replace("dt = 1.0e-8", "scheme = \"respa\"\ndt = 1.0e-8\nslow_every = 10"),
    );
}

/// The shielded drag's coefficients renewed every 10 steps under r-RESPA (`refactor_every = 10`):
/// checkpoints fall on renewals, so the resumed run is bitwise equal.
#[test]
fn resume_after_kill_is_bitwise_equal_with_the_drag_renewed_every_k_steps() {
    resume_after_kill("resume-drag", &respa_with_held_drag(""));
}

/// The test scene under r-RESPA (K = 10) with the drag renewed every outer step, and `extra`
/// lines in `[integration]`.
fn respa_with_held_drag(extra: &str) -> String {
    scene_text()
        .replace("dt = 1.0e-8", &format!("scheme = \"respa\"\ndt = 1.0e-8\nslow_every = 10{extra}"))
        .replace("[forces.drag]", "[forces.drag]\nrefactor_every = 10")
}

/// The adaptive integrator's proposed substep is in the checkpoint.
#[test]
fn resume_after_kill_is_bitwise_equal_with_the_adaptive_step() {
    // A loose tolerance and a shorter run: with 60 particles in chains the substeps follow every
    // contact oscillation, and tight tolerances cost minutes.
    let text = scene_text()
        .replace("dt = 1.0e-8", "scheme = \"adaptive-verlet\"\ntolerance = 1e-4\ndt = 1.0e-8")
        .replace("end_time = 3.0e-4", "end_time = 1.2e-4");
    resume_after_kill("resume-adaptive", &text.replace("induction = \"paper\"", "induction = \"none\""));
}

/// Renumbering during the run (every 30 steps, so at the start of the resumed piece too): the
/// checkpoint keeps the slots and their ids, and the resumed run is bitwise equal.
#[test]
fn resume_after_kill_is_bitwise_equal_with_renumbering() {
    resume_after_kill("resume-renumber", &respa_with_held_drag("\nrenumber_every = 30"));
}

/// Runs `text` as it is and with `renumber_every = every`; the two trajectories (and the
/// directory that holds them).
fn plain_and_renumbered(name: &str, text: &str, every: u64) -> (TempDir, Trajectory, Trajectory) {
    let work = workdir(name);
    let (plain, renumbered) = (work.path().join("plain.toml"), work.path().join("renumbered.toml"));
    std::fs::write(&plain, text).unwrap();
    std::fs::write(&renumbered, text.replace("dt = 1.0e-8", &format!("dt = 1.0e-8\nrenumber_every = {every}")))
        .unwrap();
    for scene in [&plain, &renumbered] {
        let out = magdem(&["run", path(scene), "-q", "-o", path(&scene.with_extension("h5"))]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let open = |scene: &Path| Trajectory::open(&scene.with_extension("h5")).unwrap();
    let (a, b) = (open(&plain), open(&renumbered));
    (work, a, b)
}

/// Where no force is a sum over pairs (gravity and the shielded Schiller–Naumann drag renewed
/// every 10 steps, on polydisperse particles: per-particle masses, weights and coefficients) a
/// renumbering changes no arithmetic: the frames are bitwise those of the run without it. So
/// every held per-particle value follows its particle (renumbering every 5 steps, between
/// renewals), and the frames are written in id order.
#[test]
fn renumbering_changes_no_bit_where_no_force_sums_over_pairs() {
    let text = scene_text()
        .replace("relative_permeability = 12.3", "relative_permeability = 12.3\nsize = { law = \"normal\", cv = 0.1 }")
        .replace("[forces.contact]\n", "")
        .replace("[forces.dipole]\ninduction = \"paper\"\ncutoff_diameters = 5.0\n", "")
        .replace("[forces.drag]", "[forces.drag]\nrefactor_every = 10")
        .replace("end_time = 3.0e-4", "end_time = 4.0e-5")
        .replace("interval = 2.0e-5", "interval = 1.0e-5");
    let (_work, a, b) = plain_and_renumbered("renumber-exact", &text, 5);
    let ids = b.checkpoint().unwrap().0.ids;
    assert!(ids.iter().enumerate().filter(|(k, &id)| *k != id as usize).count() > 30, "renumbered: {ids:?}");
    for name in ["position", "velocity", "angular_velocity", "force"] {
        let (x, y) = (a.all_vectors(name).unwrap(), b.all_vectors(name).unwrap());
        assert_eq!(x.shape(), y.shape(), "{name}");
        assert!(x.iter().zip(y.iter()).all(|(p, q)| p.to_bits() == q.to_bits()), "frames of {name} differ");
    }
}

/// With dipole forces, contacts and the paper's induction, a renumbering changes the order of
/// the sums: the run differs by round-off. Over this short run (2 000 steps, renumbered every
/// 100) positions of about 1e-4 m differ by ~1e-18 m; 1e-13 m allows the chaotic growth of that
/// round-off, while a force given to the wrong particle would move it by ~ speed × time ≈ 1e-9
/// m. Particle by particle (id order), the contact pairs of the last frame are the same.
#[test]
fn renumbering_changes_a_magnetic_run_by_round_off_only() {
    let text = scene_text()
        .replace("end_time = 3.0e-4", "end_time = 2.0e-5")
        .replace("interval = 2.0e-5", "interval = 1.0e-5");
    let (_work, a, b) = plain_and_renumbered("renumber-roundoff", &text, 100);
    let (x, y) = (a.frame_vectors("position", 2).unwrap(), b.frame_vectors("position", 2).unwrap());
    let largest = x.iter().zip(&y).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max);
    let different = x.iter().zip(&y).filter(|(p, q)| p != q).count();
    eprintln!("largest position difference {largest:e} m, {different} of {} particles differ", x.len());
    assert!(largest < 1e-13, "largest position difference {largest:e} m");
    assert!(b.checkpoint().unwrap().0.ids.iter().enumerate().any(|(k, &id)| k != id as usize), "renumbered");
    let pairs = |t: &Trajectory| -> Vec<u32> { t.file.dataset("contacts/pair").unwrap().read_raw().unwrap() };
    let starts = |t: &Trajectory| -> Vec<u64> { t.file.dataset("contacts/frame_start").unwrap().read_raw().unwrap() };
    let last = |t: &Trajectory| pairs(t)[2 * starts(t)[2] as usize..].to_vec();
    assert_eq!(last(&a), last(&b), "contact pairs of the last frame");
    assert!(!last(&a).is_empty(), "the scene should have contacts");
}

/// The phase timers (`--timings`) only read the clock: the trajectory is bitwise the same, and
/// every phase of this scene is reported with a share, the shares adding to 100%.
#[test]
fn timings_do_not_change_the_trajectory() {
    let (work, scene) = workdir_ending_at("timings", "1.0e-4");
    let dir = work.path();
    let (plain, timed) = (dir.join("plain.h5"), dir.join("timed.h5"));
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&plain)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!String::from_utf8_lossy(&out.stdout).contains("phase timings"));
    let out = magdem(&["run", path(&scene), "-q", "--timings", "-o", path(&timed)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let shares: Vec<(String, f64)> = stdout
        .lines()
        .skip_while(|l| !l.starts_with("phase timings"))
        .skip(1)
        .take_while(|l| !l.starts_with("neighbour ranges"))
        .map(|l| {
            let words: Vec<&str> = l.split_whitespace().collect();
            (words[0].to_string(), words[3].trim_end_matches('%').parse().unwrap())
        })
        .collect();
    for phase in ["neighbours", "pair-list", "seed", "moments", "contact", "dipole", "drag", "integrate", "monitor"] {
        assert!(shares.iter().any(|(name, _)| name == phase), "no {phase} in {stdout}");
    }
    // Each neighbour range says how often it was rebuilt: at least once, at the start.
    let ranges: Vec<&str> = stdout.lines().skip_while(|l| !l.starts_with("neighbour ranges")).skip(1).collect();
    assert!(!ranges.is_empty(), "no neighbour ranges in {stdout}");
    for line in ranges.iter().filter(|l| l.trim_start().starts_with("within")) {
        let rebuilds: u64 = line.split(": ").nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
        assert!(rebuilds >= 1, "{line}");
    }
    let total: f64 = shares.iter().map(|s| s.1).sum();
    assert!((total - 100.0).abs() < 0.5, "shares add to {total}%");
    assert_identical(&plain, &timed);
}

fn resume_after_kill(name: &str, text: &str) -> TempDir {
    let work = workdir(name);
    let dir = work.path();
    std::fs::write(dir.join("scene.toml"), text).unwrap();
    let scene = dir.join("scene.toml");
    let (full, killed) = (dir.join("full.h5"), dir.join("killed.h5"));
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&full)]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    // Abort (no destructors, no HDF5 close: as a kill) right after frame 6 of 16.
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&killed), "--abort-after-frame", "6"]);
    assert!(!out.status.success());
    let t = Trajectory::open(&killed).expect("a killed run leaves a readable file");
    assert_eq!(t.frames().unwrap(), 6);
    assert_eq!(t.attr_string("status").unwrap(), "running");
    drop(t);

    let out = magdem(&["run", path(&scene), "-q", "-o", path(&killed), "--resume"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(Trajectory::open(&killed).unwrap().attr_string("status").unwrap(), "completed");
    assert_identical(&full, &killed);

    // Resuming a completed run does nothing; resuming into another scene's file is refused.
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&killed), "--resume"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("already complete"));
    let other = dir.join("other.toml");
    std::fs::write(&other, text.replace("seed = 7", "seed = 8")).unwrap();
    let out = magdem(&["run", path(&other), "-q", "-o", path(&killed), "--resume"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("different scene"));
    work
}

#[test]
fn ctrl_c_checkpoints_and_the_run_resumes_to_the_same_end() {
    ctrl_c_and_resume("sigint", &scene_text(), 1);
}

/// With the RPY mobility refactorised every 16 steps, Ctrl-C checkpoints on a multiple of 16
/// (where the factor is refreshed), so the resumed run is bitwise equal too.
#[test]
fn ctrl_c_with_rpy_drag_checkpoints_on_a_refactorisation_and_resumes_bitwise() {
    let text = scene_text()
        .replace("[forces.drag]", "[forces.drag]\nlaw = \"rpy\"\nshielding = \"none\"\nrefactor_every = 16");
    ctrl_c_and_resume("sigint-rpy", &text, 16);
}

/// A kill after frame 6 and `--resume` end bitwise equal with the RPY drag refactorised every 10
/// steps.
#[test]
fn resume_after_kill_is_bitwise_equal_with_rpy_drag_refactored_every_k_steps() {
    let text = scene_text()
        .replace("[forces.drag]", "[forces.drag]\nlaw = \"rpy\"\nshielding = \"none\"\nrefactor_every = 10");
    resume_after_kill("resume-rpy", &text);
}

/// Interrupts a longer run of `text` with SIGINT, checks that its checkpoint falls on a multiple
/// of `multiple` steps, resumes it and compares it bitwise with an uninterrupted run.
fn ctrl_c_and_resume(name: &str, text: &str, multiple: u64) {
    let work = workdir(name);
    let dir = work.path();
    let scene = dir.join("scene.toml");
    let (full, interrupted) = (dir.join("full.h5"), dir.join("interrupted.h5"));
    let long = text.replace("end_time = 3.0e-4", "end_time = 1.5e-3");
    std::fs::write(&scene, &long).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["run", path(&scene), "-q", "-o", path(&interrupted)])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for progress, not for a clock: until the file (flushed after every frame, HDF5 file
    // locking off) holds 3 of its 75 frames, then send SIGINT. A read racing a write may fail;
    // it is retried. The run must still be going when the frames appear.
    let frames_written = || Trajectory::open(&interrupted).ok().and_then(|t| t.frames().ok()).unwrap_or(0);
    let started = std::time::Instant::now();
    while frames_written() < 3 {
        assert!(child.try_wait().unwrap().is_none(), "the run ended before writing 3 frames");
        assert!(started.elapsed() < std::time::Duration::from_secs(600), "no progress in 600 s");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    let status = child.wait().unwrap();
    let t = Trajectory::open(&interrupted).unwrap();
    let state = t.attr_string("status").unwrap();
    assert_eq!(status.code(), Some(130), "the signal came at frame 3 of 75: the run must not have completed");
    assert_eq!(state, "interrupted");
    let (ck, _) = t.checkpoint().unwrap();
    assert!(ck.step > 0 && ck.step < 150_000);
    assert_eq!(ck.step % multiple, 0, "checkpoint at step {}", ck.step);
    drop(t);
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&interrupted), "--resume"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&full)]);
    assert!(out.status.success());
    assert_identical(&full, &interrupted);
}

/// A finished run records the threads it ran on beside its wall time (the finite-size table
/// reads both), for one thread and for two.
#[test]
fn a_run_records_its_thread_count() {
    let (work, scene) = workdir_ending_at("threads", "2.0e-5");
    let dir = work.path();
    for threads in [1u64, 2] {
        let file = dir.join(format!("run-{threads}.h5"));
        let out = Command::new(env!("CARGO_BIN_EXE_magdem"))
            .args(["run", path(&scene), "-q", "-o", path(&file)])
            .env("RAYON_NUM_THREADS", threads.to_string())
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let t = Trajectory::open(&file).unwrap();
        assert_eq!(t.attr::<u64>("threads").unwrap(), threads);
        assert!(t.attr::<f64>("wall_time_s").unwrap() > 0.0);
    }
}

/// The file opens in h5py with the documented layout (h5dump when Python/h5py is absent).
#[test]
fn trajectory_is_readable_from_python() {
    let (work, scene) = workdir_ending_at("h5py", "4.0e-5");
    let dir = work.path();
    let file = dir.join("run.h5");
    assert!(magdem(&["run", path(&scene), "-q", "-o", path(&file)]).status.success());
    let script = r#"
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
pos = f["frames/position"][...]
assert pos.shape == (3, 60, 3), pos.shape
assert f["frames/time"].shape == (3,)
assert f.attrs["format"] == "magdem-trajectory"
assert f.attrs["engine"] == "magdem"
assert "version = 1" in f["scene"][()].decode()
assert np.all(np.isfinite(pos))
assert f["frames/position"].compression == "gzip"
assert f["particles/radius"].shape == (60,)
print("h5py ok", pos.shape)
"#;
    let python = Command::new("python3").args(["-c", script, path(&file)]).output();
    match python {
        Ok(out) if out.status.success() => println!("{}", String::from_utf8_lossy(&out.stdout)),
        Ok(out) if String::from_utf8_lossy(&out.stderr).contains("No module named") => {
            let dump =
                Command::new("h5dump").args(["-H", path(&file)]).output().expect("neither h5py nor h5dump available");
            let text = String::from_utf8_lossy(&dump.stdout);
            assert!(
                dump.status.success() && text.contains("DATASET \"position\"") && text.contains("( 3, 60, 3 )"),
                "{text}"
            );
        }
        Ok(out) => panic!("h5py check failed: {}", String::from_utf8_lossy(&out.stderr)),
        Err(_) => {
            let dump = Command::new("h5dump")
                .args(["-H", path(&file)])
                .output()
                .expect("neither python3 nor h5dump available");
            assert!(dump.status.success());
        }
    }
}

/// A finished run is never replaced without `--overwrite`; a completed run of another scene is
/// not resumed into; every refusal exits 2 with one line naming the file.
#[test]
fn an_existing_output_is_refused_unless_overwritten() {
    let (work, scene) = workdir_ending_at("overwrite", "4.0e-5");
    let dir = work.path();
    let file = dir.join("run.h5");
    assert!(magdem(&["run", path(&scene), "-q", "-o", path(&file)]).status.success());
    let before = std::fs::read(&file).unwrap();
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&file)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run.h5 exists (status completed")
            && err.contains("--overwrite")
            && err.trim().lines().count() == 1,
        "{err}"
    );
    assert_eq!(std::fs::read(&file).unwrap(), before, "the refused run left the file as it was");
    // A file that is not a trajectory is refused too.
    let junk = dir.join("junk.h5");
    std::fs::write(&junk, b"not hdf5").unwrap();
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&junk)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a readable magdem trajectory"));
    // --overwrite replaces it: the junk file becomes the same run, bit for bit.
    assert!(magdem(&["run", path(&scene), "-q", "-o", path(&junk), "--overwrite"]).status.success());
    assert_identical(&file, &junk);
}

/// Two processes writing one file: the second is refused at start; a `kill -9` of the first
/// leaves no stuck lock, and `--resume` continues its file.
#[test]
fn a_second_writer_is_refused_and_a_killed_one_leaves_no_lock() {
    let (work, scene) = workdir_ending_at("lock", "3.0e-3");
    let dir = work.path();
    let file = dir.join("run.h5");
    let mut first = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["run", path(&scene), "-q", "-o", path(&file)])
        .spawn()
        .unwrap();
    // Wait for the first frames (the lock is taken before the file is created).
    let started = std::time::Instant::now();
    while Trajectory::open(&file).ok().and_then(|t| t.frames().ok()).unwrap_or(0) < 2 {
        assert!(started.elapsed().as_secs() < 60, "the first run wrote no frames");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&file), "--resume"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("being written by another magdem process"), "{err}");
    Command::new("kill").args(["-9", &first.id().to_string()]).status().unwrap();
    first.wait().unwrap();
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&file), "--resume"]);
    assert!(out.status.success(), "after kill -9 the lock is free: {}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(Trajectory::open(&file).unwrap().attr_string("status").unwrap(), "completed");
}

/// A small tmpfs mounted for one test and unmounted when dropped. Mounting needs root, as
/// `make test` runs (README), so failing to mount fails the test; without root, leave the test
/// out by name (`cargo test -- --skip a_full_disk`).
struct Tmpfs(std::path::PathBuf);

impl Tmpfs {
    fn mount(size: &str) -> Self {
        let dir = tempfile::Builder::new().prefix("magdem-full-").tempdir().unwrap().keep();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs", path(&dir)])
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            let _ = std::fs::remove_dir(&dir);
            panic!("cannot mount a tmpfs: this test needs root with mount permission (or --skip a_full_disk)");
        }
        Self(dir)
    }
    fn resize(&self, size: &str) {
        assert!(Command::new("mount")
            .args(["-o", &format!("remount,size={size}"), path(&self.0)])
            .status()
            .unwrap()
            .success());
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
        let _ = std::fs::remove_dir(&self.0);
    }
}

/// A disk that fills up mid-run: the run stops before the frame that would not fit (exit 1, one
/// line naming the file and the frame), the file keeps every frame before it, and `--resume`
/// continues once there is space, ending bitwise equal to a run that had space throughout.
#[test]
fn a_full_disk_stops_the_run_cleanly_and_resume_continues() {
    let disk = Tmpfs::mount("600k");
    let work = workdir("full");
    let dir = work.path();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        scene_text()
            .replace("interval = 2.0e-5", "interval = 2.0e-6")
            .replace("end_time = 3.0e-4", "end_time = 2.0e-4"),
    )
    .unwrap();
    let (full, file) = (dir.join("full.h5"), disk.0.join("run.h5"));
    assert!(magdem(&["run", path(&scene), "-q", "-o", path(&full)]).status.success());
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&file)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("stopped before frame") && err.contains("run.h5") && err.trim().lines().count() == 1, "{err}");
    let t = Trajectory::open(&file).expect("the file stays readable");
    let kept = t.frames().unwrap();
    assert!(kept > 1 && kept < 101, "{kept} frames kept");
    assert_eq!(t.attr_string("status").unwrap(), "interrupted");
    drop(t);
    disk.resize("8m");
    let out = magdem(&["run", path(&scene), "-q", "-o", path(&file), "--resume"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_identical(&full, &file);
}

/// A truncated trajectory and an HDF5 file of another program get a one-line error naming the
/// file from `info`, `analyse` and `run --resume`.
#[test]
fn damaged_and_foreign_files_are_refused_with_one_line_naming_them() {
    let (work, scene) = workdir_ending_at("damaged", "4.0e-5");
    let dir = work.path();
    let good = dir.join("good.h5");
    assert!(magdem(&["run", path(&scene), "-q", "-o", path(&good)]).status.success());
    let bytes = std::fs::read(&good).unwrap();
    let truncated = dir.join("truncated.h5");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let foreign = dir.join("foreign.h5");
    let f = hdf5::File::create(&foreign).unwrap();
    f.new_dataset::<f64>().shape([4]).create("temperature").unwrap().write(&[1.0, 2.0, 3.0, 4.0]).unwrap();
    drop(f);
    for file in [&truncated, &foreign] {
        let name = file.file_name().unwrap().to_str().unwrap();
        for args in [
            vec!["info", path(file)],
            vec!["analyse", path(file)],
            vec!["run", path(&scene), "-q", "-o", path(file), "--resume"],
        ] {
            let out = magdem(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "{args:?} accepted {name}");
            assert!(err.contains(name) && err.trim().lines().count() == 1, "{args:?}: {err}");
        }
    }
}

/// Every per-particle vector of the state (the list `State::vectors` derives from the state's
/// own fields), the contact springs, the clock and the adaptive step survive a checkpoint bit for
/// bit: each field is filled with distinct values, written, read back and compared as a whole.
#[test]
fn every_state_field_round_trips_through_the_checkpoint() {
    use magdem::core::state::Vec3;
    use magdem::io::trajectory::{RunInfo, TrajectoryWriter};
    let scene = magdem::scene::Scene::parse(&scene_text(), "round trip").unwrap();
    let mut state = scene.initial_state();
    let value = |k: usize| ((k as f64 * 0.618_033_988_75).fract() - 0.5) * 1e-3;
    for (f, (name, vector)) in state.vectors_mut().into_iter().enumerate() {
        assert_eq!(vector.len(), 60, "{name}");
        for (i, v) in vector.iter_mut().enumerate() {
            *v = Vec3::from_fn(|c, _| value(1 + 3 * (i + 60 * f) + c));
        }
    }
    state.particles.has_permanent_moments = true;
    state.history.pairs = vec![((0, 3), Vec3::new(1e-9, -2e-9, 3e-9)), ((4, 59), Vec3::new(-1e-10, 0.0, 5e-10))].into();
    state.history.walls = vec![((2, 1), Vec3::new(0.0, 7e-10, -1e-10)), ((2, 4), Vec3::new(3e-11, 0.0, 0.0))];
    (state.step, state.time, state.next_substep) = (123_456, 1.23456e-3, Some(3.3e-10));
    // Renumbered (slots in reverse): the checkpoint keeps the slots and their ids.
    state.renumber(&magdem::core::renumber::Renumbering::new((0..60).rev().collect()));
    // The overlap diagnostics are not stored (the next evaluation sets them).
    state.diagnostics = Default::default();
    let work = workdir("round-trip");
    let file = work.path().join("round.h5");
    let info = RunInfo { engine: "magdem", integrator: "velocity-verlet" };
    let writer = TrajectoryWriter::create(&file, &(&scene).into(), &info).unwrap();
    writer.write_checkpoint(&state).unwrap();
    drop(writer);
    let (restored, _) = Trajectory::open(&file).unwrap().checkpoint().unwrap();
    for ((name, a), (_, b)) in state.vectors().into_iter().zip(restored.vectors()) {
        assert!(a == b, "{name} differs after the round trip");
    }
    assert!(restored == state, "the restored state differs from the written one");
}

/// `magdem info FILE | head` with the reader gone: the process ends by SIGPIPE, as other
/// command-line tools do, not with a panic in its printing.
#[test]
fn a_closed_output_pipe_ends_the_command_quietly() {
    use std::os::unix::process::ExitStatusExt;
    let (work, scene) = workdir_ending_at("pipe", "4.0e-5");
    let file = work.path().join("run.h5");
    assert!(magdem(&["run", path(&scene), "-q", "-o", path(&file)]).status.success());
    let mut child = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["analyse", path(&file)])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.signal(), Some(libc::SIGPIPE), "status {:?}", out.status);
}
