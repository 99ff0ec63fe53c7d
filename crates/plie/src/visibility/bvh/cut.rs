//! Where a fan's walk down the scene BVH starts (issue 21; issue 15's "bounded cut"): for an octree
//! leaf and a light, at most [`CUT_MAX`] children of BVH nodes whose boxes hold every triangle box
//! that meets the hull of the leaf's box and the light's bounding box ([`Shaft::of_boxes`]). A fan
//! from a point of the leaf to the light lies inside that hull, so testing the cut's boxes as the
//! children of one node ([`super::Bvh::fan_occluded`]) reaches every triangle a walk from the root
//! would, without visiting the nodes above the cut.
//!
//! The cut is chosen greedily: the root's children that meet the region, then the inner child with
//! the largest box replaced by its own children that meet it, as long as at most [`CUT_MAX`] remain.
//! It keeps its entries' boxes (decoded from their parents as a walk decodes them) and what they
//! lead to, so a walk reads one cut and no parent node.

use glam::{DVec3, Vec3};
use obvhs::cwbvh::node::CwBvhNode;

use super::{Bvh, PAD};
use crate::construct::shaft::{Plane, Shaft};
use crate::geometry::Aabb;
use crate::visibility::simd::Avx2;

/// Most entries of a cut: one node's worth of box lanes. Measured (callgrind at 64 rays): 16 cost
/// more than 8 on huis-c, cornell-bunny and cornell-dragon-100k, and less on conference-lit.
pub(crate) const CUT_MAX: usize = 8;

/// Most slanted planes of the hull of two boxes ([`Shaft::of_boxes`]): four lines bridge two
/// rectangles, per axis.
const SLANTED_MAX: usize = 12;

/// An entry of a cut being chosen: the parent node, the child's slot, its box's area, and whether
/// it is an inner node that may still be expanded (not a leaf, not found too wide to expand).
type Entry = (u32, u8, f32, bool);

/// What a cut's entry (a child of a BVH node) leads to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Child {
    /// No entry.
    #[default]
    None,
    /// An inner node.
    Node(u32),
    /// A leaf: `(start, len)` in the primitive indices.
    Leaf(u32, u32),
}

impl Child {
    /// Child `c` of `node` (which has one there).
    #[inline]
    pub(super) fn of(node: &CwBvhNode, c: usize) -> Child {
        if node.is_leaf(c) {
            let (start, len) = node.child_primitives(c);
            Child::Leaf(start, len)
        } else {
            Child::Node(node.child_node_index(c))
        }
    }
}

/// A cut: up to [`CUT_MAX`] children of BVH nodes, with their boxes (in the BVH's normalised units,
/// as the walk decodes them from their parents) in lanes, so that a walk reads the cut without
/// reading the parents.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Cut {
    /// Per axis, the entries' lower bounds.
    pub lo: [[f32; CUT_MAX]; 3],
    /// Per axis, the entries' upper bounds.
    pub hi: [[f32; CUT_MAX]; 3],
    /// What each entry leads to.
    pub child: [Child; CUT_MAX],
    /// Entries.
    pub len: u8,
}

/// A half-space `n . p <= d` (world units) for tests of the BVH's boxes ([`Bvh::local_plane`]):
/// a box of centre `c` and half-size `h` in normalised units, grown by twice the padding there, may
/// meet it if `n . c - |n| . h + k <= 0` (`k` carries `d`, the BVH's origin and scale and the
/// padding; multiplied through by the scale and in `f64`, its rounding is far below the padding).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct LocalPlane {
    n: DVec3,
    abs_n: DVec3,
    k: f64,
}

impl LocalPlane {
    /// False if the box of centre `c` and half-size `h` (normalised units), grown by twice the
    /// padding, lies wholly beyond the plane.
    #[inline]
    pub(super) fn may_meet(&self, c: DVec3, h: DVec3) -> bool {
        self.n.dot(c) - self.abs_n.dot(h) + self.k <= 0.0
    }

