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

use super::query::SEGMENT_EPS;
use super::{LightRays, QueryCtx};
use crate::geometry::{Aabb, RayTest, Triangle};
use crate::scene::{Scene, TriId};

pub use super::pyramid::Pyramid;

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
        if self.tests.len() < n {
            self.tests.resize(n, RayTest::new(Vec3::ZERO, Vec3::X, 0.0, 1.0));
        }
        self.built.clear();
        self.built.resize(n.div_ceil(64), 0);
        self.live = 0;
    }

    /// Makes the rays `k` with `want(k)` the active ones.
    pub fn select(&mut self, want: impl Fn(usize) -> bool) {
        let n = self.all_kz.len();
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
                lanes[..m].copy_from_slice(from);
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
            let lanes = Lanes { x: &self.ax, y: &self.ay, z: &self.az, len: &self.al, sz: &self.asz, kz: &self.akz };
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

/// The inverse of a direction's component for the slab test, with a non-finite one (of a zero or
/// tiny component) replaced by `±f32::MAX`. A product with it is then never NaN, and the slab it gives
/// is the whole line where the box's slab holds the origin and empty (up to the segment's tiny
/// motion along that axis, which is far below the boxes' growth by the construction tolerance)
/// where it does not, as [`crate::geometry::Segment`]'s parallel case decides.
#[inline]
fn inverse(d: f32) -> f32 {
    let i = 1.0 / d;
    if i.is_finite() {
        i
    } else {
        f32::MAX.copysign(i)
    }
}

/// The per-ray values of [`Fan::set`] from the directions `[dx, dy, dz]`, eight rays at a time, as the
/// scalar loop computes them (the same IEEE operations in the same order, so the same bits): into
/// `[len, sz, ix, iy, iz]` and `kz`. Returns how many rays it did (a multiple of eight); the caller
/// does the rest.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
unsafe fn ray_lanes_avx(d: [&[f32]; 3], out: [&mut [f32]; 5], kz: &mut [u32]) -> usize {
    use std::arch::x86_64::*;
    let [dx, dy, dz] = d;
    let [len, sz, ix, iy, iz] = out;
    let n = [dx.len(), dy.len(), dz.len(), len.len(), sz.len(), ix.len(), iy.len(), iz.len(), kz.len()]
        .into_iter()
        .min()
        .unwrap_or(0)
        / LANES
        * LANES;
    let sign = _mm256_set1_ps(-0.0);
    let (inf, max) = (_mm256_set1_ps(f32::INFINITY), _mm256_set1_ps(f32::MAX));
    let one = _mm256_set1_ps(1.0);
    let inverse = |v: __m256| {
        let i = _mm256_div_ps(one, v);
        let finite = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, i), inf);
        _mm256_blendv_ps(_mm256_or_ps(max, _mm256_and_ps(sign, i)), i, finite)
    };
    let mut k = 0;
    while k < n {
        // SAFETY: k + LANES <= n <= every array's length.
        unsafe {
            let (x, y, z) = (
                _mm256_loadu_ps(dx.as_ptr().add(k)),
                _mm256_loadu_ps(dy.as_ptr().add(k)),
                _mm256_loadu_ps(dz.as_ptr().add(k)),
            );
            let dot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z));
            _mm256_storeu_ps(len.as_mut_ptr().add(k), _mm256_sqrt_ps(dot));
            _mm256_storeu_ps(ix.as_mut_ptr().add(k), inverse(x));
            _mm256_storeu_ps(iy.as_mut_ptr().add(k), inverse(y));
            _mm256_storeu_ps(iz.as_mut_ptr().add(k), inverse(z));
            let (ax, ay, az) = (_mm256_andnot_ps(sign, x), _mm256_andnot_ps(sign, y), _mm256_andnot_ps(sign, z));
            let c0 = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(ax, ay), _mm256_cmp_ps::<_CMP_GE_OQ>(ax, az));
            let c1 = _mm256_cmp_ps::<_CMP_GE_OQ>(ay, az);
            let dk = _mm256_blendv_ps(_mm256_blendv_ps(z, y, c1), x, c0);
            _mm256_storeu_ps(sz.as_mut_ptr().add(k), _mm256_div_ps(one, dk));
            let k12 = _mm256_blendv_ps(_mm256_set1_ps(2.0), one, c1);
            let kk = _mm256_cvttps_epi32(_mm256_blendv_ps(k12, _mm256_setzero_ps(), c0));
            _mm256_storeu_si256(kz.as_mut_ptr().add(k).cast(), kk);
        }
        k += LANES;
    }
    n
}

