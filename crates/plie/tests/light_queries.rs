//! The per-light query (`Visibility::occluded_light`, issue 21): all samples of one light from one
//! point answered at once must equal the per-ray query sample by sample, and both must equal brute
//! force, in every exact mode, on every built-in scene and on the real scenes in ../shared/scenes/.
//! Points lie on triangles, on leaf faces, edges and corners, and anywhere; sample sets are random in
//! size (1 to 80) and position; the point's leaf is given or left for the mode to find.

mod support;

use glam::{Vec2, Vec3};
use plie::internals::lie::PlieParams;
use plie::visibility::{LightRays, Mode, QueryCtx};
use plie::{LightId, Scene, TriId};
use proptest::prelude::*;
use support::{start_point, Built, TestRng};

/// One (point, light) query.
struct Query {
    x: Vec3,
    tri: TriId,
    leaf: Option<plie::octree::LeafId>,
    light: LightId,
    targets: Vec<Vec3>,
}

impl Query {
    fn rays(&self) -> LightRays<'_> {
        LightRays { origin: self.x, origin_tri: self.tri, leaf: self.leaf, light: self.light, targets: &self.targets }
    }
}

/// `n` queries: a point in front of a light, and 1 to 80 samples on it.
fn queries(scene: &Scene, built: &Built, n: usize, seed: u64) -> Vec<Query> {
    let mut rng = TestRng(seed);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let li = rng.below(scene.lights.len());
        let light = &scene.lights[li];
        let (x, tri) = start_point(scene, built.octree(), &mut rng);
        if (x - light.vertices[0]).dot(light.normal) <= 0.0 {
            continue;
        }
        let count = if rng.below(3) == 0 { 64 } else { 1 + rng.below(80) };
        let targets = (0..count).map(|_| light.sample(Vec2::new(rng.f32(), rng.f32()))).collect();
        let leaf = if rng.below(4) == 0 { None } else { built.octree().locate(x) };
        out.push(Query { x, tri, leaf, light: LightId(li as u32), targets });
    }
    out
}

/// Checks every exact mode's per-light answers against its per-ray answers and against brute force;
/// returns the counters of the queries.
fn check(scene: &Scene, built: &Built, qs: &[Query]) -> plie::visibility::QueryStats {
    let brute = built.vis(scene, Mode::Brute);
    let mut ctx = QueryCtx::new(scene.triangles.len());
    let reference: Vec<Vec<bool>> =
        qs.iter().map(|q| (0..q.targets.len()).map(|k| brute.occluded(&q.rays().ray(k), &mut ctx)).collect()).collect();
    let blocked: usize = reference.iter().flatten().filter(|&&b| b).count();
    let total: usize = reference.iter().map(Vec::len).sum();
    assert!(blocked > 0 && blocked < total, "{}: the queries must include both answers", scene.name);
    for mode in Mode::EXACT.into_iter().filter(|&m| m != Mode::Brute) {
        let vis = built.vis(scene, mode);
        let mut out = Vec::new();
        for (qi, q) in qs.iter().enumerate() {
            let rays = q.rays();
            out.clear();
            out.resize(q.targets.len(), false);
            vis.occluded_light(&rays, &mut out, &mut ctx);
            for k in 0..q.targets.len() {
                let per_ray = vis.occluded(&rays.ray(k), &mut ctx);
                assert_eq!(
                    out[k], per_ray,
                    "{} {mode}: query {qi} sample {k}: per-light {} per-ray {per_ray}",
                    scene.name, out[k]
                );
                assert_eq!(
                    out[k],
                    reference[qi][k],
                    "{} {mode}: query {qi} sample {k} ({:?}): {} but brute force says {}",
                    scene.name,
                    rays.ray(k),
                    out[k],
                    reference[qi][k]
                );
            }
        }
    }
    ctx.stats
}

#[test]
fn per_light_answers_equal_per_ray_and_brute_force_on_builtin_scenes() {
    for scene in support::builtins() {
        let built = Built::new(&scene, PlieParams::thesis());
        check(&scene, &built, &queries(&scene, &built, 200, 21));
    }
}

