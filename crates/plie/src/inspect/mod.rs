//! `plie inspect`: what the P-LIE stores for one cell (SPEC §4), shown the way the thesis' figures
//! 4.2, 5.8, 5.11 and 5.12 show it: the octree's leaves, the leaf holding a point, and per face and
//! light its data object, blockers (§4.4), umbra and penumbra (§4.5).
//!
//! - [`Inspector::inspect`] finds the leaf containing a point and gathers, for one light and the chosen
//!   faces (one face, or every face that sees the light), each face's [`FaceStatus`], its blockers and
//!   its regions as world-space triangles: an [`Inspection`].
//! - [`summary`] reports leaves: data objects per face and light, blockers, umbra and penumbra area
//!   fractions (summed from the stored triangles), removed faces.
//! - [`overlay`] turns an [`Inspection`] into a scene that plie's own renderer draws (the PNG of
//!   `plie inspect`); [`crate::io::gltf_export`] writes the same as a glTF scene.
//!
//! **No record: removed or unlit.** A (leaf, face, light) has no record either because the face
//! cannot see the light (§4.1) or because the face lies fully in umbra and its record was removed
//! (§4.6). To tell them apart the face/light condition is evaluated again with the builder's own
//! tolerance ([`crate::construct::tolerance`]). A removed face is shown fully in umbra; its blockers
//! were dropped with the record, so they are gathered again exactly as the builder gathered them
//! (same shaft, same tolerance), so that the picture shows what casts the umbra.

pub mod overlay;
pub mod summary;

use glam::{DVec2, DVec3, Vec3};

use crate::construct::blockers::{gather_blockers, GatherScratch};
use crate::construct::data_objects::face_sees_light;
use crate::construct::shaft::Shaft;
use crate::error::{Error, Result};
use crate::geometry::clip::clip3;
use crate::geometry::Aabb;
use crate::lie::frame::{FaceFrame, Tri2, UNITS};
use crate::lie::Plie;
use crate::octree::{Dir, LeafId, Octree};
use crate::scene::{LightId, Scene, TriId};

/// Colour of blockers where they lie in the shaft between face and light (linear RGB).
pub const BLOCKER_COLOUR: Vec3 = Vec3::new(0.08, 0.25, 1.0);
/// Colour of the rest of the blocker triangles (the part outside every shaft shown).
pub const BLOCKER_REST_COLOUR: Vec3 = Vec3::new(0.42, 0.5, 0.78);
/// Colour of umbra regions.
pub const UMBRA_COLOUR: Vec3 = Vec3::new(0.0, 0.8, 0.0);
/// Colour of penumbra regions.
pub const PENUMBRA_COLOUR: Vec3 = Vec3::new(1.0, 0.85, 0.0);
/// Colour of the octree's leaf edges.
pub const LEAF_COLOUR: Vec3 = Vec3::new(0.03, 0.03, 0.03);
/// Colour of the inspected leaf's edges.
pub const HIGHLIGHT_COLOUR: Vec3 = Vec3::new(1.0, 0.0, 1.0);

/// How far regions are drawn off their face, as a fraction of the leaf's size (penumbra; umbra twice
/// as far, so it shows where the two overlap by construction).
pub const REGION_LIFT: f32 = 1e-3;
/// How far clipped blockers are drawn off their triangle, as a fraction of the scene's size.
pub const BLOCKER_LIFT: f32 = 1e-4;

/// What the P-LIE holds for one (leaf, face, light).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceStatus {
    /// A data object: its index in [`Plie::records`].
    Record(usize),
    /// The face sees the light but lies fully in umbra: its record was removed (§4.6).
    Removed,
    /// The face cannot see the light (§4.1): no light from it enters the cell through this face.
    CannotSeeLight,
}

impl FaceStatus {
    /// A short lower-case name: `record`, `removed`, `cannot_see_light`.
    pub fn name(self) -> &'static str {
        match self {
            FaceStatus::Record(_) => "record",
            FaceStatus::Removed => "removed",
            FaceStatus::CannotSeeLight => "cannot_see_light",
        }
    }

    /// True unless the face cannot see the light (a "lit face" in §4.7's sense).
    pub fn sees_light(self) -> bool {
        self != FaceStatus::CannotSeeLight
    }
}

/// One face of the inspected leaf for the inspected light.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceView {
    /// The face.
    pub face: Dir,
    /// What the P-LIE holds for it.
    pub status: FaceStatus,
    /// Its blockers: the record's, or for a removed face gathered again as the builder did.
    pub blockers: Vec<TriId>,
    /// The blockers clipped to the shaft between face and light (§4.4 step 3: the part of each
    /// blocker that light on its way to this face can meet): each blocker with its part in the shaft,
    /// a convex polygon in world space (blockers only touching the grown shaft have none).
    pub clipped: Vec<(TriId, Vec<Vec3>)>,
    /// Umbra triangles in the face's plane (world space, counter-clockwise around the outward normal);
    /// the whole face when removed.
    pub umbra: Vec<[Vec3; 3]>,
    /// Penumbra triangles, as `umbra`.
    pub penumbra: Vec<[Vec3; 3]>,
    /// Umbra area as a fraction of the face.
    pub umbra_fraction: f64,
    /// Penumbra area as a fraction of the face.
    pub penumbra_fraction: f64,
}

