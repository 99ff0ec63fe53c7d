//! Umbra and penumbra (SPEC §4.5), removal of dark records (§4.6) and the face-grid umbra cells: each
//! classification is checked against the blocker test on sampled segments, on built-in scenes and on
//! the real scenes of ../shared/scenes/; golden fixtures check hand-computed regions.

mod support;

use glam::{DVec2, Vec2, Vec3};
use plie::geometry::RayTest;
use plie::internals::construct::regions::face_regions;
use plie::internals::construct::shaft::Shaft;
use plie::internals::lie::frame::{face_axes, in_triangles, FaceFrame, Tri2, UNITS};
use plie::internals::lie::grid::cell_box;
use plie::internals::lie::{Cell, Plie, PlieParams, Propagation, Regions};
use plie::octree::{Dir, LeafId, Octree};
use plie::visibility::query::SEGMENT_EPS;
use plie::{LightId, Scene, SceneBuilder, TriId};
use support::TestRng;

/// True if one of `tris` (all scene triangles when `None`) other than the light's blocks `f -> y`.
fn blocked_by(scene: &Scene, light: LightId, f: Vec3, y: Vec3, tris: Option<&[TriId]>) -> bool {
    let ray = RayTest::new(f, y - f, SEGMENT_EPS, 1.0 - SEGMENT_EPS);
    let test = |t: TriId| scene.tri_light[t.idx()] != Some(light) && ray.hit(&scene.triangles[t.idx()]).is_some();
    match tris {
        Some(list) => list.iter().any(|&t| test(t)),
        None => (0..scene.triangles.len() as u32).map(TriId).any(test),
    }
}

/// A uniform point in an integer triangle (units).
fn point_in(t: &Tri2, rng: &mut TestRng) -> DVec2 {
    let (mut a, mut b) = (rng.f32() as f64, rng.f32() as f64);
    if a + b > 1.0 {
        (a, b) = (1.0 - a, 1.0 - b);
    }
    let p = t.map(|v| DVec2::new(v[0] as f64, v[1] as f64));
    p[0] + (p[1] - p[0]) * a + (p[2] - p[0]) * b
}

fn build(scene: &Scene, params: PlieParams) -> (Octree, Plie) {
    plie::Environment::build(scene, &params).unwrap().0.into_parts()
}

/// Checks every record's regions and grid cells, and every removed record, against sampled segments.
/// Returns (umbra points, lit points, removed records) checked.
fn check_regions(scene: &Scene, max_triangles: usize, samples: usize) -> (usize, usize, usize) {
    // Without propagation: every removed record is then one the regions found dark (tests/propagation.rs
    // checks the records propagation deletes).
    let params = PlieParams { max_triangles, propagation: Propagation::Off, ..PlieParams::default() };
    let (octree, plie) = build(scene, params);
    let (_, bare) = build(scene, PlieParams { regions: Regions::Skip, ..params });
    let mut rng = TestRng(0x5eed ^ scene.triangles.len() as u64);
    let (mut umbra_pts, mut lit_pts, mut removed) = (0, 0, 0);
    for r in &bare.records {
        let light = &scene.lights[r.light.idx()];
        let b = octree.leaf_bounds(r.leaf);
        let frame = FaceFrame::new(r.face, &b);
        let world = |x: DVec2| frame.point(x).as_vec3();
        let light_pt = |rng: &mut TestRng| light.sample(Vec2::new(rng.f32(), rng.f32()));
        let Some(ri) = plie.record_id(r.leaf, r.face, r.light) else {
            // Removed: fully dark from every face point (corners included) to every light point.
            removed += 1;
            for k in 0..samples {
                let x = if k < 4 {
                    DVec2::new((k & 1) as f64, (k >> 1) as f64) * UNITS
                } else {
                    DVec2::new(rng.f32() as f64, rng.f32() as f64) * UNITS
                };
                let (f, y) = (world(x), light_pt(&mut rng));
                assert!(
                    blocked_by(scene, r.light, f, y, None),
                    "{}: removed record {r:?} sees {y} from {f}",
                    scene.name
                );
            }
            continue;
        };
        let blockers = plie.blockers_of(&plie.records[ri]);
        for t in plie.umbra_of(ri).iter().take(samples) {
            let f = world(point_in(t, &mut rng));
            let y = light_pt(&mut rng);
            assert!(blocked_by(scene, r.light, f, y, None), "{}: umbra point {f} of {r:?} sees {y}", scene.name);
            umbra_pts += 1;
        }
        for _ in 0..samples {
            let x = DVec2::new(rng.f32() as f64, rng.f32() as f64) * UNITS;
            if in_triangles(plie.umbra_of(ri), x) || in_triangles(plie.penumbra_of(ri), x) {
                continue;
            }
            let (f, y) = (world(x), light_pt(&mut rng));
            assert!(!blocked_by(scene, r.light, f, y, Some(blockers)), "{}: lit point {f} of {r:?}", scene.name);
            lit_pts += 1;
        }
        let g = plie.grids[ri];
        for j in 0..g.res {
            for i in 0..g.res {
                let q = r.face.face_corners(&cell_box(r.face, &b, g.res, i, j));
                let umbra = plie.cell(&g, (j * g.res + i) as usize) == Cell::Umbra;
                for _ in 0..samples.min(8) {
                    let f = q[0] + (q[1] - q[0]) * rng.f32() + (q[3] - q[0]) * rng.f32();
                    let y = light_pt(&mut rng);
                    match plie.cell(&g, (j * g.res + i) as usize) {
                        Cell::Umbra => assert!(blocked_by(scene, r.light, f, y, None), "umbra cell {f}"),
                        Cell::Blockers([]) => {
                            assert!(!blocked_by(scene, r.light, f, y, Some(blockers)), "lit cell {f}")
                        }
                        // A capped record's cell: the scene answers (none here: the P-LIE is uncapped).
                        Cell::Blockers(_) | Cell::Scene => {}
                    }
                }
                umbra_pts += umbra as usize;
            }
        }
    }
    (umbra_pts, lit_pts, removed)
}

