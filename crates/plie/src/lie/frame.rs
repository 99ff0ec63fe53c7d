//! The face's 2D frame (SPEC §4.5): where on a cell face a point lies, in the integer units the
//! P-LIE stores umbra and penumbra triangles in. For a face along axis `k` the in-face axes are
//! `((k+1) % 3, (k+2) % 3)`, the origin is the face's minimum corner, and a side is [`UNITS`] long.
//! The construction writes regions in this frame; the queries read them in it.

use glam::{DVec2, DVec3};

use crate::geometry::Aabb;
use crate::octree::Dir;

/// Integer units per face side.
pub const UNITS: f64 = (1u32 << 20) as f64;

/// A triangle of a region, in the face's integer units.
pub type Tri2 = [[i32; 2]; 3];

/// The two in-face axes of a face along `axis`: the same `(u, v)` as [`Dir::face_corners`].
#[inline]
pub fn face_axes(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// The 2D frame of a face: in-face axes `(u, v)` as [`face_axes`], origin at the face's minimum
/// corner, `UNITS` per side; heights are measured outward from the face plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceFrame {
    k: usize,
    u: usize,
    v: usize,
    w: f64,
    sign: f64,
    origin: DVec2,
    q: f64,
}

impl FaceFrame {
    /// The frame of face `face` of the cell `cell`.
    pub fn new(face: Dir, cell: &Aabb) -> FaceFrame {
        let k = face.axis();
        let (u, v) = face_axes(k);
        let w = if face.is_positive() { cell.max[k] } else { cell.min[k] } as f64;
        let side = (cell.max[u] - cell.min[u]).max(cell.max[v] - cell.min[v]) as f64;
        FaceFrame {
            k,
            u,
            v,
            w,
            sign: if face.is_positive() { 1.0 } else { -1.0 },
            origin: DVec2::new(cell.min[u] as f64, cell.min[v] as f64),
            q: UNITS / side,
        }
    }

    /// Units per world unit.
    #[inline]
    pub fn scale(&self) -> f64 {
        self.q
    }

    /// The in-face coordinates of `p`, in units.
    #[inline]
    pub fn units(&self, p: DVec3) -> DVec2 {
        DVec2::new((p[self.u] - self.origin.x) * self.q, (p[self.v] - self.origin.y) * self.q)
    }

    /// The point of the face plane at in-face coordinates `x` (units).
    pub fn point(&self, x: DVec2) -> DVec3 {
        let mut p = DVec3::ZERO;
        p[self.k] = self.w;
        p[self.u] = self.origin.x + x.x / self.q;
        p[self.v] = self.origin.y + x.y / self.q;
        p
    }

    /// Height of `p` above the face plane (positive outside the cell).
    #[inline]
    pub fn height(&self, p: DVec3) -> f64 {
        self.sign * (p[self.k] - self.w)
    }

    /// The half-space `height(p) >= h` as `n . p <= d`.
    pub(crate) fn above(&self, h: f64) -> (DVec3, f64) {
        let mut n = DVec3::ZERO;
        n[self.k] = -self.sign;
        (n, -self.sign * self.w - h)
    }

    /// The half-space `height(p) <= h` as `n . p <= d`.
    pub(crate) fn below(&self, h: f64) -> (DVec3, f64) {
        let mut n = DVec3::ZERO;
        n[self.k] = self.sign;
        (n, self.sign * self.w + h)
    }

    /// Central projection of `p` from the light point `v` (at height `hv > height(p)`) onto the face
    /// plane, in units.
    #[inline]
    pub(crate) fn project(&self, v: DVec3, hv: f64, p: DVec3) -> DVec2 {
        let lambda = hv / (hv - self.height(p));
        self.units(v + (p - v) * lambda)
    }
}

/// True if the face point `x` (units) lies in one of `tris`, edges included with a small slack.
#[inline]
pub fn in_triangles(tris: &[Tri2], x: DVec2) -> bool {
    tris.iter().any(|t| {
        let p = t.map(|v| DVec2::new(v[0] as f64, v[1] as f64));
        let orient = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        let s = if orient < 0.0 { -1.0 } else { 1.0 };
        (0..3).all(|i| {
            let (a, b) = (p[i], p[(i + 1) % 3]);
            s * (b - a).perp_dot(x - a) >= -0.5 * (b - a).length()
        })
    })
}
