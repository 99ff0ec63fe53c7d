//! Smaller objects that furnish the Huis scenes (SPEC §6, thesis §7.6-7.8): a desk lamp, a globe, a
//! pot plant, a waste bin, mugs, a flat screen with keyboard and mouse (Huis B and C), and the room's
//! fittings (door, window, radiator, pictures). Metres, local frames as in `furniture`.

use glam::{Vec2, Vec3};

use super::shapes::{ellipse, hash01, Cap, Node, Place};
use crate::scene::{MaterialId, SceneBuilder};

/// An adjustable desk lamp: round foot, a two-part arm and a conical shade (about 190 triangles).
pub(super) fn desk_lamp(b: &mut SceneBuilder, at: &Place, metal: MaterialId, shade: MaterialId) {
    let v = Vec3::new;
    b.cylinder(at.p(v(0.0, 0.0, 0.0)), at.p(v(0.0, 0.02, 0.0)), 0.08, 0.075, 16, metal);
    let arm = [
        Node::round(at.p(v(0.0, 0.015, 0.0)), 0.01),
        Node::round(at.p(v(0.02, 0.25, -0.05)), 0.009),
        Node::round(at.p(v(0.05, 0.42, 0.12)), 0.008),
        Node::round(at.p(v(0.06, 0.40, 0.2)), 0.008),
    ];
    b.tube(&arm, at.dir(Vec3::X), 6, Cap::Flat, false, metal);
    // The shade opens downward and forward from the end of the arm.
    b.cylinder(at.p(v(0.06, 0.41, 0.2)), at.p(v(0.065, 0.3, 0.28)), 0.025, 0.075, 16, shade);
}

/// A desk globe: foot, post, a half meridian arc and the sphere (about 800 triangles).
pub(super) fn globe(b: &mut SceneBuilder, at: &Place, sea: MaterialId, metal: MaterialId, segments: usize) {
    let v = Vec3::new;
    let (r, c) = (0.15, v(0.0, 0.25, 0.0));
    b.cylinder(at.p(v(0.0, 0.0, 0.0)), at.p(v(0.0, 0.025, 0.0)), 0.09, 0.08, 16, metal);
    // The meridian: a tube along a half circle around the tilted axis, just outside the sphere; the
    // post carries its lower end.
    let tilt = 23.5f32.to_radians();
    let axis = at.dir(v(tilt.sin(), tilt.cos(), 0.0));
    b.cylinder(at.p(v(0.0, 0.025, 0.0)), at.p(c) - axis * (r + 0.012), 0.012, 0.012, 8, metal);
    let side = at.dir(Vec3::Z);
    let arc: Vec<Node> = (0..=12)
        .map(|k| {
            let t = std::f32::consts::PI * (k as f32 / 12.0 - 0.5);
            let p = at.p(c) + (axis.cross(side) * t.cos() + axis * t.sin()) * -(r + 0.012);
            Node::round(p, 0.006)
        })
        .collect();
    b.tube(&arc, side, 6, Cap::Flat, false, metal);
    b.sphere(at.p(c), r, segments, segments / 2, sea);
}

/// A pot plant: a tapered pot, soil, and `leaves` arching leaves (one-sided strips) rising from it.
pub(super) fn plant(
    b: &mut SceneBuilder,
    at: &Place,
    pot: MaterialId,
    soil: MaterialId,
    leaf: MaterialId,
    leaves: u32,
) {
    let v = Vec3::new;
    open_vessel(b, at, 0.11, 0.15, 0.3, 0.012, 16, pot);
    b.cylinder(at.p(v(0.0, 0.2, 0.0)), at.p(v(0.0, 0.26, 0.0)), 0.12, 0.13, 16, soil);
    for k in 0..leaves {
        let h = |i: u32| hash01(4242, k * 5 + i);
        let yaw = 360.0 * (k as f32 * 0.618_034).fract();
        let leaf_at = at.then(v(0.0, 0.26, 0.0), yaw);
        let (len, rise, width) = (0.25 + 0.2 * h(0), 0.6 + 0.6 * h(1), 0.035 + 0.025 * h(2));
        // A strip of quads along the leaf, arching up then out; widest in the middle.
        let n = 4;
        let pts: Vec<(Vec3, f32)> = (0..=n)
            .map(|i| {
                let s = i as f32 / n as f32;
                let p = v(len * s, len * rise * (1.2 * s - 0.7 * s * s), 0.0);
                let w = width * (std::f32::consts::PI * (0.15 + 0.85 * s)).sin().max(0.15);
                (p, w)
            })
            .collect();
        for i in 0..n {
            let (p0, w0) = pts[i];
            let (p1, w1) = pts[i + 1];
            let q = |p: Vec3, w: f32| leaf_at.p(p + v(0.0, 0.0, w));
            b.quad(q(p0, w0), q(p1, w1), q(p1, -w1), q(p0, -w0), leaf);
        }
    }
}

