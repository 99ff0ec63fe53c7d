//! Fuzz targets for the readers of hostile input (issue 16): OBJ, MTL, glTF/GLB and `.plie`.
//!
//! A small mutational fuzzer that runs in `cargo test` (cargo-fuzz needs a nightly toolchain and a
//! sanitizer build of every dependency; this runs on stable): each target mutates its seed corpus
//! (`tests/fuzz/seeds`, and for `.plie` a file built from `cornell-cube-1`) by byte flips, token
//! insertions, deletions, duplications (long faces, repeated lines), truncations and splices, writes
//! the case to a temporary folder and loads it. A case passes when the reader returns `Ok` or `Err`;
//! a panic fails the target, and its input is saved under `target/fuzz-crashes/` to be added to
//! `tests/fuzz/regressions/`, whose files every run loads first.
//!
//! `cargo test -p plie --test fuzz` runs `PLIE_FUZZ_CASES` cases per target (default 60, fixed seeds:
//! the same cases every run). `PLIE_FUZZ_SECONDS=60` runs each target for that many seconds instead,
//! and `PLIE_FUZZ_SEED` changes the seed (`.ci/run` and docs/robustness.md).

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use plie::io::plie_file::{load_plie, save_plie};
use plie::io::{load_scene, LoadOptions};
use plie::octree::Octree;

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz")
}

fn seed(name: &str) -> Vec<u8> {
    std::fs::read(fuzz_dir().join("seeds").join(name)).unwrap()
}

/// Tokens the mutator inserts: what the formats are made of, and the values that broke readers.
const TOKENS: &[&str] = &[
    "\n",
    " ",
    "/",
    "-",
    "0",
    "1",
    "-1",
    "3",
    "1e39",
    "nan",
    "inf",
    "99999999999999999999",
    "f 1 2 3 1 2 3 1 2 3",
    "v 0 0 0",
    "mtllib ",
    "usemtl ",
    "newmtl ",
    "Ke 1 1 1",
    "Kd",
    "/etc/passwd",
    "../../x",
    "/dev/zero",
    "file:///etc/passwd",
    "\"",
    ",",
    "{",
    "}",
    "[",
    "]",
    ":",
    "null",
    "\"uri\"",
    "\"POSITION\"",
    "\"accessors\"",
    "\"count\"",
    "\"byteLength\"",
    "\"indices\"",
    "\"mode\"",
    "\"nodes\"",
    "\"children\"",
    "1e308",
    "4294967295",
    "-2147483648",
    "\u{0}",
    "\u{ff}",
];

/// SplitMix64.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        plie::render::sampler::mix64(self.0)
    }

    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

/// One to four mutations of `data`; `other` is spliced from.
fn mutate(data: &[u8], other: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut d = data.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = d.len();
        match rng.below(7) {
            0 if n > 0 => {
                let i = rng.below(n);
                d[i] ^= 1 << rng.below(8);
            }
            1 if n > 0 => {
                let i = rng.below(n);
                d[i] = rng.next() as u8;
            }
            2 => {
                let i = rng.below(n + 1);
                let t = TOKENS[rng.below(TOKENS.len())].as_bytes();
                d.splice(i..i, t.iter().copied());
            }
            3 if n > 0 => {
                let i = rng.below(n);
                let j = (i + 1 + rng.below(32)).min(n);
                d.drain(i..j);
            }
            4 if n > 0 => {
                // Duplicate a range many times: long faces, repeated lines and members.
                let i = rng.below(n);
                let j = (i + 1 + rng.below(64)).min(n);
                let piece = d[i..j].to_vec();
                for _ in 0..1 + rng.below(200) {
                    d.splice(j..j, piece.iter().copied());
                }
            }
            5 => d.truncate(rng.below(n + 1)),
            _ if !other.is_empty() => {
                let i = rng.below(n + 1);
                let a = rng.below(other.len());
                let b = (a + 1 + rng.below(64)).min(other.len());
                d.splice(i..i, other[a..b].iter().copied());
            }
            _ => {}
        }
    }
    d
}

/// How long a target runs: `PLIE_FUZZ_SECONDS`, else `PLIE_FUZZ_CASES` cases (default 60).
enum Budget {
    Cases(usize),
    Time(Duration),
}

