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
//! The watertight test itself runs eight rays wide where two or more rays of a block of eight need
//! it ([`lanes::exact_avx`]): the same IEEE operations in the same order as
//! [`RayTest::hit`](crate::geometry::RayTest::hit), so the same answers; a lane where an edge function
//! comes out exactly zero (which the scalar test recomputes in f64) is left to the scalar test. With
//! at most [`DIRECT_MAX`] rays to test, the edge test is skipped: it would cost more than it saves.
//!
//! A second cull rejects a triangle for all rays at once: the pyramid from `x` over the light polygon
//! ([`Pyramid`]), grown by a margin, contains every segment; a triangle whose three vertices lie
//! beyond one of its planes meets none of them. A triangle that more than [`DIRECT_MAX`] open rays
//! reach is also tested against the whole light before the lanes: if its own plane has `x` and
//! every corner of the light on one side ([`Pyramid::beside`]), or every corner lies clearly
//! outside its cone from `x` by the same edge functions and margins as the lanes' test
//! ([`Pyramid::outside_cone`]: the functions are linear, so a bound at the corners holds at every
//! sample), every ray misses without a lane computed (measured, docs/results.md issue 21 session 29:
//! 7% fewer instructions of the query at 64 rays; for fewer rays they cost more than they save).

use glam::Vec3;

use super::simd::Avx2;
use super::verdicts::Verdicts;
use super::{LightRays, QueryCtx};
use crate::geometry::{RayTest, Triangle};
use crate::scene::{Scene, TriId};

pub use super::pyramid::Pyramid;
pub(crate) use lanes::nonzero_bytes;
use lanes::nonzero_words;

mod lanes;

#[cfg(target_arch = "x86_64")]
use lanes::{exact_avx, vertices_rel, Shear};
#[cfg(target_arch = "x86_64")]
use lanes::{fan_lanes_avx, inverse_lanes_avx, shear_lanes_avx};
use lanes::{inverse, meets_boxes, misses, ray_meets_boxes, shear_lanes, BoxLanes, Lanes};

/// Relative margin of the edge functions. The watertight test's sheared edge function of an edge
/// `(p, q)` differs from the real `det(p, q, d) / d_kz` by at most about `32 ε |p| |q|` (the shear has
/// factors of magnitude at most 1), and ours, a cross product and a dot product, from
/// `det(p, q, d)` by at most about `10 ε |p| |q| |d|`; since `|d_kz| <= |d|`, a computed value beyond
/// `42 ε |p| |q| |d|` has the sign of the real one, and so has the watertight test's. We take six times
/// that.
pub const EDGE_MARGIN: f32 = 256.0 * f32::EPSILON;

/// Lanes of the fast test.
const LANES: usize = 8;

/// Per-thread scratch of a fan: the directions `d_k = y_k - x` in lanes, their lengths, the lazily
/// built exact ray tests, and which rays are still open.
#[derive(Clone, Debug, Default)]
pub struct Fan {
    origin: Vec3,
    /// Per ray, in lanes: its direction `d = y - x`, its length, the watertight test's `1 / d[kz]`
    /// and the inverse direction for box tests ([`inverse`]); padded with zeros to whole lanes (a
    /// zero direction meets no box and no triangle's cone).
    all: [Vec<f32>; 8],
    /// Per ray: the watertight test's axis `kz` (the largest component of `d`).
    all_kz: Vec<u32>,
    /// The exact tests, built on first use: valid where bit `k` of `built` is set.
    tests: Vec<RayTest>,
    /// Per ray, the rest of the watertight test's shear ([`RayTest::shear`]): `sx`, `sy` and the
    /// axes `kx`, `ky` (`sz` and `kz` are in `all` and `all_kz`), padded to whole lanes.
    shear_s: [Vec<f32>; 2],
    shear_k: [Vec<u32>; 2],
    built: Vec<u64>,
    /// Whether the inverse directions (the last three of `all`) and the shears are computed for
    /// the current rays: where the CPU has AVX2, [`Fan::set`] leaves them to the first box test
    /// ([`Fan::ready_boxes`]) and the first watertight test, which many fans never run (a fan
    /// tested against a shaft's or a list's triangles tests no box; most triangles a fan meets are
    /// decided without the watertight test).
    inverse_ready: bool,
    shears_ready: bool,
    /// Bit `k` of word `k / 64`: ray `k` is still open (not found occluded).
    open: Vec<u64>,
    /// Bit per ray: the fast test could not prove a miss for the current triangle.
    maybe: Vec<u64>,
    /// Rays still open.
    live: usize,
    /// The first [`BLOCKERS`] triangles that closed a ray since [`Fan::set`] (`u32::MAX` past the
    /// last).
    blockers: [u32; BLOCKERS],
    /// The pyramid of the current light.
    pub pyramid: Pyramid,
}

