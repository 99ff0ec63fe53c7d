//! The Cornell family of SPEC §6: Cornell Cube 1-5 (thesis §7.1-7.5), in millimetres.
//!
//! The room follows the published Cornell box data (Cornell Program of Computer Graphics), squared off
//! so that walls meet exactly: x from 0 to 556 (the red wall at x = 556, the green one at x = 0), y from
//! 0 (floor) to 548.8 (ceiling), z from 0 (the open front) to 559.2 (back wall). The five walls face
//! into the room; the 130 x 105 mm light hangs 0.5 mm under the ceiling and emits down. The blocks are
//! the published ones (their top corners, extruded down to the floor, no bottom face). The camera is
//! the published one: (278, 273, -800) looking along +z, vertical field of view 39.3°; image right is
//! -x, so the red wall is on the left of the picture.
//!
//! Directions are SPEC §3's: Left/Right = -x/+x, Down/Up = -y/+y, Back/Front = -z/+z. Note that
//! "Front" is then the **back wall** side of the room (far from the camera).
//!
//! Cornell Cube 1: the thesis (§7.1) says the *right-bottom-front* octree cell lies in umbra on every
//! face. With the root split at the scene centre (SPEC §3) that is the octant x >= 278, y <= 274.4,
//! z >= 279.6 (the red, back, bottom corner of the room). The hovering plane, a 190 mm square, is
//! placed for it: 50 mm under the light, overhanging the light by 5 mm on the -x and -z sides and by
//! 55 and 80 mm on the +x and +z sides, so every segment from that octant to the light crosses it (the
//! worst case, the octant's top corner at the red wall and back wall, needs 39 and 42 mm), while the
//! rest of the room still gets penumbra past the plane's short overhangs. `tests/builtin.rs` checks
//! this by brute force.

use glam::Vec3;

use super::shapes::{rect, Facing};
use crate::error::Result;
use crate::geometry::Dir;
use crate::scene::{Camera, MaterialId, SceneBuilder};

/// The room's far corner: x, y, z extents in millimetres.
pub(super) const ROOM: Vec3 = Vec3::new(556.0, 548.8, 559.2);
/// Radiance of the Cornell lights: a warm white, about twice the classic (17, 12, 4) and less
/// orange, because only direct light is rendered (the classic value counts on interreflections).
const RADIANCE: Vec3 = Vec3::new(32.0, 26.0, 17.0);
/// How far lights hang in front of the surface they are mounted on.
const LIGHT_GAP: f32 = 0.5;
/// Top corners of the short block, counter-clockwise seen from above (published data).
pub(super) const SHORT_BLOCK: [Vec3; 4] = [
    Vec3::new(130.0, 0.0, 65.0),
    Vec3::new(82.0, 0.0, 225.0),
    Vec3::new(240.0, 0.0, 272.0),
    Vec3::new(290.0, 0.0, 114.0),
];
/// Height of the short block.
pub(super) const SHORT_HEIGHT: f32 = 165.0;
const TALL_BLOCK: [Vec3; 4] = [
    Vec3::new(423.0, 0.0, 247.0),
    Vec3::new(265.0, 0.0, 296.0),
    Vec3::new(314.0, 0.0, 456.0),
    Vec3::new(472.0, 0.0, 406.0),
];
const TALL_HEIGHT: f32 = 330.0;

/// The five walls (10 triangles), the ceiling light (2) and the classic camera; also returns the white
/// material (floor, ceiling and back wall) for the blocks.
pub(super) fn room(name: &str) -> Result<(SceneBuilder, MaterialId)> {
    let mut b = SceneBuilder::new(name);
    let white = b.diffuse("white", Vec3::splat(0.73));
    let red = b.diffuse("red", Vec3::new(0.63, 0.065, 0.05));
    let green = b.diffuse("green", Vec3::new(0.14, 0.45, 0.09));
    for (side, m) in [(Dir::Down, white), (Dir::Up, white), (Dir::Front, white), (Dir::Left, green), (Dir::Right, red)]
    {
        b.axis_box(Vec3::ZERO, ROOM, &[side], Facing::Inward, m);
    }
    let center = Vec3::new(278.0, ROOM.y - LIGHT_GAP, 279.5);
    // X x Z = -Y: the light emits down.
    b.light("ceiling light", &rect(center, Vec3::X * 65.0, Vec3::Z * 52.5), RADIANCE);
    b.camera(Camera::new(Vec3::new(278.0, 273.0, -800.0), Vec3::new(278.0, 273.0, 0.0), Vec3::Y, 39.3)?);
    Ok((b, white))
}

/// The short and the tall block (20 triangles).
pub(super) fn blocks(b: &mut SceneBuilder, m: MaterialId) {
    b.block_on(SHORT_BLOCK, SHORT_HEIGHT, m);
    b.block_on(TALL_BLOCK, TALL_HEIGHT, m);
}

/// The square plane of Cornell Cube 1, facing down, as a fan of four triangles around its centre (see
/// the module doc for its placement).
fn hovering_plane(b: &mut SceneBuilder, m: MaterialId) {
    let (x0, x1, z0, z1) = (208.0, 398.0, 222.0, 412.0);
    let y = ROOM.y - LIGHT_GAP - 50.0;
    let center = Vec3::new(0.5 * (x0 + x1), y, 0.5 * (z0 + z1));
    let c = rect(center, Vec3::X * (0.5 * (x1 - x0)), Vec3::Z * (0.5 * (z1 - z0)));
    for k in 0..4 {
        b.triangle(center, c[k], c[(k + 1) % 4], m);
    }
}

/// Cornell Cube 1: room, light and the hovering plane (16 triangles).
pub(super) fn cube1() -> Result<SceneBuilder> {
    let (mut b, white) = room("cornell-cube-1")?;
    hovering_plane(&mut b, white);
    Ok(b)
}

/// Cornell Cube 2: the classic box (32 triangles).
pub(super) fn cube2() -> Result<SceneBuilder> {
    let (mut b, white) = room("cornell-cube-2")?;
    blocks(&mut b, white);
    Ok(b)
}

/// Cornell Cube 3: room, light and two spheres of 960 triangles (1932 triangles).
pub(super) fn cube3() -> Result<SceneBuilder> {
    let (mut b, white) = room("cornell-cube-3")?;
    b.sphere(Vec3::new(380.0, 110.0, 370.0), 110.0, 32, 16, white);
    b.sphere(Vec3::new(160.0, 80.0, 170.0), 80.0, 32, 16, white);
    Ok(b)
}

/// Cornell Cube 4: Cornell Cube 2 and a second light high on the green wall, shining across the room
/// (34 triangles).
pub(super) fn cube4() -> Result<SceneBuilder> {
    let (mut b, white) = room("cornell-cube-4")?;
    blocks(&mut b, white);
    // Y x Z = +X: into the room.
    b.light("wall light", &rect(Vec3::new(LIGHT_GAP, 420.0, 300.0), Vec3::Y * 52.5, Vec3::Z * 65.0), RADIANCE);
    Ok(b)
}

/// Cornell Cube 5: Cornell Cube 1 and a second light on the back wall, shining toward the open front
/// (18 triangles).
pub(super) fn cube5() -> Result<SceneBuilder> {
    let (mut b, white) = room("cornell-cube-5")?;
    hovering_plane(&mut b, white);
    // Y x X = -Z: toward the camera.
    let center = Vec3::new(278.0, 380.0, ROOM.z - LIGHT_GAP);
    b.light("back light", &rect(center, Vec3::Y * 52.5, Vec3::X * 65.0), RADIANCE);
    Ok(b)
}
