//! `plie build --memory-budget` (issue 15): the memory budget of the P-LIE construction, its default
//! (a safe fraction of the machine's memory), and the peak memory the build reports (VmHWM).
//!
//! The library takes a budget for the blocker lists alone ([`plie::BuildOptions::list_bytes`]); the rest of a
//! build (scene, octree, BVH-free construction scratch, region triangles) is estimated per triangle
//! here, and the lists get half of what remains, because flattening them into the P-LIE's arrays
//! briefly holds a second copy.

use anyhow::{bail, Result};
use plie::BuildStats;
use plie::Scene;

use crate::progress::Bar;

/// Bytes assumed for everything but the blocker lists: a fixed part...
const BASE_BYTES: u64 = 256 << 20;
/// ...and a part per triangle (scene, octree, per-thread gather stamps, regions).
const BYTES_PER_TRIANGLE: u64 = 1024;
/// Fraction of the machine's memory used when no budget is given.
const DEFAULT_FRACTION: f64 = 0.5;
/// Budget when the machine's memory cannot be read.
const FALLBACK_BYTES: u64 = 4 << 30;

/// Parses `4G`, `512M`, `1.5G`, `800K` or a number of bytes (powers of 1024).
pub fn parse_bytes(s: &str) -> std::result::Result<u64, String> {
    let t = s.trim();
    let (num, mul) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let m: u64 = match c.to_ascii_uppercase() {
                'K' => 1 << 10,
                'M' => 1 << 20,
                'G' => 1 << 30,
                'T' => 1 << 40,
                _ => return Err(format!("unknown unit in `{s}`: use K, M, G or T")),
            };
            (&t[..i], m)
        }
        _ => (t, 1),
    };
    let v: f64 = num.parse().map_err(|_| format!("expected a size such as 4G or 512M, not `{s}`"))?;
    if !v.is_finite() || v <= 0.0 || v * mul as f64 > u64::MAX as f64 / 2.0 {
        return Err(format!("the memory budget must be a positive size, not `{s}`"));
    }
    Ok((v * mul as f64) as u64)
}

/// The default budget: half the machine's memory (`MemTotal` of /proc/meminfo), else 4 GiB.
pub fn default_bytes() -> u64 {
    meminfo_kb("MemTotal:").map_or(FALLBACK_BYTES, |kb| (kb as f64 * 1024.0 * DEFAULT_FRACTION) as u64)
}

/// The bytes the blocker lists may take within `budget` for `scene`.
pub fn list_bytes(budget: u64, scene: &Scene) -> usize {
    let rest = BASE_BYTES + BYTES_PER_TRIANGLE * scene.triangles.len() as u64;
    (budget.saturating_sub(rest) / 2).min(usize::MAX as u64) as usize
}

/// Refuses a budget too small for the scene itself.
pub fn check(budget: u64, scene: &Scene) -> Result<()> {
    if list_bytes(budget, scene) == 0 {
        let need = BASE_BYTES + BYTES_PER_TRIANGLE * scene.triangles.len() as u64;
        bail!("--memory-budget {budget} bytes is below what the scene alone needs (about {need} bytes)");
    }
    Ok(())
}

/// Says (unless quiet) how many records the budget turned into scene records.
pub fn warn_over(stats: &BuildStats, bar: &Bar) {
    if stats.bounded.records_over_budget > 0 {
        bar.warn(&format!(
            "memory budget reached: {} records store no blocker list and are answered by the scene BVH (exact, slower to shade); raise --memory-budget to keep them",
            stats.bounded.records_over_budget
        ));
    }
}

/// Peak resident memory of this process so far (`VmHWM`), in bytes, where the system tells it.
pub fn peak_bytes() -> Option<u64> {
    status_kb("VmHWM:").map(|kb| kb * 1024)
}

fn meminfo_kb(key: &str) -> Option<u64> {
    kb_field(&std::fs::read_to_string("/proc/meminfo").ok()?, key)
}

fn status_kb(key: &str) -> Option<u64> {
    kb_field(&std::fs::read_to_string("/proc/self/status").ok()?, key)
}

/// The value in kB of the line starting with `key` in a /proc file.
fn kb_field(text: &str, key: &str) -> Option<u64> {
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_with_units_and_bad_ones_are_refused() {
        assert_eq!(parse_bytes("4G"), Ok(4 << 30));
        assert_eq!(parse_bytes("512m"), Ok(512 << 20));
        assert_eq!(parse_bytes("1.5G"), Ok(3 << 29));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        for bad in ["", "G", "-1G", "0", "4X", "nanG", "1e30T"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn kb_fields_are_read() {
        assert_eq!(kb_field("VmPeak:\t  10 kB\nVmHWM:\t  1234 kB\n", "VmHWM:"), Some(1234));
        assert_eq!(kb_field("VmPeak: 10 kB\n", "VmHWM:"), None);
    }
}
