//! The files of `plie bench`: report.md (our figures beside the thesis' Tables 8.1-8.4 and A.1-A.4),
//! results.csv, results.json and the chart shading.svg ([`crate::bench_chart`]). Every file is written
//! atomically.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use plie::visibility::Mode;

use crate::bench_data::{seconds_of, Plan, Results};
use crate::out_dir::OutDir;

/// The thesis' figures (shared/thesis/*.tsv).
#[derive(Default)]
pub struct Thesis {
    /// (scene, config) -> (seconds, leaves).
    construction: HashMap<(String, String), (f64, String)>,
    /// (scene, method, shadow rays, umbra data, eye rays, refined) -> seconds.
    shading: HashMap<(String, String, u32, String, u32, String), f64>,
}

impl Thesis {
    /// Reads `dir/construction.tsv` and `dir/shading-times.tsv`.
    fn load(dir: &Path) -> Result<Thesis> {
        let mut t = Thesis::default();
        for row in tsv(&dir.join("construction.tsv"))? {
            if let [scene, _, _, config, secs, leaves, ..] = row.as_slice() {
                let secs: f64 = secs.parse().with_context(|| format!("bad seconds '{secs}'"))?;
                t.construction.insert((scene.clone(), config.clone()), (secs, leaves.clone()));
            }
        }
        for row in tsv(&dir.join("shading-times.tsv"))? {
            if let [scene, method, rays, umbra, eye, refined, secs] = row.as_slice() {
                let key = (scene.clone(), method.clone(), rays.parse()?, umbra.clone(), eye.parse()?, refined.clone());
                t.shading.insert(key, secs.parse().with_context(|| format!("bad seconds '{secs}'"))?);
            }
        }
        Ok(t)
    }

    /// Test-1 shading seconds (umbra data built, not refined: the data of Table 8.1).
    fn shading(&self, scene: &str, method: &str, size: u32, rays: u32) -> Option<f64> {
        self.shading_of(scene, method, size, rays, false)
    }

    /// Shading seconds with umbra data, refined (test 2, the "+ u" columns) or not (test 1).
    fn shading_of(&self, scene: &str, method: &str, size: u32, rays: u32, refined: bool) -> Option<f64> {
        let refined = if refined { "yes" } else { "no" }.to_string();
        let key = (thesis_name(scene), method.to_string(), rays, "yes".to_string(), size, refined);
        self.shading.get(&key).copied()
    }

    fn construction(&self, scene: &str, config: &str) -> Option<&(f64, String)> {
        self.construction.get(&(thesis_name(scene), config.to_string()))
    }
}

fn tsv(path: &Path) -> Result<Vec<Vec<String>>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let rows = text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    Ok(rows.map(|l| l.split('\t').map(|s| s.trim().to_string()).collect()).collect())
}

/// The thesis' name of a built-in scene: "cornell-cube-1" -> "Cornell Cube 1".
fn thesis_name(scene: &str) -> String {
    let words = scene.split('-').map(|w| {
        let mut c = w.chars();
        c.next().map(|f| f.to_uppercase().chain(c).collect::<String>()).unwrap_or_default()
    });
    words.collect::<Vec<_>>().join(" ")
}

/// Writes report.md, results.csv, results.json and shading.svg into `out`.
pub fn write_all(out: &mut OutDir, thesis_dir: &Path, plan: &Plan, r: &Results) -> Result<()> {
    let thesis = Thesis::load(thesis_dir);
    let report = markdown(plan, r, thesis_dir, thesis.as_ref().map_err(|e| format!("{e:#}")));
    let json = serde_json::to_string_pretty(r)? + "\n";
    let svg = crate::bench_chart::svg(plan, r)?;
    out.write("report.md", &report)?;
    out.write("results.csv", &csv(r))?;
    out.write("results.json", &json)?;
    out.write("shading.svg", &svg)?;
    Ok(())
}

/// One row per measurement: construction, then shading (all threads and 1 thread).
fn csv(r: &Results) -> String {
    let mut s = String::from(concat!(
        "kind,scene,triangles,mode,size,shadow_rays,threads,seconds,rays,tests_per_ray,mrays_per_s,mrays_per_s_per_core,",
        "blocker_tests_per_ray,own_leaf_tests_per_ray\n"
    ));
    for sc in &r.scenes {
        for b in &sc.builds {
            let _ =
                writeln!(s, "build,{},{},plie-{},,,{},{},,,,,,", sc.name, sc.triangles, b.config, r.threads, b.seconds);
        }
        for x in &sc.shading {
            let _ = writeln!(
                s,
                "shading,{},{},{},{},{},{},{},{},{},{},{},{},{}",
                sc.name,
                sc.triangles,
                mode_label(x.mode, x.refined),
                x.size,
                x.shadow_rays,
                x.threads,
                x.seconds,
                x.rays,
                x.triangle_tests_per_ray,
                x.mrays_per_second,
                x.mrays_per_second_per_core,
                x.blocker_tests_per_ray,
                x.own_leaf_tests_per_ray
            );
        }
    }
    s
}