#[test]
fn regions_agree_with_the_blocker_test_on_builtin_scenes() {
    let (mut umbra, mut lit, mut removed) = (0, 0, 0);
    for name in plie::scene::builtin::NAMES {
        let scene = plie::scene::builtin::load(name).unwrap();
        for max_triangles in [200, 24] {
            let (u, l, r) = check_regions(&scene, max_triangles, 12);
            (umbra, lit, removed) = (umbra + u, lit + l, removed + r);
        }
    }
    eprintln!("checked {umbra} umbra points, {lit} lit points, {removed} removed records");
    assert!(umbra > 10_000 && lit > 10_000 && removed > 100, "{umbra} {lit} {removed}");
}

#[test]
#[ignore = "exhaustive tier (real scenes): cargo test --workspace -- --ignored"]
fn regions_agree_with_the_blocker_test_on_shared_scenes() {
    if support::shared_scenes().is_none() {
        return;
    }
    for scene in support::load_shared() {
        if scene.triangles.len() > 50_000 {
            continue; // cornell-dragon-100k: covered by the exactness tests.
        }
        let (u, l, r) = check_regions(&scene, 200, 6);
        eprintln!("{}: {u} umbra points, {l} lit points, {r} removed records", scene.name);
        assert!(u > 0 && l > 0, "{}: nothing classified", scene.name);
    }
}

/// Thesis §7.1 / SPEC §6: the right-bottom-front cell of Cornell Cube 1 has every lit face in umbra,
/// so all its records are removed; without regions they are there.
#[test]
fn cornell_cube_1_right_bottom_front_cell_has_every_lit_face_in_umbra() {
    for name in ["cornell-cube-1", "cornell-cube-5"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let (octree, plie) = build(&scene, PlieParams::default());
        let (_, bare) = build(&scene, PlieParams { regions: Regions::Skip, ..PlieParams::default() });
        let c = octree.root_bounds().center();
        let leaf = octree.locate(c + Vec3::new(1.0, -1.0, 1.0)).unwrap();
        let b = octree.leaf_bounds(leaf);
        assert!(b.min.x >= c.x && b.max.y <= c.y && b.min.z >= c.z, "{name}: {b:?}");
        let lit: Vec<Dir> = Dir::ALL.into_iter().filter(|&d| bare.record(leaf, d, LightId(0)).is_some()).collect();
        assert!(lit.len() >= 3, "{name}: lit faces {lit:?}");
        for d in lit {
            assert!(plie.record(leaf, d, LightId(0)).is_none(), "{name}: face {d:?} kept its record");
        }
    }
}

