//! A fan of shadow rays down the scene BVH at once (issues 15 and 21), as a packet: the samples of
//! one light from one point. The `bvh` mode answers every light this way, and the P-LIE modes the
//! lights their footprints leave open ([`crate::visibility::lie`]) and the rays through records that
//! store no list ([`crate::lie::RecordKind::Scene`]).
//!
//! A node's eight child boxes are first culled by the pyramid from the point over the light
//! ([`crate::visibility::pyramid::Pyramid::culls_rel8`]) where the node has more than
//! [`CULL_ABOVE`] open rays, then each is tested against every ray still in the node's mask, eight
//! rays at a time, or one ray against all eight boxes where the node's rays are few and spread out
//! ([`Fan::meets8`]); a leaf's triangles (read from the BVH's copy of them in leaf order) are
//! tested against the rays that met its box ([`Fan::test_within`]). Inner children are visited
//! nearest first (along the first sample's direction), so that blockers close the rays early. A
//! node left with one open ray is walked by that ray alone ([`Bvh::ray_walk`]): a slab test of the
//! ray against the eight child boxes per node, with no masks to keep. The P-LIE modes start below
//! the root, from the cut of the point's leaf and the light ([`super::cut`]), whose entries are
//! tested as the children of one node.
//!
//! The boxes are the BVH's own (each triangle's box padded by `PAD` in its normalised space), taken
//! back to world units relative to the fan's apex; the rounding of that is far below the padding, so
//! no ray that meets a triangle misses its boxes. Triangles are decided by the fan's exact test, so
//! every answer is [`super::segment_occluded`]'s, which is brute force's.
//!
//! Where the CPU has AVX2, the walk is compiled for it as a whole, so that the fan's lane kernels
//! inline into it (measured: 2-8% fewer instructions per query, docs/results.md session 13); it
//! hands the proof of AVX2 ([`crate::visibility::simd::Avx2`]) down, so that no kernel checks the
//! CPU again (3.4% fewer, session 27); and a fan of at most 64 rays (one word of mask) has its own
//! copy in which the loops over mask words collapse.

use glam::{Vec3, Vec3A};
use obvhs::cwbvh::node::CwBvhNode;

use super::crowd::{Prims, Single};
use super::cut::{Child, Cut, CUT_MAX};
use super::{Bvh, LeafTris};
use crate::visibility::fan::{nonzero_bytes, Fan, WalkStack};
use crate::visibility::simd::Avx2;
use crate::visibility::{LightRays, QueryCtx};