fn budget() -> Budget {
    if let Some(s) = std::env::var("PLIE_FUZZ_SECONDS").ok().and_then(|s| s.parse::<f64>().ok()) {
        return Budget::Time(Duration::from_secs_f64(s));
    }
    Budget::Cases(std::env::var("PLIE_FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(60))
}

/// The longest a single case may take (a hang shows up as a failure, not a stuck run).
const CASE_LIMIT: Duration = Duration::from_secs(20);

/// Runs `target` on mutations of `seeds` (file name in the case folder, contents) within the budget;
/// `target` gets the folder and returns nothing (its `Result` is dropped): only panics and slow cases
/// fail. The first file of `seeds` is the one mutated; the others are written unchanged beside it.
fn fuzz(name: &str, seeds: &[(&str, Vec<u8>)], target: impl Fn(&Path)) {
    let base: u64 = std::env::var("PLIE_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(16);
    let mut rng = Rng(base ^ fnv(name.as_bytes()));
    let start = Instant::now();
    let mut cases = 0usize;
    let mut failures = Vec::new();
    loop {
        match budget() {
            Budget::Cases(n) if cases >= n => break,
            Budget::Time(t) if start.elapsed() >= t => break,
            _ => {}
        }
        let (file, data) = &seeds[0];
        let other = &seeds[rng.below(seeds.len())].1;
        let input = mutate(data, other, &mut rng);
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(file), &input).unwrap();
        for (f, d) in &seeds[1..] {
            std::fs::write(dir.path().join(f), d).unwrap();
        }
        let t = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| target(dir.path())));
        let slow = t.elapsed() > CASE_LIMIT;
        if outcome.is_err() || slow {
            let saved = save_crash(name, file, &input);
            let why = if slow { format!("took {:.1} s", t.elapsed().as_secs_f64()) } else { "panicked".into() };
            failures.push(format!("{name} case {cases} {why}: input saved as {}", saved.display()));
        }
        cases += 1;
    }
    eprintln!("fuzz {name}: {cases} cases in {:.1} s, {} failures", start.elapsed().as_secs_f64(), failures.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Saves a failing input under `target/fuzz-crashes/`.
fn save_crash(name: &str, file: &str, input: &[u8]) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/fuzz-crashes");
    std::fs::create_dir_all(&dir).unwrap();
    let ext = Path::new(file).extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    let path = dir.join(format!("{name}-{:016x}.{ext}", fnv(input)));
    std::fs::write(&path, input).unwrap();
    path
}

/// FNV-1a (a stable name for saved inputs).
fn fnv(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &x| (h ^ x as u64).wrapping_mul(0x100_0000_01b3))
}

/// Loads a scene and, when it loads, builds its octree (where coincident triangles once exploded).
fn load_and_build(path: &Path) {
    if let Ok(scene) = load_scene(path) {
        let _ = Octree::build(&scene, plie::octree::OctreeParams::default()).expect("valid octree parameters");
    }
}

#[test]
fn fuzz_obj() {
    let seeds = [("scene.obj", seed("scene.obj")), ("quad-light.mtl", seed("quad-light.mtl"))];
    fuzz("obj", &seeds, |d| load_and_build(&d.join("scene.obj")));
}

#[test]
fn fuzz_mtl() {
    let seeds = [("quad-light.mtl", seed("quad-light.mtl")), ("scene.obj", seed("scene.obj"))];
    fuzz("mtl", &seeds, |d| load_and_build(&d.join("scene.obj")));
}

#[test]
fn fuzz_gltf() {
    let seeds = [("embedded.gltf", seed("embedded.gltf")), ("external.gltf", seed("external.gltf"))];
    fuzz("gltf", &seeds, |d| load_and_build(&d.join("embedded.gltf")));
    let seeds = [("external.gltf", seed("external.gltf")), ("external.bin", seed("external.bin"))];
    fuzz("gltf-external", &seeds, |d| load_and_build(&d.join("external.gltf")));
}

#[test]
fn fuzz_glb() {
    let seeds = [("scene.glb", seed("scene.glb")), ("embedded.gltf", seed("embedded.gltf"))];
    fuzz("glb", &seeds, |d| load_and_build(&d.join("scene.glb")));
}

/// A `.plie` file of cornell-cube-1 (built here: the format's version may change).
fn plie_seed() -> (plie::Scene, Vec<u8>) {
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let params = plie::lie::PlieParams { grids: plie::lie::Grids::Build, ..plie::lie::PlieParams::thesis() };
    let octree = Octree::build(&scene, params.octree()).expect("valid octree parameters");
    let built = plie::construct::build_refined(&scene, octree, params, &plie::render::NoProgress);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("seed.plie");
    save_plie(&path, &scene, &built.octree, &built.plie).unwrap();
    (scene, std::fs::read(&path).unwrap())
}

/// Loads a `.plie` file, with its checksum rewritten when `fix_checksum` (as the fuzzer did),
/// and, when it loads, answers sampled shadow rays with it: altered data must not panic a mode.
fn load_plie_case(scene: &plie::Scene, path: &Path, fix_checksum: bool) {
    if fix_checksum {
        let mut b = std::fs::read(path).unwrap();
        if b.len() >= 28 {
            let sum = plie_checksum(&b[28..]);
            b[20..28].copy_from_slice(&sum.to_le_bytes());
            std::fs::write(path, &b).unwrap();
        }
    }
    if let Ok((octree, plie)) = load_plie(path, scene, None) {
        let _ = plie::verify::verify_sample(scene, &octree, &plie, 8, 4, 1);
    }
}

/// The `.plie` checksum (XXH3-64 of the payload), through the library's own reader: a file whose
/// header is rewritten with it passes the checksum.
fn plie_checksum(payload: &[u8]) -> u64 {
    plie::io::plie_file::checksum(payload)
}

#[test]
fn fuzz_plie() {
    let (scene, bytes) = plie_seed();
    let seeds = [("f.plie", bytes.clone())];
    fuzz("plie", &seeds, |d| load_plie_case(&scene, &d.join("f.plie"), false));
    fuzz("plie-checksummed", &seeds, |d| load_plie_case(&scene, &d.join("f.plie"), true));
}

/// Every saved crash input loads without a panic (scene files as scenes, `.plie` files for
/// cornell-cube-1).
#[test]
fn regressions() {
    let dir = fuzz_dir().join("regressions");
    let mut n = 0;
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        match path.extension().and_then(|e| e.to_str()) {
            Some("obj" | "gltf" | "glb") => {
                let _ = plie::io::load_scene_with(&path, LoadOptions::default());
                load_and_build(&path);
            }
            Some("plie") => {
                let _ = load_plie(&path, &scene, None);
            }
            _ => continue,
        }
        n += 1;
    }
    eprintln!("fuzz regressions: {n} inputs");
}
