//! Render a scene in one call: a built-in scene (or a scene file given as the first argument), the
//! BVH for shadow rays, then the same image with a P-LIE's face grids: exact modes give the same
//! pixels. Writes `render_scene.png` to the system's temporary folder.
//!
//! `cargo run --release -p plie --example render_scene [SCENE]`

use plie::{Environment, Mode, PlieParams, Renderer};

fn main() -> plie::Result<()> {
    run(&std::env::args().nth(1).unwrap_or_else(|| "cornell-cube-2".into()))
}

/// The example on scene `name` (a built-in name or a scene file).
pub fn run(name: &str) -> plie::Result<()> {
    let scene = match plie::scene::builtin::load(name) {
        Ok(scene) => scene,
        Err(_) => plie::io::load_scene(name.as_ref())?,
    };
    let renderer = Renderer::new().size(64, 48).eye_rays(1).shadow_rays(4).seed(7);

    // Without preprocessing: the scene BVH answers the shadow rays.
    let bvh = renderer.render(&scene, Mode::Bvh, None)?;

    // With a P-LIE: build it once, then render with the fastest mode it supports.
    let (env, _) = Environment::build(&scene, &PlieParams::default())?;
    let grid = renderer.render(&scene, env.best_mode(), Some(&env))?;
    assert_eq!(bvh.pixels, grid.pixels, "every exact mode renders the same image");

    let out = std::env::temp_dir().join("render_scene.png");
    grid.save(&out)?;
    println!(
        "{}: {} x {} pixels, {} shadow rays, written to {}",
        scene.name,
        grid.width,
        grid.height,
        grid.stats.shadow_rays,
        out.display()
    );
    Ok(())
}