fn markdown(plan: &Plan, r: &Results, dir: &Path, thesis: Result<&Thesis, String>) -> String {
    let mut s = String::new();
    header(&mut s, plan, r);
    let th = match thesis {
        Ok(t) => {
            let _ = writeln!(s, "Thesis figures: `{}` (C# on a Pentium IV 1.9 GHz).\n", dir.display());
            Some(t)
        }
        Err(e) => {
            let _ = writeln!(s, "Thesis figures not found ({e}): the thesis columns are omitted.\n");
            None
        }
    };
    construction(&mut s, r, th);
    shading(&mut s, plan, r, th);
    speed_ups(&mut s, plan, r, th);
    break_even(&mut s, r);
    throughput(&mut s, r);
    s
}

fn header(s: &mut String, plan: &Plan, r: &Results) {
    let _ = writeln!(s, "# plie bench\n");
    let _ = writeln!(s, "- command: `{}`", r.command);
    let _ = writeln!(s, "- date: {}", r.date);
    let cpu = r.cpu.as_deref().unwrap_or("unknown CPU");
    let _ = writeln!(s, "- machine: {cpu}, {} cores available; {} threads used", r.cores, r.threads);
    let _ = writeln!(s, "- runs: median of {} per figure{}", r.runs, if r.quick { " (--quick)" } else { "" });
    let settings: Vec<String> = plan.sizes.iter().map(|n| format!("{n}x{n}")).collect();
    let rays: Vec<String> = plan.shadow_rays.iter().map(u32::to_string).collect();
    let _ = writeln!(
        s,
        "- shading: pass 2 alone (hit buffer built beforehand, not timed), {} eye rays (1 per pixel), {} shadow rays per light",
        settings.join(" and "),
        rays.join(" and ")
    );
    let _ = writeln!(
        s,
        "- `+u`: on the P-LIE refined by umbra (rules 1 and 2), at most 2 splits (the thesis' test 2), with its \
         refined octree; the weights of its speed-ups are the unrefined octree mode's times, as in the thesis.\n"
    );
}

fn construction(s: &mut String, r: &Results, th: Option<&Thesis>) {
    let _ = writeln!(s, "## Construction\n");
    let _ = writeln!(
        s,
        "P-LIE construction alone (octree excluded), median seconds. `blockers only`: 200 triangles per \
         leaf, no umbra/penumbra (Table 8.4); `regions`: with umbra/penumbra, removal of fully dark \
         records and propagation of umbra (test 1, Table 8.3 \"full\"); `no propagation`: the same \
         without propagation; `+ grids`: `regions` with face grids (mode grid); `refined`: `regions` \
         refined by umbra, at most 2 splits (test 2, Table 8.3's second rows), with its leaves and \
         records; `refined + grids`: the same with face grids. Records removed: fully dark (of those, \
         deleted by propagation without computing them).\n"
    );
    let mut head = "| scene | triangles | lights | octree s | leaves | records (removed dark; by propagation) | blockers/record (max) | blockers only s | regions s | no propagation s | + grids s | refined s (leaves; records) | refined + grids s |".to_string();
    let mut rule = "|---|---|---|---|---|---|---|---|---|---|---|---|---|".to_string();
    if th.is_some() {
        head += " thesis 8.4 blockers-only s | thesis 8.3 full s (leaves) | thesis 8.3 refined s (leaves) |";
        rule += "---|---|---|";
    }
    let _ = writeln!(s, "{head}\n{rule}");
    for sc in &r.scenes {
        let (b, g, o, np) = (&sc.builds[0], &sc.builds[1], &sc.builds[2], &sc.builds[3]);
        let (rf, rg) = (&sc.builds[4], &sc.builds[5]);
        let _ = write!(
            s,
            "| {} | {} | {} | {:.4} | {} | {} ({}; {}) | {:.1} ({}) | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} ({}; {}) | {:.4} |",
            sc.name,
            sc.triangles,
            sc.lights,
            sc.octree_seconds,
            b.leaves,
            b.records,
            b.records_removed_umbra + b.records_removed_propagation,
            b.records_removed_propagation,
            b.blockers_mean,
            b.blockers_max,
            o.seconds,
            b.seconds,
            np.seconds,
            g.seconds,
            rf.seconds,
            rf.leaves,
            rf.records,
            rg.seconds
        );
        if let Some(t) = th {
            let bo = t.construction(&sc.name, "blockers_only").map(|x| format!("{:.2}", x.0)).unwrap_or_default();
            let with_leaves =
                |c| t.construction(&sc.name, c).map(|x| format!("{:.2} ({})", x.0, x.1)).unwrap_or_default();
            let _ = write!(s, " {bo} | {} | {} |", with_leaves("full"), with_leaves("refined"));
        }
        s.push('\n');
    }
    let total = |i: usize| r.scenes.iter().map(|sc| sc.builds[i].seconds).sum::<f64>();
    let _ = writeln!(
        s,
        "| **total** | | | | | | | **{:.3}** | **{:.3}** | **{:.3}** | **{:.3}** | **{:.3}** | **{:.3}** |",
        total(2),
        total(0),
        total(3),
        total(1),
        total(4),
        total(5)
    );
    s.push('\n');
}

