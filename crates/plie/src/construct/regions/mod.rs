//! Umbra and penumbra on a record's face (SPEC §4.5) and the test behind removal (§4.6).
//!
//! All work happens in the face's plane, in integer units: the face square is `UNITS` wide, and
//! i_overlay computes unions and differences on the snapped polygons, so booleans never fail on
//! near-degenerate input. For each blocker `T` and each light vertex `v`:
//!
//! - **Umbra of `T`** = intersection over `v` of the projection of `T` from `v` onto the face plane. For
//!   a convex light and a convex blocker, every segment from a point of it to any point of the light
//!   meets `T`. The face's umbra is the union over blockers.
//! - **Shadow region of `T`** = convex hull of its projections: every face point from which some
//!   segment to the light meets `T` lies in it. Penumbra = union of shadow regions minus umbra. The
//!   union is taken on a 64 x 64 raster of the face (every cell a shadow region meets), a superset
//!   that is all the "lit" answer needs and far cheaper than exact booleans of thousands of
//!   overlapping regions; the difference with the umbra is exact (i_overlay).
//!
//! **Exactness (SPEC §5).** A region decision must never disagree with the watertight test of the
//! actual shadow ray `x -> y`, which crosses the face at `f`, counts hits for `t` in
//! `(SEGMENT_EPS, 1 - SEGMENT_EPS)` only, and is computed in `f32`. So regions are built with margins:
//!
//! - *Umbra (a subset).* `T` is first shrunk inside its own plane by `r / cos` (`r` above `f32` error,
//!   `cos` the smallest cosine between `T`'s normal and any face-to-light direction; a blocker that some
//!   ray grazes is skipped), so a ray through the shrunk part hits `T` well inside its edges. It is then
//!   cut to the slab at least `guard` above the face and below the lowest light vertex, so the hit lies
//!   inside the ray's parameter range. The projections are eroded by `margin` (face-point error plus
//!   snapping) before they are intersected.
//! - *Shadow region (a superset).* `T` is clipped to the grown shaft (a blocking hit lies in it) and
//!   the hull of its projections is dilated by a bound on how far an `r` move of a blocker point or
//!   of the light point moves the projection, plus `margin`. When some blocker point reaches the height
//!   of a light vertex, projections are unbounded and the shadow region is the whole face.
//! - Penumbra is shadow minus an umbra *core* (the umbra eroded by a few more units), so umbra and
//!   penumbra overlap slightly and no snapped gap between them can pass for "lit".
//!
//! A record whose face, grown by the margin, lies inside the umbra is fully dark: every ray through it
//! is blocked, and it can be removed (§4.6).
//!
//! This file runs the steps for one record; each concern is its own module: `project` (one
//! blocker's umbra and shadow region), `patches` (blockers fused along shared edges), `crossing`
//! (umbra cast by several blockers together), `raster` (the union of shadow regions) and
//! `polygon` (integer polygons and their booleans).

mod crossing;
mod patches;
mod polygon;
mod project;
mod raster;

use crossing::Flat;
use patches::fused_patches;
use polygon::{area, difference, square, triangulate, union, vertex_count};
use project::{Shadow, Umbra};
use raster::Raster;

use glam::{DVec2, DVec3};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay::{Overlay, ShapeType};
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::i_shape::int::shape::{IntContour, IntShapes};

use super::shaft::Shaft;
use crate::geometry::clip::signed_area2;
use crate::geometry::Aabb;
use crate::geometry::SEGMENT_EPS;
use crate::lie::frame::{FaceFrame, Tri2, UNITS};
use crate::octree::Dir;
use crate::scene::{Light, Scene, TriId};

/// Extra erosion, in units, of the umbra core that penumbra is cut from.
const CORE_EXTRA: f64 = 3.0;

/// Blockers that some face-to-light direction meets at a cosine below this get no umbra.
const MIN_COS: f64 = 0.02;

/// The error bound `r` (world units) the regions are built with: above `f32` rounding of the scene's
/// coordinates (`abs_scale` is the largest absolute coordinate) and at least the construction
/// tolerance `tol`.
pub fn error_bound(tol: f32, abs_scale: f32) -> f64 {
    (tol as f64).max(abs_scale as f64 * 1e-5)
}

