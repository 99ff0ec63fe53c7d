//! Area lights from the emissive triangles of a scene file (SPEC §1: lights are one-sided planar convex
//! polygons, built from triangles).
//!
//! Files store lights as triangles with an emissive material. Triangles that have the same radiance, lie
//! in one plane, face the same way and share edges are fused into one light whose polygon is the
//! boundary of their union, counter-clockwise around the emitting side:
//!
//! 1. Vertices are welded by position (files often duplicate shared vertices), within a tolerance
//!    relative to the triangles' size ([`weld_tolerance`]).
//! 2. Two triangles are neighbours if they share a welded edge in opposite directions (consistent
//!    winding), have the same radiance (bit for bit) and their normals agree within `1e-4` rad.
//! 3. A connected set of neighbours whose boundary is one simple, planar, convex loop (after dropping
//!    collinear vertices) becomes one light: a quad of two triangles, a fan, a grid of quads.
//! 4. Otherwise (an L shape, a ring, a bent strip) the set is split greedily into convex parts: a part
//!    grows from a seed triangle by adding neighbours glued along a boundary edge as long as the part
//!    stays convex and planar. Every part is a light; at worst every triangle is its own light.
//!
//! A zero-area emissive triangle is an error ([`ZeroAreaLight`]): a light must have an area.
//! Triangles that meet only at a T-junction do not share an edge and stay separate lights (correct, just
//! more lights than necessary). Welding uses a hash grid with the largest tolerance as cell size: fast
//! for the handful of light triangles of real scenes; a huge emissive triangle next to very many tiny
//! ones would make it quadratic.

use std::collections::HashMap;

use glam::Vec3;

use crate::geometry::newell;
use crate::scene::{SceneBuilder, TriId};

/// An emissive triangle as a loader found it: already added to the [`SceneBuilder`] as `id`, with its
/// vertices counter-clockwise around the side it emits to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissiveTriangle {
    /// The triangle in the builder.
    pub id: TriId,
    /// Its vertices, counter-clockwise seen from the emitting side.
    pub vertices: [Vec3; 3],
    /// Emitted radiance (linear RGB, positive).
    pub radiance: Vec3,
}

/// One light found by [`group_lights`].
#[derive(Clone, Debug, PartialEq)]
pub struct LightGroup {
    /// The triangles that make up the light.
    pub triangles: Vec<TriId>,
    /// The convex polygon, counter-clockwise around the emitting side.
    pub polygon: Vec<Vec3>,
    /// Emitted radiance.
    pub radiance: Vec3,
}

/// The emissive triangle at `index` (into the slice given to [`group_lights`]) has zero area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ZeroAreaLight {
    /// Index into the input slice.
    pub index: usize,
}

/// Groups emissive triangles into convex polygonal lights (see the module doc). The lights come out in
/// the order of their first triangle.
pub fn group_lights(tris: &[EmissiveTriangle]) -> Result<Vec<LightGroup>, ZeroAreaLight> {
    if let Some(index) = tris.iter().position(|t| is_zero_area(&t.vertices)) {
        return Err(ZeroAreaLight { index });
    }
    let mesh = Mesh::new(tris);
    let mut lights = Vec::new();
    for comp in mesh.components() {
        match mesh.whole_polygon(&comp) {
            Some(polygon) => lights.push(mesh.light(&comp, polygon)),
            None => mesh.convex_parts(&comp, &mut lights),
        }
    }
    lights.sort_by_key(|l| l.triangles[0]);
    Ok(lights)
}

/// [`group_lights`], then declares every group a light of `builder`. Returns the number of lights.
pub fn add_lights(builder: &mut SceneBuilder, tris: &[EmissiveTriangle]) -> Result<usize, ZeroAreaLight> {
    let lights = group_lights(tris)?;
    let n = lights.len();
    for l in lights {
        builder.light_from_triangles(l.triangles, l.polygon, l.radiance);
    }
    Ok(n)
}

/// True if the triangle is too thin to be a light (the same bound as the light validation, with
/// margin): area at most `1e-9` of its bounding box's largest extent squared.
fn is_zero_area(v: &[Vec3; 3]) -> bool {
    let area = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
    let ext = v[0].max(v[1]).max(v[2]) - v[0].min(v[1]).min(v[2]);
    let e = ext.max_element();
    let has_area = area.is_finite() && area > 1e-9 * e * e;
    !has_area
}

