//! The fuzz targets of issue 16, one function per reader: what a target does with one input. Shared by
//! the cargo-fuzz binaries (`fuzz/fuzz_targets/`, which include this file), the stable fuzzer and the
//! replay of kept crash inputs (`crates/plie/tests/fuzz.rs`). A target returns normally for any input
//! the reader accepts or refuses; a panic (or, under libFuzzer, an abort, a timeout or an allocation
//! over its limit) is a finding.
//!
//! Adding a target: a function here, an entry in [`TARGETS`], a three-line binary in
//! `fuzz/fuzz_targets/NAME.rs` with its `[[bin]]` in `fuzz/Cargo.toml`, and seed inputs in
//! `fuzz/seeds/NAME/`.

use std::path::Path;
use std::sync::OnceLock;

use plie::internals::io::plie_file::checksum;
use plie::io::{load_scene_with, LoadOptions};
use plie::octree::{Octree, OctreeParams};
use plie::visibility::bvh::Bvh;
use plie::{Environment, Scene};

/// A target: what it does with one input.
pub type Target = fn(&[u8]);

/// Every target by name (the names of the cargo-fuzz binaries and of `fuzz/seeds/NAME/` and
/// `fuzz/regressions/NAME/`).
pub const TARGETS: &[(&str, Target)] = &[
    ("obj", obj),
    ("mtl", mtl),
    ("gltf", gltf),
    ("glb", glb),
    ("plie", plie),
    ("plie_checksummed", plie_checksummed),
    ("mitsuba_xml", mitsuba_xml),
    ("ply", ply),
    ("serialized", serialized),
];

/// The companion files the scene targets write beside their input (the seeds of the stable fuzzer).
const SCENE_OBJ: &[u8] = include_bytes!("seeds/scene.obj");
const QUAD_LIGHT_MTL: &[u8] = include_bytes!("seeds/quad-light.mtl");
const EXTERNAL_BIN: &[u8] = include_bytes!("seeds/external.bin");
const SCENE_XML: &[u8] = include_bytes!("seeds/scene.xml");
const MESH_PLY: &[u8] = include_bytes!("seeds/mesh.ply");
const MESH_BINARY_PLY: &[u8] = include_bytes!("seeds/mesh-binary.ply");
const MESH_SERIALIZED: &[u8] = include_bytes!("seeds/mesh.serialized");
const TEX_PNG: &[u8] = include_bytes!("seeds/tex.png");

/// The files the seed Mitsuba scene names, but `except`.
fn mitsuba_files(except: &str) -> Vec<(&'static str, &'static [u8])> {
    [
        ("mesh.ply", MESH_PLY),
        ("mesh-binary.ply", MESH_BINARY_PLY),
        ("mesh.serialized", MESH_SERIALIZED),
        ("tex.png", TEX_PNG),
    ]
    .into_iter()
    .filter(|(n, _)| *n != except)
    .collect()
}

/// The input as a Mitsuba scene file (`scene.xml`) beside the seed scene's meshes and texture.
pub fn mitsuba_xml(input: &[u8]) {
    scene_case("scene.xml", input, &mitsuba_files(""));
}

/// The input as a PLY mesh, read alone (ASCII or binary, as its header says) and as the seed
/// scene's `mesh.ply`.
pub fn ply(input: &[u8]) {
    let mut files = mitsuba_files("mesh.ply");
    files.push(("scene.xml", SCENE_XML));
    with_files("mesh.ply", input, &files, |dir| {
        let _ = plie::io::ply::load_ply(&dir.join("mesh.ply"));
        load_scene_and_build(&dir.join("scene.xml"));
    });
}

/// The input as a Mitsuba `.serialized` file: its first shapes read alone, then as the seed
/// scene's `mesh.serialized`.
pub fn serialized(input: &[u8]) {
    let mut files = mitsuba_files("mesh.serialized");
    files.push(("scene.xml", SCENE_XML));
    with_files("mesh.serialized", input, &files, |dir| {
        for i in 0..3 {
            let _ = plie::io::serialized::load_serialized(&dir.join("mesh.serialized"), i);
        }
        load_scene_and_build(&dir.join("scene.xml"));
    });
}

/// The input as an OBJ file (`scene.obj`) beside the seed's MTL file.
pub fn obj(input: &[u8]) {
    scene_case("scene.obj", input, &[("quad-light.mtl", QUAD_LIGHT_MTL)]);
}

/// The input as the MTL file (`quad-light.mtl`) of the seed's OBJ file.
pub fn mtl(input: &[u8]) {
    with_files("quad-light.mtl", input, &[("scene.obj", SCENE_OBJ)], |dir| {
        load_scene_and_build(&dir.join("scene.obj"))
    });
}

/// The input as a glTF file (`scene.gltf`) beside the seed's external buffer `external.bin`.
pub fn gltf(input: &[u8]) {
    scene_case("scene.gltf", input, &[("external.bin", EXTERNAL_BIN)]);
}

/// The input as a GLB file (`scene.glb`).
pub fn glb(input: &[u8]) {
    scene_case("scene.glb", input, &[]);
}

