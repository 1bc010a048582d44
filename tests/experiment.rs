//! Experiments: sweeps expand to the Cartesian product, every point runs once, finished runs are
//! skipped, interrupted ones resumed, and a finished run whose scene changed is never silently
//! overwritten.

mod common;

use magdem::experiment::{run_experiment, run_order, ExperimentOptions, Outcome};
use magdem::scene::experiment::Experiment;
use std::path::PathBuf;
use std::process::Command;
use tempfile::TempDir;

fn base() -> String {
    common::scene(
        r#"version = 1
name = "tiny"
seed = 1
[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0e-4, 1.0e-4, 1.0e-4]
"#,
        r#"[[particles]]
species = "p"
count = 20
[forces.contact]
[forces.dipole]
induction = "paper"
cutoff_diameters = 4.0
[forces.drag]
[integration]
dt = 1.0e-8
end_time = 2.0e-5
[output]
interval = 2.0e-6
"#,
    )
}

/// An experiment file over one base scene in a fresh directory, removed when the guard drops.
fn setup(name: &str, sweep: &str) -> (TempDir, PathBuf, PathBuf) {
    let work = tempfile::Builder::new().prefix(&format!("magdem-exp-{name}-")).tempdir().unwrap();
    let dir = work.path();
    std::fs::write(dir.join("base.toml"), base()).unwrap();
    let out = dir.join("runs");
    let file = dir.join("experiment.toml");
    std::fs::write(
        &file,
        format!("name = \"{name}\"\nbases = [\"base.toml\"]\noutput = \"{}\"\n[sweep]\n{sweep}", out.display()),
    )
    .unwrap();
    (work, file, out)
}

#[test]
fn sweeps_run_once_skip_when_done_and_never_overwrite_changed_runs_silently() {
    let (_work, file, out) =
        setup("sweep", "seed = [1, 2]\n\"integration.dt\" = [1.0e-8, 2.0e-8]\n\"particles.0.count\" = [12]\n");
    let exp = Experiment::from_file(&file).unwrap();
    assert_eq!(exp.points.len(), 4);
    let ids: Vec<&str> = exp.points.iter().map(|p| p.id.as_str()).collect();
    assert!(ids.contains(&"base__dt-2e-8__count-12__seed-2"), "{ids:?}");
    assert_eq!(exp.points[0].scene.initial.len(), 12);
    let options = ExperimentOptions { jobs: Some(2), ..Default::default() };
    let first = run_experiment(&exp, &options).unwrap();
    assert!(
        first.iter().all(|r| r.outcome == Outcome::Completed),
        "{:?}",
        first.iter().map(|r| r.outcome.label()).collect::<Vec<_>>()
    );
    let manifest = std::fs::read_to_string(out.join("manifest.csv")).unwrap();
    assert_eq!(manifest.lines().count(), 5, "{manifest}");
    // The two seeds place particles differently.
    let t1 = magdem::io::trajectory::Trajectory::open(&first[0].file).unwrap().frame_vectors("position", 0).unwrap();
    let t2 = magdem::io::trajectory::Trajectory::open(&first[1].file).unwrap().frame_vectors("position", 0).unwrap();
    assert_ne!(t1, t2);

    let again = run_experiment(&exp, &options).unwrap();
    assert!(again.iter().all(|r| r.outcome == Outcome::Skipped));

    // The base scene changes: finished runs are kept and reported, unless overwriting is asked for.
    std::fs::write(file.parent().unwrap().join("base.toml"), base().replace("restitution = 0.5", "restitution = 0.6"))
        .unwrap();
    let changed = Experiment::from_file(&file).unwrap();
    let kept = run_experiment(&changed, &options).unwrap();
    assert!(kept.iter().all(|r| matches!(r.outcome, Outcome::KeptChanged { .. })));
    let replaced = run_experiment(&changed, &ExperimentOptions { overwrite_changed: true, ..options }).unwrap();
    assert!(replaced.iter().all(|r| r.outcome == Outcome::Completed));
}

#[test]
fn an_interrupted_point_is_resumed() {
    let (_work, file, out) = setup("resume", "seed = [3]\n");
    let exp = Experiment::from_file(&file).unwrap();
    let point = &exp.points[0];
    // Produce the point's file as a killed run would leave it.
    std::fs::create_dir_all(&out).unwrap();
    let scene_file = out.join("point.toml");
    std::fs::write(&scene_file, &point.scene.text).unwrap();
    let target = out.join(format!("{}.h5", point.id));
    let status = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["run", scene_file.to_str().unwrap(), "-q", "-o", target.to_str().unwrap(), "--abort-after-frame", "3"])
        .status()
        .unwrap();
    assert!(!status.success());
    let results = run_experiment(&exp, &ExperimentOptions::default()).unwrap();
    assert_eq!(results[0].outcome, Outcome::Resumed);
    let t = magdem::io::trajectory::Trajectory::open(&target).unwrap();
    assert_eq!(t.attr_string("status").unwrap(), "completed");
    assert_eq!(t.frames().unwrap(), 11);
}