#[test]
#[ignore = "exhaustive tier (real scenes): cargo test --workspace -- --ignored"]
fn per_light_answers_equal_per_ray_and_brute_force_on_shared_scenes() {
    for scene in support::load_shared() {
        let built = Built::new(&scene, PlieParams::thesis());
        // Brute force over 100k triangles is slow: fewer queries on the large scenes.
        let n = if scene.triangles.len() > 10_000 { 40 } else { 300 };
        check(&scene, &built, &queries(&scene, &built, n, 22));
        // And points crowded on pieces, whose lights get answered from their shafts.
        let (clusters, per) = if scene.triangles.len() > 10_000 { (4, 40) } else { (12, 60) };
        check(&scene, &built, &clustered_queries(&scene, &built, clusters, per, 27));
    }
}

/// With face grids and a small blocker cap, many lights are answered through the gathered lists
/// and many rays through records that store no list (the scene BVH): still as per ray and as brute
/// force.
#[test]
fn per_light_answers_with_grids_and_a_small_blocker_cap() {
    for name in ["cornell-cube-2", "huis-c", "dragon"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        for cap in [None, Some(16)] {
            let built = Built::new(&scene, PlieParams { blocker_cap: cap, ..PlieParams::default() });
            let stats = check(&scene, &built, &queries(&scene, &built, 200, 24));
            let l = stats.lights;
            assert!(l.gathered > 0 && l.scene > 0, "{name} {cap:?}: both ways taken: {l:?}");
        }
    }
}

/// The queries with at least `min` samples, the `i`-th of them cut to at most `count(i)`.
fn cut_to(qs: Vec<Query>, min: usize, count: impl Fn(usize) -> usize) -> Vec<Query> {
    let kept = qs.into_iter().filter(|q| q.targets.len() >= min);
    kept.enumerate()
        .map(|(i, mut q)| {
            q.targets.truncate(count(i));
            q
        })
        .collect()
}

/// With 8 to 16 samples (which go straight to the watertight test, without the lane test), the
/// lights answered through the gathered lists are counted as gathered, not as whole lit.
#[test]
fn gathered_lights_are_counted_with_few_samples() {
    let scene = plie::scene::builtin::load("huis-c").unwrap();
    let built = Built::new(&scene, PlieParams::default());
    let qs = cut_to(queries(&scene, &built, 400, 25), 8, |_| 16);
    let l = check(&scene, &built, &qs).lights;
    assert!(l.gathered > 0 && l.whole_lit > 0, "{l:?}");
}

/// Lights with 2 to 7 samples facing the point (the thesis' 4 rays, or a light partly behind the
/// point) are answered by the P-LIE modes as a fan too (`FAN_MIN`), as per ray and as brute
/// force.
#[test]
fn few_samples_are_answered_per_light() {
    let scene = plie::scene::builtin::load("huis-c").unwrap();
    let built = Built::new(&scene, PlieParams::default());
    let qs = cut_to(queries(&scene, &built, 400, 28), 7, |i| 2 + i % 6);
    let l = check(&scene, &built, &qs).lights;
    // Each P-LIE mode answers every query per light (one mode alone would count them all).
    assert!(l.queries >= qs.len() as u64, "{} of {} queries per light: {l:?}", l.queries, qs.len());
}

/// The refined P-LIE (split leaves) answers per light as per ray too.
#[test]
fn per_light_answers_on_a_refined_p_lie() {
    let scene = plie::scene::builtin::load("huis-a").unwrap();
    let refine = plie::internals::construct::refine::RefineParams {
        umbra_full: true,
        umbra_free: true,
        ..plie::internals::construct::refine::RefineParams::none()
    };
    let params = PlieParams { refine, ..PlieParams::thesis() };
    let built = Built::refined(&scene, params);
    check(&scene, &built, &queries(&scene, &built, 300, 23));
}

