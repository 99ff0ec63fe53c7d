//! Loading a P-LIE from bytes in memory (issue 20: a distributed object store hands a worker the
//! `.plie` file's bytes): the same environment as from the file, and the same checks, with errors
//! naming where the bytes came from.

use plie::{Environment, Error, PlieFileError, PlieParams};

#[test]
fn bytes_load_as_the_file_does_and_are_checked_the_same_way() {
    let dir = tempfile::tempdir().unwrap();
    let scene = plie::scene::builtin::load("huis-a").unwrap();
    let (env, _) = Environment::build(&scene, &PlieParams::default()).unwrap();
    let file = dir.path().join("h.plie");
    env.save(&file, &scene).unwrap();
    let bytes = std::fs::read(&file).unwrap();

    let from_file = Environment::load(&file, &scene, None).unwrap();
    let from_bytes = Environment::load_bytes(&bytes, "object 7", &scene, Some(env.params())).unwrap();
    assert_eq!(from_bytes.plie(), from_file.plie());
    assert_eq!(from_bytes.octree(), from_file.octree());

    let problem = |b: &[u8], scene: &plie::Scene| match Environment::load_bytes(b, "object 7", scene, None) {
        Err(Error::PlieFile { path, problem }) => {
            assert_eq!(path.to_str(), Some("object 7"));
            problem
        }
        Err(e) => panic!("expected a .plie file error, got {e}"),
        Ok(_) => panic!("bad bytes loaded"),
    };
    assert_eq!(problem(b"junk", &scene), PlieFileError::BadMagic);
    assert!(matches!(problem(&bytes[..bytes.len() - 1], &scene), PlieFileError::Truncated { .. }));
    let mut flipped = bytes.clone();
    *flipped.last_mut().unwrap() ^= 1;
    assert_eq!(problem(&flipped, &scene), PlieFileError::Checksum);
    let other = plie::scene::builtin::load("huis-b").unwrap();
    assert!(matches!(problem(&bytes, &other), PlieFileError::OtherScene { .. }));
    let other_params = PlieParams { max_triangles: 50, ..PlieParams::default() };
    let err = Environment::load_bytes(&bytes, "object 7", &scene, Some(&other_params)).err().unwrap();
    assert!(err.to_string().contains("other parameters"), "{err}");
}