impl Fan {
    /// Starts the fan of `rays` (directions computed exactly as [`super::ShadowRay::new`] does).
    pub fn set(&mut self, rays: &LightRays) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = Avx2::detect() {
            // SAFETY: AVX2 is available (the proof).
            return unsafe { self.set_avx(rays, simd) };
        }
        self.set_in(rays, None)
    }

    /// [`Fan::set`] compiled for AVX2 as a whole, so that its lane kernels inline into it.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    unsafe fn set_avx(&mut self, rays: &LightRays, simd: Avx2) {
        self.set_in(rays, Some(simd))
    }

    /// The body of [`Fan::set`].
    #[inline(always)]
    fn set_in(&mut self, rays: &LightRays, simd: Option<Avx2>) {
        let x = rays.origin;
        let n = rays.targets.len();
        self.origin = x;
        let padded = n.div_ceil(LANES) * LANES;
        let words = n.div_ceil(64);
        // A render asks the same number of samples every time: the arrays keep their length.
        if self.tests.len() != n || self.all_kz.len() != padded {
            for v in self.all.iter_mut().chain(&mut self.shear_s) {
                v.resize(padded, 0.0);
            }
            for v in std::iter::once(&mut self.all_kz).chain(&mut self.shear_k) {
                v.resize(padded, 0);
            }
            self.tests.resize(n, RayTest::new(Vec3::ZERO, Vec3::X, 0.0, 1.0));
            self.built.resize(words, 0);
            self.open.resize(words, 0);
            self.maybe.resize(words, 0);
        }
        // Blocks of eight rays in one pass where the CPU has AVX2 (the last one padded: the
        // arrays hold whole blocks); without it, ray by ray, as those lanes compute them.
        let mut done = 0;
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        #[cfg(target_arch = "x86_64")]
        if simd.is_some() {
            // A fan of at most `DIRECT_MAX` rays gives every triangle it meets to the watertight
            // test, so it needs its shears anyway: all at once costs less (measured,
            // docs/results.md issue 21 session 29); a larger one leaves the inverse directions
            // and the shears to first use.
            let (all, kz, s, k) = (&mut self.all, &mut self.all_kz, &mut self.shear_s, &mut self.shear_k);
            // SAFETY: AVX2 is available (the proof).
            done = unsafe {
                if n <= DIRECT_MAX as usize {
                    fan_lanes_avx::<true>(rays.targets, x, all, kz, s, k)
                } else {
                    fan_lanes_avx::<false>(rays.targets, x, all, kz, s, k)
                }
            };
        }
        if done < n {
            let [dx, dy, dz, len, sz, ix, iy, iz] = &mut self.all;
            let kzs = &mut self.all_kz;
            for k in done..n {
                let d = rays.targets[k] - x;
                (dx[k], dy[k], dz[k]) = (d.x, d.y, d.z);
                len[k] = d.length();
                (ix[k], iy[k], iz[k]) = (inverse(d.x), inverse(d.y), inverse(d.z));
                let kz = RayTest::major_axis(d);
                kzs[k] = kz as u32;
                sz[k] = 1.0 / d[kz];
            }
            let [dx, dy, dz, _, sz, ..] = &self.all;
            let [sx, sy] = &mut self.shear_s;
            let [kx, ky] = &mut self.shear_k;
            let d = [&dx[done..n], &dy[done..n], &dz[done..n]];
            shear_lanes(
                d,
                &sz[done..n],
                &self.all_kz[done..n],
                [&mut sx[done..n], &mut sy[done..n]],
                [&mut kx[done..n], &mut ky[done..n]],
            );
        }
        // The padding lanes: zero (a zero direction meets no box and no triangle's cone). (Those
        // of the inverse directions and shears computed on first use hold what the zero direction
        // gives them; no test reads a padding lane but under a mask of the fan's rays.)
        if padded > n {
            for v in self.all.iter_mut().chain(&mut self.shear_s) {
                v[n..].fill(0.0);
            }
            for v in std::iter::once(&mut self.all_kz).chain(&mut self.shear_k) {
                v[n..].fill(0);
            }
        }
        // Every ray open. (One word, the usual case, without a call to `memset`.)
        if words == 1 {
            (self.built[0], self.open[0], self.maybe[0]) = (0, u64::MAX, 0);
        } else {
            self.built.fill(0);
            self.open.fill(u64::MAX);
            self.maybe.fill(0);
        }
        if n % 64 != 0 {
            self.open[words - 1] = (1u64 << (n % 64)) - 1;
        }
        self.live = n;
        self.blockers = [u32::MAX; BLOCKERS];
        // Without AVX2 the loop above computed everything.
        let ready = simd.is_none() || n <= DIRECT_MAX as usize;
        (self.inverse_ready, self.shears_ready) = (ready, ready);
    }

    /// Computes the inverse directions of the current rays if [`Fan::set`] left them: a walk calls
    /// this before its first box test ([`Fan::meets8`], [`Fan::ray_meets8`]).
    #[inline(always)]
    pub(crate) fn ready_boxes(&mut self, simd: Option<Avx2>) {
        if !self.inverse_ready {
            self.make_inverse(simd);
        }
    }

    /// The body of [`Fan::ready_boxes`] (left by [`Fan::set`] only where the CPU has AVX2).
    fn make_inverse(&mut self, simd: Option<Avx2>) {
        #[cfg(target_arch = "x86_64")]
        if simd.is_some() {
            // SAFETY: AVX2 is available (the proof).
            unsafe { inverse_lanes_avx(&mut self.all) };
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        self.inverse_ready = true;
        // A fan of many rays: boxes outside the pyramid's bounding box are culled too.
        self.pyramid.bound();
    }

    /// Computes the shears of the current rays if [`Fan::set`] left them (before a watertight
    /// test).
    #[inline(always)]
    fn ready_shears(&mut self, simd: Option<Avx2>) {
        if !self.shears_ready {
            self.make_shears(simd);
        }
    }

    /// The body of [`Fan::ready_shears`].
    fn make_shears(&mut self, simd: Option<Avx2>) {
        #[cfg(target_arch = "x86_64")]
        if simd.is_some() {
            // SAFETY: AVX2 is available (the proof).
            unsafe { shear_lanes_avx(&self.all, &self.all_kz, &mut self.shear_s, &mut self.shear_k) };
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        self.shears_ready = true;
    }

    /// The first triangles (up to [`BLOCKERS`]) that closed a ray since [`Fan::set`], `u32::MAX`
    /// past the last.
    #[inline]
    pub fn blockers(&self) -> [u32; BLOCKERS] {
        self.blockers
    }

    /// Notes that `t` closed a ray.
    #[inline(always)]
    fn note_blocker(&mut self, t: TriId) {
        if let Some(b) = self.blockers.iter_mut().find(|b| **b == u32::MAX) {
            *b = t.0;
        }
    }

    /// Builds the exact tests of the rays `bits` of word `w` that are not built yet.
    #[inline]
    fn build(&mut self, w: usize, bits: u64, rays: &LightRays) {
        let mut todo = bits & !self.built[w];
        self.built[w] |= todo;
        while todo != 0 {
            let k = w * 64 + todo.trailing_zeros() as usize;
            todo &= todo - 1;
            self.tests[k] = rays.ray(k).test;
            debug_assert_eq!(
                self.tests[k].shear(),
                (
                    [self.shear_s[0][k], self.shear_s[1][k], self.all[4][k]],
                    [self.shear_k[0][k], self.shear_k[1][k], self.all_kz[k]]
                )
            );
        }
    }

    /// The watertight test of `tri` for the rays `bits` of word `w`: each ray it blocks gets
    /// `out[k]` set and is closed. Blocks of eight rays with two or more to test take the
    /// lane-wide copy of the test ([`lanes::exact_avx`]), which answers as it does.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn exact(
        &mut self,
        tri: &Triangle,
        w: usize,
        bits: u64,
        rays: &LightRays,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        if bits == 0 {
            return;
        }
        self.ready_shears(simd);
        ctx.stats.triangle_tests += u64::from(bits.count_ones());
        let mut one_by_one = bits;
        let mut hits = 0u64;
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        #[cfg(target_arch = "x86_64")]
        if simd.is_some() {
            // SAFETY: AVX2 is available (the proof).
            let v = unsafe { vertices_rel(tri, self.origin) };
            let [sx, sy] = &self.shear_s;
            let [kx, ky] = &self.shear_k;
            let shear = Shear { s: [sx, sy, &self.all[4]], k: [kx, ky, &self.all_kz] };
            one_by_one = 0;
            // The blocks of eight rays with a ray to test.
            let mut rest = bits;
            while rest != 0 {
                let at = rest.trailing_zeros() as usize / LANES * LANES;
                let byte = rest >> at & 0xff;
                rest &= !(0xff << at);
                // SAFETY: AVX2 is available (the proof); the shear lanes are padded to whole
                // blocks.
                let (hit, scalar) = unsafe { exact_avx(v, &shear, w * 64 + at) };
                hits |= (u64::from(hit) & byte) << at;
                one_by_one |= (u64::from(scalar) & byte) << at;
            }
        }
        if one_by_one != 0 {
            self.build(w, one_by_one, rays);
        }
        while one_by_one != 0 {
            let i = one_by_one.trailing_zeros() as usize;
            one_by_one &= one_by_one - 1;
            if self.tests[w * 64 + i].hit(tri).is_some() {
                hits |= 1 << i;
            }
        }
        self.open[w] &= !hits;
        self.live -= hits.count_ones() as usize;
        while hits != 0 {
            let i = hits.trailing_zeros() as usize;
            hits &= hits - 1;
            out[w * 64 + i] = true;
        }
    }

    /// Words of a mask over the rays (64 rays per word).
    #[inline]
    pub fn words(&self) -> usize {
        self.open.len()
    }

    /// The open rays, one bit each.
    #[inline]
    pub fn open(&self) -> &[u64] {
        &self.open
    }

    /// The fan's apex `x`.
    #[inline]
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// For each box `c` of eight with bit `c` of `alive` set, given relative to the apex as lanes
    /// (`lo[axis][c]`, `hi[axis][c]`): `to[c * w..(c + 1) * w]` (`w` = [`Fan::words`]) becomes the
    /// open rays of `within` whose segments meet it, by the slab test (eight rays at a time, or one
    /// ray against the eight boxes where that is cheaper; it never drops a ray whose segment meets
    /// the box). Returns the boxes some ray meets, as bits. Counts a
    /// box test per ray and box tested.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn meets8(
        &self,
        lo: &[[f32; 8]; 3],
        hi: &[[f32; 8]; 3],
        alive: u8,
        within: &[u64],
        to: &mut [u64],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) -> u8 {
        let [.., ix, iy, iz] = &self.all;
        let lanes = BoxLanes { ix, iy, iz };
        // The caller's slices say how many words (so a caller that knows it lets the compiler know).
        let w = within.len();
        debug_assert_eq!(w, self.open.len());
        debug_assert!(self.inverse_ready);
        let mut hit = 0u8;
        let mut out = [0u64; 8];
        for i in 0..w {
            let f = within[i] & self.open[i];
            if f == 0 {
                out = [0; 8];
            } else {
                ctx.stats.box_tests += u64::from(f.count_ones() * alive.count_ones());
                meets_boxes(lo, hi, alive, &lanes, i * 64, f, &mut out, simd);
            }
            if w == 1 {
                to[..8].copy_from_slice(&out);
            } else {
                for (c, &o) in out.iter().enumerate() {
                    to[c * w + i] = o;
                }
            }
            hit |= nonzero_words(&out, simd);
        }
        hit
    }

    /// Of the eight boxes `c` with bit `c` of `alive` set, given relative to the apex as lanes, those
    /// that the segment of ray `k` meets, as bits: [`Fan::meets8`]'s test for one ray. Counts a box
    /// test per box tested.
    #[inline(always)]
    pub fn ray_meets8(
        &self,
        lo: &[[f32; 8]; 3],
        hi: &[[f32; 8]; 3],
        alive: u8,
        k: usize,
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) -> u8 {
        debug_assert!(self.inverse_ready);
        let [.., ix, iy, iz] = &self.all;
        ctx.stats.box_tests += u64::from(alive.count_ones());
        ray_meets_boxes(lo, hi, alive, &BoxLanes { ix, iy, iz }, k, simd)
    }

    /// [`Fan::test`] of triangle `t`, given as `tri` (the scene's or a copy of it), for the open
    /// lanes of `within` only: up to [`DIRECT_MAX`] lanes go straight to the watertight test, more
    /// first through the eight-lane edge test.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn test_within(
        &mut self,
        tri: &Triangle,
        t: TriId,
        rays: &LightRays,
        within: &[u64],
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        self.test_masked(tri, t, rays, Some(within), out, ctx, simd);
    }

    /// Rays not yet found occluded.
    #[inline]
    pub fn live(&self) -> usize {
        self.live
    }

    /// Tests triangle `t` against the open rays: each ray `k` it blocks gets `out[k]` set and
    /// is closed. Up to [`DIRECT_MAX`] open rays go straight to the watertight test. Counts a lane
    /// test per open ray through the edge test, and a triangle test per ray given the watertight
    /// test. The caller has excluded the rays' own triangles (the origin's and the light's). With
    /// `simd` (the caller's proof of AVX2, [`Avx2::detect`]) the lane kernels run; without, the
    /// scalar tests, which answer alike.
    #[inline]
    pub fn test(
        &mut self,
        scene: &Scene,
        rays: &LightRays,
        t: TriId,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        self.test_masked(&scene.triangles[t.idx()], t, rays, None, out, ctx, simd);
    }

    /// [`Fan::test`], for the open lanes of `within` only when given: up to [`DIRECT_MAX`] of them
    /// go straight to the watertight test, more first through the edge test.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn test_masked(
        &mut self,
        tri: &Triangle,
        t: TriId,
        rays: &LightRays,
        within: Option<&[u64]>,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        let mask = |w: usize| within.map_or(u64::MAX, |m| m[w]);
        // The words of the mask (from `within` where given, so a caller that knows it lets the
        // compiler know).
        let words = within.map_or(self.open.len(), |m| m.len());
        debug_assert_eq!(words, self.open.len());
        let count = match within {
            None => self.live as u32,
            Some(_) => (0..words).map(|w| (self.open[w] & mask(w)).count_ones()).sum(),
        };
        let live = self.live;
        if count <= DIRECT_MAX {
            for w in 0..words {
                let bits = self.open[w] & mask(w);
                self.exact(tri, w, bits, rays, out, ctx, simd);
            }
        } else {
            let x = self.origin;
            let (a, b, c) = (tri.v[0] - x, tri.v[1] - x, tri.v[2] - x);
            // (Counted as the lanes' test, which the whole light's tests below stand in for.)
            ctx.stats.lane_tests += self.live as u64;
            // A triangle whose plane has the apex and the whole light on one side meets no ray.
            if self.pyramid.beside(a, b, c) {
                return;
            }
            let s = edge_normals(a, b, c);
            let finite = s.iter().all(|v| v.is_finite());
            // Every sample outside the triangle's cone: all sure misses at once.
            if finite && self.pyramid.outside_cone(&s) {
                return;
            }
            // The watertight test's hit parameter is a weighted mean of the vertices' `p[kz] / d[kz]`
            // (computed as it computes them); lanes where all of them lie well before the segment's
            // range or beyond the light miss, whatever the roundings (`lanes::Z_NEAR`,
            // `lanes::Z_FAR`). Per axis, the least and greatest vertex coordinate.
            let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
            let span = [(lo.x, hi.x), (lo.y, hi.y), (lo.z, hi.z)];
            // The open rays of the mask, less the sure misses.
            for w in 0..words {
                self.maybe[w] = self.open[w] & mask(w);
            }
            if finite {
                let [x, y, z, len, sz, ..] = &self.all;
                let lanes = Lanes { x, y, z, len, sz, kz: &self.all_kz };
                misses(&s, &span, &lanes, &mut self.maybe[..words], simd);
            }
            for w in 0..words {
                let bits = self.maybe[w];
                self.exact(tri, w, bits, rays, out, ctx, simd);
            }
        }
        if self.live < live {
            self.note_blocker(t);
        }
    }
}

