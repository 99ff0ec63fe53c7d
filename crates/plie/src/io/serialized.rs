//! Mitsuba's `.serialized` meshes (issue 18): a file of one or more zlib-compressed triangle meshes.
//!
//! Each mesh: `u16` magic `0x041C`, `u16` version (3 or 4), then a zlib stream holding `u32` flags
//! (`0x0001` vertex normals, `0x0002` texture coordinates, `0x0008` vertex colours, `0x1000` single,
//! `0x2000` double precision), in version 4 a NUL-terminated name, `u64` vertex and triangle counts, the
//! positions, normals, texture coordinates and colours, and the indices (`u32`, or `u64` above 2^32
//! vertices). The file ends with the byte offset of every mesh (`u64` in version 4, `u32` in version
//! 3) and their number (`u32`). All little-endian. Counts are bounded and data is decompressed only as
//! far as it is there, so a hostile file cannot make the reader allocate without bound.

use std::io::Read;
use std::path::Path;

use flate2::read::ZlibDecoder;
use glam::{Vec2, Vec3};

use super::input::{read_bounded, MAX_INPUT_BYTES};
use super::parse_error;
use super::tri_mesh::TriMesh;
use crate::error::Result;

const MAGIC: u16 = 0x041C;
/// The most vertices or triangles of one mesh plie reads.
pub const MAX_COUNT: u64 = 1 << 28;

/// Reads mesh number `index` of the serialized file at `path`.
pub fn load_serialized(path: &Path, index: usize) -> Result<TriMesh> {
    let bytes = read_bounded(path, MAX_INPUT_BYTES)?;
    parse_serialized(&bytes, index).map_err(|m| parse_error(path, None, m))
}

/// Parses mesh number `index` of a serialized file.
pub fn parse_serialized(bytes: &[u8], index: usize) -> std::result::Result<TriMesh, String> {
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
    let mut z = ZlibDecoder::new(&bytes[start + 4..]);
    let mut r = Reader { z: &mut z };
    let flags = r.u32()?;
    if version == 4 {
        let mut n = 0;
        while r.bytes(1)?[0] != 0 {
            n += 1;
            if n > 4096 {
                return Err("the mesh name is longer than 4096 bytes".into());
            }
        }
    }
    let (nv, nt) = (r.u64()?, r.u64()?);
    if nv > MAX_COUNT || nt > MAX_COUNT {
        return Err(format!("{nv} vertices and {nt} triangles: more than the limit of {MAX_COUNT}"));
    }
    let double = flags & 0x2000 != 0;
    let real = if double { 8 } else { 4 };
    let floats = |r: &mut Reader, n: u64| -> std::result::Result<Vec<f32>, String> {
        let b = r.bytes(n as usize * real)?;
        Ok(if double {
            b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])) as f32).collect()
        } else {
            b.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap_or([0; 4]))).collect()
        })
    };
    let p = floats(&mut r, 3 * nv)?;
    let positions: Vec<Vec3> = p.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
        return Err(format!("vertex {i} is not finite"));
    }
    if flags & 0x0001 != 0 {
        floats(&mut r, 3 * nv)?;
    }
    let uvs = if flags & 0x0002 != 0 {
        let t = floats(&mut r, 2 * nv)?;
        t.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])).collect()
    } else {
        Vec::new()
    };
    if flags & 0x0008 != 0 {
        floats(&mut r, 3 * nv)?;
    }
    let wide = nv > u32::MAX as u64;
    let b = r.bytes(3 * nt as usize * if wide { 8 } else { 4 })?;
    let idx: Vec<u64> = if wide {
        b.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap_or([0; 8]))).collect()
    } else {
        b.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap_or([0; 4])) as u64).collect()
    };
    if let Some(i) = idx.iter().find(|&&i| i >= nv) {
        return Err(format!("triangle index {i} out of range: the mesh has {nv} vertices"));
    }
    if nt == 0 {
        return Err("the mesh has no triangles".into());
    }
    let triangles = idx.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32, c[2] as u32]).collect();
    Ok(TriMesh { positions, uvs, triangles })
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
struct Reader<'a, 'b> {
    z: &'a mut ZlibDecoder<&'b [u8]>,
}

impl Reader<'_, '_> {
    fn bytes(&mut self, n: usize) -> std::result::Result<Vec<u8>, String> {
        let mut v = Vec::new();
        (&mut *self.z).take(n as u64).read_to_end(&mut v).map_err(|e| format!("cannot decompress the mesh: {e}"))?;
        if v.len() < n {
            return Err("the compressed mesh data ends early".into());
        }
        Ok(v)
    }

    fn u32(&mut self) -> std::result::Result<u32, String> {
        let b = self.bytes(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self) -> std::result::Result<u64, String> {
        let b = self.bytes(8)?;
        Ok(u64::from_le_bytes(b.try_into().unwrap_or([0; 8])))
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
