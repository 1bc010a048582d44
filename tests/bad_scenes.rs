//! Invalid scenes are refused with a one-line message naming the key, the value and why; the CLI
//! exits with code 2. The corpus is `tests/data/bad/` (one file per case, the expected fragments
//! in its `expected.txt`); a seeded mutation fuzzer runs the shipped scenes through 10 000
//! random edits, none of which may panic.

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

fn corpus() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bad")
}

/// The corpus `tests/data/bad/*.toml` with each file's expected fragments (`expected.txt`).
fn cases() -> Vec<(String, Vec<String>)> {
    let text = std::fs::read_to_string(corpus().join("expected.txt")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let (name, fragments) = l.split_once(": ").unwrap();
            (name.to_string(), fragments.split(" | ").map(str::to_string).collect())
        })
        .collect()
}

#[test]
fn every_bad_scene_of_the_corpus_is_refused_with_a_message_naming_the_cause() {
    let cases = cases();
    let files = std::fs::read_dir(corpus())
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().extension().is_some_and(|x| x == "toml"))
        .count();
    assert_eq!(cases.len(), files, "every corpus file has its expectation, and no expectation lacks its file");
    assert!(cases.len() >= 40, "{} cases", cases.len());
    for (name, expected) in &cases {
        let err = Scene::from_file(&corpus().join(name)).expect_err(name).to_string();
        println!("{name}: {err}");
        assert!(!err.contains('\n'), "{name}: message is not one line: {err}");
        for fragment in expected {
            assert!(err.contains(fragment.as_str()), "{name}: {err:?} lacks {fragment:?}");
        }
    }
}

/// `validate` and `run` refuse the same scenes with the same one-line message and code 2, and
/// `run` writes nothing: a zero step, a run of more steps than an f64 counts exactly, no particles.
#[test]
fn validate_and_run_refuse_alike_with_code_2_and_one_line() {
    let zero_count = "positions = [[2.0e-5, 5.0e-5, 5.0e-5], [8.0e-5, 5.0e-5, 5.0e-5]]";
    for (from, to, expected) in [
        ("dt = 1.0e-8", "dt = 0.0", "integration.dt = 0"),
        ("end_time = 1.0e-6", "end_time = 1.0e300", "integration.end_time = 1e300"),
        (zero_count, "count = 0", "particles[0].count = 0: the scene places no particles"),
    ] {
        let work = tempfile::Builder::new().prefix("magdem-bad-").tempdir().unwrap();
        let dir = work.path();
        let path = dir.join("bad.toml");
        std::fs::write(&path, edit(from, to)).unwrap();
        let (scene, output) = (path.to_str().unwrap(), dir.join("x.h5"));
        let runs: [(&str, Vec<&str>); 2] =
            [("validate", vec!["validate", scene]), ("run", vec!["run", scene, "-q", "-o", output.to_str().unwrap()])];
        let mut messages = vec![];
        for (sub, args) in runs {
            let out = Command::new(env!("CARGO_BIN_EXE_magdem")).args(&args).output().unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr).trim().to_string();
            assert_eq!(out.status.code(), Some(2), "{sub}: {stderr}");
            assert_eq!(stderr.lines().count(), 1, "{sub}: {stderr}");
            assert!(stderr.contains(expected), "{sub}: {stderr}");
            messages.push(stderr);
        }
        assert_eq!(messages[0], messages[1]);
        assert!(!output.exists(), "{to}: run wrote {}", output.display());
    }
}