/// Distance under which two vertices of a triangle are the same point: `1e-4` of its longest edge plus
/// `1e-6` of its largest coordinate (the noise of coordinates printed with 6-7 digits).
pub fn weld_tolerance(v: &[Vec3; 3]) -> f32 {
    let longest = (v[1] - v[0]).length().max((v[2] - v[1]).length()).max((v[0] - v[2]).length());
    let coord = v[0].abs().max(v[1].abs()).max(v[2].abs()).max_element();
    1e-4 * longest + 1e-6 * coord
}

/// `(b - a) x (c - b) . n`: positive for a left (convex) turn around `n`.
fn turn(a: Vec3, b: Vec3, c: Vec3, n: Vec3) -> f32 {
    (b - a).cross(c - b).dot(n)
}

/// The emissive triangles with welded vertex ids and edge adjacency.
struct Mesh<'a> {
    tris: &'a [EmissiveTriangle],
    /// Welded vertex id of each corner (`3 * tri + corner`).
    ids: Vec<u32>,
    /// Position of each welded id (its first corner's position).
    pos: Vec<Vec3>,
    /// Unit normal and weld tolerance of each triangle.
    normal: Vec<Vec3>,
    tol: Vec<f32>,
    /// Neighbours of each triangle (shared opposite edge, same radiance, same plane).
    adj: Vec<Vec<usize>>,
}

