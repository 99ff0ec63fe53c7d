//! The leaf's own triangles, culled (SPEC §8 point 4). Every P-LIE mode ends by testing the triangles of
//! the ray's own leaf, which cover the part of the segment inside the leaf (SPEC §5); a leaf holds up
//! to `max_triangles` (200) of them, and testing them all dominated the P-LIE modes' time.
//!
//! So each leaf with many triangles gets a `RES x RES x RES` grid of voxels, each listing the
//! triangles whose grown bounding box overlaps the voxel grown by the same pad. A ray visits only the
//! voxels the part of its segment inside the leaf can touch (the voxel range of that part's bounding
//! box, each voxel then slab-tested), and tests their triangles once each (the query's stamps).
//!
//! Conservative: a triangle hit at a point `p` inside the leaf has `p` in its grown box and in some
//! grown voxel the segment passes through, so it is tested. A hit outside the leaf lies beyond the
//! exit face, where the record's blockers (or the no-record answer) cover it.

use super::QueryCtx;
use crate::geometry::{Aabb, Segment};
use crate::octree::{LeafId, Octree};
use crate::scene::TriId;

/// Voxels per axis of a leaf's grid.
const RES: usize = 4;

/// Leaves with at most this many triangles keep their plain list.
const MIN_TRIANGLES: usize = 24;

/// Per-leaf voxel grids over the leaves' own triangles.
pub struct LeafVoxels {
    /// Per leaf: first voxel in `voxels`, or `u32::MAX` for a leaf that keeps its plain list.
    first: Vec<u32>,
    /// Per voxel: `(start, len)` in `tris`.
    voxels: Vec<(u32, u32)>,
    tris: Vec<TriId>,
    pad: f32,
}

impl LeafVoxels {
    /// Grids for the leaves of `octree` with more than `MIN_TRIANGLES` triangles, from the grown
    /// triangle boxes `tri_boxes` (grown by `pad`).
    pub fn new(octree: &Octree, tri_boxes: &[Aabb], pad: f32) -> LeafVoxels {
        let mut out =
            LeafVoxels { first: Vec::with_capacity(octree.leaf_count()), voxels: Vec::new(), tris: Vec::new(), pad };
        let mut lists: Vec<Vec<TriId>> = vec![Vec::new(); RES * RES * RES];
        for leaf in octree.leaves() {
            let own = octree.leaf_triangles(leaf);
            if own.len() <= MIN_TRIANGLES {
                out.first.push(u32::MAX);
                continue;
            }
            out.first.push(out.voxels.len() as u32);
            let b = octree.leaf_bounds(leaf);
            for l in &mut lists {
                l.clear();
            }
            for &t in own {
                let (lo, hi) = out.range(&b, &tri_boxes[t.idx()]);
                for z in lo[2]..=hi[2] {
                    for y in lo[1]..=hi[1] {
                        for x in lo[0]..=hi[0] {
                            lists[(z * RES + y) * RES + x].push(t);
                        }
                    }
                }
            }
            for l in &lists {
                out.voxels.push((out.tris.len() as u32, l.len() as u32));
                out.tris.extend_from_slice(l);
            }
        }
        out
    }

    /// The voxel index range (inclusive, per axis) that the box `q` overlaps in the leaf box `b`, with
    /// voxels grown by the pad.
    #[inline]
    fn range(&self, b: &Aabb, q: &Aabb) -> ([usize; 3], [usize; 3]) {
        let mut lo = [0; 3];
        let mut hi = [RES - 1; 3];
        for k in 0..3 {
            let w = (b.max[k] - b.min[k]) / RES as f32;
            let f = |x: f32| ((x - b.min[k]) / w).floor().clamp(0.0, (RES - 1) as f32) as usize;
            lo[k] = f(q.min[k] - self.pad);
            hi[k] = f(q.max[k] + self.pad);
        }
        (lo, hi)
    }

    /// The grown box of voxel `(x, y, z)` of the leaf box `b`.
    #[inline]
    fn voxel_box(&self, b: &Aabb, v: [usize; 3]) -> Aabb {
        let mut lo = b.min;
        let mut hi = b.max;
        for k in 0..3 {
            let w = (b.max[k] - b.min[k]) / RES as f32;
            lo[k] = b.min[k] + w * v[k] as f32;
            if v[k] + 1 < RES {
                hi[k] = b.min[k] + w * (v[k] + 1) as f32;
            }
        }
        Aabb::new(lo, hi).expanded(self.pad)
    }

