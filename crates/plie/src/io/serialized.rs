//! Mitsuba's `.serialized` meshes (issue 18): a file of one or more zlib-compressed triangle meshes.
//!
//! Each mesh: `u16` magic `0x041C`, `u16` version (3 or 4), then a zlib stream holding `u32` flags
//! (`0x0001` vertex normals, `0x0002` texture coordinates, `0x0008` vertex colours, `0x1000` single,
//! `0x2000` double precision), in version 4 a NUL-terminated name, `u64` vertex and triangle counts, the
//! positions, normals, texture coordinates and colours, and the indices (`u32`, or `u64` above 2^32
//! vertices, which is over plie's limit). The file ends with the byte offset of every mesh (`u64` in
//! version 4, `u32` in version 3) and their number (`u32`). All little-endian.
//!
//! A zlib stream expands up to about 1,000 times, so a small file can declare and hold a huge mesh
//! (a 195 KB file of 2^24 triangles, a 3 MB file of 2^28). The counts are checked against the limits
//! ([`Limits`]: by default the Mitsuba scene's [`MAX_TRIANGLES`] and three vertices a triangle) as
//! soon as they are read, before anything is allocated or decompressed; the data is then decompressed
//! a chunk at a time into arrays that grow only as far as the data is there (with `try_reserve`, so a
//! failed allocation is an error, not an abort). Memory stays proportional to what the limits allow:
//! at most about 12 bytes a vertex (20 with texture coordinates) and 12 a triangle, plus one chunk.

use std::io::Read;
use std::path::Path;

use flate2::read::ZlibDecoder;
use glam::{Vec2, Vec3};

use super::input::{read_bounded, MAX_INPUT_BYTES};
use super::mitsuba::MAX_TRIANGLES;
use super::parse_error;
use super::tri_mesh::TriMesh;
use crate::error::Result;

const MAGIC: u16 = 0x041C;
/// The most bytes decompressed at a time.
const CHUNK_BYTES: usize = 1 << 20;

/// The most vertices and triangles a mesh may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// The most vertices.
    pub vertices: u64,
    /// The most triangles.
    pub triangles: u64,
}

impl Default for Limits {
    /// A Mitsuba scene's whole budget: [`MAX_TRIANGLES`] triangles and three times as many vertices
    /// (more vertices than three a triangle cannot all be used).
    fn default() -> Self {
        Limits { vertices: 3 * MAX_TRIANGLES as u64, triangles: MAX_TRIANGLES as u64 }
    }
}

/// Reads mesh number `index` of the serialized file at `path`, within the default [`Limits`].
pub fn load_serialized(path: &Path, index: usize) -> Result<TriMesh> {
    load_serialized_within(path, index, Limits::default())
}

/// [`load_serialized`] within `limits` (what a scene has left of its budget).
pub fn load_serialized_within(path: &Path, index: usize, limits: Limits) -> Result<TriMesh> {
    let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
    parse_serialized_within(&bytes, index, limits).map_err(|m| parse_error(path, None, m))
}

/// Parses mesh number `index` of a serialized file, within the default [`Limits`].
pub fn parse_serialized(bytes: &[u8], index: usize) -> std::result::Result<TriMesh, String> {
    parse_serialized_within(bytes, index, Limits::default())
}

