//! `magdem validate`, `magdem deck` and the files route's hidden `magdem magnetic-forces`.

use super::{fail, load};
use magdem::reference::{self, Engine};
use magdem::scene::Scene;
use std::path::Path;
use std::process::ExitCode;

/// `magdem validate SCENE`: the scene's particles, terms and step estimates, without running it.
pub fn validate(path: &Path) -> ExitCode {
    let scene = match load(path) {
        Ok(s) => s,
        Err(code) => return code,
    };
    describe(&scene);
    ExitCode::SUCCESS
}

fn describe(scene: &Scene) {
    let s = &scene.spec;
    println!("scene {} ({})", s.name.as_deref().unwrap_or("unnamed"), &scene.hash[..12]);
    println!("  particles: {}  box: {:?} .. {:?}", scene.initial.len(), s.domain.lo, s.domain.hi);
    println!("  terms: {}", s.forces.names().join(", "));
    println!(
        "  integrator {}: {} steps, a frame every {} steps",
        s.integration.scheme,
        scene.total_steps(),
        scene.steps_per_frame()
    );
    println!("  {}", scene.estimate.summary(scene.dt()));
    for w in &scene.warnings {
        println!("  warning: {w}");
    }
}

/// `magdem deck SCENE --engine E -o DIR`: the scene as a LIGGGHTS or LAMMPS input deck.
pub fn deck(path: &Path, engine: Engine, output: &Path, native: bool) -> ExitCode {
    let scene = match load(path) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let coupling = if native { reference::deck::Coupling::Native } else { reference::deck::Coupling::Callback };
    match reference::deck::write_with(engine, &scene, output, &coupling) {
        Ok(deck) => {
            println!(
                "wrote {}, its fix.* include files and {} in {}",
                deck.input.display(),
                deck.data.display(),
                output.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => fail(e, 2),
    }
}

/// `magdem magnetic-forces SCENE POSITIONS PREFIX`: the files route's force evaluation.
pub fn magnetic_forces(path: &Path, positions: &Path, prefix: &Path) -> ExitCode {
    let scene = match load(path) {
        Ok(s) => s,
        Err(code) => return code,
    };
    match reference::files_route::magnetic_forces(&scene, positions, prefix) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e, 1),
    }
}
