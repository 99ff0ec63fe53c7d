//! The `.plie` file: a P-LIE saved once and loaded for any number of renders.
//!
//! Layout (little-endian):
//!
//! | bytes | content |
//! |---|---|
//! | 8 | magic `PLIE\r\n\x1a\n` |
//! | 4 | format version ([`FORMAT_VERSION`]) |
//! | 8 | payload length |
//! | 8 | XXH3-64 checksum of the payload |
//! | n | payload: [`FileBody`] in postcard encoding |
//!
//! The payload holds the build parameters (the P-LIE holds them too, with the limits it was built
//! within, so that `plie verify --full` rebuilds it exactly), a fingerprint of the scene's geometry,
//! materials and lights, a fingerprint of the octree the P-LIE was built on, and the P-LIE. The
//! octree itself is not stored:
//! it is a deterministic function of the scene and the parameters, and is rebuilt on load (a fraction
//! of the P-LIE's build time), then refined by replaying the P-LIE's list of split nodes (SPEC §4.8);
//! its fingerprint proves it is the same one. Every way a file can be wrong
//! (another format, another version, truncated, corrupted, another scene, other parameters, an
//! inconsistent structure) is an error, never a panic. Writes are atomic.

use std::path::Path;

use serde::{Deserialize, Serialize};
use xxhash_rust::xxh3::{xxh3_64, Xxh3};

use super::atomic::write_atomic;
use crate::error::{Error, PlieFileError, Result};
use crate::lie::{Plie, PlieParams};
use crate::octree::Octree;
use crate::scene::Scene;

/// First bytes of every `.plie` file.
pub const MAGIC: [u8; 8] = *b"PLIE\r\n\x1a\n";
/// Version of the layout written by this build of plie.
pub const FORMAT_VERSION: u32 = 7;
const HEADER: usize = 8 + 4 + 8 + 8;

/// What a `.plie` file holds after its header.
#[derive(Serialize, Deserialize)]
pub struct FileBody {
    /// Build parameters.
    pub params: PlieParams,
    /// [`scene_fingerprint`] of the scene it was built for.
    pub scene_fingerprint: u64,
    /// [`octree_fingerprint`] of the octree it was built on.
    pub octree_fingerprint: u64,
    /// The P-LIE.
    pub plie: Plie,
}

/// The checksum a `.plie` header stores for `payload` (XXH3-64).
pub fn checksum(payload: &[u8]) -> u64 {
    xxh3_64(payload)
}

/// A hash of everything that shapes the P-LIE: triangles, their materials' emission, lights.
pub fn scene_fingerprint(scene: &Scene) -> u64 {
    let mut h = Batched::new();
    h.put(&(scene.triangles.len() as u64).to_le_bytes());
    for t in &scene.triangles {
        for v in &t.v {
            for c in v.to_array() {
                h.put(&c.to_le_bytes());
            }
        }
    }
    for l in &scene.tri_light {
        h.put(&l.map_or(u32::MAX, |l| l.0).to_le_bytes());
    }
    for l in &scene.lights {
        for v in &l.vertices {
            for c in v.to_array() {
                h.put(&c.to_le_bytes());
            }
        }
        for c in l.radiance.to_array() {
            h.put(&c.to_le_bytes());
        }
    }
    h.digest()
}

/// A hash of the octree's leaves: their boxes and triangle lists.
pub fn octree_fingerprint(octree: &Octree) -> u64 {
    let mut h = Batched::new();
    for l in octree.leaves() {
        let b = octree.leaf_bounds(l);
        for c in b.min.to_array().into_iter().chain(b.max.to_array()) {
            h.put(&c.to_le_bytes());
        }
        h.put(&(octree.leaf_triangles(l).len() as u32).to_le_bytes());
        for t in octree.leaf_triangles(l) {
            h.put(&t.0.to_le_bytes());
        }
    }
    h.digest()
}

/// A streaming XXH3 fed in blocks: the digest of a byte stream does not depend on how it is cut, so
/// this is the hash of the same bytes fed one value at a time (a call per 4 bytes, which made
/// writing a 10M-triangle scene's `.plie` take 2.0-2.3 s, 0.6 s now: docs/results.md session 40).
struct Batched {
    h: Xxh3,
    buf: Vec<u8>,
}

impl Batched {
    const BLOCK: usize = 1 << 16;

    fn new() -> Batched {
        Batched { h: Xxh3::new(), buf: Vec::with_capacity(Self::BLOCK) }
    }

    fn put(&mut self, bytes: &[u8]) {
        if self.buf.len() + bytes.len() > Self::BLOCK {
            self.h.update(&self.buf);
            self.buf.clear();
        }
        self.buf.extend_from_slice(bytes);
    }

    fn digest(mut self) -> u64 {
        self.h.update(&self.buf);
        self.h.digest()
    }
}

/// Saves the P-LIE built for `scene` on `octree`, atomically. Returns the bytes written.
pub(crate) fn save_plie(path: &Path, scene: &Scene, octree: &Octree, plie: &Plie) -> Result<u64> {
    let body = FileBody {
        params: plie.params,
        scene_fingerprint: scene_fingerprint(scene),
        octree_fingerprint: octree_fingerprint(octree),
        plie: plie.clone(),
    };
    let payload = postcard::to_stdvec(&body)
        .map_err(|e| Error::Io { path: path.to_path_buf(), source: std::io::Error::other(e.to_string()) })?;
    let io = |source| Error::Io { path: path.to_path_buf(), source };
    write_atomic(path, |w| {
        w.write_all(&MAGIC).map_err(io)?;
        w.write_all(&FORMAT_VERSION.to_le_bytes()).map_err(io)?;
        w.write_all(&(payload.len() as u64).to_le_bytes()).map_err(io)?;
        w.write_all(&xxh3_64(&payload).to_le_bytes()).map_err(io)?;
        w.write_all(&payload).map_err(io)?;
        Ok(())
    })?;
    Ok((HEADER + payload.len()) as u64)
}