/// Umbra and penumbra of one record, triangulated in its face's units.
#[derive(Clone, Debug, Default)]
pub struct FaceRegions {
    /// Umbra triangles (points inside are fully dark).
    pub umbra: Vec<Tri2>,
    /// Penumbra triangles (outside umbra and penumbra a point is fully lit by the blockers).
    pub penumbra: Vec<Tri2>,
    /// The face, grown by the margin, lies inside the umbra: the record can be removed.
    pub full_umbra: bool,
    /// Umbra area as a fraction of the face (before triangulation).
    pub umbra_fraction: f64,
    /// Penumbra area as a fraction of the face.
    pub penumbra_fraction: f64,
    /// Vertices of the umbra and penumbra polygons.
    pub polygon_vertices: usize,
    /// Blockers that contribute umbra.
    pub umbra_blockers: usize,
    /// Lowest and highest height above the face (world units) of the blocker geometry that casts the
    /// umbra: a segment from an umbra point to the light is blocked between these heights. `None` when
    /// some umbra comes from the crossing test (a light vertex near the face plane) or there is none.
    /// Used to certify propagation (see [`crate::construct::propagation`]).
    pub hit_heights: Option<(f64, f64)>,
    /// Height above the face plane of the light's lowest vertex (world units).
    pub min_light_height: f64,
    /// The margin by which the face is grown before it is compared with the umbra, in world units: a
    /// fully dark face is dark on the face grown by this much in its plane.
    pub margin_world: f64,
    umbra_shapes: IntShapes<i32>,
    /// Without a union ([`face_umbra_cover`]): the convex umbra polygons (units, counter-clockwise),
    /// each cast by one blocker, eroded by the margin like the contours a union is taken of; the
    /// umbra is their union.
    convex: Vec<Vec<DVec2>>,
    margin: f64,
}

impl FaceRegions {
    /// The margin in face units (see [`FaceRegions::margin_world`]).
    pub fn margin_units(&self) -> f64 {
        self.margin
    }

    /// True if the square `[lo, hi]` (units), grown by the margin, lies inside the umbra: used to
    /// classify face-grid cells.
    pub fn square_in_umbra(&self, lo: DVec2, hi: DVec2) -> bool {
        if !self.convex.is_empty() {
            let (lo, hi) = ((lo - self.margin).floor(), (hi + self.margin).ceil());
            return self.convex.iter().any(|p| contains_rect(p, lo, hi));
        }
        if self.umbra_shapes.is_empty() {
            return false;
        }
        let sq = square(lo - self.margin, hi + self.margin);
        let mut o = Overlay::new(64);
        o.add_contour(&sq, ShapeType::Subject);
        o.add_source(&self.umbra_shapes, ShapeType::Clip);
        o.overlay(OverlayRule::Difference, FillRule::NonZero).is_empty()
    }
}

/// The triangles of a fan over the convex polygon `p`, vertices rounded to units (as [`polygon::snap`]
/// rounds the polygons the union is taken of); degenerate ones left out.
fn fan(p: &[DVec2]) -> impl Iterator<Item = Tri2> + '_ {
    let r = |q: DVec2| [q.x.round() as i32, q.y.round() as i32];
    (1..p.len().saturating_sub(1)).map(move |i| [r(p[0]), r(p[i]), r(p[i + 1])]).filter(|t| {
        let (a, b, c) = (t[0], t[1], t[2]);
        (b[0] - a[0]) as i64 * (c[1] - a[1]) as i64 - (b[1] - a[1]) as i64 * (c[0] - a[0]) as i64 != 0
    })
}

/// Scratch buffers reused across blockers.
#[derive(Default)]
struct Scratch {
    poly: Vec<DVec3>,
    tmp3: Vec<DVec3>,
    pts: Vec<DVec2>,
    hull: Vec<DVec2>,
    a: Vec<DVec2>,
    b: Vec<DVec2>,
    tmp2: Vec<DVec2>,
}

/// What the regions of one record are computed from.
struct Setup<'a> {
    frame: FaceFrame,
    /// Light vertices with their heights.
    light: Vec<(DVec3, f64)>,
    /// Lowest light-vertex height.
    min_h: f64,
    /// Error bound in world units (above `f32` rounding of the scene's coordinates).
    r: f64,
    /// Distance from the face plane and from the light's lowest vertex that umbra blockers keep.
    guard: f64,
    /// Longest face-to-light distance (bounding-box diagonal).
    diag: f64,
    /// Margin in units: face-point error plus snapping.
    margin: f64,
    shaft: &'a Shaft,
    /// Highest height a blocking hit can have: `(1 - SEGMENT_EPS)` times the highest light vertex.
    max_hit_h: f64,
    face: Dir,
    cell: &'a Aabb,
    light_pts: &'a [glam::Vec3],
    tol: f32,
    /// The sub-shafts of a `FALLBACK_RES²` grid on the face with their squares, made when needed.
    cell_shafts: std::cell::OnceCell<Vec<(Shaft, (u32, u32))>>,
}

