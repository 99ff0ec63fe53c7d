//! The degenerate triangles a [`super::SceneBuilder`] drops as they are added. The builder stores only
//! the triangles it keeps, yet its ids ([`super::TriId`]) count every triangle in the order it was
//! given: loaders name lights by those ids, and messages name triangles by them. [`Dropped`] keeps
//! which ids were dropped, as runs of consecutive ids (a file of degenerate triangles is one run),
//! and maps an id to where its triangle is stored and back.

use super::MaterialId;

/// The dropped ids `start..end`, which come after `kept_before` kept triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Run {
    start: u32,
    end: u32,
    kept_before: u32,
}

/// The ids of the dropped triangles, and enough of their materials to report one that does not exist.
#[derive(Clone, Debug, Default)]
pub(super) struct Dropped {
    /// Ascending, separated by at least one kept id.
    runs: Vec<Run>,
    /// How many ids were dropped.
    count: u32,
    /// Every dropped triangle whose material index is above those of all earlier dropped triangles,
    /// with its id: the first dropped triangle whose material does not exist is among them.
    material_records: Vec<(u32, MaterialId)>,
}

impl Dropped {
    /// Records that triangle `id`, with material `m`, was dropped. Every id below `id` was either kept
    /// or recorded before.
    pub(super) fn push(&mut self, id: u32, m: MaterialId) {
        match self.runs.last_mut() {
            Some(r) if r.end == id => r.end += 1,
            _ => self.runs.push(Run { start: id, end: id + 1, kept_before: id - self.count }),
        }
        self.count += 1;
        if self.material_records.last().is_none_or(|&(_, top)| m > top) {
            self.material_records.push((id, m));
        }
    }

    /// How many triangles were dropped.
    pub(super) fn count(&self) -> usize {
        self.count as usize
    }

    /// Where triangle `id` (one given to the builder) is stored, or `None` if it was dropped.
    pub(super) fn stored(&self, id: u32) -> Option<u32> {
        match self.runs.partition_point(|r| r.start <= id).checked_sub(1).map(|i| self.runs[i]) {
            None => Some(id),
            Some(r) if id < r.end => None,
            Some(r) => Some(r.kept_before + (id - r.end)),
        }
    }

    /// The id the builder gave the triangle stored at `stored`.
    pub(super) fn given(&self, stored: u32) -> u32 {
        match self.runs.partition_point(|r| r.kept_before <= stored).checked_sub(1).map(|i| self.runs[i]) {
            None => stored,
            Some(r) => r.end + (stored - r.kept_before),
        }
    }

    /// The first dropped triangle whose material index is not below `materials`: its id and material.
    pub(super) fn first_missing_material(&self, materials: usize) -> Option<(u32, MaterialId)> {
        self.material_records.iter().copied().find(|(_, m)| m.idx() >= materials)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_map_to_stored_indices_and_back() {
        // Given ids 0..12; dropped: 0, 1, 4, 5, 6, 9, 11.
        let drop = [0, 1, 4, 5, 6, 9, 11];
        let mut d = Dropped::default();
        for id in drop {
            d.push(id, MaterialId(0));
        }
        assert_eq!(d.runs.len(), 4, "consecutive ids make one run");
        assert_eq!(d.count(), drop.len());
        let kept: Vec<u32> = (0..12).filter(|i| !drop.contains(i)).collect();
        for id in 0..12 {
            assert_eq!(d.stored(id), kept.iter().position(|&k| k == id).map(|s| s as u32), "id {id}");
        }
        for (s, &id) in kept.iter().enumerate() {
            assert_eq!(d.given(s as u32), id, "stored {s}");
        }
        // Ids after the last one given are kept ones still to come.
        assert_eq!(d.stored(12), Some(5));
        assert_eq!(d.given(5), 12);
    }

    #[test]
    fn nothing_dropped_is_the_identity() {
        let d = Dropped::default();
        assert_eq!((d.stored(7), d.given(7), d.count()), (Some(7), 7, 0));
        assert_eq!(d.first_missing_material(0), None);
    }

    #[test]
    fn the_first_dropped_triangle_with_a_missing_material_is_found() {
        let mut d = Dropped::default();
        for (id, m) in [(0, 2), (3, 1), (4, 5), (8, 3), (9, 7), (10, 6)] {
            d.push(id, MaterialId(m));
        }
        assert_eq!(d.material_records, [(0, MaterialId(2)), (4, MaterialId(5)), (9, MaterialId(7))]);
        for (materials, first) in [
            (0, Some((0, 2))),
            (2, Some((0, 2))),
            (3, Some((4, 5))),
            (5, Some((4, 5))),
            (6, Some((9, 7))),
            (7, Some((9, 7))),
            (8, None),
        ] {
            assert_eq!(d.first_missing_material(materials), first.map(|(id, m)| (id, MaterialId(m))), "{materials}");
        }
    }
}
