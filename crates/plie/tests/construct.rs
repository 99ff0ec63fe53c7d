//! P-LIE construction (SPEC §4.1-§4.4) checked independently of the code that builds it:
//! - every triangle met by a segment from a face point to a light point is among that record's
//!   blockers (sampled segments, brute-force triangle tests);
//! - a face with no record really receives no light through it (sampled face/light point pairs);
//! - the thesis' dot-product rule drops a record that the exact condition keeps, and that record
//!   matters for the image.

use glam::{Vec2, Vec3};
use plie::geometry::RayTest;
use plie::internals::construct::data_objects::{face_sees_light, thesis_face_sees_light};
use plie::internals::lie::{PlieParams, Regions};
use plie::octree::{Dir, LeafId, Octree};
use plie::visibility::Mode;
use plie::{LightId, Scene, SceneBuilder};

/// The modes answered from the P-LIE.
const PLIE_MODES: [Mode; 4] = [Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid];

/// splitmix64 in [0, 1).
struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A closed room with a floating plate, a sphere, and a tilted light.
fn room() -> Scene {
    let mut b = SceneBuilder::new("room");
    let w = b.diffuse("w", Vec3::splat(0.7));
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    b.quad(p(0., 0., 0.), p(0., 0., 10.), p(10., 0., 10.), p(10., 0., 0.), w); // floor (up)
    b.quad(p(0., 10., 0.), p(10., 10., 0.), p(10., 10., 10.), p(0., 10., 10.), w); // ceiling
    b.quad(p(0., 0., 10.), p(0., 10., 10.), p(10., 10., 10.), p(10., 0., 10.), w); // back
    b.quad(p(0., 0., 0.), p(0., 10., 0.), p(0., 10., 10.), p(0., 0., 10.), w); // left
    b.quad(p(3., 6., 3.), p(3., 6., 7.), p(7., 6., 7.), p(7., 6., 3.), w); // plate
    let c = p(6.0, 2.5, 5.0);
    let (rings, segs) = (8, 12);
    let v = |i: usize, j: usize| {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        let ph = std::f32::consts::TAU * (j % segs) as f32 / segs as f32;
        c + Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * 1.5
    };
    for i in 0..rings {
        for j in 0..segs {
            if i > 0 {
                b.triangle(v(i, j), v(i + 1, j + 1), v(i, j + 1), w);
            }
            if i + 1 < rings {
                b.triangle(v(i, j), v(i + 1, j), v(i + 1, j + 1), w);
            }
        }
    }
    // Tilted light near the ceiling, emitting down and sideways.
    let l = [p(4.0, 9.0, 4.0), p(6.0, 9.5, 4.0), p(6.0, 9.5, 6.0), p(4.0, 9.0, 6.0)];
    b.light("l", &[l[0], l[1], l[2], l[3]], Vec3::splat(5.0));
    b.build().unwrap()
}

fn hits_any_t(scene: &Scene, a: Vec3, b: Vec3, t: usize) -> bool {
    RayTest::new(a, b - a, 0.0, 1.0).hit(&scene.triangles[t]).is_some()
}

/// The P-LIE of `scene` built with `params` by [`plie::Environment::build`], which builds the same
/// `octree` (checked).
fn build_on(scene: &Scene, octree: &Octree, params: PlieParams) -> (plie::internals::lie::Plie, plie::BuildStats) {
    let (env, stats) = plie::Environment::build(scene, &params).unwrap();
    assert!(env.octree() == octree, "the environment's octree is the one of its parameters");
    (env.into_parts().1, stats)
}

