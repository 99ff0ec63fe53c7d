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

use std::collections::hash_map::{Entry, HashMap};

use glam::{DVec2, DVec3};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay::{Overlay, ShapeType};
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::i_float::int::point::IntPoint;
use i_overlay::i_shape::int::shape::{IntContour, IntShapes};
use i_triangle::int::triangulator::IntTriangulator;

use super::grid::face_axes;
use super::shaft::Shaft;
use crate::geometry::clip::{clip2, clip3, hull2, signed_area2};
use crate::geometry::Aabb;
use crate::octree::Dir;
use crate::scene::{Light, Scene, TriId};
use crate::visibility::query::SEGMENT_EPS;

/// Integer units per face side.
pub const UNITS: f64 = (1u32 << 20) as f64;

/// A triangle of a region, in the face's integer units.
pub type Tri2 = [[i32; 2]; 3];

/// Extra erosion, in units, of the umbra core that penumbra is cut from.
const CORE_EXTRA: f64 = 3.0;

/// Blockers that some face-to-light direction meets at a cosine below this get no umbra.
const MIN_COS: f64 = 0.02;

/// The 2D frame of a face: in-face axes `(u, v)` as [`face_axes`], origin at the face's minimum
/// corner, `UNITS` per side; heights are measured outward from the face plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceFrame {
    k: usize,
    u: usize,
    v: usize,
    w: f64,
    sign: f64,
    origin: DVec2,
    q: f64,
}

impl FaceFrame {
    /// The frame of face `face` of the cell `cell`.
    pub fn new(face: Dir, cell: &Aabb) -> FaceFrame {
        let k = face.axis();
        let (u, v) = face_axes(k);
        let w = if face.is_positive() { cell.max[k] } else { cell.min[k] } as f64;
        let side = (cell.max[u] - cell.min[u]).max(cell.max[v] - cell.min[v]) as f64;
        FaceFrame {
            k,
            u,
            v,
            w,
            sign: if face.is_positive() { 1.0 } else { -1.0 },
            origin: DVec2::new(cell.min[u] as f64, cell.min[v] as f64),
            q: UNITS / side,
        }
    }

    /// Units per world unit.
    #[inline]
    pub fn scale(&self) -> f64 {
        self.q
    }

    /// The in-face coordinates of `p`, in units.
    #[inline]
    pub fn units(&self, p: DVec3) -> DVec2 {
        DVec2::new((p[self.u] - self.origin.x) * self.q, (p[self.v] - self.origin.y) * self.q)
    }

    /// The point of the face plane at in-face coordinates `x` (units).
    pub fn point(&self, x: DVec2) -> DVec3 {
        let mut p = DVec3::ZERO;
        p[self.k] = self.w;
        p[self.u] = self.origin.x + x.x / self.q;
        p[self.v] = self.origin.y + x.y / self.q;
        p
    }

    /// Height of `p` above the face plane (positive outside the cell).
    #[inline]
    pub fn height(&self, p: DVec3) -> f64 {
        self.sign * (p[self.k] - self.w)
    }

    /// The half-space `height(p) >= h` as `n . p <= d`.
    fn above(&self, h: f64) -> (DVec3, f64) {
        let mut n = DVec3::ZERO;
        n[self.k] = -self.sign;
        (n, -self.sign * self.w - h)
    }

    /// The half-space `height(p) <= h` as `n . p <= d`.
    fn below(&self, h: f64) -> (DVec3, f64) {
        let mut n = DVec3::ZERO;
        n[self.k] = self.sign;
        (n, self.sign * self.w + h)
    }

    /// Central projection of `p` from the light point `v` (at height `hv > height(p)`) onto the face
    /// plane, in units.
    #[inline]
    fn project(&self, v: DVec3, hv: f64, p: DVec3) -> DVec2 {
        let lambda = hv / (hv - self.height(p));
        self.units(v + (p - v) * lambda)
    }
}

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
    regions(scene, face, cell, light, blockers, shaft, (tol, abs_scale), true)
}

