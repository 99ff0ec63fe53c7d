//! The Dragon scene of SPEC §6 (thesis §7.9): Cornell Cube 2 (walls, light, blocks: 32 triangles) with
//! a small procedural dragon of about 2734 triangles standing on the short block, which is the right
//! one in the picture (the thesis' "rechter balk").
//!
//! The creature is one smooth swept tube from snout to tail tip (head, S-shaped neck, body, a tail
//! curling over the block toward the camera), four legs, two half-raised wings with a bone along their
//! leading edge, horns, eyes and a row of spikes along the back. It shadows itself: the wings over the
//! body, the neck over the front legs, the spikes on the back, the body on the tail and the legs. All
//! parts are closed meshes except the wing membranes (one-sided sheets, which block both ways).
//!
//! Modelled in a local frame on the block's top: `a` along the block's front edge (toward +x, where the
//! dragon looks), `h` up, `c` across (toward the back wall); millimetres.

use glam::{Vec2, Vec3};

use super::cornell::{self, SHORT_BLOCK, SHORT_HEIGHT};
use super::shapes::{ellipse, frames, smooth, Cap, Node};
use crate::error::Result;
use crate::scene::{MaterialId, SceneBuilder};

/// Segments around the body tube.
const BODY_SEGMENTS: usize = 16;

/// Local frame on top of the short block.
#[derive(Clone, Copy, Debug)]
struct Frame {
    origin: Vec3,
    a: Vec3,
    c: Vec3,
}

impl Frame {
    fn on_short_block() -> Frame {
        let center = SHORT_BLOCK.iter().copied().sum::<Vec3>() / 4.0 + Vec3::Y * SHORT_HEIGHT;
        let a = (SHORT_BLOCK[3] - SHORT_BLOCK[0]).normalize();
        Frame { origin: center, a, c: a.cross(Vec3::Y) }
    }

    /// The world point at local `(a, h, c)`.
    fn p(&self, a: f32, h: f32, c: f32) -> Vec3 {
        self.origin + self.a * a + Vec3::Y * h + self.c * c
    }

    /// A node at local `(a, h, c)` with radii `(across, up)`.
    fn node(&self, (a, h, c): (f32, f32, f32), rx: f32, ry: f32) -> Node {
        Node { center: self.p(a, h, c), radius: Vec2::new(rx, ry) }
    }
}

/// The Dragon scene: Cornell Cube 2 and the creature on the short block.
pub(super) fn dragon() -> Result<SceneBuilder> {
    let (mut b, white) = cornell::room("dragon")?;
    cornell::blocks(&mut b, white);
    let skin = b.diffuse("dragon skin", Vec3::new(0.32, 0.55, 0.25));
    let horn = b.diffuse("dragon horn", Vec3::new(0.85, 0.8, 0.62));
    let wing = b.diffuse("dragon wing", Vec3::new(0.6, 0.22, 0.15));
    let f = Frame::on_short_block();
    let spine = body(&mut b, &f, skin);
    spikes(&mut b, &spine, horn);
    for side in [-1.0, 1.0] {
        legs(&mut b, &f, side, skin, horn);
        head_details(&mut b, &f, side, horn);
        wing_membrane(&mut b, &f, side, wing, skin);
    }
    Ok(b)
}

/// Head, neck, body and tail as one tube from the snout to the tail tip; returns its spine.
fn body(b: &mut SceneBuilder, f: &Frame, m: MaterialId) -> Vec<Node> {
    let control = [
        f.node((112.0, 136.0, 0.0), 3.0, 2.5), // snout
        f.node((100.0, 139.0, 0.0), 7.0, 6.0),
        f.node((86.0, 142.0, 0.0), 9.0, 8.5),
        f.node((72.0, 146.0, 0.0), 12.0, 12.0), // skull
        f.node((60.0, 140.0, 0.0), 10.0, 11.0),
        f.node((54.0, 124.0, 0.0), 8.5, 9.0), // neck
        f.node((50.0, 106.0, 0.0), 10.0, 10.0),
        f.node((44.0, 88.0, 0.0), 13.0, 13.0),
        f.node((34.0, 74.0, 0.0), 18.0, 18.0), // shoulders
        f.node((18.0, 66.0, 0.0), 24.0, 22.0),
        f.node((0.0, 63.0, 0.0), 27.0, 24.0), // belly
        f.node((-18.0, 62.0, 0.0), 25.0, 22.0),
        f.node((-34.0, 56.0, 0.0), 19.0, 17.0), // hips
        f.node((-48.0, 44.0, -4.0), 13.0, 13.0),
        f.node((-60.0, 30.0, -14.0), 10.0, 10.0), // tail
        f.node((-66.0, 18.0, -32.0), 8.0, 8.0),
        f.node((-60.0, 10.0, -52.0), 6.0, 6.0),
        f.node((-44.0, 7.0, -64.0), 4.5, 4.5),
        f.node((-26.0, 6.0, -66.0), 3.0, 3.0),
        f.node((-14.0, 5.0, -62.0), 0.0, 0.0), // tip
    ];
    let spine = smooth(&control, 3);
    b.tube(&spine, Vec3::Y, BODY_SEGMENTS, Cap::Flat, false, m);
    spine
}

