//! The path tracer (global illumination) against closed forms: the furnace, where every surface of a
//! closed box emits `Le` and reflects with albedo `rho`, so radiance is `Le (1 - rho^k) / (1 - rho)`
//! after `k` path vertices (Mitsuba's `max_depth = k`) and `Le / (1 - rho)` unbounded; path mode at
//! depth 2 against direct mode's expectation; and exactness (bit-identical images across exact modes
//! and thread counts).

use glam::Vec3;
use plie::internals::lie::PlieParams;
use plie::internals::render::path::{Nee, PathSettings, PathStats};
use plie::internals::render::RenderSettings;
use plie::visibility::{Mode, QueryStats};
use plie::{Camera, Environment, Integrator, Material, Renderer, Scene, SceneBuilder, Timing, TriId};

/// A path-traced image and its figures.
struct PathRendered {
    pixels: Vec<Vec3>,
    stats: QueryStats,
    path: PathStats,
}

/// A closed unit cube, every face an inward-facing light of radiance `le` and albedo `rho`.
fn furnace(rho: f32, le: f32) -> Scene {
    furnace_rgb(rho, Vec3::splat(le))
}

/// [`furnace`] with radiance `le` per channel.
fn furnace_rgb(rho: f32, le: Vec3) -> Scene {
    let mut b = SceneBuilder::new("furnace");
    let m = b.material(Material { name: "wall".into(), albedo: Vec3::splat(rho), emission: le, texture: None });
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    // Each face counter-clockwise seen from inside the cube (so its front faces inward).
    let faces = [
        [c(0., 0., 0.), c(0., 1., 0.), c(0., 1., 1.), c(0., 0., 1.)], // x = 0, normal +x
        [c(1., 0., 0.), c(1., 0., 1.), c(1., 1., 1.), c(1., 1., 0.)], // x = 1, normal -x
        [c(0., 0., 0.), c(0., 0., 1.), c(1., 0., 1.), c(1., 0., 0.)], // y = 0, normal +y
        [c(0., 1., 0.), c(1., 1., 0.), c(1., 1., 1.), c(0., 1., 1.)], // y = 1, normal -y
        [c(0., 0., 0.), c(1., 0., 0.), c(1., 1., 0.), c(0., 1., 0.)], // z = 0, normal +z
        [c(0., 0., 1.), c(0., 1., 1.), c(1., 1., 1.), c(1., 0., 1.)], // z = 1, normal -z
    ];
    for f in faces {
        let first = b.triangle_count() as u32;
        b.quad(f[0], f[1], f[2], f[3], m);
        b.light_from_triangles(vec![TriId(first), TriId(first + 1)], f.to_vec(), le);
    }
    b.build().unwrap()
}

fn inside_camera() -> Camera {
    Camera::new(Vec3::new(0.5, 0.5, 0.2), Vec3::new(0.6, 0.4, 1.0), Vec3::Y, 90.0).unwrap()
}

fn trace(scene: &Scene, camera: &Camera, size: u32, n: u32, path: PathSettings, mode: Mode) -> PathRendered {
    let settings = RenderSettings { width: size, height: size, eye_rays: 1, shadow_rays: n, seed: 7 };
    let params = PlieParams { max_triangles: 4, ..PlieParams::default() };
    let env = mode.needs_plie().then(|| Environment::build(scene, &params).unwrap().0);
    let renderer = Renderer::new().settings(settings).camera(*camera).integrator(Integrator::Path(path));
    let image = renderer.render(scene, mode, env.as_ref()).unwrap();
    let Timing::Path { path, .. } = image.timing else { panic!("not path-traced") };
    PathRendered { pixels: image.pixels, stats: image.stats, path }
}