/// [`face_regions`] without the penumbra (left empty): for a record that stores no list
/// ([`crate::lie::RecordKind::Scene`]), whose `blockers` are only some of its blockers. Their umbra is
/// part of the true umbra; their penumbra would not bound the true one, so it is not computed.
#[allow(clippy::too_many_arguments)]
pub fn face_umbra(
    scene: &Scene,
    face: Dir,
    cell: &Aabb,
    light: &Light,
    blockers: &[TriId],
    shaft: &Shaft,
    tol: f32,
    abs_scale: f32,
) -> FaceRegions {
    regions(scene, face, cell, light, blockers, shaft, (tol, abs_scale), false)
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
    penumbra: bool,
) -> FaceRegions {
    let frame = FaceFrame::new(face, cell);
    let lv: Vec<(DVec3, f64)> = light.vertices.iter().map(|v| (v.as_dvec3(), frame.height(v.as_dvec3()))).collect();
    let min_h = lv.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let all = Aabb::from_points(face.face_corners(cell).iter().chain(&light.vertices));
    let diag = all.size().as_dvec3().length();
    let r = error_bound(tol, abs_scale);
    let margin = r * frame.q + 2.0;
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
    for &t in blockers {
        let tri = scene.triangles[t.idx()].v.map(|p| p.as_dvec3());
        if let Some(u) = s.umbra_of(&tri, &mut sc) {
            add(u, &mut umbra, &mut core);
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
    let patches = fused_patches(scene, blockers, s.r);
    for patch in &patches {
        if let Some(u) = s.umbra_of(patch, &mut sc) {
            add(u, &mut umbra, &mut core);
        }
    }
    let projected = umbra.len();
    // Projections from light vertices on or behind the face plane are unbounded: certify squares of
    // the face by the crossing test instead.
    if s.min_h <= 2.0 * s.guard {
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

/// A blocker's shadow region.
enum Shadow {
    /// The blocker lies outside the shaft.
    None,
    /// Projections are unbounded: the whole face.
    Whole,
    /// A convex polygon (units), left in the scratch buffer `a`.
    Polygon,
    /// The fallback grid's cells whose sub-shafts the blocker meets (when projections from the
    /// light's vertices do not bound it).
    Cells(Vec<(u32, u32)>),
}

/// Cells per side of the raster that unites the shadow regions.
const RASTER: usize = 64;

/// The union of the shadow regions as a `RASTER x RASTER` bitmap of face cells, each set when a
/// shadow region meets it: a superset of the union, which is all "lit" needs (a point outside every
/// set cell is outside every shadow region), and far cheaper than exact booleans of thousands of
/// overlapping regions. The outermost cells stand for everything beyond the face's edges too.
#[derive(Default)]
struct Raster {
    rows: Vec<u64>,
    set: usize,
}

impl Raster {
    fn ensure(&mut self) {
        if self.rows.is_empty() {
            self.rows = vec![0; RASTER];
        }
    }

    fn is_empty(&self) -> bool {
        self.set == 0
    }

    fn full(&self) -> bool {
        self.set == RASTER * RASTER
    }

    fn mark(&mut self, j: usize, i0: usize, i1: usize) {
        self.ensure();
        let bits = if i1 - i0 + 1 == 64 { u64::MAX } else { ((1u64 << (i1 - i0 + 1)) - 1) << i0 };
        self.set += (bits & !self.rows[j]).count_ones() as usize;
        self.rows[j] |= bits;
    }

    fn mark_all(&mut self) {
        for j in 0..RASTER {
            self.mark(j, 0, RASTER - 1);
        }
    }

    /// Marks the cells of fallback-grid cell `(i, j)`.
    fn mark_fallback_cell(&mut self, i: u32, j: u32) {
        let k = RASTER / FALLBACK_RES as usize;
        for row in j as usize * k..(j as usize + 1) * k {
            self.mark(row, i as usize * k, (i as usize + 1) * k - 1);
        }
    }

    /// Marks every cell the convex polygon `poly` (units) meets: per row, the polygon clipped to the
    /// row's slab gives the range of columns.
    fn mark_polygon(&mut self, poly: &[DVec2], tmp: &mut Vec<DVec2>, row: &mut Vec<DVec2>) {
        let w = UNITS / RASTER as f64;
        let cell = |x: f64| ((x / w).floor().max(0.0) as usize).min(RASTER - 1);
        let (y_lo, y_hi) = poly.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.y), b.max(p.y)));
        if poly.is_empty() {
            return;
        }
        for j in cell(y_lo)..=cell(y_hi) {
            row.clear();
            row.extend_from_slice(poly);
            if j > 0 {
                clip2(row, DVec2::NEG_Y, -(j as f64 * w), tmp);
            }
            if j + 1 < RASTER {
                clip2(row, DVec2::Y, (j + 1) as f64 * w, tmp);
            }
            if row.is_empty() {
                continue;
            }
            let (x_lo, x_hi) =
                row.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p.x), b.max(p.x)));
            self.mark(j, cell(x_lo), cell(x_hi));
        }
    }

    /// The set cells as rectangles (runs of each row), the outermost grown by `2 * margin` beyond the
    /// face's edges.
    fn rectangles(&self, margin: f64) -> IntShapes<i32> {
        let w = UNITS / RASTER as f64;
        let edge = |k: usize| match k {
            0 => -2.0 * margin,
            RASTER => UNITS + 2.0 * margin,
            _ => k as f64 * w,
        };
        let mut out = Vec::new();
        for (j, &bits) in self.rows.iter().enumerate() {
            let mut i = 0;
            while i < RASTER {
                if bits >> i & 1 == 0 {
                    i += 1;
                    continue;
                }
                let start = i;
                while i < RASTER && bits >> i & 1 == 1 {
                    i += 1;
                }
                out.push(vec![square(DVec2::new(edge(start), edge(j)), DVec2::new(edge(i), edge(j + 1)))]);
            }
        }
        out
    }
}

