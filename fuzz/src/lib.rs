//! The cargo-fuzz targets' bodies (issue 16): the one copy in `crates/plie/tests/fuzz/targets.rs`,
//! which the stable fuzzer and the replay of kept crash inputs (`crates/plie/tests/fuzz.rs`) share.

#[path = "../../crates/plie/tests/fuzz/targets.rs"]
mod targets;

pub use targets::*;
