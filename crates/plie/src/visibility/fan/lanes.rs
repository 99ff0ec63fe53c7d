//! The fan's lane kernels (issue 21): per-ray values of a fan (its shears for the watertight test
//! among them), the slab test of a box (eight rays against one box, or one ray against eight
//! boxes), the edge-function test of a triangle and the watertight test itself, eight lanes at a
//! time with AVX2 and lane by lane otherwise. Each kernel computes exactly what its scalar form
//! does, or only proves what the exact test would decide (see [`super`]).

use glam::Vec3;

use super::LANES;
#[cfg(target_arch = "x86_64")]
use crate::geometry::Triangle;
use crate::geometry::SEGMENT_EPS;
use crate::visibility::simd::Avx2;

/// The inverse of a direction's component for the slab test, with a non-finite one (of a zero or
/// tiny component) replaced by `±f32::MAX`. A product with it is then never NaN, and the slab it gives
/// is the whole line where the box's slab holds the origin and empty (up to the segment's tiny
/// motion along that axis, which is far below the boxes' growth by the construction tolerance)
/// where it does not, as [`crate::geometry::Segment`]'s parallel case decides.
#[inline]
pub(super) fn inverse(d: f32) -> f32 {
    let i = 1.0 / d;
    if i.is_finite() {
        i
    } else {
        f32::MAX.copysign(i)
    }
}

/// The per-ray values of [`super::Fan::set`] for one block of eight directions `(x, y, z)`: their
/// lengths, the watertight test's `kz` and `1 / d[kz]`, and the inverse directions ([`inverse`]), as
/// the scalar loop computes them (the same IEEE operations in the same order, so the same bits).
#[cfg(target_arch = "x86_64")]
struct RayBlock {
    len: std::arch::x86_64::__m256,
    sz: std::arch::x86_64::__m256,
    ix: std::arch::x86_64::__m256,
    iy: std::arch::x86_64::__m256,
    iz: std::arch::x86_64::__m256,
    kz: std::arch::x86_64::__m256i,
}

/// [`RayBlock`] of eight directions.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
fn ray_block(x: std::arch::x86_64::__m256, y: std::arch::x86_64::__m256, z: std::arch::x86_64::__m256) -> RayBlock {
    use std::arch::x86_64::*;
    let sign = _mm256_set1_ps(-0.0);
    let (inf, max) = (_mm256_set1_ps(f32::INFINITY), _mm256_set1_ps(f32::MAX));
    let one = _mm256_set1_ps(1.0);
    let inverse = |v: __m256| {
        let i = _mm256_div_ps(one, v);
        let finite = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, i), inf);
        _mm256_blendv_ps(_mm256_or_ps(max, _mm256_and_ps(sign, i)), i, finite)
    };
    let dot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y)), _mm256_mul_ps(z, z));
    let (ax, ay, az) = (_mm256_andnot_ps(sign, x), _mm256_andnot_ps(sign, y), _mm256_andnot_ps(sign, z));
    let c0 = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(ax, ay), _mm256_cmp_ps::<_CMP_GE_OQ>(ax, az));
    let c1 = _mm256_cmp_ps::<_CMP_GE_OQ>(ay, az);
    let dk = _mm256_blendv_ps(_mm256_blendv_ps(z, y, c1), x, c0);
    let k12 = _mm256_blendv_ps(_mm256_set1_ps(2.0), one, c1);
    RayBlock {
        len: _mm256_sqrt_ps(dot),
        sz: _mm256_div_ps(one, dk),
        ix: inverse(x),
        iy: inverse(y),
        iz: inverse(z),
        kz: _mm256_cvttps_epi32(_mm256_blendv_ps(k12, _mm256_setzero_ps(), c0)),
    }
}

/// Per lane, `v[k]` for the lane's axis `k` (0, 1 or 2).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
unsafe fn by_axis(k: std::arch::x86_64::__m256i, v: [std::arch::x86_64::__m256; 3]) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    let is0 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(k, _mm256_setzero_si256()));
    let is1 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(k, _mm256_set1_epi32(1)));
    _mm256_blendv_ps(_mm256_blendv_ps(v[2], v[1], is1), v[0], is0)
}

/// The slab test of [`meets_box`] for eight (segment, box) pairs in lanes: the segments from the
/// apex with inverse directions `inv` (parameter range `[SEGMENT_EPS, 1 - SEGMENT_EPS]`) against the
/// boxes `[lo, hi]` given relative to the apex. Returns the lanes that meet, as bits. Both the
/// eight-rays and the eight-boxes kernels run this, so they answer alike.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
unsafe fn slab_avx(
    lo: [std::arch::x86_64::__m256; 3],
    hi: [std::arch::x86_64::__m256; 3],
    inv: [std::arch::x86_64::__m256; 3],
) -> u32 {
    use std::arch::x86_64::*;
    let (t_min, t_max) = (_mm256_set1_ps(SEGMENT_EPS), _mm256_set1_ps(1.0 - SEGMENT_EPS));
    let (ax, cx) = (_mm256_mul_ps(lo[0], inv[0]), _mm256_mul_ps(hi[0], inv[0]));
    let (ay, cy) = (_mm256_mul_ps(lo[1], inv[1]), _mm256_mul_ps(hi[1], inv[1]));
    let (az, cz) = (_mm256_mul_ps(lo[2], inv[2]), _mm256_mul_ps(hi[2], inv[2]));
    let t0 = _mm256_max_ps(
        _mm256_max_ps(_mm256_min_ps(ax, cx), _mm256_min_ps(ay, cy)),
        _mm256_max_ps(_mm256_min_ps(az, cz), t_min),
    );
    let t1 = _mm256_min_ps(
        _mm256_min_ps(_mm256_max_ps(ax, cx), _mm256_max_ps(ay, cy)),
        _mm256_min_ps(_mm256_max_ps(az, cz), t_max),
    );
    _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1)) as u32
}

/// The rest of each ray's shear for the watertight test, as [`crate::geometry::RayTest::new`]
/// computes it from the direction `d`, `sz = 1 / d[kz]` and `kz`: the axes `kx = kz + 1`, `ky = kx + 1`
/// (mod 3, swapped where `d[kz] < 0`) and `sx = d[kx] sz`, `sy = d[ky] sz`, into `s` and `k`, lane by
/// lane: for the rays that [`fan_lanes_avx`] leaves (fewer than eight, or all without AVX2), whose
/// [`shear_block`] computes each lane as this does.
#[inline(always)]
pub(super) fn shear_lanes(d: [&[f32]; 3], sz: &[f32], kz: &[u32], s: [&mut [f32]; 2], k: [&mut [u32]; 2]) {
    let n = d
        .iter()
        .map(|v| v.len())
        .chain([sz.len(), kz.len(), s[0].len(), s[1].len(), k[0].len(), k[1].len()])
        .min()
        .unwrap_or(0);
    let [sx, sy] = s;
    let [kx, ky] = k;
    for j in 0..n {
        let z = kz[j] as usize;
        let (mut x, mut y) = ((z + 1) % 3, (z + 2) % 3);
        if d[z][j] < 0.0 {
            std::mem::swap(&mut x, &mut y);
        }
        (kx[j], ky[j]) = (x as u32, y as u32);
        sx[j] = d[x][j] * sz[j];
        sy[j] = d[y][j] * sz[j];
    }
}

