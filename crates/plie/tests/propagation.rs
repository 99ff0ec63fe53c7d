//! Propagation of umbra (SPEC §4.7) on real scenes, checked independently of the code that decides it:
//!
//! - soundness: for every record propagation deleted, on every built-in scene and the OBJs of
//!   ../shared/scenes/, sampled segments from the face to its light, and shadow rays from inside the
//!   leaf that leave it through that face, are all blocked (brute force);
//! - with and without propagation, the P-LIEs hold the same records, except fully dark ones that
//!   propagation deleted without computing them;
//! - images rendered from P-LIEs with many propagated records are bit-identical to brute force's (and
//!   tests/exactness.rs and tests/images.rs check every mode with the thesis' parameters, which
//!   propagate);
//! - the result does not depend on the thread count.

mod support;

use glam::{Vec2, Vec3};
use plie::internals::construct::Built;
use plie::internals::lie::{Plie, PlieParams, Propagation};
use plie::internals::render::RenderSettings;
use plie::internals::visibility::lie::exit_face;
use plie::octree::{Dir, LeafId, Octree};
use plie::visibility::{Brute, Mode, QueryCtx, ShadowRay, Visibility};
use plie::{LightId, Scene, TriId};
use support::TestRng;

/// Scenes above this many triangles get the soundness check only (a build without propagation too would
/// take minutes).
const MAX_TRIANGLES: usize = 50_000;

fn build(scene: &Scene, octree: &Octree, params: PlieParams) -> Built {
    support::construct(scene, octree, params)
}

/// Every sampled segment from each propagated face (corners, edges and interior) to its light, and
/// every sampled shadow ray from inside the leaf that leaves it through that face, is blocked.
/// Returns the number of segments checked.
fn check_sound(scene: &Scene, octree: &Octree, built: &Built, samples: usize) -> usize {
    let brute = Brute::new(scene);
    let mut ctx = QueryCtx::new(scene.triangles.len());
    let mut rng = TestRng(0x9e0f ^ scene.triangles.len() as u64);
    let mut checked = 0;
    let none = TriId(u32::MAX);
    for d in &built.propagated {
        let light = &scene.lights[d.light.idx()];
        let b = octree.leaf_bounds(d.leaf);
        let q = d.face.face_corners(&b);
        let in_front = |x: Vec3, y: Vec3| (x - y).dot(light.normal) > 0.0;
        for k in 0..samples {
            let y = light.sample(Vec2::new(rng.f32(), rng.f32()));
            // A face point: the corners, points on the edges, then anywhere.
            let (a, c) = match k {
                0..4 => ((k & 1) as f32, (k >> 1) as f32),
                4..8 => (rng.f32(), (k & 1) as f32),
                _ => (rng.f32(), rng.f32()),
            };
            let f = q[0] + (q[1] - q[0]) * a + (q[3] - q[0]) * c;
            if (y - f).dot(d.face.normal()) > 0.0 && in_front(f, y) {
                let ray = ShadowRay::new(f, y, d.light, none, None);
                assert!(brute.occluded(&ray, &mut ctx), "{}: propagated {d:?} sees {y} from {f}", scene.name);
                checked += 1;
            }
            // A point inside the leaf whose ray leaves through the face.
            let x = rng.point_in(b.min, b.max);
            let ray = ShadowRay::new(x, y, d.light, none, Some(d.leaf));
            if in_front(x, y) && exit_face(octree, d.leaf, &ray).is_some_and(|(face, _)| face == d.face) {
                assert!(brute.occluded(&ray, &mut ctx), "{}: propagated {d:?}, ray {x} -> {y}", scene.name);
                checked += 1;
            }
        }
    }
    checked
}

/// Without propagation every record is computed; with it, the same records are kept, identical, and
/// every other one is either removed in both or deleted by propagation.
fn check_same_records(scene: &Scene, octree: &Octree, with: &Built, without: &Plie) {
    let plie = &with.plie;
    let mut propagated: Vec<(LeafId, Dir, LightId)> =
        with.propagated.iter().map(|d| (d.leaf, d.face, d.light)).collect();
    propagated.sort();
    for leaf in octree.leaves() {
        for face in Dir::ALL {
            for li in 0..scene.lights.len() as u32 {
                let light = LightId(li);
                let key = (leaf, face, light);
                let is_propagated = propagated.binary_search(&key).is_ok();
                match (plie.record_id(leaf, face, light), without.record_id(leaf, face, light)) {
                    (Some(a), Some(b)) => {
                        assert!(!is_propagated, "{}: {key:?} propagated but kept", scene.name);
                        assert_eq!(plie.blockers_of(&plie.records[a]), without.blockers_of(&without.records[b]));
                        assert_eq!(plie.umbra_of(a), without.umbra_of(b), "{}: {key:?} umbra", scene.name);
                        assert_eq!(plie.penumbra_of(a), without.penumbra_of(b), "{}: {key:?} penumbra", scene.name);
                        let (ga, gb) = (plie.grids[a], without.grids[b]);
                        assert_eq!(ga.res, gb.res);
                        for c in 0..(ga.res * ga.res) as usize {
                            assert_eq!(plie.cell(&ga, c), without.cell(&gb, c), "{}: {key:?} cell {c}", scene.name);
                        }
                    }
                    (Some(_), None) => panic!("{}: {key:?} only with propagation", scene.name),
                    (None, Some(_)) => {
                        assert!(is_propagated, "{}: {key:?} lost without being propagated", scene.name)
                    }
                    (None, None) => {}
                }
            }
        }
    }
}