/// A mode's column label: `lie`, or `lie+u` on the refined P-LIE.
fn mode_label(mode: Mode, refined: bool) -> String {
    format!("{mode}{}", if refined { "+u" } else { "" })
}

fn shading(s: &mut String, plan: &Plan, r: &Results, th: Option<&Thesis>) {
    let _ = writeln!(s, "## Shading\n");
    for &size in &plan.sizes {
        for &rays in &plan.shadow_rays {
            let _ = writeln!(s, "### {size}x{size} eye rays, {rays} shadow rays per light\n");
            let ours: Vec<(Mode, bool)> =
                plan.modes.iter().map(|&m| (m, false)).chain(plan.refined_modes.iter().map(|&m| (m, true))).collect();
            let theirs: Vec<(&str, bool)> =
                THESIS_MODES.iter().map(|&m| (m, false)).chain(THESIS_MODES[1..].iter().map(|&m| (m, true))).collect();
            let mut head = String::from("| scene |");
            for &(m, u) in &ours {
                let _ = write!(head, " {} s |", mode_label(m, u));
            }
            if th.is_some() {
                for &(m, u) in &theirs {
                    let _ = write!(head, " thesis {m}{} s |", if u { "+u" } else { "" });
                }
            }
            let cols = ours.len() + 1 + if th.is_some() { theirs.len() } else { 0 };
            let _ = writeln!(s, "{head}\n|{}", "---|".repeat(cols));
            for sc in &r.scenes {
                let _ = write!(s, "| {} |", sc.name);
                for &(m, u) in &ours {
                    let _ = write!(s, " {} |", fmt_opt(seconds_of(sc, m, u, size, rays, r.threads), 4));
                }
                if let Some(t) = th {
                    for &(m, u) in &theirs {
                        let _ = write!(s, " {} |", fmt_opt(t.shading_of(&sc.name, m, size, rays, u), 2));
                    }
                }
                s.push('\n');
            }
            s.push('\n');
        }
    }
}

/// The thesis' shading methods, modes (a)-(d).
const THESIS_MODES: [&str; 4] = ["OCTREE", "LIE", "UMBRA", "PENUMBRA"];

fn fmt_opt(x: Option<f64>, digits: usize) -> String {
    x.map(|v| format!("{v:.digits$}")).unwrap_or_default()
}

fn speed_ups(s: &mut String, plan: &Plan, r: &Results, th: Option<&Thesis>) {
    let _ = writeln!(s, "## Weighted speed-ups\n");
    let _ = writeln!(
        s,
        "Tables 8.1 and 8.2 style: `1 - sum(t_mode) / sum(t_octree)` over the scenes measured (the thesis' \
         column over those of them it has), `t_octree` always the unrefined octree mode's time. Table 8.2 is \
         the thesis' LIE+u column (its printed 126x126, 9 rays figure is 50.98%; its own Table A.2 gives \
         the value here).\n"
    );
    let others: Vec<(Mode, bool)> = plan
        .modes
        .iter()
        .copied()
        .filter(|m| *m != Mode::Octree)
        .map(|m| (m, false))
        .chain(plan.refined_modes.iter().map(|&m| (m, true)))
        .collect();
    let theirs: [(&str, bool); 6] =
        [("LIE", false), ("UMBRA", false), ("PENUMBRA", false), ("LIE", true), ("UMBRA", true), ("PENUMBRA", true)];
    let mut head = String::from("| setting |");
    for &(m, u) in &others {
        let _ = write!(head, " {} |", mode_label(m, u));
    }
    if th.is_some() {
        for (m, u) in theirs {
            let _ = write!(head, " thesis {m}{} |", if u { "+u" } else { "" });
        }
    }
    let cols = others.len() + 1 + if th.is_some() { theirs.len() } else { 0 };
    let _ = writeln!(s, "{head}\n|{}", "---|".repeat(cols));
    for &size in &plan.sizes {
        for &rays in &plan.shadow_rays {
            let _ = write!(s, "| {size}x{size}, {rays} rays |");
            let sum = |m: Mode, u: bool| {
                r.scenes.iter().filter_map(|sc| seconds_of(sc, m, u, size, rays, r.threads)).sum::<f64>()
            };
            let base = sum(Mode::Octree, false);
            for &(m, u) in &others {
                let _ = write!(s, " {:.1}% |", 100.0 * (1.0 - sum(m, u) / base));
            }
            if let Some(t) = th {
                for (m, u) in theirs {
                    let pairs: Vec<(f64, f64)> = r
                        .scenes
                        .iter()
                        .filter_map(|sc| {
                            let octree = t.shading(&sc.name, "OCTREE", size, rays)?;
                            Some((octree, t.shading_of(&sc.name, m, size, rays, u)?))
                        })
                        .collect();
                    let (o, l) = pairs.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
                    let cell = if pairs.is_empty() { String::new() } else { format!("{:.1}%", 100.0 * (1.0 - l / o)) };
                    let _ = write!(s, " {cell} |");
                }
            }
            s.push('\n');
        }
    }
    s.push('\n');
}