/// The edge normals of the triangle `(a, b, c)` (relative to the fan's apex) scaled by the inverse
/// of their margins: a ray of direction `d` is a sure miss where one `s_i . d` exceeds `|d|` and
/// another is below `-|d|`. (The L1 norm bounds the Euclidean one, so the margins only grow; the
/// scaling's own rounding is far inside them.)
#[inline(always)]
fn edge_normals(a: Vec3, b: Vec3, c: Vec3) -> [Vec3; 3] {
    let l1 = |v: Vec3| v.abs().element_sum();
    let (la, lb, lc) = (l1(a), l1(b), l1(c));
    [
        b.cross(c) * (EDGE_MARGIN * lb * lc).recip(),
        c.cross(a) * (EDGE_MARGIN * lc * la).recip(),
        a.cross(b) * (EDGE_MARGIN * la * lb).recip(),
    ]
}

/// At most this many rays of a triangle test go straight to the watertight test, without the edge
/// test first. Measured (callgrind of the query at 64 rays on cornell-cube-2, huis-c, dragon,
/// cornell-bunny and conference-lit, docs/results.md session 9): 16 to 32 needed the fewest
/// instructions of 3, 8, 16, 24, 32 and 64 once the watertight test ran eight rays wide (3 did before).
const DIRECT_MAX: u32 = 16;

