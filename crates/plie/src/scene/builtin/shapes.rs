//! Mesh helpers for the built-in scenes of SPEC §6: boxes with chosen faces, hexahedra, swept tubes,
//! UV spheres, cylinders, tori and rectangles, all added straight to a [`SceneBuilder`].
//!
//! Conventions: every closed mesh is wound counter-clockwise around its **outward** normal (rooms, with
//! [`Facing::Inward`], around the inward one), and is watertight: a vertex shared by several triangles
//! is computed once and reused, so the watertight ray test of SPEC §5 cannot slip between them.
//!
//! Swept meshes are built from *rings*: consecutive rings of equal length are joined by quads, and a
//! ring of one point is a pole (a cone apex, or the centre of a flat cap). A ring must run
//! counter-clockwise around the direction in which the rings advance; then every face looks outward.

use glam::{Vec2, Vec3};

use crate::geometry::Dir;
use crate::scene::{MaterialId, SceneBuilder};

/// Every side of a box but the bottom: a block standing on something.
pub(crate) const NO_BOTTOM: [Dir; 5] = [Dir::Left, Dir::Right, Dir::Up, Dir::Back, Dir::Front];

/// The corners of a hexahedron's side (indices as in [`SceneBuilder::hexahedron`]), counter-clockwise
/// around the outward normal.
fn side_corners(side: Dir) -> [usize; 4] {
    match side {
        Dir::Left => [0, 4, 6, 2],
        Dir::Right => [1, 3, 7, 5],
        Dir::Down => [0, 1, 5, 4],
        Dir::Up => [2, 6, 7, 3],
        Dir::Back => [0, 2, 3, 1],
        Dir::Front => [4, 5, 7, 6],
    }
}

/// Which way the faces of a box look.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Facing {
    /// Away from the box's inside (a solid block).
    Outward,
    /// Into the box (the walls of a room).
    Inward,
}

/// How a tube's open ends are closed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Cap {
    /// Left open.
    Open,
    /// Closed by a flat disc (a fan around the end point).
    Flat,
}

/// One point of a tube's spine: centre and the two radii of its elliptical cross-section (`x` across,
/// `y` along the tube's reference "up"). A zero radius makes the ring a single point (a cone apex).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Node {
    /// Centre of the cross-section.
    pub(crate) center: Vec3,
    /// Radii across and up.
    pub(crate) radius: Vec2,
}

impl Node {
    /// A circular cross-section.
    pub(crate) fn round(center: Vec3, r: f32) -> Node {
        Node { center, radius: Vec2::splat(r) }
    }
}

/// The four corners of the rectangle `center ± u ± v`, counter-clockwise around `u x v`.
pub(crate) fn rect(center: Vec3, u: Vec3, v: Vec3) -> [Vec3; 4] {
    [center - u - v, center + u - v, center + u + v, center - u + v]
}

/// A deterministic hash of `(seed, i)` to `[0, 1)`: the scenes' only "randomness".
pub(crate) fn hash01(seed: u32, i: u32) -> f32 {
    let mut x = (seed as u64) << 32 | i as u64;
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 31;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// `n` points on the ellipse `center + rx cos(t) a + ry sin(t) b`, starting at `t = phase`; counter-
/// clockwise around `a x b`.
pub(crate) fn ellipse(center: Vec3, a: Vec3, b: Vec3, radius: Vec2, n: usize, phase: f32) -> Vec<Vec3> {
    if radius.x <= 0.0 || radius.y <= 0.0 {
        return vec![center];
    }
    (0..n)
        .map(|k| {
            let t = phase + std::f32::consts::TAU * k as f32 / n as f32;
            center + a * (radius.x * t.cos()) + b * (radius.y * t.sin())
        })
        .collect()
}

/// Where a piece of furniture stands: an origin and a rotation about +y, mapping the piece's local
/// coordinates (x right, y up, z toward its front) to the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Place {
    origin: Vec3,
    x: Vec3,
    z: Vec3,
}

