//! Morton (Z-order) codes (SPEC §8 point 4): the spatial order of long blocker lists
//! ([`crate::lie::order`]).

use glam::Vec3;

use super::Aabb;

/// The 63-bit Morton code of `p`, quantised to 2^21 steps per axis of `b`.
pub fn morton3(b: &Aabb, p: Vec3) -> u64 {
    let spread = |x: u64| {
        let mut x = x & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    };
    const STEPS: f32 = ((1 << 21) - 1) as f32;
    let size = (b.max - b.min).max(Vec3::splat(f32::MIN_POSITIVE));
    let q = ((p - b.min) / size * STEPS).clamp(Vec3::ZERO, Vec3::splat(STEPS));
    spread(q.x as u64) | spread(q.y as u64) << 1 | spread(q.z as u64) << 2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves_axes() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(morton3(&b, Vec3::ZERO), 0);
        let top = (1u64 << 21) - 1;
        assert_eq!(morton3(&b, Vec3::ONE), (1u64 << 63) - 1, "all 63 bits set at the far corner");
        // The highest bit of x is bit 60, of y 61, of z 62.
        assert_eq!(morton3(&b, Vec3::new(1.0, 0.0, 0.0)) >> 60, 1);
        assert_eq!(morton3(&b, Vec3::new(0.0, 1.0, 0.0)) >> 60, 2);
        assert_eq!(morton3(&b, Vec3::new(0.0, 0.0, 1.0)) >> 60, 4);
        assert!(top > 0);
        // Out of the box clamps; a flat box does not divide by zero.
        assert_eq!(morton3(&b, Vec3::splat(-5.0)), 0);
        let flat = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0));
        assert!(morton3(&flat, Vec3::new(0.5, 0.0, 0.5)) > 0);
    }
}
