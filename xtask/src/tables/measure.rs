//! Wall-clock measurement: the median over several runs of the mean time of one call.

use std::time::{Duration, Instant};

/// How long and how often to measure one operation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Each run lasts at least this long (the iteration count is calibrated to it).
    pub run: Duration,
    /// Runs whose per-call times give the median.
    pub runs: usize,
}

impl Budget {
    /// The default of a full `cargo xtask tables`: 5 runs of at least 10 ms each.
    pub fn full() -> Budget {
        Budget {
            run: Duration::from_millis(10),
            runs: 5,
        }
    }

    /// A quick budget for smoke tests: 3 runs of at least 0.2 ms.
    pub fn quick() -> Budget {
        Budget {
            run: Duration::from_micros(200),
            runs: 3,
        }
    }
}

/// Median over `budget.runs` runs of the nanoseconds per call of `f`. The iteration count of a run is
/// doubled from 1 until one run takes at least `budget.run` (that calibration run is not counted).
pub fn median_ns(budget: Budget, mut f: impl FnMut()) -> f64 {
    let mut iters: u64 = 1;
    loop {
        let t = Instant::now();
        for _ in 0..iters {
            f();
        }
        if t.elapsed() >= budget.run || iters >= 1 << 30 {
            break;
        }
        iters *= 2;
    }
    let mut per_call: Vec<f64> = (0..budget.runs.max(1))
        .map(|_| {
            let t = Instant::now();
            for _ in 0..iters {
                f();
            }
            t.elapsed().as_nanos() as f64 / iters as f64
        })
        .collect();
    median(&mut per_call)
}

/// Median of `v` ([`motion_lod::quality::median`]), NaN when empty. Reorders `v`.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        motion_lod::quality::median(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert!(median(&mut []).is_nan());
    }

    #[test]
    fn median_ns_calls_the_operation_and_is_positive() {
        let mut calls = 0u64;
        let ns = median_ns(Budget::quick(), || {
            calls += 1;
            std::hint::black_box(calls);
        });
        assert!(ns.is_finite() && ns >= 0.0);
        assert!(calls >= 3);
    }
}
