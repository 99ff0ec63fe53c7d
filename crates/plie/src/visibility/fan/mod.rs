//! A fan of shadow rays: the `N` segments from one shaded point `x` to the samples `y_k` of one light,
//! tested against a candidate triangle all at once (issue 21; SPEC §5 asks each ray alone).
//!
//! The rays share their origin, so a triangle `(a, b, c)` (relative to `x`) gives three edge planes
//! through `x` with normals `b × c`, `c × a`, `a × b`. A ray with direction `d` passes inside the
//! triangle's cone when the three edge functions `n_i · d` have one sign; when one is clearly positive
//! and another clearly negative, it passes outside, and the watertight test (which evaluates the same
//! three functions, up to one common factor, in its sheared frame) must miss. "Clearly" means beyond a
//! margin of `EDGE_MARGIN |p| |q| |d|` for the edge `(p, q)`, which bounds the rounding of both
//! computations with a wide safety factor (see [`EDGE_MARGIN`]). Those misses are decided `N` lanes wide
//! without the watertight test; every other (triangle, ray) pair — inside, near an edge, or not
//! finite — gets the exact [`blocks`](super::blocks) predicate. So each answer is the watertight
//! test's, bit for bit, and the fast path only skips work.
//!
//! A second cull rejects a triangle for all rays at once: the pyramid from `x` over the light polygon
//! ([`Pyramid`]), grown by a margin, contains every segment; a triangle whose three vertices lie
//! beyond one of its planes meets none of them.

use glam::Vec3;

use super::{LightRays, QueryCtx};
use crate::geometry::{Aabb, RayTest, Triangle};
use crate::scene::{Scene, TriId};

pub use super::pyramid::Pyramid;

mod lanes;

#[cfg(target_arch = "x86_64")]
use lanes::ray_lanes_avx;
use lanes::{inverse, meets_box, misses, BoxLanes, Lanes};

/// Relative margin of the edge functions. The watertight test's sheared edge function of an edge
/// `(p, q)` differs from the real `det(p, q, d) / d_kz` by at most about `32 ε |p| |q|` (the shear has
/// factors of magnitude at most 1), and ours, a cross product and a dot product, from
/// `det(p, q, d)` by at most about `10 ε |p| |q| |d|`; since `|d_kz| <= |d|`, a computed value beyond
/// `42 ε |p| |q| |d|` has the sign of the real one, and so has the watertight test's. We take six times
/// that.
pub const EDGE_MARGIN: f32 = 256.0 * f32::EPSILON;

/// Lanes of the fast test.
const LANES: usize = 8;

/// Per-thread scratch of a fan: the directions `d_k = y_k - x`, their lengths, the lazily built
/// exact ray tests, and the *active* rays (those the current candidates are tested against) copied
/// into lanes.
#[derive(Clone, Debug, Default)]
pub struct Fan {
    origin: Vec3,
    /// Per ray, in the order of the active lanes' arrays (`ax` ... `aiz`): its direction `d = y - x`,
    /// its length, the watertight test's `1 / d[kz]` and the inverse direction for box tests
    /// ([`inverse`]).
    all: [Vec<f32>; 8],
    /// Per ray: the watertight test's axis `kz` (the largest component of `d`).
    all_kz: Vec<u32>,
    /// Rays in the fan (the arrays `all` and `all_kz` are padded with zeros to whole lanes).
    n: usize,
    /// True while every ray is active ([`Fan::select_all`]): the edge test's lanes are then `all`'s
    /// own arrays.
    whole: bool,
    /// The exact tests, built on first use: valid where bit `k` of `built` is set.
    tests: Vec<RayTest>,
    built: Vec<u64>,
    /// Active rays: their indices, and their directions and lengths in lanes (padded with zeros to a
    /// multiple of [`LANES`]).
    idx: Vec<u32>,
    ax: Vec<f32>,
    ay: Vec<f32>,
    az: Vec<f32>,
    al: Vec<f32>,
    /// Per active lane: the watertight test's `1 / d[kz]`, and its axis `kz`.
    asz: Vec<f32>,
    akz: Vec<u32>,
    /// Per active lane: the inverse direction for box tests ([`inverse`]).
    aix: Vec<f32>,
    aiy: Vec<f32>,
    aiz: Vec<f32>,
    /// The lane masks of a walk down a box hierarchy ([`Fan::narrow`]): [`WALK_LEVELS`] masks of
    /// `open.len()` words each.
    masks: Vec<u64>,
    /// Bit `j` of word `j / 64`: active lane `j` is still open (not found occluded).
    open: Vec<u64>,
    /// Bit per active lane: the fast test could not prove a miss for the current triangle.
    maybe: Vec<u64>,
    /// Active rays still open.
    live: usize,
    /// The pyramid of the current light.
    pub pyramid: Pyramid,
}

