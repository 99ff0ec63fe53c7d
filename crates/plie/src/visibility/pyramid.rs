//! The pyramid from a shaded point `x` over a light polygon (issue 21): it contains every shadow ray
//! from `x` to the light, so a triangle or box beyond one of its planes (grown by a margin) meets
//! none of them. The per-light query culls its candidates with it before the fan's lane tests
//! ([`super::fan`]). A light of three or four corners has what every pyramid over it needs computed
//! once ([`PyramidBasis`]), so that a pyramid costs a few lane operations per (point, light) pair.

use glam::{Vec3, Vec4};

use crate::geometry::{Aabb, Triangle};
use crate::scene::{Light, LightId, Scene};
use crate::visibility::simd::Avx2;

/// The pyramid conv(`x` ∪ light polygon), as planes with inward unit normals through `x` (one per
/// light edge) and the light's own plane, each grown outward by `margin`.
#[derive(Clone, Debug, Default)]
pub struct Pyramid {
    /// Inward unit normals of the side planes (through the apex), for more than four sides (see
    /// [`Pyramid::sides`]).
    sides: Vec<Vec3>,
    /// For at most four sides: their normals, `few[..n]` (kept in place, not in `sides`).
    few: [Vec3; 4],
    n: usize,
    /// The same normals' `x`, `y` and `z` in four lanes, for at most four sides (a triangle's third
    /// side repeated); `None` for more sides (or none).
    lanes: Option<[Vec4; 3]>,
    /// Unit normal of the light plane pointing toward the apex, and the plane's offset.
    cap: (Vec3, f32),
    apex: Vec3,
    margin: f32,
    /// The light's corners relative to the apex, in four lanes per axis (a triangle's last corner
    /// twice), for lights of at most four corners ([`Pyramid::beside`]); `None` for more.
    corners: Option<[Vec4; 3]>,
    /// How far the light's samples may lie outside its polygon but for rounding ([`stray_of`]).
    stray: f32,
    /// The corners' lengths (the same lanes) and how far a sample's direction may lie from the
    /// corners' cone ([`Pyramid::outside_cone`]), computed on first use.
    cone: Option<(Vec4, f32)>,
    /// The pyramid's bounding box relative to the apex (the apex and the light's corners), grown
    /// by the margin, where [`Pyramid::bound`] computed it.
    bounds: Option<(Vec3, Vec3)>,
}

/// What [`Pyramid::set_from`] needs of a light of at most four corners, computed once per light
/// ([`PyramidBasis::of`]): its corners in lanes ([`corner_lanes`]), its
/// centre, normal and plane offset.
#[derive(Clone, Copy, Debug)]
pub struct PyramidBasis {
    /// Lane `i`: corner `min(i, n - 1)`, per axis.
    p: [Vec4; 3],
    /// Lane `i`: the corner after lane `i`'s (the last back to corner 0), per axis.
    q: [Vec4; 3],
    /// The first corner.
    v0: Vec3,
    /// [`Light::center`].
    centre: Vec3,
    /// The light's unit normal and `normal . v0`.
    cap: (Vec3, f32),
    /// Corners: 3 or 4.
    n: usize,
    /// How far the light's samples may lie outside its polygon but for rounding ([`stray_of`]).
    stray: f32,
}

/// The margin every per-light query grows its pyramid by: ten times the scene's tolerance
/// ([`Scene::tolerance`]: [`crate::geometry::TOLERANCE_REL`] of its size, or the rounding of its
/// coordinates where that is larger, so that a light's samples, rounded off its tilted plane far
/// from the origin, stay inside).
pub fn margin_of(scene: &Scene) -> f32 {
    scene.tolerance() * 10.0
}

impl PyramidBasis {
    /// The basis of `light`, if it has at most four corners.
    pub fn of(light: &Light) -> Option<PyramidBasis> {
        let v = &light.vertices;
        let n = v.len();
        if !(3..=4).contains(&n) {
            return None;
        }
        let (p, q) = corner_lanes(v);
        let (centre, cap) = (light.center(), (light.normal, light.normal.dot(v[0])));
        Some(PyramidBasis { p, q, v0: v[0], centre, cap, n, stray: stray_of(light) })
    }
}

/// How far the samples of `light` may lie outside its polygon, but for rounding: a parallelogram is
/// sampled over `v0`, `v1`, `v3` and `v1 + v3 - v0` ([`Light::sample`]), which is `v2` only up to
/// the deviation the light's check accepts; each such sample is within that deviation of the
/// polygon (the bilinear map's point of the polygon differs by `u v (v1 + v3 - v0 - v2)`). Other
/// polygons are sampled inside their triangles: 0.
fn stray_of(light: &Light) -> f32 {
    let v = &light.vertices;
    if light.parallelogram_edges().is_none() {
        return 0.0;
    }
    let d = v[1].as_dvec3() + v[3].as_dvec3() - v[0].as_dvec3() - v[2].as_dvec3();
    (d.length() * 1.01) as f32
}