/// One blocker's umbra, its core, and the height range of the blocker part casting it.
type Umbra = (IntContour<i32>, Option<IntContour<i32>>, (f64, f64));

/// Cells per side of the grid used when a blocker's shadow cannot be bounded by projections.
const FALLBACK_RES: u32 = 8;

impl Setup<'_> {
    /// The umbra of one blocker and its core (both eroded, snapped, counter-clockwise), if any, with
    /// the lowest and highest height of the part of the blocker that casts it.
    fn umbra_of(&self, tri: &[DVec3], s: &mut Scratch) -> Option<Umbra> {
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).try_normalize()?;
        if self.min_h <= 2.0 * self.guard {
            return None;
        }
        s.poly.clear();
        s.poly.extend_from_slice(tri);
        let (na, da) = self.frame.above(self.guard);
        clip3(&mut s.poly, na, da, &mut s.tmp3);
        let (nb, db) = self.frame.below(self.min_h - self.guard);
        clip3(&mut s.poly, nb, db, &mut s.tmp3);
        // Every direction from the blocker to the light (the convex hull of vertex differences) must
        // cross the blocker's plane at a cosine of at least MIN_COS.
        let mut cos = f64::INFINITY;
        let mut sign = 0.0;
        for &(v, _) in &self.light {
            for p in &s.poly {
                let dot = n.dot((v - *p).normalize_or_zero());
                if sign == 0.0 {
                    sign = dot.signum();
                }
                if dot * sign <= 0.0 {
                    return None;
                }
                cos = cos.min(dot.abs());
            }
        }
        if cos < MIN_COS {
            return None;
        }
        let inset = self.r / cos + self.r;
        let k = tri.len();
        for i in 0..k {
            let (a, b, c) = (tri[i], tri[(i + 1) % k], tri[(i + 2) % k]);
            let mut d = n.cross(b - a).normalize();
            if d.dot(c - a) < 0.0 {
                d = -d;
            }
            clip3(&mut s.poly, -d, -d.dot(a) - inset, &mut s.tmp3);
        }
        if s.poly.len() < 3 {
            return None;
        }
        let heights = s.poly.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| {
            let h = self.frame.height(p);
            (lo.min(h), hi.max(h))
        });
        let lo = DVec2::splat(-3.0 * self.margin);
        let hi = DVec2::splat(UNITS + 3.0 * self.margin);
        s.a.clear();
        s.a.extend_from_slice(&square_f(lo, hi));
        s.b.clear();
        s.b.extend_from_slice(&s.a);
        for &(v, hv) in &self.light {
            s.pts.clear();
            s.pts.extend(s.poly.iter().map(|&p| self.frame.project(v, hv, p)));
            let a2 = signed_area2(&s.pts);
            if a2.abs() < 2.0 {
                return None;
            }
            if a2 < 0.0 {
                s.pts.reverse();
            }
            let m = s.pts.len();
            for i in 0..m {
                let (a, b) = (s.pts[i], s.pts[(i + 1) % m]);
                let e = b - a;
                let len = e.length();
                let nrm = DVec2::new(e.y, -e.x);
                clip2(&mut s.a, nrm, nrm.dot(a) - self.margin * len, &mut s.tmp2);
                clip2(&mut s.b, nrm, nrm.dot(a) - (self.margin + CORE_EXTRA) * len, &mut s.tmp2);
            }
            if s.a.len() < 3 {
                return None;
            }
        }
        let umbra = snap(&s.a)?;
        Some((umbra, snap(&s.b), heights))
    }

    /// The shadow region of one blocker (dilated, snapped, counter-clockwise).
    fn shadow_of(&self, tri: &[DVec3; 3], s: &mut Scratch) -> Shadow {
        s.poly.clear();
        s.poly.extend_from_slice(tri);
        // A hit from inside the cell lies in the shaft and (t < 1 - SEGMENT_EPS) below `max_hit_h`.
        let (nb, db) = self.frame.below(self.max_hit_h);
        for (n, d) in self.shaft.planes.iter().map(|p| (p.n, p.d)).chain([(nb, db)]) {
            clip3(&mut s.poly, n, d, &mut s.tmp3);
            if s.poly.is_empty() {
                return Shadow::None;
            }
        }
        let h_max = s.poly.iter().map(|&p| self.frame.height(p)).fold(f64::NEG_INFINITY, f64::max);
        let gap = self.min_h - h_max;
        if gap <= 2.0 * self.r {
            return self.cells_shadow(tri);
        }
        // How far an `r` move of a blocker point or of the light point can move a projection.
        let mut dilate = 0.0f64;
        s.pts.clear();
        for &(v, hv) in &self.light {
            let lambda = hv / (hv - h_max).max(gap);
            dilate = dilate.max(3f64.sqrt() * self.r * lambda.max(1.0) * (1.0 + self.diag / (hv - h_max).max(gap)));
            s.pts.extend(s.poly.iter().map(|&p| self.frame.project(v, hv, p)));
        }
        if dilate * self.frame.q > UNITS / FALLBACK_RES as f64 {
            return self.cells_shadow(tri);
        }
        hull2(&mut s.pts, &mut s.hull);
        let d = dilate * self.frame.q + self.margin;
        s.pts.clear();
        for &p in &s.hull {
            s.pts.extend([DVec2::new(-d, -d), DVec2::new(d, -d), DVec2::new(d, d), DVec2::new(-d, d)].map(|o| p + o));
        }
        hull2(&mut s.pts, &mut s.a);
        if contains_square(&s.a, -self.margin, UNITS + self.margin) {
            return Shadow::Whole;
        }
        let lo = -2.0 * self.margin;
        let hi = UNITS + 2.0 * self.margin;
        for (n, dd) in [(DVec2::X, hi), (DVec2::NEG_X, -lo), (DVec2::Y, hi), (DVec2::NEG_Y, -lo)] {
            clip2(&mut s.a, n, dd, &mut s.tmp2);
        }
        if s.a.is_empty() {
            Shadow::None
        } else {
            Shadow::Polygon
        }
    }
}

