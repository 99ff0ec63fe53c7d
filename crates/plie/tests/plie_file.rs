//! The `.plie` file (issue: P-LIE construction): round trip to the same image, and every way a file
//! can be wrong is a clear error — never a panic, never a wrong image.

mod support;

use std::path::Path;

use plie::internals::io::plie_file::{FORMAT_VERSION, MAGIC};
use plie::internals::lie::{Plie, PlieParams};
use plie::internals::render::RenderSettings;
use plie::octree::Octree;
use plie::visibility::Mode;
use plie::{Environment, Renderer, Scene};

fn built(scene: &Scene, params: PlieParams) -> (Octree, Plie) {
    Environment::build(scene, &params).unwrap().0.into_parts()
}

/// [`Environment::save`] of an octree and a P-LIE (possibly altered).
fn save_plie(path: &Path, scene: &Scene, octree: &Octree, p: &Plie) -> plie::Result<u64> {
    Environment::from_parts(scene, octree.clone(), p.clone()).save(path, scene)
}

/// [`Environment::load`], in parts.
fn load_plie(path: &Path, scene: &Scene, expect: Option<PlieParams>) -> plie::Result<(Octree, Plie)> {
    Environment::load(path, scene, expect.as_ref()).map(Environment::into_parts)
}

fn image(scene: &Scene, octree: &Octree, p: &Plie) -> Vec<[u32; 3]> {
    let env = Environment::from_parts(scene, octree.clone(), p.clone());
    let s = RenderSettings { width: 48, height: 48, eye_rays: 1, shadow_rays: 4, seed: 11 };
    let img = Renderer::new().settings(s).render(scene, Mode::Lie, Some(&env)).unwrap();
    img.pixels.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
}

fn err_of(r: plie::Result<(Octree, plie::internals::lie::Plie)>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn round_trip_gives_the_same_p_lie_and_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["cornell-cube-4", "dragon"] {
        let scene = plie::scene::builtin::load(name).unwrap();
        let params = PlieParams::thesis();
        let (octree, p) = built(&scene, params);
        let path = dir.path().join(format!("{name}.plie"));
        let bytes = save_plie(&path, &scene, &octree, &p).unwrap();
        assert_eq!(bytes, std::fs::metadata(&path).unwrap().len());
        let (octree2, p2) = load_plie(&path, &scene, Some(params)).unwrap();
        assert_eq!(p, p2);
        assert_eq!(octree, octree2);
        assert_eq!(image(&scene, &octree, &p), image(&scene, &octree2, &p2), "{name}");
    }
}

#[test]
fn bad_files_are_refused_with_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let scene = plie::scene::builtin::load("cornell-cube-2").unwrap();
    let params = PlieParams::thesis();
    let (octree, p) = built(&scene, params);
    let path = dir.path().join("good.plie");
    save_plie(&path, &scene, &octree, &p).unwrap();
    let good = std::fs::read(&path).unwrap();
    let write = |name: &str, bytes: &[u8]| {
        let q = dir.path().join(name);
        std::fs::write(&q, bytes).unwrap();
        q
    };

    // Another scene.
    let other = plie::scene::builtin::load("cornell-cube-4").unwrap();
    assert!(err_of(load_plie(&path, &other, None)).contains("another scene"));
    // Other parameters than asked for.
    let e = err_of(load_plie(&path, &scene, Some(PlieParams { max_triangles: 50, ..params })));
    assert!(e.contains("other parameters"), "{e}");
    // Not a .plie file at all, and an empty one.
    assert!(err_of(load_plie(&write("x.plie", b"hello world, not a plie"), &scene, None)).contains("not a .plie file"));
    assert!(err_of(load_plie(&write("e.plie", b""), &scene, None)).contains("not a .plie file"));
    // Another format version.
    let mut v = good.clone();
    v[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    let e = err_of(load_plie(&write("v.plie", &v), &scene, None));
    assert!(e.contains("version") && e.contains(&format!("{}", FORMAT_VERSION + 1)), "{e}");
    // Truncated: in the header, and in the payload.
    assert!(err_of(load_plie(&write("t1.plie", &good[..MAGIC.len() + 6]), &scene, None)).contains("truncated"));
    assert!(err_of(load_plie(&write("t2.plie", &good[..good.len() - 7]), &scene, None)).contains("truncated"));
    // Extra bytes after the payload.
    let mut x = good.clone();
    x.extend_from_slice(b"junk");
    assert!(err_of(load_plie(&write("x2.plie", &x), &scene, None)).contains("corrupted"));
    // One flipped bit anywhere in the payload: the checksum catches it.
    for pos in [28, good.len() / 2, good.len() - 1] {
        let mut c = good.clone();
        c[pos] ^= 0x10;
        let e = err_of(load_plie(&write("c.plie", &c), &scene, None));
        assert!(e.contains("corrupted"), "byte {pos}: {e}");
    }
    // A missing file.
    let e = err_of(load_plie(&dir.path().join("missing.plie"), &scene, None));
    assert!(e.contains("missing.plie"), "{e}");
}

#[test]
fn saving_is_atomic_and_keeps_existing_files_on_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let (octree, p) = built(&scene, PlieParams::thesis());
    let bad = dir.path().join("no/such/dir/x.plie");
    assert!(save_plie(&bad, &scene, &octree, &p).is_err());
    assert!(!bad.exists());
    let path = dir.path().join("keep.plie");
    save_plie(&path, &scene, &octree, &p).unwrap();
    let before = std::fs::read(&path).unwrap();
    save_plie(&path, &scene, &octree, &p).unwrap();
    assert_eq!(before, std::fs::read(&path).unwrap());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 1, "no temporary files left: {leftovers:?}");
}

/// A refined P-LIE (SPEC §4.8) saves its split nodes: loading replays them and gives the same octree,
/// P-LIE and image; asking for another refinement, or a file whose split list was tampered with (and
/// re-checksummed), is an error.
#[test]
fn refined_round_trip_and_refinement_mismatch() {
    use plie::internals::construct::refine::RefineParams;
    let dir = tempfile::tempdir().unwrap();
    let scene = plie::scene::builtin::load("cornell-cube-5").unwrap();
    let params = PlieParams { refine: RefineParams::thesis_umbra(), ..PlieParams::thesis() };
    let (env, _) = Environment::build(&scene, &params).unwrap();
    let (b_octree, b_plie) = env.into_parts();
    assert!(!b_plie.splits.is_empty());
    let path = dir.path().join("refined.plie");
    save_plie(&path, &scene, &b_octree, &b_plie).unwrap();
    let (octree2, p2) = load_plie(&path, &scene, Some(params)).unwrap();
    assert!(octree2 == b_octree && p2 == b_plie);
    assert_eq!(image(&scene, &b_octree, &b_plie), image(&scene, &octree2, &p2));
    assert!(load_plie(&path, &scene, None).is_ok());
    let e = err_of(load_plie(&path, &scene, Some(PlieParams::thesis())));
    assert!(e.contains("other parameters"), "{e}");
    // A split list naming a node that is no leaf: the file is refused.
    let mut bad = b_plie.clone();
    bad.splits[0][0] = 0;
    let q = dir.path().join("bad-splits.plie");
    save_plie(&q, &scene, &b_octree, &bad).unwrap();
    let e = err_of(load_plie(&q, &scene, None));
    assert!(e.contains("inconsistent") && e.contains("node 0"), "{e}");
}
