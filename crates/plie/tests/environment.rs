//! The public entry points (issue 14): [`Environment`] builds (refinement included), saves, loads,
//! validates and answers; [`Renderer`] renders in one call, direct light and path tracing, with the
//! same pixels as the stages called by hand; bad parameters and bad files are typed errors, never
//! panics.

use plie::internals::construct::refine::RefineParams;
use plie::internals::render::path::{render_path, Nee, PathSettings};
use plie::internals::render::shade::shade;
use plie::internals::render::{HitBuffer, NoProgress, RenderSettings};
use plie::octree::{Octree, OctreeParams};
use plie::visibility::bvh::Bvh;
use plie::{Environment, Error, Integrator, Mode, PlieFileError, PlieParams, Propagation, Regions, Renderer, Shadows};

fn bits(p: &[glam::Vec3]) -> Vec<[u32; 3]> {
    p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
}

#[test]
fn build_includes_refinement_and_equals_the_stages() {
    let scene = plie::scene::builtin::load("cornell-cube-4").unwrap();
    let params = PlieParams { refine: RefineParams::thesis_umbra(), ..PlieParams::default() };
    let (env, stats) = Environment::build(&scene, &params).unwrap();
    let octree = Octree::build(&scene, params.octree()).unwrap();
    // `Environment::build`'s limits: the default clip budgets per triangle, no list budget.
    let n = scene.triangles.len();
    let limits = plie::internals::construct::Limits {
        list_bytes: None,
        lift_clips: Some(plie::DEFAULT_LIFT_CLIPS * n),
        cell_clips: Some(plie::DEFAULT_CELL_CLIPS * n),
    };
    assert_eq!(env.plie().limits, limits, "the P-LIE records the limits it was built within");
    let built = plie::internals::construct::build_bounded(&scene, octree, params, limits, &NoProgress).unwrap();
    assert!(stats.refinement.rounds > 0, "cornell-cube-4 refines by umbra");
    assert_eq!(env.plie(), &built.plie);
    assert_eq!(env.octree(), &built.octree);
    assert_eq!(stats.blockers.records, built.stats.blockers.records);
    assert!(env.validate(&scene).is_ok(), "{}", env.validate(&scene));
}

#[test]
fn save_and_load_round_trip_and_write_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = plie::scene::builtin::load("dragon").unwrap();
    let params = PlieParams::default();
    let (env, _) = Environment::build(&scene, &params).unwrap();
    let a = dir.path().join("a.plie");
    let b = dir.path().join("b.plie");
    let bytes = env.save(&a, &scene).unwrap();
    assert_eq!(bytes, std::fs::metadata(&a).unwrap().len());
    let loaded = Environment::load(&a, &scene, Some(&params)).unwrap();
    loaded.save(&b, &scene).unwrap();
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "saving what was loaded writes the same bytes");
    assert_eq!(loaded.plie(), env.plie());
    assert_eq!(loaded.octree(), env.octree());
    assert_eq!(loaded.best_mode(), Mode::Grid);
}

#[test]
fn bad_files_are_typed_errors() {
    let dir = tempfile::tempdir().unwrap();
    let scene = plie::scene::builtin::load("cornell-cube-2").unwrap();
    let params = PlieParams::thesis();
    let (env, _) = Environment::build(&scene, &params).unwrap();
    let path = dir.path().join("good.plie");
    env.save(&path, &scene).unwrap();
    let good = std::fs::read(&path).unwrap();
    let problem = |bytes: &[u8], scene: &plie::Scene, expect: Option<&PlieParams>| {
        let p = dir.path().join("bad.plie");
        std::fs::write(&p, bytes).unwrap();
        match Environment::load(&p, scene, expect) {
            Err(Error::PlieFile { path, problem }) => {
                assert_eq!(path, p);
                problem
            }
            Err(e) => panic!("not a PlieFile error: {e}"),
            Ok(_) => panic!("a bad file was accepted"),
        }
    };
    assert_eq!(problem(b"not a plie file at all", &scene, None), PlieFileError::BadMagic);
    assert_eq!(problem(&good[..20], &scene, None), PlieFileError::TruncatedHeader);
    let mut v = good.clone();
    v[8] = 99;
    assert!(matches!(problem(&v, &scene, None), PlieFileError::Version { found: 99, .. }));
    assert!(matches!(problem(&good[..good.len() - 3], &scene, None), PlieFileError::Truncated { .. }));
    let mut v = good.clone();
    v.push(0);
    assert_eq!(problem(&v, &scene, None), PlieFileError::TrailingBytes { extra: 1 });
    let mut v = good.clone();
    let last = v.len() - 1;
    v[last] ^= 1;
    assert_eq!(problem(&v, &scene, None), PlieFileError::Checksum);
    let other = plie::scene::builtin::load("cornell-cube-1").unwrap();
    assert!(matches!(problem(&good, &other, None), PlieFileError::OtherScene { .. }));
    let asked = PlieParams { max_triangles: 7, ..params };
    assert!(matches!(problem(&good, &scene, Some(&asked)), PlieFileError::OtherParameters { .. }));
    // One line each, naming the file.
    let e = Environment::load(&dir.path().join("bad.plie"), &scene, Some(&asked)).err().unwrap().to_string();
    assert!(e.contains("bad.plie") && !e.contains('\n'), "{e}");
}