/// An undirected edge by the bits of its end points.
type EdgeKey = ([u32; 3], [u32; 3]);

/// The key of edge `(a, b)`: equal for `(b, a)` and only for bit-identical end points, which is when the
/// watertight test lets no ray slip between the two triangles.
fn edge_key(a: glam::Vec3, b: glam::Vec3) -> EdgeKey {
    let (ka, kb) = (a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits));
    if ka <= kb {
        (ka, kb)
    } else {
        (kb, ka)
    }
}

/// Flat convex patches made of several blockers: triangles joined through bit-identical shared
/// edges (so the watertight test lets no ray through between them), coplanar within `r / 100`, whose
/// union is exactly its convex hull (areas equal, every unshared edge on the hull's boundary). A ray
/// through the interior of such a patch hits one of its triangles, so the patch may cast umbra as one
/// blocker: a plate or a wall split into triangles does, where none of its triangles does alone.
fn fused_patches(scene: &Scene, blockers: &[TriId], r: f64) -> Vec<Vec<DVec3>> {
    let tris: Vec<[DVec3; 3]> = blockers.iter().map(|t| scene.triangles[t.idx()].v.map(|p| p.as_dvec3())).collect();
    let normals: Vec<Option<DVec3>> = tris.iter().map(|t| (t[1] - t[0]).cross(t[2] - t[0]).try_normalize()).collect();
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut edges: HashMap<EdgeKey, (usize, u32)> = HashMap::new();
    for (i, &t) in blockers.iter().enumerate() {
        let v = scene.triangles[t.idx()].v;
        for e in 0..3 {
            match edges.entry(edge_key(v[e], v[(e + 1) % 3])) {
                Entry::Occupied(mut o) => {
                    let (j, n) = *o.get();
                    o.insert((j, n + 1));
                    let (Some(ni), Some(nj)) = (normals[i], normals[j]) else { continue };
                    let far = tris[i][(e + 2) % 3];
                    let near = *tris[j].iter().find(|p| !tris[i].contains(p)).unwrap_or(&tris[j][0]);
                    let (p, q) = (tris[i][e], tris[i][(e + 1) % 3]);
                    let side = |x: DVec3| nj.dot((q - p).cross(x - p));
                    if ni.dot(nj).abs() > 1.0 - 1e-12
                        && nj.dot(far - tris[j][0]).abs() <= 0.01 * r
                        && side(far) * side(near) < 0.0
                    {
                        let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                        parent[a] = b;
                    }
                }
                Entry::Vacant(slot) => {
                    slot.insert((i, 1));
                }
            }
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for i in 0..tris.len() {
        let g = root(&mut parent, i);
        groups.entry(g).or_default().push(i);
    }
    let mut out = Vec::new();
    let mut members: Vec<Vec<usize>> = groups.into_values().filter(|m| m.len() >= 2).collect();
    members.sort_unstable();
    for m in members {
        let t0 = tris[m[0]];
        let Some(n) = normals[m[0]] else { continue };
        let e1 = (t0[1] - t0[0]).normalize();
        let e2 = n.cross(e1);
        let to2 = |p: DVec3| DVec2::new((p - t0[0]).dot(e1), (p - t0[0]).dot(e2));
        let mut pts: Vec<DVec2> = m.iter().flat_map(|&i| tris[i].map(to2)).collect();
        let mut hull = Vec::new();
        hull2(&mut pts, &mut hull);
        let hull_area = signed_area2(&hull).abs();
        let sum: f64 = m.iter().map(|&i| signed_area2(&tris[i].map(to2)).abs()).sum();
        if hull.len() < 3 || (sum - hull_area).abs() > 1e-9 * hull_area {
            continue;
        }
        // Every edge used once lies on the hull's boundary.
        let eps = 1e-9 * hull_area.sqrt();
        let on_hull = |x: DVec2| {
            let k = hull.len();
            (0..k).any(|h| {
                let (a, b) = (hull[h], hull[(h + 1) % k]);
                let e = b - a;
                e.perp_dot(x - a).abs() <= eps * e.length() && (x - a).dot(e) >= -eps && (x - b).dot(e) <= eps
            })
        };
        let boundary_ok = m.iter().all(|&i| {
            let v = scene.triangles[blockers[i].idx()].v;
            (0..3).all(|e| {
                let once = edges.get(&edge_key(v[e], v[(e + 1) % 3])).is_some_and(|x| x.1 == 1);
                !once || (on_hull(to2(tris[i][e])) && on_hull(to2(tris[i][(e + 1) % 3])))
            })
        });
        if boundary_ok {
            out.push(hull.iter().map(|p| t0[0] + e1 * p.x + e2 * p.y).collect());
        }
    }
    out
}

/// True if the convex counter-clockwise polygon contains the square `[lo, hi]²`.
fn contains_square(poly: &[DVec2], lo: f64, hi: f64) -> bool {
    let m = poly.len();
    m >= 3
        && [DVec2::splat(lo), DVec2::new(hi, lo), DVec2::splat(hi), DVec2::new(lo, hi)]
            .iter()
            .all(|&c| (0..m).all(|i| (poly[(i + 1) % m] - poly[i]).perp_dot(c - poly[i]) >= 0.0))
}

impl Setup<'_> {
    /// A blocker's shadow as the squares (grown by the margin) of the fallback grid's cells whose
    /// sub-shafts, conv(cell ∪ light) grown by the tolerance, it meets: a ray crossing the face in
    /// another cell lies in that cell's sub-shaft and cannot meet the blocker.
    fn cells_shadow(&self, tri: &[DVec3; 3]) -> Shadow {
        let cells = self.cell_shafts.get_or_init(|| {
            let g = FALLBACK_RES;
            let mut out = Vec::with_capacity((g * g) as usize);
            for j in 0..g {
                for i in 0..g {
                    let b = super::grid::cell_box(self.face, self.cell, g, i, j);
                    let shaft = Shaft::new(&self.face.face_corners(&b), self.light_pts, self.tol);
                    out.push((shaft, (i, j)));
                }
            }
            out
        });
        let t = tri.map(|p| p.as_vec3());
        let bounds = Aabb::from_points(t.iter());
        let hit: Vec<(u32, u32)> = cells
            .iter()
            .filter(|(sh, _)| sh.bounds.overlaps(&bounds) && sh.clips_triangle(&t))
            .map(|&(_, ij)| ij)
            .collect();
        if hit.len() == cells.len() {
            Shadow::Whole
        } else if hit.is_empty() {
            Shadow::None
        } else {
            Shadow::Cells(hit)
        }
    }
}

/// Depth of the quadtree of face squares tried by the crossing test.
const CROSSING_DEPTH: u32 = 3;

impl Setup<'_> {
    /// Adds to the umbra (and its core) the squares of the face, from the whole face down to
    /// `CROSSING_DEPTH` levels of quarters, that one blocker polygon certifies by
    /// [`Setup::crossing_blocks`].
    fn crossing_squares(
        &self,
        polys: &[Flat],
        lo: DVec2,
        size: f64,
        depth: u32,
        umbra: &mut Vec<IntContour<i32>>,
        core: &mut Vec<IntContour<i32>>,
    ) {
        let grown = [lo, lo + DVec2::new(size, 0.0), lo + size, lo + DVec2::new(0.0, size)];
        // Certify the square grown by twice the margin; add it grown by one margin.
        let m = DVec2::splat(2.0 * self.margin);
        let corners = [grown[0] - m, grown[1] + DVec2::new(m.x, -m.y), grown[2] + m, grown[3] + DVec2::new(-m.x, m.y)]
            .map(|c| self.frame.point(c));
        if polys.iter().any(|p| self.crossing_blocks(p, &corners)) {
            umbra.push(square(lo - self.margin, lo + size + self.margin));
            let c = self.margin - CORE_EXTRA;
            core.push(square(lo - c, lo + size + c));
            return;
        }
        if depth < CROSSING_DEPTH {
            let h = size / 2.0;
            for d in [DVec2::ZERO, DVec2::new(h, 0.0), DVec2::new(0.0, h), DVec2::splat(h)] {
                self.crossing_squares(polys, lo + d, h, depth + 1, umbra, core);
            }
        }
    }

    /// A flat convex blocker prepared for [`Setup::crossing_blocks`]: `None` if degenerate or if the
    /// light is not entirely at least `guard` in front of its plane.
    fn flat(&self, poly: Vec<DVec3>) -> Option<Flat> {
        let mut n = (poly[1] - poly[0]).cross(poly[2] - poly[0]).try_normalize()?;
        let o = poly[0];
        if n.dot(self.light[0].0 - o) < 0.0 {
            n = -n;
        }
        if self.light.iter().any(|&(v, _)| n.dot(v - o) < self.guard) {
            return None;
        }
        let k = poly.len();
        let centre = poly.iter().copied().sum::<DVec3>() / k as f64;
        let edges = (0..k)
            .map(|i| {
                let (a, b) = (poly[i], poly[(i + 1) % k]);
                let mut e = n.cross(b - a).normalize();
                if e.dot(centre - a) < 0.0 {
                    e = -e;
                }
                (e, e.dot(a))
            })
            .collect();
        Some(Flat { n, o, edges })
    }

    /// True if every segment from the face square with corners `sq` to the light crosses the flat
    /// convex blocker `f` well inside it: square and light lie on opposite sides of its plane, at
    /// least `guard` away, and the crossings of the segments between their corners (whose convex
    /// hull holds every crossing) lie in the blocker shrunk by `r / cos + r`.
    fn crossing_blocks(&self, f: &Flat, sq: &[DVec3; 4]) -> bool {
        let d = |p: DVec3| f.n.dot(p - f.o);
        if sq.iter().any(|&c| d(c) > -self.guard) {
            return false;
        }
        let crossing = |c: DVec3, v: DVec3| c + (v - c) * (d(c) / (d(c) - d(v)));
        let inside = |g: DVec3, inset: f64| f.edges.iter().all(|&(e, ea)| e.dot(g) - ea >= inset);
        // Cheap rejection first: one crossing, no inset.
        if !inside(crossing(sq[0], self.light[0].0), 0.0) {
            return false;
        }
        let mut cos = f64::INFINITY;
        for &(v, _) in &self.light {
            for &c in sq {
                cos = cos.min(f.n.dot((v - c).normalize()));
            }
        }
        if cos < MIN_COS {
            return false;
        }
        let inset = self.r / cos + self.r;
        self.light.iter().all(|&(v, _)| sq.iter().all(|&c| inside(crossing(c, v), inset)))
    }
}