impl Place {
    /// Local origin at `origin`, turned by `yaw_deg` about +y (counter-clockwise seen from above).
    pub(crate) fn new(origin: Vec3, yaw_deg: f32) -> Place {
        // Snap the rounding noise of quarter turns, so walls stay exactly where they are.
        let snap = |v: f32| if v.abs() < 1e-6 { 0.0 } else { v };
        let (s, c) = yaw_deg.to_radians().sin_cos();
        let (s, c) = (snap(s), snap(c));
        Place { origin, x: Vec3::new(c, 0.0, -s), z: Vec3::new(s, 0.0, c) }
    }

    /// The world point of local `v`.
    pub(crate) fn p(&self, v: Vec3) -> Vec3 {
        self.origin + self.dir(v)
    }

    /// The world direction of local `v`.
    pub(crate) fn dir(&self, v: Vec3) -> Vec3 {
        self.x * v.x + Vec3::Y * v.y + self.z * v.z
    }

    /// The local axes in the world (right-handed).
    pub(crate) fn frame(&self) -> [Vec3; 3] {
        [self.x, Vec3::Y, self.z]
    }

    /// The placement of a sub-part at local `v`, turned by a further `yaw_deg`.
    pub(crate) fn then(&self, v: Vec3, yaw_deg: f32) -> Place {
        let inner = Place::new(Vec3::ZERO, yaw_deg);
        Place { origin: self.p(v), x: self.dir(inner.x), z: self.dir(inner.z) }
    }
}

impl SceneBuilder {
    /// The hexahedron with corners `c[i]`, where bit 0 of `i` is "+x", bit 1 "+y", bit 2 "+z" of a
    /// (possibly deformed) box with positive orientation. Adds the listed sides (named by their outward
    /// direction, SPEC §3), two triangles each.
    pub(crate) fn hexahedron(&mut self, c: &[Vec3; 8], sides: &[Dir], facing: Facing, m: MaterialId) {
        for s in sides {
            let [a, b, cc, d] = side_corners(*s).map(|i| c[i]);
            match facing {
                Facing::Outward => self.quad(a, b, cc, d, m),
                Facing::Inward => self.quad(d, cc, b, a, m),
            }
        }
    }

