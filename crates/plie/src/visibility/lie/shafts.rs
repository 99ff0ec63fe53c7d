//! Shafts from the shaded triangle (issue 21): the lights the footprints leave to the scene BVH
//! ([`super::whole::Whole::Mixed`]) are asked, point after point, from the same few pieces of
//! surface. For a shaded triangle `T`, an octree leaf and a light, every segment from a point of `T`
//! in the leaf to the light lies in the shaft `conv(A ∪ light)` of the piece `A = T ∩ leaf` (SPEC
//! §4.2's shaft, with the piece for the face). So the triangles that meet that shaft, found once by a
//! walk of the scene BVH from the leaf's cut ([`crate::visibility::bvh::Cut`]), are the only ones
//! that can block any of those segments; where they are few, every later point of the piece tests
//! them as a fan instead of walking the BVH.
//!
//! The region is conservative: the planes of the hull of `A`'s box and the light's box
//! ([`Shaft::of_boxes`]) and `T`'s own plane (turned away from the light), each moved out by
//! [`SHAFT_MARGIN`] times the scene tolerance. A query uses a piece's list only if its point lies
//! within the tolerance of `A`'s box and of `T`'s plane (checked at every query, so an
//! imprecise hit point falls back to the walk); every segment from such a point lies many
//! tolerances inside every plane, and a triangle is dropped only if its three vertices lie beyond
//! one of them. So each triangle that can block a segment is in the list, each is decided by the
//! watertight test, and every answer is brute force's.
//!
//! Leaves crowded with triangles of their own keep the walk (as they do for lit and gathered
//! lights, [`super::light`]): their pieces' shafts are seldom short (conference-lit at 254 x 254,
//! 16 rays: 684 of 980 lists built over more than [`SHAFT_MAX`] triangles before they were left
//! out), and their lookups cost more than the lists saved.
//!
//! Lists are built on a piece's [`BUILD_AT`]-th query (a piece asked a few times would not repay
//! the walk that gathers it) and shared by all threads, in shards behind locks. At most
//! [`SHAFT_MAX`] triangles are kept; a piece with more is marked for the walk. The table stops
//! growing at [`PIECES_MAX`] pieces, and no list is built past [`LISTS_MAX`]. Which thread builds
//! a list, and when, changes no answer.
//!
//! A list keeps its triangles' vertices in lanes, eight triangles a block, so that the pyramid of
//! each query culls them eight at a time ([`Pyramid::culls8`]) instead of reading each triangle
//! from the scene and testing it alone.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;

use super::LieVisibility;
use crate::construct::shaft::{Plane, Shaft};
use crate::geometry::clip::clip3;
use crate::geometry::Aabb;
use crate::octree::LeafId;
use crate::scene::{LightId, TriId};
use crate::visibility::fan::Pyramid;
use crate::visibility::pyramid::TriLanes;
use crate::visibility::simd::Avx2;
use crate::visibility::{LightRays, QueryCtx};

/// Most triangles a piece's list keeps: a light with more from that piece walks the scene BVH.
/// Measured (callgrind inside `occluded_light`, 254x254, 16 rays, docs/results.md session 21):
/// with lists built at the 32nd query, 4, 8 and 12 took 537.7, 517.3 and 508.3 M instructions on
/// cornell-dragon-100k (32, built at the 2nd query: 506.1 M), and 894.4, 895.0 and 895.7 M on
/// conference-lit.
pub(super) const SHAFT_MAX: usize = 12;

/// The query of a piece at which its list is built: building one costs about as much as a few
/// walks, so only pieces asked often repay it. Measured as [`SHAFT_MAX`] (with 12, before crowded
/// leaves were left out): building at the 2nd, 8th and 32nd query took 505.2, 506.7 and 508.3 M
/// instructions on cornell-dragon-100k and 966.9, 916.1 and 895.7 M on conference-lit; with
/// crowded leaves left out, the 8th and the 32nd differ by 0.1% summed over four scenes.
const BUILD_AT: u32 = 32;

/// The planes' margin, in scene tolerances ([`LieVisibility::pad`]): a segment from an accepted
/// point lies this many tolerances inside each plane, but for rounding (the pyramid's cull keeps
/// ten, [`crate::visibility::pyramid::margin_of`]).
const SHAFT_MARGIN: f32 = 16.0;

/// Most pieces the table holds: about 32 bytes each, so at most about 32 MiB, which only a render
/// of over 30 million (point, light) pairs in uncrowded leaves reaches.
const PIECES_MAX: usize = 1 << 20;

