//! Wall-clock time per named phase of the step (neighbours, moments, each force term, ...).

use std::time::{Duration, Instant};

#[derive(Debug, Default, Clone)]
pub struct PhaseTimers {
    phases: Vec<(&'static str, Duration)>,
}

impl PhaseTimers {
    /// Runs `f`, adding its duration to phase `name`.
    pub fn time<R>(&mut self, name: &'static str, f: impl FnOnce() -> R) -> R {
        let start = Instant::now();
        let result = f();
        self.add(name, start.elapsed());
        result
    }

    pub fn add(&mut self, name: &'static str, elapsed: Duration) {
        match self.phases.iter_mut().find(|(n, _)| *n == name) {
            Some((_, d)) => *d += elapsed,
            None => self.phases.push((name, elapsed)),
        }
    }

    pub fn get(&self, name: &str) -> Duration {
        self.phases.iter().find(|(n, _)| *n == name).map(|(_, d)| *d).unwrap_or_default()
    }

    pub fn phases(&self) -> &[(&'static str, Duration)] {
        &self.phases
    }
}
