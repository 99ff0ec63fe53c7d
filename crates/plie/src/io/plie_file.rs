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
//! The payload holds the build parameters, a fingerprint of the scene's geometry, materials and lights,
//! a fingerprint of the octree the P-LIE was built on, and the P-LIE. The octree itself is not stored:
//! it is a deterministic function of the scene and the parameters, and is rebuilt on load (a fraction
//! of the P-LIE's build time), then refined by replaying the P-LIE's list of split nodes (SPEC §4.8);
//! its fingerprint proves it is the same one. Every way a file can be wrong
//! (another format, another version, truncated, corrupted, another scene, other parameters, an
//! inconsistent structure) is an error, never a panic. Writes are atomic.

use std::path::Path;

use serde::{Deserialize, Serialize};
use xxhash_rust::xxh3::{xxh3_64, Xxh3};

use super::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::lie::{Plie, PlieParams, RecordKind, CHUNKED_MIN, NO_RECORD, SCENE_CELL, UMBRA_CELL};
use crate::octree::Octree;
use crate::scene::Scene;

/// First bytes of every `.plie` file.
pub const MAGIC: [u8; 8] = *b"PLIE\r\n\x1a\n";
/// Version of the layout written by this build of plie.
pub const FORMAT_VERSION: u32 = 5;
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
    let mut h = Xxh3::new();
    h.update(&(scene.triangles.len() as u64).to_le_bytes());
    for t in &scene.triangles {
        for v in &t.v {
            for c in v.to_array() {
                h.update(&c.to_le_bytes());
            }
        }
    }
    for l in &scene.tri_light {
        h.update(&l.map_or(u32::MAX, |l| l.0).to_le_bytes());
    }
    for l in &scene.lights {
        for v in &l.vertices {
            for c in v.to_array() {
                h.update(&c.to_le_bytes());
            }
        }
        for c in l.radiance.to_array() {
            h.update(&c.to_le_bytes());
        }
    }
    h.digest()
}

/// A hash of the octree's leaves: their boxes and triangle lists.
pub fn octree_fingerprint(octree: &Octree) -> u64 {
    let mut h = Xxh3::new();
    for l in octree.leaves() {
        let b = octree.leaf_bounds(l);
        for c in b.min.to_array().into_iter().chain(b.max.to_array()) {
            h.update(&c.to_le_bytes());
        }
        h.update(&(octree.leaf_triangles(l).len() as u32).to_le_bytes());
        for t in octree.leaf_triangles(l) {
            h.update(&t.0.to_le_bytes());
        }
    }
    h.digest()
}

/// Saves the P-LIE built for `scene` on `octree`, atomically. Returns the bytes written.
pub fn save_plie(path: &Path, scene: &Scene, octree: &Octree, plie: &Plie) -> Result<u64> {
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
/// P-LIE was built on. Returns the octree and the P-LIE.
pub fn load_plie(path: &Path, scene: &Scene, expect: Option<PlieParams>) -> Result<(Octree, Plie)> {
    let bytes = super::input::read_bounded(path, super::input::MAX_INPUT_BYTES)?;
    decode_plie(&bytes, path, scene, expect)
}

/// [`load_plie`] from the bytes of a `.plie` file already in memory (e.g. fetched from a distributed
/// object store), with the same checks; `origin` names the bytes in errors.
pub fn load_plie_bytes(
    bytes: &[u8],
    origin: &str,
    scene: &Scene,
    expect: Option<PlieParams>,
) -> Result<(Octree, Plie)> {
    decode_plie(bytes, Path::new(origin), scene, expect)
}

/// Checks and decodes the bytes of a `.plie` file (see [`load_plie`]); `path` names them in errors.
fn decode_plie(bytes: &[u8], path: &Path, scene: &Scene, expect: Option<PlieParams>) -> Result<(Octree, Plie)> {
    let bad = |m: String| Error::Parse { path: path.to_path_buf(), line: None, message: m };
    if bytes.len() < 8 || bytes[..8] != MAGIC {
        return Err(bad("not a .plie file (wrong magic bytes)".into()));
    }
    if bytes.len() < HEADER {
        return Err(bad("truncated .plie file (incomplete header)".into()));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(bad(format!(
            "made with .plie format version {version}; this plie reads version {FORMAT_VERSION}: rebuild it with `plie build`"
        )));
    }
    let len = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    let sum = u64::from_le_bytes(bytes[20..28].try_into().expect("8 bytes"));
    let payload = &bytes[HEADER..];
    if (payload.len() as u64) < len {
        return Err(bad(format!("truncated .plie file ({} of {len} payload bytes)", payload.len())));
    }
    if payload.len() as u64 != len {
        return Err(bad(format!("corrupted .plie file ({} bytes after the payload)", payload.len() as u64 - len)));
    }
    if xxh3_64(payload) != sum {
        return Err(bad("corrupted .plie file (checksum mismatch)".into()));
    }
    let body: FileBody =
        postcard::from_bytes(payload).map_err(|_| {
        bad("corrupted .plie file: the checksum matches but the content is not a P-LIE (written by another program or altered): rebuild it with `plie build`".into())
    })?;
    if body.scene_fingerprint != scene_fingerprint(scene) {
        return Err(bad(format!("was built for another scene, not '{}' (rebuild it with `plie build`)", scene.name)));
    }
    if let Some(p) = expect {
        if p.octree() != body.params.octree() || p.refine != body.params.refine {
            let (file, asked) = (describe_params(&body.params), describe_params(&p));
            return Err(bad(format!("was built with other parameters ({file}) than asked for ({asked})")));
        }
    }
    body.params.octree().validate().map_err(|e| bad(format!("invalid parameters in file: {e}")))?;
    body.params.refine.validate(body.params.regions).map_err(|e| bad(format!("invalid parameters in file: {e}")))?;
    let mut octree = Octree::build(scene, body.params.octree());
    for round in &body.plie.splits {
        octree = octree.split_nodes(scene, round).map_err(|e| bad(format!("inconsistent .plie file: {e}")))?;
    }
    if octree_fingerprint(&octree) != body.octree_fingerprint {
        return Err(bad("its octree differs from the one this plie builds for the scene: rebuild it".into()));
    }
    check_structure(&body.plie, scene, &octree).map_err(|m| bad(format!("inconsistent .plie file: {m}")))?;
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
        Some(crate::construct::refine::MaxBlockers::Fixed(n)) => s += &format!(" --max-blockers {n}"),
        Some(crate::construct::refine::MaxBlockers::Adaptive) => s += " --max-blockers adaptive",
        None => {}
    }
    s
}

