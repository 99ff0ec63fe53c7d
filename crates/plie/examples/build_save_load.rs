//! Build a P-LIE once, save it, and load it for later renders: the octree of a scene refined by
//! umbra (SPEC §4.8), its statistics, the `.plie` file, and the checks a loaded file passes.
//!
//! `cargo run --release -p plie --example build_save_load [SCENE]`

use plie::RefineParams;
use plie::{Environment, PlieFileError, PlieParams};

fn main() -> plie::Result<()> {
    run(&std::env::args().nth(1).unwrap_or_else(|| "cornell-cube-4".into()))
}

/// The example on scene `name` (a built-in name).
pub fn run(name: &str) -> plie::Result<()> {
    let scene = plie::scene::builtin::load(name)?;

    // Parameters check themselves: a bad one is an error, never a panic.
    let bad = PlieParams { max_depth: 0, ..PlieParams::default() };
    assert!(Environment::build(&scene, &bad).is_err());

    let params = PlieParams { refine: RefineParams::thesis_umbra(), ..PlieParams::default() };
    let (env, stats) = Environment::build(&scene, &params)?;
    println!("{stats}");

    let dir = std::env::temp_dir().join(format!("plie-example-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|source| plie::Error::Io { path: dir.clone(), source })?;
    let path = dir.join(format!("{name}.plie"));
    let bytes = env.save(&path, &scene)?;
    println!("saved {bytes} bytes to {}", path.display());

    // Loading rebuilds the octree, replays the refinement and checks the file against the scene.
    let loaded = Environment::load(&path, &scene, Some(&params))?;
    assert_eq!(loaded.plie(), env.plie());
    let report = loaded.validate(&scene);
    assert!(report.is_ok(), "{report}");
    print!("{report}");

    // A file for another scene is refused with a typed error.
    let other = plie::scene::builtin::load("cornell-cube-1")?;
    match Environment::load(&path, &other, None) {
        Err(plie::Error::PlieFile { problem: PlieFileError::OtherScene { .. }, .. }) => {
            println!("refused for another scene, as it should be")
        }
        Err(e) => return Err(e),
        Ok(_) => unreachable!("a P-LIE loads only for its own scene"),
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}