/// A square face under a square plate under a square light, all parallel: the umbra and penumbra are
/// squares that can be computed by hand.
fn parallel_fixture(plate: (f32, f32), height: f32) -> (Scene, Vec3, Vec3) {
    let mut b = SceneBuilder::new("parallel");
    let m = b.diffuse("w", Vec3::splat(0.5));
    let (lo, hi) = plate;
    b.quad(
        Vec3::new(lo, height, lo),
        Vec3::new(lo, height, hi),
        Vec3::new(hi, height, hi),
        Vec3::new(hi, height, lo),
        m,
    );
    b.light(
        "l",
        &[Vec3::new(0.4, 10.0, 0.4), Vec3::new(0.6, 10.0, 0.4), Vec3::new(0.6, 10.0, 0.6), Vec3::new(0.4, 10.0, 0.6)],
        Vec3::ONE,
    );
    let scene = b.build().unwrap();
    (scene, Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0))
}

/// Umbra and penumbra fractions of the Up face of the unit cell under `parallel_fixture`.
fn fractions(plate: (f32, f32), height: f32) -> (f64, f64, bool) {
    let (scene, lo, hi) = parallel_fixture(plate, height);
    let cell = plie::geometry::Aabb::new(lo, hi);
    let face = Dir::Up;
    let light = &scene.lights[0];
    let tol = 1e-5;
    let shaft = Shaft::new(&face.face_corners(&cell), &light.vertices, tol);
    let blockers: Vec<TriId> = (0..2).map(TriId).collect();
    let r = face_regions(&scene, face, &cell, light, &blockers, &shaft, tol, 10.0);
    (r.umbra_fraction, r.penumbra_fraction, r.full_umbra)
}

#[test]
fn golden_parallel_plate_umbra_and_penumbra() {
    // The unit cell's Up face (y = 1); light [0.4, 0.6]² at y = 10 (height 9 above the face); a plate
    // [a, b]² at y = 5.5 (height 4.5). From a light vertex at v the plate projects onto the face scaled
    // by s = 9 / (9 - 4.5) = 2 about v: [2a - v, 2b - v] per axis. The umbra (intersection over v in
    // {0.4, 0.6}) is [2a - 0.4, 2b - 0.6], the shadow (hull) [2a - 0.6, 2b - 0.4], both clipped to [0, 1].
    let close = |x: f64, want: f64| (x - want).abs() < 0.005;
    // Penumbra is rasterised conservatively on a 64 x 64 raster: up to a cell more on each side.
    let covers = |x: f64, want: f64| x >= want - 0.005 && x <= want + 0.07;
    // [0.3, 0.7]: umbra [0.2, 0.8]² = 0.36, shadow [0, 1]², penumbra 0.64.
    let (u, p, full) = fractions((0.3, 0.7), 5.5);
    assert!(close(u, 0.36) && covers(p, 0.64) && !full, "{u} {p} {full}");
    // [0.45, 0.55]: no umbra ([0.5, 0.5]), shadow [0.3, 0.7]² = 0.16.
    let (u, p, full) = fractions((0.45, 0.55), 5.5);
    assert!(u == 0.0 && covers(p, 0.16) && !full, "{u} {p} {full}");
    // [0.15, 0.85]: umbra [-0.1, 1.1]² covers the face with room to spare: fully dark.
    let (_, _, full) = fractions((0.15, 0.85), 5.5);
    assert!(full);
    // [0.2, 0.8]: umbra exactly the face; the margin keeps it from being called fully dark.
    let (u, _, full) = fractions((0.2, 0.8), 5.5);
    assert!(close(u, 1.0) && !full, "{u} {full}");
}

/// The face axes used by the frame are the grid's.
#[test]
fn face_frame_round_trips_points() {
    let cell = plie::geometry::Aabb::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(3.0, 4.0, 5.0));
    for face in Dir::ALL {
        let fr = FaceFrame::new(face, &cell);
        let (u, v) = face_axes(face.axis());
        let c = face.face_corners(&cell)[2];
        let x = fr.units(c.as_dvec3());
        assert!((fr.point(x) - c.as_dvec3()).length() < 1e-9);
        assert!(x.x.abs() < 1e-6 || (x.x - UNITS).abs() < 1e-6, "{face:?} {u} {v}");
    }
    let _ = LeafId(0);
}
