//! Refinement of the octree (SPEC §4.8):
//! - refined P-LIEs stay exact: every mode answers sampled shadow rays as the BVH (itself checked
//!   against brute force in tests/exactness.rs) and renders images bit-identical to brute force, on
//!   every built-in scene and on the real scenes in ../shared/scenes/;
//! - the records a refined build reuses from earlier rounds equal those of a build from scratch on
//!   the refined octree, and the result does not depend on the thread count;
//! - the maximum split depth bounds every chain, including one that would split without end.

mod support;

use glam::Vec3;
use plie::internals::construct::refine::{MaxBlockers, RefineParams};
use plie::internals::lie::{Grids, PlieParams, Propagation};
use plie::internals::render::RenderSettings;
use plie::octree::Octree;
use plie::visibility::{Mode, QueryCtx};
use plie::Scene;
use rayon::prelude::*;
use support::Built;

fn refined_params() -> PlieParams {
    PlieParams { refine: RefineParams::thesis_umbra(), ..PlieParams::thesis() }
}

fn bits(p: &[Vec3]) -> Vec<[u32; 3]> {
    p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
}

/// Every mode renders the brute-force image bit for bit, and answers sampled shadow rays as the BVH.
fn check_exact(scene: &Scene, built: &Built, settings: &RenderSettings, rays: usize) {
    let camera = scene.camera_or_default();
    let image = |mode: Mode| {
        let vis = built.vis(scene, mode);
        bits(&support::render(scene, &camera, settings, &built.bvh, Some(built.octree()), vis.as_ref()))
    };
    let reference = image(Mode::Brute);
    let lit = reference.iter().filter(|p| p.iter().any(|&c| f32::from_bits(c) > 0.0)).count();
    assert!(lit > reference.len() / 4, "{}: the image is mostly black", scene.name);
    let rays = support::shadow_rays(scene, built.octree(), rays, 4321);
    let answers = |mode: Mode| -> Vec<bool> {
        let vis = built.vis(scene, mode);
        rays.par_chunks(256)
            .flat_map_iter(|chunk| {
                let mut ctx = QueryCtx::new(scene.triangles.len());
                chunk.iter().map(|r| vis.occluded(r, &mut ctx)).collect::<Vec<_>>()
            })
            .collect()
    };
    let truth = answers(Mode::Bvh);
    for mode in Mode::EXACT.into_iter().filter(|m| m.needs_plie()) {
        let diff = image(mode).iter().zip(&reference).filter(|(a, b)| a != b).count();
        assert_eq!(diff, 0, "{}: refined {mode} differs from brute in {diff} pixels", scene.name);
        assert!(answers(mode) == truth, "{}: refined {mode} disagrees with bvh on shadow rays", scene.name);
    }
}

#[test]
fn refined_p_lies_are_exact_on_builtin_scenes() {
    let settings = RenderSettings { width: 32, height: 32, eye_rays: 1, shadow_rays: 4, seed: 11 };
    for scene in support::builtins() {
        let built = Built::refined(&scene, refined_params());
        assert_eq!(built.plie().params.refine, RefineParams::thesis_umbra());
        assert!(!built.plie().splits.is_empty(), "{}: refinement by umbra split nothing", scene.name);
        check_exact(&scene, &built, &settings, 20_000);
    }
}

#[test]
#[ignore = "exhaustive tier (real scenes): cargo test --workspace -- --ignored"]
fn refined_p_lies_are_exact_on_shared_scenes() {
    let settings = RenderSettings { width: 24, height: 24, eye_rays: 1, shadow_rays: 4, seed: 13 };
    for scene in support::load_shared() {
        let built = Built::refined(&scene, refined_params());
        eprintln!("{}: {} leaves after refinement", scene.name, built.octree().leaf_count());
        check_exact(&scene, &built, &settings, 5_000);
    }
}

#[test]
fn refined_p_lies_by_blockers_are_exact() {
    let settings = RenderSettings { width: 24, height: 24, eye_rays: 1, shadow_rays: 4, seed: 17 };
    for name in ["dragon", "huis-c", "cornell-cube-3"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let refine = RefineParams { blockers: Some(MaxBlockers::Adaptive), ..RefineParams::none() };
        let built = Built::refined(&scene, PlieParams { refine, ..PlieParams::thesis() });
        check_exact(&scene, &built, &settings, 10_000);
    }
}

