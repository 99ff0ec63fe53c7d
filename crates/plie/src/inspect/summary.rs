//! `plie inspect --summary`: per leaf, what the P-LIE stores for each face and light (SPEC §4): a data
//! object with its blocker count and umbra/penumbra area fractions (summed from the stored region
//! triangles, §4.5), a removed record (fully in umbra, §4.6), or none (the face cannot see the light,
//! §4.1). A removed record stores no blockers, so its count is absent, not recomputed.

use serde::{Serialize, Serializer};

use super::{area_fraction, FaceStatus, Inspector};
use crate::octree::{Dir, LeafId};
use crate::scene::LightId;

/// Which leaves, lights and faces a summary lists (`None`: all).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Filter {
    /// Only this leaf.
    pub leaf: Option<LeafId>,
    /// Only this light.
    pub light: Option<LightId>,
    /// Only this face.
    pub face: Option<Dir>,
}

/// One (face, light) of a leaf.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaceSummary {
    /// The face.
    #[serde(serialize_with = "dir_name")]
    pub face: Dir,
    /// The light's index.
    pub light: u32,
    /// What the P-LIE holds: `record`, `removed` or `cannot_see_light`.
    #[serde(serialize_with = "status_name")]
    pub status: FaceStatus,
    /// Blockers stored on the record (`None` without a record).
    pub blockers: Option<u32>,
    /// Umbra area as a fraction of the face: 1 when removed; `None` without a record or without
    /// regions (`--no-regions`).
    pub umbra_fraction: Option<f64>,
    /// Penumbra area as a fraction of the face: 0 when removed; `None` as for `umbra_fraction`.
    pub penumbra_fraction: Option<f64>,
}

/// One leaf.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LeafSummary {
    /// The leaf's index.
    pub leaf: u32,
    /// Its depth (the root is 0).
    pub depth: u32,
    /// Its box's minimum corner.
    pub min: [f32; 3],
    /// Its box's maximum corner.
    pub max: [f32; 3],
    /// Triangles in the leaf.
    pub triangles: usize,
    /// Its faces and lights, face-major in [`Dir::ALL`] order.
    pub faces: Vec<FaceSummary>,
}

/// The summary of the listed leaves.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// The scene's name.
    pub scene: String,
    /// Leaves of the octree (all of them, listed or not).
    pub octree_leaves: usize,
    /// Lights of the scene.
    pub lights: usize,
    /// Whether the P-LIE has umbra and penumbra regions.
    pub regions: bool,
    /// Listed (face, light) rows with a record.
    pub records: usize,
    /// Listed rows whose record was removed (fully in umbra).
    pub removed: usize,
    /// Listed rows whose face cannot see the light.
    pub cannot_see_light: usize,
    /// The listed leaves.
    pub leaves: Vec<LeafSummary>,
}

fn dir_name<S: Serializer>(d: &Dir, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(d.name())
}

fn status_name<S: Serializer>(st: &FaceStatus, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(st.name())
}

impl Inspector<'_> {
    /// The summary of the leaves, lights and faces `filter` selects.
    pub fn summary(&self, filter: Filter) -> Summary {
        let (scene, octree, plie) = (self.scene(), self.octree(), self.plie());
        let leaves: Vec<LeafId> = match filter.leaf {
            Some(l) => vec![l],
            None => octree.leaves().collect(),
        };
        let lights: Vec<LightId> = match filter.light {
            Some(l) => vec![l],
            None => (0..scene.lights.len() as u32).map(LightId).collect(),
        };
        let faces: Vec<Dir> = filter.face.map_or(Dir::ALL.to_vec(), |d| vec![d]);
        let mut out = Summary {
            scene: scene.name.clone(),
            octree_leaves: octree.leaf_count(),
            lights: scene.lights.len(),
            regions: plie.params.has_regions(),
            records: 0,
            removed: 0,
            cannot_see_light: 0,
            leaves: Vec::with_capacity(leaves.len()),
        };
        for leaf in leaves {
            let b = octree.leaf_bounds(leaf);
            let mut rows = Vec::with_capacity(faces.len() * lights.len());
            for &face in &faces {
                for &light in &lights {
                    let status = self.status(leaf, face, light);
                    let (blockers, umbra, penumbra) = match status {
                        FaceStatus::Record(r) => {
                            out.records += 1;
                            let fractions = plie
                                .params
                                .has_regions()
                                .then(|| (area_fraction(plie.umbra_of(r)), area_fraction(plie.penumbra_of(r))));
                            (Some(plie.records[r].blockers_len), fractions.map(|f| f.0), fractions.map(|f| f.1))
                        }
                        FaceStatus::Removed => {
                            out.removed += 1;
                            (None, Some(1.0), Some(0.0))
                        }
                        FaceStatus::CannotSeeLight => {
                            out.cannot_see_light += 1;
                            (None, None, None)
                        }
                    };
                    rows.push(FaceSummary {
                        face,
                        light: light.0,
                        status,
                        blockers,
                        umbra_fraction: umbra,
                        penumbra_fraction: penumbra,
                    });
                }
            }
            out.leaves.push(LeafSummary {
                leaf: leaf.0,
                depth: octree.leaf_depth(leaf),
                min: b.min.to_array(),
                max: b.max.to_array(),
                triangles: octree.leaf_triangles(leaf).len(),
                faces: rows,
            });
        }
        out
    }
}
