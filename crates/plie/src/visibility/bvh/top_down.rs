//! A top-down BVH build for the boxes PLOC would merge in quadratic time (the scene BVH's build,
//! [`super::Bvh::build`]). PLOC merges, pass after pass, the neighbours in Morton order that choose
//! each other as the cheapest to merge with. Where that cost changes steadily along the order, few
//! choose each other and each pass merges few pairs: a fan of triangles around one centre that
//! spans the scene (a disc of `n` segments, or one OBJ face of `n` corners, which is triangulated as
//! such a fan) took 0.98 s at 25,000 triangles, 3.78 s at 50,000 and 15.28 s at 100,000.
//! [`ploc_would_stall`] makes PLOC's first choice for every box and, where a stretch of the Morton
//! order pairs up too little, [`build`] splits the boxes top-down by the surface area heuristic
//! over binned centres (`O(n log n)`) instead. Scenes whose boxes pair up as meshes do keep PLOC's
//! BVH. Either way the boxes are the same padded boxes, so the answers are the same.

use glam::Vec3A;
use obvhs::aabb::Aabb as BAabb;
use obvhs::bvh2::{node::Bvh2Node, Bvh2};
use obvhs::ploc::morton::morton_encode_u64_unorm;
use rayon::prelude::*;

/// Fewer boxes than this are left to PLOC whatever their shape (a quadratic build of 16,384 boxes
/// takes well under a second).
const CHECKED_FROM: usize = 16384;
/// The stretch of the Morton order whose pairing is judged.
const WINDOW: usize = 4096;
/// How far along the Morton order each box looks for its partner: PLOC's (`PlocSearchDistance::Medium`).
const SEARCH: usize = 14;
/// A stretch in which fewer than one box in this many pairs up stalls PLOC.
const STALL: usize = 16;
/// Bins of the surface area heuristic.
const BINS: usize = 16;

/// True if PLOC would merge some stretch of `boxes` in quadratic time: ordered by the Morton code
/// of their centres, each box chooses the neighbour within [`SEARCH`] whose union with it has the
/// least area (PLOC's choice), and in some stretch of [`WINDOW`] boxes fewer than one in [`STALL`]
/// is chosen back.
pub(super) fn ploc_would_stall(boxes: &[BAabb]) -> bool {
    let n = boxes.len();
    if n < CHECKED_FROM {
        return false;
    }
    let bounds = boxes.iter().fold(BAabb::empty(), |b, x| b.union(x));
    let size = bounds.diagonal().max(Vec3A::splat(f32::MIN_POSITIVE)).as_dvec3();
    let mut order: Vec<(u64, u32)> = boxes
        .par_iter()
        .enumerate()
        .map(|(i, b)| (morton_encode_u64_unorm((b.center() - bounds.min).as_dvec3() / size), i as u32))
        .collect();
    order.par_sort_unstable();
    let at = |k: usize| &boxes[order[k].1 as usize];
    let choice: Vec<usize> = (0..n)
        .into_par_iter()
        .map(|k| {
            let lo = k.saturating_sub(SEARCH);
            let hi = (k + SEARCH).min(n - 1);
            let mut best = (f32::INFINITY, k);
            for j in (lo..=hi).filter(|&j| j != k) {
                let cost = at(k).union(at(j)).half_area();
                if cost < best.0 {
                    best = (cost, j);
                }
            }
            best.1
        })
        .collect();
    (0..n).step_by(WINDOW).any(|start| {
        let end = (start + WINDOW).min(n);
        let paired = (start..end).filter(|&k| choice[choice[k]] == k).count();
        // A last stretch shorter than half a window is too short to judge, and is not judged.
        end - start >= WINDOW / 2 && paired * STALL < end - start
    })
}

/// A BVH2 over `boxes` (leaves of one box, as PLOC builds), split top-down: each node's boxes are
/// binned by their centres along the centres' longest axis and split where the surface area
/// heuristic is least, or at the median where the centres coincide along it or every split
/// leaves one side empty.
pub(super) fn build(boxes: &[BAabb]) -> Bvh2 {
    let n = boxes.len();
    let mut nodes: Vec<Bvh2Node> = Vec::with_capacity((2 * n).saturating_sub(1));
    let mut indices: Vec<u32> = (0..n as u32).collect();
    let centres: Vec<Vec3A> = boxes.iter().map(BAabb::center).collect();
    let mut max_depth = 0;
    if n == 0 {
        return Bvh2::default();
    }
    nodes.push(Bvh2Node::default());
    // (node, first, end, depth) still to fill.
    let mut todo = vec![(0usize, 0usize, n, 1usize)];
    while let Some((node, first, end, depth)) = todo.pop() {
        max_depth = max_depth.max(depth);
        let ids = &mut indices[first..end];
        let bounds = ids.iter().fold(BAabb::empty(), |b, &i| b.union(&boxes[i as usize]));
        if ids.len() == 1 {
            nodes[node] = Bvh2Node::new(bounds, 1, first as u32);
            continue;
        }
        let mid = first + split(ids, boxes, &centres);
        let left = nodes.len();
        nodes.push(Bvh2Node::default());
        nodes.push(Bvh2Node::default());
        nodes[node] = Bvh2Node::new(bounds, 0, left as u32);
        todo.push((left, first, mid, depth + 1));
        todo.push((left + 1, mid, end, depth + 1));
    }
    Bvh2 {
        nodes,
        primitive_indices: indices,
        children_are_ordered_after_parents: true,
        max_depth: max_depth.max(obvhs::bvh2::DEFAULT_MAX_STACK_DEPTH),
        ..Bvh2::default()
    }
}