/// The corners `p` of the edges of a polygon of three or four corners `v`, and the corners `q` they
/// lead to, in four lanes per axis: lane `i` holds edge `min(i, n - 1)` (a triangle's last edge
/// twice), the last edge back to corner 0.
fn corner_lanes(v: &[Vec3]) -> ([Vec4; 3], [Vec4; 3]) {
    let n = v.len();
    debug_assert!((3..=4).contains(&n));
    let corner = |i: usize| v[i.min(n - 1)];
    let next = |i: usize| v[(i.min(n - 1) + 1) % n];
    let lanes = |f: &dyn Fn(usize) -> Vec3| [0, 1, 2].map(|k| Vec4::new(f(0)[k], f(1)[k], f(2)[k], f(3)[k]));
    (lanes(&corner), lanes(&next))
}

impl Pyramid {
    /// Inward unit normals of the side planes (through the apex); none where the pyramid is not
    /// defined.
    #[inline(always)]
    fn sides(&self) -> &[Vec3] {
        if self.lanes.is_some() {
            &self.few[..self.n]
        } else {
            &self.sides
        }
    }

    /// [`Pyramid::set`] for a light of at most four corners from its precomputed `basis`: the same
    /// operations on the same values, so the same pyramid, bit for bit.
    pub fn set_from(&mut self, x: Vec3, basis: &PyramidBasis, margin: f32) -> bool {
        let ok = self.start(x, basis.cap, basis.v0, margin)
            && self.set_sides_from_lanes(x, (&basis.p, &basis.q), basis.centre - x, basis.n);
        if ok {
            self.stray = basis.stray;
        }
        ok
    }

    /// Empties the pyramid and sets its apex `x`, margin and cap (the light's unit normal and
    /// offset, `v0` a corner): false if `x` lies too close to the light's plane (within four
    /// margins) for the side planes to be well defined.
    fn start(&mut self, x: Vec3, cap: (Vec3, f32), v0: Vec3, margin: f32) -> bool {
        self.sides.clear();
        self.lanes = None;
        self.corners = None;
        (self.stray, self.cone) = (0.0, None);
        self.bounds = None;
        self.n = 0;
        self.apex = x;
        self.margin = margin;
        self.cap = cap;
        let h = cap.0.dot(x - v0);
        !(h.is_nan() || h <= 4.0 * margin)
    }

    /// The pyramid from `x` over `light`'s sample domain, grown by `margin` (a length). Returns false
    /// (and leaves an empty pyramid, which culls nothing) if `x` lies too close to the light's plane
    /// for the side planes to be well defined.
    pub fn set(&mut self, x: Vec3, light: &Light, margin: f32) -> bool {
        let (n, v) = (light.normal, &light.vertices);
        if !self.start(x, (n, n.dot(v[0])), v[0], margin) {
            return false;
        }
        // The sample domain's hull is the polygon (plus, for a parallelogram, its fourth corner
        // recomputed, within rounding of the vertex): the polygon's edges, grown by the margin.
        let toward_centre = light.center() - x;
        if v.len() <= 4 {
            let ok = self.set_sides_lanes(x, v, toward_centre);
            if ok {
                self.stray = stray_of(light);
            }
            ok
        } else {
            self.set_sides(x, v, toward_centre)
        }
    }

    /// The side planes of the polygon `v` seen from `x`, one edge at a time (polygons of more than
    /// four corners: no lanes); false (and no sides) if an edge's plane is not well defined.
    fn set_sides(&mut self, x: Vec3, v: &[Vec3], toward_centre: Vec3) -> bool {
        // Each edge (v[i], v[i + 1]), the last closing the polygon, relative to the apex.
        let mut q = v[0] - x;
        let first = q;
        for i in 0..v.len() {
            let p = q;
            q = if i + 1 < v.len() { v[i + 1] - x } else { first };
            // The plane through the apex and the edge (p, q), its normal turned toward the centre.
            let s = p.cross(q);
            let len = s.length();
            if len.is_nan() || len <= 0.0 || len.is_infinite() {
                self.sides.clear();
                return false;
            }
            let mut s = s / len;
            if s.dot(toward_centre) < 0.0 {
                s = -s;
            }
            self.sides.push(s);
        }
        true
    }

    /// [`Pyramid::set_sides`] for a triangle or a quadrilateral, its edges in four lanes (a
    /// triangle's last edge twice): the same operations in the same order (`Vec3::cross`,
    /// `length`, the division, `dot`), so the same planes, bit for bit.
    fn set_sides_lanes(&mut self, x: Vec3, v: &[Vec3], toward_centre: Vec3) -> bool {
        let (p, q) = corner_lanes(v);
        self.set_sides_from_lanes(x, (&p, &q), toward_centre, v.len())
    }