#[test]
fn blockers_contain_every_triangle_between_face_and_light() {
    let scene = room();
    let params = PlieParams { max_triangles: 8, ..PlieParams::thesis() };
    let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
    let (plie, stats) = build_on(&scene, &octree, params);
    assert!(stats.blockers.records > 0 && stats.blockers.blockers_total > 0);
    let mut rng = Rng(3);
    let mut checked = 0;
    for r in &plie.records {
        let face = r.face.face_corners(&octree.leaf_bounds(r.leaf));
        let light = &scene.lights[r.light.idx()];
        let blockers = plie.blockers_of(r);
        for _ in 0..64 {
            let f = face[0] + (face[1] - face[0]) * rng.f() + (face[3] - face[0]) * rng.f();
            let y = light.sample(Vec2::new(rng.f(), rng.f()));
            for t in 0..scene.triangles.len() {
                if scene.tri_light[t] == Some(r.light) || !hits_any_t(&scene, f, y, t) {
                    continue;
                }
                checked += 1;
                assert!(
                    blockers.contains(&plie::TriId(t as u32)),
                    "triangle {t} lies between face {:?} of leaf {:?} and light {:?} but is not a blocker",
                    r.face,
                    r.leaf,
                    r.light
                );
            }
        }
    }
    assert!(checked > 1000, "the check must meet blockers ({checked})");
}

#[test]
fn faces_without_a_record_receive_no_light() {
    // Without regions, so that no record is removed for being dark (tests/regions.rs checks those).
    let scene = room();
    let params = PlieParams { max_triangles: 8, regions: Regions::Skip, ..PlieParams::thesis() };
    let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
    let (plie, _) = build_on(&scene, &octree, params);
    let light = &scene.lights[0];
    let mut rng = Rng(11);
    let mut missing = 0;
    for l in 0..octree.leaf_count() as u32 {
        for face in Dir::ALL {
            if plie.record(LeafId(l), face, LightId(0)).is_some() {
                continue;
            }
            missing += 1;
            let q = face.face_corners(&octree.leaf_bounds(LeafId(l)));
            for _ in 0..32 {
                let f = q[0] + (q[1] - q[0]) * rng.f() + (q[3] - q[0]) * rng.f();
                let y = light.sample(Vec2::new(rng.f(), rng.f()));
                let enters = (y - f).dot(face.normal()) > 0.0 && (f - y).dot(light.normal) > 0.0;
                assert!(!enters, "light enters leaf {l} through {face:?} but it has no record");
            }
        }
    }
    assert!(missing > 0);
}

#[test]
fn thesis_dot_product_rule_drops_a_needed_record() {
    // A light tilted away from an Up face (n_face . n_light > 0) that still shines down onto it.
    let mut b = SceneBuilder::new("tilted");
    let w = b.diffuse("w", Vec3::splat(0.7));
    b.quad(
        Vec3::new(-5.0, 0.0, -5.0),
        Vec3::new(-5.0, 0.0, 5.0),
        Vec3::new(5.0, 0.0, 5.0),
        Vec3::new(5.0, 0.0, -5.0),
        w,
    );
    // Emits toward -x and slightly up: normal (-1, 0.2, 0) normalised.
    let c = Vec3::new(4.0, 3.0, 0.0);
    let up = Vec3::new(0.2, 1.0, 0.0).normalize();
    let poly = [c - up + Vec3::Z, c + up + Vec3::Z, c + up - Vec3::Z, c - up - Vec3::Z];
    b.light("l", &poly, Vec3::ONE);
    let scene = b.build().unwrap();
    let light = &scene.lights[0];
    assert!(light.normal.x < 0.0 && light.normal.y > 0.0, "{}", light.normal);
    // The Up face of a cell below and to the left of the light.
    let face = Dir::Up.face_corners(&plie::geometry::Aabb::new(Vec3::new(-2.0, 0.0, -1.0), Vec3::new(0.0, 1.0, 1.0)));
    assert!(!thesis_face_sees_light(&face, Dir::Up.normal(), light), "the thesis' rule drops it");
    assert!(face_sees_light(&face, Dir::Up.normal(), light, 0.0), "the exact rule keeps it");
    // And light really arrives through it: a face point and a light point with both conditions.
    let (f, y) = (face[0], light.vertices[1]);
    assert!((y - f).dot(Dir::Up.normal()) > 0.0 && (f - y).dot(light.normal) > 0.0);
}

