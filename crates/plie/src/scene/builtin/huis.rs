//! The Huis ("house") scenes of SPEC §6 (thesis §7.6-7.8), in metres: an office of 5.0 x 2.7 x 4.2 m
//! (x right, y up, z from the front wall at 0 to the back wall at 4.2) with walls, floor and ceiling
//! facing in, and one central 0.6 x 0.6 m ceiling light hanging 5 mm under the ceiling.
//!
//! - Huis A: two bookcases against the back wall, with shelves, books, stacks and boxes; a desk in the
//!   back-right corner with a lamp, a mug and papers; an office chair (star base) in front of it; a
//!   round side table with a globe on a rug; a plant, a waste bin, a door, a window with a radiator
//!   under it, pictures. The shadows under the chair and between the shelves are the complex ones.
//! - Huis B: the same room in other colours, plain bookcases with ring binders, a flat screen with
//!   keyboard and mouse on the desk, a finer chair and globe, a second plant.
//! - Huis C: Huis B with a second ceiling light over the front of the room, outside the camera's view.
//!
//! The camera stands in the front-right corner at eye height and looks across the room to the
//! bookcases; the central light is in view near the top of the picture.

use glam::Vec3;

use super::chair::{office_chair, ChairDetail, ChairPaint};
use super::decor;
use super::furniture::{bookcase, desk, round_table, Bookcase, Shelving};
use super::shapes::{rect, Facing, Place};
use crate::error::Result;
use crate::geometry::Dir;
use crate::scene::{Camera, MaterialId, SceneBuilder};

/// The room's far corner.
const ROOM: Vec3 = Vec3::new(5.0, 2.7, 4.2);
/// Radiance of the ceiling lights (a warm white).
const RADIANCE: Vec3 = Vec3::new(48.0, 45.0, 40.0);
/// Height of the desk top.
const DESK_TOP: f32 = 0.75;

/// The colours of one variant.
struct Palette {
    walls: Vec3,
    floor: Vec3,
    ceiling: Vec3,
    case_wood: Vec3,
    desk_wood: Vec3,
    cushion: Vec3,
    covers: [Vec3; 6],
    accent: Vec3,
}

const PALETTE_A: Palette = Palette {
    walls: Vec3::new(0.72, 0.66, 0.55),
    floor: Vec3::new(0.42, 0.28, 0.16),
    ceiling: Vec3::splat(0.8),
    case_wood: Vec3::new(0.36, 0.22, 0.12),
    desk_wood: Vec3::new(0.6, 0.45, 0.28),
    cushion: Vec3::new(0.12, 0.18, 0.45),
    covers: [
        Vec3::new(0.55, 0.1, 0.08),
        Vec3::new(0.1, 0.25, 0.5),
        Vec3::new(0.12, 0.4, 0.15),
        Vec3::new(0.75, 0.65, 0.35),
        Vec3::new(0.3, 0.12, 0.35),
        Vec3::new(0.8, 0.78, 0.7),
    ],
    accent: Vec3::new(0.7, 0.25, 0.1),
};

const PALETTE_B: Palette = Palette {
    walls: Vec3::new(0.58, 0.64, 0.7),
    floor: Vec3::new(0.3, 0.3, 0.32),
    ceiling: Vec3::splat(0.82),
    case_wood: Vec3::splat(0.78),
    desk_wood: Vec3::new(0.75, 0.74, 0.7),
    cushion: Vec3::new(0.55, 0.08, 0.06),
    covers: [
        Vec3::new(0.1, 0.1, 0.12),
        Vec3::new(0.85, 0.75, 0.1),
        Vec3::new(0.1, 0.45, 0.55),
        Vec3::new(0.6, 0.6, 0.6),
        Vec3::new(0.75, 0.3, 0.1),
        Vec3::new(0.2, 0.5, 0.2),
    ],
    accent: Vec3::new(0.15, 0.35, 0.6),
};

/// The materials shared by the pieces.
struct Mats {
    walls: MaterialId,
    case_wood: MaterialId,
    desk_wood: MaterialId,
    metal: MaterialId,
    black: MaterialId,
    cushion: MaterialId,
    covers: Vec<MaterialId>,
    cardboard: MaterialId,
    accent: MaterialId,
    white: MaterialId,
    leaf: MaterialId,
    soil: MaterialId,
    sea: MaterialId,
}