    /// The side planes seen from `x` of the edges `(p, q)` of a polygon of `n` corners, in lanes
    /// ([`corner_lanes`]): the body of [`Pyramid::set_sides_lanes`] and [`Pyramid::set_from`].
    #[inline(always)]
    fn set_sides_from_lanes(
        &mut self,
        x: Vec3,
        (p, q): (&[Vec4; 3], &[Vec4; 3]),
        toward_centre: Vec3,
        n: usize,
    ) -> bool {
        // The corners relative to the apex: `v - x` per component, as `Vec3`'s subtraction.
        let rel = |c: &[Vec4; 3]| [c[0] - Vec4::splat(x.x), c[1] - Vec4::splat(x.y), c[2] - Vec4::splat(x.z)];
        let ([px, py, pz], [qx, qy, qz]) = (rel(p), rel(q));
        // p x q, as `Vec3::cross`.
        let (sx, sy, sz) = (py * qz - qy * pz, pz * qx - qz * px, px * qy - qx * py);
        let len = (sx * sx + sy * sy + sz * sz).sqrt();
        if !len.is_finite() || len.cmple(Vec4::ZERO).any() {
            self.sides.clear();
            return false;
        }
        let (sx, sy, sz) = (sx / len, sy / len, sz / len);
        let flip = (sx * toward_centre.x + sy * toward_centre.y + sz * toward_centre.z).cmplt(Vec4::ZERO);
        let (sx, sy, sz) = (Vec4::select(flip, -sx, sx), Vec4::select(flip, -sy, sy), Vec4::select(flip, -sz, sz));
        self.few = [
            Vec3::new(sx.x, sy.x, sz.x),
            Vec3::new(sx.y, sy.y, sz.y),
            Vec3::new(sx.z, sy.z, sz.z),
            Vec3::new(sx.w, sy.w, sz.w),
        ];
        self.n = n;
        self.lanes = Some([sx, sy, sz]);
        self.corners = Some([px, py, pz]);
        true
    }

    /// [`Pyramid::set`] from `x` over light `light` of `scene`, grown by the margin every per-light
    /// query uses: ten times the scene's tolerance ([`TOLERANCE_REL`] of its size).
    pub fn set_in(&mut self, scene: &Scene, x: Vec3, light: LightId) -> bool {
        self.set(x, &scene.lights[light.idx()], margin_of(scene))
    }

    /// Computes the pyramid's bounding box (where it keeps the light's corners), so that
    /// [`Pyramid::culls_rel8`] also culls the boxes outside it: a fan of many rays asks for it
    /// before its walk ([`super::fan::Fan::ready_boxes`]); for a few rays it costs more than it
    /// saves (measured, docs/results.md issue 21 session 29).
    pub(crate) fn bound(&mut self) {
        if let Some([px, py, pz]) = self.corners {
            let lo = Vec3::new(px.min_element(), py.min_element(), pz.min_element()).min(Vec3::ZERO);
            let hi = Vec3::new(px.max_element(), py.max_element(), pz.max_element()).max(Vec3::ZERO);
            self.bounds = Some((lo - Vec3::splat(self.margin), hi + Vec3::splat(self.margin)));
        }
    }

    /// True if the plane of the triangle `(a, b, c)` (given relative to the apex) has the apex and
    /// every corner of the light on one side, each farther than the margin: then every segment
    /// from the apex to the light (within the margin) lies on that side, at least the margin from
    /// the triangle, as the sides' cull ([`Pyramid::culls`]) leaves it. The plane is computed in
    /// `f64` from the `f32` vertices (their differences and the products of those are exact there,
    /// but for coordinates of very different size), and a sliver (its normal shorter than `1e-6`
    /// times the product of its edges, so that a rounding could tilt it) is never beside. False
    /// for lights of more than four corners.
    #[inline(always)]
    pub(crate) fn beside(&self, a: Vec3, b: Vec3, c: Vec3) -> bool {
        let Some([cx, cy, cz]) = self.corners else {
            return false;
        };
        let (a, e, f) = (a.as_dvec3(), (b.as_dvec3() - a.as_dvec3()), (c.as_dvec3() - a.as_dvec3()));
        let n = e.cross(f);
        let nn = n.length_squared();
        // (Written so that a NaN is never beside.)
        let wide = nn > 1e-12 * e.length_squared() * f.length_squared();
        if !wide {
            return false;
        }
        let k = n.dot(a);
        let m = f64::from(self.margin) * f64::from(self.margin) * nn;
        // The apex's side (its offset is `-k`), then each corner's on the same side.
        let s0 = -k;
        let clear = s0 * s0 > m;
        if !clear {
            return false;
        }
        let (cx, cy, cz) = (cx.as_dvec4(), cy.as_dvec4(), cz.as_dvec4());
        let s = cx * n.x + cy * n.y + cz * n.z - glam::DVec4::splat(k);
        let same = if s0 > 0.0 { s.cmpgt(glam::DVec4::ZERO) } else { s.cmplt(glam::DVec4::ZERO) };
        same.all() && (s * s).cmpgt(glam::DVec4::splat(m)).all()
    }

