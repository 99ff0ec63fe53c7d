//! Helpers shared by the `plie` binary's end-to-end tests: run it, read its stderr, expect a one-line
//! error.
#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs the `plie` binary with `args`.
pub fn plie(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_plie")).args(args).output().expect("run plie")
}

/// The process's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `plie args`, expects failure with a one-line error containing `needle`.
pub fn fails_with(args: &[&str], needle: &str) {
    let o = plie(args);
    let err = stderr(&o);
    assert!(!o.status.success(), "{args:?} should fail; stderr: {err}");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{args:?}: expected a one-line error, got: {err}");
    assert!(
        lines[0].to_lowercase().contains(&needle.to_lowercase()),
        "{args:?}: error should mention '{needle}': {err}"
    );
}
