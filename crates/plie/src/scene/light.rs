//! Area lights (SPEC §1): planar convex polygons emitting constant radiance `L_e` into the half-space
//! their normal points to. The polygon's vertices are the light's "coordinates" used by the P-LIE
//! construction; sampling is uniform over its area (SPEC §2).

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::TriId;
use crate::error::{Error, Result};
use crate::geometry::newell;

/// A one-sided convex polygonal area light.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Vertices, counter-clockwise seen from the side the light emits to.
    pub vertices: Vec<Vec3>,
    /// Unit normal of the emitting side.
    pub normal: Vec3,
    /// Area.
    pub area: f32,
    /// Emitted radiance `L_e`, linear RGB.
    pub radiance: Vec3,
    /// The scene triangles that make up the light; shadow rays toward this light ignore them.
    pub triangles: Vec<TriId>,
    /// Cumulative area fractions of the fan triangles `(v0, v_i, v_i+1)`, for sampling.
    fan_cdf: Vec<f32>,
    /// True if the polygon is a parallelogram, sampled by the bilinear map (keeps N-rooks strata).
    parallelogram: bool,
}

/// The first points of a list as `[x, y, z], ...` for messages (at most 4, then how many more).
pub(crate) fn list_points(points: &[Vec3]) -> String {
    let mut s: Vec<String> = points.iter().take(4).map(|p| p.to_string()).collect();
    if points.len() > 4 {
        s.push(format!("... ({} in all)", points.len()));
    }
    s.join(", ")
}

impl Light {
    /// A light from a convex polygon (counter-clockwise around the emitting side) and its radiance.
    /// Fails on fewer than 3 vertices, non-finite values, zero area, a non-planar or non-convex polygon,
    /// or a radiance that is negative, non-finite or zero.
    pub fn new(vertices: Vec<Vec3>, radiance: Vec3, triangles: Vec<TriId>) -> Result<Light> {
        let bad = |m: &str| Error::InvalidScene(format!("light with vertices {}: {m}", list_points(&vertices)));
        if vertices.len() < 3 {
            return Err(bad("fewer than 3 vertices"));
        }
        if !vertices.iter().all(|v| v.is_finite()) {
            return Err(bad("non-finite coordinate"));
        }
        if !radiance.is_finite() || radiance.min_element() < 0.0 || radiance.max_element() <= 0.0 {
            return Err(bad(&format!("radiance {radiance} must be finite, non-negative and not zero")));
        }
        // Newell normal: robust for any planar polygon, and for one far from the origin.
        let n = newell(&vertices);
        let area = (0.5 * n.length()) as f32;
        let size = extent(&vertices);
        if area.is_nan() || area <= 1e-10 * size * size {
            return Err(bad("zero area"));
        }
        let normal = n.normalize().as_vec3();
        // How far rounding the corners to f32 may have moved them: a small light far from the
        // origin is planar and convex only up to that.
        let rounding = 4.0 * f32::EPSILON * vertices.iter().fold(0.0f32, |m, v| m.max(v.abs().max_element()));
        for v in &vertices {
            if (*v - vertices[0]).dot(normal).abs() > (1e-4 * size).max(rounding) {
                return Err(bad("vertices are not coplanar"));
            }
        }
        let k = vertices.len();
        for i in 0..k {
            let (a, b, c) = (vertices[i], vertices[(i + 1) % k], vertices[(i + 2) % k]);
            if (b - a).cross(c - b).dot(normal) < -(1e-6 * size * size).max(4.0 * rounding * size) {
                return Err(bad("polygon is not convex"));
            }
        }
        let mut fan_cdf = Vec::with_capacity(k - 2);
        let mut acc = 0.0;
        for i in 1..k - 1 {
            acc += 0.5 * (vertices[i] - vertices[0]).cross(vertices[i + 1] - vertices[0]).length();
            fan_cdf.push(acc);
        }
        for c in &mut fan_cdf {
            *c /= acc;
        }
        // `v0 + v2 - v1 - v3` from differences, in f64 (the sums of coordinates far from the origin
        // would round away what is tested).
        let parallelogram = k == 4 && {
            let d = |i: usize, j: usize| vertices[i].as_dvec3() - vertices[j].as_dvec3();
            (d(2, 1) - d(3, 0)).length() <= 1e-5 * size as f64
        };
        // Its power (area times radiance, summed over the channels) must be a finite f32, so that
        // shading and the path tracer's choice of a light by power stay finite.
        if !(area * radiance.element_sum()).is_finite() {
            return Err(bad(&format!("radiance {radiance} times area {area} is beyond the range of f32")));
        }
        Ok(Light { vertices, normal, area, radiance, triangles, fan_cdf, parallelogram })
    }

