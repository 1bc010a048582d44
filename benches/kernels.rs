//! Criterion benchmarks of the solver's kernels: one force term at a time and a full step, at
//! several particle counts, single-threaded. `cargo bench --bench kernels` (add `-- --quick` for
//! a fast pass); `magdem bench` compares whole runs against LIGGGHTS and LAMMPS.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use magdem::bench::{contact_scene, magnetic_scene, Packing};
use magdem::scene::Scene;

/// Case-1 parameters at 4.5 mg/ml with every term of the paper (box scaled to `n` particles).
fn case1(n: usize) -> Scene {
    let scale = (n as f64 / 307.0).cbrt();
    let (l, h) = (3.96e-4 * scale, 3.3e-4 * scale);
    let text = format!(
        "version = 1\nseed = 1\n[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [{l:e}, {l:e}, {h:e}]\n[fluid]\ndensity = 1000.0\nviscosity = 1.0e-3\n\
         [field]\nb0 = [0.4, 0.0, 0.0]\n[[species]]\nname = \"p\"\ndiameter = 11.0e-6\ndensity = 1087.0\nyoungs_modulus = 1.0e9\n\
         poisson_ratio = 0.5\nfriction = 0.5\nrestitution = 0.5\nrelative_permeability = 12.3\n[[particles]]\nspecies = \"p\"\ncount = {n}\n\
         [forces.contact]\nwalls = true\n[forces.dipole]\ninduction = \"paper\"\ncutoff_diameters = 15.0\n\
         [forces.drag]\nlaw = \"schiller-naumann\"\nshielding = \"paper\"\n[forces.gravity]\ng = [0.0, 0.0, -9.81]\n\
         [integration]\nscheme = \"velocity-verlet\"\ndt = 1.0e-8\nend_time = 1.0e-3\n[output]\ninterval = 1.0e-3\n"
    );
    Scene::parse(&text, "bench case 1").unwrap()
}

fn single_thread<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(f)
}

/// Each force term of the case-1 scene alone (the moments phase runs with the magnetic terms).
fn force_terms(c: &mut Criterion) {
    let mut group = c.benchmark_group("force term");
    for n in [300, 3000, 30000] {
        let scene = case1(n);
        group.throughput(Throughput::Elements(n as u64));
        for term in ["contact", "dipole", "drag", "gravity"] {
            let mut sim = scene.simulation(None);
            sim.initialise().unwrap();
            // The dipole case keeps the moments it reads (computed in every evaluation).
            sim.field.terms.retain(|t| t.name() == term || (term == "dipole" && t.name() == "moments"));
            group.bench_with_input(BenchmarkId::new(term, n), &n, |b, _| {
                single_thread(|| b.iter(|| sim.field.evaluate(&mut sim.state, 1e-8)));
            });
        }
    }
    group.finish();
}

/// A full velocity-Verlet step: the contact-only scenes and case 1 with every term.
fn steps(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    for n in [300, 3000, 30000] {
        let scenes = [
            ("contact dilute", Scene::parse(&contact_scene(Packing::Dilute, n, 1000), "bench").unwrap()),
            ("contact loose", Scene::parse(&contact_scene(Packing::Loose, n, 1000), "bench").unwrap()),
            ("contact packed", Scene::parse(&contact_scene(Packing::Packed, n, 1000), "bench").unwrap()),
            ("case 1", case1(n)),
        ];
        for (name, scene) in scenes {
            // The packed bed's lattice holds about n particles.
            group.throughput(Throughput::Elements(scene.initial.len() as u64));
            let mut sim = scene.simulation(None);
            sim.initialise().unwrap();
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                single_thread(|| b.iter(|| sim.step().unwrap()))
            });
        }
    }
    group.finish();
}

/// The dipole sum alone over all pairs (fixed moments), as `magdem bench` times it.
fn dipole_all_pairs(c: &mut Criterion) {
    let mut group = c.benchmark_group("dipole all pairs");
    for n in [300, 1000, 3000] {
        let scene = Scene::parse(&magnetic_scene(n, None, 1), "bench").unwrap();
        let mut sim = scene.simulation(None);
        sim.initialise().unwrap();
        group.throughput(Throughput::Elements((n * (n - 1) / 2) as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            single_thread(|| b.iter(|| sim.field.evaluate(&mut sim.state, 1e-8)))
        });
    }
    group.finish();
}

criterion_group!(benches, force_terms, steps, dipole_all_pairs);
criterion_main!(benches);
