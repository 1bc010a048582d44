//! Records the git commit the binary was built from (written into every trajectory) and, with the
//! `liggghts-shim` feature, builds the LIGGGHTS callback shim as a shared object.
use std::path::PathBuf;
use std::process::Command;

fn main() {
    let commit = Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    let dirty = Command::new("git")
        .args(["status", "--porcelain", "--untracked-files=no"])
        .output()
        .ok()
        .is_some_and(|o| !o.stdout.is_empty());
    println!("cargo:rustc-env=MAGDEM_GIT_COMMIT={commit}{}", if dirty { "-dirty" } else { "" });
    println!("cargo:rerun-if-changed=.git/HEAD");
    println!("cargo:rerun-if-changed=.git/index");

    let shim = "src/reference/shim/liggghts_shim.cpp";
    println!("cargo:rerun-if-changed={shim}");
    if std::env::var_os("CARGO_FEATURE_LIGGGHTS_SHIM").is_some() {
        let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("libmagdem_liggghts_shim.so");
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
        println!("cargo:rustc-env=MAGDEM_LIGGGHTS_SHIM={}", out.display());
    }
}