/// Which Huis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Variant {
    A,
    B,
}

/// Huis A (about 4913 triangles, one light).
pub(super) fn huis_a() -> Result<SceneBuilder> {
    office("huis-a", Variant::A)
}

/// Huis B (about 5789 triangles, one light).
pub(super) fn huis_b() -> Result<SceneBuilder> {
    office("huis-b", Variant::B)
}

/// Huis C: Huis B with a second light over the front of the room, out of the camera's view.
pub(super) fn huis_c() -> Result<SceneBuilder> {
    let mut b = office("huis-c", Variant::B)?;
    let center = Vec3::new(1.4, ROOM.y - 0.005, 0.7);
    b.light("front ceiling light", &rect(center, Vec3::X * 0.25, Vec3::Z * 0.25), RADIANCE);
    Ok(b)
}

/// The room, its light and camera, and the furniture of `variant`.
fn office(name: &str, variant: Variant) -> Result<SceneBuilder> {
    let pal = match variant {
        Variant::A => &PALETTE_A,
        Variant::B => &PALETTE_B,
    };
    let mut b = SceneBuilder::new(name);
    let m = materials(&mut b, pal);
    let floor = b.diffuse("floor", pal.floor);
    let ceiling = b.diffuse("ceiling", pal.ceiling);
    b.axis_box(Vec3::ZERO, ROOM, &[Dir::Down], Facing::Inward, floor);
    b.axis_box(Vec3::ZERO, ROOM, &[Dir::Up], Facing::Inward, ceiling);
    b.axis_box(Vec3::ZERO, ROOM, &[Dir::Left, Dir::Right, Dir::Back, Dir::Front], Facing::Inward, m.walls);
    let center = Vec3::new(0.5 * ROOM.x, ROOM.y - 0.005, 0.5 * ROOM.z);
    // X x Z = -Y: the light emits down.
    b.light("ceiling light", &rect(center, Vec3::X * 0.3, Vec3::Z * 0.3), RADIANCE);
    let eye = Vec3::new(4.4, 1.75, 0.25);
    b.camera(Camera::new(eye, Vec3::new(2.0, 1.0, 4.0), Vec3::Y, 65.0)?);
    bookcases(&mut b, &m, variant);
    work_place(&mut b, &m, variant);
    furnishings(&mut b, &m, variant);
    Ok(b)
}

fn materials(b: &mut SceneBuilder, pal: &Palette) -> Mats {
    Mats {
        walls: b.diffuse("walls", pal.walls),
        case_wood: b.diffuse("bookcase", pal.case_wood),
        desk_wood: b.diffuse("desk", pal.desk_wood),
        metal: b.diffuse("metal", Vec3::splat(0.55)),
        black: b.diffuse("black plastic", Vec3::splat(0.05)),
        cushion: b.diffuse("cushion", pal.cushion),
        covers: pal.covers.iter().enumerate().map(|(i, &c)| b.diffuse(&format!("cover {i}"), c)).collect(),
        cardboard: b.diffuse("cardboard", Vec3::new(0.62, 0.48, 0.3)),
        accent: b.diffuse("accent", pal.accent),
        white: b.diffuse("paper", Vec3::splat(0.85)),
        leaf: b.diffuse("leaf", Vec3::new(0.12, 0.38, 0.08)),
        soil: b.diffuse("soil", Vec3::new(0.2, 0.13, 0.08)),
        sea: b.diffuse("globe", Vec3::new(0.12, 0.3, 0.6)),
    }
}

/// Two bookcases side by side against the back wall, facing into the room.
fn bookcases(b: &mut SceneBuilder, m: &Mats, variant: Variant) {
    let shelving = Shelving { wood: m.case_wood, covers: m.covers.clone(), boxes: m.cardboard };
    let kind = if variant == Variant::A { Bookcase::Detailed } else { Bookcase::Simple };
    for (k, right_end) in [1.35f32, 2.5].into_iter().enumerate() {
        // Turned 180 degrees: local x runs toward -x, local z (the front) toward -z.
        let at = Place::new(Vec3::new(right_end, 0.0, ROOM.z - 0.005), 180.0);
        bookcase(b, &at, kind, &shelving, 7 + k as u32);
    }
}