/// A flat convex blocker: plane normal `n` (toward the light) through `o`, and per edge the inward
/// in-plane normal `e` with `e . a` for a point `a` of the edge.
struct Flat {
    n: DVec3,
    o: DVec3,
    edges: Vec<(DVec3, f64)>,
}

/// The axis-aligned square `[lo, hi]` as a counter-clockwise `f64` polygon.
fn square_f(lo: DVec2, hi: DVec2) -> [DVec2; 4] {
    [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)]
}

/// The square `[lo, hi]` snapped outward to units, counter-clockwise.
fn square(lo: DVec2, hi: DVec2) -> IntContour<i32> {
    let (x0, y0) = (lo.x.floor() as i32, lo.y.floor() as i32);
    let (x1, y1) = (hi.x.ceil() as i32, hi.y.ceil() as i32);
    vec![IntPoint::new(x0, y0), IntPoint::new(x1, y0), IntPoint::new(x1, y1), IntPoint::new(x0, y1)]
}

/// A convex counter-clockwise polygon rounded to units, or `None` if it collapses.
fn snap(poly: &[DVec2]) -> Option<IntContour<i32>> {
    let mut out: IntContour<i32> = Vec::with_capacity(poly.len());
    for p in poly {
        let q = IntPoint::new(p.x.round() as i32, p.y.round() as i32);
        if out.last() != Some(&q) {
            out.push(q);
        }
    }
    while out.len() > 1 && out.first() == out.last() {
        out.pop();
    }
    (out.len() >= 3 && contour_area2(&out) > 0).then_some(out)
}