/// Most lists built: about 700 bytes each at most (the list of at most [`SHAFT_MAX`] triangles and
/// two blocks of their vertices in lanes, 288 bytes a block), so at most about 90 MiB.
const LISTS_MAX: usize = 1 << 17;

/// Shards of the table: locks taken by different threads rarely meet.
const SHARDS: usize = 64;

/// A piece: (leaf, shaded triangle, light).
type Key = (u32, u32, u32);

/// What the table knows of a piece.
#[derive(Clone, Copy, Debug)]
enum Piece {
    /// Asked this many times.
    Seen(u32),
    /// No list: too many triangles in its shaft (or the triangle misses the leaf's box).
    Walk,
    /// Its list: entry `i` of its shard's `lists`.
    List(u32),
}

/// A piece's list: `tris[start..start + len]` of its shard, their vertices in blocks of eight
/// from `lanes[block]` on, for the points within `within` (the piece's box, grown by the
/// tolerance) and with `plane.0 . x <= plane.1`.
#[derive(Clone, Copy, Debug)]
struct List {
    within: Aabb,
    plane: (DVec3, f64),
    start: u32,
    len: u32,
    block: u32,
}

/// A shard of the table.
#[derive(Default)]
struct Shard {
    pieces: FxHashMap<Key, Piece>,
    lists: Vec<List>,
    tris: Vec<TriId>,
    lanes: Vec<TriLanes>,
}

/// The table of pieces and their lists, shared by the threads of a render.
pub(crate) struct Shafts {
    shards: Vec<Mutex<Shard>>,
    pieces: AtomicUsize,
    lists: AtomicUsize,
}

impl Default for Shafts {
    fn default() -> Shafts {
        let shards = (0..SHARDS).map(|_| Mutex::default()).collect();
        Shafts { shards, pieces: AtomicUsize::new(0), lists: AtomicUsize::new(0) }
    }
}

/// What [`LieVisibility::shaft_list`] found.
pub(super) enum Found {
    /// The point's piece has a list, copied out: these are all the triangles that can block.
    List,
    /// No list (yet, or ever): walk the scene BVH.
    Walk,
}