/// An open vessel with walls of thickness `wall`: bottom radius `r0`, rim radius `r1`, height `h`.
/// Closed surface (outside, rim, inside, inner floor): `10 * segments` triangles.
#[allow(clippy::too_many_arguments)]
pub(super) fn open_vessel(
    b: &mut SceneBuilder,
    at: &Place,
    r0: f32,
    r1: f32,
    h: f32,
    wall: f32,
    segments: usize,
    m: MaterialId,
) {
    let (x, z) = (at.dir(Vec3::X), at.dir(Vec3::Z));
    let ring = |y: f32, r: f32| ellipse(at.p(Vec3::Y * y), z, x, Vec2::splat(r), segments, 0.0);
    let rings = [
        vec![at.p(Vec3::ZERO)],
        ring(0.0, r0),
        ring(h, r1),
        ring(h, r1 - wall),
        ring(wall, r0 - wall),
        vec![at.p(Vec3::Y * wall)],
    ];
    b.rings(&rings, false, m);
}

/// A flat screen on a foot: foot plate, neck, housing and the dark panel in front.
pub(super) fn flat_screen(b: &mut SceneBuilder, at: &Place, housing: MaterialId, panel: MaterialId) {
    let v = Vec3::new;
    b.local_box(at, v(-0.12, 0.0, -0.09), v(0.12, 0.012, 0.09), housing);
    b.local_box(at, v(-0.03, 0.012, -0.03), v(0.03, 0.2, -0.01), housing);
    b.local_box(at, v(-0.3, 0.12, -0.01), v(0.3, 0.48, 0.025), housing);
    b.local_box(at, v(-0.29, 0.135, 0.025), v(0.29, 0.47, 0.03), panel);
}

/// A keyboard: a base plate and `rows x cols` keys (plus a space bar), each a closed box.
pub(super) fn keyboard(b: &mut SceneBuilder, at: &Place, base: MaterialId, keys: MaterialId, rows: u32, cols: u32) {
    let v = Vec3::new;
    let pitch = 0.019;
    let (w, d) = (pitch * cols as f32 + 0.02, pitch * (rows + 1) as f32 + 0.02);
    b.local_box(at, v(-0.5 * w, 0.0, -0.5 * d), v(0.5 * w, 0.015, 0.5 * d), base);
    let key = |b: &mut SceneBuilder, x0: f32, x1: f32, z: f32| {
        b.local_box(at, v(x0, 0.015, z - 0.0075), v(x1, 0.024, z + 0.0075), keys);
    };
    for r in 0..rows {
        let z = -0.5 * d + 0.01 + pitch * (r as f32 + 0.5);
        for c in 0..cols {
            let x = -0.5 * w + 0.01 + pitch * c as f32;
            key(b, x + 0.002, x + pitch - 0.002, z);
        }
    }
    let z = -0.5 * d + 0.01 + pitch * (rows as f32 + 0.5);
    key(b, -0.3 * w, 0.3 * w, z);
}

/// A computer mouse: a flattened superellipsoid.
pub(super) fn mouse(b: &mut SceneBuilder, at: &Place, m: MaterialId) {
    let center = at.p(Vec3::new(0.0, 0.016, 0.0));
    let frame = [at.dir(Vec3::X), Vec3::Y, at.dir(Vec3::Z)];
    b.superellipsoid(center, frame, Vec3::new(0.03, 0.016, 0.055), 0.7, 12, 6, m);
}