/// The desk in the back-right corner, what stands on it, and the chair in front of it.
fn work_place(b: &mut SceneBuilder, m: &Mats, variant: Variant) {
    let desk_at = Place::new(Vec3::new(4.7, 0.0, ROOM.z - 0.05), 180.0);
    desk(b, &desk_at, m.desk_wood, m.metal);
    let on_desk = |x: f32, z: f32, yaw: f32| Place::new(Vec3::new(x, DESK_TOP, z), yaw);
    decor::desk_lamp(b, &on_desk(4.5, 3.95, 200.0), m.metal, m.accent);
    decor::open_vessel(b, &on_desk(3.35, 3.6, 0.0), 0.035, 0.04, 0.1, 0.004, 12, m.accent);
    for (k, h) in [0.004f32, 0.008, 0.012].into_iter().enumerate() {
        let at = on_desk(3.6 + 0.01 * k as f32, 3.75, 8.0 * k as f32);
        b.local_box(&at, Vec3::new(-0.105, h - 0.004, -0.15), Vec3::new(0.105, h, 0.15), m.white);
    }
    let detail = match variant {
        Variant::A => ChairDetail { cushion_segments: 22, cushion_bands: 8, wheel_segments: 8 },
        Variant::B => {
            decor::flat_screen(b, &on_desk(3.95, 3.95, 0.0), m.black, m.black);
            decor::keyboard(b, &on_desk(3.95, 3.62, 0.0), m.black, m.metal, 5, 14);
            decor::mouse(b, &on_desk(4.32, 3.62, 0.0), m.black);
            ChairDetail { cushion_segments: 24, cushion_bands: 8, wheel_segments: 10 }
        }
    };
    let paint = ChairPaint { frame: m.black, plastic: m.black, cushion: m.cushion };
    office_chair(b, &Place::new(Vec3::new(3.95, 0.0, 2.95), 20.0), paint, detail);
    decor::open_vessel(b, &Place::new(Vec3::new(2.95, 0.0, 3.15), 0.0), 0.12, 0.15, 0.35, 0.01, 16, m.metal);
}

/// Side table with a globe on a rug, plants, door, window, radiator and pictures.
fn furnishings(b: &mut SceneBuilder, m: &Mats, variant: Variant) {
    let v = Vec3::new;
    b.axis_box(v(0.9, 0.002, 1.4), v(2.5, 0.012, 2.7), &Dir::ALL, Facing::Outward, m.accent);
    let table = Place::new(v(1.7, 0.0, 2.05), 0.0);
    round_table(b, &table, m.desk_wood, m.metal, 32);
    let globe_segments = if variant == Variant::A { 16 } else { 20 };
    decor::globe(b, &table.then(v(0.05, 0.73, 0.0), 30.0), m.sea, m.metal, globe_segments);
    decor::plant(b, &Place::new(v(0.45, 0.0, 3.2), 0.0), m.accent, m.soil, m.leaf, 18);
    // Fittings on the walls: local z = 0 on the wall, local z pointing into the room.
    let left_wall = |z: f32| Place::new(v(0.0, 0.0, z), 90.0);
    let right_wall = |z: f32| Place::new(v(ROOM.x, 0.0, z), -90.0);
    decor::door(b, &left_wall(2.2), m.desk_wood, m.white, m.metal);
    decor::window(b, &right_wall(1.3), m.white, m.covers[2]);
    decor::radiator(b, &right_wall(1.5), m.white, 10);
    decor::picture(b, &left_wall(3.6).then(v(0.0, 1.3, 0.0), 0.0), 0.6, 0.45, m.case_wood, m.covers[3]);
    let back_wall = |x: f32| Place::new(v(x, 0.0, ROOM.z), 180.0);
    decor::picture(b, &back_wall(4.4).then(v(0.0, 1.35, 0.0), 0.0), 0.9, 0.6, m.black, m.covers[4]);
}
