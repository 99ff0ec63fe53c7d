//! When a split can separate a cell's triangles (SPEC §3, the split rule; thesis §3.1.2).
//!
//! The octree splits a cell that holds more than `max_triangles` triangles. Two kinds of triangles
//! no split can separate, and this module counts each kind as one:
//! - **Exact copies** (the same three vertices in any order, bit for bit): they overlap the same
//!   cells. A face line `f 1 2 3 1 2 3 ...` adding 200 copies of the Cornell box's floor triangle
//!   made 1,220,836 leaves.
//! - **A hub**: a vertex inside the cell's box (grown by `eps`) that more than `max_triangles`
//!   distinct triangles of the scene share. Every cell whose grown box holds the hub overlaps all of
//!   them, so below this cell one cell per level would still hold them all, down to `max_depth`, and
//!   the cells around it, each crossed by the hub's triangles, would split into rings at every level.
//!   A disc of 20,000 segments around one centre (an OBJ face of 20,000 corners) made 44,108
//!   leaves and a 296 MB P-LIE that took 37.2 s to build.
//!
//! [`SplitCount::groups`] is the count the split rule compares with `max_triangles`: for a cell
//! whose grown box holds exactly one hub, the distinct triangles that do not touch it plus one;
//! otherwise its distinct triangles. Two hubs can be separated by splitting (they are different
//! points), so a cell with more than one still splits until each has its own. A mesh whose vertices
//! are shared by at most `max_triangles` triangles (every shared scene: at most 40, against the
//! default 200) has no hub, so the count is its distinct triangles and its octree is what it was
//! before hubs were counted. Which triangles a cell holds, and so every answer, never depends on
//! this count: only where the octree stops splitting does.

use rustc_hash::{FxHashMap, FxHashSet};

use crate::geometry::Aabb;
use crate::scene::{Scene, TriId};

/// A vertex compared bit for bit.
type Key = [u32; 3];

fn key(v: glam::Vec3) -> Key {
    v.to_array().map(f32::to_bits)
}

/// What the split rule needs of the whole scene, computed once per build: which triangles are the
/// first of their exact copies, and the vertices more than `max_triangles` distinct triangles share
/// (each a hub of any cell whose grown box holds it: all of its triangles overlap that cell).
pub(super) struct SplitCount {
    first_copy: Vec<bool>,
    /// Hub vertices, ascending.
    hubs: Vec<Key>,
}

impl SplitCount {
    /// Counts for `scene` at the split limit `max_triangles`.
    pub(super) fn new(scene: &Scene, max_triangles: usize) -> SplitCount {
        let first_copy = first_copies(scene);
        let mut valence: FxHashMap<Key, u32> = FxHashMap::default();
        for (t, _) in scene.triangles.iter().zip(&first_copy).filter(|(_, &first)| first) {
            for v in t.v {
                *valence.entry(key(v)).or_insert(0) += 1;
            }
        }
        let mut hubs: Vec<Key> =
            valence.into_iter().filter(|&(_, n)| n as usize > max_triangles).map(|(k, _)| k).collect();
        hubs.sort_unstable();
        SplitCount { first_copy, hubs }
    }

    /// The number of distinct triangles of a cell (exact copies counted once).
    pub(super) fn distinct(&self, tris: &[TriId]) -> usize {
        tris.iter().filter(|t| self.first_copy[t.idx()]).count()
    }

    /// Every hub, as indices for [`SplitCount::hubs_in`] and [`SplitCount::groups`] (none, without
    /// allocating, in a scene without hubs).
    pub(super) fn all_hubs(&self) -> Vec<u32> {
        (0..self.hubs.len() as u32).collect()
    }

    /// The hubs of `among` that lie in the box `grown` (a cell's box grown by `eps`). A cell's hubs
    /// are among its parent's, so the build filters each cell's from its parent's list.
    pub(super) fn hubs_in(&self, among: &[u32], grown: &Aabb) -> Vec<u32> {
        let inside = |&&h: &&u32| grown.contains(glam::Vec3::from_array(self.hubs[h as usize].map(f32::from_bits)));
        among.iter().filter(inside).copied().collect()
    }

    /// What the split rule compares with `max_triangles` for a cell whose triangles are `tris` and
    /// whose grown box holds the hubs `hubs` ([`SplitCount::hubs_in`]): with exactly one hub, the
    /// distinct triangles that do not touch it, plus one; otherwise [`SplitCount::distinct`].
    pub(super) fn groups(&self, scene: &Scene, tris: &[TriId], hubs: &[u32]) -> usize {
        let &[hub] = hubs else { return self.distinct(tris) };
        let hub = self.hubs[hub as usize];
        let free = tris
            .iter()
            .filter(|t| self.first_copy[t.idx()])
            .filter(|&&t| !scene.triangle(t).v.iter().any(|&v| key(v) == hub))
            .count();
        free + 1
    }
}

