//! The P-LIE's own consistency check (SPEC §4): what a `.plie` file must satisfy before any query
//! reads it, and what tests check after a build.

use super::{Plie, RecordKind, CHUNKED_MIN, NO_RECORD, SCENE_CELL, UMBRA_CELL};
use crate::octree::Octree;
use crate::scene::Scene;

impl Plie {
    /// Checks the P-LIE's tables against the `scene` and `octree` it was built for: every index in
    /// range, every record filed where the index says it is, short lists in ascending order, sizes
    /// that match. Returns the first inconsistency found. Files are checked so on load.
    pub fn validate(&self, scene: &Scene, octree: &Octree) -> Result<(), String> {
        let p = self;
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
            // Records no index entry names are read too (`plie verify` samples every record): their
            // leaf and light must exist (found by the `plie_checksummed` fuzz target).
            if rec.leaf.0 as u64 >= p.leaves as u64 || rec.light.0 as u64 >= p.lights as u64 {
                return Err(format!("record {i}: leaf {} or light {} out of range", rec.leaf.0, rec.light.0));
            }
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
        // `unsigned_abs`: `i32::MIN.abs()` overflows (a panic in debug builds, and in release a
        // negative value that passed this check; found by the `plie_checksummed` fuzz target).
        let limit = 4 * super::frame::UNITS as u32;
        if p.region_tris.iter().flatten().flatten().any(|&c| c.unsigned_abs() > limit) {
            return Err("region triangle out of range".into());
        }
        Ok(())
    }
}
