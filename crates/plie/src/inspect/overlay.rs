//! The picture of `plie inspect` (like the thesis' figures 5.11 and 5.12), drawn by plie's own
//! renderer (SPEC §2) from an *overlay scene*: the original scene plus marker geometry.
//!
//! - **Leaves**: every leaf edge as a thin axis-aligned box (a "beam"), each edge once. A beam is cut
//!   into pieces whose width is [`OverlayStyle::line_px`] pixels at the piece's distance from the eye,
//!   so lines keep about the same width on screen; the inspected leaf's edges are twice as wide and
//!   [`HIGHLIGHT_COLOUR`].
//! - **Blockers** of the faces shown: the part of each that lies in a shown face's shaft (the clipped
//!   blocker of §4.4, what can actually stop light on its way to the face) in [`BLOCKER_COLOUR`],
//!   lifted a hair toward the eye; the rest of the triangle in pale [`BLOCKER_REST_COLOUR`]. Light
//!   triangles keep their own material, so a light stays recognisable.
//! - **Umbra and penumbra** triangles lie in the face's plane, lifted a hair (a thousandth of the
//!   leaf's size, umbra twice as far so it wins where the two overlap by construction) toward the eye,
//!   so they neither fight with a wall in the same plane nor hide behind it.
//!
//! Marker triangles are *unlit*: albedo 0 and emission equal to their colour, wound to face the eye
//! (emission is one-sided), so their colour reads the same in light and in shadow. Blockers are partly
//! emissive, partly diffuse, so they stay blue in shadow and still show their shape. Markers never
//! cast shadows: the shadow rays are answered by a visibility over the **original** scene, whose
//! triangles keep their ids in the overlay scene (markers are appended after them), so the scene's own
//! shading is exactly that of `plie render`.

use std::collections::HashSet;

use glam::Vec3;

use super::{
    Inspection, BLOCKER_COLOUR, BLOCKER_LIFT, BLOCKER_REST_COLOUR, HIGHLIGHT_COLOUR, LEAF_COLOUR, PENUMBRA_COLOUR,
    REGION_LIFT, UMBRA_COLOUR,
};
use crate::error::Result;
use crate::geometry::{Aabb, Triangle};
use crate::octree::{Dir, Octree};
use crate::render::{render, Progress, RenderSettings, Rendered};
use crate::scene::{Camera, Material, MaterialId, Scene};
use crate::visibility::bvh::Bvh;
use crate::visibility::BvhVisibility;

/// Pieces each leaf edge is cut into, each with its own width.
const PIECES: usize = 8;

/// How the overlay is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverlayStyle {
    /// Width of leaf edges in pixels (the inspected leaf's are twice as wide).
    pub line_px: f32,
    /// The image is scaled by `2^exposure_ev` (as `plie render --exposure`); marker colours are divided
    /// by it first, so they come out unchanged.
    pub exposure_ev: f32,
}

impl Default for OverlayStyle {
    /// 1.5-pixel lines, no exposure change.
    fn default() -> OverlayStyle {
        OverlayStyle { line_px: 1.5, exposure_ev: 0.0 }
    }
}

/// The overlay scene for `ins` seen from `camera` in an image `image_height` pixels high (see the
/// module doc). Triangles `0 .. scene.triangles.len()` are the original ones, in order (blockers with
/// their overlay material, wound to face the eye); markers follow.
pub fn overlay_scene(
    scene: &Scene,
    octree: &Octree,
    ins: &Inspection,
    camera: &Camera,
    image_height: u32,
    style: &OverlayStyle,
) -> Scene {
    let mut out = scene.clone();
    let m = Materials::add(&mut out, style.exposure_ev.exp2());
    let eye = camera.eye;
    for &t in &ins.blockers {
        if scene.tri_light[t.idx()].is_none() {
            out.tri_material[t.idx()] = m.rest;
            out.triangles[t.idx()] = Triangle { v: facing(eye, out.triangles[t.idx()].v) };
        }
    }
    let size = scene.scale().max(octree.root_bounds().size().max_element());
    let mut markers = Vec::new();
    leaf_beams(octree, ins, camera, image_height, style, size, &m, &mut markers);
    let region_lift = ins.bounds.size().max_element() * REGION_LIFT;
    for f in &ins.faces {
        for (t, poly) in &f.clipped {
            let n = toward(eye, poly[0], scene.triangle(*t).normal());
            for i in 1..poly.len() - 1 {
                let tri = [poly[0], poly[i], poly[i + 1]].map(|p| p + n * size * BLOCKER_LIFT);
                markers.push((facing(eye, tri), m.blocker));
            }
        }
        let n = toward(eye, f.face.face_corners(&ins.bounds)[0], f.face.normal());
        for (tris, mat, h) in [(&f.penumbra, m.penumbra, region_lift), (&f.umbra, m.umbra, 2.0 * region_lift)] {
            markers.extend(tris.iter().map(|t| (facing(eye, t.map(|p| p + n * h)), mat)));
        }
    }
    for (t, mat) in markers {
        let tri = Triangle { v: t };
        if tri.is_degenerate() {
            continue;
        }
        out.bounds = out.bounds.union(tri.aabb());
        out.triangles.push(tri);
        out.tri_material.push(mat);
        out.tri_light.push(None);
    }
    out
}

