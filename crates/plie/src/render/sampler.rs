//! Random numbers and N-rooks sampling (SPEC §2). Streams are derived by hashing the seed with the
//! pixel, the eye ray and the light, so every sample is fixed by *what* it is for, never by which
//! thread computes it: images do not depend on the thread count.

use glam::Vec2;

/// splitmix64's finaliser: a strong 64-bit mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// splitmix64's increment: the `k`-th draw of a stream is `mix64(state + k * GOLDEN)`.
const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A small counter-based generator (splitmix64).
#[derive(Clone, Copy, Debug)]
pub struct Rng(u64);

impl Rng {
    /// The stream for `(seed, a, b, c)`.
    pub fn stream(seed: u64, a: u64, b: u64, c: u64) -> Rng {
        Rng(mix64(mix64(mix64(mix64(seed) ^ a) ^ b) ^ c))
    }

    /// Next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix64(self.0)
    }

    /// Uniform in `[0, 1)`.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform integer in `0..n` (`n > 0`).
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        (((self.next_u64() >> 32) * n as u64) >> 32) as u32
    }
}

/// Fills `out` with `out.len()` N-rooks (Latin hypercube) points in the unit square: one point in each
/// column stratum and one in each row stratum, rows randomly permuted.
///
/// One 64-bit draw per point gives both jitters (24 bits each) and, for up to [`SHORT_SHUFFLE`]
/// points, the shuffle's index (the low 16 bits). The rows are shuffled inside-out (Durstenfeld's
/// forward form): point `i` takes the row of a random earlier point `j <= i`, which takes row `i`.
/// The draws are counter-based, so up to [`SHORT_SHUFFLE`] points they are made for all points at
/// once, in lanes, and the shuffle follows.
pub fn n_rooks(rng: &mut Rng, out: &mut [Vec2]) {
    let n = out.len();
    if n > SHORT_SHUFFLE {
        return n_rooks_long(rng, out);
    }
    let mut picks = [0u8; SHORT_SHUFFLE];
    let picks = &mut picks[..n];
    draw_points(rng.0, out, picks);
    rng.0 = rng.0.wrapping_add(GOLDEN.wrapping_mul(n as u64));
    for (i, &j) in picks.iter().enumerate() {
        let j = usize::from(j);
        let row = out[i].y;
        out[i].y = out[j].y;
        out[j].y = row;
    }
}

/// For each point `i` of `out`, from the stream's `i + 1`-th draw after `state`: its column
/// (jittered) in `x`, row `i` (jittered) in `y`, and in `picks` the earlier point `j <= i` whose row
/// it takes in the shuffle. Where the CPU has AVX2, as a copy compiled for it, which computes the
/// draws in lanes: integer arithmetic and the same rounded float operations, so the same points.
fn draw_points(state: u64, out: &mut [Vec2], picks: &mut [u8]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is available (checked above).
        return unsafe { draw_points_avx(state, out, picks) };
    }
    draw_points_in(state, out, picks)
}

/// [`draw_points`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx,avx2")]
unsafe fn draw_points_avx(state: u64, out: &mut [Vec2], picks: &mut [u8]) {
    draw_points_in(state, out, picks)
}

/// The body of [`draw_points`] (at most [`SHORT_SHUFFLE`] points).
#[inline(always)]
fn draw_points_in(state: u64, out: &mut [Vec2], picks: &mut [u8]) {
    let inv = 1.0 / out.len() as f32;
    let scale = 1.0 / (1u32 << 24) as f32;
    let mut counter = state;
    for (i, (p, pick)) in out.iter_mut().zip(picks.iter_mut()).enumerate() {
        let k = i as u64 + 1;
        counter = counter.wrapping_add(GOLDEN);
        let u = mix64(counter);
        let fi = (i as i32) as f32;
        let jx = ((u >> 40) as i32) as f32 * scale;
        let jy = (((u >> 16) & 0xff_ffff) as i32) as f32 * scale;
        // At most 1: `1 / n` may round up.
        p.x = ((fi + jx) * inv).min(1.0);
        p.y = ((fi + jy) * inv).min(1.0);
        *pick = (((u & 0xffff) * k) >> 16) as u8;
    }
}

/// [`n_rooks`] beyond [`SHORT_SHUFFLE`] points: the shuffle's index from a draw of its own.
fn n_rooks_long(rng: &mut Rng, out: &mut [Vec2]) {
    let n = out.len();
    let inv = 1.0 / n as f32;
    let scale = 1.0 / (1u32 << 24) as f32;
    for i in 0..n {
        let u = rng.next_u64();
        let jx = (u >> 40) as f32 * scale;
        let jy = ((u >> 16) & 0xff_ffff) as f32 * scale;
        let j = rng.below(i as u32 + 1) as usize;
        let row = ((i as f32 + jy) * inv).min(1.0);
        out[i].x = ((i as f32 + jx) * inv).min(1.0);
        out[i].y = out[j].y;
        out[j].y = row;
    }
}

/// The most points whose shuffle takes its index from the jitters' draw: 16 bits pick among at
/// most 256 rows, each with a probability within 0.4% of the others', and the index fits a byte.
pub const SHORT_SHUFFLE: usize = 256;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn n_rooks_has_one_sample_per_row_and_column() {
        let mut rng = Rng::stream(7, 1, 2, 3);
        let mut pts = vec![Vec2::ZERO; 25];
        n_rooks(&mut rng, &mut pts);
        let mut cols = [0; 25];
        let mut rows = [0; 25];
        for p in &pts {
            cols[(p.x * 25.0) as usize] += 1;
            rows[(p.y * 25.0) as usize] += 1;
        }
        assert!(cols.iter().all(|&c| c == 1) && rows.iter().all(|&r| r == 1));
    }

    #[test]
    fn n_rooks_stratifies_beyond_the_short_shuffle() {
        let n = SHORT_SHUFFLE + 44;
        let mut pts = vec![Vec2::ZERO; n];
        n_rooks(&mut Rng::stream(7, 1, 2, 4), &mut pts);
        let mut rows = vec![0; n];
        for (i, p) in pts.iter().enumerate() {
            assert_eq!((p.x * n as f32) as usize, i);
            rows[(p.y * n as f32) as usize] += 1;
        }
        assert!(rows.iter().all(|&r| r == 1));
    }

    #[test]
    fn n_rooks_draws_every_row_order_equally_often() {
        // Three points have six row orders; 60,000 draws give each about 10,000.
        let mut counts = [0u32; 6];
        let mut pts = [Vec2::ZERO; 3];
        for k in 0..60_000 {
            n_rooks(&mut Rng::stream(3, k, 0, 0), &mut pts);
            let r = pts.map(|p| (p.y * 3.0) as usize);
            counts[r[0] * 2 + usize::from(r[1] > r[2])] += 1;
        }
        assert!(counts.iter().all(|&c| (9_500..10_500).contains(&c)), "{counts:?}");
    }

    #[test]
    fn streams_differ_and_repeat() {
        let a: Vec<u64> = (0..4).map(|_| Rng::stream(1, 2, 3, 4).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(Rng::stream(1, 2, 3, 4).next_u64(), Rng::stream(1, 2, 3, 5).next_u64());
    }
}