/// [`shear_lanes`] for one block of eight directions `d` with their `kz` and `sz`: `(sx, sy, kx,
/// ky)`, each lane as the scalar code computes it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
fn shear_block(
    d: [std::arch::x86_64::__m256; 3],
    kzv: std::arch::x86_64::__m256i,
    szv: std::arch::x86_64::__m256,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256, std::arch::x86_64::__m256i, std::arch::x86_64::__m256i) {
    use std::arch::x86_64::*;
    let (zero, one, two) = (_mm256_setzero_si256(), _mm256_set1_epi32(1), _mm256_set1_epi32(2));
    let next = |a: __m256i| _mm256_blendv_epi8(_mm256_add_epi32(a, one), zero, _mm256_cmpeq_epi32(a, two));
    // SAFETY: AVX2 is enabled here.
    let pick = |a: __m256i| unsafe { by_axis(a, d) };
    let (a, b) = (next(kzv), next(next(kzv)));
    let neg = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_LT_OQ>(pick(kzv), _mm256_setzero_ps()));
    let (kxv, kyv) = (_mm256_blendv_epi8(a, b, neg), _mm256_blendv_epi8(b, a, neg));
    (_mm256_mul_ps(pick(kxv), szv), _mm256_mul_ps(pick(kyv), szv), kxv, kyv)
}

/// The per-ray values of [`super::Fan::set`] for the blocks of eight points of `ys` (the fan's
/// targets, from `x`) in one pass: the directions `y - x` (as `Vec3`'s subtraction), their lengths,
/// `1 / d[kz]` ([`RayBlock`]) into `all` (`dx, dy, dz, len, sz`) and `kz`, and with `ALL` also the
/// inverse directions (`all`'s `ix, iy, iz`) and [`shear_block`] (the shears `s` and their axes
/// `k`), each lane as the scalar code computes it. Without `ALL` those are left to
/// [`inverse_lanes_avx`] and [`shear_lanes_avx`], on first use. Returns how many points it did:
/// all of them where the arrays have room for whole blocks, else a multiple of eight (the caller
/// does the rest).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
pub(super) unsafe fn fan_lanes_avx<const ALL: bool>(
    ys: &[Vec3],
    x: Vec3,
    all: &mut [Vec<f32>; 8],
    kz: &mut [u32],
    s: &mut [Vec<f32>; 2],
    k: &mut [Vec<u32>; 2],
) -> usize {
    use std::arch::x86_64::*;
    // The fewest lanes any array holds (loops over arrays of fixed length, so unrolled).
    let mut room = kz.len();
    for v in all.iter() {
        room = room.min(v.len());
    }
    if ALL {
        for v in s.iter() {
            room = room.min(v.len());
        }
        for v in k.iter() {
            room = room.min(v.len());
        }
    }
    let n = ys.len().min(room) / LANES * LANES;
    let (sx, sy, sz) = (_mm256_set1_ps(x.x), _mm256_set1_ps(x.y), _mm256_set1_ps(x.z));
    let [dx, dy, dz, len, szs, ix, iy, iz] = all;
    let ([shx, shy], [kx, ky]) = (s, k);
    // The lanes `j..j + 8` from the eight points at `p`.
    // SAFETY (of each call below): `p` points to eight points and j + LANES <= room.
    let mut block = |p: *const Vec3, j: usize| unsafe {
        let (px, py, pz) = points_block(p.cast::<f32>());
        let (x, y, z) = (_mm256_sub_ps(px, sx), _mm256_sub_ps(py, sy), _mm256_sub_ps(pz, sz));
        // (Without `ALL`, the inverse directions of `r` are not stored, so not computed.)
        let r = ray_block(x, y, z);
        let put = |v: &mut Vec<f32>, a: __m256| _mm256_storeu_ps(v.as_mut_ptr().add(j), a);
        put(dx, x);
        put(dy, y);
        put(dz, z);
        put(len, r.len);
        put(szs, r.sz);
        _mm256_storeu_si256(kz.as_mut_ptr().add(j).cast(), r.kz);
        if ALL {
            let (sxv, syv, kxv, kyv) = shear_block([x, y, z], r.kz, r.sz);
            put(ix, r.ix);
            put(iy, r.iy);
            put(iz, r.iz);
            put(shx, sxv);
            put(shy, syv);
            _mm256_storeu_si256(kx.as_mut_ptr().add(j).cast(), kxv);
            _mm256_storeu_si256(ky.as_mut_ptr().add(j).cast(), kyv);
        }
    };
    let mut j = 0;
    while j < n {
        // (j + LANES <= n <= ys.len(); `Vec3` is three `f32`s without padding.)
        block(ys[j..].as_ptr(), j);
        j += LANES;
    }
    // A last, partial block where the arrays have room for a whole one (a fan padded to whole
    // blocks): its points copied into eight, the rest of them the apex (the caller overwrites
    // those lanes).
    if j < ys.len() && j + LANES <= room {
        let mut last = [x; LANES];
        last[..ys.len() - j].copy_from_slice(&ys[j..]);
        block(last.as_ptr(), j);
        j = ys.len();
    }
    j
}

/// The inverse directions ([`inverse`], as [`RayBlock`] computes them) of the directions in `all`
/// (`dx, dy, dz`), into its `ix, iy, iz`, for the whole blocks of eight lanes the arrays hold.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
pub(super) unsafe fn inverse_lanes_avx(all: &mut [Vec<f32>; 8]) {
    use std::arch::x86_64::*;
    let mut room = usize::MAX;
    for v in all.iter() {
        room = room.min(v.len());
    }
    let [dx, dy, dz, _, _, ix, iy, iz] = all;
    let mut j = 0;
    while j + LANES <= room {
        // SAFETY: j + LANES <= room, the length of every array.
        unsafe {
            let get = |v: &Vec<f32>| _mm256_loadu_ps(v.as_ptr().add(j));
            // (Only the inverse directions of `r` are stored, so only they are computed.)
            let r = ray_block(get(dx), get(dy), get(dz));
            let put = |v: &mut Vec<f32>, a: __m256| _mm256_storeu_ps(v.as_mut_ptr().add(j), a);
            put(ix, r.ix);
            put(iy, r.iy);
            put(iz, r.iz);
        }
        j += LANES;
    }
}

/// The rest of the watertight test's shear ([`shear_block`]) of the directions in `all` (`dx, dy,
/// dz`, with `sz` and the axes `kz`): `sx`, `sy` into `s` and the axes `kx`, `ky` into `k`, for
/// the whole blocks of eight lanes the arrays hold.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
pub(super) unsafe fn shear_lanes_avx(all: &[Vec<f32>; 8], kz: &[u32], s: &mut [Vec<f32>; 2], k: &mut [Vec<u32>; 2]) {
    use std::arch::x86_64::*;
    let mut room = kz.len();
    for v in all.iter().chain(s.iter()) {
        room = room.min(v.len());
    }
    for v in k.iter() {
        room = room.min(v.len());
    }
    let [dx, dy, dz, _, szs, ..] = all;
    let ([shx, shy], [kx, ky]) = (s, k);
    let mut j = 0;
    while j + LANES <= room {
        // SAFETY: j + LANES <= room, the length of every array.
        unsafe {
            let get = |v: &Vec<f32>| _mm256_loadu_ps(v.as_ptr().add(j));
            let kzv = _mm256_loadu_si256(kz.as_ptr().add(j).cast());
            let (sxv, syv, kxv, kyv) = shear_block([get(dx), get(dy), get(dz)], kzv, get(szs));
            _mm256_storeu_ps(shx.as_mut_ptr().add(j), sxv);
            _mm256_storeu_ps(shy.as_mut_ptr().add(j), syv);
            _mm256_storeu_si256(kx.as_mut_ptr().add(j).cast(), kxv);
            _mm256_storeu_si256(ky.as_mut_ptr().add(j).cast(), kyv);
        }
        j += LANES;
    }
}