/// The overlay's materials, added to the scene.
struct Materials {
    leaf: MaterialId,
    highlight: MaterialId,
    umbra: MaterialId,
    penumbra: MaterialId,
    blocker: MaterialId,
    rest: MaterialId,
}

impl Materials {
    /// Adds the materials; emissions are divided by the exposure factor `k`.
    fn add(out: &mut Scene, k: f32) -> Materials {
        let mut add = |name: &str, albedo: Vec3, emission: Vec3| {
            out.materials.push(Material {
                name: format!("inspect: {name}"),
                albedo,
                emission: emission / k,
                texture: None,
            });
            MaterialId(out.materials.len() as u32 - 1)
        };
        Materials {
            leaf: add("leaf", Vec3::ZERO, LEAF_COLOUR),
            highlight: add("inspected leaf", Vec3::ZERO, HIGHLIGHT_COLOUR),
            umbra: add("umbra", Vec3::ZERO, UMBRA_COLOUR),
            penumbra: add("penumbra", Vec3::ZERO, PENUMBRA_COLOUR),
            blocker: add("blocker in the shaft", BLOCKER_COLOUR * 0.6, BLOCKER_COLOUR * 0.25),
            rest: add("blocker outside the shaft", BLOCKER_REST_COLOUR * 0.6, BLOCKER_REST_COLOUR * 0.15),
        }
    }
}

/// `t`, wound to face `eye`.
fn facing(eye: Vec3, t: [Vec3; 3]) -> [Vec3; 3] {
    if (t[1] - t[0]).cross(t[2] - t[0]).dot(eye - t[0]) < 0.0 {
        [t[0], t[2], t[1]]
    } else {
        t
    }
}

/// `n` or `-n`, whichever points from the plane through `p` toward `eye`.
fn toward(eye: Vec3, p: Vec3, n: Vec3) -> Vec3 {
    if (eye - p).dot(n) < 0.0 {
        -n
    } else {
        n
    }
}

/// Beams along every leaf edge (each once), the inspected leaf's twice as wide and highlighted.
#[allow(clippy::too_many_arguments)]
fn leaf_beams(
    octree: &Octree,
    ins: &Inspection,
    camera: &Camera,
    image_height: u32,
    style: &OverlayStyle,
    size: f32,
    m: &Materials,
    out: &mut Vec<([Vec3; 3], MaterialId)>,
) {
    let pixel = 2.0 * (camera.fov_deg.to_radians() * 0.5).tan() / image_height.max(1) as f32;
    let width_at = |p: Vec3, px: f32| (p.distance(camera.eye) * pixel * px).max(size * 1e-6);
    let mut seen = HashSet::new();
    for leaf in octree.leaves().filter(|&l| l != ins.leaf) {
        for (a, b) in box_edges(&octree.leaf_bounds(leaf)) {
            if seen.insert((a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits))) {
                beam(a, b, |p| width_at(p, style.line_px), m.leaf, out);
            }
        }
    }
    for (a, b) in box_edges(&ins.bounds) {
        beam(a, b, |p| width_at(p, 2.0 * style.line_px), m.highlight, out);
    }
}

