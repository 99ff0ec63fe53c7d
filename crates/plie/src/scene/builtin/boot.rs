//! The Boot ("boat") scene of SPEC §6 (thesis §7.10), in metres: a 9.6 m sailing yacht floating on a
//! 70 x 70 m water plane, lit by one small light (3 x 3 m) about 40 m away, high up behind the
//! camera and out of its view. Apart from the boat's own shadow on the water there are hardly any
//! shadows, so the top faces of most octree cells see the light unblocked.
//!
//! The boat (bow toward +x, waterline at y = 0, centreline z = 0): a hull swept through cross-sections
//! from the transom to the bow, closed by a cambered deck (one watertight surface, hull and deck in
//! their own colours); a rounded cabin with windows, a hatch and a cockpit coaming; a mast, a boom, a
//! mainsail and a jib (one-sided sheets), stays, a railing of stanchions and lifelines, and a lifebuoy
//! on the stern.

use glam::Vec3;

use super::shapes::{any_perpendicular, rect, Cap, Facing, Node};
use crate::error::Result;
use crate::geometry::Dir;
use crate::scene::{Camera, MaterialId, SceneBuilder};

/// Radiance of the distant light.
const RADIANCE: Vec3 = Vec3::new(420.0, 400.0, 370.0);
/// Stern and bow of the hull.
const STERN: f32 = -4.6;
const BOW: f32 = 5.0;
/// Cross-sections along the hull.
const STATIONS: usize = 39;
/// Points down one side of a cross-section (keel excluded) and across the deck (sheer excluded).
const SIDE: usize = 10;
const DECK: usize = 5;
/// Height of the mast top.
const MAST_TOP: f32 = 13.0;

/// The Boot scene.
pub(super) fn boot() -> Result<SceneBuilder> {
    let mut b = SceneBuilder::new("boot");
    let water = b.diffuse("water", Vec3::new(0.08, 0.22, 0.3));
    let hull = b.diffuse("hull", Vec3::splat(0.82));
    let teak = b.diffuse("deck", Vec3::new(0.55, 0.4, 0.24));
    let cabin = b.diffuse("cabin", Vec3::new(0.86, 0.83, 0.74));
    let dark = b.diffuse("windows", Vec3::splat(0.05));
    let metal = b.diffuse("metal", Vec3::splat(0.6));
    let sail = b.diffuse("sail", Vec3::new(0.86, 0.84, 0.8));
    let buoy = b.diffuse("lifebuoy", Vec3::new(0.85, 0.3, 0.05));
    b.quad(
        Vec3::new(-35.0, 0.0, -35.0),
        Vec3::new(-35.0, 0.0, 35.0),
        Vec3::new(35.0, 0.0, 35.0),
        Vec3::new(35.0, 0.0, -35.0),
        water,
    );
    hull_and_deck(&mut b, hull, teak);
    superstructure(&mut b, cabin, dark, teak);
    rig(&mut b, metal, sail);
    railing(&mut b, metal);
    b.torus(Vec3::new(STERN - 0.06, 0.75, 0.0), Vec3::X, 0.3, 0.07, 20, 8, buoy);
    // The light: high up behind the camera, facing the boat.
    let center = Vec3::new(26.0, 16.0, -8.0);
    let n = (Vec3::new(0.0, 1.0, 0.0) - center).normalize();
    let u = any_perpendicular(n) * 1.5;
    b.light("sun", &rect(center, u, n.cross(u)), RADIANCE);
    b.camera(Camera::new(Vec3::new(12.5, 4.5, -14.0), Vec3::new(0.0, 5.6, 0.0), Vec3::Y, 48.0)?);
    Ok(b)
}

/// Height of the deck edge (sheer) at `x`: rising toward the bow.
fn sheer(x: f32) -> f32 {
    let t = (x - STERN) / (BOW - STERN);
    0.9 + 0.4 * t * t
}

/// Half-beam at deck level at `x`: fullest a third of the way from the stern, fine at the bow.
fn half_beam(x: f32) -> f32 {
    let t = (x - STERN) / (BOW - STERN);
    (1.6 * (std::f32::consts::PI * (0.35 + 0.65 * t)).sin().max(0.0).powf(0.7)).max(0.03)
}