/// The active rays' inverse directions in lanes.
struct BoxLanes<'a> {
    ix: &'a [f32],
    iy: &'a [f32],
    iz: &'a [f32],
}

/// The bits of `within` (the word of lanes `base..base + 64`) whose segments (origin at the
/// fan's apex, parameter range `[SEGMENT_EPS, 1 - SEGMENT_EPS]`) meet the box `[lo, hi]` given
/// relative to the apex.
#[inline]
fn meets_box(lo: Vec3, hi: Vec3, lanes: &BoxLanes, base: usize, within: u64) -> u64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is available (checked above); the lane arrays are padded to whole blocks.
        return unsafe { meets_box_avx(lo, hi, lanes, base, within) };
    }
    let mut out = 0;
    let mut bits = within;
    while bits != 0 {
        let b = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let j = base + b;
        let inv = Vec3::new(lanes.ix[j], lanes.iy[j], lanes.iz[j]);
        let (a, c) = (lo * inv, hi * inv);
        let t0 = a.min(c).max_element().max(SEGMENT_EPS);
        let t1 = a.max(c).min_element().min(1.0 - SEGMENT_EPS);
        if t0 <= t1 {
            out |= 1 << b;
        }
    }
    out
}

/// [`meets_box`], eight lanes at a time (blocks of lanes with no bit in `within` are skipped).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
unsafe fn meets_box_avx(lo: Vec3, hi: Vec3, lanes: &BoxLanes, base: usize, within: u64) -> u64 {
    use std::arch::x86_64::*;
    let sp = |v: f32| _mm256_set1_ps(v);
    let (lx, ly, lz, hx, hy, hz) = (sp(lo.x), sp(lo.y), sp(lo.z), sp(hi.x), sp(hi.y), sp(hi.z));
    let (t_min, t_max) = (sp(SEGMENT_EPS), sp(1.0 - SEGMENT_EPS));
    let n = lanes.ix.len().min(lanes.iy.len()).min(lanes.iz.len());
    let mut out = 0u64;
    let mut block = 0;
    while block < 8 {
        let byte = (within >> (block * 8)) & 0xff;
        let j = base + block * LANES;
        if byte != 0 && j + LANES <= n {
            // SAFETY: j + LANES <= n <= every array's length.
            let (ix, iy, iz) = unsafe {
                (
                    _mm256_loadu_ps(lanes.ix.as_ptr().add(j)),
                    _mm256_loadu_ps(lanes.iy.as_ptr().add(j)),
                    _mm256_loadu_ps(lanes.iz.as_ptr().add(j)),
                )
            };
            let (ax, cx) = (_mm256_mul_ps(lx, ix), _mm256_mul_ps(hx, ix));
            let (ay, cy) = (_mm256_mul_ps(ly, iy), _mm256_mul_ps(hy, iy));
            let (az, cz) = (_mm256_mul_ps(lz, iz), _mm256_mul_ps(hz, iz));
            let t0 = _mm256_max_ps(
                _mm256_max_ps(_mm256_min_ps(ax, cx), _mm256_min_ps(ay, cy)),
                _mm256_max_ps(_mm256_min_ps(az, cz), t_min),
            );
            let t1 = _mm256_min_ps(
                _mm256_min_ps(_mm256_max_ps(ax, cx), _mm256_max_ps(ay, cy)),
                _mm256_min_ps(_mm256_max_ps(az, cz), t_max),
            );
            let m = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u64;
            out |= (m & byte) << (block * 8);
        }
        block += 1;
    }
    out
}

/// The active rays in lanes (see [`Fan`]).
struct Lanes<'a> {
    x: &'a [f32],
    y: &'a [f32],
    z: &'a [f32],
    len: &'a [f32],
    sz: &'a [f32],
    kz: &'a [u32],
}