    /// True if the box `(lo, hi)` (normalised units) may meet every plane of `planes`.
    #[inline]
    pub(super) fn all_may_meet(planes: &[LocalPlane], lo: Vec3, hi: Vec3) -> bool {
        let (c, h) = (((lo + hi) * 0.5).as_dvec3(), ((hi - lo) * 0.5).as_dvec3());
        planes.iter().all(|p| p.may_meet(c, h))
    }
}

/// The slanted planes of a cut's region ([`LocalPlane`]) in `f32`, so that eight boxes are tested
/// at once ([`LanePlanes::keep8`]).
#[derive(Clone, Copy, Debug, Default)]
struct LanePlanes {
    /// Per plane: `n`, `|n|` (per axis), `2 k`, and the rounding bound's `16 ε |n|_1` and
    /// `32 ε |k|`.
    n: [[f32; 3]; SLANTED_MAX],
    abs_n: [[f32; 3]; SLANTED_MAX],
    k2: [f32; SLANTED_MAX],
    slope: [f32; SLANTED_MAX],
    floor: [f32; SLANTED_MAX],
    len: usize,
}

impl LanePlanes {
    /// The first [`SLANTED_MAX`] of `planes`.
    fn of(planes: &[LocalPlane]) -> LanePlanes {
        let mut to = LanePlanes::default();
        for (i, p) in planes.iter().take(SLANTED_MAX).enumerate() {
            to.n[i] = p.n.as_vec3().to_array();
            to.abs_n[i] = p.abs_n.as_vec3().to_array();
            to.k2[i] = (2.0 * p.k) as f32;
            to.slope[i] = (16.0 * f64::from(f32::EPSILON) * p.abs_n.element_sum()) as f32;
            to.floor[i] = (32.0 * f64::from(f32::EPSILON) * p.k.abs()) as f32;
            to.len = i + 1;
        }
        to
    }

    /// Of eight boxes `(lo, hi)` (normalised units, in lanes), those that may meet every plane, as
    /// bits: [`LocalPlane::may_meet`] of each box in `f32`, twice over (`a = lo + hi`, `b = hi -
    /// lo`: `n . a - |n| . b + 2 k <= 0`), accepted up to a bound on that sum's rounding. Each of
    /// its roundings (`n`, `k`, `a`, `b`, six products and six sums) errs by at most `ε` of the
    /// terms' magnitude `sum |n_i| (|a_i| + |b_i|) + 2 |k|`, which is at most `|n|_1 m + 2 |k|`
    /// with `m` the box's largest `|a_i| + |b_i|`: the bound `16 ε (|n|_1 m + 2 |k|)` holds them
    /// with room for its own rounding. So every box the exact test accepts is kept.
    #[inline(always)]
    fn keep8(&self, lo: &[[f32; 8]; 3], hi: &[[f32; 8]; 3]) -> u8 {
        let (mut a, mut b) = ([[0f32; 8]; 3], [[0f32; 8]; 3]);
        for k in 0..3 {
            for c in 0..8 {
                (a[k][c], b[k][c]) = (lo[k][c] + hi[k][c], hi[k][c] - lo[k][c]);
            }
        }
        let mut m = [0f32; 8];
        for c in 0..8 {
            let size = |k: usize| a[k][c].abs() + b[k][c].abs();
            m[c] = size(0).max(size(1)).max(size(2));
        }
        let mut keep = [1u32; 8];
        for p in 0..self.len.min(SLANTED_MAX) {
            let ([nx, ny, nz], [ax, ay, az]) = (self.n[p], self.abs_n[p]);
            for c in 0..8 {
                let v = nx * a[0][c] + ny * a[1][c] + nz * a[2][c] - (ax * b[0][c] + ay * b[1][c] + az * b[2][c])
                    + self.k2[p];
                keep[c] &= u32::from(v <= self.slope[p] * m[c] + self.floor[p]);
            }
        }
        (0..8).fold(0, |bits, c| bits | (keep[c] as u8) << c)
    }
}

