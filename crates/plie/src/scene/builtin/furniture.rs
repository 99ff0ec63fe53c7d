//! Case furniture for the Huis scenes of SPEC §6 (thesis §7.6-7.8): bookcases with shelves and books,
//! a desk and a round side table. Metres; every piece is modelled in its own local frame (x right,
//! y up, z toward its front, origin at the back-left foot) and put in the room by a [`Place`].
//! Books and boxes are closed boxes, sized by a fixed hash so the scenes are deterministic.

use glam::Vec3;

use super::shapes::{hash01, Place};
use crate::scene::{MaterialId, SceneBuilder};

/// How much detail a bookcase gets: Huis A's is joinery with a face frame and mouldings, filled with
/// single books; Huis B's is a plain carcass holding ring binders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Bookcase {
    /// Carcass, shelf lips, crown and base moulding, single books and boxes.
    Detailed,
    /// Carcass only, filled with binders.
    Simple,
}

/// Materials of a bookcase and its contents.
#[derive(Clone, Debug)]
pub(super) struct Shelving {
    /// The bookcase itself.
    pub(super) wood: MaterialId,
    /// Book or binder colours, picked by hash.
    pub(super) covers: Vec<MaterialId>,
    /// Storage boxes.
    pub(super) boxes: MaterialId,
}

const WIDTH: f32 = 1.0;
const HEIGHT: f32 = 2.0;
const DEPTH: f32 = 0.35;
const BOARD: f32 = 0.02;
const PLINTH: f32 = 0.08;
const COMPARTMENTS: usize = 5;

/// A bookcase of 1.0 x 2.0 x 0.35 m with five compartments, filled; `seed` varies the contents.
pub(super) fn bookcase(b: &mut SceneBuilder, at: &Place, kind: Bookcase, m: &Shelving, seed: u32) {
    let (w, h, d, t) = (WIDTH, HEIGHT, DEPTH, BOARD);
    let v = Vec3::new;
    b.local_box(at, v(0.0, 0.0, 0.0), v(t, h, d), m.wood);
    b.local_box(at, v(w - t, 0.0, 0.0), v(w, h, d), m.wood);
    b.local_box(at, v(t, h - t, 0.0), v(w - t, h, d), m.wood);
    b.local_box(at, v(t, PLINTH, 0.0), v(w - t, h - t, 0.01), m.wood);
    b.local_box(at, v(t, 0.0, 0.03), v(w - t, PLINTH, d - 0.02), m.wood);
    let pitch = (h - t - PLINTH) / COMPARTMENTS as f32;
    for k in 0..COMPARTMENTS {
        // Shelf k carries compartment k; its top is the compartment's floor.
        let y0 = PLINTH + pitch * k as f32;
        b.local_box(at, v(t, y0, 0.01), v(w - t, y0 + t, d), m.wood);
        let floor = y0 + t;
        let room = pitch - t;
        match kind {
            Bookcase::Detailed => {
                b.local_box(at, v(t, y0 - 0.006, d), v(w - t, y0 + t + 0.006, d + 0.012), m.wood);
                fill_with_books(b, at, floor, room, m, seed * 31 + k as u32);
            }
            Bookcase::Simple => fill_with_binders(b, at, floor, room, m, seed * 31 + k as u32),
        }
    }
    if kind == Bookcase::Detailed {
        b.local_box(at, v(-0.015, h, -0.0), v(w + 0.015, h + 0.04, d + 0.025), m.wood);
        b.local_box(at, v(-0.008, 0.0, d), v(w + 0.008, PLINTH, d + 0.012), m.wood);
    }
}

