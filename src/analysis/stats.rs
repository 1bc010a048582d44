//! Summary statistics: mean, population and sample standard deviation, and the 95% confidence
//! interval of a mean over independent runs (Student's t, statrs).

use statrs::distribution::{ContinuousCDF, StudentsT};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    pub n: usize,
    pub mean: f64,
    /// √(Σ(x − x̄)²/n): what the paper's Table 3 uses (its 4.5 mg/ml row is reproduced only so).
    pub population_std: f64,
    /// √(Σ(x − x̄)²/(n − 1)).
    pub sample_std: f64,
}

pub fn summary(values: &[f64]) -> Summary {
    let n = values.len();
    // No values, no mean (NaN, so that an empty set is never averaged in as zero).
    let mean = if n > 0 { values.iter().sum::<f64>() / n as f64 } else { f64::NAN };
    let ss: f64 = values.iter().map(|v| (v - mean).powi(2)).sum();
    Summary {
        n,
        mean,
        population_std: if n > 0 { (ss / n as f64).sqrt() } else { f64::NAN },
        sample_std: if n > 1 { (ss / (n - 1) as f64).sqrt() } else { f64::NAN },
    }
}

/// Half-width of the 95% confidence interval of the mean of `values` (independent samples).
pub fn ci95_half_width(values: &[f64]) -> f64 {
    let s = summary(values);
    if s.n < 2 {
        return f64::NAN;
    }
    let t = StudentsT::new(0.0, 1.0, (s.n - 1) as f64).expect("valid degrees of freedom").inverse_cdf(0.975);
    t * s.sample_std / (s.n as f64).sqrt()
}

/// Least-squares line y = a + b x through `points`: the slope b and the half-width of its 95%
/// confidence interval, t(0.975, n − 2) √(Σr²/(n − 2) / Σ(x − x̄)²) (NaN with fewer than three
/// points or without spread in x).
pub fn slope_ci95(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len();
    if n < 3 {
        return (f64::NAN, f64::NAN);
    }
    let (mx, my) =
        (points.iter().map(|p| p.0).sum::<f64>() / n as f64, points.iter().map(|p| p.1).sum::<f64>() / n as f64);
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return (f64::NAN, f64::NAN);
    }
    let b = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / sxx;
    let residuals: f64 = points.iter().map(|p| (p.1 - my - b * (p.0 - mx)).powi(2)).sum();
    let t = StudentsT::new(0.0, 1.0, (n - 2) as f64).expect("valid degrees of freedom").inverse_cdf(0.975);
    (b, t * (residuals / (n - 2) as f64 / sxx).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textbook_values() {
        let s = summary(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(s.mean, 5.0);
        assert_eq!(s.population_std, 2.0);
        assert!((s.sample_std - (32.0_f64 / 7.0).sqrt()).abs() < 1e-15);
        // t(0.975, 7) = 2.364624...
        let h = ci95_half_width(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert!((h - 2.364624251592785 * s.sample_std / 8.0_f64.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn slope_of_a_line_and_its_interval() {
        // Exact line: slope 0.5, no residual, zero-width interval.
        let exact: Vec<(f64, f64)> = (0..5).map(|k| (k as f64, 1.0 + 0.5 * k as f64)).collect();
        let (b, ci) = slope_ci95(&exact);
        assert!((b - 0.5).abs() < 1e-15 && ci.abs() < 1e-12);
        // y = 0, 1, 0, 1 at x = 0..3: b = 0.2, Σr² = 0.8, Σ(x − x̄)² = 5, t(0.975, 2) = 4.302653.
        let (b, ci) = slope_ci95(&[(0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (3.0, 1.0)]);
        assert!((b - 0.2).abs() < 1e-15);
        assert!((ci - 4.302652729911275 * (0.8_f64 / 2.0 / 5.0).sqrt()).abs() < 1e-9);
        assert!(slope_ci95(&[(1.0, 1.0), (1.0, 2.0), (1.0, 3.0)]).0.is_nan());
    }
}