/// The coordinates of the eight points (24 floats) at `p`, taken apart with shuffles: `(x, y, z)`.
///
/// # Safety
/// `p` points to 24 readable floats.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
unsafe fn points_block(
    p: *const f32,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
    use std::arch::x86_64::*;
    // SAFETY: the caller's 24 floats.
    unsafe {
        let lo = |i: usize| _mm256_castps128_ps256(_mm_loadu_ps(p.add(4 * i)));
        // x0 y0 z0 x1 | x4 y4 z4 x5, y1 z1 x2 y2 | y5 z5 x6 y6, z2 x3 y3 z3 | z6 x7 y7 z7.
        let m03 = _mm256_insertf128_ps::<1>(lo(0), _mm_loadu_ps(p.add(12)));
        let m14 = _mm256_insertf128_ps::<1>(lo(1), _mm_loadu_ps(p.add(16)));
        let m25 = _mm256_insertf128_ps::<1>(lo(2), _mm_loadu_ps(p.add(20)));
        // x2 y2 x3 y3 | x6 y6 x7 y7, y0 z0 y1 z1 | y4 z4 y5 z5.
        let xy = _mm256_shuffle_ps::<0b10_01_11_10>(m14, m25);
        let yz = _mm256_shuffle_ps::<0b01_00_10_01>(m03, m14);
        (
            _mm256_shuffle_ps::<0b10_00_11_00>(m03, xy),
            _mm256_shuffle_ps::<0b11_01_10_00>(yz, xy),
            _mm256_shuffle_ps::<0b11_00_11_01>(yz, m25),
        )
    }
}

/// The rays' inverse directions in lanes.
pub(super) struct BoxLanes<'a> {
    pub(super) ix: &'a [f32],
    pub(super) iy: &'a [f32],
    pub(super) iz: &'a [f32],
}

/// The bits of `within` (the word of lanes `base..base + 64`) whose segments (origin at the
/// fan's apex, parameter range `[SEGMENT_EPS, 1 - SEGMENT_EPS]`) meet the box `[lo, hi]` given
/// relative to the apex. Ray by ray: the test the box kernels ([`slab_avx`]) compute eight lanes
/// wide, for CPUs without AVX2.
#[inline]
pub(super) fn meets_box(lo: Vec3, hi: Vec3, lanes: &BoxLanes, base: usize, within: u64) -> u64 {
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

/// [`meets_box`] for each box `c` of eight with bit `c` of `alive` set, given as lanes
/// (`lo[axis][c]`, `hi[axis][c]`): `out[c]` becomes the bits of `within` whose segments meet box `c`
/// (0 for the others).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn meets_boxes(
    lo: &[[f32; 8]; 3],
    hi: &[[f32; 8]; 3],
    alive: u8,
    lanes: &BoxLanes,
    base: usize,
    within: u64,
    out: &mut [u64; 8],
    simd: Option<Avx2>,
) {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    if simd.is_some() {
        // Eight rays at a time costs a test per box and block of eight holding a ray of `within`;
        // one ray at a time, a test per ray (measured by callgrind on five scenes at 64 rays,
        // docs/results.md session 9: weighing the two from 1:2 to 3:1 changed little).
        let blocks = nonzero_bytes(within).count_ones();
        // SAFETY: AVX2 is available (the proof); the lane arrays are padded to whole blocks.
        unsafe {
            if within.count_ones() < alive.count_ones() * blocks {
                meets_boxes_by_ray_avx(lo, hi, alive, lanes, base, within, out);
            } else {
                meets_boxes_avx(lo, hi, alive, lanes, base, within, out);
            }
        }
        return;
    }
    each_box(lo, hi, alive, out, |l, h| meets_box(l, h, lanes, base, within));
}

/// Bit `c` set where byte `c` of `m` is not zero.
#[inline(always)]
pub(crate) fn nonzero_bytes(m: u64) -> u8 {
    const LOW7: u64 = 0x7f7f_7f7f_7f7f_7f7f;
    // The top bit of each byte: set where the byte is not zero.
    let top = (((m & LOW7) + LOW7) | m) & !LOW7;
    // Gathers the eight top bits into the top byte.
    ((top >> 7).wrapping_mul(0x0102_0408_1020_4080) >> 56) as u8
}

/// Bit `c` set where `m[c]` is not zero (the boxes that a ray meets, from [`meets_boxes`]'s masks).
#[inline(always)]
pub(super) fn nonzero_words(m: &[u64; 8], simd: Option<Avx2>) -> u8 {
    #[cfg(target_arch = "x86_64")]
    if simd.is_some() {
        // SAFETY: AVX2 is available (the proof).
        return unsafe { nonzero_words_avx(m) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    m.iter().enumerate().fold(0, |b, (c, &w)| b | u8::from(w != 0) << c)
}

/// [`nonzero_words`] with two compares of four words.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
unsafe fn nonzero_words_avx(m: &[u64; 8]) -> u8 {
    use std::arch::x86_64::*;
    // SAFETY: eight words, read as two vectors of four.
    let (a, b) = unsafe { (_mm256_loadu_si256(m.as_ptr().cast()), _mm256_loadu_si256(m.as_ptr().add(4).cast())) };
    let zero = _mm256_setzero_si256();
    let za = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(a, zero)));
    let zb = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(b, zero)));
    !((za | zb << 4) as u8)
}

/// `out[c]` becomes `meets(lo_c, hi_c)` for each box `c` with bit `c` of `alive` set, 0 for the
/// others (the loop of [`meets_boxes`], inlined into each of its two paths).
#[inline(always)]
fn each_box(lo: &[[f32; 8]; 3], hi: &[[f32; 8]; 3], alive: u8, out: &mut [u64; 8], meets: impl Fn(Vec3, Vec3) -> u64) {
    let corner = |v: &[[f32; 8]; 3], c: usize| Vec3::new(v[0][c], v[1][c], v[2][c]);
    for (c, o) in out.iter_mut().enumerate() {
        *o = if alive >> c & 1 != 0 { meets(corner(lo, c), corner(hi, c)) } else { 0 };
    }
}

/// Of the eight boxes `c` with bit `c` of `alive` set, given as lanes relative to the apex
/// (`lo[axis][c]`, `hi[axis][c]`), those that the segment of ray `j` meets, as bits: [`meets_box`]'s
/// test of one ray against eight boxes.
#[inline(always)]
pub(super) fn ray_meets_boxes(
    lo: &[[f32; 8]; 3],
    hi: &[[f32; 8]; 3],
    alive: u8,
    lanes: &BoxLanes,
    j: usize,
    simd: Option<Avx2>,
) -> u8 {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    if simd.is_some() {
        // SAFETY: AVX2 is available (the proof).
        return unsafe { ray_meets_boxes_avx(lo, hi, alive, lanes, j) };
    }
    let corner = |v: &[[f32; 8]; 3], c: usize| Vec3::new(v[0][c], v[1][c], v[2][c]);
    let (base, bit) = (j / 64 * 64, 1u64 << (j % 64));
    (0..8)
        .filter(|&c| alive >> c & 1 != 0 && meets_box(corner(lo, c), corner(hi, c), lanes, base, bit) != 0)
        .fold(0, |m, c| m | 1 << c)
}