/// Square pyramids standing on the top of the tube (from the neck to the tail), leaning back.
fn spikes(b: &mut SceneBuilder, spine: &[Node], m: MaterialId) {
    let fr = frames(spine, Vec3::Y, false);
    for i in (16..spine.len() - 6).step_by(2) {
        let (node, [t, a, up]) = (spine[i], fr[i]);
        let height = (0.7 * node.radius.y).clamp(4.0, 12.0);
        let base = node.center + up * (0.85 * node.radius.y);
        let tip = base + up * height + t * (0.5 * height);
        let w = 0.3 * height;
        let corners = ellipse(base, a, t, Vec2::splat(w), 4, std::f32::consts::FRAC_PI_4);
        // `corners` run counter-clockwise around a x t = -up; the sides around the apex face out.
        for k in 0..4 {
            b.triangle(corners[(k + 1) % 4], corners[k], tip, m);
        }
    }
}

/// The front and hind leg on one side (`side` = -1 toward the camera, +1 away), with claws.
fn legs(b: &mut SceneBuilder, f: &Frame, side: f32, m: MaterialId, claw_m: MaterialId) {
    let front = [
        f.node((26.0, 64.0, 14.0 * side), 10.0, 10.0),
        f.node((34.0, 40.0, 19.0 * side), 7.0, 7.0),
        f.node((30.0, 18.0, 21.0 * side), 5.0, 5.0),
        f.node((32.0, 9.0, 21.0 * side), 4.5, 5.5),
        f.node((32.0, 3.0, 21.0 * side), 5.0, 9.0),
    ];
    let hind = [
        f.node((-24.0, 58.0, 18.0 * side), 13.0, 13.0),
        f.node((-6.0, 38.0, 26.0 * side), 9.0, 9.0),
        f.node((-30.0, 18.0, 27.0 * side), 6.0, 6.0),
        f.node((-24.0, 9.0, 27.0 * side), 5.0, 6.0),
        f.node((-24.0, 3.0, 27.0 * side), 5.5, 10.0),
    ];
    for leg in [front, hind] {
        // Cross-sections oriented by the dragon's forward axis: the feet are long, not wide.
        b.tube(&leg, f.a, 10, Cap::Flat, false, m);
        // Three claws pointing forward from the front of the foot, tips just above the block.
        let (a, c) = ((leg[4].center - f.origin).dot(f.a), (leg[4].center - f.origin).dot(f.c));
        for dc in [-3.5, 0.0, 3.5] {
            let claw = [f.node((a + 6.0, 4.0, c + dc), 2.0, 2.0), f.node((a + 14.0, 1.0, c + 1.6 * dc), 0.0, 0.0)];
            b.tube(&claw, Vec3::Y, 4, Cap::Flat, false, claw_m);
        }
    }
}

/// A horn and an eye on one side of the head.
fn head_details(b: &mut SceneBuilder, f: &Frame, side: f32, m: MaterialId) {
    let horn = [f.node((66.0, 152.0, 6.0 * side), 3.5, 3.5), f.node((46.0, 174.0, 13.0 * side), 0.0, 0.0)];
    b.tube(&horn, Vec3::Y, 6, Cap::Flat, false, m);
    b.sphere(f.p(84.0, 148.0, 7.0 * side), 3.0, 8, 6, m);
}

/// A half-raised wing on one side: a bone along the leading edge and a membrane behind it.
fn wing_membrane(b: &mut SceneBuilder, f: &Frame, side: f32, membrane: MaterialId, bone: MaterialId) {
    let (nu, nv) = (6, 4);
    let shoulder = f.p(14.0, 80.0, 16.0 * side);
    let elbow = f.p(4.0, 122.0, 52.0 * side);
    let tip = f.p(-34.0, 150.0, 74.0 * side);
    let root = f.p(-26.0, 72.0, 14.0 * side);
    let leading = |u: f32| {
        if u < 0.4 {
            shoulder.lerp(elbow, u / 0.4)
        } else {
            elbow.lerp(tip, (u - 0.4) / 0.6)
        }
    };
    // The trailing edge sags down and back between root and tip (scalloped membrane).
    let trailing = |u: f32| {
        let end = tip + f.a * -8.0 + Vec3::Y * -10.0;
        root.lerp(end, u) + (Vec3::Y * -14.0 + f.a * -10.0) * (std::f32::consts::PI * u).sin()
    };
    let grid: Vec<Vec<Vec3>> = (0..=nu)
        .map(|i| {
            let u = i as f32 / nu as f32;
            (0..=nv).map(|j| leading(u).lerp(trailing(u), j as f32 / nv as f32)).collect()
        })
        .collect();
    for i in 0..nu {
        for j in 0..nv {
            let (p, q, r, s) = (grid[i][j], grid[i + 1][j], grid[i + 1][j + 1], grid[i][j + 1]);
            // Keep the upper side the front on both wings.
            if side < 0.0 {
                b.quad(p, q, r, s, membrane);
            } else {
                b.quad(s, r, q, p, membrane);
            }
        }
    }
    let spine = [Node::round(shoulder, 3.0), Node::round(elbow, 2.2), Node::round(tip, 0.0)];
    b.tube(&spine, Vec3::Y, 6, Cap::Flat, false, bone);
}