#[test]
fn lie_mode_matches_brute_force_in_the_room() {
    use plie::visibility::{Brute, QueryCtx, ShadowRay, Visibility};
    let scene = room();
    for max_triangles in [8, 200] {
        let params = PlieParams { max_triangles, ..PlieParams::default() };
        let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
        let (plie, stats) = build_on(&scene, &octree, params);
        assert!(stats.grids.grids > 0);
        let brute = Brute::new(&scene);
        let env = plie::Environment::from_parts(&scene, octree.clone(), plie.clone());
        let modes = PLIE_MODES.map(|m| (m, env.visibility(m, &scene).unwrap()));
        let mut ctx = QueryCtx::new(scene.triangles.len());
        let mut rng = Rng(5);
        let light = &scene.lights[0];
        let (mut n, mut blocked) = (0, 0);
        while n < 100_000 {
            let t = (rng.f() * scene.triangles.len() as f32) as usize % scene.triangles.len();
            // A point on a leaf face lies on no triangle: no origin triangle (x must lie on its own).
            let (x, t) = if n % 3 == 0 {
                let c = octree.leaf_bounds(LeafId((rng.f() * octree.leaf_count() as f32) as u32));
                (Vec3::new(c.min.x, c.min.y + rng.f() * (c.max.y - c.min.y), c.max.z), u32::MAX as usize)
            } else {
                (scene.triangles[t].point(rng.f() * 0.5, rng.f() * 0.5), t)
            };
            let y = light.sample(Vec2::new(rng.f(), rng.f()));
            if (x - y).dot(light.normal) <= 0.0 {
                continue;
            }
            let ray = ShadowRay::new(x, y, LightId(0), plie::TriId(t as u32), octree.locate(x));
            let expect = brute.occluded(&ray, &mut ctx);
            for (m, v) in &modes {
                assert_eq!(v.occluded(&ray, &mut ctx), expect, "{m}, ray {n}: {ray:?}");
            }
            blocked += expect as usize;
            n += 1;
        }
        assert!(blocked > 1000 && blocked < 99_000, "{blocked}");
    }
}