    /// The axis-aligned box `[min, max]` with the listed sides.
    pub(crate) fn axis_box(&mut self, min: Vec3, max: Vec3, sides: &[Dir], facing: Facing, m: MaterialId) {
        let c = std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        });
        self.hexahedron(&c, sides, facing, m);
    }

    /// A closed box `center ± half.x u ± half.y v ± half.z w` for a right-handed orthonormal frame
    /// `u, v, w` (12 triangles).
    pub(crate) fn oriented_box(&mut self, center: Vec3, frame: [Vec3; 3], half: Vec3, m: MaterialId) {
        let [u, v, w] = frame;
        let c = std::array::from_fn(|i| {
            let s = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
            center + u * (half.x * s(1)) + v * (half.y * s(2)) + w * (half.z * s(4))
        });
        self.hexahedron(&c, &Dir::ALL, Facing::Outward, m);
    }

    /// The closed box `[min, max]` in `place`'s local coordinates (12 triangles).
    pub(crate) fn local_box(&mut self, place: &Place, min: Vec3, max: Vec3, m: MaterialId) {
        self.oriented_box(place.p(0.5 * (min + max)), place.frame(), 0.5 * (max - min), m);
    }

    /// A block standing on the horizontal quad `base` (counter-clockwise seen from above), `height`
    /// high: four sides and the top, no bottom (10 triangles).
    pub(crate) fn block_on(&mut self, base: [Vec3; 4], height: f32, m: MaterialId) {
        let up = Vec3::Y * height;
        // Bottom corners 0, 4, 5, 1 of a box run counter-clockwise seen from above.
        let c = [base[0], base[3], base[0] + up, base[3] + up, base[1], base[2], base[1] + up, base[2] + up];
        self.hexahedron(&c, &NO_BOTTOM, Facing::Outward, m);
    }

    /// Joins consecutive rings (see the module doc). `closed` joins the last ring to the first too.
    pub(crate) fn rings(&mut self, rings: &[Vec<Vec3>], closed: bool, m: MaterialId) {
        let n = rings.len();
        let pairs = if closed { n } else { n.saturating_sub(1) };
        for i in 0..pairs {
            let (a, b) = (&rings[i], &rings[(i + 1) % n]);
            match (a.len(), b.len()) {
                (1, 1) => {}
                (1, k) => (0..k).for_each(|j| {
                    self.triangle(a[0], b[(j + 1) % k], b[j], m);
                }),
                (k, 1) => (0..k).for_each(|j| {
                    self.triangle(a[j], a[(j + 1) % k], b[0], m);
                }),
                (k, l) => {
                    assert_eq!(k, l, "rings of different sizes");
                    for j in 0..k {
                        let j1 = (j + 1) % k;
                        self.quad(a[j], a[j1], b[j1], b[j], m);
                    }
                }
            }
        }
    }

    /// A tube swept along `spine` with `segments` points per ring (see [`frames`] for how `up` orients
    /// the cross-sections). Open ends with a non-zero radius get `cap`. `closed` makes the spine a loop
    /// (a torus-like ring; `cap` is then ignored).
    pub(crate) fn tube(&mut self, spine: &[Node], up: Vec3, segments: usize, cap: Cap, closed: bool, m: MaterialId) {
        let n = spine.len();
        let mut rings: Vec<Vec<Vec3>> = spine
            .iter()
            .zip(frames(spine, up, closed))
            .map(|(node, [_, a, b])| ellipse(node.center, a, b, node.radius, segments, 0.0))
            .collect();
        if !closed && cap == Cap::Flat {
            if rings[0].len() > 1 {
                rings.insert(0, vec![spine[0].center]);
            }
            if rings[rings.len() - 1].len() > 1 {
                rings.push(vec![spine[n - 1].center]);
            }
        }
        self.rings(&rings, closed, m);
    }

    /// A closed cylinder (or cone frustum) from `a` (radius `ra`) to `b` (radius `rb`), `4 * segments`
    /// triangles.
    pub(crate) fn cylinder(&mut self, a: Vec3, b: Vec3, ra: f32, rb: f32, segments: usize, m: MaterialId) {
        let up = any_perpendicular(b - a);
        let spine = [Node::round(a, ra), Node::round(b, rb)];
        self.tube(&spine, up, segments, Cap::Flat, false, m);
    }

    /// A UV sphere: `segments` around the vertical axis, `bands` from pole to pole:
    /// `2 * segments * (bands - 1)` triangles (32 x 16 gives 960).
    pub(crate) fn sphere(&mut self, center: Vec3, radius: f32, segments: usize, bands: usize, m: MaterialId) {
        let mut rings = vec![vec![center - Vec3::Y * radius]];
        for i in 1..bands {
            let phi = std::f32::consts::PI * i as f32 / bands as f32;
            let c = center - Vec3::Y * (radius * phi.cos());
            rings.push(ellipse(c, Vec3::Z, Vec3::X, Vec2::splat(radius * phi.sin()), segments, 0.0));
        }
        rings.push(vec![center + Vec3::Y * radius]);
        self.rings(&rings, false, m);
    }

    /// A superellipsoid (a cushion, a rounded block): half-sizes `half` along the right-handed frame
    /// `[u, v, w]`, squareness `exponent` (1 is an ellipsoid, toward 0 a box with rounded edges), poles
    /// on the `v` axis. `2 * segments * (bands - 1)` triangles.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn superellipsoid(
        &mut self,
        center: Vec3,
        [u, v, w]: [Vec3; 3],
        half: Vec3,
        exponent: f32,
        segments: usize,
        bands: usize,
        m: MaterialId,
    ) {
        let pow = |x: f32| x.signum() * x.abs().powf(exponent);
        let mut rings = vec![vec![center - v * half.y]];
        for i in 1..bands {
            let phi = -std::f32::consts::FRAC_PI_2 + std::f32::consts::PI * i as f32 / bands as f32;
            let (c, s) = (pow(phi.cos()), pow(phi.sin()));
            let ring = (0..segments).map(|k| {
                let t = std::f32::consts::TAU * k as f32 / segments as f32;
                // Counter-clockwise around w x u = v.
                center + v * (half.y * s) + w * (half.z * c * pow(t.cos())) + u * (half.x * c * pow(t.sin()))
            });
            rings.push(ring.collect());
        }
        rings.push(vec![center + v * half.y]);
        self.rings(&rings, false, m);
    }

    /// A torus around the axis `axis` through `center`: `2 * major * minor` triangles.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn torus(
        &mut self,
        center: Vec3,
        axis: Vec3,
        big_r: f32,
        small_r: f32,
        major: usize,
        minor: usize,
        m: MaterialId,
    ) {
        let axis = axis.normalize();
        let a = any_perpendicular(axis);
        let b = axis.cross(a);
        let spine: Vec<Node> = ellipse(center, a, b, Vec2::splat(big_r), major, 0.0)
            .into_iter()
            .map(|p| Node::round(p, small_r))
            .collect();
        self.tube(&spine, axis, minor, Cap::Open, true, m);
    }
}