/// Twice the signed area of an integer contour.
fn contour_area2(c: &[IntPoint<i32>]) -> i64 {
    let n = c.len();
    (0..n)
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % n]);
            a.x as i64 * b.y as i64 - b.x as i64 * a.y as i64
        })
        .sum()
}

/// The union of convex contours, merged pairwise: each overlay then only meets the boundaries of two
/// partial unions, not every edge crossing inside the final union (umbra regions overlap a lot).
fn union(contours: Vec<IntContour<i32>>) -> IntShapes<i32> {
    let mut parts: Vec<IntShapes<i32>> = contours.into_iter().map(|c| vec![vec![c]]).collect();
    while parts.len() > 1 {
        let mut next = Vec::with_capacity(parts.len().div_ceil(2));
        let mut it = parts.into_iter();
        while let Some(a) = it.next() {
            match it.next() {
                Some(b) => {
                    let mut o = Overlay::new(vertex_count(&a) + vertex_count(&b));
                    o.add_source(&a, ShapeType::Subject);
                    o.add_source(&b, ShapeType::Clip);
                    next.push(o.overlay(OverlayRule::Union, FillRule::NonZero));
                }
                None => next.push(a),
            }
        }
        parts = next;
    }
    parts.pop().unwrap_or_default()
}

/// `a` minus `b`.
fn difference(a: &IntShapes<i32>, b: &IntShapes<i32>) -> IntShapes<i32> {
    if a.is_empty() || b.is_empty() {
        return a.clone();
    }
    let mut o = Overlay::new(vertex_count(a) + vertex_count(b));
    o.add_source(a, ShapeType::Subject);
    o.add_source(b, ShapeType::Clip);
    o.overlay(OverlayRule::Difference, FillRule::NonZero)
}