    /// How far the light is from a planar convex polygon (what [`Light::new`] allows for the
    /// rounding of its corners): the largest distance of a corner from the light's plane, or of a
    /// corner outside the line of the edge before it; computed in f64.
    pub(crate) fn deviation(&self) -> f32 {
        let k = self.vertices.len();
        let v = |i: usize| self.vertices[i % k].as_dvec3();
        let n = self.normal.as_dvec3();
        let mut dev = 0.0f64;
        for i in 0..k {
            dev = dev.max((v(i) - v(0)).dot(n).abs());
            let (a, b, c) = (v(i), v(i + 1), v(i + 2));
            let len = (b - a).length();
            if len > 0.0 {
                dev = dev.max(-(b - a).cross(c - b).dot(n) / len);
            }
        }
        dev as f32
    }

    /// The size of the light: the largest extent of its corners' bounding box.
    pub(crate) fn size(&self) -> f32 {
        extent(&self.vertices)
    }

    /// For a parallelogram, its corner `v0` and edge vectors `v1 - v0`, `v3 - v0`: [`Light::sample`]
    /// maps `u` to `v0 + (v1 - v0) u.x + (v3 - v0) u.y`. `None` for other polygons.
    pub fn parallelogram_edges(&self) -> Option<(Vec3, Vec3, Vec3)> {
        let v = &self.vertices;
        self.parallelogram.then(|| (v[0], v[1] - v[0], v[3] - v[0]))
    }

    /// [`Light::sample`] of every `u` of `us`, appended to `out` (the same values, computed with the
    /// same operations: a parallelogram's edge vectors are only computed once).
    pub fn sample_into(&self, us: &[Vec2], out: &mut Vec<Vec3>) {
        if let Some((o, e1, e3)) = self.parallelogram_edges() {
            out.extend(us.iter().map(|u| o + e1 * u.x + e3 * u.y));
        } else {
            out.extend(us.iter().map(|&u| self.sample(u)));
        }
    }

    /// Maps `u` in the unit square to a point on the light, uniformly by area: a stratified set of `u`
    /// (N-rooks) stays stratified over the light.
    #[inline]
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let v = &self.vertices;
        if self.parallelogram {
            return v[0] + (v[1] - v[0]) * u.x + (v[3] - v[0]) * u.y;
        }
        // Pick a fan triangle by area with u.x, then reuse the remainder of u.x.
        let i = self.fan_cdf.partition_point(|&c| c < u.x).min(self.fan_cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.fan_cdf[i - 1] };
        let hi = self.fan_cdf[i];
        let ux = if hi > lo { ((u.x - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
        let s = ux.sqrt();
        let (b1, b2) = (s * (1.0 - u.y), s * u.y);
        v[0] + (v[i + 1] - v[0]) * b1 + (v[i + 2] - v[0]) * b2
    }

    /// Points whose convex hull holds every point [`Light::sample`] returns, up to `f32` rounding: the
    /// vertices, and for a parallelogram (sampled by the bilinear map, which the test above accepts up
    /// to a small deviation) also `v1 + v3 - v0`.
    pub fn sample_domain(&self) -> Vec<Vec3> {
        let v = &self.vertices;
        let mut out = v.clone();
        if self.parallelogram {
            out.push(v[1] + v[3] - v[0]);
        }
        out
    }

    /// Centroid of the vertices.
    pub fn center(&self) -> Vec3 {
        self.vertices.iter().copied().sum::<Vec3>() / self.vertices.len() as f32
    }
}

/// Largest extent of a point set, as a length scale for tolerances.
fn extent(p: &[Vec3]) -> f32 {
    crate::geometry::Aabb::from_points(p).size().max_element().max(f32::MIN_POSITIVE)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Vec3> {
        vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)]
    }

    #[test]
    fn square_light_normal_area_and_samples() {
        let l = Light::new(square(), Vec3::ONE, vec![]).unwrap();
        assert!((l.area - 1.0).abs() < 1e-6);
        assert!((l.normal - Vec3::Y).length() < 1e-6);
        let p = l.sample(Vec2::new(0.25, 0.75));
        assert!(p.y.abs() < 1e-7 && (0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.z));
    }

