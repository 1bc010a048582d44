//! Records the git commit the binary was built from (written into every trajectory), lists the
//! reference engines (one file each in `src/reference/engines/`) and, with the `liggghts-shim`
//! feature, builds the LIGGGHTS callback shim as a shared object.
use std::path::PathBuf;
use std::process::Command;

/// What the binary is built from: its sources. A dirty file elsewhere (a report, a run) does not
/// change the binary, and `.git/index` is not watched: `git status` rewrites it, so watching it
/// rebuilt magdem after every `git status`.
const SOURCES: &[&str] = &["src", "templates", "Cargo.toml", "Cargo.lock", "build.rs"];

fn main() {
    let commit = Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    let dirty = Command::new("git")
        .args(["status", "--porcelain", "--untracked-files=no", "--"])
        .args(SOURCES)
        .output()
        .ok()
        .is_some_and(|o| !o.stdout.is_empty());
    println!("cargo:rustc-env=MAGDEM_GIT_COMMIT={commit}{}", if dirty { "-dirty" } else { "" });
    // A new commit moves HEAD or a branch ref (loose or packed); a path that does not exist
    // would rerun this script on every build, so only existing ones are watched.
    for path in [".git/HEAD", ".git/refs/heads", ".git/packed-refs"].iter().chain(SOURCES) {
        if std::path::Path::new(path).exists() {
            println!("cargo:rerun-if-changed={path}");
        }
    }

    engines();

    let shim = "src/reference/shim/liggghts_shim.cpp";
    println!("cargo:rerun-if-changed={shim}");
    if std::env::var_os("CARGO_FEATURE_LIGGGHTS_SHIM").is_some() {
        let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("libmagdem_liggghts_shim.so");
        println!("cargo:rustc-env=MAGDEM_LIGGGHTS_SHIM={}", out.display());
        let modified = |p: &std::path::Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
        if modified(&out).is_some_and(|built| modified(shim.as_ref()).is_some_and(|source| built > source)) {
            return;
        }
        // The cc crate finds the C++ compiler and its flags; the shim is linked as a shared object.
        let compiler = cc::Build::new().cpp(true).get_compiler();
        let status = compiler
            .to_command()
            .args(["-shared", "-fPIC", "-O2", "-DOMPI_SKIP_MPICXX", "-I/usr/include/liggghts"])
            .arg("-I/usr/lib/x86_64-linux-gnu/openmpi/include")
            .arg(shim)
            .args(["-o", out.to_str().unwrap(), "-lliggghts"])
            .status()
            .expect("run the C++ compiler");
        assert!(status.success(), "building the LIGGGHTS shim failed (is libliggghts-dev installed?)");
    }
}

/// `$OUT_DIR/engines.rs`, included by `src/reference/mod.rs`: a module per file of
/// `src/reference/engines/` (each defines `ENGINE`, its `Dialect`) and `ALL`, every engine in
/// file-name order. A new engine is its file, nothing else.
fn engines() {
    let dir = std::path::Path::new("src/reference/engines");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("src/reference/engines")
        .filter_map(|e| e.ok()?.file_name().into_string().ok()?.strip_suffix(".rs").map(String::from))
        .collect();
    names.sort();
    let root = std::env::var("CARGO_MANIFEST_DIR").unwrap();
    let mut code = String::new();
    for name in &names {
        code += &format!("#[path = \"{root}/src/reference/engines/{name}.rs\"]\npub mod {name};\n");
    }
    let all: Vec<String> = names.iter().map(|n| format!("Engine(&{n}::ENGINE)")).collect();
    code += &format!("/// Every engine, in file-name order.\npub static ALL: &[Engine] = &[{}];\n", all.join(", "));
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("engines.rs");
    if std::fs::read_to_string(&out).ok().as_deref() != Some(code.as_str()) {
        std::fs::write(out, code).expect("write engines.rs");
    }
}
