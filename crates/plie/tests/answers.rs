//! The answer paths of the P-LIE modes' per-ray query (`plie render --stats`): every shadow ray is
//! counted on exactly one [`Answer`] path, each path gives the answer it stands for (checked against
//! brute force ray by ray), the triangle tests split exactly into blocker and own-leaf tests, and the
//! modes without a P-LIE leave these counters at zero. (A light with 2 or more samples facing the
//! point is answered by the per-light query, whose paths `light_queries.rs` covers; the renders
//! here ask ray by ray through [`PerRay`].)

mod support;

use glam::Vec2;
use plie::internals::lie::PlieParams;
use plie::internals::render::shade::shade;
use plie::internals::render::{HitBuffer, NoProgress};
use plie::visibility::{Answer, Mode, QueryCtx, QueryStats, ShadowRay, Visibility};
use plie::{LightId, Scene, TriId};
use support::{Built, TestRng};

const SCENES: [&str; 2] = ["cornell-cube-1", "huis-a"];

fn scenes() -> Vec<(Scene, Built)> {
    SCENES
        .iter()
        .map(|n| {
            let scene = plie::scene::builtin::load(n).unwrap();
            let built = Built::new(&scene, PlieParams::thesis());
            (scene, built)
        })
        .collect()
}

/// A visibility asked ray by ray: its per-light query is the trait's loop over the per-ray one.
struct PerRay<'a>(Box<dyn Visibility + 'a>);

impl Visibility for PerRay<'_> {
    fn occluded(&self, ray: &ShadowRay, ctx: &mut QueryCtx) -> bool {
        self.0.occluded(ray, ctx)
    }
}

/// The shading pass at 40x40, one eye ray per pixel, 4 shadow rays per light, ray by ray.
fn render_stats(scene: &Scene, built: &Built, mode: Mode) -> QueryStats {
    let camera = scene.camera_or_default();
    let hits = HitBuffer::build(scene, &camera, (40, 40, 1), &built.bvh, Some(built.octree()));
    shade(scene, &hits, &PerRay(built.vis(scene, mode)), 4, 7, &NoProgress).1
}

#[test]
fn every_shadow_ray_of_a_render_takes_exactly_one_path() {
    for (scene, built) in scenes() {
        let reference = render_stats(&scene, &built, Mode::Bvh);
        let [lie, umbra, penumbra, grid] = [Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid].map(|mode| {
            let s = render_stats(&scene, &built, mode);
            let a = s.answers;
            let what = format!("{} {mode}: {s:?}", scene.name);
            assert!(s.shadow_rays > 0, "{what}");
            assert_eq!((s.shadow_rays, s.occluded), (reference.shadow_rays, reference.occluded), "{what}");
            assert_eq!(a.total(), s.shadow_rays, "one path per ray: {what}");
            // The hit buffer gives every point its leaf, so every ray consults the P-LIE.
            assert_eq!(a.outside_octree, 0, "{what}");
            assert_eq!(s.occluded, a.no_record + a.umbra + a.blockers_hit + a.own_leaf, "{what}");
            assert_eq!(s.shadow_rays - s.occluded, a.lit + a.blockers_miss + a.inside_leaf, "{what}");
            assert_eq!(s.triangle_tests, s.blocker_tests + s.own_leaf_tests, "{what}");
            if mode == Mode::Lie {
                assert_eq!(a.umbra, 0, "mode lie has no umbra regions: {what}");
            }
            assert!(a.blockers_hit > 0 && a.blockers_miss > 0 && a.inside_leaf > 0, "{what}");
            s
        });
        let what = format!("{}: lie {lie:?}, umbra {umbra:?}, penumbra {penumbra:?}, grid {grid:?}", scene.name);
        // Regions only ever answer earlier: more rays end in umbra, fewer test blockers.
        assert!(umbra.answers.umbra > 0 && penumbra.answers.umbra == umbra.answers.umbra, "{what}");
        assert!(penumbra.answers.lit >= lie.answers.lit && penumbra.blocker_tests <= umbra.blocker_tests, "{what}");
        assert!(umbra.blocker_tests <= lie.blocker_tests, "{what}");
        // Both modes find the same exit face and record and test the same own triangles; a grid cell's
        // list is part of its record's, so an empty record list means empty cell lists.
        assert_eq!(lie.answers.no_record, grid.answers.no_record, "{what}");
        assert_eq!(lie.answers.inside_leaf, grid.answers.inside_leaf, "{what}");
        assert!(grid.answers.lit >= lie.answers.lit, "{what}");
        if scene.name == "huis-a" {
            assert!(lie.answers.lit > 0 && grid.answers.lit > lie.answers.lit, "{what}");
        }
    }
}