    /// A light small against its distance from the origin keeps its area and normal (the Newell
    /// sum from the origin cancelled to noise: such lights were refused as of zero area or not
    /// planar, or got a wrong normal).
    #[test]
    fn small_light_far_from_the_origin() {
        for (far, size) in [(Vec3::new(432.5, -740.8, -874.6), 0.2), (Vec3::new(-147_218.0, -20_539.4, -36_335.1), 0.1)]
        {
            for (u, v) in [(Vec3::Y, Vec3::Z), (Vec3::Z, Vec3::X), (Vec3::X, Vec3::Y)] {
                let normal = u.cross(v);
                // Counter-clockwise around `normal`.
                let quad = vec![far, far + u * size, far + (u + v) * size, far + v * size];
                // The area of the rectangle the rounded corners make.
                let side = |k: usize| (quad[k].as_dvec3() - quad[0].as_dvec3()).length();
                let area = side(1) * side(3);
                let l = Light::new(quad, Vec3::ONE, vec![]).unwrap_or_else(|e| panic!("{normal}: {e}"));
                assert!((l.area as f64 / area - 1.0).abs() < 1e-4, "{normal}: area {} for {area}", l.area);
                assert!(l.normal.dot(normal) > 0.9999, "{normal}: normal {}", l.normal);
            }
        }
    }

    /// A small light turned any way, far from the origin, is planar and convex up to the rounding
    /// of its corners to f32, and is accepted.
    #[test]
    fn small_turned_light_far_from_the_origin() {
        let far = Vec3::new(36.48, 52.03, 23.85);
        for k in 0..200 {
            let a = k as f32 * 0.37;
            let rot = glam::Mat3::from_euler(glam::EulerRot::XYZ, a, a * 1.7, a * 2.3);
            let size = 0.01;
            let quad: Vec<Vec3> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
                .iter()
                .map(|&(u, v)| far + rot * Vec3::new(u * size, v * size, 0.0))
                .collect();
            let l = Light::new(quad, Vec3::ONE, vec![]).unwrap_or_else(|e| panic!("turn {k}: {e}"));
            assert!(l.normal.dot(rot * Vec3::Z) > 0.999, "turn {k}: normal {}", l.normal);
        }
    }

    /// A light flat and convex only up to its corners' rounding is accepted where that is within
    /// the scene's tolerance, which far from the origin grows with the coordinates
    /// ([`crate::geometry::tolerance_of`]); one that `Light::new` accepts for that rounding but that
    /// lies further from a flat convex polygon than the scene's tolerance is refused with a clear
    /// error.
    #[test]
    fn rounding_of_a_light_within_the_scene_tolerance() {
        let scene = |at: Vec3, corners: &[Vec3]| {
            let mut b = crate::scene::SceneBuilder::new("far");
            let w = b.diffuse("w", Vec3::splat(0.5));
            b.triangle(at, at + Vec3::X, at + Vec3::Z, w);
            let poly: Vec<Vec3> = corners.iter().map(|&c| at + Vec3::Y + c).collect();
            b.light("l", &poly, Vec3::ONE);
            b.build()
        };
        for k in 0..50 {
            let a = k as f32 * 0.37;
            let rot = glam::Mat3::from_euler(glam::EulerRot::XYZ, a, a * 1.7, a * 2.3);
            let quad: Vec<Vec3> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
                .map(|(u, v)| rot * Vec3::new(u * 0.01, v * 0.01, 0.0))
                .into();
            for at in [Vec3::new(30.0, 50.0, 20.0), Vec3::splat(5000.0)] {
                assert!(scene(at, &quad).is_ok(), "turn {k} at {at}");
            }
        }
        // Flat, but with a corner pushed in by 0.04: within what `Light::new` allows for rounding
        // 5000 units out, not within this scene's tolerance (its size is about 1).
        let dented: Vec<Vec3> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.2, 1.0), (0.1, 0.96), (0.0, 1.0)]
            .map(|(x, z)| Vec3::new(x, 0.0, z))
            .into();
        let e = scene(Vec3::splat(5000.0), &dented).expect_err("a dented light");
        assert!(e.to_string().contains("too small for its distance from the origin"), "{e}");
    }

    #[test]
    fn triangle_light_samples_stay_inside() {
        let l = Light::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], Vec3::ONE, vec![]).unwrap();
        for i in 0..10 {
            for j in 0..10 {
                let p = l.sample(Vec2::new(i as f32 / 9.0, j as f32 / 9.0));
                assert!(p.x >= -1e-6 && p.y >= -1e-6 && p.x + p.y <= 1.0 + 1e-6);
            }
        }
    }

    #[test]
    fn rejects_bad_lights() {
        assert!(Light::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], Vec3::ONE, vec![]).is_err());
        assert!(Light::new(square(), Vec3::ZERO, vec![]).is_err());
        assert!(Light::new(square(), Vec3::splat(f32::NAN), vec![]).is_err());
        let mut s = square();
        s.swap(1, 2); // bow-tie
        assert!(Light::new(s, Vec3::ONE, vec![]).is_err());
    }
}