/// The frame `[t, a, b]` of each spine node: `t` the unit tangent (central differences), `b` the
/// cross-section's "up" (`up` made perpendicular to the first tangent, then carried along the spine by
/// parallel transport, so the tube does not twist and `up` need only avoid the first tangent), and
/// `a = b x t`, so that `t, a, b` is right-handed and rings built on `a, b` run counter-clockwise
/// around `t`.
pub(crate) fn frames(spine: &[Node], up: Vec3, closed: bool) -> Vec<[Vec3; 3]> {
    let n = spine.len();
    let mut b = up;
    (0..n)
        .map(|i| {
            let (prev, next) = if closed {
                (spine[(i + n - 1) % n].center, spine[(i + 1) % n].center)
            } else {
                (spine[i.saturating_sub(1)].center, spine[(i + 1).min(n - 1)].center)
            };
            let t = (next - prev).normalize();
            b = (b - t * b.dot(t)).normalize();
            [t, b.cross(t), b]
        })
        .collect()
}

/// A smooth spine through the control nodes: Catmull-Rom for the centres, linear for the radii (so a
/// zero radius stays at the end it was given for), `per_span` nodes per span plus the last control.
pub(crate) fn smooth(control: &[Node], per_span: usize) -> Vec<Node> {
    let n = control.len();
    let p = |i: isize| -> Vec3 {
        if i < 0 {
            2.0 * control[0].center - control[1].center
        } else if i as usize >= n {
            2.0 * control[n - 1].center - control[n - 2].center
        } else {
            control[i as usize].center
        }
    };
    let mut out = Vec::with_capacity((n - 1) * per_span + 1);
    for i in 0..n - 1 {
        let (p0, p1, p2, p3) = (p(i as isize - 1), p(i as isize), p(i as isize + 1), p(i as isize + 2));
        for k in 0..per_span {
            let t = k as f32 / per_span as f32;
            let center = 0.5
                * (2.0 * p1
                    + (p2 - p0) * t
                    + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * (t * t)
                    + (3.0 * p1 - p0 - 3.0 * p2 + p3) * (t * t * t));
            let radius = control[i].radius.lerp(control[i + 1].radius, t);
            out.push(Node { center, radius });
        }
    }
    out.push(control[n - 1]);
    out
}