/// For every triangle, whether it is the first of its exact copies (the same vertices, in any order,
/// compared bit for bit). Copies overlap the same cells, so a cell holding a copy holds its first.
fn first_copies(scene: &Scene) -> Vec<bool> {
    let mut seen = FxHashSet::with_capacity_and_hasher(scene.triangles.len(), Default::default());
    scene
        .triangles
        .iter()
        .map(|t| {
            let mut corners = t.v.map(key);
            corners.sort_unstable();
            seen.insert(corners)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use std::f32::consts::TAU;

    use glam::Vec3;

    use super::*;
    use crate::SceneBuilder;

    /// `n` triangles around the origin in the plane `y = 0`, `extra` small triangles away from it,
    /// and a light.
    fn fan(n: usize, extra: usize) -> Scene {
        let mut b = SceneBuilder::new("fan");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        let rim = |i: usize| Vec3::new((TAU * i as f32 / n as f32).cos(), 0.0, (TAU * i as f32 / n as f32).sin());
        for i in 0..n {
            b.triangle(Vec3::ZERO, rim(i + 1), rim(i), m);
        }
        for i in 0..extra {
            let p = Vec3::new(0.1 + 0.001 * i as f32, 0.2, 0.1);
            b.triangle(p, p + Vec3::X * 0.01, p + Vec3::Z * 0.01, m);
        }
        b.light("light", &[Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.1)], Vec3::ONE);
        b.build().expect("valid scene")
    }

    fn all(s: &Scene) -> Vec<TriId> {
        (0..s.triangles.len() as u32).map(TriId).collect()
    }

    /// The count of the split rule for all of `s`'s triangles in the box `grown`.
    fn groups(s: &Scene, limit: usize, grown: &Aabb) -> usize {
        let count = SplitCount::new(s, limit);
        count.groups(s, &all(s), &count.hubs_in(&count.all_hubs(), grown))
    }

    #[test]
    fn a_hub_counts_once_with_the_triangles_around_it() {
        let s = fan(300, 20);
        let tris = all(&s);
        let around = Aabb::cube(Vec3::ZERO, 0.5);
        // 300 triangles share the centre: one hub, and the others (20 and the light's) count one each.
        let others = tris.len() - 300;
        assert_eq!(groups(&s, 200, &around), others + 1);
        // A limit above the hub's 300 triangles: no hub, every triangle counts.
        assert_eq!(groups(&s, 300, &around), tris.len());
        // A box that leaves the centre out: the triangles can be separated there.
        let beside = Aabb::new(Vec3::new(0.2, -0.1, 0.2), Vec3::new(0.9, 0.1, 0.9));
        assert_eq!(groups(&s, 200, &beside), tris.len());
    }

    #[test]
    fn two_hubs_in_a_box_still_split() {
        // Two fans of 300 triangles, one around the origin and one around (3, 0, 0).
        let mut b = SceneBuilder::new("fans");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        for c in [Vec3::ZERO, Vec3::X * 3.0] {
            let rim = |i: usize| c + Vec3::new((TAU * i as f32 / 300.0).cos(), 0.0, (TAU * i as f32 / 300.0).sin());
            for i in 0..300 {
                b.triangle(c, rim(i + 1), rim(i), m);
            }
        }
        b.light("light", &[Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.1)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let n = s.triangles.len();
        assert_eq!(groups(&s, 200, &s.bounds.expanded(0.1)), n);
        assert_eq!(groups(&s, 200, &Aabb::cube(Vec3::ZERO, 0.5)), n - 300 + 1);
        assert_eq!(groups(&s, 200, &Aabb::cube(Vec3::X * 3.0, 0.5)), n - 300 + 1);
    }

    #[test]
    fn vertices_shared_by_a_few_triangles_are_no_hubs() {
        // A grid of 40 x 40 squares: 3,200 triangles, each vertex shared by at most 6.
        let mut b = SceneBuilder::new("grid");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        let p = |i: usize, j: usize| Vec3::new(i as f32, 0.0, j as f32);
        for i in 0..40 {
            for j in 0..40 {
                b.triangle(p(i, j), p(i, j + 1), p(i + 1, j), m);
                b.triangle(p(i + 1, j), p(i, j + 1), p(i + 1, j + 1), m);
            }
        }
        b.light("light", &[Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.1)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let tris = all(&s);
        let everything = s.bounds.expanded(1.0);
        for limit in [6, 7, 200] {
            assert_eq!(groups(&s, limit, &everything), tris.len(), "limit {limit}");
        }
        // Below 6 the inner vertices are hubs. A box holding many can still be split between
        // them, so they do not count; a box holding one counts its 6 triangles once.
        assert_eq!(groups(&s, 5, &everything), tris.len());
        assert_eq!(groups(&s, 5, &Aabb::cube(Vec3::new(20.0, 0.0, 20.0), 0.5)), tris.len() - 6 + 1);
    }

    #[test]
    fn copies_count_once() {
        let mut b = SceneBuilder::new("copies");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        for _ in 0..5 {
            b.triangle(Vec3::ZERO, Vec3::X, Vec3::Z, m);
        }
        b.triangle(Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z, m);
        b.light("light", &[Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.0), Vec3::new(0.1, 2.0, 0.1)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let tris = all(&s);
        // Five copies, another triangle and the light's.
        assert_eq!(SplitCount::new(&s, 200).distinct(&tris), 3);
        assert_eq!(groups(&s, 2, &s.bounds.expanded(1.0)), 3);
    }
}