    /// True if every sample of the light lies clearly outside the cone from the apex over a
    /// triangle, as the fan's edge test decides each ray ([`super::fan`]): `s` are the triangle's
    /// three edge normals through the apex, scaled by the inverse of their margins, so that a ray
    /// of direction `d` is a sure miss where one `s_i . d` exceeds `|d|` and another is below
    /// `-|d|`. Each edge function is linear in `d`, so where every corner `c` gives
    /// `s_i . c > 1.1 (|c| + r (1 + |s_i|))` (and another edge the same below), so does every
    /// direction in the corners' cone, and a sample's direction strays from that cone by at most
    /// `r` (computed on first use with the corners' lengths, the field `cone`); the factor 1.1
    /// covers the rounding of `s_i . c` (at most
    /// `3 ε |s_i| |c|`, and `|s_i| <= 1 / (256 ε)`). False for lights of more than four corners.
    #[inline(always)]
    pub(crate) fn outside_cone(&mut self, s: &[Vec3; 3]) -> bool {
        let Some([cx, cy, cz]) = self.corners else {
            return false;
        };
        let (len, reach) = *self.cone.get_or_insert_with(|| {
            // A sample's direction `fl(fl(y) - x)` lies within a few roundings of the world
            // coordinates of the light and of `x` from the corners' cone (a sample
            // `v0 + e1 u + e3 v` rounds by at most about `20 ε` of the largest coordinate, its
            // direction and the corners' by `ε` of theirs; the Euclidean norm is at most `sqrt 3`
            // times that): 64 roundings of the L1 norms (the corners' world coordinates within a
            // rounding of `c + x`), and what a parallelogram's samples may stray beyond its
            // polygon ([`stray_of`]).
            let x = self.apex;
            let world = (cx + Vec4::splat(x.x)).abs() + (cy + Vec4::splat(x.y)).abs() + (cz + Vec4::splat(x.z)).abs();
            let l1 = world.max_element() + x.abs().element_sum();
            ((cx * cx + cy * cy + cz * cz).sqrt(), 64.0 * f32::EPSILON * l1 + self.stray)
        });
        let (mut above, mut below) = (false, false);
        for si in s {
            let e = cx * si.x + cy * si.y + cz * si.z;
            let t = (len + Vec4::splat(reach * (1.0 + si.length()))) * 1.1;
            above |= e.cmpgt(t).all();
            below |= e.cmplt(-t).all();
        }
        above && below
    }

    /// True if no segment from the apex to a point of the light (within the margin) can meet
    /// `tri`: all its vertices lie beyond one plane.
    #[inline]
    pub fn culls(&self, tri: &Triangle) -> bool {
        let x = self.apex;
        let m = self.margin;
        let (a, b, c) = (tri.v[0] - x, tri.v[1] - x, tri.v[2] - x);
        if let Some([sx, sy, sz]) = self.lanes {
            // Four sides at once, each dot product in `Vec3::dot`'s order (so the same values).
            let beyond = |p: Vec3| (sx * p.x + sy * p.y + sz * p.z).cmplt(Vec4::splat(-m));
            if (beyond(a) & beyond(b) & beyond(c)).any() {
                return true;
            }
        } else {
            for s in self.sides() {
                if s.dot(a) < -m && s.dot(b) < -m && s.dot(c) < -m {
                    return true;
                }
            }
        }
        if self.sides().is_empty() {
            return false;
        }
        let (n, off) = self.cap;
        n.dot(tri.v[0]) - off < -m && n.dot(tri.v[1]) - off < -m && n.dot(tri.v[2]) - off < -m
    }

    /// Of up to eight triangles in lanes, those [`Pyramid::culls`] culls, as bits (bit `c` for lane
    /// `c`; lanes past the block's triangles come out as its zero triangles do). With `simd` and
    /// at most four sides, eight lanes at a time: the same operations in the same order, so the
    /// same bits.
    #[inline]
    pub(crate) fn culls8(&self, t: &TriLanes, simd: Option<Avx2>) -> u8 {
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        #[cfg(target_arch = "x86_64")]
        if let (Some(_), Some(lanes)) = (simd, &self.lanes) {
            // SAFETY: AVX2 is available (the proof).
            return unsafe { self.culls8_avx(lanes, t) };
        }
        (0..8).fold(0, |bits, c| bits | u8::from(self.culls(&t.triangle(c))) << c)
    }

