//! Empty: it exists so that cargo resolves this crate's build-dependencies
//! (the host-side features it unifies; see Cargo.toml).

fn main() {}