impl Fan {
    /// Starts the fan of `rays` (directions computed exactly as [`super::ShadowRay::new`] does).
    pub fn set(&mut self, rays: &LightRays) {
        let x = rays.origin;
        let n = rays.targets.len();
        self.origin = x;
        for v in &mut self.all {
            v.resize(n, 0.0);
        }
        self.all_kz.resize(n, 0);
        let [dx, dy, dz, len, sz, ix, iy, iz] = &mut self.all;
        for (k, y) in rays.targets.iter().enumerate() {
            let d = *y - x;
            (dx[k], dy[k], dz[k]) = (d.x, d.y, d.z);
        }
        let kzs = &mut self.all_kz[..n];
        let mut done = 0;
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 is available (checked above).
            done = unsafe {
                ray_lanes_avx(
                    [&dx[..n], &dy[..n], &dz[..n]],
                    [&mut len[..n], &mut sz[..n], &mut ix[..n], &mut iy[..n], &mut iz[..n]],
                    kzs,
                )
            };
        }
        for k in done..n {
            let d = Vec3::new(dx[k], dy[k], dz[k]);
            len[k] = d.length();
            (ix[k], iy[k], iz[k]) = (inverse(d.x), inverse(d.y), inverse(d.z));
            // As `RayTest::new` chooses it.
            let a = d.abs();
            let kz = if a.x >= a.y && a.x >= a.z {
                0
            } else if a.y >= a.z {
                1
            } else {
                2
            };
            kzs[k] = kz as u32;
            sz[k] = 1.0 / d[kz];
        }
        // The padding lanes: zero (a zero direction meets no box and no triangle's cone).
        let padded = n.div_ceil(LANES) * LANES;
        for v in &mut self.all {
            v.resize(padded, 0.0);
        }
        self.all_kz.resize(padded, 0);
        self.n = n;
        self.whole = false;
        if self.tests.len() < n {
            self.tests.resize(n, RayTest::new(Vec3::ZERO, Vec3::X, 0.0, 1.0));
        }
        self.built.clear();
        self.built.resize(n.div_ceil(64), 0);
        self.live = 0;
    }

    /// Makes every ray active, copying only the lanes of box tests (the edge test reads `all`).
    pub fn select_all(&mut self) {
        for (lanes, from) in [&mut self.aix, &mut self.aiy, &mut self.aiz].into_iter().zip(&self.all[5..]) {
            lanes.clear();
            lanes.extend_from_slice(from);
        }
        self.idx.clear();
        self.idx.extend(0..self.n as u32);
        self.whole = true;
        self.reopen();
    }

    /// Makes the rays `k` with `want(k)` the active ones.
    pub fn select(&mut self, want: impl Fn(usize) -> bool) {
        let n = self.n;
        self.idx.clear();
        self.idx.extend((0..n as u32).filter(|&k| want(k as usize)));
        let m = self.idx.len();
        let padded = m.div_ceil(LANES) * LANES;
        let active = [
            &mut self.ax,
            &mut self.ay,
            &mut self.az,
            &mut self.al,
            &mut self.asz,
            &mut self.aix,
            &mut self.aiy,
            &mut self.aiz,
        ];
        for (lanes, from) in active.into_iter().zip(&self.all) {
            lanes.resize(padded, 0.0);
            if m == n {
                lanes[..m].copy_from_slice(&from[..m]);
            } else {
                for (l, &k) in lanes.iter_mut().zip(&self.idx) {
                    *l = from[k as usize];
                }
            }
            // The padding lanes: zero (a zero direction meets no box and no triangle's cone).
            lanes[m..].fill(0.0);
        }
        self.akz.resize(padded, 0);
        for (l, &k) in self.akz.iter_mut().zip(&self.idx) {
            *l = self.all_kz[k as usize];
        }
        self.akz[m..].fill(0);
        self.whole = false;
        self.reopen();
    }

    /// Opens every active ray and clears the masks.
    fn reopen(&mut self) {
        let m = self.idx.len();
        let words = m.div_ceil(64);
        self.open.clear();
        self.open.resize(words, u64::MAX);
        if m % 64 != 0 {
            self.open[words - 1] = (1u64 << (m % 64)) - 1;
        }
        self.maybe.clear();
        self.maybe.resize(words, 0);
        self.masks.clear();
        self.masks.resize(words * WALK_LEVELS, 0);
        self.live = m;
    }

    /// One step down a box hierarchy walked by all active rays at once: mask `level` becomes the
    /// open lanes of mask `level - 1` (of all open lanes, for level 0) whose segments meet the box
    /// `b`. Returns whether any does. The test is the slab test of [`crate::geometry::Segment::clip`],
    /// eight lanes at a time; it never drops a lane whose segment meets `b`. Counts a box test per
    /// lane tested.
    #[inline]
    pub fn narrow(&mut self, b: &Aabb, level: usize, ctx: &mut QueryCtx) -> bool {
        let w = self.open.len();
        let (above, rest) = self.masks.split_at_mut(level * w);
        let from = if level == 0 { &self.open[..] } else { &above[(level - 1) * w..] };
        let to = &mut rest[..w];
        let lanes = BoxLanes { ix: &self.aix, iy: &self.aiy, iz: &self.aiz };
        let (lo, hi) = (b.min - self.origin, b.max - self.origin);
        let mut any = 0;
        for i in 0..w {
            let f = from[i] & self.open[i];
            ctx.stats.box_tests += u64::from(f.count_ones());
            to[i] = if f == 0 { 0 } else { meets_box(lo, hi, &lanes, i * 64, f) };
            any |= to[i];
        }
        any != 0
    }

    /// Mask `level` becomes all open lanes (for a hierarchy whose top box is not worth testing).
    #[inline]
    pub fn narrow_to_open(&mut self, level: usize) {
        let w = self.open.len();
        self.masks[level * w..(level + 1) * w].copy_from_slice(&self.open);
    }

    /// The watertight test of triangle `t` for each open lane of mask `level`: each ray it blocks
    /// gets `out[k]` set and is closed. The caller has excluded the rays' own triangles.
    #[inline]
    pub fn test_level(
        &mut self,
        scene: &Scene,
        rays: &LightRays,
        t: TriId,
        level: usize,
        out: &mut [bool],
        ctx: &mut QueryCtx,
    ) {
        let w = self.open.len();
        let tri = &scene.triangles[t.idx()];
        for i in 0..w {
            let bits = self.masks[level * w + i] & self.open[i];
            self.exact(tri, i, bits, rays, out, ctx);
        }
    }

    /// The watertight test of `tri` for the active lanes `bits` of word `w`: each ray it blocks gets
    /// `out[k]` set and is closed.
    #[inline]
    fn exact(
        &mut self,
        tri: &Triangle,
        w: usize,
        mut bits: u64,
        rays: &LightRays,
        out: &mut [bool],
        ctx: &mut QueryCtx,
    ) {
        while bits != 0 {
            let j = w * 64 + bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let k = self.idx[j] as usize;
            if self.built[k / 64] & (1 << (k % 64)) == 0 {
                self.tests[k] = rays.ray(k).test;
                self.built[k / 64] |= 1 << (k % 64);
            }
            ctx.stats.triangle_tests += 1;
            if self.tests[k].hit(tri).is_some() {
                self.open[w] &= !(1u64 << (j % 64));
                self.live -= 1;
                out[k] = true;
            }
        }
    }

    /// Active rays not yet found occluded.
    #[inline]
    pub fn live(&self) -> usize {
        self.live
    }

    /// Tests triangle `t` against the open active rays: each ray `k` it blocks gets `out[k]` set and
    /// is closed. Counts a lane test per open ray, and a triangle test per watertight test. The caller has excluded the rays' own
    /// triangles (the origin's and the light's).
    #[inline]
    pub fn test(&mut self, scene: &Scene, rays: &LightRays, t: TriId, out: &mut [bool], ctx: &mut QueryCtx) {
        let tri = &scene.triangles[t.idx()];
        let x = self.origin;
        let (a, b, c) = (tri.v[0] - x, tri.v[1] - x, tri.v[2] - x);
        // Edge normals scaled by the inverse of their margins: a lane is a sure miss where one scaled
        // edge function exceeds `|d|` and another is below `-|d|`. (The L1 norm bounds the
        // Euclidean one, so the margins only grow; the scaling's own rounding is far inside them.)
        let l1 = |v: Vec3| v.abs().element_sum();
        let (la, lb, lc) = (l1(a), l1(b), l1(c));
        let s = [
            b.cross(c) * (EDGE_MARGIN * lb * lc).recip(),
            c.cross(a) * (EDGE_MARGIN * lc * la).recip(),
            a.cross(b) * (EDGE_MARGIN * la * lb).recip(),
        ];
        ctx.stats.lane_tests += self.live as u64;
        // The watertight test's hit parameter is a weighted mean of the vertices' `p[kz] / d[kz]`
        // (computed as it computes them); lanes where all of them lie outside the segment's range
        // (beyond a margin for the mean's rounding) miss. Per axis, the least and greatest vertex
        // coordinate.
        let span = [0, 1, 2].map(|k| (a[k].min(b[k]).min(c[k]), a[k].max(b[k]).max(c[k])));
        if s.iter().all(|v| v.is_finite()) {
            let lanes = if self.whole {
                let [x, y, z, len, sz, ..] = &self.all;
                Lanes { x, y, z, len, sz, kz: &self.all_kz }
            } else {
                Lanes { x: &self.ax, y: &self.ay, z: &self.az, len: &self.al, sz: &self.asz, kz: &self.akz }
            };
            misses(&s, &span, &lanes, &mut self.maybe);
        } else {
            self.maybe.fill(u64::MAX);
        }
        for w in 0..self.open.len() {
            let bits = self.maybe[w] & self.open[w];
            self.exact(tri, w, bits, rays, out, ctx);
        }
    }
}

/// Masks of a walk down a list's box hierarchy ([`Fan::narrow`]): one per level, and the triangles'.
const WALK_LEVELS: usize = super::list_boxes::MAX_LEVELS + 1;

/// Per-thread scratch of the per-light queries ([`super::Visibility::occluded_light`]).
#[derive(Clone, Debug, Default)]
pub struct LightScratch {
    /// The fan of the current (point, light).
    pub fan: Fan,
    /// Per ray: how it would be answered if no candidate hits it (an index for the mode's own use).
    pub path: Vec<u8>,
    /// Per ray: the index of its blocker list in `lists` (`u32::MAX`: none).
    pub list: Vec<u32>,
    /// The distinct blocker lists of the current (point, light): the mode's own keys.
    pub lists: Vec<u32>,
    /// The light's footprints on the leaf's faces.
    pub feet: Vec<super::footprint::FaceFootprint>,
    /// The `(start, len)` of the face-grid cell lists gathered in `lists` (to keep each list once).
    pub ranges: Vec<(u32, u32)>,
}