    /// [`Pyramid::culls8`] in AVX lanes, for at most four sides (`lanes`: [`Pyramid::lanes`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    unsafe fn culls8_avx(&self, [sx, sy, sz]: &[Vec4; 3], t: &TriLanes) -> u8 {
        use std::arch::x86_64::*;
        let load = |v: &[f32; 8]| {
            // SAFETY: eight floats.
            unsafe { _mm256_loadu_ps(v.as_ptr()) }
        };
        let (sp, mul, add) = (|v: f32| _mm256_set1_ps(v), |a, b| _mm256_mul_ps(a, b), |a, b| _mm256_add_ps(a, b));
        let x = self.apex;
        let m = sp(-self.margin);
        // Each vertex, absolute (for the cap) and relative to the apex (for the sides).
        let abs = t.v.map(|v| v.map(|a| load(&a)));
        let rel = abs
            .map(|[vx, vy, vz]| [_mm256_sub_ps(vx, sp(x.x)), _mm256_sub_ps(vy, sp(x.y)), _mm256_sub_ps(vz, sp(x.z))]);
        let mut culled = _mm256_setzero_ps();
        // The four lanes of the sides (a triangle's third side repeated: the same test twice).
        for i in 0..4 {
            let (a, b, c) = (sp(sx[i]), sp(sy[i]), sp(sz[i]));
            let beyond = |[px, py, pz]: [__m256; 3]| {
                _mm256_cmp_ps::<_CMP_LT_OQ>(add(add(mul(a, px), mul(b, py)), mul(c, pz)), m)
            };
            let all = _mm256_and_ps(_mm256_and_ps(beyond(rel[0]), beyond(rel[1])), beyond(rel[2]));
            culled = _mm256_or_ps(culled, all);
        }
        // The cap (the pyramid has sides: `lanes` holds them).
        let (n, off) = self.cap;
        let (nx, ny, nz, off) = (sp(n.x), sp(n.y), sp(n.z), sp(off));
        let below = |[px, py, pz]: [__m256; 3]| {
            _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_sub_ps(add(add(mul(nx, px), mul(ny, py)), mul(nz, pz)), off), m)
        };
        let all = _mm256_and_ps(_mm256_and_ps(below(abs[0]), below(abs[1])), below(abs[2]));
        _mm256_movemask_ps(_mm256_or_ps(culled, all)) as u8
    }

    /// True if no segment of the pyramid can meet anything in the box `[lo, hi]`, given relative to
    /// the apex. Only the side planes (and, where [`Pyramid::bound`] computed it, the bounding box)
    /// are tested. (The walks use [`Pyramid::culls_rel8`]; this is its reference.)
    #[cfg(test)]
    pub fn culls_rel(&self, lo: Vec3, hi: Vec3) -> bool {
        let m = self.margin;
        if let Some([sx, sy, sz]) = self.lanes {
            // The box corner farthest along each normal, four normals at once.
            let far =
                |s: Vec4, lo: f32, hi: f32| Vec4::select(s.cmpge(Vec4::ZERO), Vec4::splat(hi), Vec4::splat(lo)) * s;
            let d = far(sx, lo.x, hi.x) + far(sy, lo.y, hi.y) + far(sz, lo.z, hi.z);
            let outside = self.bounds.is_some_and(|(bl, bh)| lo.cmpgt(bh).any() || hi.cmplt(bl).any());
            return d.cmplt(Vec4::splat(-m)).any() || outside;
        }
        self.sides().iter().any(|s| s.dot(Vec3::select(s.cmpge(Vec3::ZERO), hi, lo)) < -m)
    }

    /// Which of eight boxes, given relative to the apex as lanes (`lo[axis][c]`, `hi[axis][c]` for
    /// box `c`), no segment of the pyramid can meet: bit `c` is set if box `c` lies beyond a side
    /// plane (the corner farthest along its normal still beyond it by the margin) or, where
    /// [`Pyramid::bound`] computed it, outside the pyramid's bounding box.
    #[inline(always)]
    pub(crate) fn culls_rel8(&self, lo: &[[f32; 8]; 3], hi: &[[f32; 8]; 3], simd: Option<Avx2>) -> u8 {
        #[cfg(not(target_arch = "x86_64"))]
        let _ = simd;
        #[cfg(target_arch = "x86_64")]
        if simd.is_some() {
            // SAFETY: AVX2 is available (the proof).
            return unsafe { self.culls_rel8_avx(lo, hi) };
        }
        let m = -self.margin;
        let mut culled = [0u32; 8];
        for s in self.sides().iter().copied() {
            let far = |k: usize| if s[k] >= 0.0 { hi[k] } else { lo[k] };
            let (fx, fy, fz) = (far(0), far(1), far(2));
            for c in 0..8 {
                culled[c] |= u32::from(s.x * fx[c] + s.y * fy[c] + s.z * fz[c] < m);
            }
        }
        if let Some((bl, bh)) = self.bounds {
            for k in 0..3 {
                for c in 0..8 {
                    culled[c] |= u32::from(lo[k][c] > bh[k] || hi[k][c] < bl[k]);
                }
            }
        }
        (0..8).fold(0, |bits, c| bits | (culled[c] as u8) << c)
    }

    /// [`Pyramid::culls_rel8`] with the eight boxes in AVX lanes (the same operations in the same
    /// order, so the same bits).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx,avx2")]
    #[inline]
    unsafe fn culls_rel8_avx(&self, lo: &[[f32; 8]; 3], hi: &[[f32; 8]; 3]) -> u8 {
        use std::arch::x86_64::*;
        let m = _mm256_set1_ps(-self.margin);
        let mut culled = _mm256_setzero_ps();
        for s in self.sides().iter().copied() {
            let far = |k: usize| {
                let v = if s[k] >= 0.0 { &hi[k] } else { &lo[k] };
                // SAFETY: eight floats.
                unsafe { _mm256_loadu_ps(v.as_ptr()) }
            };
            let (fx, fy, fz) = (far(0), far(1), far(2));
            let d = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(s.x), fx), _mm256_mul_ps(_mm256_set1_ps(s.y), fy)),
                _mm256_mul_ps(_mm256_set1_ps(s.z), fz),
            );
            culled = _mm256_or_ps(culled, _mm256_cmp_ps::<_CMP_LT_OQ>(d, m));
        }
        // Boxes outside the pyramid's bounding box.
        if let Some((bl, bh)) = self.bounds {
            for k in 0..3 {
                // SAFETY: eight floats each.
                let (l, h) = unsafe { (_mm256_loadu_ps(lo[k].as_ptr()), _mm256_loadu_ps(hi[k].as_ptr())) };
                culled = _mm256_or_ps(culled, _mm256_cmp_ps::<_CMP_GT_OQ>(l, _mm256_set1_ps(bh[k])));
                culled = _mm256_or_ps(culled, _mm256_cmp_ps::<_CMP_LT_OQ>(h, _mm256_set1_ps(bl[k])));
            }
        }
        _mm256_movemask_ps(culled) as u8
    }

    /// True if no segment of the pyramid can meet anything in the box `b`.
    #[inline]
    pub fn culls_box(&self, b: &Aabb) -> bool {
        if self.sides().is_empty() {
            return false;
        }
        let x = self.apex;
        let m = self.margin;
        // The box corner farthest along the normal.
        let far = |s: Vec3| Vec3::select(s.cmpge(Vec3::ZERO), b.max, b.min);
        for s in self.sides() {
            if s.dot(far(*s) - x) < -m {
                return true;
            }
        }
        let (n, off) = self.cap;
        n.dot(far(n)) - off < -m
    }
}