/// The umbra and penumbra of the record (`face` of `cell`, `light`, `blockers`). `tol` is the
/// construction tolerance, `abs_scale` the largest absolute coordinate of the scene.
#[allow(clippy::too_many_arguments)]
pub fn face_regions(
    scene: &Scene,
    face: Dir,
    cell: &Aabb,
    light: &Light,
    blockers: &[TriId],
    shaft: &Shaft,
    tol: f32,
    abs_scale: f32,
) -> FaceRegions {
    regions(scene, face, cell, light, blockers, shaft, (tol, abs_scale), Want::Both)
}

/// The umbra of a record that stores no list ([`crate::lie::RecordKind::Scene`], issue 15), whose
/// `blockers` are only some of its blockers, at a cost bounded per blocker: only the blockers whose
/// umbra could alone contain a face square of `side` units grown by the margin
/// (`Setup::may_cover`, a few projections) get their umbra computed, and it is kept as their
/// convex polygons, without union, fused patches, crossing test or penumbra. A face square is in
/// umbra when one polygon contains it ([`FaceRegions::square_in_umbra`]); the face is fully dark
/// when one contains it whole. Their umbra is part of the true umbra, so both stay sound; the
/// penumbra of a subset would not bound the true one. Measured against the full regions of the
/// subset in docs/results.md (issue 15): a sixth of the build time on the stress scene, grid shading
/// at most 3% slower on the real scenes (fewer faces removed as dark).
#[allow(clippy::too_many_arguments)]
pub fn face_umbra_cover(
    scene: &Scene,
    face: Dir,
    cell: &Aabb,
    light: &Light,
    blockers: &[TriId],
    shaft: &Shaft,
    (tol, abs_scale): (f32, f32),
    side: f64,
) -> FaceRegions {
    regions(scene, face, cell, light, blockers, shaft, (tol, abs_scale), Want::Cover(side))
}

/// What [`regions`] computes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Want {
    /// Umbra and penumbra.
    Both,
    /// Umbra only, as convex polygons, from the blockers that could alone cover a face square of this
    /// many units.
    Cover(f64),
}

/// True if the convex counter-clockwise polygon contains the rectangle `[lo, hi]`.
fn contains_rect(poly: &[DVec2], lo: DVec2, hi: DVec2) -> bool {
    let m = poly.len();
    m >= 3
        && [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]
            .iter()
            .all(|&c| (0..m).all(|i| (poly[(i + 1) % m] - poly[i]).perp_dot(c - poly[i]) >= 0.0))
}

