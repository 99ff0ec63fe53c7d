//! Morton (Z-order) codes and the spatial order of long blocker lists (SPEC §8 point 4).
//!
//! The construction stores every blocker list of at least [`crate::lie::CHUNKED_MIN`] triangles in
//! the Morton order of its triangles' box centres, quantised within the list's own bounding box, so
//! consecutive triangles lie close together; the visibility then puts a box around every chunk of
//! [`crate::lie::CHUNK`] of them (and every group of chunks) and a shadow ray skips the chunks it
//! misses. The order never changes an answer: a list is a set of candidates.

use glam::Vec3;

use super::Aabb;
use crate::scene::{Scene, TriId};

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

/// Sorts `list` (triangles of `scene`) by the Morton code of their box centres within the list's
/// bounding box; ties by id, so the order is a function of the set.
pub fn sort_spatially(scene: &Scene, list: &mut [TriId]) {
    let Some(bounds) = list.iter().map(|t| scene.triangles[t.idx()].aabb()).reduce(Aabb::union) else {
        return;
    };
    list.sort_by_cached_key(|t| (morton3(&bounds, scene.triangles[t.idx()].aabb().center()), *t));
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
