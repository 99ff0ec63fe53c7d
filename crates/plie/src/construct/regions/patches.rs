//! Fused patches (SPEC §4.5): blockers that share bit-identical edges form a surface no ray slips
//! through, so their union casts more umbra than each alone. Groups neighbouring blockers into
//! coplanar convex patches whose umbra is computed as one blocker's.

use glam::{DVec2, DVec3};

use crate::geometry::clip::{hull2, signed_area2};

use crate::scene::{Scene, TriId};

/// An undirected edge by the bits of its end points.
pub(super) type EdgeKey = ([u32; 3], [u32; 3]);

/// The key of edge `(a, b)`: equal for `(b, a)` and only for bit-identical end points, which is when the
/// watertight test lets no ray slip between the two triangles.
pub(super) fn edge_key(a: glam::Vec3, b: glam::Vec3) -> EdgeKey {
    let (ka, kb) = (a.to_array().map(f32::to_bits), b.to_array().map(f32::to_bits));
    if ka <= kb {
        (ka, kb)
    } else {
        (kb, ka)
    }
}

/// Flat convex patches made of several blockers: triangles joined through bit-identical shared
/// edges (so the watertight test lets no ray through between them), coplanar within `r / 100`, whose
/// union is exactly its convex hull (areas equal, every unshared edge on the hull's boundary). A ray
/// through the interior of such a patch hits one of its triangles, so the patch may cast umbra as one
/// blocker: a plate or a wall split into triangles does, where none of its triangles does alone.
pub(super) fn fused_patches(scene: &Scene, blockers: &[TriId], r: f64) -> Vec<Vec<DVec3>> {
    let tris: Vec<[DVec3; 3]> = blockers.iter().map(|t| scene.triangles[t.idx()].v.map(|p| p.as_dvec3())).collect();
    let normals: Vec<Option<DVec3>> = tris.iter().map(|t| (t[1] - t[0]).cross(t[2] - t[0]).try_normalize()).collect();
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    fn root(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    // Edges sorted by key (then by blocker and edge): each run of equal keys is one shared edge, its
    // first entry the blocker that every later one is tried against.
    let mut edges: Vec<(EdgeKey, u32)> = Vec::with_capacity(3 * blockers.len());
    for &t in blockers {
        let v = scene.triangles[t.idx()].v;
        edges.extend((0..3).map(|e| (edge_key(v[e], v[(e + 1) % 3]), 0)));
    }
    for (k, x) in edges.iter_mut().enumerate() {
        x.1 = k as u32;
    }
    edges.sort_unstable();
    // Per edge `3 i + e`: used by one blocker only.
    let mut once = vec![false; edges.len()];
    for run in edges.chunk_by(|a, b| a.0 == b.0) {
        let j = (run[0].1 / 3) as usize;
        once[run[0].1 as usize] = run.len() == 1;
        for &(_, k) in &run[1..] {
            let (i, e) = ((k / 3) as usize, (k % 3) as usize);
            let (Some(ni), Some(nj)) = (normals[i], normals[j]) else { continue };
            let far = tris[i][(e + 2) % 3];
            let near = *tris[j].iter().find(|p| !tris[i].contains(p)).unwrap_or(&tris[j][0]);
            let (p, q) = (tris[i][e], tris[i][(e + 1) % 3]);
            let side = |x: DVec3| nj.dot((q - p).cross(x - p));
            if ni.dot(nj).abs() > 1.0 - 1e-12
                && nj.dot(far - tris[j][0]).abs() <= 0.01 * r
                && side(far) * side(near) < 0.0
            {
                let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                parent[a] = b;
            }
        }
    }
    let roots: Vec<usize> = (0..tris.len()).map(|i| root(&mut parent, i)).collect();
    let mut order: Vec<usize> = (0..tris.len()).collect();
    order.sort_by_key(|&i| (roots[i], i));
    let mut members: Vec<Vec<usize>> =
        order.chunk_by(|&a, &b| roots[a] == roots[b]).filter(|m| m.len() >= 2).map(<[usize]>::to_vec).collect();
    members.sort_unstable();
    let mut out = Vec::new();
    for m in members {
        let t0 = tris[m[0]];
        let Some(n) = normals[m[0]] else { continue };
        let e1 = (t0[1] - t0[0]).normalize();
        let e2 = n.cross(e1);
        let to2 = |p: DVec3| DVec2::new((p - t0[0]).dot(e1), (p - t0[0]).dot(e2));
        let mut pts: Vec<DVec2> = m.iter().flat_map(|&i| tris[i].map(to2)).collect();
        let mut hull = Vec::new();
        hull2(&mut pts, &mut hull);
        let hull_area = signed_area2(&hull).abs();
        let sum: f64 = m.iter().map(|&i| signed_area2(&tris[i].map(to2)).abs()).sum();
        if hull.len() < 3 || (sum - hull_area).abs() > 1e-9 * hull_area {
            continue;
        }
        // Every edge used once lies on the hull's boundary.
        let eps = 1e-9 * hull_area.sqrt();
        let on_hull = |x: DVec2| {
            let k = hull.len();
            (0..k).any(|h| {
                let (a, b) = (hull[h], hull[(h + 1) % k]);
                let e = b - a;
                e.perp_dot(x - a).abs() <= eps * e.length() && (x - a).dot(e) >= -eps && (x - b).dot(e) <= eps
            })
        };
        let boundary_ok = m.iter().all(|&i| {
            (0..3).all(|e| !once[3 * i + e] || (on_hull(to2(tris[i][e])) && on_hull(to2(tris[i][(e + 1) % 3]))))
        });
        if boundary_ok {
            out.push(hull.iter().map(|p| t0[0] + e1 * p.x + e2 * p.y).collect());
        }
    }
    out
}
