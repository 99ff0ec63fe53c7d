//! Box hierarchies over long blocker lists (SPEC §8 point 4): a shadow ray (or all the samples of a
//! light at once) tests the box of a run of [`CHUNK`] triangles before their own boxes, the box of
//! [`CHUNK`] such chunks before theirs, and so on up to one box, so it skips most of a long list
//! whose triangles lie away from it. Long lists are stored in Morton order
//! ([`crate::geometry::morton`]), so the runs are compact. Built when a P-LIE visibility is made;
//! the boxes only cull, so answers do not change.

use crate::geometry::Aabb;
use crate::lie::{CHUNK, CHUNKED_MIN};
use crate::scene::TriId;

/// Most levels a hierarchy can have (enough for `CHUNK^12` triangles).
pub const MAX_LEVELS: usize = 12;

/// The boxes of every long list of a P-LIE's lists (records' or face-grid cells').
#[derive(Default)]
pub struct ListBoxes {
    /// Per list: the index of its first box in `boxes`, or `u32::MAX` for a short list.
    pub(crate) first: Vec<u32>,
    /// Per long list, its levels one after the other: the chunks' boxes (unions of the grown
    /// triangle boxes), then the boxes of runs of [`CHUNK`] chunk boxes, up to a single box.
    boxes: Vec<Aabb>,
}

/// Where each level of the hierarchy over `n` triangles starts among its boxes, and how many
/// boxes it has; level 0 holds the chunks, the top level one box.
#[derive(Clone, Copy)]
struct Levels {
    start: [u32; MAX_LEVELS],
    count: [u32; MAX_LEVELS],
    depth: usize,
}

impl Levels {
    #[inline]
    fn new(n: usize) -> Levels {
        let mut l = Levels { start: [0; MAX_LEVELS], count: [0; MAX_LEVELS], depth: 0 };
        let (mut c, mut at) = (n.div_ceil(CHUNK), 0);
        loop {
            l.start[l.depth] = at as u32;
            l.count[l.depth] = c as u32;
            l.depth += 1;
            at += c;
            if c <= 1 || l.depth == MAX_LEVELS {
                return l;
            }
            c = c.div_ceil(CHUNK);
        }
    }

    fn total(&self) -> usize {
        (self.start[self.depth - 1] + self.count[self.depth - 1]) as usize
    }
}

impl ListBoxes {
    /// The hierarchies of the lists `ranges` (start, len) of `refs`. Ranges may repeat (grid cells
    /// share lists): a repeated range (same start and length) shares its boxes.
    pub fn new(ranges: impl Iterator<Item = (u32, u32)>, refs: &[TriId], tri_boxes: &[Aabb]) -> ListBoxes {
        let mut out = ListBoxes::default();
        let mut seen: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
        for (start, len) in ranges {
            if (len as usize) < CHUNKED_MIN || start == u32::MAX {
                out.first.push(u32::MAX);
                continue;
            }
            let f = *seen.entry((start, len)).or_insert_with(|| {
                let f = out.boxes.len();
                let union = |it: &mut dyn Iterator<Item = Aabb>| it.reduce(Aabb::union).expect("not empty");
                for chunk in refs[start as usize..(start + len) as usize].chunks(CHUNK) {
                    out.boxes.push(union(&mut chunk.iter().map(|t| tri_boxes[t.idx()])));
                }
                let levels = Levels::new(len as usize);
                for l in 1..levels.depth {
                    let below = f + levels.start[l - 1] as usize;
                    for i in 0..levels.count[l] as usize {
                        let end = (below + (i + 1) * CHUNK).min(below + levels.count[l - 1] as usize);
                        let b = union(&mut out.boxes[below + i * CHUNK..end].iter().copied());
                        out.boxes.push(b);
                    }
                }
                debug_assert_eq!(out.boxes.len() - f, levels.total());
                f as u32
            });
            out.first.push(f);
        }
        out
    }

    /// List `i` (stored at `list`) with its hierarchy if it is long.
    #[inline]
    pub fn of<'s>(&'s self, i: usize, list: &'s [TriId]) -> Chunked<'s> {
        match self.first[i] {
            u32::MAX => Chunked { list, boxes: &[] },
            f => {
                let n = Levels::new(list.len()).total();
                Chunked { list, boxes: &self.boxes[f as usize..f as usize + n] }
            }
        }
    }
}

/// A blocker list with, if long, the boxes of its hierarchy (all levels, chunks first).
#[derive(Clone, Copy)]
pub struct Chunked<'a> {
    /// The triangles.
    pub list: &'a [TriId],
    /// The boxes (empty for a short list).
    pub boxes: &'a [Aabb],
}

/// What a walk down a list's hierarchy does at its boxes and chunks ([`Chunked::walk`]).
pub trait ListVisitor {
    /// Whether to go into the box `b`, entered at `depth` (1 for the children of the top box).
    fn enter(&mut self, b: &Aabb, depth: usize) -> bool;
    /// Visits a run of triangles whose boxes were all entered (at `depth`, 0 for a short list or
    /// a list of one chunk); returns true to stop the walk.
    fn chunk(&mut self, tris: &[TriId], depth: usize) -> bool;
}

