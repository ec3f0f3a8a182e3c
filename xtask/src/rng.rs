//! A tiny deterministic pseudo-random generator (SplitMix64) for the fixture plan.
//!
//! The fixtures must be byte-identical on every machine and every run, so the generator is the
//! project's own (`lod_policy::SplitMix64`, no dependency whose stream could change between
//! versions); `lod_policy::SplitMix64`'s tests pin its stream against the reference values.

pub use lod_policy::SplitMix64;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_stays_in_range() {
        let mut r = SplitMix64::new(7);
        for _ in 0..1000 {
            let x = r.uniform(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
        }
    }
}
