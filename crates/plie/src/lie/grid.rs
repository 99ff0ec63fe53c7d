//! Face-grid cells (our addition, SPEC §8 points 2-4): a record's `g x g` grid divides its face
//! into cells `(i, j)` along the in-face axes of [`super::frame`]; cell `(i, j)` is stored at
//! `j * g + i`. The construction fills each cell's list; a query looks up the cell a ray crosses.

use crate::geometry::Aabb;
use crate::octree::Dir;

use super::frame::face_axes;

/// The box of cell `(i, j)` of face `face` of `cell` (flat along the face's axis).
pub fn cell_box(face: Dir, cell: &Aabb, g: u32, i: u32, j: u32) -> Aabb {
    let k = face.axis();
    let (u, v) = face_axes(k);
    let w = if face.is_positive() { cell.max[k] } else { cell.min[k] };
    let (mut lo, mut hi) = (cell.min, cell.max);
    lo[k] = w;
    hi[k] = w;
    let du = (cell.max[u] - cell.min[u]) / g as f32;
    let dv = (cell.max[v] - cell.min[v]) / g as f32;
    lo[u] = cell.min[u] + du * i as f32;
    hi[u] = if i + 1 == g { cell.max[u] } else { cell.min[u] + du * (i + 1) as f32 };
    lo[v] = cell.min[v] + dv * j as f32;
    hi[v] = if j + 1 == g { cell.max[v] } else { cell.min[v] + dv * (j + 1) as f32 };
    Aabb::new(lo, hi)
}

/// The cell of a `g x g` face grid that the face point `p` falls in (clamped to the face).
#[inline]
pub fn cell_of(face: Dir, cell: &Aabb, g: u32, p: glam::Vec3) -> usize {
    let (u, v) = face_axes(face.axis());
    let fu = (p[u] - cell.min[u]) / (cell.max[u] - cell.min[u]) * g as f32;
    let fv = (p[v] - cell.min[v]) / (cell.max[v] - cell.min[v]) * g as f32;
    let i = (fu.max(0.0) as u32).min(g - 1);
    let j = (fv.max(0.0) as u32).min(g - 1);
    (j * g + i) as usize
}
