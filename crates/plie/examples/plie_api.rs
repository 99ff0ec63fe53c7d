//! The library API end to end: load a scene, build a P-LIE, save it, load it back, ask it about a
//! shadow ray, and render an image with it.
//!
//! Run with `cargo run --release -p plie --example plie_api`.

use glam::Vec2;
use plie::io::plie_file::{load_plie, save_plie};
use plie::lie::PlieParams;
use plie::octree::Octree;
use plie::render::{render, NoProgress, RenderSettings};
use plie::visibility::bvh::Bvh;
use plie::visibility::{for_mode, Mode, QueryCtx, ShadowRay};
use plie::{LightId, TriId};

fn main() -> plie::Result<()> {
    let scene = plie::scene::builtin::load("dragon")?;

    // Build once, independent of any camera.
    let params = PlieParams::thesis();
    let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
    let (plie, stats) = plie::construct::build(&scene, &octree, params, &NoProgress);
    println!(
        "built: {} leaves, {} records, {:.1} blockers per record",
        stats.leaves, stats.records, stats.blockers_mean
    );

    // Save and load (the octree is rebuilt and checked against the file's fingerprint).
    let path = std::env::temp_dir().join("dragon-example.plie");
    let bytes = save_plie(&path, &scene, &octree, &plie)?;
    let (octree, plie) = load_plie(&path, &scene, Some(params))?;
    println!("saved and loaded {} bytes", bytes);

    // One shadow ray, as another renderer would ask it: from a point on the floor to a light sample.
    let bvh = Bvh::build(&scene);
    let lie = for_mode(Mode::Lie, &scene, &bvh, &octree, Some(&plie))?;
    let floor = TriId(0);
    let x = scene.triangle(floor).point(0.3, 0.3);
    let y = scene.lights[0].sample(Vec2::new(0.5, 0.5));
    let ray = ShadowRay::new(x, y, LightId(0), floor, octree.locate(x));
    let mut ctx = QueryCtx::new(scene.triangle_count());
    println!("x = {x} sees y = {y}: {}", !lie.occluded(&ray, &mut ctx));

    // A small image.
    let settings = RenderSettings { width: 64, height: 64, eye_rays: 1, shadow_rays: 4, seed: 0 };
    let camera = scene.camera_or_default();
    let image = render(&scene, &camera, &settings, &bvh, Some(&octree), lie.as_ref(), &NoProgress)?;
    println!(
        "rendered {} pixels in {:.3} s, {} shadow rays",
        image.pixels.len(),
        image.shading_seconds,
        image.stats.shadow_rays
    );
    std::fs::remove_file(&path).ok();
    Ok(())
}