/// A run whose frames alone exceed the free space of its disk is refused before it writes
/// anything: an fcc bed of a few hundred particles, 1e12 frames of ~1e4 bytes (~1e16 bytes).
#[test]
fn a_run_larger_than_its_disk_is_refused_before_writing() {
    let work = tempfile::Builder::new().prefix("magdem-disk-").tempdir().unwrap();
    let dir = work.path();
    let path = dir.join("huge.toml");
    let positions = "positions = [[2.0e-5, 5.0e-5, 5.0e-5], [8.0e-5, 5.0e-5, 5.0e-5]]";
    let text = edit(positions, "lattice = { kind = \"fcc\" }")
        .replace("end_time = 1.0e-6", "end_time = 1.0e4\n[output]\ninterval = 1.0e-8");
    std::fs::write(&path, text).unwrap();
    let output = dir.join("huge.h5");
    let out = Command::new(env!("CARGO_BIN_EXE_magdem"))
        .args(["run", path.to_str().unwrap(), "-q", "-o", output.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("integration.end_time") && stderr.contains("output.interval"), "{stderr}");
    assert!(stderr.contains("bytes free"), "{stderr}");
    assert!(std::fs::read_dir(dir).unwrap().count() == 1, "run wrote into {}", dir.display());
}

#[test]
fn the_cli_refuses_every_corpus_scene_with_code_2_and_one_line() {
    for (name, _) in cases().iter().step_by(5) {
        let path = corpus().join(name);
        let out =
            Command::new(env!("CARGO_BIN_EXE_magdem")).args(["validate", path.to_str().unwrap()]).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{name}: {stderr}");
    }
}

/// One random edit of a scene's text: drop a line, replace a number by NaN, ±inf, 0, its
/// negative or 1e300, or swap a value's type.
fn mutate(text: &str, rng: &mut rand_chacha::ChaCha8Rng) -> String {
    use rand::RngExt;
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let k = rng.random_range(0..lines.len());
    let numbers = |line: &str| -> Vec<(usize, usize)> {
        let bytes = line.as_bytes();
        let mut spans = vec![];
        let mut i = 0;
        while i < bytes.len() {
            let starts =
                bytes[i].is_ascii_digit() && (i == 0 || !bytes[i - 1].is_ascii_alphanumeric() && bytes[i - 1] != b'_');
            if starts {
                let j = (i..bytes.len())
                    .find(|&j| !(bytes[j].is_ascii_alphanumeric() || b".+-_".contains(&bytes[j])))
                    .unwrap_or(bytes.len());
                spans.push((i, j));
                i = j;
            } else {
                i += 1;
            }
        }
        spans
    };
    match rng.random_range(0..4) {
        0 => {
            lines.remove(k);
        }
        1 | 2 => {
            let spans = numbers(&lines[k]);
            if let Some(&(a, b)) = spans.get(rng.random_range(0..spans.len().max(1))) {
                let old = lines[k][a..b].to_string();
                let new = [
                    "nan",
                    "inf",
                    "-inf",
                    "0",
                    "0.0",
                    &format!("-{old}"),
                    "1e300",
                    "-1e300",
                    "1e-300",
                    "\"x\"",
                    "[1.0]",
                    "true",
                ][rng.random_range(0..12)]
                .to_string();
                lines[k].replace_range(a..b, &new);
            }
        }
        _ => {
            if let Some((key, value)) = lines[k].split_once(" = ") {
                let swapped = if value.starts_with('"') {
                    "1.0".to_string()
                } else if value.starts_with('[') {
                    "0.5".into()
                } else {
                    format!("\"{value}\"")
                };
                lines[k] = format!("{key} = {swapped}");
            }
        }
    }
    lines.join("\n")
}

#[test]
fn ten_thousand_random_edits_of_the_shipped_scenes_never_panic() {
    use rand::SeedableRng;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("experiments/scenes");
    let mut scenes: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| std::fs::read_to_string(e.unwrap().path()).unwrap()).collect();
    scenes.sort();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let (mut valid, mut refused) = (0, 0);
    let cases = 10_000;
    for case in 0..cases {
        let mut text = scenes[case % scenes.len()].clone();
        for _ in 0..1 + case % 3 {
            text = mutate(&text, &mut rng);
        }
        match std::panic::catch_unwind(|| Scene::parse(&text, "fuzz.toml").map(|_| ()).map_err(|e| e.to_string())) {
            Ok(Ok(())) => valid += 1,
            Ok(Err(message)) => {
                assert!(
                    !message.contains('\n') && !message.is_empty(),
                    "case {case}: not one line: {message:?}\n{text}"
                );
                refused += 1;
            }
            Err(_) => panic!("case {case} panicked on:\n{text}"),
        }
    }
    println!("{cases} mutated scenes: {valid} valid, {refused} refused with one line");
    assert_eq!(valid + refused, cases);
    assert!(
        refused > cases / 4 && valid > cases / 20,
        "the mutations reach both outcomes: {valid} valid, {refused} refused"
    );
}