/// With propagation off, a refined build equals a build from scratch on the refined octree: the
/// records reused from earlier rounds are exactly what a fresh build computes for those leaves.
#[test]
fn reused_records_equal_a_build_from_scratch() {
    for name in ["cornell-cube-1", "cornell-cube-4", "dragon", "huis-c"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let params = PlieParams { propagation: Propagation::Off, grids: Grids::Build, ..refined_params() };
        let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
        let refined = support::construct(&scene, &octree, params);
        assert!(refined.stats.refinement.rounds > 0, "{name}: nothing split");
        let fresh = support::construct(&scene, &refined.octree, PlieParams { refine: RefineParams::none(), ..params });
        let (fresh, stats) = (fresh.plie, fresh.stats);
        let mut got = refined.plie.clone();
        got.splits.clear();
        got.params.refine = RefineParams::none();
        assert!(got == fresh, "{name}: the refined build's records differ from a fresh build on its octree");
        assert_eq!(refined.stats.blockers.records, stats.blockers.records);
        assert_eq!(refined.stats.regions.records_removed_umbra, stats.regions.records_removed_umbra);
    }
}

/// The refined octree and P-LIE are the same for 1 and 2 threads, with propagation on.
#[test]
fn refinement_does_not_depend_on_the_thread_count() {
    for name in ["cornell-cube-5", "huis-a"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let octree = Octree::build(&scene, PlieParams::thesis().octree()).expect("valid octree parameters");
                let b = support::construct(&scene, &octree, PlieParams { grids: Grids::Build, ..refined_params() });
                (b.octree, b.plie, b.propagated)
            })
        };
        let (o1, p1, d1) = run(1);
        let (o2, p2, d2) = run(2);
        assert!(o1 == o2 && p1 == p2 && d1 == d2, "{name}: refinement differs between 1 and 2 threads");
    }
}

/// Cornell Cube 1's hovering plane is a blocker of every cell, so refinement by "more than 0
/// blockers" would split without end: the maximum split depth stops it, and every leaf stays within
/// it.
#[test]
fn max_split_depth_bounds_a_chain_that_would_never_stop() {
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let base = Octree::build(&scene, PlieParams::thesis().octree()).expect("valid octree parameters");
    assert!(base.leaves().all(|l| base.leaf_depth(l) == 1));
    for k in 0..=3u32 {
        let refine = RefineParams { blockers: Some(MaxBlockers::Fixed(0)), max_split_depth: k, ..RefineParams::none() };
        let params = PlieParams { refine, ..PlieParams::thesis() };
        let b = support::construct(&scene, &base, params);
        assert_eq!(b.stats.refinement.rounds, k as usize, "k = {k}");
        assert_eq!(b.plie.splits.len(), k as usize);
        assert_eq!(b.octree.depth(), 1 + k, "k = {k}: some leaf splits exactly k times");
        assert!(b.octree.leaves().all(|l| b.octree.leaf_depth(l) <= 1 + k));
        assert!(b.octree.validate(&scene).violations.is_empty());
        let splits: usize = b.stats.refinement.splits_by_criterion.values().sum();
        assert_eq!(b.octree.leaf_count(), base.leaf_count() + 7 * splits);
        assert_eq!(
            b.stats.refinement.splits_by_criterion.keys().copied().collect::<Vec<_>>(),
            if k == 0 { vec![] } else { vec!["blockers"] }
        );
        if k > 0 {
            let u = b.stats.refinement.unrefined.expect("the unrefined round's figures");
            assert_eq!(u.leaves, base.leaf_count());
            assert!(b.stats.blockers.records > u.records);
        }
    }
}

/// Refinement by umbra on Cornell Cube 1: the cells under the hovering plane split, and more records
/// are removed as fully dark than without refinement.
#[test]
fn umbra_refinement_removes_more_dark_records() {
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let octree = Octree::build(&scene, PlieParams::thesis().octree()).expect("valid octree parameters");
    let plain = support::construct(&scene, &octree, PlieParams::thesis()).stats;
    let b = support::construct(&scene, &octree, refined_params());
    assert!(
        b.stats.refinement.splits_by_criterion.get("umbra_full").copied().unwrap_or(0) > 0,
        "{:?}",
        b.stats.refinement.splits_by_criterion
    );
    let dark = |s: &plie::BuildStats| s.regions.records_removed_umbra + s.propagation.records_removed;
    assert!(dark(&b.stats) > dark(&plain), "refined {} dark records, unrefined {}", dark(&b.stats), dark(&plain));
}
