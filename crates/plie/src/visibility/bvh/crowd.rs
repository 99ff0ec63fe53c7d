//! Crowds of triangles with one centre in the BVH (issue 16's finding): PLOC orders boxes by the
//! Morton code of their centres and cannot order equal codes, so more than [`CROWD_LIMIT`] boxes
//! whose centres share a Morton cell become one primitive listing their triangles ([`Groups`]);
//! traversals are compiled for each kind of primitive ([`Prims`]: [`Single`] or [`Groups`]).

use obvhs::aabb::Aabb as BAabb;
use rayon::prelude::*;

/// More boxes than this with their centres in one Morton cell (`group_crowded_centres`) are one
/// BVH primitive. Two is common (both halves of an axis-aligned rectangle share their box), more rare.
pub const CROWD_LIMIT: usize = 8;

/// The triangles of each BVH primitive `p`: `tris[starts[p]..starts[p + 1]]`; and, once the BVH
/// is built ([`Groups::place`]), where the triangles of the primitive at each position of the BVH's
/// primitive index array begin in the leaf-ordered copy ([`super::LeafTris`]).
pub(super) struct Groups {
    starts: Vec<u32>,
    tris: Vec<u32>,
    placed: Vec<u32>,
}

impl Groups {
    /// Bytes held.
    pub(super) fn memory_bytes(&self) -> usize {
        (self.starts.len() + self.tris.len() + self.placed.len()) * 4
    }

    /// Notes where the triangles of each position of `primitive_indices` begin when laid out in
    /// that order (and where the last ends).
    pub(super) fn place(&mut self, primitive_indices: &[u32]) {
        self.placed = Vec::with_capacity(primitive_indices.len() + 1);
        let mut at = 0u32;
        for p in primitive_indices {
            self.placed.push(at);
            at += self.of(p).len() as u32;
        }
        self.placed.push(at);
    }
}

/// The triangles of a BVH primitive. Traversals are compiled for each kind, so the common one
/// ([`Single`]) pays nothing for the other.
pub(super) trait Prims {
    /// The triangles of primitive `*p` (`p` points into the BVH's primitive index array).
    fn of<'a>(&'a self, p: &'a u32) -> &'a [u32];

    /// The range of the leaf-ordered triangles ([`super::LeafTris`]) of the primitives at
    /// positions `start..start + len` of the BVH's primitive index array.
    fn span(&self, start: u32, len: u32) -> std::ops::Range<usize>;
}

/// Every primitive is the triangle of the same index.
pub(super) struct Single;

impl Prims for Single {
    #[inline(always)]
    fn of<'a>(&'a self, p: &'a u32) -> &'a [u32] {
        std::slice::from_ref(p)
    }

    #[inline(always)]
    fn span(&self, start: u32, len: u32) -> std::ops::Range<usize> {
        start as usize..(start + len) as usize
    }
}

impl Prims for Groups {
    #[inline(always)]
    fn of<'a>(&'a self, p: &'a u32) -> &'a [u32] {
        &self.tris[self.starts[*p as usize] as usize..self.starts[*p as usize + 1] as usize]
    }

    #[inline(always)]
    fn span(&self, start: u32, len: u32) -> std::ops::Range<usize> {
        self.placed[start as usize] as usize..self.placed[(start + len) as usize] as usize
    }
}

/// Cells per axis of the grid that [`group_crowded_centres`] puts box centres in: 2^21, the
/// resolution of the 63-bit Morton codes PLOC sorts by (`SortPrecision::U64`).
const CENTRE_CELLS: f64 = (1u32 << 21) as f64;

/// When more than [`CROWD_LIMIT`] boxes have their centres in one cell of a 2^21-per-axis grid over
/// the normalised scene (`size` units wide, boxes padded by `pad`) (so one Morton code, which PLOC cannot order: exact copies, instances with
/// one transform, or triangles nested around one centre): the primitives' boxes (one per crowded
/// cell, the union of its boxes, and one per other triangle, in order of first appearance) and their
/// triangles.
pub(super) fn group_crowded_centres(boxes: &[BAabb], size: f32, pad: f32) -> Option<(Vec<BAabb>, Groups)> {
    let per_unit = CENTRE_CELLS / f64::from(size + 2.0 * pad);
    // The cell as one number: 21 bits per axis.
    let cell = |b: &BAabb| {
        let c = (b.min + b.max) * 0.5;
        let [x, y, z] = c.to_array().map(|x| (f64::from(x + pad) * per_unit).clamp(0.0, CENTRE_CELLS - 1.0) as u64);
        x << 42 | y << 21 | z
    };
    // Whether any cell holds more than the limit: sorted, a crowd is a run (the common case ends here).
    let mut sorted: Vec<u64> = boxes.par_iter().map(cell).collect();
    sorted.par_sort_unstable();
    if !sorted.windows(CROWD_LIMIT + 1).any(|w| w[0] == w[CROWD_LIMIT]) {
        return None;
    }
    let mut count = std::collections::HashMap::new();
    for run in sorted.chunk_by(|a, b| a == b) {
        count.insert(run[0], run.len());
    }
    let cells: Vec<u64> = boxes.iter().map(cell).collect();
    let mut crowd = std::collections::HashMap::new();
    let mut members: Vec<Vec<u32>> = Vec::new();
    let mut prim_boxes: Vec<BAabb> = Vec::new();
    for (t, (b, c)) in boxes.iter().zip(&cells).enumerate() {
        if count[c] > CROWD_LIMIT {
            let p = *crowd.entry(*c).or_insert_with(|| {
                prim_boxes.push(*b);
                members.push(Vec::new());
                members.len() - 1
            });
            prim_boxes[p] = prim_boxes[p].union(b);
            members[p].push(t as u32);
        } else {
            prim_boxes.push(*b);
            members.push(vec![t as u32]);
        }
    }
    let mut starts = Vec::with_capacity(members.len() + 1);
    let mut tris = Vec::with_capacity(boxes.len());
    starts.push(0);
    for m in members {
        tris.extend(m);
        starts.push(tris.len() as u32);
    }
    Some((prim_boxes, Groups { starts, tris, placed: Vec::new() }))
}
