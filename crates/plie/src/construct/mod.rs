//! P-LIE construction (SPEC §4), built once for every leaf, face and light, independent of any camera.
//! This file only runs the stages in order; each stage is its own module:
//!
//! 1. [`data_objects`]: which (leaf, face, light) need a record (§4.1, exact condition).
//! 2. [`shaft`]: bounding volume and supporting planes of conv(face ∪ light) (§4.2, §4.3).
//! 3. [`blockers`]: gather candidates from the overlapping leaves, de-duplicate, clip (§4.4). With a
//!    blocker cap (issue 15), [`lift`] gathers the records over it again after the round with a
//!    larger cap, while a budget of clips lasts, and [`scene_cells`] gathers the cells of those
//!    still over it with a small cap, while a second budget lasts.
//! 4. [`regions`]: umbra and penumbra on the face (§4.5); a record fully in umbra is removed (§4.6).
//! 5. [`grid`]: per record, a face grid of per-cell blocker lists with its umbra cells marked (our
//!    addition, SPEC §8 points 2-4).
//! 6. [`propagation`]: faces proven dark by a dark neighbour lose their record before stages 2-5 run
//!    for them (§4.7).
//!
//! 7. [`refine`]: a chain of criteria picks leaves to split (§4.8); the next round computes the new
//!    leaves' records with stages 1-6 and reuses every other record (they do not depend on how other
//!    leaves are split), until no leaf asks or the maximum split depth is reached.
//!
//! The (leaf, light) tasks of a round run in parallel in a fixed order and are committed in that
//! order (`round`, [`schedule`]); propagation runs at each commit, so the result does not depend on
//! the thread count. `record` runs stages 2-5 for one face; `flatten` turns the last round into
//! the [`Plie`]'s arrays and [`BuildStats`].

pub mod blockers;
pub mod data_objects;
mod flatten;
pub mod grid;
pub mod lift;
pub mod propagation;
mod record;
pub mod refine;
pub mod regions;
mod round;
pub mod scene_cells;
pub mod schedule;
pub mod shaft;
mod stats;

use std::time::Instant;

pub use crate::lie::Limits;
use crate::lie::{Plie, PlieParams};
use crate::octree::Octree;
use crate::progress::Progress;
use crate::scene::Scene;
use lift::{lift_caps, Lift};
use propagation::Propagated;
use refine::Refiner;
use round::{run_round, Prior};
use scene_cells::{gather_scene_cells, Cells};
pub use stats::{
    BlockerStats, BoundedStats, BuildStats, GridStats, OctreeStats, PropagationStats, RefinementStats, RegionStats,
    RoundStats,
};

pub use crate::geometry::TOLERANCE_REL;

/// The absolute tolerance of the construction for `scene` over `octree`: [`TOLERANCE_REL`] times the
/// larger of the scene's size and the octree's root cube, or, for a scene far from the origin, the
/// rounding of the root cube's coordinates ([`crate::geometry::tolerance_of`]). Every test that must
/// agree with the builder (e.g. `plie inspect` telling a removed record from a face that cannot see
/// the light) uses this.
pub fn tolerance(scene: &Scene, octree: &Octree) -> f32 {
    crate::geometry::tolerance_of(scene.scale().max(octree.root_bounds().size().max_element()), abs_scale(octree))
}

/// The largest absolute coordinate of `octree`'s root cube: the scale of the `f32` rounding the
/// regions and propagation allow for.
pub(crate) fn abs_scale(octree: &Octree) -> f32 {
    octree.root_bounds().largest_abs()
}

/// The construction was interrupted ([`Progress::cancelled`]); nothing was built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("interrupted")]
pub struct Interrupted;

/// The P-LIE, the octree it belongs to, its statistics, and the records propagation deleted.
pub struct Built {
    /// The octree (refined if refinement split any leaf).
    pub octree: Octree,
    /// The P-LIE.
    pub plie: Plie,
    /// Its statistics.
    pub stats: BuildStats,
    /// The records deleted by propagation (leaves of [`Built::octree`]), in the order they were.
    pub propagated: Vec<Propagated>,
}

/// [`build_bounded`] without limits or refinement, for the crate's unit tests.
#[cfg(test)]
pub(crate) fn build(scene: &Scene, octree: &Octree, params: PlieParams, progress: &dyn Progress) -> (Plie, BuildStats) {
    assert!(!params.refine.enabled(), "construct::build does not refine the octree");
    let b = build_bounded(scene, octree.clone(), params, Limits::default(), progress).expect("not cancelled");
    (b.plie, b.stats)
}

/// Builds the P-LIE of `scene` over `octree` (stages 1-6) and refines the octree as `params.refine`
/// asks (stage 7), within `limits`, returning the refined octree with it; returns [`Interrupted`] as
/// soon as `progress` says [`Progress::cancelled`]. ([`crate::Environment::build`] is the entry point
/// for users: it builds the octree from the parameters and checks them first.)
pub fn build_bounded(
    scene: &Scene,
    octree: Octree,
    params: PlieParams,
    limits: Limits,
    progress: &dyn Progress,
) -> Result<Built, Interrupted> {
    let t0 = Instant::now();
    let mut octree = octree;
    let mut refiner = Refiner::new(&octree);
    let mut totals = flatten::Totals::default();
    totals.lift = Lift::new(&limits);
    totals.cells = Cells::new(&limits);
    let mut prior = None;
    let round = loop {
        // Stages 1-6 for every (leaf, light), but those of leaves the last round did not split.
        let mut round = run_round(scene, &octree, params, limits, progress, &refiner.stage(), prior.take())?;
        lift_caps(scene, &octree, params, &limits, progress, &mut round, &mut totals.lift)?;
        gather_scene_cells(scene, &octree, params, &limits, progress, &mut round, &mut totals.cells)?;
        totals.add(&round);
        if !params.refine.enabled() {
            break round;
        }
        totals.unrefined.get_or_insert_with(|| round.summary(&octree, t0));
        // Stage 7: the chain of criteria picks leaves to split; the next round computes their children.
        let split = refiner.choose(scene, &octree, &round, &params.refine);
        if split.is_empty() {
            break round;
        }
        let (refined, origin) = refiner.split(scene, &octree, &split);
        prior = Some(Prior { round, origin });
        octree = refined;
    };
    let mut built = flatten::finish(scene, octree, params, round, refiner, totals, t0);
    built.plie.limits = limits;
    Ok(built)
}