/// Many points on the same few pieces of triangles (a triangle's part in one leaf), as a render
/// asks them: the P-LIE modes answer such pieces' lights from the triangles of their shafts once a
/// piece has been asked often enough (`lie::shafts`), and still as per ray and as brute force.
fn clustered_queries(scene: &Scene, built: &Built, clusters: usize, per: usize, seed: u64) -> Vec<Query> {
    let mut rng = TestRng(seed);
    let mut out = Vec::with_capacity(clusters * per);
    let mut made = 0;
    while made < clusters {
        let t = rng.below(scene.triangles.len());
        let li = rng.below(scene.lights.len());
        let light = &scene.lights[li];
        let tri = &scene.triangles[t];
        if scene.tri_light[t].is_some() {
            continue;
        }
        let (u0, v0) = (rng.f32() * 0.8, rng.f32() * 0.8);
        let (u0, v0) = if u0 + v0 > 0.9 { (0.9 - v0, 0.9 - u0) } else { (u0, v0) };
        let points: Vec<Vec3> = (0..per)
            .map(|_| tri.point((u0 + rng.f32() * 0.05).min(1.0), (v0 + rng.f32() * 0.05).min(1.0 - u0)))
            .filter(|x| (*x - light.vertices[0]).dot(light.normal) > 0.0)
            .collect();
        if points.len() < per {
            continue;
        }
        made += 1;
        for x in points {
            let count = 8 + rng.below(57);
            let targets = (0..count).map(|_| light.sample(Vec2::new(rng.f32(), rng.f32()))).collect();
            let leaf = built.octree().locate(x);
            out.push(Query { x, tri: TriId(t as u32), leaf, light: LightId(li as u32), targets });
        }
    }
    out
}

/// Also the lights answered by the blockers of the light's last walk that found every ray
/// occluded (`lie::light`): neighbouring points in shadow; and those whose footprints were not
/// sought because their leaf's had decided nothing the last few times (`visibility::verdicts`).
#[test]
fn per_light_answers_from_shafts_equal_per_ray_and_brute_force() {
    let (mut shaft, mut last, mut unsought) = (0, 0, 0);
    for name in ["cornell-cube-2", "huis-c", "dragon"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let built = Built::new(&scene, PlieParams::default());
        let stats = check(&scene, &built, &clustered_queries(&scene, &built, 24, 80, 26));
        shaft += stats.lights.shaft;
        last += stats.lights.last_blockers;
        unsought += stats.lights.unsought;
    }
    // Some lights were answered from their pieces' shafts (each piece is asked up to 80 times),
    // and some by their last blockers.
    assert!(shaft > 0, "no light answered from a shaft");
    assert!(last > 0, "no light answered by its last blockers");
    assert!(unsought > 0, "no light answered without its footprints");
}

fn cornell() -> &'static (Scene, Built) {
    static S: std::sync::OnceLock<(Scene, Built)> = std::sync::OnceLock::new();
    S.get_or_init(|| {
        let scene = plie::scene::builtin::load("cornell-cube-2").unwrap();
        let built = Built::new(&scene, PlieParams::thesis());
        (scene, built)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random points anywhere in the box, random sample sets on the light: per-light answers equal
    /// per-ray answers and brute force in the P-LIE modes and the BVH.
    #[test]
    fn random_points_and_sample_sets(
        p in (0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0),
        us in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0), 1..80),
        give_leaf in any::<bool>(),
    ) {
        let (scene, built) = cornell();
        let b = scene.bounds;
        let x = b.min + (b.max - b.min) * Vec3::new(p.0, p.1, p.2);
        let light = &scene.lights[0];
        prop_assume!((x - light.vertices[0]).dot(light.normal) > 0.0);
        let targets: Vec<Vec3> = us.iter().map(|&(u, v)| light.sample(Vec2::new(u, v))).collect();
        let q = Query { x, tri: TriId(u32::MAX), leaf: if give_leaf { built.octree().locate(x) } else { None }, light: LightId(0), targets };
        let rays = q.rays();
        let mut ctx = QueryCtx::new(scene.triangles.len());
        let brute = built.vis(scene, Mode::Brute);
        for mode in [Mode::Bvh, Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid] {
            let vis = built.vis(scene, mode);
            let mut out = vec![false; q.targets.len()];
            vis.occluded_light(&rays, &mut out, &mut ctx);
            for (k, &o) in out.iter().enumerate() {
                prop_assert_eq!(o, vis.occluded(&rays.ray(k), &mut ctx), "{} sample {}", mode, k);
                prop_assert_eq!(o, brute.occluded(&rays.ray(k), &mut ctx), "{} sample {}", mode, k);
            }
        }
    }
}