#[test]
fn bad_parameters_are_errors_not_panics() {
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let bad_octree = OctreeParams { max_triangles: 0, max_depth: 3 };
    assert!(matches!(Octree::build(&scene, bad_octree), Err(Error::InvalidParameter(_))));
    assert!(Shadows::with_octree_params(&scene, bad_octree).is_err());
    for params in [
        PlieParams { max_depth: 0, ..PlieParams::default() },
        PlieParams { max_triangles: 0, ..PlieParams::default() },
        PlieParams { regions: Regions::Skip, refine: RefineParams::thesis_umbra(), ..PlieParams::default() },
    ] {
        assert!(matches!(Environment::build(&scene, &params), Err(Error::InvalidParameter(_))), "{params:?}");
    }
    let r = Renderer::new().size(0, 4).render(&scene, Mode::Bvh, None);
    assert!(matches!(r, Err(Error::InvalidParameter(_))));
}

#[test]
fn modes_are_refused_where_they_cannot_answer() {
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let shadows = Shadows::new(&scene);
    assert!(shadows.visibility(Mode::Grid).is_err(), "the P-LIE modes need an environment");
    assert!(Renderer::new().size(4, 4).render(&scene, Mode::Lie, None).is_err());
    let params = PlieParams { regions: Regions::Skip, propagation: Propagation::Off, ..PlieParams::default() };
    let (env, _) = Environment::build(&scene, &params).unwrap();
    assert!(env.visibility(Mode::Umbra, &scene).is_err(), "umbra needs regions");
    assert!(env.visibility(Mode::Lie, &scene).is_ok());
    let other = plie::scene::builtin::load("cornell-cube-2").unwrap();
    assert!(env.visibility(Mode::Lie, &other).is_err(), "another scene");
}

#[test]
fn the_renderer_gives_the_pixels_of_the_stages_called_by_hand() {
    let scene = plie::scene::builtin::load("cornell-cube-5").unwrap();
    let (env, _) = Environment::build(&scene, &PlieParams::default()).unwrap();
    let settings = RenderSettings { width: 24, height: 16, eye_rays: 1, shadow_rays: 4, seed: 3 };
    let camera = scene.camera_or_default();
    let bvh = Bvh::build(&scene);
    let by_hand_vis = env.visibility(Mode::Grid, &scene).unwrap();
    let size = (settings.width, settings.height, settings.eye_rays);
    let hits = HitBuffer::build(&scene, &camera, size, &bvh, Some(env.octree()));
    let by_hand = shade(&scene, &hits, by_hand_vis.as_ref(), settings.shadow_rays, settings.seed, &NoProgress).0;
    let renderer = Renderer::new().settings(settings);
    let grid = renderer.render(&scene, Mode::Grid, Some(&env)).unwrap();
    assert_eq!(bits(&grid.pixels), bits(&by_hand));
    for mode in [Mode::Brute, Mode::Octree, Mode::Bvh] {
        assert_eq!(bits(&renderer.render(&scene, mode, None).unwrap().pixels), bits(&by_hand), "{mode}");
        assert_eq!(bits(&renderer.render(&scene, mode, Some(&env)).unwrap().pixels), bits(&by_hand), "{mode}");
    }

    let path = PathSettings { spp: 2, max_depth: 4, rr_depth: Some(2), nee: Nee::All };
    let path_vis = env.visibility(Mode::Umbra, &scene).unwrap();
    let by_hand =
        render_path(&scene, &camera, &settings, &path, &bvh, Some(env.octree()), path_vis.as_ref(), &NoProgress)
            .unwrap()
            .pixels;
    let traced = renderer.integrator(Integrator::Path(path));
    assert_eq!(bits(&traced.render(&scene, Mode::Umbra, Some(&env)).unwrap().pixels), bits(&by_hand));
    assert_eq!(bits(&traced.render(&scene, Mode::Bvh, None).unwrap().pixels), bits(&by_hand));
}