/// Both checks on one scene; returns (records propagated, segments checked).
fn check_scene(scene: &Scene, max_triangles: usize, samples: usize) -> (usize, usize) {
    let params = PlieParams { max_triangles, ..PlieParams::default() };
    let octree = Octree::build(scene, params.octree()).expect("valid octree parameters");
    let with = build(scene, &octree, params);
    let without = build(scene, &octree, PlieParams { propagation: Propagation::Off, ..params });
    assert!(without.propagated.is_empty());
    assert_eq!(with.stats.propagation.records_removed, with.propagated.len());
    check_same_records(scene, &octree, &with, &without.plie);
    (with.propagated.len(), check_sound(scene, &octree, &with, samples))
}

#[test]
fn propagated_records_are_dark_and_the_rest_unchanged_on_builtin_scenes() {
    let (mut propagated, mut checked) = (0, 0);
    for name in plie::scene::builtin::NAMES {
        let scene = plie::scene::builtin::load(name).unwrap();
        for max_triangles in [200, 24] {
            let (p, c) = check_scene(&scene, max_triangles, 16);
            eprintln!("{name} ({max_triangles} per leaf): {p} records propagated, {c} segments blocked");
            (propagated, checked) = (propagated + p, checked + c);
        }
    }
    assert!(propagated > 1000 && checked > 10_000, "{propagated} {checked}");
}

#[test]
#[ignore = "exhaustive tier (real scenes): cargo test --workspace -- --ignored"]
fn propagated_records_are_dark_and_the_rest_unchanged_on_shared_scenes() {
    for scene in support::load_shared() {
        if scene.triangles.len() > MAX_TRIANGLES {
            // Soundness only, at the thesis' 200 per leaf: a second build without propagation would
            // take minutes.
            let params = PlieParams::thesis();
            let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
            let with = build(&scene, &octree, params);
            let c = check_sound(&scene, &octree, &with, 16);
            eprintln!(
                "{} (200 per leaf): {} records propagated, {c} segments blocked",
                scene.name,
                with.propagated.len()
            );
            continue;
        }
        for max_triangles in [200, 24] {
            let (p, c) = check_scene(&scene, max_triangles, 16);
            eprintln!("{} ({max_triangles} per leaf): {p} records propagated, {c} segments blocked", scene.name);
        }
    }
}

/// Refinement (SPEC §4.8) reuses propagated faces of leaves it keeps and propagates into the new ones:
/// every face logged as propagated in the refined octree is dark.
#[test]
fn propagated_records_of_refined_p_lies_are_dark() {
    let mut propagated = 0;
    for name in ["huis-a", "huis-c", "boot"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let params = PlieParams {
            refine: plie::internals::construct::refine::RefineParams::thesis_umbra(),
            ..PlieParams::thesis()
        };
        let b = support::construct(
            &scene,
            &Octree::build(&scene, params.octree()).expect("valid octree parameters"),
            params,
        );
        assert!(b.stats.refinement.rounds > 0);
        assert_eq!(b.stats.propagation.records_removed, b.propagated.len());
        let c = check_sound(&scene, &b.octree, &b, 16);
        eprintln!("{name} refined: {} records propagated, {c} segments blocked", b.propagated.len());
        propagated += b.propagated.len();
    }
    assert!(propagated > 100, "{propagated}");
}

#[test]
fn propagation_does_not_depend_on_the_thread_count() {
    let scene = plie::scene::builtin::load("huis-a").unwrap();
    let params = PlieParams { max_triangles: 24, ..PlieParams::thesis() };
    let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
    let on = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| build(&scene, &octree, params))
    };
    let one = on(1);
    assert!(one.propagated.len() > 100, "{}", one.propagated.len());
    for threads in [2, 3] {
        let other = on(threads);
        assert_eq!(one.propagated, other.propagated, "{threads} threads");
        assert!(one.plie == other.plie, "P-LIE differs between 1 and {threads} threads");
    }
}

#[test]
fn images_with_many_propagated_records_match_brute_force() {
    let settings = RenderSettings { width: 48, height: 48, eye_rays: 1, shadow_rays: 4, seed: 3 };
    for name in ["huis-a", "huis-c", "boot"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let params = PlieParams { max_triangles: 24, ..PlieParams::default() };
        let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
        let built = build(&scene, &octree, params);
        assert!(built.propagated.len() > 100, "{name}: {}", built.propagated.len());
        let bvh = plie::visibility::bvh::Bvh::build(&scene);
        let camera = scene.camera_or_default();
        let env = plie::Environment::from_parts(&scene, octree.clone(), built.plie.clone());
        let image = |mode: Mode| {
            let vis = env.visibility(mode, &scene).unwrap();
            let px = support::render(&scene, &camera, &settings, &bvh, Some(&octree), vis.as_ref());
            px.iter().map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>()
        };
        let reference = image(Mode::Brute);
        for mode in [Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid] {
            assert!(image(mode) == reference, "{name}: {mode} differs from brute force");
        }
    }
}
