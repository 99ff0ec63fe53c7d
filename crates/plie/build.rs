//! Build script: tells the tests whether the real scenes `../shared/scenes` (beside the workspace) are
//! there. Where they are absent, the tests that need them are compiled `#[ignore]`d with that reason,
//! so `cargo test`'s summary counts them as ignored instead of reporting them `ok` without running.

use std::path::Path;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(plie_no_shared_scenes)");
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let scenes = Path::new(&manifest).join("../../../shared/scenes");
    if scenes.join("README.md").is_file() {
        // Re-run if the folder changes (or disappears).
        println!("cargo::rerun-if-changed={}", scenes.display());
    } else {
        // Absent: re-run only when this script changes (`touch crates/plie/build.rs` after adding the
        // folder), not on every build.
        println!("cargo::rustc-cfg=plie_no_shared_scenes");
        println!("cargo::rerun-if-changed=build.rs");
    }
}