/// Relative margin of the hit parameter's rounding: the watertight test's weighted mean of three
/// products is within a few `ε` of the largest one's magnitude.
const T_MARGIN: f32 = 1e-5;

/// Sets bit `j` of `maybe` unless lane `j` is a sure miss of the triangle with scaled edge normals
/// `s` (see [`Fan::test`]), or its hit parameter cannot fall in the segment's range (`span`: per
/// axis, the least and greatest vertex coordinate, taken along the lane's `kz`).
#[inline]
fn misses(s: &[Vec3; 3], span: &[(f32, f32); 3], lanes: &Lanes, maybe: &mut [u64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is available (checked above); the lane arrays are padded to whole blocks.
        unsafe { misses_avx(s, span, lanes, maybe) };
        return;
    }
    misses_scalar(s, span, lanes, maybe);
}

/// [`misses`], lane by lane.
fn misses_scalar(s: &[Vec3; 3], span: &[(f32, f32); 3], lanes: &Lanes, maybe: &mut [u64]) {
    maybe.fill(0);
    for j in 0..lanes.x.len().min(maybe.len() * 64) {
        let d = Vec3::new(lanes.x[j], lanes.y[j], lanes.z[j]);
        let l = lanes.len[j];
        let e = [s[0].dot(d), s[1].dot(d), s[2].dot(d)];
        let pos = e.iter().any(|&e| e > l);
        let neg = e.iter().any(|&e| e < -l);
        let outside = {
            let (lo, hi) = span[lanes.kz[j] as usize];
            let (z1, z2) = (lo * lanes.sz[j], hi * lanes.sz[j]);
            let (zlo, zhi) = (z1.min(z2), z1.max(z2));
            let m = T_MARGIN * zlo.abs().max(zhi.abs());
            zlo > 1.0 - SEGMENT_EPS + m || zhi < SEGMENT_EPS - m
        };
        if !(outside || pos && neg) {
            maybe[j / 64] |= 1 << (j % 64);
        }
    }
}