/// The input as edits ([`apply_edits`]) of a real `.plie` file of `cornell-cube-1` (built once per
/// process, so the edits follow format changes), the checksum left as it was: the magic, version,
/// length and checksum checks face it ([`plie_file`]).
pub fn plie(input: &[u8]) {
    plie_file(&apply_edits(&plie_seed().1, input), false);
}

/// As [`plie`], with the checksum rewritten after the edits, as the fuzzer did: the structure
/// checks and `verify` face the altered content, not the checksum.
pub fn plie_checksummed(input: &[u8]) {
    plie_file(&apply_edits(&plie_seed().1, input), true);
}

/// `bytes` as a `.plie` file for `cornell-cube-1`, its checksum first rewritten when `fix_checksum`;
/// when it loads, `verify` rebuilds and compares sampled records and answers shadow rays with it.
pub fn plie_file(bytes: &[u8], fix_checksum: bool) {
    let mut bytes = bytes.to_vec();
    if fix_checksum && bytes.len() >= 28 {
        let sum = checksum(&bytes[28..]);
        bytes[20..28].copy_from_slice(&sum.to_le_bytes());
    }
    let (scene, _) = plie_seed();
    with_files("f.plie", &bytes, &[], |dir| {
        if let Ok(env) = Environment::load(&dir.join("f.plie"), scene, None) {
            let _ = plie::internals::verify::verify_sample(scene, env.octree(), env.plie(), 8, 4, 1);
        }
    });
}

/// Writes `input` as `name` and `companions` beside it in a new temporary folder, loads `name` as a
/// scene and, when it loads, builds its octree and BVH.
fn scene_case(name: &str, input: &[u8], companions: &[(&str, &[u8])]) {
    with_files(name, input, companions, |dir| load_scene_and_build(&dir.join(name)));
}

/// Runs `f` on a new temporary folder holding `input` as `name` and `companions`; removes it after.
fn with_files(name: &str, input: &[u8], companions: &[(&str, &[u8])], f: impl FnOnce(&Path)) {
    let dir = tempfile::tempdir().expect("a temporary folder");
    std::fs::write(dir.path().join(name), input).expect("write the input");
    for (n, bytes) in companions {
        std::fs::write(dir.path().join(n), bytes).expect("write a companion file");
    }
    f(dir.path());
}

/// Loads a scene file (paths outside its folder refused, as by default) and, when it loads, builds
/// its octree (where coincident triangles once exploded) and BVH (where they once ran too deep).
fn load_scene_and_build(path: &Path) {
    if let Ok(scene) = load_scene_with(path, LoadOptions::default()) {
        let _ = Octree::build(&scene, OctreeParams::default()).expect("valid octree parameters");
        let _ = Bvh::build(&scene);
    }
}

/// `cornell-cube-1` and a `.plie` file of it (grids on), built once.
pub fn plie_seed() -> &'static (Scene, Vec<u8>) {
    static SEED: OnceLock<(Scene, Vec<u8>)> = OnceLock::new();
    SEED.get_or_init(|| {
        let scene = plie::scene::builtin::load("cornell-cube-1").expect("built-in scene");
        let params = plie::internals::lie::PlieParams {
            grids: plie::internals::lie::Grids::Build,
            ..plie::internals::lie::PlieParams::thesis()
        };
        let (env, _) = Environment::build(&scene, &params).expect("valid parameters");
        let dir = tempfile::tempdir().expect("a temporary folder");
        let path = dir.path().join("seed.plie");
        env.save(&path, &scene).expect("save the seed");
        let bytes = std::fs::read(&path).expect("read the seed");
        (scene, bytes)
    })
}

/// `data` changed by the edits `program` spells, one after another, each a 5-byte head (an
/// operation byte, a little-endian `u32` offset taken modulo the current length plus one) and its
/// operands: `0` overwrite with the next `n` bytes (`n` the byte after the head), `1` fill `n` bytes
/// with the byte after `n` (the "51 zero bytes at offset 347"), `2` insert the next `n`
/// bytes, `3` delete `n` bytes, `4` truncate. A short or empty program leaves `data` as it is.
pub fn apply_edits(data: &[u8], program: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    let mut p = program;
    while p.len() >= 5 {
        let op = p[0] % 5;
        let at = u32::from_le_bytes([p[1], p[2], p[3], p[4]]) as usize % (d.len() + 1);
        p = &p[5..];
        let n = p.first().map_or(0, |&n| n as usize);
        p = p.get(1..).unwrap_or(&[]);
        match op {
            0 | 2 => {
                let bytes = &p[..n.min(p.len())];
                p = &p[bytes.len()..];
                if op == 0 {
                    let end = (at + bytes.len()).min(d.len());
                    d.splice(at..end, bytes.iter().copied());
                } else {
                    d.splice(at..at, bytes.iter().copied());
                }
            }
            1 => {
                let fill = p.first().copied().unwrap_or(0);
                p = p.get(1..).unwrap_or(&[]);
                let end = (at + n).min(d.len());
                d[at..end].fill(fill);
            }
            3 => {
                let end = (at + n).min(d.len());
                d.drain(at..end);
            }
            _ => d.truncate(at),
        }
    }
    d
}