/// Triangles a fan remembers as having closed rays ([`Fan::blockers`]): the last blockers a
/// P-LIE mode keeps per light (`lie::light`). Measured (callgrind of the query at 16 and 64 rays on
/// conference-lit, huis-c, cornell-dragon-100k and cornell-bunny, docs/results.md issue 21 session
/// 23): 8 needed the fewest instructions of 1, 2, 4, 8 and 16 at 16 rays, and 0.1% more than 16 at 64.
pub const BLOCKERS: usize = 8;

/// Per-thread scratch of the per-light queries ([`super::Visibility::occluded_light`]).
#[derive(Clone, Debug, Default)]
pub struct LightScratch {
    /// The fan of the current (point, light).
    pub fan: Fan,
    /// The distinct blocker lists of the current (point, light): the mode's own keys.
    pub lists: Vec<u32>,
    /// The `(start, len)` of the face-grid cell lists gathered in `lists` (to keep each list once).
    pub ranges: Vec<(u32, u32)>,
    /// The stack of a walk down the scene BVH.
    pub walk: WalkStack,
    /// The list of the current point's shaft (`lie::shafts`).
    pub shaft: Vec<TriId>,
    /// Per light (by index), the blockers of the last walk down the scene BVH that found every
    /// ray occluded ([`Fan::blockers`]; `u32::MAX` past the last, or for none).
    pub last_blockers: Vec<[u32; BLOCKERS]>,
    /// Which (leaf, light) pairs' footprints decided nothing lately (`lie::light`).
    pub verdicts: Verdicts,
}