/// [`ray_meets_boxes`] with the eight boxes in lanes: [`slab_avx`], as every box test of a fan.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
unsafe fn ray_meets_boxes_avx(lo: &[[f32; 8]; 3], hi: &[[f32; 8]; 3], alive: u8, lanes: &BoxLanes, j: usize) -> u8 {
    use std::arch::x86_64::*;
    // SAFETY: eight floats each.
    let (l, h) = unsafe {
        (
            [_mm256_loadu_ps(lo[0].as_ptr()), _mm256_loadu_ps(lo[1].as_ptr()), _mm256_loadu_ps(lo[2].as_ptr())],
            [_mm256_loadu_ps(hi[0].as_ptr()), _mm256_loadu_ps(hi[1].as_ptr()), _mm256_loadu_ps(hi[2].as_ptr())],
        )
    };
    let inv = [_mm256_set1_ps(lanes.ix[j]), _mm256_set1_ps(lanes.iy[j]), _mm256_set1_ps(lanes.iz[j])];
    // SAFETY: AVX2 is enabled here.
    (unsafe { slab_avx(l, h, inv) } as u8) & alive
}

/// [`meets_boxes`] with the eight boxes in lanes and one ray at a time: cheaper than eight rays
/// at a time when the rays of `within` are few and spread over many blocks of eight. Each (ray, box)
/// is decided by [`slab_avx`], as in [`meets_boxes_avx`], so with the same answer.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
pub(super) unsafe fn meets_boxes_by_ray_avx(
    lo: &[[f32; 8]; 3],
    hi: &[[f32; 8]; 3],
    alive: u8,
    lanes: &BoxLanes,
    base: usize,
    within: u64,
    out: &mut [u64; 8],
) {
    use std::arch::x86_64::*;
    *out = [0; 8];
    if alive == 0 {
        return;
    }
    // SAFETY: eight floats each.
    let (lx, ly, lz, hx, hy, hz) = unsafe {
        (
            _mm256_loadu_ps(lo[0].as_ptr()),
            _mm256_loadu_ps(lo[1].as_ptr()),
            _mm256_loadu_ps(lo[2].as_ptr()),
            _mm256_loadu_ps(hi[0].as_ptr()),
            _mm256_loadu_ps(hi[1].as_ptr()),
            _mm256_loadu_ps(hi[2].as_ptr()),
        )
    };
    let mut bits = within;
    while bits != 0 {
        let b = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let j = base + b;
        let inv = [_mm256_set1_ps(lanes.ix[j]), _mm256_set1_ps(lanes.iy[j]), _mm256_set1_ps(lanes.iz[j])];
        // SAFETY: AVX2 is enabled here.
        let mut m = unsafe { slab_avx([lx, ly, lz], [hx, hy, hz], inv) } & u32::from(alive);
        while m != 0 {
            let c = m.trailing_zeros() as usize;
            m &= m - 1;
            out[c] |= 1 << b;
        }
    }
}

/// [`meets_boxes`] in one call with AVX2: per block of eight lanes with a bit in `within`, its
/// inverse directions loaded once and tested against each box of `alive` by [`slab_avx`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
unsafe fn meets_boxes_avx(
    lo: &[[f32; 8]; 3],
    hi: &[[f32; 8]; 3],
    alive: u8,
    lanes: &BoxLanes,
    base: usize,
    within: u64,
    out: &mut [u64; 8],
) {
    use std::arch::x86_64::*;
    *out = [0; 8];
    let n = lanes.ix.len().min(lanes.iy.len()).min(lanes.iz.len());
    let mut rest = within;
    while rest != 0 {
        let at = rest.trailing_zeros() as usize / LANES * LANES;
        let byte = rest >> at & 0xff;
        rest &= !(0xff << at);
        let j = base + at;
        if j + LANES > n {
            continue;
        }
        // SAFETY: j + LANES <= n <= every array's length; AVX2 is enabled here.
        let inv = unsafe {
            [
                _mm256_loadu_ps(lanes.ix.as_ptr().add(j)),
                _mm256_loadu_ps(lanes.iy.as_ptr().add(j)),
                _mm256_loadu_ps(lanes.iz.as_ptr().add(j)),
            ]
        };
        let mut boxes = alive;
        while boxes != 0 {
            let c = boxes.trailing_zeros() as usize;
            boxes &= boxes - 1;
            let sp = |v: f32| _mm256_set1_ps(v);
            let (l, h) = ([sp(lo[0][c]), sp(lo[1][c]), sp(lo[2][c])], [sp(hi[0][c]), sp(hi[1][c]), sp(hi[2][c])]);
            // SAFETY: AVX2 is enabled here.
            let m = u64::from(unsafe { slab_avx(l, h, inv) });
            out[c] |= (m & byte) << at;
        }
    }
}

/// The rays in lanes (see [`Fan`]).
pub(super) struct Lanes<'a> {
    pub(super) x: &'a [f32],
    pub(super) y: &'a [f32],
    pub(super) z: &'a [f32],
    pub(super) len: &'a [f32],
    pub(super) sz: &'a [f32],
    pub(super) kz: &'a [u32],
}

/// The hit parameter's bound near the apex: a triangle whose scaled major-axis coordinates
/// `z_i = sz (v_i - x)[kz]` (as the watertight test computes them) are all finite and at most this
/// is missed. The test compares `ts = u z_0 + v z_1 + w z_2` with `SEGMENT_EPS d`, `d = u + v + w`,
/// for edge functions `u, v, w` of one sign (else it misses; take them non-negative, the other
/// case is the negation). Rounding is monotone, and takes a value below `2^-150` to zero and any
/// other to at most twice itself, so `ts <= 2 Z_NEAR (u + v + w) (1 + 2^-23) = SEGMENT_EPS (u + v +
/// w) (1 + 2^-23) / 4`; `SEGMENT_EPS d` rounds to at least half its value if that is at least
/// `2^-149`, which is more; and if it is less, every product is below `2^-152`, so `ts <= 0`. A
/// bound relative to the `z_i` alone would not do: where `u, v, w` are below the normal range, each
/// product's rounding is absolute, and three products rounding up can outweigh `SEGMENT_EPS d`
/// (found: `z_i = 0.99 SEGMENT_EPS`, edge functions near `10^-41`, a hit at `t = 1.48e-4`).
const Z_NEAR: f32 = SEGMENT_EPS / 8.0;

/// The hit parameter's bound beyond the light: a triangle whose `z_i` are all finite and at least
/// this is missed. Each product `u z_i` is then at least `u`, so it rounds to at least `u`, and `ts`
/// to at least `d`, which is at least `(1 - SEGMENT_EPS) d` rounded (monotone rounding again).
const Z_FAR: f32 = 1.0;

/// Clears bit `j` of `maybe` (the lanes to decide, set by the caller) where lane `j` is a sure
/// miss of the triangle with scaled edge normals `s` (see [`Fan::test`]), or its hit parameter
/// cannot fall in the segment's range (`span`: per axis, the least and greatest vertex coordinate,
/// taken along the lane's `kz`). Blocks of eight lanes with no bit set are not computed.
#[inline]
pub(super) fn misses(s: &[Vec3; 3], span: &[(f32, f32); 3], lanes: &Lanes, maybe: &mut [u64], simd: Option<Avx2>) {
    #[cfg(not(target_arch = "x86_64"))]
    let _ = simd;
    #[cfg(target_arch = "x86_64")]
    if simd.is_some() {
        // SAFETY: AVX2 is available (the proof); the lane arrays are padded to whole blocks.
        unsafe { misses_avx(s, span, lanes, maybe) };
        return;
    }
    misses_scalar(s, span, lanes, maybe);
}

