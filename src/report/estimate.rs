//! Estimates over independent runs: a mean with its CI95, paired and unpaired relative changes
//! between ensembles, and the size–velocity law of aggregates. Shared by the reports.

use super::runs::Run;
use crate::analysis::stats::{ci95_half_width, summary};
use std::collections::BTreeMap;

/// A mean over independent runs and its 95 % confidence half-width.
#[derive(Debug, Clone, Copy, serde::Serialize)]
pub struct Estimate {
    pub n: usize,
    pub mean: f64,
    pub ci95: f64,
}

impl Estimate {
    pub fn of(values: &[f64]) -> Self {
        let values: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
        let mean = if values.is_empty() { f64::NAN } else { summary(&values).mean };
        Self { n: values.len(), mean, ci95: ci95_half_width(&values) }
    }

    /// "mean ± CI95" with `digits` decimals ("mean (n = …)" without a CI, "–" without a mean).
    pub fn cell(&self, digits: usize) -> String {
        match (self.mean.is_finite(), self.ci95.is_finite()) {
            (false, _) => "–".into(),
            (true, false) => format!("{:.digits$} (n = {})", self.mean, self.n),
            (true, true) => format!("{:.digits$} ± {:.digits$}", self.mean, self.ci95),
        }
    }

    /// A change as "+mean ± CI95" with `digits` decimals ("+mean" without a CI: one run or seed).
    pub fn signed_cell(&self, digits: usize) -> String {
        match (self.mean.is_finite(), self.ci95.is_finite()) {
            (false, _) => "–".into(),
            (true, false) => format!("{:+.digits$}", self.mean),
            (true, true) => format!("{:+.digits$} ± {:.digits$}", self.mean, self.ci95),
        }
    }
}

/// Paired relative change of `b` against `a` (%), matched by seed: each seed's
/// 100 (b_s − a_s)/ā, mean ± CI95 over the seeds both have.
pub fn paired(a: &[&Run], b: &[&Run], value: impl Fn(&Run) -> f64) -> Estimate {
    let pairs: Vec<(f64, f64)> =
        a.iter().filter_map(|ra| b.iter().find(|rb| rb.seed == ra.seed).map(|rb| (value(ra), value(rb)))).collect();
    let reference = Estimate::of(&pairs.iter().map(|p| p.0).collect::<Vec<_>>()).mean;
    Estimate::of(&pairs.iter().map(|(x, y)| 100.0 * (y - x) / reference).collect::<Vec<_>>())
}

/// [`paired`] on the runs' mean lengths.
pub fn paired_change(a: &[&Run], b: &[&Run]) -> Estimate {
    paired(a, b, |r| r.mean_length_um())
}

/// Relative change of the mean of `b` against the mean of `a` (%) for unpaired ensembles, with
/// the half-width √(CI_a² + CI_b²)/ā (conservative for independent means).
pub fn unpaired(a: &[f64], b: &[f64]) -> Estimate {
    let (ea, eb) = (Estimate::of(a), Estimate::of(b));
    Estimate {
        n: ea.n.min(eb.n),
        mean: 100.0 * (eb.mean / ea.mean - 1.0),
        ci95: 100.0 * ea.ci95.hypot(eb.ci95) / ea.mean,
    }
}

/// Per run: the mean size of its last frame's aggregates, and the tracked velocities (µm/s) of
/// the free ones (no x wall holding them) with their sizes.
pub fn sizes_and_velocities(r: &Run) -> (f64, Vec<(usize, f64)>) {
    let size = summary(&r.last.iter().map(|a| a.size() as f64).collect::<Vec<_>>()).mean;
    let free = r.last.iter().filter(|a| !a.at_x_wall).map(|a| (a.size, a.tracked_vx * 1e6)).collect();
    (size, free)
}

/// Least-squares slope of ln v against ln n over the per-size means (sizes with ≥ 3 aggregates).
pub fn log_slope(by_size: &BTreeMap<usize, Vec<f64>>) -> f64 {
    let pts: Vec<(f64, f64)> = by_size
        .iter()
        .filter(|(_, v)| v.len() >= 3)
        .map(|(&n, v)| (n as f64, summary(v).mean))
        .filter(|&(_, v)| v > 0.0)
        .map(|(n, v)| (n.ln(), v.ln()))
        .collect();
    if pts.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64,
        pts.iter().map(|p| p.1).sum::<f64>() / pts.len() as f64,
    );
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}