#[test]
fn modes_without_a_p_lie_count_no_paths() {
    for (scene, built) in scenes() {
        for mode in Mode::EXACT.into_iter().filter(|m| !m.needs_plie()) {
            let s = render_stats(&scene, &built, mode);
            assert!(s.shadow_rays > 0 && s.triangle_tests > 0, "{} {mode}", scene.name);
            assert_eq!(s.answers.total(), 0, "{} {mode}: {s:?}", scene.name);
            assert_eq!((s.blocker_tests, s.own_leaf_tests), (0, 0), "{} {mode}", scene.name);
        }
    }
}

/// Shadow rays as the renderer shoots them: `x` on a triangle or anywhere in the scene, `y` on a light
/// that faces `x`.
fn shadow_rays(scene: &Scene, built: &Built, n: usize, seed: u64) -> Vec<ShadowRay> {
    let mut rng = TestRng(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let li = rng.below(scene.lights.len());
        let light = &scene.lights[li];
        let y = light.sample(Vec2::new(rng.f32(), rng.f32()));
        let (x, tri) = if rng.below(2) == 0 {
            let t = rng.below(scene.triangles.len());
            let (mut u, mut v) = (rng.f32(), rng.f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            (scene.triangles[t].point(u, v), TriId(t as u32))
        } else {
            (rng.point_in(scene.bounds.min, scene.bounds.max), TriId(u32::MAX))
        };
        if (x - y).dot(light.normal) > 0.0 {
            out.push(ShadowRay::new(x, y, LightId(li as u32), tri, built.octree().locate(x)));
        }
    }
    out
}

#[test]
fn each_path_gives_its_answer_ray_by_ray() {
    for (scene, built) in scenes() {
        let brute = built.vis(&scene, Mode::Brute);
        let mut brute_ctx = QueryCtx::new(scene.triangle_count());
        for mode in [Mode::Lie, Mode::Grid] {
            let vis = built.vis(&scene, mode);
            let mut ctx = QueryCtx::new(scene.triangle_count());
            let mut seen = std::collections::HashSet::new();
            for (i, ray) in shadow_rays(&scene, &built, 20_000, 42).iter().enumerate() {
                let before = ctx.stats;
                let occluded = vis.occluded(ray, &mut ctx);
                let after = ctx.stats;
                let what = format!("{} {mode} ray {i} {ray:?}", scene.name);
                let paths: Vec<Answer> =
                    Answer::ALL.into_iter().filter(|&a| after.answers.get(a) != before.answers.get(a)).collect();
                let [path] = paths[..] else { panic!("{what}: paths {paths:?}") };
                assert_eq!(after.answers.total(), before.answers.total() + 1, "{what}");
                seen.insert(path);

                assert_eq!(occluded, brute.occluded(ray, &mut brute_ctx), "{what}");
                if let Some(answer) = path.occluded() {
                    assert_eq!(occluded, answer, "{what}: path {path:?}");
                }
                let blocker_tests = after.blocker_tests - before.blocker_tests;
                let own_tests = after.own_leaf_tests - before.own_leaf_tests;
                assert_eq!(after.triangle_tests - before.triangle_tests, blocker_tests + own_tests, "{what}");
                match path {
                    Answer::NoRecord | Answer::Umbra => assert_eq!(blocker_tests + own_tests, 0, "{what}"),
                    Answer::Lit | Answer::InsideLeaf => assert_eq!(blocker_tests, 0, "{what}"),
                    Answer::BlockersHit => assert!(blocker_tests > 0 && own_tests == 0, "{what}"),
                    // The box cull may spare every triangle test of a non-empty list.
                    Answer::BlockersMiss => assert!(after.box_tests > before.box_tests, "{what}"),
                    Answer::OwnLeaf => assert!(own_tests > 0, "{what}"),
                    Answer::OutsideOctree => panic!("{what}: every start point lies in the octree"),
                    // The scene BVH answers the whole segment; its tests count as blocker tests.
                    Answer::SceneBvh => assert_eq!(own_tests, 0, "{what}"),
                }
            }
            for path in [Answer::BlockersHit, Answer::BlockersMiss, Answer::OwnLeaf, Answer::InsideLeaf] {
                assert!(seen.contains(&path), "{} {mode}: no ray took {path:?}", scene.name);
            }
        }
    }
}