impl Bvh {
    /// Tests the fan's open rays against every triangle of the scene the BVH was built from (but
    /// each ray's own: the origin triangle and the light's), walking the BVH with all of them at
    /// once, from `cut` (see [`Bvh::cut_of`]: the cut of a region that holds every segment of the
    /// fan) or else from the root. Each ray a triangle blocks gets `out[k]` set and is closed in
    /// the fan. The caller has set the fan's pyramid for this light.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn fan_occluded(
        &self,
        cut: Option<&Cut>,
        rays: &LightRays,
        fan: &mut Fan,
        walk: &mut WalkStack,
        out: &mut [bool],
        ctx: &mut QueryCtx,
    ) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = Avx2::detect() {
            // SAFETY: AVX2, POPCNT and BMI1 are available (the proof).
            return unsafe { self.fan_occluded_avx(cut, rays, fan, walk, out, ctx, simd) };
        }
        self.fan_occluded_in(cut, rays, fan, walk, out, ctx, None)
    }

    /// [`Bvh::fan_occluded`] compiled for AVX2 as a whole, so that the lane kernels (AVX2
    /// functions) inline into the walk instead of being called per node and triangle, and the
    /// masks' bit counts and scans are single instructions (POPCNT, BMI1's TZCNT). The same
    /// operations, so the same answers: Rust never fuses a multiply and an add.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,popcnt,bmi1")]
    #[allow(clippy::too_many_arguments)]
    unsafe fn fan_occluded_avx(
        &self,
        cut: Option<&Cut>,
        rays: &LightRays,
        fan: &mut Fan,
        walk: &mut WalkStack,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Avx2,
    ) {
        self.fan_occluded_in(cut, rays, fan, walk, out, ctx, Some(simd))
    }

    /// [`Bvh::fan_occluded`] for the BVH's kind of leaves.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn fan_occluded_in(
        &self,
        cut: Option<&Cut>,
        rays: &LightRays,
        fan: &mut Fan,
        walk: &mut WalkStack,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        // Up to 64 rays (one word of mask, the usual case) with the word count known to the
        // compiler.
        match (&self.groups, fan.words() == 1) {
            (None, true) => self.fan_walk::<_, true>(cut, &Single, rays, fan, walk, out, ctx, simd),
            (None, false) => self.fan_walk::<_, false>(cut, &Single, rays, fan, walk, out, ctx, simd),
            (Some(g), true) => self.fan_walk::<_, true>(cut, g, rays, fan, walk, out, ctx, simd),
            (Some(g), false) => self.fan_walk::<_, false>(cut, g, rays, fan, walk, out, ctx, simd),
        }
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn fan_walk<P: Prims, const ONE: bool>(
        &self,
        cut: Option<&Cut>,
        prims: &P,
        rays: &LightRays,
        fan: &mut Fan,
        walk: &mut WalkStack,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        let w = if ONE { 1 } else { fan.words() };
        if self.cw.nodes.is_empty() || fan.live() == 0 {
            return;
        }
        fan.ready_boxes(simd);
        let apex = self.to_local(fan.origin());
        let to_world = 1.0 / self.scale;
        walk.nodes.clear();
        walk.masks.clear();
        walk.visits.clear();
        walk.child_masks.resize(8 * w, 0);
        // The order of inner children: nearest first along the first sample's direction.
        let toward = rays.targets[0] - fan.origin();
        let WalkStack { nodes, masks, visits, node_mask, child_masks, ray_nodes, ray_mask } = walk;
        match cut {
            None => {
                if ONE {
                    visits.push((fan.open()[0], 0));
                } else {
                    nodes.push(0);
                    masks.extend_from_slice(fan.open());
                }
            }
            Some(cut) => {
                // The cut's entries as the children of one node, their boxes made relative to the
                // apex (all eight lanes, so that the loop is one of vectors: the lanes past the
                // cut's length are not `filled`).
                let (mut los, mut his) = ([[0f32; 8]; 3], [[0f32; 8]; 3]);
                for k in 0..3 {
                    for c in 0..CUT_MAX {
                        los[k][c] = (cut.lo[k][c] - apex[k]) * to_world;
                        his[k][c] = (cut.hi[k][c] - apex[k]) * to_world;
                    }
                }
                let culled = fan.pyramid.culls_rel8(&los, &his, simd);
                let filled = ((1u16 << cut.len) - 1) as u8;
                node_mask.clear();
                node_mask.extend_from_slice(fan.open());
                let hit =
                    fan.meets8(&los, &his, filled & !culled, &node_mask[..w], &mut child_masks[..8 * w], ctx, simd);
                let at = (hit, &los, &his, |c: usize| cut.child[c]);
                let stack = (&mut *nodes, &mut *masks, &mut *visits);
                if self.take_children::<P, ONE>(prims, rays, fan, out, ctx, at, toward, stack, child_masks, simd) {
                    return;
                }
            }
        }
        loop {
            // One word of mask (up to 64 rays) is kept in a register, with its node, more in the
            // scratch.
            let mut word = [0u64; 1];
            let ni;
            let node_mask: &[u64] = if ONE {
                let Some((m, n)) = visits.pop() else { break };
                (word[0], ni) = (m, n);
                &word
            } else {
                let Some(n) = nodes.pop() else { break };
                ni = n;
                let at = masks.len() - w;
                // Word by word: masks are one or two words, too short for a copy call.
                node_mask.clear();
                for &m in &masks[at..at + w] {
                    node_mask.push(m);
                }
                masks.truncate(at);
                node_mask
            };
            // Its rays may all have been closed since it was pushed; one ray left walks alone.
            let count: u32 = node_mask.iter().zip(fan.open()).map(|(m, o)| (m & o).count_ones()).sum();
            if count == 0 {
                continue;
            }
            if count == 1 {
                let word = node_mask.iter().zip(fan.open()).position(|(m, o)| m & o != 0).unwrap_or(0);
                let k = word * 64 + (node_mask[word] & fan.open()[word]).trailing_zeros() as usize;
                let at = (ni, k, apex, to_world);
                if self.ray_walk::<P, ONE>(prims, rays, fan, out, ctx, at, ray_nodes, ray_mask, simd) {
                    return;
                }
                continue;
            }
            let node = &self.cw.nodes[ni as usize];
            let (los, his) = child_boxes(node, apex, to_world);
            // For a few rays, their own slab tests cull as well as the pyramid would.
            let culled = if count <= CULL_ABOVE { 0 } else { fan.pyramid.culls_rel8(&los, &his, simd) };
            let filled = nonzero_bytes(u64::from_le_bytes(node.child_meta));
            let hit = fan.meets8(&los, &his, filled & !culled, &node_mask[..w], &mut child_masks[..8 * w], ctx, simd);
            let at = (hit, &los, &his, |c: usize| Child::of(node, c));
            let stack = (&mut *nodes, &mut *masks, &mut *visits);
            if self.take_children::<P, ONE>(prims, rays, fan, out, ctx, at, toward, stack, child_masks, simd) {
                return;
            }
        }
    }

    /// The subtree of node `root` walked by ray `k` alone (the last open ray of its node's
    /// mask): one slab test of the ray against a node's eight child boxes per visit, no masks and
    /// no pyramid. The same box and triangle tests as the fan's, so the same answers. True once
    /// every ray of the fan is closed.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn ray_walk<P: Prims, const ONE: bool>(
        &self,
        prims: &P,
        rays: &LightRays,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        (root, k, apex, to_world): (u32, usize, Vec3A, f32),
        stack: &mut Vec<u32>,
        mask: &mut Vec<u64>,
        simd: Option<Avx2>,
    ) -> bool {
        let w = if ONE { 1 } else { fan.words() };
        let (word, bit) = (k / 64, 1u64 << (k % 64));
        mask.clear();
        mask.resize(w, 0);
        mask[word] = bit;
        stack.clear();
        stack.push(root);
        while let Some(ni) = stack.pop() {
            let node = &self.cw.nodes[ni as usize];
            let (los, his) = child_boxes(node, apex, to_world);
            let filled = nonzero_bytes(u64::from_le_bytes(node.child_meta));
            let mut hit = fan.ray_meets8(&los, &his, filled, k, ctx, simd);
            while hit != 0 {
                let c = hit.trailing_zeros() as usize;
                hit &= hit - 1;
                match Child::of(node, c) {
                    Child::None => {}
                    Child::Leaf(start, len) => {
                        self.test_leaf(prims, rays, fan, (start, len), &mask[..w], out, ctx, simd);
                        if fan.open()[word] & bit == 0 {
                            return fan.live() == 0;
                        }
                    }
                    Child::Node(n) => stack.push(n),
                }
            }
        }
        false
    }

    /// The triangles of the BVH leaf `(start, len)` (in the primitive indices) but the rays' own,
    /// tested against the fan's open rays of `mask`, read from the leaf-ordered copy.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn test_leaf<P: Prims>(
        &self,
        prims: &P,
        rays: &LightRays,
        fan: &mut Fan,
        (start, len): (u32, u32),
        mask: &[u64],
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        let LeafTris { tris, ids, lights } = &self.leaf_tris;
        let span = prims.span(start, len);
        for ((tri, &t), &light) in tris[span.clone()].iter().zip(&ids[span.clone()]).zip(&lights[span]) {
            if !rays.own_with(t, light) {
                fan.test_within(tri, t, rays, mask, out, ctx, simd);
            }
        }
    }

    /// The children `hit` of a visit (child `c` leading to `child_of(c)`, its box `los`/`his`
    /// relative to the apex, its rays in `child_masks`): a leaf's triangles are tested against its
    /// rays, inner nodes pushed nearest last, so that the nearest is visited first (with their masks
    /// on `visits` for a fan of one word, else on `nodes` and `masks`). True once every ray is
    /// closed.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn take_children<P: Prims, const ONE: bool>(
        &self,
        prims: &P,
        rays: &LightRays,
        fan: &mut Fan,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        (hit, los, his, child_of): (u8, &[[f32; 8]; 3], &[[f32; 8]; 3], impl Fn(usize) -> Child),
        toward: Vec3,
        (nodes, masks, visits): (&mut Vec<u32>, &mut Vec<u64>, &mut Vec<(u64, u32)>),
        child_masks: &[u64],
        simd: Option<Avx2>,
    ) -> bool {
        let w = if ONE { 1 } else { fan.words() };
        let mut pending = [(0f32, 0u32, 0usize); 8];
        let mut count = 0;
        let mut rest = hit;
        while rest != 0 {
            let child = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let mask = &child_masks[child * w..(child + 1) * w];
            match child_of(child) {
                Child::None => {}
                Child::Leaf(start, len) => {
                    self.test_leaf(prims, rays, fan, (start, len), mask, out, ctx, simd);
                    if fan.live() == 0 {
                        return true;
                    }
                }
                Child::Node(n) => {
                    let centre = Vec3::new(
                        los[0][child] + his[0][child],
                        los[1][child] + his[1][child],
                        los[2][child] + his[2][child],
                    );
                    pending[count] = (centre.dot(toward), n, child);
                    count += 1;
                }
            }
        }
        if count > 0 {
            // Nearest last, so it is visited first.
            // (Insertion, for at most eight.)
            for i in 1..count {
                let mut j = i;
                while j > 0 && pending[j - 1].0.total_cmp(&pending[j].0).is_lt() {
                    pending.swap(j - 1, j);
                    j -= 1;
                }
            }
            for &(_, n, slot) in &pending[..count] {
                if ONE {
                    visits.push((child_masks[slot], n));
                } else {
                    nodes.push(n);
                    for &m in &child_masks[slot * w..(slot + 1) * w] {
                        masks.push(m);
                    }
                }
            }
        }
        false
    }
}

