//! Repeated measurements: their min, median and max, and wall-time repetitions of a closure.
//! The one helper `bench`, `study` and `report` all time with.

/// Min, median and max of repeated measurements.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
}

impl Spread {
    /// The spread of `values` (at least one); an even count takes the mean of the middle two.
    pub fn of(values: &[f64]) -> Self {
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let median = if v.len() % 2 == 1 { v[v.len() / 2] } else { 0.5 * (v[v.len() / 2 - 1] + v[v.len() / 2]) };
        Spread { min: v[0], median, max: v[v.len() - 1] }
    }
}

/// Wall times of `runs` repetitions of `f` (at least one): its last result and their spread (s).
pub fn timed<T>(runs: usize, mut f: impl FnMut() -> T) -> (T, Spread) {
    let mut times = vec![];
    let mut out = None;
    for _ in 0..runs {
        let start = std::time::Instant::now();
        out = Some(f());
        times.push(start.elapsed().as_secs_f64());
    }
    (out.expect("at least one run"), Spread::of(&times))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_takes_the_middle_of_an_even_count() {
        let s = Spread::of(&[4.0, 1.0, 3.0, 2.0]);
        assert_eq!((s.min, s.median, s.max), (1.0, 2.5, 4.0));
        assert_eq!(Spread::of(&[5.0, 1.0, 3.0]).median, 3.0);
    }

    #[test]
    fn timed_repeats_and_returns_the_last_result() {
        let mut calls = 0;
        let (last, spread) = timed(3, || {
            calls += 1;
            calls
        });
        assert_eq!((last, calls), (3, 3));
        assert!(spread.min <= spread.median && spread.median <= spread.max);
    }
}