#[test]
fn bad_sweeps_name_the_key() {
    for (sweep, fragment) in [
        ("\"particles.3.count\" = [5]\n", "sweep.particles.3.count"),
        ("seed = 4\n", "must be a non-empty list"),
        ("engine = [\"gromacs\"]\n", "sweep.engine"),
        ("\"integration.dt\" = [-1.0]\n", "integration.dt"),
    ] {
        let (_work, file, _) = setup("bad", sweep);
        let err = Experiment::from_file(&file).err().expect(sweep).to_string();
        assert!(err.contains(fragment), "{sweep}: {err}");
    }
}

#[test]
fn variants_cross_the_sweep_and_an_unstable_run_is_a_recorded_result() {
    let (_work, file, out) = setup("variants", "seed = [1, 2]\n");
    let text = std::fs::read_to_string(&file).unwrap();
    // `fast` overrides two keys; `blows-up` uses explicit Euler at a step far above its bound
    // (1e-6 s against ~7e-9 s in contact), which the solver must stop with its message.
    std::fs::write(
        &file,
        format!(
            "{text}\n[variants.fast]\n\"integration.dt\" = 2.0e-8\n\"particles.0.count\" = 8\n\
             [variants.blows-up]\n\"integration.scheme\" = \"explicit-euler\"\n\"integration.dt\" = 1.0e-6\n\"integration.end_time\" = 2.0e-3\n\
             \"field.b0\" = [1.5, 0.0, 0.0]\n\"particles.0.count\" = 40\n"
        ),
    )
    .unwrap();
    let exp = Experiment::from_file(&file).unwrap();
    assert_eq!(exp.points.len(), 4);
    let fast = exp.points.iter().find(|p| p.id == "base__fast__seed-2").expect("variant name in the id");
    assert_eq!(fast.variant.as_deref(), Some("fast"));
    assert_eq!(fast.scene.initial.len(), 8);
    assert_eq!(fast.scene.dt(), 2.0e-8);
    let results = run_experiment(&exp, &ExperimentOptions { jobs: Some(2), ..Default::default() }).unwrap();
    for (point, result) in exp.points.iter().zip(&results) {
        match point.variant.as_deref() {
            Some("fast") => assert_eq!(result.outcome, Outcome::Completed),
            _ => assert!(
                matches!(&result.outcome, Outcome::Unstable(why) if why.contains("stable dt")),
                "{}",
                result.outcome.label()
            ),
        }
    }
    // Rerunning does not retry the unstable runs: same scene, same outcome, from the file.
    let again = run_experiment(&exp, &ExperimentOptions::default()).unwrap();
    assert!(again.iter().all(|r| matches!(r.outcome, Outcome::Skipped | Outcome::Unstable(_))));
    let manifest = std::fs::read_to_string(out.join("manifest.csv")).unwrap();
    assert!(manifest.contains(",blows-up,") && manifest.contains("unstable:"), "{manifest}");
}

#[test]
fn bad_variants_name_the_key() {
    for (variant, fragment) in [
        ("[variants.x]\n\"integration.dt\" = -1.0\n", "integration.dt"),
        ("[variants.x]\nengine = \"lammps\"\n", "variants.x.engine"),
        ("[variants]\nx = 3\n", "variants.x"),
        ("[variants.\"a b\"]\nseed = 2\n", "names use letters"),
        ("[variants.mu-r-12.3]\n\"integration.dt\" = 1.0e-8\n", "[variants.\"mu-r-12.3\"]"),
    ] {
        let (_work, file, _) = setup("badvariant", "seed = [1]\n");
        let text = std::fs::read_to_string(&file).unwrap();
        std::fs::write(&file, format!("{text}\n{variant}")).unwrap();
        let err = Experiment::from_file(&file).err().expect(variant).to_string();
        assert!(err.contains(fragment), "{variant}: {err}");
    }
}