/// [`misses`], eight lanes at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
unsafe fn misses_avx(s: &[Vec3; 3], span: &[(f32, f32); 3], lanes: &Lanes, maybe: &mut [u64]) {
    use std::arch::x86_64::*;
    let n = lanes
        .x
        .len()
        .min(lanes.y.len())
        .min(lanes.z.len())
        .min(lanes.len.len())
        .min(lanes.sz.len())
        .min(lanes.kz.len())
        / LANES
        * LANES;
    let sp = |v: f32| _mm256_set1_ps(v);
    let (s0x, s0y, s0z) = (sp(s[0].x), sp(s[0].y), sp(s[0].z));
    let (s1x, s1y, s1z) = (sp(s[1].x), sp(s[1].y), sp(s[1].z));
    let (s2x, s2y, s2z) = (sp(s[2].x), sp(s[2].y), sp(s[2].z));
    let sign = sp(-0.0);
    let (lo, hi) = (span.map(|s| sp(s.0)), span.map(|s| sp(s.1)));
    let (one, two) = (_mm256_set1_epi32(1), _mm256_set1_epi32(2));
    let (t_min, t_max, t_margin) = (sp(SEGMENT_EPS), sp(1.0 - SEGMENT_EPS), sp(T_MARGIN));
    maybe.fill(0);
    let mut j = 0;
    while j < n && j / 64 < maybe.len() {
        // SAFETY: j + LANES <= n <= every array's length.
        let (x, y, z, l) = unsafe {
            (
                _mm256_loadu_ps(lanes.x.as_ptr().add(j)),
                _mm256_loadu_ps(lanes.y.as_ptr().add(j)),
                _mm256_loadu_ps(lanes.z.as_ptr().add(j)),
                _mm256_loadu_ps(lanes.len.as_ptr().add(j)),
            )
        };
        let nl = _mm256_xor_ps(l, sign);
        let dot =
            |sx, sy, sz| _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(sx, x), _mm256_mul_ps(sy, y)), _mm256_mul_ps(sz, z));
        let (e0, e1, e2) = (dot(s0x, s0y, s0z), dot(s1x, s1y, s1z), dot(s2x, s2y, s2z));
        let pos = _mm256_or_ps(
            _mm256_or_ps(_mm256_cmp_ps::<_CMP_GT_OQ>(e0, l), _mm256_cmp_ps::<_CMP_GT_OQ>(e1, l)),
            _mm256_cmp_ps::<_CMP_GT_OQ>(e2, l),
        );
        let neg = _mm256_or_ps(
            _mm256_or_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(e0, nl), _mm256_cmp_ps::<_CMP_LT_OQ>(e1, nl)),
            _mm256_cmp_ps::<_CMP_LT_OQ>(e2, nl),
        );
        let mut miss = _mm256_and_ps(pos, neg);
        {
            // SAFETY: as above.
            let (sz, kz) = unsafe {
                (_mm256_loadu_ps(lanes.sz.as_ptr().add(j)), _mm256_loadu_si256(lanes.kz.as_ptr().add(j).cast()))
            };
            // The span along each lane's own axis.
            let is1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kz, one));
            let is2 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(kz, two));
            let pick = |v: [__m256; 3]| _mm256_blendv_ps(_mm256_blendv_ps(v[0], v[1], is1), v[2], is2);
            let (lo, hi) = (pick(lo), pick(hi));
            let (z1, z2) = (_mm256_mul_ps(lo, sz), _mm256_mul_ps(hi, sz));
            let (zlo, zhi) = (_mm256_min_ps(z1, z2), _mm256_max_ps(z1, z2));
            let abs = |v| _mm256_andnot_ps(sign, v);
            let m = _mm256_mul_ps(t_margin, _mm256_max_ps(abs(zlo), abs(zhi)));
            let far = _mm256_cmp_ps::<_CMP_GT_OQ>(zlo, _mm256_add_ps(t_max, m));
            let near = _mm256_cmp_ps::<_CMP_LT_OQ>(zhi, _mm256_sub_ps(t_min, m));
            miss = _mm256_or_ps(miss, _mm256_or_ps(far, near));
        }
        let miss = _mm256_movemask_ps(miss) as u64;
        maybe[j / 64] |= (!miss & 0xff) << (j % 64);
        j += LANES;
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;

    /// The eight-lane ray values are the scalar loop's, bit for bit, on ordinary, tied, zero, signed
    /// zero, tiny and huge components.
    #[test]
    fn ray_lanes_match_the_scalar_loop() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let special = [0.0, -0.0, 1.0, -1.0, 1e-30, -1e-38, 3e38, -2.5, 0.1, 7.0, -7.0, 1e-45];
            let mut state = 11u64;
            let mut rnd = || {
                state = crate::render::sampler::mix64(state);
                special[(state % special.len() as u64) as usize] * if state & 1 << 40 != 0 { 1.0 } else { 3.3 }
            };
            let n = 4096;
            let (dx, dy, dz): (Vec<f32>, Vec<f32>, Vec<f32>) = (0..n).map(|_| (rnd(), rnd(), rnd())).collect();
            let mut out: [Vec<f32>; 5] = std::array::from_fn(|_| vec![0.0; n]);
            let mut kz = vec![0u32; n];
            let [len, sz, ix, iy, iz] = &mut out;
            // SAFETY: AVX2 is available (checked above).
            let done = unsafe { ray_lanes_avx([&dx, &dy, &dz], [len, sz, ix, iy, iz], &mut kz) };
            assert_eq!(done, n);
            for k in 0..n {
                let d = Vec3::new(dx[k], dy[k], dz[k]);
                let a = d.abs();
                let want_kz = if a.x >= a.y && a.x >= a.z {
                    0
                } else if a.y >= a.z {
                    1
                } else {
                    2
                };
                let want = [d.length(), 1.0 / d[want_kz], inverse(d.x), inverse(d.y), inverse(d.z)];
                for (w, (got, want)) in out.iter().map(|v| v[k]).zip(want).enumerate() {
                    assert_eq!(got.to_bits(), want.to_bits(), "ray {k} {d}: value {w}: {got} against {want}");
                }
                assert_eq!(kz[k], want_kz as u32, "ray {k} {d}");
            }
        }
    }
}