impl LightScratch {
    /// Tests the fan's open rays against the light's last blockers (`last_blockers`: those of the
    /// last walk for the light that found every ray occluded, [`LightScratch::keep_blockers`]),
    /// each but the rays' own triangles and those the fan's pyramid culls. The caller has set the
    /// fan and its pyramid. Any triangle's exact test is brute force's, so testing these first
    /// changes no answer, only which triangle closes a ray: in shadow, a neighbouring pixel's
    /// blockers often close every ray, and the walk is not needed.
    pub fn test_last_blockers(&mut self, scene: &Scene, rays: &LightRays, out: &mut [bool], ctx: &mut QueryCtx) {
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = Avx2::detect() {
            // SAFETY: AVX2, POPCNT and BMI1 are available (the proof).
            return unsafe { self.test_last_blockers_avx(scene, rays, out, ctx, simd) };
        }
        self.test_last_blockers_in(scene, rays, out, ctx, None)
    }

    /// [`LightScratch::test_last_blockers`] compiled for AVX2, so that the fan's kernels inline.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2,popcnt,bmi1")]
    unsafe fn test_last_blockers_avx(
        &mut self,
        scene: &Scene,
        rays: &LightRays,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Avx2,
    ) {
        self.test_last_blockers_in(scene, rays, out, ctx, Some(simd))
    }