/// Every index in range, every record where the index says it is.
fn check_structure(p: &Plie, scene: &Scene, octree: &Octree) -> std::result::Result<(), String> {
    if p.leaves as usize != octree.leaf_count() || p.lights as usize != scene.lights.len() {
        return Err(format!(
            "{} leaves and {} lights, expected {} and {}",
            p.leaves,
            p.lights,
            octree.leaf_count(),
            scene.lights.len()
        ));
    }
    if p.record_index.len() != p.leaves as usize * 6 * p.lights as usize {
        return Err("record table has the wrong size".into());
    }
    for (i, &r) in p.record_index.iter().enumerate() {
        if r == NO_RECORD {
            continue;
        }
        let rec = p.records.get(r as usize).ok_or_else(|| format!("record index {r} out of range"))?;
        let at = p.slot(rec.leaf, rec.face, rec.light);
        if at != i {
            return Err(format!("record {r} is filed under the wrong (leaf, face, light)"));
        }
    }
    for (i, rec) in p.records.iter().enumerate() {
        let end = rec.blockers_start as u64 + rec.blockers_len as u64;
        if end > p.blockers.len() as u64 {
            return Err(format!("record {i}: blocker range out of bounds"));
        }
    }
    // Short lists are promised in ascending id order (long ones in Morton order, see `CHUNKED_MIN`).
    let ascending = |l: &[crate::scene::TriId]| l.len() >= CHUNKED_MIN || l.windows(2).all(|w| w[0].0 <= w[1].0);
    if let Some(i) = p.records.iter().position(|r| !ascending(p.blockers_of(r))) {
        return Err(format!("record {i}: blocker list out of order"));
    }
    let cell_list = |&(start, len): &(u32, u32)| p.cell_blockers.get(start as usize..start as usize + len as usize);
    if p.cells.iter().filter(|&&c| c != UMBRA_CELL).any(|c| cell_list(c).is_some_and(|l| !ascending(l))) {
        return Err("grid cell blocker list out of order".into());
    }
    if let Some(t) = p.blockers.iter().chain(&p.cell_blockers).find(|t| t.idx() >= scene.triangles.len()) {
        return Err(format!("blocker triangle {} out of range", t.0));
    }
    if p.grids.len() != p.records.len() {
        return Err("grid table has the wrong size".into());
    }
    for (i, g) in p.grids.iter().enumerate() {
        if g.res > 64 || g.cells_start as u64 + (g.res as u64 * g.res as u64) > p.cells.len() as u64 {
            return Err(format!("record {i}: face grid out of bounds"));
        }
    }
    if p.records.iter().any(|r| r.kind == RecordKind::Scene && r.blockers_len != 0) {
        return Err("a record answered by the scene holds blockers".into());
    }
    if p.cells
        .iter()
        .any(|&c| c != UMBRA_CELL && c != SCENE_CELL && c.0 as u64 + c.1 as u64 > p.cell_blockers.len() as u64)
    {
        return Err("grid cell list out of bounds".into());
    }
    if p.regions.len() != p.records.len() {
        return Err("region table has the wrong size".into());
    }
    let n = p.region_tris.len() as u64;
    for (i, r) in p.regions.iter().enumerate() {
        if r.umbra_start as u64 + r.umbra_len as u64 > n || r.penumbra_start as u64 + r.penumbra_len as u64 > n {
            return Err(format!("record {i}: region triangles out of bounds"));
        }
    }
    let units = crate::construct::regions::UNITS as i32;
    if p.region_tris.iter().flatten().flatten().any(|&c| c.abs() > 4 * units) {
        return Err("region triangle out of range".into());
    }
    Ok(())
}
