//! `plie verify`: checks that a loaded P-LIE (SPEC §4) is the one plie builds for its scene, beyond
//! what the file's checksum and the structural checks on load can see (a file altered and
//! re-checksummed).
//!
//! - [`verify_full`] rebuilds the whole P-LIE with the file's parameters and limits (SPEC §4, §4.8
//!   refinement included) and compares every table; the first difference is reported by table and record.
//! - [`verify_sample`] is the quick check: for a seeded random sample of records it shoots shadow
//!   rays from points of the record's leaf to points of its light and compares the answers of every
//!   P-LIE mode (SPEC §5 modes b-d and `grid`) with brute force, the project's definition of exact.
//!   A record altered in a way that changes answers for the sampled rays is found; one that changes
//!   no sampled answer may not be: `--full` is the complete check.

use glam::Vec3;

use crate::lie::Plie;
use crate::octree::Octree;
use crate::progress::NoProgress;
use crate::scene::{Scene, TriId};
use crate::visibility::{Brute, LieVisibility, Mode, QueryCtx, ShadowRay, Visibility};

/// What a verification looked at.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Report {
    /// Records checked (all of them for [`verify_full`]).
    pub records: usize,
    /// Shadow rays compared with brute force ([`verify_sample`]; 0 for the full check).
    pub rays: usize,
}

/// Rebuilds the P-LIE of `scene` with `plie`'s parameters and limits and compares it table by
/// table. Returns the first difference as an error message.
pub fn verify_full(scene: &Scene, plie: &Plie) -> Result<Report, String> {
    let octree = Octree::build(scene, plie.params.octree()).map_err(|e| e.to_string())?;
    let built = crate::construct::build_bounded(scene, octree, plie.params, plie.limits, &NoProgress)
        .map_err(|e| e.to_string())?
        .plie;
    first_difference(&built, plie)?;
    Ok(Report { records: plie.records.len(), rays: 0 })
}

/// The first table where `stored` differs from `rebuilt`, as an error.
fn first_difference(rebuilt: &Plie, stored: &Plie) -> Result<(), String> {
    fn table<T: PartialEq>(name: &str, a: &[T], b: &[T]) -> Result<(), String> {
        if a.len() != b.len() {
            return Err(format!("{name}: {} entries stored, {} rebuilt", b.len(), a.len()));
        }
        match a.iter().zip(b).position(|(x, y)| x != y) {
            Some(i) => Err(format!("{name}: entry {i} differs from the rebuilt one")),
            None => Ok(()),
        }
    }
    if rebuilt.params != stored.params
        || rebuilt.limits != stored.limits
        || rebuilt.leaves != stored.leaves
        || rebuilt.lights != stored.lights
    {
        return Err("the header (parameters, limits, leaf or light count) differs from the rebuilt one".into());
    }
    table("octree splits", &rebuilt.splits, &stored.splits)?;
    table("record index", &rebuilt.record_index, &stored.record_index)?;
    table("records", &rebuilt.records, &stored.records)?;
    table("blockers", &rebuilt.blockers, &stored.blockers)?;
    table("regions", &rebuilt.regions, &stored.regions)?;
    table("region triangles", &rebuilt.region_tris, &stored.region_tris)?;
    table("face grids", &rebuilt.grids, &stored.grids)?;
    table("grid cells", &rebuilt.cells, &stored.cells)?;
    table("grid cell blockers", &rebuilt.cell_blockers, &stored.cell_blockers)?;
    if rebuilt != stored {
        return Err("the P-LIE differs from the rebuilt one".into());
    }
    Ok(())
}

/// Checks `records` records chosen with `seed` (all if there are fewer), `rays` shadow rays each: every
/// P-LIE mode the file supports must answer each ray as brute force does.
pub fn verify_sample(
    scene: &Scene,
    octree: &Octree,
    plie: &Plie,
    records: usize,
    rays: usize,
    seed: u64,
) -> Result<Report, String> {
    let mut rng = SplitMix(seed ^ 0x0005_eed0_f91e);
    let modes: Vec<Mode> = [Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid]
        .into_iter()
        .filter(|m| !m.needs_regions() || plie.params.has_regions())
        .filter(|m| *m != Mode::Grid || plie.params.has_grids())
        .collect();
    let bvh = crate::visibility::bvh::Bvh::build(scene);
    let lie: Vec<LieVisibility> = modes.iter().map(|&m| LieVisibility::new(scene, &bvh, octree, plie, m)).collect();
    let brute = Brute::new(scene);
    let mut ctx = QueryCtx::new(scene.triangles.len());
    let n = plie.records.len();
    let chosen: Vec<usize> = if n <= records { (0..n).collect() } else { (0..records).map(|_| rng.below(n)).collect() };
    let mut shot = 0;
    for &r in &chosen {
        let rec = &plie.records[r];
        let cell = octree.leaf_bounds(rec.leaf);
        let light = &scene.lights[rec.light.0 as usize];
        for _ in 0..rays {
            let x = cell.min + (cell.max - cell.min) * Vec3::new(rng.unit(), rng.unit(), rng.unit());
            let y = point_on_polygon(&light.vertices, &mut rng);
            let ray = ShadowRay::new(x, y, rec.light, TriId(u32::MAX), octree.locate(x));
            let truth = brute.occluded(&ray, &mut ctx);
            for (m, v) in modes.iter().zip(&lie) {
                if v.occluded(&ray, &mut ctx) != truth {
                    return Err(format!(
                        "record {r} (leaf {}, face {:?}, light {}): mode {m} answers {} for the ray from {x} to {y}, brute force {}",
                        rec.leaf.0,
                        rec.face,
                        rec.light.0,
                        word(!truth),
                        word(truth)
                    ));
                }
            }
            shot += 1;
        }
    }
    Ok(Report { records: chosen.len(), rays: shot })
}

/// "occluded" or "lit".
fn word(occluded: bool) -> &'static str {
    if occluded {
        "occluded"
    } else {
        "lit"
    }
}

/// A uniform-ish point of a convex polygon: a random fan triangle, a random point in it.
fn point_on_polygon(v: &[Vec3], rng: &mut SplitMix) -> Vec3 {
    let k = 1 + rng.below(v.len() - 2);
    let (mut a, mut b) = (rng.unit(), rng.unit());
    if a + b > 1.0 {
        (a, b) = (1.0 - a, 1.0 - b);
    }
    v[0] + (v[k] - v[0]) * a + (v[k + 1] - v[0]) * b
}

/// SplitMix64: a small seeded generator (the sample depends only on the seed).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        crate::render::sampler::mix64(self.0)
    }

    /// In `[0, n)`.
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// In `[0, 1)`.
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }
}