    /// The body of [`LightScratch::test_last_blockers`].
    #[inline(always)]
    fn test_last_blockers_in(
        &mut self,
        scene: &Scene,
        rays: &LightRays,
        out: &mut [bool],
        ctx: &mut QueryCtx,
        simd: Option<Avx2>,
    ) {
        let li = rays.light.idx();
        if self.last_blockers.len() <= li {
            self.last_blockers.resize(scene.lights.len().max(li + 1), [u32::MAX; BLOCKERS]);
        }
        for t in self.last_blockers[li] {
            // (A scratch used with another scene may name triangles this one lacks.)
            let Some(tri) = scene.triangles.get(t as usize) else { break };
            let t = TriId(t);
            if rays.own(scene, t) {
                continue;
            }
            if !self.fan.pyramid.culls(tri) {
                self.fan.test(scene, rays, t, out, ctx, simd);
                if self.fan.live() == 0 {
                    return;
                }
            }
        }
    }

    /// After a walk for `rays.light` (preceded by [`LightScratch::test_last_blockers`]): keeps
    /// the fan's blockers as the light's last ones if every ray is occluded, else forgets them.
    pub fn keep_blockers(&mut self, rays: &LightRays) {
        // (`test_last_blockers` made room for this light.)
        self.last_blockers[rays.light.idx()] =
            if self.fan.live() == 0 { self.fan.blockers() } else { [u32::MAX; BLOCKERS] };
    }
}