/// `kill -9` of `magdem experiment` mid-ensemble: every run it had finished stays finished (and
/// is skipped, its file untouched), and rerunning the experiment resumes the interrupted ones.
#[test]
fn a_killed_ensemble_loses_no_finished_run_and_resumes_the_rest() {
    let (_work, file, out) = setup("killed", "seed = [1, 2, 3, 4]\n");
    let text = std::fs::read_to_string(&file).unwrap();
    // Runs of about a second each, one at a time.
    std::fs::write(&file, format!("{text}\"integration.end_time\" = [2.0e-4]\n")).unwrap();
    let exp = Experiment::from_file(&file).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["experiment", file.to_str().unwrap(), "-j", "1", "-q"])
        .spawn()
        .unwrap();
    let status = |p: &magdem::scene::experiment::Point| {
        magdem::io::trajectory::Trajectory::open(&out.join(format!("{}.h5", p.id)))
            .ok()
            .and_then(|t| t.attr_string("status").ok())
    };
    let started = std::time::Instant::now();
    loop {
        let states: Vec<Option<String>> = exp.points.iter().map(status).collect();
        let done = states.iter().filter(|s| s.as_deref() == Some("completed")).count();
        if done >= 1 && states.iter().any(|s| s.as_deref() == Some("running")) {
            break;
        }
        assert!(
            started.elapsed().as_secs() < 120 && done < exp.points.len(),
            "no moment with a finished and a running point: {states:?}"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    Command::new("kill").args(["-9", &child.id().to_string()]).status().unwrap();
    child.wait().unwrap();
    let finished: Vec<(String, std::time::SystemTime)> = exp
        .points
        .iter()
        .filter(|p| status(p).as_deref() == Some("completed"))
        .map(|p| (p.id.clone(), std::fs::metadata(out.join(format!("{}.h5", p.id))).unwrap().modified().unwrap()))
        .collect();
    assert!(!finished.is_empty());
    let results = run_experiment(&exp, &ExperimentOptions { jobs: Some(1), ..Default::default() }).unwrap();
    for (r, p) in results.iter().zip(&exp.points) {
        match finished.iter().find(|(id, _)| id == &p.id) {
            Some((_, modified)) => {
                assert_eq!(r.outcome, Outcome::Skipped, "{}", p.id);
                assert_eq!(std::fs::metadata(&r.file).unwrap().modified().unwrap(), *modified, "{} untouched", p.id);
            }
            None => {
                assert!(matches!(r.outcome, Outcome::Resumed | Outcome::Completed), "{}: {}", p.id, r.outcome.label())
            }
        }
    }
    assert!(results.iter().any(|r| r.outcome == Outcome::Resumed), "the point running at the kill is resumed");
    assert!(exp.points.iter().all(|p| status(p).as_deref() == Some("completed")));
}

#[test]
fn equal_cost_points_start_seed_by_seed_after_the_expensive_ones() {
    let (_work, file, _out) = setup("order", "seed = [1, 2, 3]\n\"particles.0.count\" = [10, 20]\n");
    let exp = Experiment::from_file(&file).unwrap();
    let started: Vec<(usize, u64)> = run_order(std::slice::from_ref(&exp))
        .into_iter()
        .map(|(_, p)| (exp.points[p].scene.initial.len(), exp.points[p].scene.spec.seed))
        .collect();
    assert_eq!(started, [(20, 1), (20, 2), (20, 3), (10, 1), (10, 2), (10, 3)]);
}

#[test]
fn runs_a_digest_records_are_not_run_again_on_another_machine() {
    let (work, setup_file, out) = setup("digested", "seed = [1, 2]\n");
    // The experiment file in a directory of its own, as a report reads them.
    let experiments = work.path().join("experiments");
    std::fs::create_dir(&experiments).unwrap();
    let file = experiments.join("experiment.toml");
    std::fs::write(&file, std::fs::read_to_string(&setup_file).unwrap().replace("\"base.toml\"", "\"../base.toml\""))
        .unwrap();
    let exp = Experiment::from_file(&file).unwrap();
    let options = ExperimentOptions { jobs: Some(2), ..Default::default() };
    assert!(run_experiment(&exp, &options).unwrap().iter().all(|r| r.outcome == Outcome::Completed));
    // The runs are digested (`magdem report digests`); the trajectories then exist only where
    // they were made.
    let digests = work.path().join("digests");
    let changed = magdem::report::digest::update(&experiments, &digests, 1e-3).unwrap();
    assert_eq!(changed, vec!["digested".to_string()]);
    assert!(magdem::report::digest::update(&experiments, &digests, 1e-3).unwrap().is_empty(), "nothing new");
    std::fs::remove_dir_all(&out).unwrap();
    let with = ExperimentOptions { digests: vec![digests.clone()], ..options.clone() };
    let again = run_experiment(&exp, &with).unwrap();
    assert!(
        again.iter().all(|r| r.outcome == Outcome::Digested),
        "{:?}",
        again.iter().map(|r| r.outcome.label()).collect::<Vec<_>>()
    );
    assert!(again.iter().all(|r| !r.file.exists()), "nothing is run");
    // A changed base scene under the same run ids, and a seed the digest lacks, run.
    let base = work.path().join("base.toml");
    std::fs::write(&base, std::fs::read_to_string(&base).unwrap().replace("count = 20", "count = 18")).unwrap();
    std::fs::write(&file, std::fs::read_to_string(&file).unwrap().replace("seed = [1, 2]", "seed = [1, 2, 3]"))
        .unwrap();
    let changed = Experiment::from_file(&file).unwrap();
    let third = run_experiment(&changed, &with).unwrap();
    let labels: Vec<String> = third.iter().map(|r| r.outcome.label()).collect();
    assert!(third.iter().all(|r| r.outcome == Outcome::Completed), "{labels:?}");
}

/// `--dry-run` lists every point and runs nothing; a warning that every point's scene carries
/// (here a gradient that is not divergence-free) is printed once, with the number of points.
#[test]
fn a_dry_run_lists_the_points_and_each_warning_once() {
    let (work, file, out) = setup("dry", "seed = [1, 2, 3]\n");
    let base = work.path().join("base.toml");
    let text = std::fs::read_to_string(&base).unwrap();
    let gradient = "b0 = [0.4, 0.0, 0.0]\ngradient = [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]";
    std::fs::write(&base, text.replacen("b0 = [0.4, 0.0, 0.0]", gradient, 1)).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["experiment", "--dry-run", "--no-digests"])
        .arg(&file)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(stdout.lines().filter(|l| l.contains(".h5  20 particles")).count(), 3, "{stdout}");
    let warnings: Vec<&str> = stdout.lines().filter(|l| l.contains("warning")).collect();
    assert_eq!(warnings.len(), 1, "{stdout}");
    assert!(warnings[0].contains("(3 points)") && warnings[0].contains("divergence"), "{stdout}");
    assert!(!out.exists(), "a dry run writes nothing");
}