/// [`parse_serialized`] within `limits`.
pub fn parse_serialized_within(bytes: &[u8], index: usize, limits: Limits) -> std::result::Result<TriMesh, String> {
    let start = if index == 0 { 0 } else { offset(bytes, index)? };
    let head = bytes.get(start..start + 4).ok_or("the file is too short for a mesh header")?;
    let magic = u16::from_le_bytes([head[0], head[1]]);
    let version = u16::from_le_bytes([head[2], head[3]]);
    if magic != MAGIC {
        return Err(format!("not a serialized mesh: magic {magic:#06x}, expected {MAGIC:#06x}"));
    }
    if version != 3 && version != 4 {
        return Err(format!("serialized format version {version} is not supported (3 and 4 are)"));
    }
    let mut r = Reader { z: ZlibDecoder::new(&bytes[start + 4..]) };
    let flags = r.u32()?;
    if version == 4 {
        let mut n = 0;
        while r.u8()? != 0 {
            n += 1;
            if n > 4096 {
                return Err("the mesh name is longer than 4096 bytes".into());
            }
        }
    }
    let (nv, nt) = (r.u64()?, r.u64()?);
    // Before anything is allocated or decompressed.
    if nt > limits.triangles {
        return Err(format!(
            "the mesh declares {nt} triangles: more than the {} plie reads (a scene holds at most {MAX_TRIANGLES})",
            limits.triangles
        ));
    }
    if nv > limits.vertices {
        return Err(format!(
            "the mesh declares {nv} vertices: more than the {} plie reads (three a triangle of {MAX_TRIANGLES})",
            limits.vertices
        ));
    }
    if nt == 0 {
        return Err("the mesh has no triangles".into());
    }
    // Both fit in `usize` and `u32` now (the limits are far below 2^32), so indices are `u32`.
    let (nv, nt) = (usize::try_from(nv).map_err(|_| "too many vertices")?, nt as usize);
    if nv > u32::MAX as usize {
        return Err(format!("{nv} vertices: more than 2^32 are not supported"));
    }
    let double = flags & 0x2000 != 0;
    let real = if double { 8 } else { 4 };
    let decode = |b: &[u8]| -> f32 {
        if double {
            f64::from_le_bytes(b.try_into().unwrap_or([0; 8])) as f32
        } else {
            f32::from_le_bytes(b.try_into().unwrap_or([0; 4]))
        }
    };
    let mut positions: Vec<Vec3> = Vec::new();
    r.records(nv, 3 * real, |b| {
        let v = Vec3::new(decode(&b[..real]), decode(&b[real..2 * real]), decode(&b[2 * real..]));
        if !v.is_finite() {
            return Err(format!("vertex {} is not finite", positions.len()));
        }
        push(&mut positions, v, nv)
    })?;
    if flags & 0x0001 != 0 {
        r.records(nv, 3 * real, |_| Ok(()))?;
    }
    let mut uvs: Vec<Vec2> = Vec::new();
    if flags & 0x0002 != 0 {
        r.records(nv, 2 * real, |b| push(&mut uvs, Vec2::new(decode(&b[..real]), decode(&b[real..])), nv))?;
    }
    if flags & 0x0008 != 0 {
        r.records(nv, 3 * real, |_| Ok(()))?;
    }
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    r.records(nt, 12, |b| {
        let t = [0, 4, 8].map(|o| u32::from_le_bytes(b[o..o + 4].try_into().unwrap_or([0; 4])));
        if let Some(i) = t.iter().find(|&&i| i as usize >= nv) {
            return Err(format!("triangle index {i} out of range: the mesh has {nv} vertices"));
        }
        push(&mut triangles, t, nt)
    })?;
    Ok(TriMesh { positions, uvs, triangles })
}

/// Pushes `x` onto `v`, one of at most `n` (declared) elements: when full, `v` doubles, but never
/// past `n`, and with `try_reserve_exact`, so an allocation that fails is an error, not an abort.
fn push<T>(v: &mut Vec<T>, x: T, n: usize) -> std::result::Result<(), String> {
    if v.len() == v.capacity() {
        let more = v.len().max(1024).min(n.saturating_sub(v.len())).max(1);
        v.try_reserve_exact(more).map_err(|e| format!("cannot allocate memory for the mesh: {e}"))?;
    }
    v.push(x);
    Ok(())
}

/// The byte offset of mesh `index` from the table at the end of the file.
fn offset(bytes: &[u8], index: usize) -> std::result::Result<usize, String> {
    let n = bytes.len();
    let count_at = n.checked_sub(4).ok_or("the file is too short")?;
    let count = u32::from_le_bytes(bytes[count_at..].try_into().unwrap_or([0; 4])) as usize;
    if index >= count {
        return Err(format!("shape_index {index}, but the file holds {count} meshes"));
    }
    let version = bytes.get(2..4).map(|b| u16::from_le_bytes([b[0], b[1]])).unwrap_or(0);
    let width = if version == 3 { 4 } else { 8 };
    let table = count_at.checked_sub(count * width).ok_or("the mesh table is longer than the file")?;
    let at = table + index * width;
    let o = if width == 4 {
        u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap_or([0; 4])) as u64
    } else {
        u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap_or([0; 8]))
    };
    usize::try_from(o)
        .ok()
        .filter(|&o| o < table)
        .ok_or_else(|| format!("mesh {index} starts at {o}, outside the file"))
}

/// Reads from the decompressed stream, only as much as is there.
struct Reader<'b> {
    z: ZlibDecoder<&'b [u8]>,
}