    /// Calls `test` on every triangle of `leaf` that the part of `seg` from `p0` to `p1` (its part in
    /// the leaf) may hit, once each, until it returns true; returns whether it did.
    #[inline]
    pub fn any(
        &self,
        octree: &Octree,
        leaf: LeafId,
        seg: &Segment,
        (p0, p1): (glam::Vec3, glam::Vec3),
        ctx: &mut QueryCtx,
        mut test: impl FnMut(TriId, &mut QueryCtx) -> bool,
    ) -> bool {
        let first = self.first[leaf.idx()];
        if first == u32::MAX {
            return octree.leaf_triangles(leaf).iter().any(|&t| test(t, ctx));
        }
        let b = octree.leaf_bounds(leaf);
        let (lo, hi) = self.range(&b, &Aabb::new(p0.min(p1), p0.max(p1)));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let (s, n) = self.voxels[first as usize + (z * RES + y) * RES + x];
                    if n == 0 || seg.clip(&self.voxel_box(&b, [x, y, z])).is_none() {
                        continue;
                    }
                    for &t in &self.tris[s as usize..(s + n) as usize] {
                        if ctx.first_visit(t) && test(t, ctx) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::RayTest;
    use crate::visibility::lie::exit_face;
    use crate::visibility::ShadowRay;
    use glam::Vec3;

    /// Every own triangle that a segment hits inside its leaf is visited.
    #[test]
    fn voxels_visit_every_triangle_hit_inside_the_leaf() {
        let scene = crate::scene::builtin::load("huis-a").unwrap();
        let octree = Octree::build(&scene, crate::octree::OctreeParams::thesis()).expect("valid octree parameters");
        let pad = scene.tolerance();
        let boxes: Vec<Aabb> = scene.triangles.iter().map(|t| t.aabb().expanded(pad)).collect();
        let vox = LeafVoxels::new(&octree, &boxes, pad);
        assert!(vox.first.iter().any(|&f| f != u32::MAX), "some leaf has a grid");
        let mut ctx = QueryCtx::new(scene.triangles.len());
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        let root = octree.root_bounds();
        let (mut checked, mut visited_total) = (0, 0);
        for i in 0..20_000 {
            let leaf = LeafId((rnd() * octree.leaf_count() as f32) as u32 % octree.leaf_count() as u32);
            let b = octree.leaf_bounds(leaf);
            let x = b.min + (b.max - b.min) * Vec3::new(rnd(), rnd(), rnd());
            let y = if i % 2 == 0 {
                root.min + (root.max - root.min) * Vec3::new(rnd(), rnd(), rnd())
            } else {
                b.min + (b.max - b.min) * Vec3::new(rnd(), rnd(), rnd())
            };
            if (y - x).length() < 1e-3 {
                continue;
            }
            let ray = ShadowRay::new(x, y, crate::LightId(0), TriId(u32::MAX), Some(leaf));
            let t_end = exit_face(&octree, leaf, &ray).map_or(ray.test.t_max, |(_, t)| t.min(ray.test.t_max));
            let seg = Segment::new(x, y - x, ray.test.t_min, ray.test.t_max);
            let part = (x + (y - x) * ray.test.t_min, x + (y - x) * t_end);
            let mut visited = Vec::new();
            ctx.begin_query();
            vox.any(&octree, leaf, &seg, part, &mut ctx, |t, _| {
                visited.push(t);
                false
            });
            visited_total += visited.len();
            let test = RayTest::new(x, y - x, ray.test.t_min, ray.test.t_max);
            for &t in octree.leaf_triangles(leaf) {
                if let Some(th) = test.hit(&scene.triangles[t.idx()]) {
                    if th <= t_end {
                        checked += 1;
                        assert!(visited.contains(&t), "ray {i}: triangle {t:?} hit at t = {th} inside leaf {leaf:?}");
                    }
                }
            }
        }
        assert!(checked > 1000, "{checked}");
        assert!(visited_total < 20_000 * 200, "the voxels cull something");
    }
}