/// A door in the wall behind `at` (local z = 0 is the wall's surface): frame, slab and lever handle.
pub(super) fn door(b: &mut SceneBuilder, at: &Place, frame: MaterialId, slab: MaterialId, metal: MaterialId) {
    let v = Vec3::new;
    let (w, h) = (0.9, 2.05);
    b.local_box(at, v(-0.06, 0.0, 0.0), v(0.0, h + 0.06, 0.03), frame);
    b.local_box(at, v(w, 0.0, 0.0), v(w + 0.06, h + 0.06, 0.03), frame);
    b.local_box(at, v(0.0, h, 0.0), v(w, h + 0.06, 0.03), frame);
    b.local_box(at, v(0.0, 0.005, 0.0), v(w, h, 0.015), slab);
    b.cylinder(at.p(v(w - 0.08, 1.05, 0.015)), at.p(v(w - 0.08, 1.05, 0.07)), 0.012, 0.012, 8, metal);
    b.local_box(at, v(w - 0.2, 1.04, 0.06), v(w - 0.07, 1.06, 0.08), metal);
}

/// A window in the wall behind `at`: a light pane in a frame with a cross bar, and a sill.
pub(super) fn window(b: &mut SceneBuilder, at: &Place, frame: MaterialId, pane: MaterialId) {
    let v = Vec3::new;
    let (x0, x1, y0, y1) = (0.0, 1.4, 0.9, 2.2);
    let t = 0.06;
    b.local_box(at, v(x0, y0, 0.0), v(x1, y1, 0.005), pane);
    b.local_box(at, v(x0 - t, y0 - t, 0.0), v(x0, y1 + t, 0.05), frame);
    b.local_box(at, v(x1, y0 - t, 0.0), v(x1 + t, y1 + t, 0.05), frame);
    b.local_box(at, v(x0, y1, 0.0), v(x1, y1 + t, 0.05), frame);
    b.local_box(at, v(x0, y0 - t, 0.0), v(x1, y0, 0.05), frame);
    b.local_box(at, v(0.5 * (x0 + x1) - 0.025, y0, 0.005), v(0.5 * (x0 + x1) + 0.025, y1, 0.04), frame);
    b.local_box(at, v(x0, 0.5 * (y0 + y1) - 0.025, 0.005), v(x1, 0.5 * (y0 + y1) + 0.025, 0.04), frame);
    b.local_box(at, v(x0 - 0.1, y0 - t - 0.03, 0.0), v(x1 + 0.1, y0 - t, 0.2), frame);
}

/// A panel radiator on the wall behind `at`: `fins` vertical fins between two pipes.
pub(super) fn radiator(b: &mut SceneBuilder, at: &Place, m: MaterialId, fins: u32) {
    let v = Vec3::new;
    let pitch = 0.1;
    let w = pitch * fins as f32;
    for k in 0..fins {
        let x = pitch * k as f32;
        b.local_box(at, v(x + 0.01, 0.15, 0.04), v(x + pitch - 0.01, 0.75, 0.09), m);
    }
    for y in [0.2, 0.7] {
        b.cylinder(at.p(v(-0.03, y, 0.065)), at.p(v(w + 0.03, y, 0.065)), 0.015, 0.015, 8, m);
    }
    for x in [0.02, w - 0.02] {
        b.local_box(at, v(x - 0.01, 0.4, 0.0), v(x + 0.01, 0.44, 0.04), m);
    }
}

/// A picture on the wall behind `at`: frame and canvas, `w` x `h`, bottom-left corner at the origin.
pub(super) fn picture(b: &mut SceneBuilder, at: &Place, w: f32, h: f32, frame: MaterialId, canvas: MaterialId) {
    let v = Vec3::new;
    b.local_box(at, v(0.0, 0.0, 0.0), v(w, h, 0.025), frame);
    b.local_box(at, v(0.04, 0.04, 0.025), v(w - 0.04, h - 0.04, 0.03), canvas);
}
