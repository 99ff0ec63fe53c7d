//! How a P-LIE mode answered a shadow ray (SPEC §5, issue 4's `--stats`): which test decided it. Every
//! shadow ray a P-LIE mode answers takes exactly one path, so the [`Answers`] counters sum to the
//! number of rays; every path but [`Answer::OutsideOctree`] also fixes the answer. Modes that do not
//! use a P-LIE leave the counters at zero.

use serde::Serialize;

/// The test that decided a shadow ray in a P-LIE mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Answer {
    /// The segment leaves its leaf through a face with no record for the light: occluded, no test.
    NoRecord,
    /// The segment crosses the face inside the record's umbra: occluded, no test.
    Umbra,
    /// The segment crosses the face where no blocker can be (the record's or the grid cell's blocker
    /// list is empty, or a lit region): blockers skipped, and the leaf's own triangles missed.
    Lit,
    /// A blocker of the record (or of its grid cell) hit: occluded.
    BlockersHit,
    /// Blockers tested, none hit, and the leaf's own triangles missed: visible.
    BlockersMiss,
    /// A triangle of the ray's own leaf hit (after [`Answer::Lit`], [`Answer::BlockersMiss`] or
    /// [`Answer::InsideLeaf`] would have let the ray through): occluded.
    OwnLeaf,
    /// The segment never leaves its leaf, and the leaf's own triangles missed: visible.
    InsideLeaf,
    /// The start point lies in no leaf: answered by walking the octree (mode a), either way.
    OutsideOctree,
    /// The whole segment answered by the scene BVH, either way: it leaves its leaf through a face
    /// whose record stores no list ([`crate::lie::RecordKind::Scene`]: more blockers than the cap,
    /// or over the memory budget), and not inside its umbra; or, in the per-light query, its light's
    /// footprints were neither all umbra, all lit, nor over short lists only.
    SceneBvh,
}

impl Answer {
    /// Every path, in the order `--stats` prints them.
    pub const ALL: [Answer; 9] = [
        Answer::NoRecord,
        Answer::Umbra,
        Answer::Lit,
        Answer::BlockersHit,
        Answer::BlockersMiss,
        Answer::OwnLeaf,
        Answer::InsideLeaf,
        Answer::OutsideOctree,
        Answer::SceneBvh,
    ];

    /// The name of the path: its [`Answers`] field and JSON key.
    pub fn name(self) -> &'static str {
        match self {
            Answer::NoRecord => "no_record",
            Answer::Umbra => "umbra",
            Answer::Lit => "lit",
            Answer::BlockersHit => "blockers_hit",
            Answer::BlockersMiss => "blockers_miss",
            Answer::OwnLeaf => "own_leaf",
            Answer::InsideLeaf => "inside_leaf",
            Answer::OutsideOctree => "outside_octree",
            Answer::SceneBvh => "scene_bvh",
        }
    }

    /// The answer this path gives: `Some(true)` occluded, `Some(false)` visible, `None` either.
    pub fn occluded(self) -> Option<bool> {
        match self {
            Answer::NoRecord | Answer::Umbra | Answer::BlockersHit | Answer::OwnLeaf => Some(true),
            Answer::Lit | Answer::BlockersMiss | Answer::InsideLeaf => Some(false),
            Answer::OutsideOctree | Answer::SceneBvh => None,
        }
    }
}

/// Shadow rays per [`Answer`] path; the fields are named as [`Answer::name`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Answers {
    /// See [`Answer::NoRecord`].
    pub no_record: u64,
    /// See [`Answer::Umbra`].
    pub umbra: u64,
    /// See [`Answer::Lit`].
    pub lit: u64,
    /// See [`Answer::BlockersHit`].
    pub blockers_hit: u64,
    /// See [`Answer::BlockersMiss`].
    pub blockers_miss: u64,
    /// See [`Answer::OwnLeaf`].
    pub own_leaf: u64,
    /// See [`Answer::InsideLeaf`].
    pub inside_leaf: u64,
    /// See [`Answer::OutsideOctree`].
    pub outside_octree: u64,
    /// See [`Answer::SceneBvh`].
    pub scene_bvh: u64,
}

impl Answers {
    /// The counter of path `a`.
    #[inline]
    pub fn get_mut(&mut self, a: Answer) -> &mut u64 {
        match a {
            Answer::NoRecord => &mut self.no_record,
            Answer::Umbra => &mut self.umbra,
            Answer::Lit => &mut self.lit,
            Answer::BlockersHit => &mut self.blockers_hit,
            Answer::BlockersMiss => &mut self.blockers_miss,
            Answer::OwnLeaf => &mut self.own_leaf,
            Answer::InsideLeaf => &mut self.inside_leaf,
            Answer::OutsideOctree => &mut self.outside_octree,
            Answer::SceneBvh => &mut self.scene_bvh,
        }
    }

    /// Rays that took path `a`.
    pub fn get(mut self, a: Answer) -> u64 {
        *self.get_mut(a)
    }

    /// Counts one ray on path `a`.
    #[inline]
    pub fn count(&mut self, a: Answer) {
        *self.get_mut(a) += 1;
    }

    /// Counts `n` rays on path `a`.
    #[inline]
    pub fn count_n(&mut self, a: Answer, n: usize) {
        *self.get_mut(a) += n as u64;
    }

    /// Rays counted on any path.
    pub fn total(self) -> u64 {
        Answer::ALL.iter().map(|&a| self.get(a)).sum()
    }
}

impl std::ops::AddAssign for Answers {
    fn add_assign(&mut self, o: Answers) {
        for a in Answer::ALL {
            *self.get_mut(a) += o.get(a);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_match_the_serialized_fields_and_counts_add_up() {
        let mut a = Answers::default();
        for (i, &p) in Answer::ALL.iter().enumerate() {
            for _ in 0..=i {
                a.count(p);
            }
        }
        let v = serde_json::to_value(a).unwrap();
        for (i, &p) in Answer::ALL.iter().enumerate() {
            assert_eq!(a.get(p), i as u64 + 1);
            assert_eq!(v[p.name()], i as u64 + 1, "field {}", p.name());
        }
        assert_eq!(v.as_object().unwrap().len(), Answer::ALL.len());
        let mut b = a;
        b += a;
        assert_eq!(b.total(), 2 * a.total());
        assert_eq!(a.total(), 45);
    }
}
