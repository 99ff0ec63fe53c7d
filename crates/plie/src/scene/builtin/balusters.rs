//! The stress scene of issue 15 (not a thesis scene): a room, 4 x 3 x 4 metres, whose floor carries an
//! `n x n` grid of thin square rods (balusters, 2 cm thick, 2.2 m high), lit by one small light (30 x
//! 30 cm) under the middle of the ceiling. Every shaft from a face below the rods' tops to the light
//! crosses hundreds of rods: the case where flat per-record blocker lists (SPEC §4.4) grow as records
//! times shaft triangles. `balusters` is the full size (`n = 64`, 40,974 triangles, for `plie bench`);
//! `balusters-N` any `n` from 1 to [`MAX_RODS`] (the tests use small ones).

use glam::Vec3;

use super::shapes::{rect, Facing, NO_BOTTOM};
use crate::error::Result;
use crate::geometry::Dir;
use crate::scene::{Camera, SceneBuilder};

/// Rods per side of the full-size scene.
pub const FULL_RODS: u32 = 64;
/// Most rods per side `balusters-N` accepts.
pub const MAX_RODS: u32 = 256;

/// The room's far corner (metres; the near corner is the origin).
const ROOM: Vec3 = Vec3::new(4.0, 3.0, 4.0);
/// Rod cross-section (metres) and height.
const ROD_WIDTH: f32 = 0.02;
const ROD_HEIGHT: f32 = 2.2;
/// The rods stand in the square `[MARGIN, ROOM - MARGIN]` of the floor.
const MARGIN: f32 = 0.5;

/// The number of rods per side named by `name` (`balusters` or `balusters-N`), if it is one.
pub fn rods_of(name: &str) -> Option<u32> {
    if name == "balusters" {
        return Some(FULL_RODS);
    }
    let n: u32 = name.strip_prefix("balusters-")?.parse().ok()?;
    (1..=MAX_RODS).contains(&n).then_some(n)
}

/// The scene with `n x n` rods (`10 n² + 14` triangles).
pub(super) fn balusters(name: &str, n: u32) -> Result<SceneBuilder> {
    let mut b = SceneBuilder::new(name);
    let wall = b.diffuse("wall", Vec3::splat(0.7));
    let wood = b.diffuse("wood", Vec3::new(0.55, 0.38, 0.22));
    b.axis_box(Vec3::ZERO, ROOM, &Dir::ALL, Facing::Inward, wall);
    let pitch = (ROOM.x - 2.0 * MARGIN) / n as f32;
    for i in 0..n {
        for k in 0..n {
            let c = Vec3::new(MARGIN + pitch * (i as f32 + 0.5), 0.0, MARGIN + pitch * (k as f32 + 0.5));
            let h = Vec3::new(0.5 * ROD_WIDTH, 0.0, 0.5 * ROD_WIDTH);
            b.axis_box(c - h, c + h + Vec3::Y * ROD_HEIGHT, &NO_BOTTOM, Facing::Outward, wood);
        }
    }
    // X x Z = -Y: the light emits down.
    let center = Vec3::new(0.5 * ROOM.x, ROOM.y - 0.01, 0.5 * ROOM.z);
    b.light("ceiling light", &rect(center, Vec3::X * 0.15, Vec3::Z * 0.15), Vec3::splat(60.0));
    b.camera(Camera::new(Vec3::new(2.0, 2.6, 0.05), Vec3::new(2.0, 0.6, 3.0), Vec3::Y, 70.0)?);
    Ok(b)
}
