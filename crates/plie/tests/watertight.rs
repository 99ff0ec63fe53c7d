//! SPEC §5: the one watertight segment/triangle test. Rays aimed exactly at shared vertices and edges
//! of a closed mesh must never slip through, in any visibility mode.

mod support;

use glam::Vec3;
use plie::internals::lie::PlieParams;
use plie::visibility::{Mode, QueryCtx, ShadowRay};
use plie::{LightId, SceneBuilder, TriId};
use support::TestRng;

/// A closed UV sphere with shared vertices (poles included), plus a small light far away.
fn sphere(rings: usize, segments: usize) -> (plie::Scene, Vec<Vec3>, Vec<(Vec3, Vec3)>) {
    let mut b = SceneBuilder::new("sphere");
    let m = b.diffuse("m", Vec3::splat(0.5));
    let c = Vec3::new(0.3, -0.2, 0.1);
    let vert = |i: usize, j: usize| {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        let ph = 2.0 * std::f32::consts::PI * (j % segments) as f32 / segments as f32;
        c + Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * 2.0
    };
    let mut verts = Vec::new();
    let mut edges = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, bb, cc, d) = (vert(i, j), vert(i + 1, j), vert(i + 1, j + 1), vert(i, j + 1));
            if i > 0 {
                b.triangle(a, cc, d, m);
                edges.push((a, cc));
            }
            if i + 1 < rings {
                b.triangle(a, bb, cc, m);
            }
            verts.push(a);
            edges.push((a, bb));
            edges.push((bb, cc));
        }
    }
    let l = Vec3::new(50.0, 50.0, 50.0);
    b.light("l", &[l, l + Vec3::X, l + Vec3::Z], Vec3::ONE);
    (b.build().unwrap(), verts, edges)
}

#[test]
fn rays_through_shared_vertices_and_edges_never_slip_through() {
    let (scene, verts, edges) = sphere(17, 23);
    let built = support::Built::new(&scene, PlieParams { max_triangles: 16, ..PlieParams::thesis() });
    let center = Vec3::new(0.3, -0.2, 0.1);
    let mut rng = TestRng(5);
    let mut targets: Vec<Vec3> = verts.clone();
    for (a, b) in &edges {
        targets.push((*a + *b) * 0.5);
        let t = rng.f32();
        targets.push(*a + (*b - *a) * t);
    }
    // Free segments (not toward a light sample): every mode that does not use a P-LIE.
    for mode in Mode::EXACT.into_iter().filter(|m| !m.needs_plie()) {
        let vis = built.vis(&scene, mode);
        let mut ctx = QueryCtx::new(scene.triangles.len());
        for p in &targets {
            // From far outside, through the target, to the center: must cross the closed surface.
            let from = center + (*p - center) * 3.0;
            let ray = ShadowRay::new(from, center, LightId(0), TriId(u32::MAX), None);
            assert!(vis.occluded(&ray, &mut ctx), "{mode}: ray through {p} slipped through");
            // And along an axis-parallel direction through the same point.
            let from = *p + Vec3::new(0.0, 5.0, 0.0);
            let ray =
                ShadowRay::new(from, center + (*p - center) * 0.5 - Vec3::Y * 5.0, LightId(0), TriId(u32::MAX), None);
            let brute = built.vis(&scene, Mode::Brute).occluded(&ray, &mut ctx);
            assert_eq!(vis.occluded(&ray, &mut ctx), brute, "{mode}: disagrees with brute force");
        }
    }
}