/// Renders the inspection: the overlay scene's hit buffer, shaded with shadow rays answered over the
/// original `scene` (markers cast no shadows), scaled by `2^style.exposure_ev`.
#[allow(clippy::too_many_arguments)]
pub fn render_inspection(
    scene: &Scene,
    octree: &Octree,
    ins: &Inspection,
    camera: &Camera,
    settings: &RenderSettings,
    style: &OverlayStyle,
    progress: &dyn Progress,
) -> Result<Rendered> {
    settings.validate()?;
    camera.validate()?;
    let overlay = overlay_scene(scene, octree, ins, camera, settings.height, style);
    let scene_bvh = Bvh::build(scene);
    let vis = BvhVisibility::new(scene, &scene_bvh);
    let overlay_bvh = Bvh::build(&overlay);
    let mut out = render(&overlay, camera, settings, &overlay_bvh, None, &vis, progress)?;
    let k = style.exposure_ev.exp2();
    if k != 1.0 {
        out.pixels.iter_mut().for_each(|p| *p *= k);
    }
    Ok(out)
}

/// `camera` moved to frame the box `b`: looking at its centre from the side `camera` looks from (along
/// `eye - target`), as far away as makes its bounding sphere span 60% of the vertical field of view.
/// Up vector and field of view are kept.
pub fn camera_on_box(camera: &Camera, b: &Aabb) -> Camera {
    let from = (camera.eye - camera.target).normalize();
    let half = (camera.fov_deg.to_radians() * 0.5 * 0.6).sin();
    let dist = (b.diagonal() * 0.5).max(1e-6) / half;
    let center = b.center();
    Camera { eye: center + from * dist, target: center, up: camera.up, fov_deg: camera.fov_deg }
}

/// The 12 edges of a box, each from its lower to its upper end.
pub fn box_edges(b: &Aabb) -> [(Vec3, Vec3); 12] {
    let mut edges = [(Vec3::ZERO, Vec3::ZERO); 12];
    for k in 0..3 {
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        for j in 0..4 {
            let mut a = b.min;
            if j & 1 != 0 {
                a[u] = b.max[u];
            }
            if j & 2 != 0 {
                a[v] = b.max[v];
            }
            let mut e = a;
            e[k] = b.max[k];
            edges[k * 4 + j] = (a, e);
        }
    }
    edges
}

/// The axis-aligned edge `a -> b` as [`PIECES`] boxes, each `width(midpoint)` wide and overlapping its
/// neighbours by half a width.
fn beam(a: Vec3, b: Vec3, width: impl Fn(Vec3) -> f32, m: MaterialId, out: &mut Vec<([Vec3; 3], MaterialId)>) {
    for i in 0..PIECES {
        let p0 = a.lerp(b, i as f32 / PIECES as f32);
        let p1 = a.lerp(b, (i + 1) as f32 / PIECES as f32);
        let h = 0.5 * width((p0 + p1) * 0.5);
        let piece = Aabb::new(p0.min(p1) - Vec3::splat(h), p0.max(p1) + Vec3::splat(h));
        for d in Dir::ALL {
            let q = d.face_corners(&piece);
            out.push(([q[0], q[1], q[2]], m));
            out.push(([q[0], q[2], q[3]], m));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_edges_are_the_twelve_axis_aligned_edges() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let edges = box_edges(&b);
        let mut lengths: Vec<f32> = edges.iter().map(|(a, e)| a.distance(*e)).collect();
        lengths.sort_by(f32::total_cmp);
        assert_eq!(lengths, [1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 3.0, 3.0, 3.0, 3.0]);
        let distinct: HashSet<_> =
            edges.iter().map(|(a, e)| (a.to_array().map(f32::to_bits), e.to_array().map(f32::to_bits))).collect();
        assert_eq!(distinct.len(), 12);
    }

    #[test]
    fn camera_on_box_looks_at_the_box_from_the_same_side() {
        let c = Camera::new(Vec3::new(0.0, 5.0, -10.0), Vec3::ZERO, Vec3::Y, 40.0).unwrap();
        let b = Aabb::new(Vec3::new(3.0, 0.0, 3.0), Vec3::new(4.0, 1.0, 4.0));
        let f = camera_on_box(&c, &b);
        assert_eq!(f.target, b.center());
        let from = (f.eye - f.target).normalize();
        assert!(from.dot((c.eye - c.target).normalize()) > 0.9999);
        let r = b.diagonal() * 0.5;
        let half_angle = (r / f.eye.distance(f.target)).asin().to_degrees();
        assert!((half_angle - 0.6 * 20.0).abs() < 1e-3, "{half_angle}");
        f.validate().unwrap();
    }
}
