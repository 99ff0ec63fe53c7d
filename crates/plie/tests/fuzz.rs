//! Fuzz targets for the readers of hostile input (issue 16): OBJ, MTL, glTF/GLB, `.plie`, Mitsuba XML,
//! PLY and Mitsuba `.serialized` (issue 18).
//!
//! The targets' bodies are in `tests/fuzz/targets.rs`, shared with the cargo-fuzz binaries of `fuzz/`
//! (coverage-guided, run by `scripts/fuzz.sh` and `.ci/run`). Here they run on stable inside
//! `cargo test`, in three ways:
//!
//! - every committed input of `fuzz/seeds/TARGET/` and `fuzz/regressions/TARGET/` (cargo-fuzz's seeds
//!   and the inputs it once failed on), and the older `tests/fuzz/regressions/` files;
//! - a small mutational fuzzer: each target mutates its seeds (`tests/fuzz/seeds`, and for `.plie` a
//!   file built from `cornell-cube-1`) by byte flips, token insertions, deletions, duplications (long
//!   faces, repeated lines), truncations and splices. A panic or a case over 20 s fails the target,
//!   and its input is saved under `target/fuzz-crashes/`.
//!
//! `cargo test -p plie --test fuzz` runs `PLIE_FUZZ_CASES` cases per target (default 60, fixed seeds:
//! the same cases every run). `PLIE_FUZZ_SECONDS=60` runs each target for that many seconds instead,
//! and `PLIE_FUZZ_SEED` changes the seed (docs/robustness.md).

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[path = "fuzz/targets.rs"]
mod targets;

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz")
}

/// The cargo-fuzz folder `fuzz/` at the repository's root.
fn cargo_fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
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
        plie::internals::render::sampler::mix64(self.0)
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

/// Runs `target` on mutations of `seeds[0]` (splicing from any of `seeds`) within the budget: only
/// panics and slow cases fail. `ext` names saved inputs.
fn fuzz(name: &str, ext: &str, seeds: &[Vec<u8>], target: impl Fn(&[u8])) {
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
        let other = &seeds[rng.below(seeds.len())];
        let input = mutate(&seeds[0], other, &mut rng);
        let t = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| target(&input)));
        let slow = t.elapsed() > CASE_LIMIT;
        if outcome.is_err() || slow {
            let saved = save_crash(name, ext, &input);
            let why = if slow { format!("took {:.1} s", t.elapsed().as_secs_f64()) } else { "panicked".into() };
            failures.push(format!("{name} case {cases} {why}: input saved as {}", saved.display()));
        }
        cases += 1;
    }
    eprintln!("fuzz {name}: {cases} cases in {:.1} s, {} failures", start.elapsed().as_secs_f64(), failures.len());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Saves a failing input under `target/fuzz-crashes/`.
fn save_crash(name: &str, ext: &str, input: &[u8]) -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/fuzz-crashes");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}-{:016x}.{ext}", fnv(input)));
    std::fs::write(&path, input).unwrap();
    path
}

/// FNV-1a (a stable name for saved inputs).
fn fnv(b: &[u8]) -> u64 {
    b.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &x| (h ^ x as u64).wrapping_mul(0x100_0000_01b3))
}

#[test]
fn fuzz_obj() {
    fuzz("obj", "obj", &[seed("scene.obj"), seed("quad-light.mtl")], targets::obj);
}

#[test]
fn fuzz_mtl() {
    fuzz("mtl", "mtl", &[seed("quad-light.mtl"), seed("scene.obj")], targets::mtl);
}

#[test]
fn fuzz_gltf() {
    fuzz("gltf", "gltf", &[seed("embedded.gltf"), seed("external.gltf")], targets::gltf);
    fuzz("gltf-external", "gltf", &[seed("external.gltf"), seed("external.bin")], targets::gltf);
}

#[test]
fn fuzz_glb() {
    fuzz("glb", "glb", &[seed("scene.glb"), seed("embedded.gltf")], targets::glb);
}

#[test]
fn fuzz_mitsuba_xml() {
    fuzz("mitsuba-xml", "xml", &[seed("scene.xml"), seed("mesh.ply")], targets::mitsuba_xml);
}

#[test]
fn fuzz_ply() {
    fuzz("ply", "ply", &[seed("mesh.ply"), seed("mesh-binary.ply")], targets::ply);
    fuzz("ply-binary", "ply", &[seed("mesh-binary.ply"), seed("mesh.ply")], targets::ply);
}

#[test]
fn fuzz_serialized() {
    fuzz("serialized", "serialized", &[seed("mesh.serialized")], targets::serialized);
}

#[test]
fn fuzz_plie() {
    let seeds = [targets::plie_seed().1.clone()];
    fuzz("plie", "plie", &seeds, |b| targets::plie_file(b, false));
    fuzz("plie-checksummed", "plie", &seeds, |b| targets::plie_file(b, true));
}

/// The `.plie` targets reach past the loader: their seed loads, so `verify` runs on what loads.
#[test]
fn the_plie_seed_loads() {
    let (scene, bytes) = targets::plie_seed();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("seed.plie");
    std::fs::write(&path, bytes).unwrap();
    plie::Environment::load(&path, scene, None).unwrap();
    // The edits keep an empty program's input as it is and change it otherwise.
    assert_eq!(&targets::apply_edits(bytes, &[]), bytes);
    assert_ne!(&targets::apply_edits(bytes, &[1, 91, 1, 0, 0, 51, 0]), bytes);
}

/// Every committed input of the cargo-fuzz targets (`fuzz/seeds/TARGET/`, and the inputs a run once
/// failed on, `fuzz/regressions/TARGET/`) runs through its target without a panic; every folder
/// names a target.
#[test]
fn cargo_fuzz_seeds_and_regressions() {
    let mut n = 0;
    for kind in ["seeds", "regressions"] {
        let Ok(dirs) = std::fs::read_dir(cargo_fuzz_dir().join(kind)) else { continue };
        for dir in dirs {
            let dir = dir.unwrap().path();
            if !dir.is_dir() {
                continue;
            }
            let name = dir.file_name().unwrap().to_string_lossy().into_owned();
            let target = targets::TARGETS.iter().find(|(t, _)| *t == name);
            let Some((_, target)) = target else { panic!("fuzz/{kind}/{name}: no such target") };
            for f in std::fs::read_dir(&dir).unwrap() {
                let f = f.unwrap().path();
                if f.is_file() {
                    target(&std::fs::read(&f).unwrap());
                    n += 1;
                }
            }
        }
    }
    eprintln!("cargo-fuzz seeds and regressions: {n} inputs");
    assert!(n >= targets::TARGETS.len(), "{n} inputs");
}

/// Every input of `tests/fuzz/regressions/` (kept before the cargo-fuzz targets) loads without a panic
/// (scene files as scenes, `.plie` files for cornell-cube-1).
#[test]
fn regressions() {
    let dir = fuzz_dir().join("regressions");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        match path.extension().and_then(|e| e.to_str()) {
            Some("obj") => targets::obj(&bytes),
            Some("gltf") => targets::gltf(&bytes),
            Some("glb") => targets::glb(&bytes),
            Some("plie") => targets::plie_file(&bytes, false),
            Some("xml") => targets::mitsuba_xml(&bytes),
            Some("ply") => targets::ply(&bytes),
            Some("serialized") => targets::serialized(&bytes),
            _ => continue,
        }
        n += 1;
    }
    eprintln!("fuzz regressions: {n} inputs");
}
