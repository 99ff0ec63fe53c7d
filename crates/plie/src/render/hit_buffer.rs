//! Pass 1 of SPEC §2: the hit buffer. For every eye ray (K x K regular rays per pixel) the nearest hit:
//! point, geometric normal turned toward the eye, ray direction, triangle and the octree leaf holding
//! the point. Built with the BVH for every visibility mode, so all modes shade the same points.

use glam::Vec3;
use rayon::prelude::*;

use crate::octree::{LeafId, Octree};
use crate::scene::{Camera, Scene, TriId};
use crate::visibility::bvh::Bvh;

/// One eye ray's nearest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Hit point `x`.
    pub point: Vec3,
    /// Unit geometric normal, on the side the eye ray came from (two-sided shading).
    pub normal: Vec3,
    /// Unit eye-ray direction.
    pub dir: Vec3,
    /// Triangle hit.
    pub tri: TriId,
    /// True if the eye ray hit the triangle's front (counter-clockwise) side.
    pub front: bool,
    /// Octree leaf containing the point, if an octree was given.
    pub leaf: Option<LeafId>,
}

/// The hit buffer: `width * height * k * k` entries, pixel-major (row by row, top row first), the
/// `k x k` eye rays of a pixel consecutive.
#[derive(Clone, Debug)]
pub struct HitBuffer {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Eye rays per pixel along each axis.
    pub k: u32,
    /// The hits (`None`: the eye ray left the scene).
    pub hits: Vec<Option<Hit>>,
}

impl HitBuffer {
    /// Traces the eye rays. `octree`, when given, fills in [`Hit::leaf`].
    pub fn build(
        scene: &Scene,
        camera: &Camera,
        (width, height, k): (u32, u32, u32),
        bvh: &Bvh,
        octree: Option<&Octree>,
    ) -> HitBuffer {
        let frame = camera.frame(width, height);
        let per_pixel = (k * k) as usize;
        let mut hits = vec![None; width as usize * height as usize * per_pixel];
        hits.par_chunks_mut(width as usize * per_pixel).enumerate().for_each(|(py, row)| {
            for (i, slot) in row.iter_mut().enumerate() {
                let px = (i / per_pixel) as u32;
                let s = (i % per_pixel) as u32;
                let x = px as f32 + ((s % k) as f32 + 0.5) / k as f32;
                let y = py as f32 + ((s / k) as f32 + 0.5) / k as f32;
                let (o, d) = frame.ray(x, y);
                *slot = bvh.closest_hit(scene, o, d).map(|(tri, t)| {
                    let point = o + d * t;
                    let n = scene.triangles[tri.idx()].normal();
                    let front = n.dot(d) < 0.0;
                    Hit {
                        point,
                        normal: if front { n } else { -n },
                        dir: d,
                        tri,
                        front,
                        leaf: octree.and_then(|oc| oc.locate(point)),
                    }
                });
            }
        });
        HitBuffer { width, height, k, hits }
    }
}
