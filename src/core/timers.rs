//! Wall-clock time per named phase of the step (neighbours, moments, each force term, ...).
//!
//! Off by default: reading the clock costs ~20 ns, several times per step, which is a few per
//! cent of a small scene's step. `magdem run --timings` and `magdem bench`'s profile switch it on.

use std::time::{Duration, Instant};

#[derive(Debug, Default, Clone)]
pub struct PhaseTimers {
    enabled: bool,
    phases: Vec<(&'static str, Duration)>,
}

impl PhaseTimers {
    pub fn enabled() -> Self {
        Self { enabled: true, phases: vec![] }
    }

    /// The current time when timing is on.
    pub fn start(&self) -> Option<Instant> {
        self.enabled.then(Instant::now)
    }

    /// Adds the time since `started` (from [`Self::start`]) to phase `name`.
    pub fn stop(&mut self, name: &'static str, started: Option<Instant>) {
        if let Some(t0) = started {
            self.add(name, t0.elapsed());
        }
    }

    /// Runs `f`, adding its duration to phase `name`.
    pub fn time<R>(&mut self, name: &'static str, f: impl FnOnce() -> R) -> R {
        let started = self.start();
        let result = f();
        self.stop(name, started);
        result
    }

    pub fn add(&mut self, name: &'static str, elapsed: Duration) {
        match self.phases.iter_mut().find(|(n, _)| *n == name) {
            Some((_, d)) => *d += elapsed,
            None => self.phases.push((name, elapsed)),
        }
    }

    pub fn phases(&self) -> &[(&'static str, Duration)] {
        &self.phases
    }
}