/// Depth of the keel line at `x`: deepest amidships, rising to the transom and the forefoot.
fn keel(x: f32) -> f32 {
    let t = (x - STERN) / (BOW - STERN);
    -0.3 + 0.55 * t * t * t - 0.6 * (std::f32::consts::PI * t).sin()
}

/// The cross-section at `x`, counter-clockwise around +x: keel, up the port (-z) side, across the
/// cambered deck, down the starboard side. Edges `SIDE..=SIDE + DECK` are deck, the others hull.
fn section(x: f32) -> Vec<Vec3> {
    let (ys, yk, hb) = (sheer(x), keel(x), half_beam(x));
    let side = |k: usize, sign: f32| {
        let th = std::f32::consts::FRAC_PI_2 * k as f32 / SIDE as f32;
        Vec3::new(x, yk + (ys - yk) * (1.0 - th.cos()), sign * hb * th.sin().powf(0.6))
    };
    let mut ring: Vec<Vec3> = (0..=SIDE).map(|k| side(k, -1.0)).collect();
    for j in 1..=DECK {
        let z = hb * (2.0 * j as f32 / (DECK + 1) as f32 - 1.0);
        ring.push(Vec3::new(x, ys + 0.08 * (1.0 - (z / hb).powi(2)), z));
    }
    ring.extend((1..=SIDE).rev().map(|k| side(k, 1.0)));
    ring
}

/// The hull sides and the deck: quads between consecutive sections, a flat transom, a small flat bow.
fn hull_and_deck(b: &mut SceneBuilder, hull: MaterialId, deck: MaterialId) {
    let rings: Vec<Vec<Vec3>> = (0..STATIONS)
        .map(|i| {
            let s = i as f32 / (STATIONS - 1) as f32;
            // Denser toward the bow, where the shape changes fastest.
            section(STERN + (BOW - STERN) * (1.0 - (1.0 - s) * (1.0 - s) * 0.3 - 0.7 * (1.0 - s)))
        })
        .collect();
    let n = rings[0].len();
    // Ring edge j runs from point j to point j + 1; the deck edges are SIDE..SIDE + DECK.
    let paint = |j: usize| if (SIDE..=SIDE + DECK).contains(&j) { deck } else { hull };
    for w in rings.windows(2) {
        for j in 0..n {
            let j1 = (j + 1) % n;
            b.quad(w[0][j], w[0][j1], w[1][j1], w[1][j], paint(j));
        }
    }
    for (ring, forward) in [(&rings[0], false), (&rings[STATIONS - 1], true)] {
        let c = ring.iter().copied().sum::<Vec3>() / n as f32;
        for j in 0..n {
            let (p, q) = (ring[j], ring[(j + 1) % n]);
            if forward {
                b.triangle(p, q, c, hull);
            } else {
                b.triangle(c, q, p, hull);
            }
        }
    }
}

/// Cabin with windows, a foredeck hatch and the cockpit coaming.
fn superstructure(b: &mut SceneBuilder, cabin: MaterialId, dark: MaterialId, teak: MaterialId) {
    let (cx, len) = (-0.6, 1.6);
    let base = sheer(cx) + 0.05;
    let frame = [Vec3::X, Vec3::Y, Vec3::Z];
    b.superellipsoid(Vec3::new(cx, base, 0.0), frame, Vec3::new(len, 0.55, 1.0), 0.35, 24, 10, cabin);
    for k in 0..3 {
        let x = cx - 0.9 + 0.9 * k as f32;
        for side in [-1.0, 1.0] {
            // The cabin side is at |z| = 0.997 there: the windows stand 1.3 cm proud of it.
            let (z0, z1) = if side > 0.0 { (0.97, 1.01) } else { (-1.01, -0.97) };
            b.axis_box(
                Vec3::new(x - 0.3, base + 0.2, z0),
                Vec3::new(x + 0.3, base + 0.33, z1),
                &Dir::ALL,
                Facing::Outward,
                dark,
            );
        }
    }
    let hx = 2.2;
    b.axis_box(
        Vec3::new(hx - 0.3, sheer(hx), -0.3),
        Vec3::new(hx + 0.3, sheer(hx) + 0.2, 0.3),
        &Dir::ALL,
        Facing::Outward,
        teak,
    );
    for (x0, x1, z0, z1) in [(-4.0, -2.3, 0.75, 0.8), (-4.0, -2.3, -0.8, -0.75), (-4.05, -4.0, -0.8, 0.8)] {
        b.axis_box(
            Vec3::new(x0, sheer(x1) - 0.05, z0),
            Vec3::new(x1, sheer(x1) + 0.25, z1),
            &Dir::ALL,
            Facing::Outward,
            teak,
        );
    }
}