/// Loads a `.plie` file for `scene`: checks format, version, integrity, that it was built for this
/// scene (and, if `expect` is given, on the same octree parameters; whether it has face grids does
/// not matter, modes use them when present), rebuilds the octree and checks that it is the one the
/// P-LIE was built on. Returns the octree and the P-LIE. Every problem with the file is an
/// [`Error::PlieFile`].
pub(crate) fn load_plie(path: &Path, scene: &Scene, expect: Option<PlieParams>) -> Result<(Octree, Plie)> {
    let bytes = super::input::read_bounded(path, super::input::MAX_INPUT_BYTES)?;
    read_plie(&bytes, scene, expect).map_err(|problem| Error::PlieFile { path: path.to_path_buf(), problem })
}

/// [`load_plie`] from the bytes of a `.plie` file already in memory (e.g. fetched from a distributed
/// object store), with the same checks; `origin` names the bytes in errors.
pub(crate) fn load_plie_bytes(
    bytes: &[u8],
    origin: &str,
    scene: &Scene,
    expect: Option<PlieParams>,
) -> Result<(Octree, Plie)> {
    read_plie(bytes, scene, expect).map_err(|problem| Error::PlieFile { path: origin.into(), problem })
}

/// [`load_plie`] of the file's bytes.
fn read_plie(bytes: &[u8], scene: &Scene, expect: Option<PlieParams>) -> Result<(Octree, Plie), PlieFileError> {
    if bytes.len() < 8 || bytes[..8] != MAGIC {
        return Err(PlieFileError::BadMagic);
    }
    if bytes.len() < HEADER {
        return Err(PlieFileError::TruncatedHeader);
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(PlieFileError::Version { found: version, supported: FORMAT_VERSION });
    }
    let len = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let sum = u64::from_le_bytes(bytes[20..28].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER..];
    if (payload.len() as u64) < len {
        return Err(PlieFileError::Truncated { have: payload.len() as u64, expected: len });
    }
    if payload.len() as u64 != len {
        return Err(PlieFileError::TrailingBytes { extra: payload.len() as u64 - len });
    }
    if xxh3_64(payload) != sum {
        return Err(PlieFileError::Checksum);
    }
    let body: FileBody = postcard::from_bytes(payload).map_err(|_| PlieFileError::Undecodable)?;
    if body.scene_fingerprint != scene_fingerprint(scene) {
        return Err(PlieFileError::OtherScene { scene: scene.name.clone() });
    }
    if let Some(p) = expect {
        if p.octree() != body.params.octree() || p.refine != body.params.refine {
            return Err(PlieFileError::OtherParameters {
                file: describe_params(&body.params),
                asked: describe_params(&p),
            });
        }
    }
    let invalid = |e: Error| PlieFileError::InvalidParameters(e.to_string());
    body.params.octree().validate().map_err(invalid)?;
    body.params.refine.validate(body.params.has_regions()).map_err(invalid)?;
    let mut octree = Octree::build_valid(scene, body.params.octree());
    for round in &body.plie.splits {
        octree = octree.split_nodes(scene, round).map_err(|e| PlieFileError::Inconsistent(e.to_string()))?;
    }
    if octree_fingerprint(&octree) != body.octree_fingerprint {
        return Err(PlieFileError::OtherOctree);
    }
    body.plie.validate(scene, &octree).map_err(PlieFileError::Inconsistent)?;
    Ok((octree, body.plie))
}

/// The parameters that must match, as the command-line options that set them.
fn describe_params(p: &PlieParams) -> String {
    let r = &p.refine;
    let mut refine: Vec<&str> = Vec::new();
    if r.umbra_full {
        refine.push("umbra-full");
    }
    if r.umbra_free {
        refine.push("umbra-free");
    }
    if r.blockers.is_some() {
        refine.push("blockers");
    }
    let mut s = format!("--max-triangles {} --max-depth {}", p.max_triangles, p.max_depth);
    if !refine.is_empty() {
        s += &format!(" --refine {} --max-split-depth {}", refine.join(","), r.max_split_depth);
    }
    match r.blockers {
        Some(crate::lie::MaxBlockers::Fixed(n)) => s += &format!(" --max-blockers {n}"),
        Some(crate::lie::MaxBlockers::Adaptive) => s += " --max-blockers adaptive",
        None => {}
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fed in blocks or one value at a time, the same bytes give the same digest, across block
    /// boundaries and for values of every size the fingerprints use.
    #[test]
    fn batched_digest_equals_the_value_by_value_one() {
        for n in [0usize, 1, 16_383, 16_384, 16_385, 50_000] {
            let (mut one, mut batched) = (Xxh3::new(), Batched::new());
            for i in 0..n {
                let v = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
                let bytes = v.to_le_bytes();
                let part = &bytes[..[4, 8, 4, 1][i % 4]];
                one.update(part);
                batched.put(part);
            }
            assert_eq!(batched.digest(), one.digest(), "{n} values");
        }
    }
}