/// The leaf containing a point, for one light: the faces shown and their blockers.
#[derive(Clone, Debug, PartialEq)]
pub struct Inspection {
    /// The point asked about.
    pub point: Vec3,
    /// The leaf containing it.
    pub leaf: LeafId,
    /// The leaf's box.
    pub bounds: Aabb,
    /// The leaf's depth.
    pub depth: u32,
    /// The light.
    pub light: LightId,
    /// The faces shown, in [`Dir::ALL`] order: the one asked for, or every face that sees the light.
    pub faces: Vec<FaceView>,
    /// The blockers of the faces shown, without duplicates, by ascending id.
    pub blockers: Vec<TriId>,
}

/// Reads a P-LIE together with its scene and octree; see the module doc.
pub struct Inspector<'a> {
    scene: &'a Scene,
    octree: &'a Octree,
    plie: &'a Plie,
    tol: f32,
}

impl<'a> Inspector<'a> {
    /// An inspector of `plie`, which must have been built for `scene` on `octree`.
    pub fn new(scene: &'a Scene, octree: &'a Octree, plie: &'a Plie) -> Result<Inspector<'a>> {
        if plie.leaves as usize != octree.leaf_count() || plie.lights as usize != scene.lights.len() {
            return Err(Error::InvalidParameter(format!(
                "the P-LIE has {} leaves and {} lights, but the octree has {} leaves and the scene {} lights",
                plie.leaves,
                plie.lights,
                octree.leaf_count(),
                scene.lights.len()
            )));
        }
        Ok(Inspector { scene, octree, plie, tol: crate::construct::tolerance(scene, octree) })
    }

    /// The scene.
    pub fn scene(&self) -> &'a Scene {
        self.scene
    }

