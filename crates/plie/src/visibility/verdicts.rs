//! When a light's footprints are not worth finding (issue 21): per thread, the (leaf, light)
//! pairs whose footprints ([`super::lie`]'s whole-light verdict, SPEC §5) decided nothing the last
//! [`STREAK`] times they were found. A render asks a leaf's lights point after point, and a pair's
//! verdict is nearly always decided or nearly never: for the latter the footprints are work thrown
//! away before the walk. Such a pair skips them but on every [`PROBE`]-th query, which finds them
//! again (and ends the streak where they decide). Skipping changes no answer: an undecided light
//! goes to its shaft or the scene BVH, which answer exactly; only the work depends on the order of
//! the queries.

use crate::octree::LeafId;
use crate::scene::LightId;

/// Undecided verdicts in a row after which a pair skips its footprints. Measured (callgrind inside
/// `occluded_light`, 254x254, 16 rays, `penumbra`, sums over conference-lit, huis-c,
/// cornell-dragon-100k and cornell-bunny, docs/results.md issue 21 session 27): 2, 4, 8 and 16
/// (with [`PROBE`] 64) took 1,541.96, 1,545.47, 1,551.07 and 1,559.25 M instructions, against
/// 1,708.46 M without skipping; 4 loses fewer decided verdicts than 2 for 0.2%.
const STREAK: u16 = 4;

/// A skipping pair finds its footprints on every this-many-th query. Measured as [`STREAK`] (with
/// 4): 64, 128 and 256 took 1,545.47, 1,543.81 and 1,543.08 M (with 8: 32 and 64 took 1,554.01 and
/// 1,551.07 M).
const PROBE: u16 = 64;

/// Pairs remembered (direct-mapped by a hash; a pair whose slot another took starts afresh): 48
/// KiB a thread. Measured as [`STREAK`]: 256, 1024, 4096 and 16384 slots took 1,561.26, 1,549.67,
/// 1,543.21 and 1,544.26 M.
const SLOTS: usize = 4096;

/// What one slot remembers of its pair.
#[derive(Clone, Copy, Debug)]
struct Slot {
    /// The pair (`leaf` `u32::MAX`: an empty slot).
    leaf: u32,
    light: u32,
    /// Queries of the pair since it took the slot.
    asked: u16,
    /// Undecided verdicts in a row.
    undecided: u16,
}

/// One thread's memory of which pairs' footprints decided nothing lately.
#[derive(Clone, Debug, Default)]
pub(crate) struct Verdicts {
    slots: Vec<Slot>,
}

impl Verdicts {
    /// A query of `light` from a point of `leaf`: `Some(slot)` if its footprints are to be found
    /// (then tell [`Verdicts::found`] whether they decided), `None` to skip them.
    #[inline]
    pub(crate) fn ask(&mut self, leaf: LeafId, light: LightId) -> Option<usize> {
        if self.slots.is_empty() {
            self.slots = vec![Slot { leaf: u32::MAX, light: 0, asked: 0, undecided: 0 }; SLOTS];
        }
        let hash = (leaf.0.wrapping_mul(0x9E37_79B1) ^ light.0.wrapping_mul(0x85EB_CA77)).wrapping_mul(0x9E37_79B1);
        let i = (hash >> (32 - SLOTS.trailing_zeros())) as usize;
        let s = &mut self.slots[i];
        if (s.leaf, s.light) != (leaf.0, light.0) {
            *s = Slot { leaf: leaf.0, light: light.0, asked: 0, undecided: 0 };
        }
        s.asked = s.asked.wrapping_add(1);
        (s.undecided < STREAK || s.asked % PROBE == 0).then_some(i)
    }

    /// Whether the footprints found for the query that [`Verdicts::ask`] gave `slot` decided.
    #[inline]
    pub(crate) fn found(&mut self, slot: usize, decided: bool) {
        let s = &mut self.slots[slot];
        s.undecided = if decided { 0 } else { s.undecided.saturating_add(1) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pair is skipped after `STREAK` undecided verdicts in a row, but for every `PROBE`-th
    /// query; a decided probe ends the skipping; other pairs keep their own counts.
    #[test]
    fn skips_after_a_streak_and_probes() {
        let mut v = Verdicts::default();
        let (a, b, l) = (LeafId(3), LeafId(4), LightId(1));
        for _ in 0..STREAK {
            let slot = v.ask(a, l).expect("found before the streak");
            v.found(slot, false);
        }
        // Skipped now, up to the probe.
        let mut asked = STREAK;
        while (asked + 1) % PROBE != 0 {
            assert!(v.ask(a, l).is_none(), "query {} skipped", asked + 1);
            asked += 1;
        }
        // Another pair is not.
        let slot = v.ask(b, l).expect("another pair finds its footprints");
        v.found(slot, true);
        // The probe finds them, and they decide: the streak ends.
        let slot = v.ask(a, l).expect("the probe finds them");
        v.found(slot, true);
        assert!(v.ask(a, l).is_some(), "found again after a decided probe");
    }
}