impl LieVisibility<'_> {
    /// The triangles of the list of the piece of `rays.origin_tri` in `leaf` toward `rays.light`
    /// that `pyramid` (the light's from the point) does not cull, into `out`, if the piece has a
    /// list and the point lies within it; builds it on the piece's [`BUILD_AT`]-th query.
    pub(super) fn shaft_list(
        &self,
        leaf: LeafId,
        rays: &LightRays,
        pyramid: &Pyramid,
        out: &mut Vec<TriId>,
        ctx: &mut QueryCtx,
    ) -> Found {
        let tri = rays.origin_tri;
        if tri.idx() >= self.scene.triangles.len() {
            return Found::Walk;
        }
        let key = (leaf.0, tri.0, rays.light.0);
        let shard =
            &self.shafts.shards[(leaf.0 as usize ^ (tri.0 as usize).wrapping_mul(31) ^ rays.light.idx()) % SHARDS];
        {
            let mut s = shard.lock().unwrap_or_else(|e| e.into_inner());
            let Shard { pieces, lists, tris, lanes } = &mut *s;
            match pieces.get_mut(&key) {
                None => {
                    if self.shafts.pieces.fetch_add(1, Ordering::Relaxed) < PIECES_MAX {
                        pieces.insert(key, Piece::Seen(1));
                    }
                    return Found::Walk;
                }
                Some(Piece::Walk) => return Found::Walk,
                Some(Piece::Seen(n)) => {
                    *n += 1;
                    if *n < BUILD_AT {
                        return Found::Walk;
                    }
                    if self.shafts.lists.load(Ordering::Relaxed) >= LISTS_MAX {
                        pieces.insert(key, Piece::Walk);
                        return Found::Walk;
                    }
                }
                Some(&mut Piece::List(i)) => {
                    let List { within, plane, start, len, block } = lists[i as usize];
                    if !accepts(&within, plane, rays.origin) {
                        return Found::Walk;
                    }
                    let list = &tris[start as usize..(start + len) as usize];
                    uncut(list, &lanes[block as usize..], pyramid, out, ctx);
                    return Found::List;
                }
            }
        }
        // Built outside the lock (two threads may build the same piece: the same list).
        let built = self.build_piece(leaf, tri, rays.light, out);
        let mut s = shard.lock().unwrap_or_else(|e| e.into_inner());
        let (start, block) = (s.tris.len() as u32, s.lanes.len() as u32);
        let list = built.map(|(within, plane)| List { within, plane, start, len: out.len() as u32, block });
        match list {
            None => {
                s.pieces.insert(key, Piece::Walk);
                Found::Walk
            }
            Some(list) => {
                self.shafts.lists.fetch_add(1, Ordering::Relaxed);
                s.tris.extend_from_slice(out);
                let triangles = &self.scene.triangles;
                s.lanes.extend(out.chunks(8).map(|c| TriLanes::of(c.iter().map(|t| &triangles[t.idx()]))));
                let i = s.lists.len() as u32;
                s.lists.push(list);
                s.pieces.insert(key, Piece::List(i));
                if accepts(&list.within, list.plane, rays.origin) {
                    let Shard { tris, lanes, .. } = &*s;
                    uncut(&tris[start as usize..], &lanes[block as usize..], pyramid, out, ctx);
                    Found::List
                } else {
                    Found::Walk
                }
            }
        }
    }

    /// The triangles (into `out`) that meet the shaft of the piece of `tri` in `leaf` toward
    /// `light`, with the region a point must lie in to use them; `None` if they are more than
    /// [`SHAFT_MAX`] or the triangle misses the leaf.
    fn build_piece(
        &self,
        leaf: LeafId,
        tri: TriId,
        light: LightId,
        out: &mut Vec<TriId>,
    ) -> Option<(Aabb, (DVec3, f64))> {
        out.clear();
        let pad = self.pad;
        let margin = f64::from(SHAFT_MARGIN * pad);
        let b = self.octree.leaf_bounds(leaf);
        let v = self.scene.triangles[tri.idx()].v.map(|p| p.as_dvec3());
        // The piece A: the triangle clipped to the leaf's box.
        let mut piece = v.to_vec();
        let mut tmp = Vec::with_capacity(9);
        for k in 0..3 {
            let e = DVec3::AXES[k];
            clip3(&mut piece, e, f64::from(b.max[k]), &mut tmp);
            clip3(&mut piece, -e, -f64::from(b.min[k]), &mut tmp);
        }
        if piece.is_empty() {
            return None;
        }
        let corners: Vec<Vec3> = piece.iter().map(|p| p.as_vec3()).collect();
        let within = Aabb::from_points(&corners).expanded(pad);
        let lv = &self.scene.lights[light.idx()].vertices;
        let shaft = Shaft::of_boxes(&within, &Aabb::from_points(lv), SHAFT_MARGIN * pad);
        let mut planes = shaft.planes;
        // The triangle's plane, facing away from the light (any side would do: its offset is the
        // farthest of the piece and the light, so it holds both).
        let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
        let mut plane = (DVec3::ZERO, f64::INFINITY);
        if normal != DVec3::ZERO && normal.is_finite() {
            let centre = lv.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / lv.len() as f64;
            let n = if normal.dot(centre - v[0]) > 0.0 { -normal } else { normal };
            let far =
                piece.iter().map(|p| n.dot(*p)).chain(lv.iter().map(|p| n.dot(p.as_dvec3()))).fold(f64::MIN, f64::max);
            plane = (n, far + f64::from(pad));
            planes.push(Plane { n, d: plane.1 + margin });
        }
        let (scene, cut) = (self.scene, self.cut(leaf, light));
        let complete = self.bvh.collect_in(cut, &planes, |t| {
            if t == tri || scene.tri_light[t.idx()] == Some(light) {
                return true;
            }
            let w = scene.triangles[t.idx()].v.map(|p| p.as_dvec3());
            if planes.iter().any(|p| w.iter().all(|q| p.distance(*q) > 0.0)) {
                return true;
            }
            out.push(t);
            out.len() <= SHAFT_MAX
        });
        complete.then_some((within, plane))
    }
}

/// The triangles of a piece's list `list` (their vertices in `lanes`, a block of eight after
/// another) that `pyramid` does not cull, into `out`, in order.
fn uncut(list: &[TriId], lanes: &[TriLanes], pyramid: &Pyramid, out: &mut Vec<TriId>, ctx: &mut QueryCtx) {
    ctx.stats.box_tests += list.len() as u64;
    out.clear();
    let simd = Avx2::detect();
    for (tris, block) in list.chunks(8).zip(lanes) {
        let mut keep = !pyramid.culls8(block, simd) & ((1u16 << tris.len()) - 1) as u8;
        while keep != 0 {
            let c = keep.trailing_zeros() as usize;
            keep &= keep - 1;
            out.push(tris[c]);
        }
    }
}

/// True if `x` lies within the box `within` and on the inner side of `plane`.
#[inline]
fn accepts(within: &Aabb, plane: (DVec3, f64), x: Vec3) -> bool {
    x.cmpge(within.min).all() && x.cmple(within.max).all() && plane.0.dot(x.as_dvec3()) <= plane.1
}