    /// The octree.
    pub fn octree(&self) -> &'a Octree {
        self.octree
    }

    /// The P-LIE.
    pub fn plie(&self) -> &'a Plie {
        self.plie
    }

    /// The leaf containing `p`; an error naming the root cube if `p` lies outside the octree.
    pub fn leaf_at(&self, p: Vec3) -> Result<LeafId> {
        let r = self.octree.root_bounds();
        self.octree.locate(p).ok_or_else(|| {
            Error::InvalidParameter(format!(
                "point ({}, {}, {}) lies outside the octree of '{}': its root cube spans ({}, {}, {}) to ({}, {}, {})",
                p.x, p.y, p.z, self.scene.name, r.min.x, r.min.y, r.min.z, r.max.x, r.max.y, r.max.z
            ))
        })
    }

    /// The light with index `i`; an error if the scene has no such light.
    pub fn light(&self, i: u32) -> Result<LightId> {
        let n = self.scene.lights.len();
        if (i as usize) < n {
            return Ok(LightId(i));
        }
        Err(Error::InvalidParameter(format!(
            "light {i} does not exist: '{}' has {n} light{} (0{})",
            self.scene.name,
            if n == 1 { "" } else { "s" },
            if n > 1 { format!("..{}", n - 1) } else { String::new() }
        )))
    }

    /// What the P-LIE holds for (leaf, face, light).
    pub fn status(&self, leaf: LeafId, face: Dir, light: LightId) -> FaceStatus {
        if let Some(r) = self.plie.record_id(leaf, face, light) {
            return FaceStatus::Record(r);
        }
        let corners = face.face_corners(&self.octree.leaf_bounds(leaf));
        if face_sees_light(&corners, face.normal(), &self.scene.lights[light.idx()], self.tol) {
            FaceStatus::Removed
        } else {
            FaceStatus::CannotSeeLight
        }
    }

    /// The faces of `leaf` that see `light` (with a record or removed).
    pub fn lit_faces(&self, leaf: LeafId, light: LightId) -> Vec<Dir> {
        Dir::ALL.into_iter().filter(|&d| self.status(leaf, d, light).sees_light()).collect()
    }

    /// Everything shown of one face: status, blockers, regions in world space.
    pub fn face_view(&self, leaf: LeafId, face: Dir, light: LightId) -> FaceView {
        let bounds = self.octree.leaf_bounds(leaf);
        let status = self.status(leaf, face, light);
        let mut view = FaceView {
            face,
            status,
            blockers: Vec::new(),
            clipped: Vec::new(),
            umbra: Vec::new(),
            penumbra: Vec::new(),
            umbra_fraction: 0.0,
            penumbra_fraction: 0.0,
        };
        let corners = face.face_corners(&bounds);
        let shaft = Shaft::new(&corners, &self.scene.lights[light.idx()].vertices, self.tol);
        match status {
            FaceStatus::CannotSeeLight => return view,
            FaceStatus::Removed => {
                let mut scratch = GatherScratch::new(self.scene.triangles.len());
                gather_blockers(self.scene, self.octree, &shaft, light, None, &mut scratch, &mut view.blockers);
                view.umbra = vec![[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]];
                view.umbra_fraction = 1.0;
            }
            FaceStatus::Record(r) => {
                view.blockers = self.plie.blockers_of(&self.plie.records[r]).to_vec();
                if self.plie.records[r].kind == crate::lie::RecordKind::Scene {
                    // It stores no list (answered by the scene BVH): gather them as the builder would
                    // without a cap.
                    let mut scratch = GatherScratch::new(self.scene.triangles.len());
                    gather_blockers(self.scene, self.octree, &shaft, light, None, &mut scratch, &mut view.blockers);
                }
                let frame = FaceFrame::new(face, &bounds);
                view.umbra = world_triangles(&frame, face, self.plie.umbra_of(r));
                view.penumbra = world_triangles(&frame, face, self.plie.penumbra_of(r));
                view.umbra_fraction = area_fraction(self.plie.umbra_of(r));
                view.penumbra_fraction = area_fraction(self.plie.penumbra_of(r));
            }
        }
        view.clipped = view
            .blockers
            .iter()
            .filter_map(|&t| clip_to_shaft(&self.scene.triangle(t).v, &shaft).map(|poly| (t, poly)))
            .collect();
        view
    }

    /// The leaf containing `point`, for `light`: the face `face` (an error if it cannot see the light),
    /// or every face that sees the light.
    pub fn inspect(&self, point: Vec3, light: LightId, face: Option<Dir>) -> Result<Inspection> {
        let leaf = self.leaf_at(point)?;
        self.light(light.0)?;
        let faces: Vec<Dir> = match face {
            None => self.lit_faces(leaf, light),
            Some(d) => {
                if !self.status(leaf, d, light).sees_light() {
                    let lit = self.lit_faces(leaf, light);
                    let lit = if lit.is_empty() {
                        "none does".to_string()
                    } else {
                        format!("faces that see it: {}", lit.iter().map(|d| d.name()).collect::<Vec<_>>().join(", "))
                    };
                    return Err(Error::InvalidParameter(format!(
                        "face {} of leaf {} cannot see light {} (no data object; {lit})",
                        d.name(),
                        leaf.0,
                        light.0
                    )));
                }
                vec![d]
            }
        };
        let faces: Vec<FaceView> = faces.into_iter().map(|d| self.face_view(leaf, d, light)).collect();
        let mut blockers: Vec<TriId> = faces.iter().flat_map(|f| f.blockers.iter().copied()).collect();
        blockers.sort_unstable();
        blockers.dedup();
        Ok(Inspection {
            point,
            leaf,
            bounds: self.octree.leaf_bounds(leaf),
            depth: self.octree.leaf_depth(leaf),
            light,
            faces,
            blockers,
        })
    }
}

/// The part of `tri` inside the shaft, or `None` if nothing (or only a sliver) is left.
fn clip_to_shaft(tri: &[Vec3; 3], shaft: &Shaft) -> Option<Vec<Vec3>> {
    let mut poly: Vec<DVec3> = tri.iter().map(|p| p.as_dvec3()).collect();
    let mut tmp = Vec::new();
    for p in &shaft.planes {
        clip3(&mut poly, p.n, p.d, &mut tmp);
        if poly.len() < 3 {
            return None;
        }
    }
    Some(poly.into_iter().map(|p| p.as_vec3()).collect())
}

/// Region triangles (face units) in world space, counter-clockwise around the face's outward normal.
fn world_triangles(frame: &FaceFrame, face: Dir, tris: &[Tri2]) -> Vec<[Vec3; 3]> {
    let n = face.normal();
    tris.iter()
        .map(|t| {
            let p = t.map(|v| frame.point(DVec2::new(v[0] as f64, v[1] as f64)).as_vec3());
            if (p[1] - p[0]).cross(p[2] - p[0]).dot(n) < 0.0 {
                [p[0], p[2], p[1]]
            } else {
                p
            }
        })
        .collect()
}

/// The area of region triangles (face units) as a fraction of the face, at most 1.
pub fn area_fraction(tris: &[Tri2]) -> f64 {
    let twice = tris.iter().fold(0.0, |sum, t| {
        let p = t.map(|v| DVec2::new(v[0] as f64, v[1] as f64));
        sum + (p[1] - p[0]).perp_dot(p[2] - p[0]).abs()
    });
    (0.5 * twice / (UNITS * UNITS)).min(1.0)
}