/// Mean of the first channel over pixels, and its standard error (pixels are independent).
fn mean_and_error(pixels: &[Vec3]) -> (f64, f64) {
    let n = pixels.len() as f64;
    let mean = pixels.iter().map(|p| p.x as f64).sum::<f64>() / n;
    let var = pixels.iter().map(|p| (p.x as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Tolerance: 4 standard errors of the image mean (measured from the pixels, which are independent),
/// and that standard error must be under 0.5% of the expected radiance, so a bias of 2% fails.
fn assert_close(what: &str, pixels: &[Vec3], expected: f64) {
    let (mean, se) = mean_and_error(pixels);
    eprintln!("{what}: mean {mean:.5}, expected {expected:.5}, standard error {se:.5}");
    assert!(se < 0.005 * expected, "{what}: standard error {se} too large for the test");
    assert!((mean - expected).abs() <= 4.0 * se + 1e-6 * expected, "{what}: mean {mean}, expected {expected}");
}

#[test]
fn furnace_after_k_vertices() {
    for rho in [0.3f32, 0.6, 0.8] {
        let scene = furnace(rho, 1.0);
        for k in [1, 2, 3, 5] {
            let path = PathSettings { spp: 8, max_depth: k, rr_depth: None, nee: Nee::All };
            let out = trace(&scene, &inside_camera(), 24, 2, path, Mode::Bvh);
            let r = rho as f64;
            assert_close(&format!("rho {rho}, depth {k}"), &out.pixels, (1.0 - r.powi(k)) / (1.0 - r));
        }
    }
}

#[test]
fn furnace_unbounded_with_russian_roulette() {
    for (rho, nee) in [(0.3f32, Nee::All), (0.6, Nee::Power), (0.8, Nee::All)] {
        let scene = furnace(rho, 2.0);
        let path = PathSettings { spp: 64, max_depth: -1, rr_depth: Some(2), nee };
        let out = trace(&scene, &inside_camera(), 24, 2, path, Mode::Bvh);
        assert_close(&format!("rho {rho}, unbounded, {nee:?}"), &out.pixels, 2.0 / (1.0 - rho as f64));
    }
}

#[test]
fn depth_two_equals_direct_light_in_expectation() {
    let scene = plie::scene::builtin::load("cornell-cube-2").unwrap();
    // Looking down at the floor and the blocks from inside the box: the light is out of view, so
    // pixels differ by estimator noise, not by how eye rays sample the light's sharp edges.
    let camera = Camera::new(Vec3::new(278.0, 450.0, 50.0), Vec3::new(278.0, 0.0, 300.0), Vec3::Y, 60.0).unwrap();
    let size = 32;
    let path = PathSettings { spp: 64, max_depth: 2, rr_depth: None, nee: Nee::All };
    let traced = trace(&scene, &camera, size, 4, path, Mode::Bvh);
    let settings = RenderSettings { width: size, height: size, eye_rays: 8, shadow_rays: 16, seed: 3 };
    let direct = Renderer::new().settings(settings).camera(camera).render(&scene, Mode::Bvh, None).unwrap();
    // Per-pixel differences: their mean is zero in expectation; compare it with its standard error.
    let diff: Vec<Vec3> = traced.pixels.iter().zip(&direct.pixels).map(|(a, b)| *a - *b).collect();
    let (d, se) = mean_and_error(&diff);
    let (m, _) = mean_and_error(&direct.pixels);
    eprintln!("depth 2 vs direct: mean direct {m:.5}, mean difference {d:.6} (standard error {se:.6})");
    assert!(se < 0.005 * m, "standard error {se} too large for the test");
    assert!(d.abs() <= 4.0 * se, "path at depth 2 differs from direct: {d} ({se})");
}

#[test]
fn exact_modes_give_bit_identical_path_images_for_any_thread_count() {
    let scene = plie::scene::builtin::load("cornell-cube-2").unwrap();
    let camera = scene.camera_or_default();
    let path = PathSettings { spp: 2, max_depth: 4, rr_depth: Some(2), nee: Nee::Power };
    let reference = trace(&scene, &camera, 24, 3, path, Mode::Brute);
    assert!(reference.path.bounce_rays > 0 && reference.stats.occluded > 0);
    for mode in [Mode::Bvh, Mode::Octree, Mode::Lie, Mode::Grid] {
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let out = pool.install(|| trace(&scene, &camera, 24, 3, path, mode));
            assert_eq!(out.stats.shadow_rays, reference.stats.shadow_rays, "{mode} with {threads} threads");
            assert!(out.pixels == reference.pixels, "{mode} with {threads} threads differs from brute force");
            // Only the P-LIE modes locate path vertices in the octree.
            assert_eq!(out.path.locates > 0, mode.needs_plie(), "{mode}");
        }
    }
}

/// Lights whose power is below f32's range (radiance 1e-45, the least subnormal, in one channel:
/// a third of it rounds to zero) still give finite pixels when lights are chosen by power; a light
/// whose power is beyond f32's range is refused.
#[test]
fn faint_lights_give_finite_pixels_and_overflowing_ones_are_refused() {
    let scene = furnace_rgb(0.5, Vec3::new(1e-45, 0.0, 0.0));
    for nee in [Nee::Power, Nee::All] {
        let path = PathSettings { spp: 4, max_depth: 3, rr_depth: None, nee };
        let out = trace(&scene, &inside_camera(), 8, 2, path, Mode::Bvh);
        assert!(out.pixels.iter().all(|p| p.is_finite()), "{nee:?}: a pixel is not finite");
    }
    let mut b = SceneBuilder::new("bright");
    let c = |x: f32, z: f32| Vec3::new(x, 1.0, z);
    b.light("sun", &[c(0.0, 0.0), c(0.0, 2.0), c(2.0, 2.0), c(2.0, 0.0)], Vec3::splat(3e38));
    let w = b.diffuse("w", Vec3::splat(0.5));
    b.quad(Vec3::ZERO, Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::X, w);
    let err = b.build().unwrap_err().to_string();
    assert!(err.contains("beyond the range of f32"), "{err}");
}
