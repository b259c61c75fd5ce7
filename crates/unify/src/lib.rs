//! No code. This crate's dependencies ask, in every build of the workspace,
//! for the union of the features the workspace's crates ask of them, so
//! that switching between `cargo build`, `cargo test`, `cargo bench -p …`,
//! `-p rtpipe` and maturin rebuilds nothing (docs/architecture.md,
//! "Building"). Cargo.toml says which and why.
#![deny(missing_docs)]
