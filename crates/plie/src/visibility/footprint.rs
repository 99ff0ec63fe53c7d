//! The footprint of a light on the faces of the leaf around a shaded point (issue 21): the part of
//! each face of the leaf `c` that the segments from the point `x` to the light polygon can cross
//! when they leave `c` (SPEC §5: a shadow ray leaves `c` through one face, and that face's record
//! answers it). The per-light query classifies a whole light at once from these rectangles: if the
//! face-grid cells (or records) under every footprint are lit, or all umbra, every sample's answer is
//! known without looking at the samples one by one.
//!
//! Conservative by construction: each rectangle is grown by a margin far above the rounding of the
//! per-ray exit point (`x + d t_exit`, in `f32`), and a face whose plane the light straddles gets the
//! whole face.

use glam::Vec3;

use crate::geometry::Aabb;
use crate::octree::Dir;

/// The footprint on one face: the face, and the rectangle `[u0, u1] x [v0, v1]` of the face's own
/// axes (as [`crate::lie::frame::face_axes`] orders them), in world units, clamped to the face.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceFootprint {
    /// The face of the leaf.
    pub face: Dir,
    /// `[u0, u1, v0, v1]`.
    pub rect: [f64; 4],
}

/// The footprints of the segments from `x` (inside `bounds`) to the convex polygon `light` on the
/// faces of `bounds`, each handed to `visit` as it is found; `visit` returns false to stop. Returns
/// `None` if it stopped, else whether every such segment certainly leaves the box before its
/// parameter `1 - 2 eps` (`eps` the segments' end tolerance), that is, whether no sample's ray can
/// end inside the leaf.
pub fn footprints(
    bounds: &Aabb,
    x: Vec3,
    light: &[Vec3],
    eps: f32,
    mut visit: impl FnMut(FaceFootprint) -> bool,
) -> Option<bool> {
    let xd = [x.x as f64, x.y as f64, x.z as f64];
    // The margin: relative to the coordinates involved, far above f32 rounding (~6e-8 relative).
    let scale = light.iter().fold(x.abs().max_element(), |m, v| m.max(v.abs().max_element())) as f64;
    let margin = 1e-5 * scale.max(f64::MIN_POSITIVE);
    let (lo, hi) = (bounds.min.as_dvec3().to_array(), bounds.max.as_dvec3().to_array());
    // Plain comparisons: every value here is finite (`f64::min` would also handle NaN).
    let min = |a: f64, b: f64| if b < a { b } else { a };
    let max = |a: f64, b: f64| if b > a { b } else { a };
    // The light's vertices in f64, once (on the stack for up to eight), and their least and
    // greatest coordinate per axis.
    let mut stack = [[0.0f64; 3]; 8];
    let heap: Vec<[f64; 3]>;
    let pv: &[[f64; 3]] = if light.len() <= stack.len() {
        for (d, p) in stack.iter_mut().zip(light) {
            *d = p.as_dvec3().to_array();
        }
        &stack[..light.len()]
    } else {
        heap = light.iter().map(|p| p.as_dvec3().to_array()).collect();
        &heap
    };
    let (mut pmin, mut pmax) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in pv {
        for k in 0..3 {
            pmin[k] = min(pmin[k], p[k]);
            pmax[k] = max(pmax[k], p[k]);
        }
    }
    let mut all_exit = false;
    for k in 0..3 {
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        for positive in [false, true] {
            let w = if positive { hi[k] } else { lo[k] };
            // Signed distance beyond the face plane, away from x.
            let beyond = |c: f64| if positive { c - w } else { w - c };
            // The least and greatest over the light's vertices (subtracting one value keeps the
            // order of the rounded results, so these are the extremes of `beyond` per vertex).
            let (least, most) =
                if positive { (beyond(pmin[k]), beyond(pmax[k])) } else { (beyond(pmax[k]), beyond(pmin[k])) };
            if most <= margin {
                // No light point lies clearly beyond this plane: a segment may still reach it
                // within rounding; it is counted as crossing the whole face only if some vertex
                // is not clearly inside.
                if most < -margin {
                    continue;
                }
                if !visit(FaceFootprint { face: Dir::from_axis(k, positive), rect: [lo[u], hi[u], lo[v], hi[v]] }) {
                    return None;
                }
                continue;
            }
            let rect = if least > margin {
                // Every segment crosses the plane: the cross-section is the projection of the polygon.
                let h = beyond(xd[k]).abs();
                let mut r = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
                // Every segment leaves the box at the latest where it crosses this plane, at
                // parameter s <= max over vertices (the parameter is monotone along the polygon's
                // points, being h / (h + beyond) with beyond affine).
                let mut s_max = 0.0f64;
                for p in pv {
                    // The point of the segment x -> p on the plane (its two coordinates in it).
                    let s = h / (h + beyond(p[k]));
                    let (qu, qv) = (xd[u] + (p[u] - xd[u]) * s, xd[v] + (p[v] - xd[v]) * s);
                    r = [min(r[0], qu), max(r[1], qu), min(r[2], qv), max(r[3], qv)];
                    s_max = max(s_max, s);
                }
                if s_max < 1.0 - 4.0 * eps as f64 {
                    all_exit = true;
                }
                [
                    (r[0] - margin).max(lo[u]),
                    (r[1] + margin).min(hi[u]),
                    (r[2] - margin).max(lo[v]),
                    (r[3] + margin).min(hi[v]),
                ]
            } else {
                [lo[u], hi[u], lo[v], hi[v]]
            };
            if rect[0] <= rect[1]
                && rect[2] <= rect[3]
                && !visit(FaceFootprint { face: Dir::from_axis(k, positive), rect })
            {
                return None;
            }
        }
    }
    Some(all_exit)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random segments from a point in a box to a light polygon cross a face only inside that
    /// face's footprint, and leave the box when the footprints say all do.
    #[test]
    fn footprints_hold_every_exit_point() {
        let bounds = Aabb { min: Vec3::new(0.0, 0.0, 0.0), max: Vec3::new(1.0, 1.0, 1.0) };
        let mut out = Vec::new();
        let mut state = 7u64;
        let mut rnd = || {
            state = crate::render::sampler::mix64(state);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for case in 0..2000 {
            let x = Vec3::new(rnd(), rnd(), rnd());
            let c = Vec3::new(rnd() * 6.0 - 2.5, rnd() * 3.0 + 0.2 + (case % 3) as f32, rnd() * 6.0 - 2.5);
            let (e1, e2) = (Vec3::new(rnd(), 0.0, rnd() * 0.3), Vec3::new(rnd() * 0.3, rnd() * 0.2, rnd()));
            let light = [c, c + e1, c + e1 + e2, c + e2];
            out.clear();
            let all_exit = footprints(&bounds, x, &light, 1e-4, |f| {
                out.push(f);
                true
            })
            .expect("not stopped");
            for _ in 0..64 {
                let (a, b) = (rnd(), rnd());
                let y = c + e1 * a + e2 * b;
                let d = y - x;
                // The exit face as the query finds it.
                let mut best = (1.0 - 1e-4f32, None);
                for k in 0..3 {
                    let (t, positive) = if d[k] > 0.0 {
                        ((bounds.max[k] - x[k]) / d[k], true)
                    } else if d[k] < 0.0 {
                        ((bounds.min[k] - x[k]) / d[k], false)
                    } else {
                        continue;
                    };
                    if t < best.0 {
                        best = (t, Some(Dir::from_axis(k, positive)));
                    }
                }
                let Some(face) = best.1 else {
                    assert!(!all_exit, "case {case}: a ray ends inside the box");
                    continue;
                };
                let f = x + d * best.0;
                let k = face.axis();
                let (u, v) = ((k + 1) % 3, (k + 2) % 3);
                let fp = out.iter().find(|p| p.face == face).unwrap_or_else(|| panic!("case {case}: {face:?} missing"));
                let (fu, fv) = (f[u] as f64, f[v] as f64);
                assert!(
                    fp.rect[0] <= fu.max(0.0) && fu.min(1.0) <= fp.rect[1],
                    "case {case}: {fu} outside {:?}",
                    fp.rect
                );
                assert!(
                    fp.rect[2] <= fv.max(0.0) && fv.min(1.0) <= fp.rect[3],
                    "case {case}: {fv} outside {:?}",
                    fp.rect
                );
            }
        }
    }
}
