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

use std::hash::BuildHasher;
use std::sync::atomic::{AtomicU32, Ordering};

use rayon::prelude::*;
use rustc_hash::FxBuildHasher;

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
        let hubs = hub_vertices(scene, &first_copy, max_triangles);
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
///
/// In parallel, by sorting: the triangles sorted by a hash of their sorted corners, then by index, so
/// that copies are neighbours; a run of equal hashes is sorted again by the corners themselves (two
/// triangles may share a hash without being copies), and in each group of equal corners all but the
/// first index are copies.
fn first_copies(scene: &Scene) -> Vec<bool> {
    let corners = |t: TriId| {
        let mut c = scene.triangle(t).v.map(key);
        c.sort_unstable();
        c
    };
    let mut keyed: Vec<(u64, u32)> = (0..scene.triangles.len() as u32)
        .into_par_iter()
        .map(|t| (FxBuildHasher.hash_one(corners(TriId(t))), t))
        .collect();
    keyed.par_sort_unstable();
    let mut first = vec![true; scene.triangles.len()];
    let mut run = Vec::new();
    for same_hash in keyed.chunk_by(|a, b| a.0 == b.0).filter(|r| r.len() > 1) {
        run.clear();
        run.extend(same_hash.iter().map(|&(_, t)| (corners(TriId(t)), t)));
        run.sort_unstable();
        for copies in run.chunk_by(|a, b| a.0 == b.0) {
            for &(_, t) in &copies[1..] {
                first[t as usize] = false;
            }
        }
    }
    first
}

/// The vertices that more than `max_triangles` distinct triangles (the first of their copies) share,
/// ascending.
///
/// In parallel: each corner adds one to a counter chosen by its vertex's hash, so a counter bounds
/// the number of triangles around each vertex hashed to it. Only vertices whose counter passes the
/// limit can be hubs; the counters that pass it are noted as they do (in a mesh without hubs, none
/// is, and the count ends there), and the corners hashed to them are gathered and counted exactly,
/// by sorting. The table holds about one counter per four corners, at most 2^22 (16 MiB), so that it
/// stays in cache: at the default limit of 200 a false alarm needs some 30 vertices in one counter.
fn hub_vertices(scene: &Scene, first_copy: &[bool], max_triangles: usize) -> Vec<Key> {
    let bits = (3 * scene.triangles.len()).next_power_of_two().trailing_zeros().saturating_sub(2).clamp(10, 22);
    let counter = |k: &Key| (FxBuildHasher.hash_one(k) >> (64 - bits)) as usize;
    let counts: Vec<AtomicU32> = (0..1usize << bits).map(|_| AtomicU32::new(0)).collect();
    let corners =
        || scene.triangles.par_iter().zip(first_copy).filter(|(_, &first)| first).flat_map_iter(|(t, _)| t.v.map(key));
    let limit = u32::try_from(max_triangles).unwrap_or(u32::MAX);
    // A counter passes the limit once: at the corner that takes it from `limit` to `limit + 1`.
    let passed: Vec<usize> = corners()
        .filter_map(|k| {
            let c = counter(&k);
            (counts[c].fetch_add(1, Ordering::Relaxed) == limit).then_some(c)
        })
        .collect();
    if passed.is_empty() {
        return Vec::new();
    }
    let mut over = vec![0u64; (1usize << bits).div_ceil(64)];
    for c in passed {
        over[c / 64] |= 1 << (c % 64);
    }
    let mut maybe: Vec<Key> = corners()
        .filter(|k| {
            let c = counter(k);
            over[c / 64] & (1 << (c % 64)) != 0
        })
        .collect();
    maybe.par_sort_unstable();
    maybe.chunk_by(|a, b| a == b).filter(|run| run.len() > max_triangles).map(|run| run[0]).collect()
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

    /// The parallel counts equal the plain ones (a hash set of sorted corners, a map of valences) on a
    /// mesh of shared vertices with copies in any corner order, fans of several sizes, and at limits
    /// from 0 up, so that the counters' filter passes from almost every vertex to none.
    #[test]
    fn parallel_counts_equal_plain_ones() {
        use std::collections::{HashMap, HashSet};
        let mut b = SceneBuilder::new("mesh");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        let p = |i: usize, j: usize| Vec3::new(i as f32, ((i * 7 + j * 3) % 5) as f32 * 0.1, j as f32);
        for i in 0..12 {
            for j in 0..12 {
                b.triangle(p(i, j), p(i + 1, j), p(i + 1, j + 1), m);
                b.triangle(p(i, j), p(i + 1, j + 1), p(i, j + 1), m);
                if (i + j) % 5 == 0 {
                    b.triangle(p(i + 1, j + 1), p(i, j), p(i + 1, j), m);
                }
            }
        }
        for (k, n) in [3usize, 9, 40].into_iter().enumerate() {
            let c = Vec3::new(30.0 + 5.0 * k as f32, 0.0, 0.0);
            let rim =
                |i: usize| c + Vec3::new((TAU * i as f32 / n as f32).cos(), 0.0, (TAU * i as f32 / n as f32).sin());
            for i in 0..n {
                b.triangle(c, rim(i + 1), rim(i), m);
            }
        }
        b.light("light", &[Vec3::new(0.0, 9.0, 0.0), Vec3::new(0.1, 9.0, 0.0), Vec3::new(0.1, 9.0, 0.1)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let mut seen = HashSet::new();
        let plain_first: Vec<bool> = s
            .triangles
            .iter()
            .map(|t| {
                let mut c = t.v.map(key);
                c.sort_unstable();
                seen.insert(c)
            })
            .collect();
        assert_eq!(first_copies(&s), plain_first);
        assert!(plain_first.iter().any(|&f| !f), "the mesh has copies");
        let mut valence: HashMap<Key, usize> = HashMap::new();
        for (t, _) in s.triangles.iter().zip(&plain_first).filter(|(_, &f)| f) {
            for v in t.v {
                *valence.entry(key(v)).or_insert(0) += 1;
            }
        }
        for limit in [0, 1, 2, 3, 5, 6, 8, 9, 39, 40, 200] {
            let mut plain: Vec<Key> = valence.iter().filter(|&(_, &n)| n > limit).map(|(&k, _)| k).collect();
            plain.sort_unstable();
            assert_eq!(hub_vertices(&s, &plain_first, limit), plain, "limit {limit}");
        }
    }
}