/// The eight child boxes of `node` in normalised units, eight lanes per bound, as
/// [`Bvh::child_box`] decodes each (the same operations, so the same values).
#[inline(always)]
fn child_lanes(node: &CwBvhNode) -> ([[f32; 8]; 3], [[f32; 8]; 3]) {
    let e = node.compute_extent();
    let (mut los, mut his) = ([[0f32; 8]; 3], [[0f32; 8]; 3]);
    let mins = [&node.child_min_x, &node.child_min_y, &node.child_min_z];
    let maxs = [&node.child_max_x, &node.child_max_y, &node.child_max_z];
    for k in 0..3 {
        for c in 0..8 {
            los[k][c] = node.p[k] + e[k] * f32::from(mins[k][c]);
            his[k][c] = node.p[k] + e[k] * f32::from(maxs[k][c]);
        }
    }
    (los, his)
}

impl Bvh {
    /// The cut of the hull of the box `b` and the bounding box of the light polygon `light`, grown
    /// by `pad`: the hull holds every segment from a point of `b` to a point of the light.
    pub(crate) fn cut_of(&self, b: &Aabb, light: &[Vec3], pad: f32) -> Cut {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = Avx2::detect() {
            // SAFETY: AVX2 is available (the proof).
            return unsafe { self.cut_of_avx(b, light, pad, simd) };
        }
        self.cut_of_in(b, light, pad)
    }

