//! The ten built-in test scenes of SPEC §6 (thesis chapter 7), generated in code (no files needed),
//! deterministically and in a few milliseconds. One file per family: `cornell` (Cornell Cube 1-5,
//! millimetres), `huis` (Huis A, B, C, metres), `dragon` (Cornell Cube 2 with a creature), `boot` (a
//! boat on the water, metres); the mesh helpers they share are in `shapes`. Beside them, the stress
//! scene `balusters` of issue 15 (not a thesis scene: [`STRESS`]).

mod balusters;
mod boot;
mod chair;
mod cornell;
mod decor;
mod dragon;
mod furniture;
mod huis;
mod shapes;

use super::{Scene, SceneBuilder};
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

/// One line on what the built-in scene `name` is and what it tests (`plie scenes`); `None` for an
/// unknown name.
pub fn description(name: &str) -> Option<&'static str> {
    Some(match name {
        "cornell-cube-1" => "Cornell room with a plane hovering under the light: every cell has a blocker",
        "cornell-cube-2" => "the classic Cornell box: five walls, a short and a tall block, a ceiling light",
        "cornell-cube-3" => "Cornell room with two finely tessellated spheres (960 triangles each)",
        "cornell-cube-4" => "cornell-cube-2 with a second ceiling light",
        "cornell-cube-5" => "cornell-cube-1 with a second light",
        "huis-a" => "an office: ceiling light, two bookcases, two tables, an office chair",
        "huis-b" => "huis-a with other colours, simpler bookcases and a flat screen on the desk",
        "huis-c" => "huis-b with a second light, outside the camera's view",
        "dragon" => "cornell-cube-2 with a dragon on a block: cells crowd around the dragon",
        "boot" => "a boat on the water lit by one distant light: hardly any shadow",
        "balusters" => "stress scene: a floor, 64 x 64 thin rods and a small ceiling light (balusters-N: N x N rods)",
        n if balusters::rods_of(n).is_some() => "stress scene: the balusters at another size",
        _ => return None,
    })
}

/// The built-in stress scenes (issue 15): many thin rods between the floor and a small light.
/// `balusters-N` (N from 1 to 256 rods per side) is the same scene at another size.
pub const STRESS: [&str; 1] = ["balusters"];

/// Whether `name` is a built-in scene (a thesis scene, a stress scene, or a sized stress scene).
pub fn exists(name: &str) -> bool {
    NAMES.contains(&name) || balusters::rods_of(name).is_some()
}

/// Builds the built-in scene `name`; [`Error::UnknownScene`] if there is none by that name.
pub fn load(name: &str) -> Result<Scene> {
    let builder: SceneBuilder = match name {
        "cornell-cube-1" => cornell::cube1()?,
        "cornell-cube-2" => cornell::cube2()?,
        "cornell-cube-3" => cornell::cube3()?,
        "cornell-cube-4" => cornell::cube4()?,
        "cornell-cube-5" => cornell::cube5()?,
        "huis-a" => huis::huis_a()?,
        "huis-b" => huis::huis_b()?,
        "huis-c" => huis::huis_c()?,
        "dragon" => dragon::dragon()?,
        "boot" => boot::boot()?,
        _ if balusters::rods_of(name).is_some() => {
            balusters::balusters(name, balusters::rods_of(name).expect("checked"))?
        }
        _ => {
            return Err(Error::UnknownScene {
                name: name.to_string(),
                known: format!("{}, {} (or balusters-N)", NAMES.join(", "), STRESS.join(", ")),
            })
        }
    };
    builder.build()
}
