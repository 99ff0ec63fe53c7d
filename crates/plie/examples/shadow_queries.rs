//! Ask shadow rays from your own renderer: a P-LIE answers "does anything block the segment from
//! this point to this light sample?" for any point, one ray at a time or all the samples of one
//! light at once, exactly as brute force does.
//!
//! `cargo run --release -p plie --example shadow_queries`

use glam::Vec2;
use plie::visibility::{LightRays, QueryCtx, ShadowRay};
use plie::{Environment, LightId, Mode, PlieParams, Shadows, TriId};

fn main() -> plie::Result<()> {
    run("dragon")
}

/// The example on the built-in scene `name`.
pub fn run(name: &str) -> plie::Result<()> {
    let scene = plie::scene::builtin::load(name)?;
    let (env, _) = Environment::build(&scene, &PlieParams::default())?;
    let grid = env.visibility(Mode::Grid, &scene)?;
    // The reference, without a P-LIE.
    let shadows = Shadows::new(&scene);
    let brute = shadows.visibility(Mode::Brute)?;

    // Each thread keeps one query context (scratch space and counters).
    let mut ctx = QueryCtx::new(scene.triangle_count());
    let light = LightId(0);
    let (mut rays, mut occluded) = (0, 0);
    for (i, tri) in scene.triangles.iter().enumerate().step_by(97) {
        let origin = TriId(i as u32);
        let x = tri.point(0.3, 0.3);
        // The P-LIE modes need the octree leaf holding the shaded point.
        let leaf = env.octree().locate(x);
        for s in [Vec2::new(0.25, 0.25), Vec2::new(0.5, 0.5), Vec2::new(0.75, 0.1)] {
            let y = scene.lights[light.idx()].sample(s);
            let ray = ShadowRay::new(x, y, light, origin, leaf);
            let blocked = grid.occluded(&ray, &mut ctx);
            assert_eq!(blocked, brute.occluded(&ray, &mut ctx), "exact: the same answer as brute force");
            rays += 1;
            occluded += blocked as usize;
        }

        // All samples of one light from one point at once (shares work between them).
        let targets: Vec<glam::Vec3> =
            [0.1, 0.4, 0.7].iter().map(|&u| scene.lights[light.idx()].sample(Vec2::new(u, 1.0 - u))).collect();
        let batch = LightRays { origin: x, targets: &targets, light, origin_tri: origin, leaf };
        let mut out = vec![false; targets.len()];
        grid.occluded_light(&batch, &mut out, &mut ctx);
        for (k, &o) in out.iter().enumerate() {
            assert_eq!(o, grid.occluded(&batch.ray(k), &mut ctx));
        }
    }
    println!("{rays} shadow rays from {} points: {occluded} blocked", rays / 3);
    Ok(())
}