    /// [`Bvh::cut_of`] compiled for AVX2, so that its box tests run eight lanes wide (the same
    /// operations, so the same cut).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    unsafe fn cut_of_avx(&self, b: &Aabb, light: &[Vec3], pad: f32, _: Avx2) -> Cut {
        self.cut_of_in(b, light, pad)
    }

    /// The body of [`Bvh::cut_of`].
    #[inline(always)]
    fn cut_of_in(&self, b: &Aabb, light: &[Vec3], pad: f32) -> Cut {
        let shaft = Shaft::of_boxes(b, &Aabb::from_points(light), pad);
        // The region is the shaft's bounds (the box and the light, grown by `pad`), and `cut` keeps
        // only boxes that meet it: the shaft's other planes are left to test.
        let mut planes = [LocalPlane::default(); SLANTED_MAX];
        let slanted = &shaft.planes[..shaft.planes.len() - 6];
        debug_assert!(slanted.len() <= SLANTED_MAX);
        for (to, p) in planes.iter_mut().zip(slanted) {
            *to = self.local_plane(p);
        }
        let planes = LanePlanes::of(&planes[..slanted.len().min(SLANTED_MAX)]);
        self.cut(&shaft.bounds, &planes)
    }

    /// The half-space `p` (world units) as the boxes of the BVH (normalised units) are tested
    /// against it ([`LocalPlane::may_meet`]).
    pub(super) fn local_plane(&self, p: &Plane) -> LocalPlane {
        let (origin, scale) = (self.origin.as_dvec3(), f64::from(self.scale));
        let k = (p.n.dot(origin) - p.d) * scale - 2.0 * f64::from(PAD) * p.n.abs().element_sum();
        LocalPlane { n: p.n, abs_n: p.n.abs(), k }
    }

    /// The cut of the region `region` (world units; see the module documentation), keeping only the
    /// children whose boxes (in normalised units, not grown) may meet every plane of `planes`
    /// ([`LanePlanes::keep8`]), which accepts every box that, grown by twice the padding, meets a
    /// segment of the fans the cut serves. An empty BVH has an empty cut.
    #[inline(always)]
    fn cut(&self, region: &Aabb, planes: &LanePlanes) -> Cut {
        let mut cut = Cut::default();
        if self.cw.nodes.is_empty() {
            return cut;
        }
        // The region in normalised units, grown by the padding (far above the rounding of the
        // conversion).
        let lo = Vec3::from(self.to_local(region.min)) - Vec3::splat(PAD);
        let hi = Vec3::from(self.to_local(region.max)) + Vec3::splat(PAD);
        let children = |n: u32, to: &mut [Entry; 8]| self.children_in(n, planes, (lo, hi), to);
        let mut inner = [(0, 0, 0.0, false); 8];
        let mut entries = [(0, 0, 0.0, false); CUT_MAX];
        // The root has at most eight children, all of which fit.
        const { assert!(CUT_MAX >= 8) };
        let mut len = children(0, &mut inner);
        entries[..len].copy_from_slice(&inner[..len]);
        loop {
            // The widest entry that may be expanded (the last of equals).
            let mut next: Option<usize> = None;
            for (i, e) in entries[..len].iter().enumerate() {
                if e.3 && next.is_none_or(|j| e.2.total_cmp(&entries[j].2).is_ge()) {
                    next = Some(i);
                }
            }
            let Some(i) = next else {
                break;
            };
            let (p, c) = (entries[i].0, entries[i].1);
            let n = self.cw.nodes[p as usize].child_node_index(c as usize);
            let k = children(n, &mut inner);
            if len - 1 + k > CUT_MAX {
                entries[i].3 = false;
                continue;
            }
            // The entry's place to the last one, then its children after them.
            entries[i] = entries[len - 1];
            len -= 1;
            entries[len..len + k].copy_from_slice(&inner[..k]);
            len += k;
        }
        for (k, &(p, c, ..)) in entries[..len].iter().enumerate() {
            let (lo, hi) = self.child_box(p, c as usize);
            for a in 0..3 {
                (cut.lo[a][k], cut.hi[a][k]) = (lo[a], hi[a]);
            }
            cut.child[k] = Child::of(&self.cw.nodes[p as usize], c as usize);
        }
        cut.len = len as u8;
        cut
    }

    /// The children of node `n` whose boxes meet the region `(lo, hi)` (normalised units) and may
    /// meet every plane of `planes`, into `to` as entries of a cut; their count. Their eight boxes
    /// in lanes, as [`Bvh::child_box`] decodes them.
    #[inline(always)]
    fn children_in(&self, n: u32, planes: &LanePlanes, (lo, hi): (Vec3, Vec3), to: &mut [Entry; 8]) -> usize {
        let node = &self.cw.nodes[n as usize];
        let (los, his) = child_lanes(node);
        // Filled slots whose boxes meet the region's box.
        let mut inside = node.child_meta.map(|m| u32::from(m != 0));
        for k in 0..3 {
            for c in 0..8 {
                inside[c] &= u32::from(los[k][c] <= hi[k]) & u32::from(his[k][c] >= lo[k]);
            }
        }
        let mut meets = planes.keep8(&los, &his) & (0..8).fold(0, |bits, c| bits | (inside[c] as u8) << c);
        let mut len = 0;
        while meets != 0 {
            let c = meets.trailing_zeros() as usize;
            meets &= meets - 1;
            let d = Vec3::new(his[0][c] - los[0][c], his[1][c] - los[1][c], his[2][c] - los[2][c]);
            to[len] = (n, c as u8, d.x * d.y + d.y * d.z + d.z * d.x, !node.is_leaf(c));
            len += 1;
        }
        len
    }

    /// The box of child `c` of node `n`, in normalised units, as the walks decode it.
    #[inline]
    pub(super) fn child_box(&self, n: u32, c: usize) -> (Vec3, Vec3) {
        let node = &self.cw.nodes[n as usize];
        let e = node.compute_extent();
        let lo =
            Vec3::new(f32::from(node.child_min_x[c]), f32::from(node.child_min_y[c]), f32::from(node.child_min_z[c]));
        let hi =
            Vec3::new(f32::from(node.child_max_x[c]), f32::from(node.child_max_y[c]), f32::from(node.child_max_z[c]));
        (node.p + Vec3::from(e) * lo, node.p + Vec3::from(e) * hi)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use crate::construct::shaft::Shaft;
    use crate::geometry::Aabb;
    use crate::render::sampler::mix64;
    use crate::visibility::bvh::Bvh;

    /// Uniform numbers in [0, 1) from `seed`.
    fn uniform(mut state: u64) -> impl FnMut() -> f32 {
        move || {
            state = mix64(state);
            (state >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// The planes in lanes keep every box the `f64` test keeps, boxes just inside a plane (the
    /// exact sum a hair below zero, where an `f32` sum without the rounding bound drops some)
    /// among them, and drop boxes clearly beyond one.
    #[test]
    fn lane_planes_keep_what_the_exact_test_keeps() {
        use super::{LanePlanes, LocalPlane};
        use glam::DVec3;
        let mut rnd = uniform(3);
        let (mut kept, mut dropped, mut near) = (0, 0, 0);
        for _ in 0..2000 {
            let n = (DVec3::new(rnd() as f64, rnd() as f64, rnd() as f64) - 0.5).normalize_or(DVec3::X);
            let (mut lo, mut hi) = ([[0f32; 8]; 3], [[0f32; 8]; 3]);
            for c in 0..8 {
                for k in 0..3 {
                    let a = rnd() * 1000.0;
                    (lo[k][c], hi[k][c]) = (a, a + rnd() * rnd() * 300.0);
                }
            }
            // The plane through box 0's farthest-in corner, moved by at most a hair either way,
            // so that box 0 sits on it.
            let (c0, h0) = (
                DVec3::new(
                    lo[0][0] as f64 + hi[0][0] as f64,
                    lo[1][0] as f64 + hi[1][0] as f64,
                    lo[2][0] as f64 + hi[2][0] as f64,
                ) * 0.5,
                DVec3::new(
                    hi[0][0] as f64 - lo[0][0] as f64,
                    hi[1][0] as f64 - lo[1][0] as f64,
                    hi[2][0] as f64 - lo[2][0] as f64,
                ) * 0.5,
            );
            let k = -(n.dot(c0) - n.abs().dot(h0)) + (rnd() as f64 - 0.7) * 1e-4;
            let plane = LocalPlane { n, abs_n: n.abs(), k };
            let bits = LanePlanes::of(&[plane]).keep8(&lo, &hi);
            for c in 0..8 {
                let (l, h) = (
                    DVec3::new(lo[0][c] as f64, lo[1][c] as f64, lo[2][c] as f64),
                    DVec3::new(hi[0][c] as f64, hi[1][c] as f64, hi[2][c] as f64),
                );
                let v = n.dot((l + h) * 0.5) - n.abs().dot((h - l) * 0.5) + k;
                let keep = bits >> c & 1 == 1;
                if v <= 0.0 {
                    assert!(keep, "box {c} meets the plane (v = {v}) but is dropped");
                    kept += 1;
                    near += usize::from(c == 0);
                } else if v > 1e-2 {
                    assert!(!keep, "box {c} lies {v} beyond the plane but is kept");
                    dropped += 1;
                }
            }
        }
        // Both answers occur, and most planes have box 0 on their inner side.
        assert!(kept > 2000 && dropped > 2000 && near > 1000, "{kept} kept, {dropped} dropped, {near} near");
    }

    /// Every triangle whose box meets the hull of a random box and a light lies under the cut of
    /// that hull, and the cut has at most `CUT_MAX` entries.
    #[test]
    fn the_cut_holds_every_triangle_meeting_the_region() {
        let scene = crate::scene::builtin::load("huis-c").unwrap();
        let bvh = Bvh::build(&scene);
        let (lo, size) = (scene.bounds.min, scene.bounds.max - scene.bounds.min);
        let mut rnd = uniform(11);
        let mut deeper = 0;
        for _ in 0..300 {
            let p = lo + size * Vec3::new(rnd(), rnd(), rnd());
            let b = Aabb { min: p, max: p + size * (0.02 + 0.2 * rnd()) };
            let light = &scene.lights[(rnd() * scene.lights.len() as f32) as usize % scene.lights.len()].vertices;
            let pad = scene.tolerance();
            let cut = bvh.cut_of(&b, light, pad);
            // The hull, to check against.
            let corners = b.corners();
            let region = Aabb::from_points(light.iter().chain(&corners)).expanded(pad);
            let shaft = Shaft::of_boxes(&b, &Aabb::from_points(light), pad);
            assert!(cut.len as usize <= super::CUT_MAX);
            // The triangles under the cut.
            let mut under = vec![false; scene.triangles.len()];
            let mut todo: Vec<super::Child> = cut.child[..cut.len as usize].to_vec();
            while let Some(c) = todo.pop() {
                match c {
                    super::Child::None => unreachable!("an entry leads somewhere"),
                    super::Child::Leaf(start, len) => {
                        for p in start..start + len {
                            under[bvh.cw.primitive_indices[p as usize] as usize] = true;
                        }
                    }
                    super::Child::Node(n) => {
                        let node = &bvh.cw.nodes[n as usize];
                        todo.extend((0..8).filter(|&k| node.child_meta[k] != 0).map(|k| super::Child::of(node, k)));
                    }
                }
            }
            for (t, tri) in scene.triangles.iter().enumerate() {
                let tb = tri.aabb();
                if tb.overlaps(&region) && shaft.may_overlap_box(&tb) {
                    assert!(under[t], "triangle {t} meets the region but is not under its cut");
                }
            }
            let root = &bvh.cw.nodes[0];
            let top: Vec<super::Child> =
                (0..8).filter(|&k| root.child_meta[k] != 0).map(|k| super::Child::of(root, k)).collect();
            deeper += usize::from(!cut.child[..cut.len as usize].iter().all(|c| top.contains(c)));
        }
        // Most cuts reach below the root's children (else they would save nothing).
        eprintln!("{deeper} of 300 cuts below the root's children");
        assert!(deeper > 150, "{deeper} of 300 cuts below the root's children");
    }

    /// Fans of 32 rays from random points of random boxes to a light, walked from the box's cut
    /// and from the root: the same answers, and brute force's.
    #[test]
    fn a_walk_from_the_cut_answers_as_one_from_the_root() {
        use crate::scene::{LightId, TriId};
        use crate::visibility::fan::{Fan, WalkStack};
        use crate::visibility::{Brute, LightRays, QueryCtx, Visibility};

        let scene = crate::scene::builtin::load("huis-c").unwrap();
        let bvh = Bvh::build(&scene);
        let brute = Brute::new(&scene);
        let (lo, size) = (scene.bounds.min, scene.bounds.max - scene.bounds.min);
        let mut rnd = uniform(5);
        let mut ctx = QueryCtx::new(scene.triangles.len());
        let (mut fan, mut walk) = (Fan::default(), WalkStack::default());
        let (mut occluded, mut total) = (0, 0);
        for _ in 0..200 {
            let p = lo + size * Vec3::new(rnd(), rnd(), rnd()) * 0.9;
            let b = Aabb { min: p, max: p + size * (0.01 + 0.1 * rnd()) };
            let li = (rnd() * scene.lights.len() as f32) as usize % scene.lights.len();
            let light = &scene.lights[li];
            let cut = bvh.cut_of(&b, &light.vertices, scene.tolerance());
            let x = b.min + (b.max - b.min) * Vec3::new(rnd(), rnd(), rnd());
            let v = &light.vertices;
            let targets: Vec<Vec3> = (0..32)
                .map(|_| {
                    let (s, t) = (rnd(), rnd());
                    v[0] + (v[1] - v[0]) * s + (v[v.len() - 1] - v[0]) * t * (1.0 - s)
                })
                .collect();
            let rays = LightRays {
                origin: x,
                origin_tri: TriId(u32::MAX),
                leaf: None,
                light: LightId(li as u32),
                targets: &targets,
            };
            let mut answers = [[false; 32]; 2];
            for (k, from) in [Some(&cut), None].into_iter().enumerate() {
                fan.set(&rays);
                fan.pyramid.set_in(&scene, x, rays.light);
                bvh.fan_occluded(from, &rays, &mut fan, &mut walk, &mut answers[k], &mut ctx);
            }
            assert_eq!(answers[0], answers[1], "cut against root");
            for (k, &a) in answers[0].iter().enumerate() {
                assert_eq!(a, brute.occluded(&rays.ray(k), &mut ctx), "ray {k}");
                occluded += usize::from(a);
                total += 1;
            }
        }
        // Both answers occur (319 of 6,400 rays are occluded).
        assert!(occluded > total / 40 && occluded < total * 9 / 10, "{occluded} of {total} occluded");
    }
}