/// [`misses`], lane by lane.
fn misses_scalar(s: &[Vec3; 3], span: &[(f32, f32); 3], lanes: &Lanes, maybe: &mut [u64]) {
    for j in 0..lanes.x.len().min(maybe.len() * 64) {
        if maybe[j / 64] >> (j % 64) & 1 == 0 {
            continue;
        }
        let d = Vec3::new(lanes.x[j], lanes.y[j], lanes.z[j]);
        let l = lanes.len[j];
        let e = [s[0].dot(d), s[1].dot(d), s[2].dot(d)];
        let pos = e.iter().any(|&e| e > l);
        let neg = e.iter().any(|&e| e < -l);
        let outside = {
            let (lo, hi) = span[lanes.kz[j] as usize];
            let (z1, z2) = (lo * lanes.sz[j], hi * lanes.sz[j]);
            // (Both finite, so not NaN, before `min` and `max`, which pass NaN over.)
            let finite = z1.abs() <= f32::MAX && z2.abs() <= f32::MAX;
            let (zlo, zhi) = (z1.min(z2), z1.max(z2));
            finite && (zlo >= Z_FAR || zhi <= Z_NEAR)
        };
        if outside || pos && neg {
            maybe[j / 64] &= !(1 << (j % 64));
        }
    }
}

/// [`misses`], eight lanes at a time.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
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
    // The spans' bounds in lanes 0-2, picked per lane by one permutation of lanes.
    let xyz = |v: [f32; 3]| _mm256_castps128_ps256(_mm_setr_ps(v[0], v[1], v[2], 0.0));
    let (lo, hi) = (xyz(span.map(|s| s.0)), xyz(span.map(|s| s.1)));
    let (z_near, z_far, big) = (sp(Z_NEAR), sp(Z_FAR), sp(f32::MAX));
    let mut j = 0;
    while j < n && j / 64 < maybe.len() {
        if maybe[j / 64] >> (j % 64) & 0xff == 0 {
            j += LANES;
            continue;
        }
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
            let (lo, hi) = (_mm256_permutevar8x32_ps(lo, kz), _mm256_permutevar8x32_ps(hi, kz));
            let (z1, z2) = (_mm256_mul_ps(lo, sz), _mm256_mul_ps(hi, sz));
            let (zlo, zhi) = (_mm256_min_ps(z1, z2), _mm256_max_ps(z1, z2));
            // As `misses_scalar`: both finite (false for NaN, which `min` and `max` pass over),
            // and beyond a bound.
            let abs = |v| _mm256_andnot_ps(sign, v);
            let finite =
                _mm256_and_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(abs(z1), big), _mm256_cmp_ps::<_CMP_LE_OQ>(abs(z2), big));
            let far = _mm256_cmp_ps::<_CMP_GE_OQ>(zlo, z_far);
            let near = _mm256_cmp_ps::<_CMP_LE_OQ>(zhi, z_near);
            miss = _mm256_or_ps(miss, _mm256_and_ps(finite, _mm256_or_ps(far, near)));
        }
        let miss = _mm256_movemask_ps(miss) as u64;
        maybe[j / 64] &= !((miss & 0xff) << (j % 64));
        j += LANES;
    }
}

