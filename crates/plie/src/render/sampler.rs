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
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
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
/// column stratum and one in each row stratum, rows randomly permuted. `perm` is scratch space.
pub fn n_rooks(rng: &mut Rng, out: &mut [Vec2], perm: &mut Vec<u32>) {
    let n = out.len() as u32;
    perm.clear();
    perm.extend(0..n);
    for i in (1..n).rev() {
        let j = rng.below(i + 1);
        perm.swap(i as usize, j as usize);
    }
    let inv = 1.0 / n as f32;
    for (i, p) in out.iter_mut().enumerate() {
        let x = (i as f32 + rng.next_f32()) * inv;
        let y = (perm[i] as f32 + rng.next_f32()) * inv;
        *p = Vec2::new(x.min(1.0), y.min(1.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn n_rooks_has_one_sample_per_row_and_column() {
        let mut rng = Rng::stream(7, 1, 2, 3);
        let mut pts = vec![Vec2::ZERO; 25];
        let mut perm = Vec::new();
        n_rooks(&mut rng, &mut pts, &mut perm);
        let mut cols = [0; 25];
        let mut rows = [0; 25];
        for p in &pts {
            cols[(p.x * 25.0) as usize] += 1;
            rows[(p.y * 25.0) as usize] += 1;
        }
        assert!(cols.iter().all(|&c| c == 1) && rows.iter().all(|&r| r == 1));
    }

    #[test]
    fn streams_differ_and_repeat() {
        let a: Vec<u64> = (0..4).map(|_| Rng::stream(1, 2, 3, 4).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(Rng::stream(1, 2, 3, 4).next_u64(), Rng::stream(1, 2, 3, 5).next_u64());
    }
}