/// A unit vector perpendicular to `v`.
pub(crate) fn any_perpendicular(v: Vec3) -> Vec3 {
    let v = v.normalize();
    let other = if v.x.abs() < 0.6 { Vec3::X } else { Vec3::Y };
    v.cross(other).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;

    /// Signed volume of a closed mesh (positive if wound outward) and the check that every edge is used
    /// exactly once in each direction (watertight and consistently oriented).
    fn closed_volume(tris: &[Triangle]) -> f32 {
        let key = |p: Vec3| p.to_array().map(f32::to_bits);
        let mut edges = std::collections::HashMap::new();
        let mut vol = 0.0;
        for t in tris {
            vol += t.v[0].dot(t.v[1].cross(t.v[2])) / 6.0;
            for k in 0..3 {
                *edges.entry((key(t.v[k]), key(t.v[(k + 1) % 3]))).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge used {n} times in one direction");
            assert_eq!(edges.get(&(b, a)), Some(&1), "open or inconsistently wound edge");
        }
        vol
    }

    fn built(f: impl FnOnce(&mut SceneBuilder, MaterialId)) -> Vec<Triangle> {
        let mut b = SceneBuilder::new("t");
        let m = b.diffuse("m", Vec3::ONE);
        f(&mut b, m);
        b.light("l", &rect(Vec3::splat(10.0), Vec3::X, Vec3::Z), Vec3::ONE);
        let s = b.build().unwrap();
        assert_eq!(s.degenerate_skipped, 0);
        s.triangles[..s.triangles.len() - 2].to_vec()
    }

    #[test]
    fn boxes_are_closed_and_outward() {
        let t = built(|b, m| b.axis_box(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0), &Dir::ALL, Facing::Outward, m));
        assert!((closed_volume(&t) - 6.0).abs() < 1e-5);
        let t = built(|b, m| b.axis_box(Vec3::ZERO, Vec3::ONE, &Dir::ALL, Facing::Inward, m));
        assert!((closed_volume(&t) + 1.0).abs() < 1e-5);
        let frame = [Vec3::new(0.6, 0.0, 0.8), Vec3::Y, Vec3::new(-0.8, 0.0, 0.6)];
        let t = built(|b, m| b.oriented_box(Vec3::ONE, frame, Vec3::new(1.0, 0.5, 0.25), m));
        assert!((closed_volume(&t) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn block_faces_look_outward() {
        let base = [Vec3::ZERO, Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::X];
        let t = built(|b, m| b.block_on(base, 2.0, m));
        assert_eq!(t.len(), 10);
        let c = Vec3::new(0.5, 1.0, 0.5);
        assert!(t.iter().all(|t| t.normal().dot(t.centroid() - c) > 0.0));
    }

    #[test]
    fn sphere_cylinder_torus_are_closed_with_the_right_volume() {
        let t = built(|b, m| b.sphere(Vec3::ONE, 2.0, 32, 16, m));
        assert_eq!(t.len(), 960);
        let v = closed_volume(&t);
        assert!(v > 0.95 * 32.0 / 3.0 * std::f32::consts::PI && v < 32.0 / 3.0 * std::f32::consts::PI);
        let t = built(|b, m| b.cylinder(Vec3::ZERO, Vec3::new(0.0, 3.0, 1.0), 1.0, 0.5, 24, m));
        assert_eq!(t.len(), 96);
        assert!(closed_volume(&t) > 0.0);
        let t = built(|b, m| b.torus(Vec3::ZERO, Vec3::Y, 2.0, 0.5, 24, 12, m));
        assert_eq!(t.len(), 576);
        let v = closed_volume(&t);
        let exact = 2.0 * std::f32::consts::PI.powi(2) * 2.0 * 0.25;
        // 12 x 24 inscribed polygons keep about 94% of the volume.
        assert!(v > 0.9 * exact && v < exact, "{v} vs {exact}");
    }

    #[test]
    fn superellipsoids_are_closed_and_outward_in_any_right_handed_frame() {
        let (s, c) = 0.3f32.sin_cos();
        for frame in [[Vec3::X, Vec3::Y, Vec3::Z], [-Vec3::X, Vec3::new(0.0, s, c), Vec3::new(0.0, c, -s)]] {
            let t = built(|b, m| b.superellipsoid(Vec3::ONE, frame, Vec3::new(0.3, 0.1, 0.2), 0.3, 24, 8, m));
            assert_eq!(t.len(), 2 * 24 * 7);
            let v = closed_volume(&t);
            assert!(v > 0.8 * 8.0 * 0.006 && v < 8.0 * 0.006, "{v}");
        }
    }

    #[test]
    fn pointed_tubes_are_closed() {
        let spine = [
            Node::round(Vec3::ZERO, 0.0),
            Node::round(Vec3::new(1.0, 0.2, 0.0), 0.4),
            Node { center: Vec3::new(2.0, 0.5, 0.3), radius: Vec2::new(0.5, 0.3) },
            Node::round(Vec3::new(3.0, 0.5, 0.3), 0.0),
        ];
        let t = built(|b, m| b.tube(&spine, Vec3::Y, 12, Cap::Flat, false, m));
        assert_eq!(t.len(), 12 * 4);
        assert!(closed_volume(&t) > 0.0);
    }

    #[test]
    fn hash_is_deterministic_and_in_range() {
        let v: Vec<f32> = (0..1000).map(|i| hash01(7, i)).collect();
        assert!(v.iter().all(|&x| (0.0..1.0).contains(&x)));
        assert_eq!(v[17], hash01(7, 17));
        let mean = v.iter().sum::<f32>() / 1000.0;
        assert!((mean - 0.5).abs() < 0.05);
    }
}