/// Per ray, in lanes, the watertight test's shear ([`crate::geometry::RayTest::shear`]).
#[cfg(target_arch = "x86_64")]
pub(super) struct Shear<'a> {
    pub(super) s: [&'a [f32]; 3],
    pub(super) k: [&'a [u32]; 3],
}

/// The vertices of `tri` relative to `x` (as `Vec3`'s subtraction), each in lanes 0-2 of a vector
/// (lane 3 unused), loaded straight from the triangle's nine floats.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
pub(super) fn vertices_rel(tri: &Triangle, x: Vec3) -> [std::arch::x86_64::__m128; 3] {
    use std::arch::x86_64::*;
    let p = tri.v.as_ptr().cast::<f32>();
    // SAFETY: `tri.v` is nine contiguous floats; each load reads four of them.
    let (v0, v1, t) = unsafe { (_mm_loadu_ps(p), _mm_loadu_ps(p.add(3)), _mm_loadu_ps(p.add(5))) };
    // (z1, x2, y2, z2) -> (x2, y2, z2, z1).
    let v2 = _mm_shuffle_ps::<0b00_11_10_01>(t, t);
    let xv = _mm_setr_ps(x.x, x.y, x.z, 0.0);
    [_mm_sub_ps(v0, xv), _mm_sub_ps(v1, xv), _mm_sub_ps(v2, xv)]
}

/// [`crate::geometry::RayTest::hit`] of the triangle with vertices `v` (relative to the rays'
/// common origin, in lanes 0-2: [`vertices_rel`]) for the eight lanes `base..base + 8`, with `t` in
/// `(SEGMENT_EPS, 1 - SEGMENT_EPS)`: the same IEEE operations in the same order, so the same answers.
/// Returns the lanes hit and the lanes the scalar test must decide (an edge function exactly zero,
/// which it recomputes in f64), as bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
#[inline]
pub(super) unsafe fn exact_avx(v: [std::arch::x86_64::__m128; 3], shear: &Shear, base: usize) -> (u8, u8) {
    use std::arch::x86_64::*;
    let n = shear.s.iter().map(|v| v.len()).chain(shear.k.iter().map(|v| v.len())).min().unwrap_or(0);
    assert!(base + LANES <= n, "lanes {base}.. of {n}");
    // SAFETY: base + LANES <= n <= every array's length (checked above).
    let (sx, sy, sz, kx, ky, kz) = unsafe {
        (
            _mm256_loadu_ps(shear.s[0].as_ptr().add(base)),
            _mm256_loadu_ps(shear.s[1].as_ptr().add(base)),
            _mm256_loadu_ps(shear.s[2].as_ptr().add(base)),
            _mm256_loadu_si256(shear.k[0].as_ptr().add(base).cast()),
            _mm256_loadu_si256(shear.k[1].as_ptr().add(base).cast()),
            _mm256_loadu_si256(shear.k[2].as_ptr().add(base).cast()),
        )
    };
    let sp = |v: f32| _mm256_set1_ps(v);
    // Per lane, component `k` of `v` (lanes 0-2 of `v`), by one permutation of lanes: the
    // value itself, moved.
    let (a, b, c) = (_mm256_castps128_ps256(v[0]), _mm256_castps128_ps256(v[1]), _mm256_castps128_ps256(v[2]));
    let pick = |v: __m256, k: __m256i| _mm256_permutevar8x32_ps(v, k);
    let (mul, sub, add) = (|x, y| _mm256_mul_ps(x, y), |x, y| _mm256_sub_ps(x, y), |x, y| _mm256_add_ps(x, y));
    let (akz, bkz, ckz) = (pick(a, kz), pick(b, kz), pick(c, kz));
    let ax = sub(pick(a, kx), mul(sx, akz));
    let ay = sub(pick(a, ky), mul(sy, akz));
    let bx = sub(pick(b, kx), mul(sx, bkz));
    let by = sub(pick(b, ky), mul(sy, bkz));
    let cx = sub(pick(c, kx), mul(sx, ckz));
    let cy = sub(pick(c, ky), mul(sy, ckz));
    let u = sub(mul(cx, by), mul(cy, bx));
    let v = sub(mul(ax, cy), mul(ay, cx));
    let w = sub(mul(bx, ay), mul(by, ax));
    let z = _mm256_setzero_ps();
    let eq0 = |x| _mm256_cmp_ps::<_CMP_EQ_OQ>(x, z);
    let scalar = _mm256_or_ps(_mm256_or_ps(eq0(u), eq0(v)), eq0(w));
    let any = |f: fn(__m256, __m256) -> __m256| _mm256_or_ps(_mm256_or_ps(f(u, z), f(v, z)), f(w, z));
    let neg = any(|x, z| _mm256_cmp_ps::<_CMP_LT_OQ>(x, z));
    let pos = any(|x, z| _mm256_cmp_ps::<_CMP_GT_OQ>(x, z));
    let det = add(add(u, v), w);
    let sign = sp(-0.0);
    let finite = _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_andnot_ps(sign, det), sp(f32::INFINITY));
    let det_ok = _mm256_andnot_ps(eq0(det), finite);
    let t_scaled = add(add(mul(u, mul(sz, akz)), mul(v, mul(sz, bkz))), mul(w, mul(sz, ckz)));
    // Sign-corrected: negate both where `det < 0`.
    let flip = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(det, z), sign);
    let (ts, d) = (_mm256_xor_ps(t_scaled, flip), _mm256_xor_ps(det, flip));
    let outside = _mm256_or_ps(
        _mm256_cmp_ps::<_CMP_LE_OQ>(ts, mul(sp(SEGMENT_EPS), d)),
        _mm256_cmp_ps::<_CMP_GE_OQ>(ts, mul(sp(1.0 - SEGMENT_EPS), d)),
    );
    let miss = _mm256_or_ps(_mm256_or_ps(_mm256_and_ps(neg, pos), outside), scalar);
    let hit = _mm256_andnot_ps(miss, det_ok);
    (_mm256_movemask_ps(hit) as u8, _mm256_movemask_ps(scalar) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A spread of 64-bit masks, sparse and dense.
    fn mix_bits(i: u64) -> u64 {
        let h = crate::render::sampler::mix64(i);
        match i % 3 {
            0 => h,
            1 => h & crate::render::sampler::mix64(h),
            _ => h & crate::render::sampler::mix64(h) & crate::render::sampler::mix64(h + 1),
        }
    }

    /// The nonzero-byte mask of every pattern of zero and nonzero bytes (with several nonzero values).
    #[test]
    fn nonzero_bytes_marks_every_nonzero_byte() {
        for pattern in 0..=255u8 {
            for value in [1u8, 0x7f, 0x80, 0xff, 0x24] {
                let bytes: [u8; 8] =
                    std::array::from_fn(|c| if pattern >> c & 1 != 0 { value.rotate_left(c as u32) } else { 0 });
                let want = bytes.iter().enumerate().fold(0u8, |b, (c, &m)| b | u8::from(m != 0) << c);
                assert_eq!(nonzero_bytes(u64::from_le_bytes(bytes)), want, "{bytes:?}");
            }
        }
    }

    /// [`nonzero_words`] marks the non-zero words, with and without AVX2.
    #[test]
    fn nonzero_words_marks_every_nonzero_word() {
        for pattern in 0..=255u8 {
            let words: [u64; 8] = std::array::from_fn(|c| if pattern >> c & 1 != 0 { 1u64 << (c * 9 % 64) } else { 0 });
            for simd in [None, Avx2::detect()] {
                assert_eq!(nonzero_words(&words, simd), pattern, "{words:?}");
            }
        }
    }

    /// The lanes of a fan equal the scalar formulas bit for bit, on points whose coordinates are
    /// zeros, tiny, huge and ordinary values (the apex at the origin, so each direction is the
    /// point): direction, length, `kz` and `1 / d[kz]`, the inverse direction and the shear of the
    /// ray test.
    #[test]
    fn fan_lanes_match_the_scalar_formulas() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            use crate::geometry::RayTest;
            let special = [0.0, -0.0, 1.0, -1.0, 1e-30, -1e-38, 3e38, -2.5, 0.1, 7.0, -7.0, 1e-45];
            let mut state = 11u64;
            let mut rnd = || {
                state = crate::render::sampler::mix64(state);
                special[(state % special.len() as u64) as usize] * if state & 1 << 40 != 0 { 1.0 } else { 3.3 }
            };
            // Points ending in a partial block, in arrays with room for a whole one.
            let (n, room) = (4093, 4096);
            let ys: Vec<Vec3> = (0..n).map(|_| Vec3::new(rnd(), rnd(), rnd())).collect();
            let mut all: [Vec<f32>; 8] = std::array::from_fn(|_| vec![0.0; room]);
            let mut kz = vec![0u32; room];
            let (mut s, mut k) = ([vec![0.0; room], vec![0.0; room]], [vec![0u32; room], vec![0u32; room]]);
            // SAFETY: AVX2 is available (checked above).
            let done = unsafe { fan_lanes_avx::<true>(&ys, Vec3::ZERO, &mut all, &mut kz, &mut s, &mut k) };
            assert_eq!(done, n);
            // The values left to first use, computed then: the same bits.
            let (mut later, mut kz_later) = (std::array::from_fn(|_| vec![0.0; room]), vec![0u32; room]);
            let (mut s_later, mut k_later) = ([vec![0.0; room], vec![0.0; room]], [vec![0u32; room], vec![0u32; room]]);
            // SAFETY: as above.
            unsafe {
                let done =
                    fan_lanes_avx::<false>(&ys, Vec3::ZERO, &mut later, &mut kz_later, &mut s_later, &mut k_later);
                assert_eq!(done, n);
                inverse_lanes_avx(&mut later);
                shear_lanes_avx(&later, &kz_later, &mut s_later, &mut k_later);
            }
            let bits = |v: &[f32]| -> Vec<u32> { v[..n].iter().map(|f| f.to_bits()).collect() };
            for (a, b) in all.iter().zip(&later).chain(s.iter().zip(&s_later)) {
                assert_eq!(bits(a), bits(b));
            }
            assert_eq!((&kz[..n], &k[0][..n], &k[1][..n]), (&kz_later[..n], &k_later[0][..n], &k_later[1][..n]));
            // Without room for the last block, only the whole blocks.
            let mut short: [Vec<f32>; 8] = std::array::from_fn(|_| vec![0.0; n]);
            let (mut s2, mut k2, mut kz2) =
                ([vec![0.0; n], vec![0.0; n]], [vec![0u32; n], vec![0u32; n]], vec![0u32; n]);
            // SAFETY: as above.
            let whole = unsafe { fan_lanes_avx::<true>(&ys, Vec3::ZERO, &mut short, &mut kz2, &mut s2, &mut k2) };
            assert_eq!(whole, n / LANES * LANES);
            for (j, &d) in ys.iter().enumerate() {
                let a = d.abs();
                let want_kz = if a.x >= a.y && a.x >= a.z {
                    0
                } else if a.y >= a.z {
                    1
                } else {
                    2
                };
                let want = [d.x, d.y, d.z, d.length(), 1.0 / d[want_kz], inverse(d.x), inverse(d.y), inverse(d.z)];
                for (w, (got, want)) in all.iter().map(|v| v[j]).zip(want).enumerate() {
                    assert_eq!(got.to_bits(), want.to_bits(), "ray {j} {d}: value {w}: {got} against {want}");
                }
                assert_eq!(kz[j], want_kz as u32, "ray {j} {d}");
                if d.is_finite() && d != Vec3::ZERO {
                    let (ws, wk) = RayTest::new(Vec3::ZERO, d, 0.0, 1.0).shear();
                    assert_eq!(
                        [s[0][j].to_bits(), s[1][j].to_bits()],
                        [ws[0].to_bits(), ws[1].to_bits()],
                        "ray {j} {d}"
                    );
                    assert_eq!([k[0][j], k[1][j]], [wk[0], wk[1]], "ray {j} {d}");
                }
            }
            // The points themselves taken apart: from an apex off the origin, `y - x` exactly.
            let x = Vec3::new(0.3, -7.25, 11.0);
            let ys: Vec<Vec3> =
                (0..64).map(|i| Vec3::new(i as f32 * 0.37, 5.0 - i as f32, (i * i) as f32 * 0.01)).collect();
            let (mut all, mut kz) = (std::array::from_fn(|_| vec![0.0; 64]), vec![0u32; 64]);
            let (mut s, mut k) = ([vec![0.0; 64], vec![0.0; 64]], [vec![0u32; 64], vec![0u32; 64]]);
            // SAFETY: AVX2 is available (checked above).
            assert_eq!(unsafe { fan_lanes_avx::<true>(&ys, x, &mut all, &mut kz, &mut s, &mut k) }, 64);
            for (j, &y) in ys.iter().enumerate() {
                let d = y - x;
                assert_eq!(
                    [all[0][j], all[1][j], all[2][j]].map(f32::to_bits),
                    d.to_array().map(f32::to_bits),
                    "point {j}"
                );
            }
        }
    }

    /// One ray at a time, the eight-box test answers as eight rays at a time, and so does one ray
    /// alone, on random boxes and directions (zero and tiny components included).
    #[test]
    fn box_tests_by_ray_and_by_block_agree() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let mut rng = crate::render::sampler::Rng::stream(10, 0, 0, 0);
            let mut r = |s: f32| (rng.next_f32() * 2.0 - 1.0) * s;
            let dirs: Vec<[f32; 3]> = (0..64)
                .map(|k| match k % 8 {
                    0 => [0.0, r(3.0), r(3.0)],
                    1 => [1e-30, r(3.0), r(3.0)],
                    _ => [r(3.0), r(3.0), r(3.0)],
                })
                .collect();
            let inv = |k: usize| dirs.iter().map(|d| inverse(d[k])).collect::<Vec<f32>>();
            let (ix, iy, iz) = (inv(0), inv(1), inv(2));
            let lanes = BoxLanes { ix: &ix, iy: &iy, iz: &iz };
            let mut met = 0;
            for round in 0..2000 {
                let (mut lo, mut hi) = ([[0f32; 8]; 3], [[0f32; 8]; 3]);
                for c in 0..8 {
                    for k in 0..3 {
                        let (a, b) = (r(2.0), r(2.0));
                        (lo[k][c], hi[k][c]) = (a.min(b), a.max(b));
                    }
                }
                let within = mix_bits(round);
                let alive = (round % 256) as u8 | 1;
                let (mut by_block, mut by_ray) = ([0u64; 8], [0u64; 8]);
                // SAFETY: AVX2 is available (checked above); 64 lanes.
                unsafe {
                    meets_boxes_avx(&lo, &hi, alive, &lanes, 0, within, &mut by_block);
                    meets_boxes_by_ray_avx(&lo, &hi, alive, &lanes, 0, within, &mut by_ray);
                }
                assert_eq!(by_block, by_ray, "round {round}");
                // One ray alone against the eight boxes (the walk's `ray_walk`) answers alike.
                for j in (0..64).filter(|j| within >> j & 1 != 0) {
                    let want = (0..8).fold(0u8, |m, c| m | u8::from(by_block[c] >> j & 1 != 0) << c);
                    assert_eq!(
                        ray_meets_boxes(&lo, &hi, alive, &lanes, j, Avx2::detect()),
                        want,
                        "round {round}, ray {j}"
                    );
                }
                met += by_ray.iter().map(|m| m.count_ones()).sum::<u32>();
            }
            assert!(met > 1000, "{met}");
        }
    }

    /// The eight-lane edge test and the scalar one clear the same lanes of a mask, only lanes of
    /// the mask, and some (over 128 lanes: two words, with blocks left out of the mask).
    #[test]
    fn sure_misses_in_lanes_and_one_by_one_agree() {
        if Avx2::detect().is_none() {
            eprintln!("no AVX2 here: only the scalar edge test exists");
            return;
        }
        let mut state = 5u64;
        let mut r = |scale: f32| {
            state = crate::render::sampler::mix64(state);
            ((state >> 40) as f32 / (1u64 << 24) as f32 - 0.5) * scale
        };
        let n = 128;
        let d: Vec<Vec3> = (0..n).map(|_| Vec3::new(r(2.0), r(2.0), 1.0 + r(1.0))).collect();
        let kz: Vec<u32> = d.iter().map(|&d| crate::geometry::RayTest::major_axis(d) as u32).collect();
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = d.iter().map(|d| (d.x, d.y, d.z)).collect();
        let len: Vec<f32> = d.iter().map(|d| d.length()).collect();
        let sz: Vec<f32> = d.iter().zip(&kz).map(|(d, &k)| 1.0 / d[k as usize]).collect();
        let lanes = Lanes { x: &x, y: &y, z: &z, len: &len, sz: &sz, kz: &kz };
        let (mut cleared, mut kept) = (0, 0);
        for round in 0..500 {
            // A triangle about the rays' cone, scaled as `Fan::test` scales its edge normals.
            let (a, b, c) = (
                Vec3::new(r(2.0), r(2.0), 0.5 + r(0.8)),
                Vec3::new(r(2.0), r(2.0), 0.5 + r(0.8)),
                Vec3::new(r(2.0), r(2.0), 0.5 + r(0.8)),
            );
            let l1 = |v: Vec3| v.abs().element_sum();
            let sc = |p: Vec3, q: Vec3| p.cross(q) * (super::super::EDGE_MARGIN * l1(p) * l1(q)).recip();
            let e = [sc(b, c), sc(c, a), sc(a, b)];
            let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
            let span = [(lo.x, hi.x), (lo.y, hi.y), (lo.z, hi.z)];
            // Two words; the second leaves whole blocks out.
            let mask = [mix_bits(round), mix_bits(round + 7) & 0x00ff_ff00_00ff_00ff];
            let (mut by_lanes, mut one_by_one) = (mask, mask);
            misses(&e, &span, &lanes, &mut by_lanes, Avx2::detect());
            misses_scalar(&e, &span, &lanes, &mut one_by_one);
            assert_eq!(by_lanes, one_by_one, "round {round}");
            for w in 0..2 {
                assert_eq!(by_lanes[w] & !mask[w], 0, "round {round}: a lane outside the mask");
                cleared += (mask[w] & !by_lanes[w]).count_ones();
                kept += by_lanes[w].count_ones();
            }
        }
        assert!(cleared > 1000 && kept > 100, "{cleared} cleared, {kept} kept");
    }

    /// Where the span test clears a lane, the watertight test misses, also where the edge
    /// functions fall below the normal range: a triangle a few `10^-21` wide across the rays, at
    /// `0.99 SEGMENT_EPS` along them (whose three rounded products once made a hit at `t = 1.5e-4`
    /// that a bound relative to the `z_i` culled) and just beyond the light; and ordinary triangles
    /// at and about both ends of the segment. The lanes cleared and the hits both occur.
    #[test]
    fn span_test_clears_only_misses_below_the_normal_range() {
        use crate::geometry::RayTest;
        let dirs = [Vec3::Z, Vec3::new(1e-3, -2e-3, 1.0), Vec3::new(0.3, 0.1, 1.0), Vec3::new(-0.2, 0.4, -1.0)];
        let d: Vec<Vec3> = (0..LANES).map(|j| dirs[j % dirs.len()] * (1.0 + j as f32 * 0.125)).collect();
        let tests: Vec<RayTest> =
            d.iter().map(|&d| RayTest::new(Vec3::ZERO, d, SEGMENT_EPS, 1.0 - SEGMENT_EPS)).collect();
        let kz: Vec<u32> = tests.iter().map(|t| t.shear().1[2]).collect();
        let sz: Vec<f32> = tests.iter().map(|t| t.shear().0[2]).collect();
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = d.iter().map(|d| (d.x, d.y, d.z)).collect();
        let len: Vec<f32> = d.iter().map(|d| d.length()).collect();
        let lanes = Lanes { x: &x, y: &y, z: &z, len: &len, sz: &sz, kz: &kz };
        let (mut cleared, mut hits) = (0, 0);
        let tiny = (0..4000).map(|i| 2.0e-21 + i as f32 * 2e-25);
        let wide = (0..400).map(|i| 1e-3 + i as f32 * 2.5e-3);
        for p in tiny.chain(wide) {
            for t in [0.0, 1e-6, 1.2e-5, 1.3e-5, 0.5e-4, 0.99e-4, 1e-4, 1.01e-4, 0.9999, 0.99991, 0.999911, 1.0, 1.0001]
            {
                for (j, ray) in d.iter().enumerate() {
                    // Across ray `j` at parameter `t` (its `z_i` are `t`, up to rounding).
                    let c = *ray * t;
                    let tri = Triangle::new(
                        c + Vec3::new(p, 0.0, 0.0),
                        c + Vec3::new(-p, p, 0.0),
                        c + Vec3::new(-p, -p, 0.0),
                    );
                    let (a, b, cc) = (tri.v[0], tri.v[1], tri.v[2]);
                    let (lo, hi) = (a.min(b).min(cc), a.max(b).max(cc));
                    let span = [(lo.x, hi.x), (lo.y, hi.y), (lo.z, hi.z)];
                    // Edge normals that clear no lane by themselves: only the span test decides.
                    let none = [Vec3::ZERO; 3];
                    for simd in [None, Avx2::detect()] {
                        let mut maybe = [(1u64 << LANES) - 1];
                        misses(&none, &span, &lanes, &mut maybe, simd);
                        let hit = tests[j].hit(&tri).is_some();
                        hits += usize::from(hit);
                        if maybe[0] >> j & 1 == 0 {
                            cleared += 1;
                            assert!(!hit, "p {p:e}, t {t}, ray {ray}: cleared but hit");
                        }
                    }
                }
            }
        }
        assert!(cleared > 10_000 && hits > 1_000, "{cleared} cleared, {hits} hits");
    }

    /// The shear lanes are [`crate::geometry::RayTest::new`]'s, bit for bit, on ordinary, tied,
    /// signed and tiny components, in whole blocks and in the scalar tail.
    #[test]
    fn shear_lanes_match_the_ray_test() {
        use crate::geometry::RayTest;
        let special = [1.0, -1.0, 1e-30, -1e-38, 3e38, -2.5, 0.1, 7.0, -7.0, 0.0, -0.0];
        let mut state = 13u64;
        let mut rnd = || {
            state = crate::render::sampler::mix64(state);
            special[(state % special.len() as u64) as usize] * if state & 1 << 40 != 0 { 1.0 } else { 3.3 }
        };
        let n = 4093;
        let d: Vec<Vec3> =
            (0..n).map(|_| Vec3::new(rnd(), rnd(), rnd())).filter(|d| d.is_finite() && *d != Vec3::ZERO).collect();
        let n = d.len();
        let tests: Vec<RayTest> = d.iter().map(|&d| RayTest::new(Vec3::ZERO, d, 0.0, 1.0)).collect();
        let (dx, dy, dz): (Vec<f32>, Vec<f32>, Vec<f32>) = d.iter().map(|d| (d.x, d.y, d.z)).collect();
        let sz: Vec<f32> = tests.iter().map(|t| t.shear().0[2]).collect();
        let kz: Vec<u32> = tests.iter().map(|t| t.shear().1[2]).collect();
        let (mut sx, mut sy, mut kx, mut ky) = (vec![0.0; n], vec![0.0; n], vec![0; n], vec![0; n]);
        shear_lanes([&dx, &dy, &dz], &sz, &kz, [&mut sx, &mut sy], [&mut kx, &mut ky]);
        for (j, t) in tests.iter().enumerate() {
            let (s, k) = t.shear();
            assert_eq!([sx[j].to_bits(), sy[j].to_bits()], [s[0].to_bits(), s[1].to_bits()], "ray {j} {}", d[j]);
            assert_eq!([kx[j], ky[j]], [k[0], k[1]], "ray {j} {}", d[j]);
        }
    }

    /// The eight-lane watertight test answers as [`crate::geometry::RayTest::hit`], lane by lane,
    /// on random rays and triangles, and on rays through a triangle's vertices and edges and along
    /// its plane (where edge functions come out zero and the scalar test must decide).
    #[test]
    fn lane_watertight_test_matches_the_scalar_one() {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            use crate::geometry::RayTest;
            let mut rng = crate::render::sampler::Rng::stream(9, 0, 0, 0);
            let mut v =
                || Vec3::new(rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 4.0 - 2.0);
            let (mut hits, mut scalar, mut total) = (0, 0, 0);
            for round in 0..4000 {
                let x = if round % 4 == 0 { Vec3::ZERO } else { v() };
                let tri = if round % 7 == 0 {
                    // Flat in x's plane, or with a vertex at x.
                    Triangle::new(x, v(), v())
                } else {
                    Triangle::new(v(), v(), v())
                };
                let targets: Vec<Vec3> = (0..LANES)
                    .map(|j| match (round + j) % 5 {
                        // Through a vertex, an edge's midpoint, the centroid, beyond it, or anywhere.
                        0 => x + (tri.v[j % 3] - x) * 2.0,
                        1 => x + ((tri.v[j % 3] + tri.v[(j + 1) % 3]) * 0.5 - x) * 1.5,
                        2 => x + ((tri.v[0] + tri.v[1] + tri.v[2]) / 3.0 - x) * 3.0,
                        3 => (tri.v[0] + tri.v[1] + tri.v[2]) / 3.0,
                        _ => v(),
                    })
                    // A ray needs a direction (a vertex at x sends "through the vertex" nowhere).
                    .map(|y| if y == x { x + Vec3::ONE } else { y })
                    .collect();
                let tests: Vec<RayTest> =
                    targets.iter().map(|&y| RayTest::new(x, y - x, SEGMENT_EPS, 1.0 - SEGMENT_EPS)).collect();
                let mut s: [Vec<f32>; 3] = Default::default();
                let mut k: [Vec<u32>; 3] = Default::default();
                for t in &tests {
                    let (ts, tk) = t.shear();
                    for i in 0..3 {
                        s[i].push(ts[i]);
                        k[i].push(tk[i]);
                    }
                }
                let shear = Shear { s: [&s[0], &s[1], &s[2]], k: [&k[0], &k[1], &k[2]] };
                // SAFETY: AVX2 is available (checked above); eight lanes.
                let (hit, to_scalar) = unsafe { exact_avx(vertices_rel(&tri, x), &shear, 0) };
                for (j, t) in tests.iter().enumerate() {
                    total += 1;
                    if to_scalar >> j & 1 != 0 {
                        scalar += 1;
                        continue;
                    }
                    let want = t.hit(&tri).is_some();
                    assert_eq!(hit >> j & 1 != 0, want, "round {round} lane {j}: {tri:?} from {x} to {}", targets[j]);
                    hits += usize::from(want);
                }
            }
            // Hits, misses and lanes left to the scalar test all occur.
            assert!(hits > 2000 && hits < total - 2000 && scalar > 100, "{hits} hits, {scalar} scalar of {total}");
        }
    }
}
