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
    /// stopped the walk.
    #[inline]
    pub fn walk(&self, v: &mut impl ListVisitor) -> bool {
        if self.boxes.is_empty() {
            return v.chunk(self.list, 0);
        }
        let levels = Levels::new(self.list.len());
        self.node(v, &levels, levels.depth - 1, 0, 0)
    }

    fn node(&self, v: &mut impl ListVisitor, levels: &Levels, level: usize, index: usize, depth: usize) -> bool {
        if level == 0 {
            let tris = &self.list[index * CHUNK..self.list.len().min((index + 1) * CHUNK)];
            return v.chunk(tris, depth);
        }
        let below = level - 1;
        let (start, count) = (levels.start[below] as usize, levels.count[below] as usize);
        for child in index * CHUNK..count.min((index + 1) * CHUNK) {
            if v.enter(&self.boxes[start + child], depth + 1) && self.node(v, levels, below, child, depth + 1) {
                return true;
            }
        }
        false
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