impl Reader<'_> {
    /// Fills `buf` from the stream.
    fn fill(&mut self, buf: &mut [u8]) -> std::result::Result<(), String> {
        self.z.read_exact(buf).map_err(|e| match e.kind() {
            std::io::ErrorKind::UnexpectedEof => "the compressed mesh data ends early".to_string(),
            _ => format!("cannot decompress the mesh: {e}"),
        })
    }

    /// Reads `n` records of `size` bytes, passing each to `each`, at most [`CHUNK_BYTES`] at a time.
    fn records(
        &mut self,
        n: usize,
        size: usize,
        mut each: impl FnMut(&[u8]) -> std::result::Result<(), String>,
    ) -> std::result::Result<(), String> {
        let per_chunk = (CHUNK_BYTES / size).max(1);
        let mut buf = vec![0; n.min(per_chunk) * size];
        let mut left = n;
        while left > 0 {
            let k = left.min(per_chunk);
            let b = &mut buf[..k * size];
            self.fill(b)?;
            for record in b.chunks_exact(size) {
                each(record)?;
            }
            left -= k;
        }
        Ok(())
    }

    fn u8(&mut self) -> std::result::Result<u8, String> {
        let mut b = [0; 1];
        self.fill(&mut b)?;
        Ok(b[0])
    }

    fn u32(&mut self) -> std::result::Result<u32, String> {
        let mut b = [0; 4];
        self.fill(&mut b)?;
        Ok(u32::from_le_bytes(b))
    }

    fn u64(&mut self) -> std::result::Result<u64, String> {
        let mut b = [0; 8];
        self.fill(&mut b)?;
        Ok(u64::from_le_bytes(b))
    }
}

/// Writes meshes as a version-4 serialized file (for tests and tools): positions, texture coordinates
/// when given, indices; single precision.
pub fn write_serialized(meshes: &[TriMesh]) -> Vec<u8> {
    use flate2::write::ZlibEncoder;
    use std::io::Write;
    let mut out = Vec::new();
    let mut offsets = Vec::new();
    for m in meshes {
        offsets.push(out.len() as u64);
        out.extend(MAGIC.to_le_bytes());
        out.extend(4u16.to_le_bytes());
        let mut raw = Vec::new();
        let flags: u32 = 0x1000 | if m.uvs.is_empty() { 0 } else { 0x0002 };
        raw.extend(flags.to_le_bytes());
        raw.extend(b"mesh\0");
        raw.extend((m.positions.len() as u64).to_le_bytes());
        raw.extend((m.triangles.len() as u64).to_le_bytes());
        for p in &m.positions {
            for c in p.to_array() {
                raw.extend(c.to_le_bytes());
            }
        }
        for t in &m.uvs {
            for c in t.to_array() {
                raw.extend(c.to_le_bytes());
            }
        }
        for t in &m.triangles {
            for i in t {
                raw.extend(i.to_le_bytes());
            }
        }
        let mut e = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        let _ = e.write_all(&raw);
        out.extend(e.finish().unwrap_or_default());
    }
    for o in &offsets {
        out.extend(o.to_le_bytes());
    }
    out.extend((meshes.len() as u32).to_le_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(z: f32) -> TriMesh {
        TriMesh {
            positions: vec![Vec3::new(0.0, 0.0, z), Vec3::X, Vec3::Y],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
            triangles: vec![[0, 1, 2]],
        }
    }

    #[test]
    fn round_trip_and_shape_index() {
        let file = write_serialized(&[tri(0.0), tri(5.0)]);
        assert_eq!(parse_serialized(&file, 0).unwrap(), tri(0.0));
        assert_eq!(parse_serialized(&file, 1).unwrap(), tri(5.0));
        assert!(parse_serialized(&file, 2).unwrap_err().contains("holds 2 meshes"));
    }

    #[test]
    fn hostile_files_are_errors() {
        let file = write_serialized(&[tri(0.0)]);
        for cut in [0, 3, 10, file.len() / 2] {
            assert!(parse_serialized(&file[..cut], 0).is_err(), "cut at {cut}");
        }
        let mut bad = file.clone();
        bad[0] = 0;
        assert!(parse_serialized(&bad, 0).unwrap_err().contains("magic"));
        let mut big = tri(0.0);
        big.triangles[0][2] = 7;
        assert!(parse_serialized(&write_serialized(&[big]), 0).unwrap_err().contains("out of range"));
    }
}