/// Reorders `ids` (at least two) so that the first `k` go left and the rest right, and returns `k`
/// (at least 1 and below `ids.len()`).
fn split(ids: &mut [u32], boxes: &[BAabb], centres: &[Vec3A]) -> usize {
    let cb = ids.iter().fold(BAabb::empty(), |mut b, &i| {
        b.extend(centres[i as usize]);
        b
    });
    let axis = cb.largest_axis();
    let (lo, extent) = (cb.min[axis], cb.diagonal()[axis]);
    let median = |ids: &mut [u32]| {
        let k = ids.len() / 2;
        ids.select_nth_unstable_by(k, |&a, &b| centres[a as usize][axis].total_cmp(&centres[b as usize][axis]));
        k
    };
    if !(extent > 0.0 && extent.is_finite()) {
        return median(ids);
    }
    let bin_of = |i: u32| (((centres[i as usize][axis] - lo) / extent * BINS as f32) as usize).min(BINS - 1);
    let mut bins = [(BAabb::empty(), 0usize); BINS];
    for &i in ids.iter() {
        let b = &mut bins[bin_of(i)];
        b.0 = b.0.union(&boxes[i as usize]);
        b.1 += 1;
    }
    // The area times count of the boxes left of each plane, then the right ones' added.
    let mut cost = [0.0f32; BINS - 1];
    let (mut acc, mut count) = (BAabb::empty(), 0);
    for p in 0..BINS - 1 {
        acc = acc.union(&bins[p].0);
        count += bins[p].1;
        cost[p] = if count == 0 { f32::INFINITY } else { acc.half_area() * count as f32 };
    }
    let (mut acc, mut count) = (BAabb::empty(), 0);
    for p in (0..BINS - 1).rev() {
        acc = acc.union(&bins[p + 1].0);
        count += bins[p + 1].1;
        cost[p] = if count == 0 { f32::INFINITY } else { cost[p] + acc.half_area() * count as f32 };
    }
    let best = (0..BINS - 1).min_by(|&a, &b| cost[a].total_cmp(&cost[b])).expect("bins");
    if !cost[best].is_finite() {
        return median(ids);
    }
    // Partition: the boxes of bins up to `best` first.
    let mut k = 0;
    for j in 0..ids.len() {
        if bin_of(ids[j]) <= best {
            ids.swap(j, k);
            k += 1;
        }
    }
    if k == 0 || k == ids.len() {
        median(ids)
    } else {
        k
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::TAU;

    /// The boxes of a disc of `n` triangles around one centre (as an OBJ face of `n` corners is
    /// triangulated), and of a grid of `n` triangles.
    fn disc(n: usize) -> Vec<BAabb> {
        let rim = |i: usize| {
            let a = TAU * i as f32 / n as f32;
            Vec3A::new(a.cos(), 0.0, a.sin()) * 500.0 + Vec3A::splat(500.0)
        };
        (0..n)
            .map(|i| {
                let mut b = BAabb::empty();
                b.extend(Vec3A::splat(500.0)).extend(rim(i)).extend(rim(i + 1));
                b
            })
            .collect()
    }

    fn grid(n: usize) -> Vec<BAabb> {
        let side = (n as f32 / 2.0).sqrt().ceil() as usize;
        (0..n)
            .map(|t| {
                let (c, r) = ((t / 2) % side, (t / 2) / side);
                let p = Vec3A::new(c as f32, 0.0, r as f32) * (1000.0 / side as f32);
                BAabb::new(p, p + Vec3A::new(1000.0 / side as f32, 0.0, 1000.0 / side as f32))
            })
            .collect()
    }

    /// Every box is in exactly one leaf, whose box is its own; every inner node's box holds its
    /// children's.
    fn assert_valid(bvh: &Bvh2, boxes: &[BAabb]) {
        let mut seen = vec![0u32; boxes.len()];
        let mut todo = vec![0usize];
        while let Some(i) = todo.pop() {
            let node = &bvh.nodes[i];
            if node.prim_count > 0 {
                for &p in &bvh.primitive_indices[node.first_index as usize..][..node.prim_count as usize] {
                    seen[p as usize] += 1;
                    assert_eq!(node.aabb(), &boxes[p as usize]);
                }
                continue;
            }
            for c in [node.first_index as usize, node.first_index as usize + 1] {
                let child = bvh.nodes[c].aabb();
                assert!(node.aabb().union(child) == *node.aabb(), "node {i} holds child {c}");
                assert!(c > i, "children after their parent");
                todo.push(c);
            }
        }
        assert!(seen.iter().all(|&k| k == 1), "every box in one leaf");
    }

    #[test]
    fn a_fan_stalls_ploc_and_a_grid_does_not() {
        assert!(ploc_would_stall(&disc(20_000)));
        assert!(!ploc_would_stall(&grid(20_000)));
        // Below the size checked, PLOC is kept whatever the shape.
        assert!(!ploc_would_stall(&disc(CHECKED_FROM - 1)));
    }

    #[test]
    fn the_top_down_build_holds_every_box_once() {
        for boxes in [disc(20_000), grid(5_000), disc(2), vec![BAabb::new(Vec3A::ZERO, Vec3A::ONE); 300]] {
            assert_valid(&build(&boxes), &boxes);
        }
    }
}