#[allow(clippy::too_many_arguments)]
fn regions(
    scene: &Scene,
    face: Dir,
    cell: &Aabb,
    light: &Light,
    blockers: &[TriId],
    shaft: &Shaft,
    (tol, abs_scale): (f32, f32),
    want: Want,
) -> FaceRegions {
    let penumbra = want == Want::Both;
    let cover = match want {
        Want::Cover(side) => Some(side),
        Want::Both => None,
    };
    let frame = FaceFrame::new(face, cell);
    let lv: Vec<(DVec3, f64)> = light.vertices.iter().map(|v| (v.as_dvec3(), frame.height(v.as_dvec3()))).collect();
    let min_h = lv.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let all = Aabb::from_points(face.face_corners(cell).iter().chain(&light.vertices));
    let diag = all.size().as_dvec3().length();
    let r = error_bound(tol, abs_scale);
    let margin = r * frame.scale() + 2.0;
    let s = Setup {
        frame,
        light: lv.clone(),
        min_h,
        r,
        guard: 2.0 * SEGMENT_EPS as f64 * diag + r,
        diag,
        margin,
        shaft,
        max_hit_h: (1.0 - SEGMENT_EPS as f64) * lv.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max) + r,
        face,
        cell,
        light_pts: &light.vertices,
        tol,
        cell_shafts: std::cell::OnceCell::new(),
    };
    let mut sc = Scratch::default();
    let (mut umbra, mut core) = (Vec::new(), Vec::new());
    let mut shadow = Raster::default();
    let mut heights = (f64::INFINITY, f64::NEG_INFINITY);
    let mut add = |(u, c, h): Umbra, umbra: &mut Vec<IntContour<i32>>, core: &mut Vec<IntContour<i32>>| {
        umbra.push(u);
        core.extend(c);
        heights = (heights.0.min(h.0), heights.1.max(h.1));
    };
    let mut convex: Vec<Vec<DVec2>> = Vec::new();
    for &t in blockers {
        let tri = scene.triangles[t.idx()].v.map(|p| p.as_dvec3());
        if cover.is_none_or(|side| s.may_cover(&tri, side)) {
            if let Some(u) = s.umbra_of(&tri, &mut sc) {
                if cover.is_some() {
                    convex.push(sc.a.clone());
                }
                add(u, &mut umbra, &mut core);
            }
        }
        if penumbra && !shadow.full() {
            match s.shadow_of(&tri, &mut sc) {
                Shadow::None => {}
                Shadow::Whole => shadow.mark_all(),
                Shadow::Polygon => shadow.mark_polygon(&sc.a, &mut sc.tmp2, &mut sc.b),
                Shadow::Cells(c) => c.into_iter().for_each(|(i, j)| shadow.mark_fallback_cell(i, j)),
            }
        }
    }
    // Fused blockers (SPEC §8 point 2): flat convex patches of several triangles.
    let patches = if cover.is_some() { Vec::new() } else { fused_patches(scene, blockers, s.r) };
    for patch in &patches {
        if let Some(u) = s.umbra_of(patch, &mut sc) {
            add(u, &mut umbra, &mut core);
        }
    }
    let projected = umbra.len();
    // Projections from light vertices on or behind the face plane are unbounded: certify squares of
    // the face by the crossing test instead.
    if s.min_h <= 2.0 * s.guard && cover.is_none() {
        let polys: Vec<Flat> = blockers
            .iter()
            .map(|t| scene.triangles[t.idx()].v.map(|p| p.as_dvec3()).to_vec())
            .chain(patches)
            .filter_map(|p| s.flat(p))
            .collect();
        s.crossing_squares(&polys, DVec2::ZERO, UNITS, 0, &mut umbra, &mut core);
    }
    let mut out = FaceRegions {
        margin,
        umbra_blockers: umbra.len(),
        hit_heights: (projected > 0 && umbra.len() == projected).then_some(heights),
        min_light_height: s.min_h,
        margin_world: margin / s.frame.scale(),
        ..FaceRegions::default()
    };
    if umbra.is_empty() && shadow.is_empty() {
        return out;
    }
    if cover.is_some() {
        let (lo, hi) = (DVec2::splat(-margin).floor(), DVec2::splat(UNITS + margin).ceil());
        if convex.iter().any(|p| contains_rect(p, lo, hi)) {
            out.full_umbra = true;
            return out;
        }
        let face_area = UNITS * UNITS;
        out.umbra_fraction = (convex.iter().map(|p| 0.5 * signed_area2(p)).sum::<f64>() / face_area).min(1.0);
        out.polygon_vertices = convex.iter().map(Vec::len).sum();
        out.umbra = convex.iter().flat_map(|p| fan(p)).collect();
        out.convex = convex;
        return out;
    }
    let face_sq = square(DVec2::splat(-margin), DVec2::splat(UNITS + margin));
    if !umbra.is_empty() {
        out.umbra_shapes = union(umbra);
        let mut o = Overlay::new(64);
        o.add_contour(&face_sq, ShapeType::Subject);
        o.add_source(&out.umbra_shapes, ShapeType::Clip);
        if o.overlay(OverlayRule::Difference, FillRule::NonZero).is_empty() {
            out.full_umbra = true;
            return out;
        }
    }
    let shadow_shapes = if penumbra { difference(&shadow.rectangles(margin), &union(core)) } else { Vec::new() };
    let face_area = UNITS * UNITS;
    out.umbra_fraction = (area(&out.umbra_shapes) / face_area).min(1.0);
    out.penumbra_fraction = (area(&shadow_shapes) / face_area).min(1.0);
    out.polygon_vertices = vertex_count(&out.umbra_shapes) + vertex_count(&shadow_shapes);
    out.umbra = triangulate(&out.umbra_shapes);
    out.penumbra = triangulate(&shadow_shapes);
    out
}