fn break_even(s: &mut String, r: &Results) {
    let (size, rays) = r.break_even_setting;
    let _ = writeln!(s, "## Break-even\n");
    let _ = writeln!(
        s,
        "Images of {size}x{size} eye rays, {rays} shadow rays per light, after which octree + P-LIE build + \
         shading costs less than the other mode's build + shading (SPEC §4.2.1's goal).\n"
    );
    let pairs =
        [(Mode::Lie, Mode::Octree), (Mode::Lie, Mode::Bvh), (Mode::Grid, Mode::Octree), (Mode::Grid, Mode::Bvh)];
    let cols: Vec<(Mode, bool, Mode)> = [false, true].into_iter().flat_map(|u| pairs.map(|(m, a)| (m, u, a))).collect();
    let mut head = String::from("| scene |");
    for &(m, u, a) in &cols {
        let _ = write!(head, " {} vs {a} |", mode_label(m, u));
    }
    let _ = writeln!(s, "{head}\n|{}", "---|".repeat(cols.len() + 1));
    for sc in &r.scenes {
        let _ = write!(s, "| {} |", sc.name);
        for &(m, u, a) in &cols {
            let found = sc.break_even.iter().find(|b| b.mode == m && b.refined == u && b.against == a);
            let cell = match found.map(|b| b.images) {
                Some(Some(n)) => n.to_string(),
                Some(None) => "never".to_string(),
                None => String::new(),
            };
            let _ = write!(s, " {cell} |");
        }
        s.push('\n');
    }
    s.push('\n');
}

fn throughput(s: &mut String, r: &Results) {
    let (size, rays) = r.throughput_setting;
    let _ = writeln!(s, "## Shadow-ray throughput\n");
    let _ = writeln!(s, "Million shadow rays per second at {size}x{size}, {rays} shadow rays per light.\n");
    let t = r.threads;
    let _ = writeln!(
        s,
        "| scene | mode | 1 thread M/s | {all} M/s | {all} M/s per core |\n|---|---|---|---|---|",
        all = crate::scenes::count(t, "thread")
    );
    for sc in &r.scenes {
        // One row per mode: with one thread in all, the all-threads row is the one-thread row.
        for x in sc.shading.iter().filter(|x| x.threads == 1 && !x.refined && x.size == size && x.shadow_rays == rays) {
            let all = sc
                .shading
                .iter()
                .find(|y| y.mode == x.mode && !y.refined && y.size == size && y.shadow_rays == rays && y.threads == t);
            let (m, pc) = all.map(|y| (y.mrays_per_second, y.mrays_per_second_per_core)).unwrap_or((0.0, 0.0));
            let _ = writeln!(s, "| {} | {} | {:.2} | {m:.2} | {pc:.2} |", sc.name, x.mode, x.mrays_per_second);
        }
    }
    s.push('\n');
}

/// The current time, UTC, as `YYYY-MM-DD HH:MM:SS UTC`.
pub fn utc_now() -> String {
    let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    let (days, rem) = (secs / 86_400, secs % 86_400);
    let (y, m, d) = civil_from_days(days as i64);
    format!("{y:04}-{m:02}-{d:02} {:02}:{:02}:{:02} UTC", rem / 3600, rem % 3600 / 60, rem % 60)
}

/// Days since 1970-01-01 to (year, month, day), proleptic Gregorian (H. Hinnant's algorithm).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// The CPU model from /proc/cpuinfo, if readable.
pub fn cpu_model() -> Option<String> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("model name"))?;
    Some(line.split_once(':')?.1.trim().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(19_723), (2024, 1, 1));
    }

    #[test]
    fn thesis_names() {
        assert_eq!(thesis_name("cornell-cube-1"), "Cornell Cube 1");
        assert_eq!(thesis_name("huis-a"), "Huis A");
        assert_eq!(thesis_name("dragon"), "Dragon");
    }
}