impl<'a> Mesh<'a> {
    fn new(tris: &'a [EmissiveTriangle]) -> Mesh<'a> {
        let normal: Vec<Vec3> = tris
            .iter()
            .map(|t| (t.vertices[1] - t.vertices[0]).cross(t.vertices[2] - t.vertices[0]).normalize())
            .collect();
        let tol: Vec<f32> = tris.iter().map(|t| weld_tolerance(&t.vertices)).collect();
        let (ids, pos) = weld(tris, &tol);
        let mut m = Mesh { tris, ids, pos, normal, tol, adj: vec![Vec::new(); tris.len()] };
        m.connect();
        m
    }

    fn corner(&self, t: usize, k: usize) -> u32 {
        self.ids[3 * t + k]
    }

    /// Fills `adj`: triangles sharing an edge in opposite directions, same radiance, same plane.
    fn connect(&mut self) {
        let mut edges: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for t in 0..self.tris.len() {
            for k in 0..3 {
                edges.entry((self.corner(t, k), self.corner(t, (k + 1) % 3))).or_default().push(t);
            }
        }
        for t in 0..self.tris.len() {
            for k in 0..3 {
                let (a, b) = (self.corner(t, k), self.corner(t, (k + 1) % 3));
                let Some(others) = edges.get(&(b, a)) else { continue };
                for &u in others {
                    let same_light = self.tris[u].radiance.to_array().map(f32::to_bits)
                        == self.tris[t].radiance.to_array().map(f32::to_bits);
                    let (nt, nu) = (self.normal[t], self.normal[u]);
                    let coplanar = nt.dot(nu) > 0.0 && nt.cross(nu).length() <= 1e-4;
                    if u != t && same_light && coplanar && !self.adj[t].contains(&u) {
                        self.adj[t].push(u);
                    }
                }
            }
        }
    }

    /// Connected components of `adj`, each in input order.
    fn components(&self) -> Vec<Vec<usize>> {
        let mut seen = vec![false; self.tris.len()];
        let mut comps = Vec::new();
        for s in 0..self.tris.len() {
            if seen[s] {
                continue;
            }
            seen[s] = true;
            let mut comp = vec![s];
            let mut i = 0;
            while i < comp.len() {
                for &u in &self.adj[comp[i]] {
                    if !seen[u] {
                        seen[u] = true;
                        comp.push(u);
                    }
                }
                i += 1;
            }
            comp.sort_unstable();
            comps.push(comp);
        }
        comps
    }

    /// The polygon of a whole component, if its boundary is one simple convex planar loop whose area is
    /// the triangles' total area.
    fn whole_polygon(&self, comp: &[usize]) -> Option<Vec<Vec3>> {
        if comp.len() == 1 {
            return Some(self.tris[comp[0]].vertices.to_vec());
        }
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for &t in comp {
            for k in 0..3 {
                *directed.entry((self.corner(t, k), self.corner(t, (k + 1) % 3))).or_default() += 1;
            }
        }
        let mut next: HashMap<u32, u32> = HashMap::new();
        for (&(a, b), &count) in &directed {
            if count > 1 {
                return None; // overlapping triangles
            }
            if !directed.contains_key(&(b, a)) && next.insert(a, b).is_some() {
                return None; // two boundary edges leave `a`: a pinch
            }
        }
        // Walk the loop from its smallest vertex id, so the result does not depend on hash order.
        let start = *next.keys().min()?;
        let mut ids = vec![start];
        let mut v = next[&start];
        while v != start {
            if ids.len() > next.len() {
                return None;
            }
            ids.push(v);
            v = *next.get(&v)?;
        }
        if ids.len() != next.len() {
            return None; // more than one loop: a hole or separate pieces
        }
        let area: f32 = comp.iter().map(|&t| self.area(t)).sum();
        self.convex_polygon(&ids, self.comp_tol(comp), Some(area))
    }

    fn area(&self, t: usize) -> f32 {
        let v = &self.tris[t].vertices;
        0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length()
    }

    fn comp_tol(&self, comp: &[usize]) -> f32 {
        comp.iter().map(|&t| self.tol[t]).fold(f32::INFINITY, f32::min)
    }

    /// The loop `ids` as a convex polygon with collinear vertices removed, or `None` if it is not convex
    /// or not planar within `tol`, or (if given) its area differs from `area`.
    fn convex_polygon(&self, ids: &[u32], tol: f32, area: Option<f32>) -> Option<Vec<Vec3>> {
        let mut p: Vec<Vec3> = ids.iter().map(|&i| self.pos[i as usize]).collect();
        let n = newell(&p);
        let loop_area = (0.5 * n.length()) as f32;
        let n = n.normalize_or_zero().as_vec3();
        if n == Vec3::ZERO {
            return None;
        }
        // Drop vertices within `tol` of the line through their neighbours; reject real reflex ones.
        loop {
            let k = p.len();
            if k < 3 {
                return None;
            }
            let dist = |i: usize| {
                let (a, b, c) = (p[(i + k - 1) % k], p[i], p[(i + 1) % k]);
                turn(a, b, c, n) / (c - a).length().max(f32::MIN_POSITIVE)
            };
            if (0..k).any(|i| dist(i) < -tol) {
                return None;
            }
            match (0..k).find(|&i| dist(i) <= tol) {
                Some(i) => {
                    p.remove(i);
                }
                None => break,
            }
        }
        let ext = p.iter().fold(Vec3::ZERO, |m, v| m.max((*v - p[0]).abs())).max_element();
        if p.iter().any(|v| (*v - p[0]).dot(n).abs() > (1e-5 * ext).max(tol)) {
            return None;
        }
        if area.is_some_and(|a| (a - loop_area).abs() > 1e-3 * a) {
            return None;
        }
        Some(p)
    }

    fn light(&self, part: &[usize], polygon: Vec<Vec3>) -> LightGroup {
        LightGroup {
            triangles: part.iter().map(|&t| self.tris[t].id).collect(),
            polygon,
            radiance: self.tris[part[0]].radiance,
        }
    }

    /// Splits a component greedily into convex parts (module doc, step 4).
    fn convex_parts(&self, comp: &[usize], out: &mut Vec<LightGroup>) {
        let mut taken: HashMap<usize, bool> = comp.iter().map(|&t| (t, false)).collect();
        for &seed in comp {
            if taken[&seed] {
                continue;
            }
            taken.insert(seed, true);
            let mut part = vec![seed];
            let mut boundary = vec![self.corner(seed, 0), self.corner(seed, 1), self.corner(seed, 2)];
            let (n, p0, tol) = (self.normal[seed], self.tris[seed].vertices[0], self.tol[seed]);
            let mut grew = true;
            while grew {
                grew = false;
                for &t in comp {
                    if !taken[&t] && self.try_glue(t, &mut boundary, n, p0, tol) {
                        taken.insert(t, true);
                        part.push(t);
                        grew = true;
                    }
                }
            }
            match self.convex_polygon(&boundary, tol, None) {
                Some(polygon) => out.push(self.light(&part, polygon)),
                // Cannot happen for a part grown convex, but never emit a bad polygon: fall back.
                None => out.extend(part.iter().map(|&t| self.light(&[t], self.tris[t].vertices.to_vec()))),
            }
        }
    }

    /// Adds triangle `t` to the convex part with loop `boundary` if it is glued along one boundary edge,
    /// its third vertex is new, and the part stays convex and in the plane `(p0, n)`.
    fn try_glue(&self, t: usize, boundary: &mut Vec<u32>, n: Vec3, p0: Vec3, tol: f32) -> bool {
        let k = boundary.len();
        for e in 0..3 {
            // Triangle edge q -> r glued to boundary edge r -> q; the apex c is the triangle's third vertex.
            let (q, r, c) = (self.corner(t, e), self.corner(t, (e + 1) % 3), self.corner(t, (e + 2) % 3));
            let Some(i) = (0..k).find(|&i| boundary[i] == r && boundary[(i + 1) % k] == q) else { continue };
            if boundary.contains(&c) {
                return false;
            }
            let pos = |id: u32| self.pos[id as usize];
            let (before, a, b, after) = (boundary[(i + k - 1) % k], r, q, boundary[(i + 2) % k]);
            let pc = pos(c);
            let bent = |x: Vec3, y: Vec3, z: Vec3| turn(x, y, z, n) / (z - x).length().max(f32::MIN_POSITIVE);
            let convex = bent(pos(before), pos(a), pc) >= -tol && bent(pc, pos(b), pos(after)) >= -tol;
            if convex && (pc - p0).dot(n).abs() <= tol {
                boundary.insert(i + 1, c);
                return true;
            }
            return false;
        }
        false
    }
}

/// Welds the corners of all triangles: corners closer than the smaller of their triangles' tolerances
/// get one id. Returns the id of every corner and the position of every id.
fn weld(tris: &[EmissiveTriangle], tol: &[f32]) -> (Vec<u32>, Vec<Vec3>) {
    let n = tris.len() * 3;
    let corner = |i: usize| tris[i / 3].vertices[i % 3];
    let cell = tol.iter().copied().fold(0.0f32, f32::max).max(f32::MIN_POSITIVE);
    let key = |p: Vec3| (p / cell).floor().as_i64vec3().to_array();
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for i in 0..n {
        let p = corner(i);
        let k = key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else { continue };
                    for &j in list {
                        if corner(j).distance(p) <= tol[i / 3].min(tol[j / 3]) {
                            let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
                            // Keep the smaller corner as root: ids follow input order.
                            parent[ri.max(rj)] = ri.min(rj);
                        }
                    }
                }
            }
        }
        grid.entry(k).or_default().push(i);
    }
    let mut ids = vec![0u32; n];
    let mut pos = Vec::new();
    let mut id_of_root: HashMap<usize, u32> = HashMap::new();
    for (i, id) in ids.iter_mut().enumerate() {
        let r = find(&mut parent, i);
        *id = *id_of_root.entry(r).or_insert_with(|| {
            pos.push(corner(r));
            pos.len() as u32 - 1
        });
    }
    (ids, pos)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(id: u32, a: [f32; 3], b: [f32; 3], c: [f32; 3]) -> EmissiveTriangle {
        EmissiveTriangle { id: TriId(id), vertices: [a.into(), b.into(), c.into()], radiance: Vec3::ONE }
    }

    #[test]
    fn turn_sign_is_left_positive() {
        assert!(turn(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Z) > 0.0);
    }

    #[test]
    fn welds_nearby_duplicates_but_not_distinct_points() {
        let a = tri(0, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]);
        let b = tri(1, [0.0, 0.0, 1e-7], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]);
        let tol = [weld_tolerance(&a.vertices), weld_tolerance(&b.vertices)];
        let (ids, pos) = weld(&[a, b], &tol);
        assert_eq!(pos.len(), 4);
        assert_eq!(ids[0], ids[3]);
        assert_eq!(ids[2], ids[4]);
    }

    /// A small square of two triangles far from the origin is one light of four corners (Newell's
    /// sum from the origin cancelled to noise there: it fell apart into its triangles).
    #[test]
    fn small_square_far_from_the_origin_is_one_light() {
        let (x, y, z, s) = (432.5f32, -740.8f32, -874.6f32, 0.2f32);
        let a = tri(0, [x, y, z], [x, y + s, z], [x, y + s, z + s]);
        let b = tri(1, [x, y, z], [x, y + s, z + s], [x, y, z + s]);
        let lights = group_lights(&[a, b]).unwrap();
        assert_eq!(lights.len(), 1, "{lights:?}");
        assert_eq!(lights[0].polygon.len(), 4, "{lights:?}");
    }

    #[test]
    fn zero_area_detection() {
        assert!(is_zero_area(&[Vec3::ZERO, Vec3::X, Vec3::X * 2.0]));
        assert!(!is_zero_area(&[Vec3::ZERO, Vec3::X, Vec3::Y]));
    }
}