/// Mast, boom, mainsail, jib and stays.
fn rig(b: &mut SceneBuilder, metal: MaterialId, sail: MaterialId) {
    let mast_x = 0.6;
    let (foot, top) = (Vec3::new(mast_x, sheer(mast_x), 0.0), Vec3::new(mast_x, MAST_TOP, 0.0));
    b.cylinder(foot, top, 0.09, 0.06, 12, metal);
    let (gooseneck, clew) = (Vec3::new(mast_x - 0.1, 2.3, 0.0), Vec3::new(-3.9, 2.45, 0.35));
    b.cylinder(gooseneck, clew, 0.06, 0.05, 12, metal);
    // Mainsail: from the boom up the mast, with a little belly to leeward (+z).
    sheet(
        b,
        gooseneck + Vec3::new(-0.05, 0.05, 0.0),
        Vec3::new(mast_x - 0.12, MAST_TOP - 0.4, 0.0),
        clew + Vec3::Y * 0.06,
        10,
        6,
        0.25,
        sail,
    );
    // Jib: from the bow up the forestay, clew back by the shrouds.
    let stem = Vec3::new(BOW - 0.1, sheer(BOW - 0.1), 0.0);
    let tack = stem.lerp(top, 0.03);
    let head = stem.lerp(top, 0.8);
    sheet(b, tack, head, Vec3::new(0.9, 1.75, 1.0), 8, 4, 0.2, sail);
    let stay = |b: &mut SceneBuilder, from: Vec3, to: Vec3| b.cylinder(from, to, 0.012, 0.012, 6, metal);
    stay(b, stem, top);
    stay(b, Vec3::new(STERN + 0.1, sheer(STERN + 0.1), 0.0), top);
    for side in [-1.0, 1.0] {
        stay(b, Vec3::new(mast_x - 0.3, sheer(mast_x), side * (half_beam(mast_x) - 0.1)), Vec3::new(mast_x, 10.0, 0.0));
    }
}

/// A triangular sail as a one-sided sheet: `rows` strips from the foot (`tack` to `clew`) up to
/// `head`, `cols` quads wide, the top strip a fan into the head; bellied toward +z by `belly` times
/// the foot length. `(2 * rows - 1) * cols` triangles.
#[allow(clippy::too_many_arguments)]
fn sheet(
    b: &mut SceneBuilder,
    tack: Vec3,
    head: Vec3,
    clew: Vec3,
    rows: usize,
    cols: usize,
    belly: f32,
    m: MaterialId,
) {
    let depth = 0.3 * belly * (clew - tack).length();
    let point = |i: usize, j: usize| {
        let (s, t) = (i as f32 / rows as f32, j as f32 / cols as f32);
        let p = tack.lerp(clew, t).lerp(head, s);
        p + Vec3::Z * (depth * (1.0 - s) * (std::f32::consts::PI * t).sin())
    };
    for i in 0..rows {
        for j in 0..cols {
            if i + 1 == rows {
                b.triangle(point(i, j), point(i, j + 1), head, m);
            } else {
                b.quad(point(i, j), point(i, j + 1), point(i + 1, j + 1), point(i + 1, j), m);
            }
        }
    }
}

/// Stanchions along both sides with two lifelines on top.
fn railing(b: &mut SceneBuilder, metal: MaterialId) {
    for side in [-1.0, 1.0] {
        let xs: Vec<f32> = (0..8).map(|k| -4.2 + 1.2 * k as f32).collect();
        let post = |x: f32| {
            let z = side * (half_beam(x) - 0.08);
            Vec3::new(x, sheer(x) - 0.02, z)
        };
        for &x in &xs {
            b.cylinder(post(x), post(x) + Vec3::Y * 0.65, 0.015, 0.015, 6, metal);
        }
        for h in [0.35, 0.62] {
            let line: Vec<Node> = xs.iter().map(|&x| Node::round(post(x) + Vec3::Y * h, 0.01)).collect();
            b.tube(&line, Vec3::Y, 5, Cap::Flat, false, metal);
        }
    }
}
