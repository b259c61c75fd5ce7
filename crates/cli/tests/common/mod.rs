//! Helpers shared by the end-to-end tests of the `rtpipe` binary.
#![allow(dead_code)] // each test file uses its own subset

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

/// The path of a bundled example.
pub fn example(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
        .to_string_lossy()
        .into_owned()
}

/// Runs the binary with these arguments.
pub fn rtpipe(args: &[&str]) -> Output {
    match Command::new(env!("CARGO_BIN_EXE_rtpipe"))
        .args(args)
        .output()
    {
        Ok(o) => o,
        Err(e) => panic!("cannot run rtpipe: {e}"),
    }
}

/// Stdout as JSON (the test fails with both streams shown otherwise).
pub fn json_of(o: &Output) -> Value {
    match serde_json::from_slice(&o.stdout) {
        Ok(v) => v,
        Err(e) => panic!(
            "stdout is not JSON ({e}): {}\nstderr: {}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        ),
    }
}

/// A fresh, empty scratch directory per test.
pub fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rtpipe-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    if let Err(e) = std::fs::create_dir_all(&dir) {
        panic!("cannot create {}: {e}", dir.display());
    }
    dir
}

/// The exit status is `code`; the test shows stderr otherwise.
pub fn assert_exit(o: &Output, code: i32) {
    assert_eq!(
        o.status.code(),
        Some(code),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
