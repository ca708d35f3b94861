//! Seeded property-test runners for finestep's tests.
//!
//! Every randomised test takes its runner from [`runner`], which prints the seed it
//! uses and takes it from the `FINESTEP_SEED` environment variable when that is set,
//! so any failure reruns exactly:
//!
//! ```
//! use proptest::prelude::*;
//! let mut runner = finestep_testkit::runner("doc_example", 16);
//! runner.run(&(0u32..10), |x| { prop_assert!(x < 10); Ok(()) }).unwrap();
//! ```
//!
//! Under CI (the `CI` variable set, as `.ci/run` does) an unset `FINESTEP_SEED` gives a
//! fixed seed per test, so the gate is reproducible; elsewhere each run explores a fresh
//! seed. `FINESTEP_CASES` overrides the number of cases (used by `make test-long`).

use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// The seed for `test`: `FINESTEP_SEED` if set (decimal or 0x-hex), else under CI one
/// fixed by the test's name, else fresh.
pub fn seed(test: &str) -> u64 {
    match std::env::var("FINESTEP_SEED") {
        Ok(text) => {
            parse_seed(&text).unwrap_or_else(|| panic!("FINESTEP_SEED={text:?} is not a decimal or 0x-hex u64"))
        }
        Err(_) if std::env::var_os("CI").is_some_and(|v| !v.is_empty()) => fixed_seed(test),
        Err(_) => {
            use std::hash::{BuildHasher, Hasher};
            let mut hasher = std::collections::hash_map::RandomState::new().build_hasher();
            hasher.write_u128(
                std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0),
            );
            hasher.finish()
        }
    }
}

/// FNV-1a of the test's name: stable across Rust versions, unlike `DefaultHasher`.
fn fixed_seed(test: &str) -> u64 {
    test.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

fn parse_seed(text: &str) -> Option<u64> {
    let text = text.trim();
    match text.strip_prefix("0x") {
        Some(hex) => u64::from_str_radix(hex, 16).ok(),
        None => text.parse().ok(),
    }
}

/// Number of cases: `FINESTEP_CASES` if set, else `default_cases`.
pub fn cases(default_cases: u32) -> u32 {
    std::env::var("FINESTEP_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(default_cases)
}

/// A proptest runner seeded from [`seed`], printing `test`'s seed and how to rerun it.
pub fn runner(test: &str, default_cases: u32) -> TestRunner {
    let seed = seed(test);
    eprintln!("{test}: FINESTEP_SEED={seed:#x} (rerun with this to reproduce)");
    let mut bytes = [0u8; 32];
    for (i, chunk) in bytes.chunks_mut(8).enumerate() {
        chunk.copy_from_slice(&seed.wrapping_add(i as u64).to_le_bytes());
    }
    let config = Config { cases: cases(default_cases), failure_persistence: None, ..Config::default() };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_parse_in_both_notations() {
        assert_eq!(parse_seed("42"), Some(42));
        assert_eq!(parse_seed(" 0x2a "), Some(42));
        assert_eq!(parse_seed("forty-two"), None);
    }

    #[test]
    fn fixed_seeds_differ_by_test() {
        assert_eq!(fixed_seed(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fixed_seed("a"), 0xaf63_dc4c_8601_ec8c);
        assert_ne!(fixed_seed("jogs"), fixed_seed("arcs"));
    }
}