/// The eight child boxes of `node` relative to `apex` (in the BVH's normalised units), in world
/// units, eight lanes per bound.
#[inline(always)]
fn child_boxes(node: &CwBvhNode, apex: Vec3A, to_world: f32) -> ([[f32; 8]; 3], [[f32; 8]; 3]) {
    let e = node.compute_extent();
    // The node's corner relative to the apex, in normalised units.
    let base = Vec3A::from(node.p) - apex;
    let (mut los, mut his) = ([[0f32; 8]; 3], [[0f32; 8]; 3]);
    let mins = [&node.child_min_x, &node.child_min_y, &node.child_min_z];
    let maxs = [&node.child_max_x, &node.child_max_y, &node.child_max_z];
    for k in 0..3 {
        for c in 0..8 {
            los[k][c] = (base[k] + e[k] * f32::from(mins[k][c])) * to_world;
            his[k][c] = (base[k] + e[k] * f32::from(maxs[k][c])) * to_world;
        }
    }
    (los, his)
}

/// The pyramid culls a node's child boxes only where more than this many of the fan's rays are
/// open in the node; fewer rays' slab tests are cheaper than the cull (the cut's entries are always
/// culled). Measured (callgrind of the query at 16 rays on conference-lit, huis-c,
/// cornell-dragon-100k and cornell-bunny, docs/results.md issue 21 session 25): 8 needed the fewest
/// instructions of 0, 4, 8 and 16.
const CULL_ABOVE: u32 = 8;

// A cut's entries are tested as the children of one node.
const _: () = assert!(CUT_MAX == 8);
