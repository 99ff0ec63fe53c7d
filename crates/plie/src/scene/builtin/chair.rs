//! The office chair of the Huis scenes (SPEC §6, thesis §7.6): a five-leg star base with twin-wheel
//! casters, a hub and a telescopic column, a seat plate, a cushioned seat and backrest on a curved
//! support, and two armrests. The thesis names the shadows under this chair among the most complex of
//! the scene. Metres; local frame with the origin on the floor under the column and the sitter facing
//! +z.

use glam::Vec3;

use super::shapes::{Cap, Facing, Node, Place};
use crate::geometry::Dir;
use crate::scene::{MaterialId, SceneBuilder};

/// Materials of the chair.
#[derive(Clone, Copy, Debug)]
pub(super) struct ChairPaint {
    /// Base, column, support, armrests.
    pub(super) frame: MaterialId,
    /// Casters and armrest pads.
    pub(super) plastic: MaterialId,
    /// Seat and backrest.
    pub(super) cushion: MaterialId,
}

/// How finely the chair is tessellated (Huis B's is finer).
#[derive(Clone, Copy, Debug)]
pub(super) struct ChairDetail {
    /// Segments around the cushions.
    pub(super) cushion_segments: usize,
    /// Bands from pole to pole of the cushions.
    pub(super) cushion_bands: usize,
    /// Segments around a caster wheel.
    pub(super) wheel_segments: usize,
}

const LEG_REACH: f32 = 0.33;

/// The whole chair.
pub(super) fn office_chair(b: &mut SceneBuilder, at: &Place, paint: ChairPaint, detail: ChairDetail) {
    star_base(b, at, paint, detail);
    let v = Vec3::new;
    // Telescopic column: shroud and piston.
    b.cylinder(at.p(v(0.0, 0.14, 0.0)), at.p(v(0.0, 0.31, 0.0)), 0.036, 0.033, 16, paint.frame);
    b.cylinder(at.p(v(0.0, 0.31, 0.0)), at.p(v(0.0, 0.43, 0.0)), 0.022, 0.022, 16, paint.frame);
    b.local_box(at, v(-0.13, 0.43, -0.14), v(0.13, 0.46, 0.12), paint.frame);
    cushions(b, at, paint, detail);
    for side in [-1.0, 1.0] {
        let x = 0.255 * side;
        b.local_box(at, v(x - 0.015, 0.44, -0.04), v(x + 0.015, 0.66, 0.0), paint.frame);
        b.local_box(at, v(x - 0.035, 0.66, -0.12), v(x + 0.035, 0.685, 0.13), paint.plastic);
        // Bracket from the seat plate out to the armrest post.
        let (x0, x1) = if side > 0.0 { (0.12, x) } else { (x, -0.12) };
        b.local_box(at, v(x0, 0.425, -0.04), v(x1, 0.445, 0.0), paint.frame);
    }
}

/// Hub, five tapered legs and a twin-wheel caster under the end of each.
fn star_base(b: &mut SceneBuilder, at: &Place, paint: ChairPaint, detail: ChairDetail) {
    let v = Vec3::new;
    b.cylinder(at.p(v(0.0, 0.085, 0.0)), at.p(v(0.0, 0.15, 0.0)), 0.055, 0.05, 16, paint.frame);
    for k in 0..5 {
        let leg = at.then(Vec3::ZERO, 18.0 + 72.0 * k as f32);
        // Local x of `leg` runs outward along the leg; a hexahedron tapering from hub to tip.
        let corner = |i: usize| {
            let outer = i & 1 != 0;
            let (x, half_w, y0, y1) = if outer { (LEG_REACH, 0.016, 0.075, 0.1) } else { (0.03, 0.026, 0.09, 0.14) };
            let y = if i & 2 != 0 { y1 } else { y0 };
            let z = if i & 4 != 0 { half_w } else { -half_w };
            leg.p(v(x, y, z))
        };
        b.hexahedron(&std::array::from_fn(corner), &Dir::ALL, Facing::Outward, paint.frame);
        // Caster: a fork under the leg tip and two wheels on a horizontal axle across the leg.
        b.local_box(&leg, v(LEG_REACH - 0.035, 0.05, -0.018), v(LEG_REACH + 0.005, 0.075, 0.018), paint.plastic);
        for side in [-1.0, 1.0] {
            let axle = v(LEG_REACH - 0.03, 0.027, 0.0);
            let (a, c) = (leg.p(axle + v(0.0, 0.0, 0.005 * side)), leg.p(axle + v(0.0, 0.0, 0.02 * side)));
            b.cylinder(a, c, 0.026, 0.026, detail.wheel_segments, paint.plastic);
        }
    }
}

/// The seat and the backrest (superellipsoid cushions) and the curved bar that carries the backrest.
fn cushions(b: &mut SceneBuilder, at: &Place, paint: ChairPaint, detail: ChairDetail) {
    let v = Vec3::new;
    let (segs, bands) = (detail.cushion_segments, detail.cushion_bands);
    let seat = [at.dir(Vec3::X), Vec3::Y, at.dir(Vec3::Z)];
    b.superellipsoid(at.p(v(0.0, 0.505, 0.0)), seat, v(0.24, 0.045, 0.23), 0.3, segs, bands, paint.cushion);
    // Backrest leaning back by 12 degrees; its poles on the axis through its thickness.
    let (s, c) = 12f32.to_radians().sin_cos();
    let normal = at.dir(v(0.0, s, c));
    let back = [at.dir(-Vec3::X), normal, at.dir(v(0.0, c, -s))];
    b.superellipsoid(at.p(v(0.0, 0.86, -0.3)), back, v(0.22, 0.04, 0.25), 0.3, segs, bands, paint.cushion);
    let bar = [
        Node::round(at.p(v(0.0, 0.44, -0.08)), 0.02),
        Node::round(at.p(v(0.0, 0.44, -0.25)), 0.02),
        Node::round(at.p(v(0.0, 0.52, -0.33)), 0.02),
        Node::round(at.p(v(0.0, 0.74, -0.33)), 0.02),
    ];
    b.tube(&bar, at.dir(Vec3::X), 8, Cap::Flat, false, paint.frame);
}