/// One compartment of Huis A's bookcase: runs of books, now and then a lying stack or a box, gaps.
fn fill_with_books(b: &mut SceneBuilder, at: &Place, floor: f32, room: f32, m: &Shelving, seed: u32) {
    let mut x = BOARD + 0.01;
    // Each compartment is filled over part of its width only: room for shadows between the books.
    let end = x + (WIDTH - 2.0 * BOARD - 0.02) * (0.45 + 0.5 * hash01(seed, 9999));
    let mut i = 0;
    let r = |i: u32| hash01(seed, i);
    while x < end {
        let kind = r(i * 7);
        if kind < 0.08 {
            // A storage box.
            let (bw, bh) = (0.22 + 0.08 * r(i * 7 + 1), (0.5 + 0.3 * r(i * 7 + 2)) * room);
            if x + bw > end {
                break;
            }
            b.local_box(at, Vec3::new(x, floor, 0.03), Vec3::new(x + bw, floor + bh, DEPTH - 0.02), m.boxes);
            x += bw + 0.02;
        } else if kind < 0.16 {
            // A lying stack of three books.
            let bw = 0.16 + 0.07 * r(i * 7 + 1);
            if x + bw > end {
                break;
            }
            let mut y = floor;
            for s in 0..3 {
                let th = 0.025 + 0.02 * r(i * 7 + 2 + s);
                let inset = 0.01 * s as f32;
                let cover = m.covers[(r(i * 7 + 5 + s) * m.covers.len() as f32) as usize];
                b.local_box(at, Vec3::new(x + inset, y, 0.06), Vec3::new(x + bw - inset, y + th, DEPTH - 0.03), cover);
                y += th;
            }
            x += bw + 0.015;
        } else if kind < 0.22 {
            x += 0.05 + 0.1 * r(i * 7 + 1);
        } else {
            let bw = 0.018 + 0.03 * r(i * 7 + 1);
            let bh = (0.55 + 0.4 * r(i * 7 + 2)) * room;
            let depth = 0.14 + 0.1 * r(i * 7 + 3);
            if x + bw > end {
                break;
            }
            let cover = m.covers[(r(i * 7 + 4) * m.covers.len() as f32) as usize];
            let front = DEPTH - 0.02 - 0.02 * r(i * 7 + 5);
            b.local_box(at, Vec3::new(x, floor, front - depth), Vec3::new(x + bw, floor + bh, front), cover);
            x += bw + 0.0015;
        }
        i += 1;
    }
}

/// One compartment of Huis B's bookcase: a run of equal ring binders and a gap.
fn fill_with_binders(b: &mut SceneBuilder, at: &Place, floor: f32, room: f32, m: &Shelving, seed: u32) {
    let count = 5 + (hash01(seed, 0) * 5.0) as usize;
    let start = BOARD + 0.02 + 0.3 * hash01(seed, 1);
    let (bw, bh) = (0.075, (room - 0.03).min(0.32));
    for k in 0..count {
        let x = start + k as f32 * (bw + 0.003);
        if x + bw > WIDTH - BOARD - 0.01 {
            break;
        }
        let cover = m.covers[(hash01(seed, 2 + k as u32) * m.covers.len() as f32) as usize];
        b.local_box(at, Vec3::new(x, floor, 0.04), Vec3::new(x + bw, floor + bh, DEPTH - 0.02), cover);
    }
}

/// A desk, 1.6 x 0.75 x 0.8 m: top, two legs on the left, a three-drawer pedestal on the right with
/// handles, and a modesty panel at the back.
pub(super) fn desk(b: &mut SceneBuilder, at: &Place, wood: MaterialId, metal: MaterialId) {
    let v = Vec3::new;
    let (w, h, d) = (1.6, 0.75, 0.8);
    b.local_box(at, v(0.0, h - 0.03, 0.0), v(w, h, d), wood);
    for z in [0.05, d - 0.05] {
        b.cylinder(at.p(v(0.06, 0.0, z)), at.p(v(0.06, h - 0.03, z)), 0.025, 0.025, 12, metal);
    }
    b.local_box(at, v(0.09, 0.35, 0.04), v(w - 0.45, h - 0.03, 0.06), wood);
    let (px, pw) = (w - 0.45, 0.42);
    b.local_box(at, v(px, 0.0, 0.02), v(px + pw, h - 0.03, d - 0.03), wood);
    for k in 0..3 {
        let y0 = 0.03 + 0.23 * k as f32;
        b.local_box(at, v(px + 0.01, y0, d - 0.03), v(px + pw - 0.01, y0 + 0.22, d - 0.01), wood);
        let hy = y0 + 0.16;
        b.local_box(at, v(px + 0.13, hy, d - 0.01), v(px + pw - 0.13, hy + 0.015, d + 0.015), metal);
    }
}

/// A round side table: top, column and foot (`4 * segments + 96` triangles).
pub(super) fn round_table(b: &mut SceneBuilder, at: &Place, top: MaterialId, metal: MaterialId, segments: usize) {
    let v = Vec3::new;
    b.cylinder(at.p(v(0.0, 0.70, 0.0)), at.p(v(0.0, 0.73, 0.0)), 0.45, 0.45, segments, top);
    b.cylinder(at.p(v(0.0, 0.02, 0.0)), at.p(v(0.0, 0.70, 0.0)), 0.04, 0.04, 12, metal);
    b.cylinder(at.p(v(0.0, 0.0, 0.0)), at.p(v(0.0, 0.02, 0.0)), 0.25, 0.23, 12, metal);
}