/// Area of shapes (holes subtract), in units².
fn area(shapes: &IntShapes<i32>) -> f64 {
    shapes.iter().flatten().map(|c| contour_area2(c) as f64 * 0.5).sum::<f64>().abs()
}

/// Vertices of shapes.
fn vertex_count(shapes: &IntShapes<i32>) -> usize {
    shapes.iter().flatten().map(Vec::len).sum()
}

/// Triangles of shapes.
fn triangulate(shapes: &IntShapes<i32>) -> Vec<Tri2> {
    if shapes.is_empty() {
        return Vec::new();
    }
    let t = IntTriangulator::<i32, u32>::default().triangulate_shapes(shapes);
    let p = |k: u32| {
        let q = t.points[k as usize];
        [q.x, q.y]
    };
    t.indices.chunks_exact(3).map(|i| [p(i[0]), p(i[1]), p(i[2])]).collect()
}

/// True if the face point `x` (units) lies in one of `tris`, edges included with a small slack.
#[inline]
pub fn in_triangles(tris: &[Tri2], x: DVec2) -> bool {
    tris.iter().any(|t| {
        let p = t.map(|v| DVec2::new(v[0] as f64, v[1] as f64));
        let orient = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        let s = if orient < 0.0 { -1.0 } else { 1.0 };
        (0..3).all(|i| {
            let (a, b) = (p[i], p[(i + 1) % 3]);
            s * (b - a).perp_dot(x - a) >= -0.5 * (b - a).length()
        })
    })
}