/// Up to eight triangles in lanes, for [`Pyramid::culls8`]: `v[k][axis][lane]` is coordinate
/// `axis` of vertex `k` of the block's triangle `lane` (zero past the last).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct TriLanes {
    v: [[[f32; 8]; 3]; 3],
}

impl TriLanes {
    /// The block of `tris` (at most eight).
    pub(crate) fn of<'t>(tris: impl IntoIterator<Item = &'t Triangle>) -> TriLanes {
        let mut t = TriLanes::default();
        for (c, tri) in tris.into_iter().take(8).enumerate() {
            for (k, v) in tri.v.iter().enumerate() {
                for axis in 0..3 {
                    t.v[k][axis][c] = v[axis];
                }
            }
        }
        t
    }

    /// Lane `c`'s triangle.
    fn triangle(&self, c: usize) -> Triangle {
        let v = |k: usize| Vec3::new(self.v[k][0][c], self.v[k][1][c], self.v[k][2][c]);
        Triangle::new(v(0), v(1), v(2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Rng;

    /// The four-lane cull decides as the side-by-side loop does, for triangles, quadrilaterals and a
    /// pentagon (which takes the loop), on random triangles around the pyramid.
    #[test]
    fn lane_cull_equals_the_loop() {
        // Counter-clockwise seen from below, so each light faces the apex at y = 0.
        let lights = [
            vec![Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, 2.0, 0.0), Vec3::new(0.0, 2.0, 1.0)],
            vec![
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(1.0, 2.0, 0.0),
                Vec3::new(1.0, 2.0, 1.0),
                Vec3::new(0.0, 2.0, 1.0),
            ],
            vec![
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(1.0, 2.0, 0.0),
                Vec3::new(1.0, 2.0, 1.0),
                Vec3::new(0.5, 2.0, 1.5),
                Vec3::new(0.0, 2.0, 1.0),
            ],
        ];
        let mut rng = Rng::stream(7, 0, 0, 0);
        let mut culled = 0;
        for vertices in lights {
            let light = Light::new(vertices, Vec3::ONE, vec![]).unwrap();
            let mut p = Pyramid::default();
            assert!(p.set(Vec3::new(0.3, 0.0, 0.4), &light, 1e-4));
            let mut loop_only = p.clone();
            loop_only.sides = p.sides().to_vec();
            loop_only.lanes = None;
            for _ in 0..20_000 {
                let mut v =
                    || Vec3::new(rng.next_f32() * 4.0 - 1.5, rng.next_f32() * 3.0 - 0.5, rng.next_f32() * 4.0 - 1.5);
                let tri = Triangle::new(v(), v(), v());
                assert_eq!(p.culls(&tri), loop_only.culls(&tri), "{tri:?}");
                culled += usize::from(p.culls(&tri));
            }
        }
        // Both answers occur.
        assert!(culled > 1000 && culled < 59_000, "{culled}");
    }

    /// The pyramid from a light's precomputed basis is the one [`Pyramid::set`] makes, bit for bit
    /// (sides, lanes, cap, and whether it is defined), for a triangle and a skewed quadrilateral
    /// from random points around them (some too close to the light's plane); a pentagon has no
    /// basis.
    #[test]
    fn basis_sets_the_same_pyramid() {
        let (o, e1, e3) = (Vec3::new(0.13, 2.0, 0.07), Vec3::new(0.31, 0.02, 0.97), Vec3::new(0.93, -0.01, -0.29));
        let lights = [vec![o, o + e3, o + e1], vec![o, o + e3, o + e1 + e3, o + e1]];
        let mut rng = Rng::stream(9, 0, 0, 0);
        let mut defined = 0;
        for vertices in lights {
            let light = Light::new(vertices, Vec3::ONE, vec![]).unwrap();
            let basis = PyramidBasis::of(&light).expect("at most four corners");
            for _ in 0..5_000 {
                let x = Vec3::new(rng.next_f32() * 3.0 - 1.0, rng.next_f32() * 2.1, rng.next_f32() * 3.0 - 1.0);
                let (mut a, mut b) = (Pyramid::default(), Pyramid::default());
                let ok = a.set(x, &light, 1e-4);
                assert_eq!(b.set_from(x, &basis, 1e-4), ok, "{x}");
                let bits = |p: &Pyramid| {
                    let sides: Vec<[u32; 3]> = p.sides().iter().map(|s| s.to_array().map(f32::to_bits)).collect();
                    let lanes = p.lanes.map(|l| l.map(|v| v.to_array().map(f32::to_bits)));
                    let corners = p.corners.map(|c| c.map(|v| v.to_array().map(f32::to_bits)));
                    let reach = (p.stray.to_bits(), p.cone.is_some());
                    let cap = (p.cap.0.to_array().map(f32::to_bits), p.cap.1.to_bits());
                    (sides, lanes, cap, p.apex, p.margin, corners, reach)
                };
                assert_eq!(bits(&a), bits(&b), "{x}");
                defined += usize::from(ok);
            }
        }
        assert!(defined > 5_000 && defined < 10_000, "{defined}");
        let pentagon = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.5, 1.5], [0.0, 1.0]].map(|[a, b]| Vec3::new(a, 2.0, b));
        assert!(PyramidBasis::of(&Light::new(pentagon.to_vec(), Vec3::ONE, vec![]).unwrap()).is_none());
    }

    /// A triangle [`Pyramid::beside`] the pyramid meets no segment from the apex to a sample of the
    /// light (the watertight test, on the light's corners and random points of it): random
    /// triangles around the pyramid, some touching the apex or the light, some slivers; both
    /// answers occur.
    #[test]
    fn beside_triangles_meet_no_segment() {
        use crate::geometry::RayTest;
        use crate::visibility::query::SEGMENT_EPS;
        let (o, e1, e3) = (Vec3::new(0.13, 2.0, 0.07), Vec3::new(0.31, 0.02, 0.97), Vec3::new(0.93, -0.01, -0.29));
        let light = Light::new(vec![o, o + e3, o + e1 + e3, o + e1], Vec3::ONE, vec![]).unwrap();
        let basis = PyramidBasis::of(&light).unwrap();
        let mut rng = Rng::stream(12, 0, 0, 0);
        let (mut beside, mut tested) = (0, 0);
        for i in 0..4_000 {
            let x = Vec3::new(rng.next_f32() * 3.0 - 1.0, rng.next_f32() * 1.5, rng.next_f32() * 3.0 - 1.0);
            let mut p = Pyramid::default();
            if !p.set_from(x, &basis, 1e-4) {
                continue;
            }
            let samples: Vec<Vec3> = (0..32)
                .map(|k| match k {
                    0..4 => light.vertices[k],
                    _ => o + e1 * rng.next_f32() + e3 * rng.next_f32(),
                })
                .collect();
            for j in 0..8 {
                let mut v =
                    || Vec3::new(rng.next_f32() * 4.0 - 1.5, rng.next_f32() * 3.0 - 0.5, rng.next_f32() * 4.0 - 1.5);
                let (mut a, b, mut c) = (v(), v(), v());
                match (i + j) % 4 {
                    // Touching the apex.
                    0 => a = x,
                    // Touching the light.
                    1 => a = samples[4],
                    // A sliver.
                    2 => c = a + (b - a) * 0.37 + Vec3::splat(1e-6),
                    _ => {}
                }
                let tri = Triangle::new(a, b, c);
                if !p.beside(a - x, b - x, c - x) {
                    continue;
                }
                beside += 1;
                for &y in &samples {
                    tested += 1;
                    let test = RayTest::new(x, y - x, SEGMENT_EPS, 1.0 - SEGMENT_EPS);
                    assert!(test.hit(&tri).is_none(), "apex {x}, sample {y}, {tri:?}");
                }
            }
        }
        assert!(beside > 2_000 && beside < 30_000, "{beside} of 32,000");
        assert!(tested > 0);
    }

    /// Eight boxes at once decide as one at a time, on random boxes around the pyramid.
    #[test]
    fn eight_box_cull_equals_one_at_a_time() {
        let light = Light::new(
            vec![
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(1.0, 2.0, 0.0),
                Vec3::new(1.0, 2.0, 1.0),
                Vec3::new(0.0, 2.0, 1.0),
            ],
            Vec3::ONE,
            vec![],
        )
        .unwrap();
        let mut p = Pyramid::default();
        let apex = Vec3::new(0.3, 0.0, 0.4);
        assert!(p.set(apex, &light, 1e-4));
        // With the bounding box (which culls the boxes above the light and below the apex).
        p.bound();
        let mut rng = Rng::stream(8, 0, 0, 0);
        let mut culled = 0;
        for _ in 0..5_000 {
            let (mut lo, mut hi) = ([[0f32; 8]; 3], [[0f32; 8]; 3]);
            for c in 0..8 {
                for k in 0..3 {
                    let (a, b) = (rng.next_f32() * 4.0 - 2.0, rng.next_f32() * 4.0 - 2.0);
                    (lo[k][c], hi[k][c]) = (a.min(b), a.max(b));
                }
            }
            let bits = p.culls_rel8(&lo, &hi, Avx2::detect());
            assert_eq!(p.culls_rel8(&lo, &hi, None), bits);
            for c in 0..8 {
                let (l, h) = (Vec3::new(lo[0][c], lo[1][c], lo[2][c]), Vec3::new(hi[0][c], hi[1][c], hi[2][c]));
                let one = p.culls_rel(l, h);
                assert_eq!(bits >> c & 1 == 1, one, "box {c}");
                culled += usize::from(one);
                // A culled box meets no segment from the apex to a point of the light (a slab
                // test in f64).
                for _ in 0..one as usize * 16 {
                    let y = light.sample(glam::Vec2::new(rng.next_f32(), rng.next_f32())) - apex;
                    let (mut t0, mut t1) = (0f64, 1f64);
                    for k in 0..3 {
                        let (o, d) = (0f64, f64::from(y[k]));
                        let (a, b) = (f64::from(l[k]) - o, f64::from(h[k]) - o);
                        if d == 0.0 {
                            if a > 0.0 || b < 0.0 {
                                t1 = -1.0;
                            }
                        } else {
                            let (u, v) = (a / d, b / d);
                            (t0, t1) = (t0.max(u.min(v)), t1.min(u.max(v)));
                        }
                    }
                    assert!(t0 > t1, "box {l} {h} meets the segment to {y}");
                }
            }
        }
        assert!(culled > 1000 && culled < 39_000, "{culled}");
    }

    /// Eight triangles culled in lanes are those culled one at a time, with and without AVX2:
    /// over a triangle, a quadrilateral and a hexagon (no lanes) as lights, apexes above and
    /// beside them and one on the light's plane (an empty pyramid), and triangles whose vertices
    /// lie a hair inside or outside a side or the cap, or far away; blocks of one to eight.
    #[test]
    fn eight_triangle_cull_equals_one_at_a_time() {
        let square = vec![
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::new(0.0, 2.0, 1.0),
        ];
        let triangle = square[..3].to_vec();
        let hexagon: Vec<Vec3> = (0..6)
            .map(|i| {
                let a = std::f32::consts::TAU * i as f32 / 6.0;
                Vec3::new(0.5 + 0.5 * a.cos(), 2.0, 0.5 + 0.5 * a.sin())
            })
            .collect();
        let mut rng = Rng::stream(9, 0, 0, 0);
        let (mut culled, mut kept) = (0, 0);
        for vertices in [square, triangle, hexagon] {
            let light = Light::new(vertices, Vec3::ONE, vec![]).unwrap();
            for apex in [Vec3::new(0.3, 0.0, 0.4), Vec3::new(-1.5, 0.5, 2.0), Vec3::new(0.5, 2.0, 3.0)] {
                let mut p = Pyramid::default();
                let ok = p.set(apex, &light, 1e-4);
                assert_eq!(ok, apex.y < 1.9);
                for round in 0..400 {
                    let n = 1 + round % 8;
                    let tris: Vec<Triangle> = (0..n)
                        .map(|_| {
                            // Near the light's corners and the apex (a hair either side of the
                            // planes), or anywhere in a box around them.
                            let near = |rng: &mut Rng| {
                                let base = if rng.next_f32() < 0.5 { light.vertices[0] } else { apex };
                                let e = 1e-4 * (rng.next_f32() * 4.0 - 2.0);
                                base + Vec3::new(e, -e, e) * (1.0 + rng.next_f32())
                            };
                            let far = |rng: &mut Rng| {
                                Vec3::new(
                                    rng.next_f32() * 6.0 - 3.0,
                                    rng.next_f32() * 6.0 - 2.0,
                                    rng.next_f32() * 6.0 - 3.0,
                                )
                            };
                            let mut v = || if rng.next_f32() < 0.3 { near(&mut rng) } else { far(&mut rng) };
                            Triangle::new(v(), v(), v())
                        })
                        .collect();
                    let lanes = TriLanes::of(&tris);
                    let bits = p.culls8(&lanes, Avx2::detect());
                    assert_eq!(p.culls8(&lanes, None), bits);
                    for (c, tri) in tris.iter().enumerate() {
                        let one = p.culls(tri);
                        assert_eq!(bits >> c & 1 == 1, one, "triangle {c} of {n}: {tri:?}");
                        (culled, kept) = (culled + usize::from(one), kept + usize::from(!one));
                    }
                }
            }
        }
        assert!(culled > 1000 && kept > 1000, "{culled} culled, {kept} kept");
    }

    /// The planes of a triangle or quadrilateral computed in lanes are the edge-by-edge loop's, bit
    /// for bit, and both refuse the same degenerate apexes (on an edge's line).
    #[test]
    fn lane_sides_equal_the_loop() {
        let mut rng = Rng::stream(11, 0, 0, 0);
        let mut r = |scale: f32| (rng.next_f32() - 0.5) * scale;
        let bits = |sides: &[Vec3]| -> Vec<[u32; 3]> { sides.iter().map(|s| s.to_array().map(f32::to_bits)).collect() };
        let mut refused = 0;
        for k in 0..400 {
            let n = 3 + k % 2;
            let v: Vec<Vec3> = (0..n).map(|_| Vec3::new(r(4.0), 3.0 + r(0.1), r(4.0))).collect();
            // Every tenth apex on the line of the first edge: no plane there.
            let x = if k % 10 == 0 { v[0] + (v[1] - v[0]) * 2.0 } else { Vec3::new(r(8.0), r(2.0), r(8.0)) };
            let toward = v.iter().copied().sum::<Vec3>() / n as f32 - x;
            let (mut a, mut b) = (Pyramid::default(), Pyramid::default());
            let (ra, rb) = (a.set_sides(x, &v, toward), b.set_sides_lanes(x, &v, toward));
            assert_eq!(ra, rb, "apex {x}, light {v:?}");
            assert_eq!(bits(a.sides()), bits(b.sides()), "apex {x}, light {v:?}");
            // The lanes hold the loop's sides, a triangle's last one twice.
            if ra {
                let [sx, sy, sz] = b.lanes.expect("lanes for at most four sides");
                let lane_sides: Vec<Vec3> = (0..4).map(|i| Vec3::new(sx[i], sy[i], sz[i])).collect();
                let padded: Vec<Vec3> = (0..4).map(|i| a.sides()[i.min(n - 1)]).collect();
                assert_eq!(bits(&lane_sides), bits(&padded), "apex {x}, light {v:?}");
            }
            refused += usize::from(!ra);
        }
        assert!(refused >= 20, "{refused}");
    }
}