impl Chunked<'_> {
    /// The empty list.
    pub const EMPTY: Chunked<'static> = Chunked { list: &[], boxes: &[] };

    /// Walks the hierarchy from the top (whose box is not tested: it holds the whole list), going
    /// into the boxes `v` enters and visiting their chunks in list order; returns true if `v`
    /// stopped the walk. Depth first, with a cursor per level instead of recursion, so that it
    /// inlines into its caller (the fan's AVX2 copy of a list's tests).
    #[inline(always)]
    pub fn walk(&self, v: &mut impl ListVisitor) -> bool {
        if self.boxes.is_empty() {
            return v.chunk(self.list, 0);
        }
        let levels = Levels::new(self.list.len());
        let top = levels.depth - 1;
        let chunk = |i: usize| &self.list[i * CHUNK..self.list.len().min((i + 1) * CHUNK)];
        if top == 0 {
            return v.chunk(chunk(0), 0);
        }
        // Per level below the top: the next box to visit there, and the end of its siblings.
        let (mut next, mut end) = ([0usize; MAX_LEVELS], [0usize; MAX_LEVELS]);
        let mut level = top - 1;
        end[level] = (levels.count[level] as usize).min(CHUNK);
        loop {
            if next[level] == end[level] {
                if level == top - 1 {
                    return false;
                }
                level += 1;
                continue;
            }
            let child = next[level];
            next[level] += 1;
            // The children of the top box are at depth 1.
            let depth = top - level;
            if !v.enter(&self.boxes[levels.start[level] as usize + child], depth) {
                continue;
            }
            if level == 0 {
                if v.chunk(chunk(child), depth) {
                    return true;
                }
            } else {
                level -= 1;
                next[level] = child * CHUNK;
                end[level] = (levels.count[level] as usize).min((child + 1) * CHUNK);
            }
        }
    }

    /// The boxes of level `level` (0: the chunks), for tests.
    #[cfg(test)]
    pub fn level(&self, level: usize) -> &[Aabb] {
        let l = Levels::new(self.list.len());
        if level >= l.depth || self.boxes.is_empty() {
            return &[];
        }
        &self.boxes[l.start[level] as usize..(l.start[level] + l.count[level]) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The walk as a recursion over the levels (the reference for [`Chunked::walk`]).
    fn walk_by_recursion(c: &Chunked, v: &mut impl ListVisitor) -> bool {
        fn node(
            c: &Chunked,
            v: &mut impl ListVisitor,
            levels: &Levels,
            level: usize,
            index: usize,
            depth: usize,
        ) -> bool {
            if level == 0 {
                return v.chunk(&c.list[index * CHUNK..c.list.len().min((index + 1) * CHUNK)], depth);
            }
            let below = level - 1;
            let (start, count) = (levels.start[below] as usize, levels.count[below] as usize);
            for child in index * CHUNK..count.min((index + 1) * CHUNK) {
                if v.enter(&c.boxes[start + child], depth + 1) && node(c, v, levels, below, child, depth + 1) {
                    return true;
                }
            }
            false
        }
        if c.boxes.is_empty() {
            return v.chunk(c.list, 0);
        }
        let levels = Levels::new(c.list.len());
        node(c, v, &levels, levels.depth - 1, 0, 0)
    }

    /// Records every call; enters a box by a hash of its position and the call count, and stops
    /// at the `stop`-th chunk.
    struct Record {
        calls: Vec<(bool, u32, usize)>,
        stop: usize,
    }

    impl ListVisitor for Record {
        fn enter(&mut self, b: &Aabb, depth: usize) -> bool {
            let go = (b.min.x as u64 * 2654435761 + self.calls.len() as u64 * 40503) % 5 != 0;
            self.calls.push((true, b.min.x as u32, depth));
            go
        }
        fn chunk(&mut self, tris: &[TriId], depth: usize) -> bool {
            self.calls.push((false, tris.first().map_or(u32::MAX, |t| t.0), depth));
            self.calls.iter().filter(|c| !c.0).count() == self.stop
        }
    }

    /// The walk makes the recursion's calls, in its order, and stops where it stops, on lists of
    /// one to four levels.
    #[test]
    fn the_walk_visits_as_the_recursion() {
        for n in [1, 7, CHUNKED_MIN, CHUNKED_MIN + 3, 200, 513, 600, 4100] {
            let refs: Vec<TriId> = (0..n as u32).map(TriId).collect();
            let tri_boxes: Vec<Aabb> =
                (0..n).map(|i| Aabb { min: Vec3::splat(i as f32), max: Vec3::splat(i as f32 + 1.0) }).collect();
            let lb = ListBoxes::new(std::iter::once((0, n as u32)), &refs, &tri_boxes);
            let c = lb.of(0, &refs);
            for stop in [1, 3, usize::MAX] {
                let (mut a, mut b) = (Record { calls: vec![], stop }, Record { calls: vec![], stop });
                let (sa, sb) = (c.walk(&mut a), walk_by_recursion(&c, &mut b));
                assert_eq!((sa, &a.calls), (sb, &b.calls), "{n} triangles, stop {stop}");
                assert!(!a.calls.is_empty());
            }
        }
    }
}