/// Two files of one experiment (the same name: the second continues the first's seeds) run
/// together write their runs into one directory, and its manifest lists both files' points; a
/// later call of one file keeps the other's rows.
#[test]
fn files_continuing_one_experiment_share_its_manifest() {
    let (work, file, out) = setup("continued", "seed = [1]\n");
    let more = work.path().join("more.toml");
    std::fs::write(&more, std::fs::read_to_string(&file).unwrap().replace("seed = [1]", "seed = [2, 3]")).unwrap();
    let experiments = [Experiment::from_file(&file).unwrap(), Experiment::from_file(&more).unwrap()];
    let options = ExperimentOptions { jobs: Some(2), ..Default::default() };
    let results = magdem::experiment::run_experiments(&experiments, &options).unwrap();
    assert!(results.iter().flatten().all(|r| r.outcome == Outcome::Completed));
    let manifest = std::fs::read_to_string(out.join("manifest.csv")).unwrap();
    for seed in 1..=3 {
        assert!(manifest.contains(&format!("seed-{seed}\"")), "seed {seed} missing from\n{manifest}");
    }
    assert_eq!(manifest.lines().count(), 4, "a header and three runs:\n{manifest}");
    // Running one of the files again keeps the other's rows, and lists its own once.
    magdem::experiment::run_experiment(&experiments[1], &options).unwrap();
    let again = std::fs::read_to_string(out.join("manifest.csv")).unwrap();
    assert!(again.contains("seed-1\"") && again.lines().count() == 4, "{again}");
    // A run listed by both files would be written by two workers at once: refused, nothing run.
    std::fs::write(&more, std::fs::read_to_string(&more).unwrap().replace("seed = [2, 3]", "seed = [3, 4]")).unwrap();
    std::fs::write(&file, std::fs::read_to_string(&file).unwrap().replace("seed = [1]", "seed = [1, 3]")).unwrap();
    let overlapping = [Experiment::from_file(&file).unwrap(), Experiment::from_file(&more).unwrap()];
    let Err(err) = magdem::experiment::run_experiments(&overlapping, &options) else { panic!("overlapping files ran") };
    let err = err.to_string();
    assert!(err.contains("seed-3") && err.contains("two experiment files"), "{err}");
    let seed_4 = overlapping[1].points.iter().find(|p| p.id.ends_with("seed-4")).expect("seed 4");
    assert!(!out.join(format!("{}.h5", seed_4.id)).exists(), "nothing is run");
}