#[test]
fn lie_mode_matches_brute_force_with_lights_tilted_to_grazing() {
    use plie::visibility::{Brute, QueryCtx, ShadowRay, Visibility};
    // The room plus five lights whose normals are tilted from straight down to grazing (89.9 degrees).
    let base = room();
    let mut b = SceneBuilder::new("tilted");
    let w = b.diffuse("w", Vec3::splat(0.7));
    for t in &base.triangles {
        if base.tri_light[base.triangles.iter().position(|u| u == t).unwrap()].is_none() {
            b.triangle(t.v[0], t.v[1], t.v[2], w);
        }
    }
    for (i, deg) in [0.0f32, 45.0, 80.0, 89.0, 89.9].iter().enumerate() {
        let a = deg.to_radians();
        // Emitting direction: down, rotated toward +x by `deg`.
        let n = Vec3::new(a.sin(), -a.cos(), 0.0);
        let u = Vec3::Z * 0.6;
        let v = n.cross(u).normalize() * 0.6;
        let c = Vec3::new(1.5 + 1.7 * i as f32, 8.5, 1.5 + 1.5 * i as f32);
        // Counter-clockwise around n.
        b.light(&format!("l{i}"), &[c - u - v, c + u - v, c + u + v, c - u + v], Vec3::ONE);
    }
    let scene = b.build().unwrap();
    for (i, l) in scene.lights.iter().enumerate() {
        assert!(l.normal.y < 0.0 || i == 4, "light {i} normal {}", l.normal);
    }
    let params = PlieParams { max_triangles: 8, ..PlieParams::default() };
    let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
    let (plie, _) = build_on(&scene, &octree, params);
    let brute = Brute::new(&scene);
    let env = plie::Environment::from_parts(&scene, octree.clone(), plie.clone());
    let modes = PLIE_MODES.map(|m| (m, env.visibility(m, &scene).unwrap()));
    let mut ctx = QueryCtx::new(scene.triangles.len());
    let mut rng = Rng(17);
    let (mut n, mut blocked) = (0, 0);
    while n < 100_000 {
        let li = n % scene.lights.len();
        let light = &scene.lights[li];
        let t = ((rng.f() * scene.triangles.len() as f32) as usize).min(scene.triangles.len() - 1);
        let (x, t) = if n % 4 == 0 {
            let c =
                octree.leaf_bounds(LeafId((rng.f() * octree.leaf_count() as f32) as u32 % octree.leaf_count() as u32));
            (Vec3::new(c.max.x, c.min.y + rng.f() * (c.max.y - c.min.y), c.min.z), u32::MAX as usize)
        } else {
            (scene.triangles[t].point(rng.f() * 0.5, rng.f() * 0.5), t)
        };
        let y = light.sample(Vec2::new(rng.f(), rng.f()));
        if (x - y).dot(light.normal) <= 0.0 {
            continue;
        }
        let ray = ShadowRay::new(x, y, LightId(li as u32), plie::TriId(t as u32), octree.locate(x));
        let expect = brute.occluded(&ray, &mut ctx);
        for (m, v) in &modes {
            assert_eq!(v.occluded(&ray, &mut ctx), expect, "{m}, ray {n} toward light {li}: {ray:?}");
        }
        blocked += expect as usize;
        n += 1;
    }
    assert!(blocked > 1000 && blocked < 99_000, "{blocked}");
}

#[test]
fn construction_does_not_depend_on_the_thread_count() {
    for name in ["huis-c", "dragon"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let params = PlieParams::thesis();
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
                build_on(&scene, &octree, params)
            })
        };
        let (one, s1) = build(1);
        let (two, s2) = build(2);
        assert!(one == two, "{name}: P-LIE differs between 1 and 2 threads");
        assert_eq!(s1.blockers.records, s2.blockers.records);
        assert!(s1.blockers.blockers_total > 0);
    }
}

#[test]
fn grid_cells_contain_every_triangle_between_cell_and_light() {
    use plie::internals::construct::grid::cell_box;
    let scene = room();
    let params = PlieParams { max_triangles: 64, ..PlieParams::default() };
    let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
    let (plie, stats) = build_on(&scene, &octree, params);
    assert!(stats.grids.grids > 0, "{stats:?}");
    let mut rng = Rng(23);
    let mut checked = 0;
    for (r, g) in plie.records.iter().zip(&plie.grids) {
        if g.res == 0 {
            continue;
        }
        let light = &scene.lights[r.light.idx()];
        let leaf = octree.leaf_bounds(r.leaf);
        for j in 0..g.res {
            for i in 0..g.res {
                let plie::internals::lie::Cell::Blockers(list) = plie.cell(g, (j * g.res + i) as usize) else {
                    continue; // Umbra cells: tests/regions.rs.
                };
                let q = r.face.face_corners(&cell_box(r.face, &leaf, g.res, i, j));
                for _ in 0..16 {
                    let f = q[0] + (q[1] - q[0]) * rng.f() + (q[3] - q[0]) * rng.f();
                    let y = light.sample(Vec2::new(rng.f(), rng.f()));
                    for t in 0..scene.triangles.len() {
                        if scene.tri_light[t] == Some(r.light) || !hits_any_t(&scene, f, y, t) {
                            continue;
                        }
                        checked += 1;
                        assert!(list.contains(&plie::TriId(t as u32)), "triangle {t} missing from cell ({i}, {j})");
                    }
                }
            }
        }
    }
    assert!(checked > 100, "{checked}");
}
