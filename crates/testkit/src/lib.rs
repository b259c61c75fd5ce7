//! # rtpipe-testkit
//!
//! The scaffolding the workspace's tests share, so that each test says only
//! what it checks: the bundled examples, specs from text, the property-test
//! runner that tallies how cases ended, the model's random systems, and
//! scratch directories that remove themselves ([`Scratch`]).
//!
//! A dev-dependency only: no library depends on it for its normal build.
//! The model's own unit tests cannot use its specs (they would see a second
//! copy of the model's types), only what holds no model type ([`Scratch`]);
//! its integration tests can use all of it.
#![deny(missing_docs)]

use proptest::strategy::Strategy;
use proptest::test_runner::{Config, TestCaseError, TestRunner};
use rtpipe_model::Spec;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Mutex;

pub mod alloc;
pub mod scratch;

pub use scratch::Scratch;

/// Random systems, deterministic per seed (the model's generator).
pub use rtpipe_model::gen;

/// The path of a bundled example, e.g. `example_path("paper-table2.toml")`.
pub fn example_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// The text of a bundled example (the test fails if it cannot be read).
pub fn example_text(name: &str) -> String {
    let p = example_path(name);
    match std::fs::read_to_string(&p) {
        Ok(t) => t,
        Err(e) => panic!("cannot read {}: {e}", p.display()),
    }
}

/// A bundled example, loaded and validated as `rtpipe` loads it.
pub fn example(name: &str) -> Spec {
    match Spec::load(&example_path(name)) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

/// A bundled example with its text edited first (for variants of the
/// examples that need no file of their own).
pub fn example_with(name: &str, edit: impl FnOnce(&str) -> String) -> Spec {
    spec(name, &edit(&example_text(name)))
}

/// A spec from TOML text; the test fails with the diagnostics if it is
/// invalid. `name` is the file name the diagnostics show.
pub fn spec(name: &str, text: &str) -> Spec {
    match Spec::parse(name, text) {
        Ok(s) => s,
        Err(e) => panic!("{name}: {e}"),
    }
}

/// The property-test runner of the workspace: `cases` cases, failures
/// shrink as usual but are not persisted (no regression files next to the
/// sources).
pub fn runner(cases: u32) -> TestRunner {
    TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    })
}

/// Runs `test` on `cases` values of `strategy` with [`runner`]. `test`
/// returns what it did with the case ("checked", or why it was skipped);
/// the tally is printed (visible with `--nocapture`), so that a property
/// that skips most of its cases shows it.
pub fn check<S: Strategy>(
    name: &str,
    cases: u32,
    strategy: S,
    test: impl Fn(S::Value) -> Result<&'static str, TestCaseError>,
) {
    let tally: Mutex<BTreeMap<&'static str, usize>> = Mutex::new(BTreeMap::new());
    let result = runner(cases).run(&strategy, |v| {
        let outcome = test(v)?;
        if let Ok(mut t) = tally.lock() {
            *t.entry(outcome).or_default() += 1;
        }
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    let tally = tally.into_inner().unwrap_or_default();
    let total: usize = tally.values().sum();
    eprintln!("{name}: {total} cases {tally:?}");
}

/// An unsigned integer from the environment variable `name` (a test's size
/// knob), or `default` when it is unset or not a number.
pub fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(default)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn examples_load_and_edit() {
        assert_eq!(example("paper-table2.toml").tasks.len(), 6);
        let s = example_with("paper-table2.toml", |t| {
            t.replace("name = \"paper-table2\"", "name = \"x\"")
        });
        assert_eq!(s.name, "x");
    }

    #[test]
    fn check_tallies_every_case() {
        let seen = Mutex::new(0u32);
        check("count", 17, 0u32..10, |v| {
            *seen.lock().map_err(|_| TestCaseError::fail("lock"))? += 1;
            Ok(if v < 5 { "low" } else { "high" })
        });
        assert_eq!(seen.into_inner().unwrap_or(0), 17);
    }
}