/// Scratch of a fan's walk down a tree (the scene BVH's, `Bvh::fan_occluded`): the nodes still to
/// visit, each with its mask of rays (one after the other in `masks`; for a fan of at most 64
/// rays, each mask with its node in `visits`, one push and one pop a node), the masks of the node
/// being visited and of its eight children, and the nodes and mask of a ray walking a subtree
/// alone.
#[derive(Clone, Debug, Default)]
pub struct WalkStack {
    pub nodes: Vec<u32>,
    pub masks: Vec<u64>,
    pub visits: Vec<(u64, u32)>,
    pub node_mask: Vec<u64>,
    pub child_masks: Vec<u64>,
    pub ray_nodes: Vec<u32>,
    pub ray_mask: Vec<u64>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Rng;
    use crate::scene::Light;
    use crate::visibility::pyramid::PyramidBasis;
    use crate::visibility::query::SEGMENT_EPS;
    use glam::Vec2;

    /// Where [`Pyramid::outside_cone`] finds every sample of the light outside a triangle's cone
    /// (from [`edge_normals`]), the watertight test misses every segment from the apex to the
    /// light's corners and to random points of it; with the scene near the origin and moved far
    /// from it (where the rounding of the samples' world coordinates is largest against their
    /// directions). Random triangles around the pyramid, some touching the apex or the light, some
    /// near its sides; both answers occur.
    #[test]
    fn triangles_outside_the_cone_meet_no_segment() {
        let mut rng = Rng::stream(13, 0, 0, 0);
        let (mut outside, mut inside) = (0, 0);
        // Near the origin a tilted light; far from it an axis-aligned one (whose corners stay
        // coplanar in `f32`). Each as a parallelogram sampled over a fourth corner moved outward
        // by about half of what the light's check accepts, and as a triangle.
        let tilted = (Vec3::new(0.31, 0.02, 0.97), Vec3::new(0.93, -0.01, -0.29));
        let level = (Vec3::new(0.0, 0.0, 0.97), Vec3::new(0.93, 0.0, 0.0));
        let places = [(Vec3::ZERO, tilted), (Vec3::new(400.0, -300.0, 600.0), level)];
        for ((far, (e1, e3)), corners) in places.into_iter().flat_map(|p| [(p, 4), (p, 3)]) {
            let o = Vec3::new(0.13, 2.0, 0.07) + far;
            let moved = o + e1 + e3 + (e1 + e3) * 4e-6;
            let vertices = if corners == 4 { vec![o, o + e3, moved, o + e1] } else { vec![o, o + e3, o + e1] };
            let light = Light::new(vertices, Vec3::ONE, vec![]).unwrap();
            assert_eq!(light.parallelogram_edges().is_some(), corners == 4);
            let basis = PyramidBasis::of(&light).unwrap();
            for i in 0..3_000 {
                let x = far + Vec3::new(rng.next_f32() * 3.0 - 1.0, rng.next_f32() * 1.5, rng.next_f32() * 3.0 - 1.0);
                let mut p = Pyramid::default();
                if !p.set_from(x, &basis, 1e-4) {
                    continue;
                }
                // The light's corners of the unit square (a parallelogram's fourth is `v1 + v3 -
                // v0`) and random points, by the light's own sampling.
                let mut us = vec![Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE];
                us.extend((4..32).map(|_| Vec2::new(rng.next_f32(), rng.next_f32())));
                let samples: Vec<Vec3> = us.iter().map(|&u| light.sample(u)).collect();
                for j in 0..8 {
                    let mut v = || {
                        far + Vec3::new(
                            rng.next_f32() * 4.0 - 1.5,
                            rng.next_f32() * 3.0 - 0.5,
                            rng.next_f32() * 4.0 - 1.5,
                        )
                    };
                    let (mut a, b, c) = (v(), v(), v());
                    match (i + j) % 4 {
                        0 => a = x + (a - x) * 0.01,
                        1 => a = samples[4 + j],
                        // A vertex on (or a rounding beside) the segment to a sample, so that two
                        // edge planes graze it.
                        2 => a = x + (samples[j] - x) * 0.5 + (a - x) * (j as f32 * 1e-7),
                        _ => {}
                    }
                    let s = edge_normals(a - x, b - x, c - x);
                    if !s.iter().all(|v| v.is_finite()) || !p.outside_cone(&s) {
                        inside += 1;
                        continue;
                    }
                    outside += 1;
                    let tri = Triangle::new(a, b, c);
                    for &y in &samples {
                        let test = RayTest::new(x, y - x, SEGMENT_EPS, 1.0 - SEGMENT_EPS);
                        assert!(test.hit(&tri).is_none(), "apex {x}, sample {y}, {tri:?}");
                    }
                }
            }
        }
        assert!(outside > 5_000 && inside > 5_000, "{outside} outside, {inside} not");
    }
}
