//! What propagation knows about each (leaf, face, light): whether a record is needed at all, whether it
//! is still to be computed, kept, computed dark, or deleted by propagation, and for dark faces the
//! *budget* that says how long a shadow ray the darkness vouches for (see [`dark_budget`]).

use glam::DVec3;

use super::Tolerances;
use crate::construct::data_objects::face_sees_light;
use crate::construct::regions::FaceRegions;
use crate::geometry::Aabb;
use crate::geometry::SEGMENT_EPS;
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::{Light, LightId, Scene};

/// The state of one (leaf, face, light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FaceState {
    /// The face cannot see the light (SPEC §4.1): never a record.
    NoLight,
    /// The face sees the light and its record is not computed yet.
    Pending,
    /// Computed: the record is kept.
    Kept,
    /// Computed: fully in umbra, the record is removed (§4.6). Segments that cross the face toward
    /// the light and are shorter than `budget` are blocked; `budget == 0` when the umbra cannot vouch
    /// for propagation (see [`dark_budget`]).
    Dark {
        /// Longest shadow ray (world units) the darkness vouches for.
        budget: f64,
    },
    /// Deleted by propagation without computing it (§4.7). Shadow rays shorter than `budget` that
    /// pass within the tolerance of the face toward the light are blocked.
    Propagated {
        /// Longest shadow ray (world units) the darkness vouches for.
        budget: f64,
    },
}

impl FaceState {
    /// The budget of a face known to be dark that can vouch for propagation.
    pub fn vouches(self) -> Option<f64> {
        match self {
            FaceState::Dark { budget } | FaceState::Propagated { budget } if budget > 0.0 => Some(budget),
            _ => None,
        }
    }
}

/// The [`FaceState`] of every (leaf, face, light), indexed like [`crate::lie::Plie::record_index`].
#[derive(Clone, Debug, PartialEq)]
pub struct FaceStates {
    lights: usize,
    states: Vec<FaceState>,
}

impl FaceStates {
    /// `NoLight` where the face cannot see the light (the exact §4.1 test with tolerance `tol`),
    /// `Pending` elsewhere.
    pub fn new(scene: &Scene, octree: &Octree, tol: f32) -> FaceStates {
        let lights = scene.lights.len();
        let mut states = Vec::with_capacity(octree.leaf_count() * 6 * lights);
        for leaf in octree.leaves() {
            let b = octree.leaf_bounds(leaf);
            for face in Dir::ALL {
                let corners = face.face_corners(&b);
                for light in &scene.lights {
                    let sees = face_sees_light(&corners, face.normal(), light, tol);
                    states.push(if sees { FaceState::Pending } else { FaceState::NoLight });
                }
            }
        }
        FaceStates { lights, states }
    }

    /// The index of (leaf, face, light), `0..len()`.
    #[inline]
    pub fn index(&self, leaf: LeafId, face: Dir, light: LightId) -> usize {
        FaceStates::index_of(self.lights, leaf, face, light)
    }

    /// The index of (leaf, face, light) among `lights` lights ([`FaceStates::index`]).
    #[inline]
    pub fn index_of(lights: usize, leaf: LeafId, face: Dir, light: LightId) -> usize {
        (leaf.idx() * 6 + face.index()) * lights + light.idx()
    }

    /// Number of (leaf, face, light).
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// True if there is no leaf or no light.
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// The state of (leaf, face, light).
    #[inline]
    pub fn get(&self, leaf: LeafId, face: Dir, light: LightId) -> FaceState {
        self.states[self.index(leaf, face, light)]
    }

    /// The state at index `i` ([`FaceStates::index`]).
    #[inline]
    pub fn at(&self, i: usize) -> FaceState {
        self.states[i]
    }

    /// Sets the state of (leaf, face, light).
    #[inline]
    pub fn set(&mut self, leaf: LeafId, face: Dir, light: LightId, s: FaceState) {
        let i = self.index(leaf, face, light);
        self.states[i] = s;
    }

    /// Number of (leaf, face, light) in state `Propagated`.
    pub fn propagated(&self) -> usize {
        self.states.iter().filter(|s| matches!(s, FaceState::Propagated { .. })).count()
    }
}

/// How much the watertight test's `t` of a blocking hit must clear `SEGMENT_EPS` by, relatively: far
/// above the `f32` error of `t`.
pub const BUDGET_SLACK: f64 = 1.001;

/// The budget of a face computed fully dark: the longest shadow ray `x -> y` that the umbra proves
/// blocked when the ray leaves the cell grown by `delta` through this face, or 0 if it proves none.
///
/// Such a ray is `delta` above the face plane where it leaves the grown cell and within `delta` of
/// the face in its plane; followed back to the face plane it crosses it within
/// `delta (1 + tan θ)` of the face, `θ` its angle with the face normal, bounded by the in-plane reach
/// `D` of the light over its lowest height `h_min`: `tan θ <= D / (h_min - delta)`. That crossing must
/// lie in the face grown by half the umbra's margin (the umbra covers the face grown by the whole
/// margin). The ray is then blocked between the heights `h_lo` and `h_hi` of the umbra's blockers,
/// while `x` lies at most `delta` above the face plane and `y` at least `h_min`. Heights are linear
/// along the ray, so the hit's parameter is at least `(h_lo - delta) / |y - x|` and at most
/// `1 - (h_min - h_hi) / |y - x|`: it counts for the watertight test (`t` in `(SEGMENT_EPS,
/// 1 - SEGMENT_EPS)`, with [`BUDGET_SLACK`]) when `|y - x|` is below the budget.
pub fn dark_budget(face: Dir, cell: &Aabb, light: &Light, regions: &FaceRegions, t: &Tolerances) -> f64 {
    let Some((lo, hi)) = regions.hit_heights else { return 0.0 };
    let delta = t.delta;
    let k = face.axis();
    let domain = light.sample_domain();
    // Heights and in-plane offsets of the light's sampling domain grown by `delta`.
    let w = if face.is_positive() { cell.max[k] } else { cell.min[k] } as f64;
    let sign = if face.is_positive() { 1.0 } else { -1.0 };
    let lowest = domain.iter().map(|v| sign * (v[k] as f64 - w)).fold(f64::INFINITY, f64::min);
    let min_h = regions.min_light_height.min(lowest) - delta;
    if min_h <= 2.0 * delta {
        return 0.0;
    }
    let in_plane = |p: DVec3| {
        let mut q = p;
        q[k] = 0.0;
        q.length()
    };
    // From the face grown by `delta` (at most `2 delta` more than from the face itself).
    let reach = face
        .face_corners(cell)
        .iter()
        .flat_map(|c| domain.iter().map(move |v| in_plane(v.as_dvec3() - c.as_dvec3()) + 4.0 * delta))
        .fold(0.0f64, f64::max);
    let tan = reach / (min_h - delta);
    if delta * (1.0 + tan) > 0.5 * regions.margin_world {
        return 0.0;
    }
    ((lo - delta).min(min_h - hi) / (BUDGET_SLACK * SEGMENT_EPS as f64)).max(0.0)
}
