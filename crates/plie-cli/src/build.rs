//! `plie build`: construct the P-LIE of a scene (SPEC §4) for every leaf, face and light, independent of
//! any camera, and save it as a `.plie` file.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use plie::{BuildOptions, Environment};
use serde_json::json;

use crate::plie_args::PlieArgs;
use crate::progress::Bar;
use crate::scene_arg::SceneArgs;

/// Options of `plie build`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    scene: SceneArgs,
    /// Output file (.plie).
    #[arg(short = 'o', long = "output", value_name = "OUT.plie")]
    output: PathBuf,
    #[command(flatten)]
    params: PlieArgs,
    /// Memory budget of the construction, e.g. `4G`, `512M` (default: half the machine's memory). A
    /// build that would exceed it stores the blocker lists of the records that do not fit no more
    /// (they are answered by the scene BVH, exactly) and says so; it never aborts.
    #[arg(long, value_name = "SIZE", value_parser = crate::budget::parse_bytes)]
    memory_budget: Option<u64>,
    /// Worker threads (default: all cores). The result does not depend on it.
    #[arg(long, value_name = "T")]
    threads: Option<usize>,
    /// Print one JSON object with the figures on stdout.
    #[arg(long)]
    json: bool,
    /// No progress bar, no summary.
    #[arg(long, short)]
    quiet: bool,
}

pub fn run(a: &Args) -> Result<()> {
    // First, so that Ctrl-C at any point before the file is written stops the build cleanly.
    crate::progress::install_interrupt()?;
    crate::scenes::set_threads(a.threads)?;
    crate::checks::plie_output(&a.output, &a.scene.file().into_iter().collect::<Vec<_>>())?;
    let scene = a.scene.load()?;
    if !a.quiet {
        crate::scene_arg::warn_about(&scene);
    }
    let params = a.params.params(true)?;
    let budget = a.memory_budget.unwrap_or_else(crate::budget::default_bytes);
    crate::budget::check(budget, &scene)?;
    let list_budget = Some(crate::budget::list_bytes(budget, &scene));
    let bar = Bar::new(a.quiet || a.json);
    let t_all = Instant::now();
    let options = BuildOptions { list_bytes: list_budget, progress: &bar };
    let (env, stats) = match Environment::build_with(&scene, &params, options) {
        Err(e @ plie::Error::Interrupted) => {
            return Err(anyhow::Error::new(e).context("P-LIE construction stopped by Ctrl-C; nothing was written"))
        }
        built => built?,
    };
    crate::budget::warn_over(&stats, &bar);
    let octree_seconds = stats.octree_seconds;
    let build_seconds = t_all.elapsed().as_secs_f64();
    let t = Instant::now();
    let file_bytes = env.save(&a.output, &scene).with_context(|| format!("cannot write {}", a.output.display()))?;
    let write_seconds = t.elapsed().as_secs_f64();
    let (octree, plie) = (env.octree(), env.plie());
    let peak = crate::budget::peak_bytes();
    let memory = plie.memory_bytes() + octree.memory_bytes();
    if a.json {
        let propagation = json!({
            "enabled": params.propagation == plie::Propagation::On,
            "records_removed": stats.records_removed_propagation,
            "tests": stats.propagation_tests,
            "by_rule": stats.propagation_by_rule,
            "wasted": stats.propagation_wasted,
            "seconds": stats.propagation_seconds,
            "record_seconds_mean": stats.record_seconds_mean,
            "seconds_saved_estimate": stats.propagation_seconds_saved_estimate,
        });
        let refinement = json!({
            "criteria": params.refine.chain().iter().map(|c| c.name()).collect::<Vec<_>>(),
            "max_split_depth": params.refine.max_split_depth,
            "max_blockers": params.refine.blockers.map(|m| format!("{m:?}")),
            "rounds": stats.refine_rounds,
            "splits_by_criterion": stats.refine_splits,
            "leaves_added": 7 * stats.refine_splits.values().sum::<usize>(),
            "unrefined": stats.unrefined,
        });
        // Issue 15: the bounds of the construction.
        let bounded = json!({
            "blocker_cap": params.blocker_cap,
            "records_scene": stats.records_scene,
            "records_over_budget": stats.records_over_budget,
            "list_bytes": stats.list_bytes,
            "memory_budget": budget,
            "list_budget": list_budget,
            "peak_memory_bytes": peak,
        });
        let mut v = json!({
            "scene": scene.name,
            "triangles": scene.triangle_count(),
            "lights": scene.lights.len(),
            "max_triangles": params.max_triangles,
            "max_depth": params.max_depth,
            "threads": rayon::current_num_threads(),
            "build_seconds": build_seconds,
            "octree_seconds": octree_seconds,
            "blockers_seconds": stats.blockers_seconds,
            "write_seconds": write_seconds,
            "leaves": octree.leaf_count(),
            "depth": octree.depth(),
            "faces_considered": stats.faces_considered,
            "records": stats.records,
            "records_removed_face_cannot_see_light": stats.no_record_face_cannot_see_light,
            "candidates_clipped": stats.candidates_clipped,
            "blockers_total": stats.blockers_total,
            "blockers_mean": stats.blockers_mean,
            "blockers_max": stats.blockers_max,
            "regions": params.has_regions(),
            "records_removed_umbra": stats.records_removed_umbra,
            "records_removed_propagation": stats.records_removed_propagation,
            "propagation": propagation,
            "refinement": refinement,
            "records_with_umbra": stats.records_with_umbra,
            "records_with_penumbra": stats.records_with_penumbra,
            "region_polygon_vertices": stats.region_polygon_vertices,
            "region_triangles": stats.region_triangles,
            "region_bytes": stats.region_bytes,
            "umbra_fraction_mean": stats.umbra_fraction_mean,
            "penumbra_fraction_mean": stats.penumbra_fraction_mean,
            "grids": stats.grids,
            "grid_cells": plie.cells.len(),
            "grid_cells_lit": stats.grid_cells_lit,
            "grid_cells_umbra": stats.grid_cells_umbra,
            "grid_blockers_total": plie.cell_blockers.len(),
            "bytes": memory,
            "file_bytes": file_bytes,

            "output": a.output.display().to_string(),
        });
        if let (Some(o), serde_json::Value::Object(b)) = (v.as_object_mut(), bounded) {
            o.extend(b);
        }
        println!("{v}");
    } else if !a.quiet {
        println!(
            "scene           {} ({} triangles, {})",
            scene.name,
            scene.triangle_count(),
            crate::scenes::count(scene.lights.len(), "light")
        );
        println!("octree          {} leaves, depth {} ({:.3} s)", octree.leaf_count(), octree.depth(), octree_seconds);
        println!(
            "data objects    {} of {} (leaf, face, light); {} without: the face cannot see the light",
            stats.records, stats.faces_considered, stats.no_record_face_cannot_see_light
        );
        println!(
            "blockers        {} in all, {:.1} per record (max {}), {} candidates clipped ({:.3} s)",
            stats.blockers_total,
            stats.blockers_mean,
            stats.blockers_max,
            stats.candidates_clipped,
            stats.blockers_seconds
        );
        println!(
            "scene records   {} answered by the scene BVH ({} with more than {} blockers, {} over the memory budget of {budget} bytes)",
            stats.records_scene,
            stats.records_scene - stats.records_over_budget,
            params.blocker_cap.map_or("no cap".to_string(), |c| c.to_string()),
            stats.records_over_budget
        );
        if !params.has_regions() {
            println!("regions         none (--no-regions)");
        } else {
            println!(
                "regions         {} records removed (fully in umbra); of those kept, {} with umbra, {} with penumbra",
                stats.records_removed_umbra, stats.records_with_umbra, stats.records_with_penumbra
            );
            println!(
                "                mean umbra {:.1}% and penumbra {:.1}% of a face; {} polygon vertices, {} triangles ({} bytes)",
                100.0 * stats.umbra_fraction_mean,
                100.0 * stats.penumbra_fraction_mean,
                stats.region_polygon_vertices,
                stats.region_triangles,
                stats.region_bytes
            );
        }
        if !params.has_regions() {
        } else if !params.propagates() {
            println!("propagation     none (--no-propagation)");
        } else {
            println!(
                "propagation     {} records removed without computing their blockers ({} of {} candidates proven; {} computed before being removed; {:.3} s propagating)",
                stats.records_removed_propagation,
                stats.records_removed_propagation,
                stats.propagation_tests,
                stats.propagation_wasted,
                stats.propagation_seconds
            );
            if stats.records_removed_propagation > 0 {
                let rules: Vec<String> = stats.propagation_by_rule.iter().map(|(r, n)| format!("{n} {r}")).collect();
                println!("                by rule: {}", rules.join(", "));
            }
            println!(
                "                {} (estimate: {:.2} ms per record computed, over the threads, minus propagation)",
                time_saved(stats.propagation_seconds_saved_estimate),
                1e3 * stats.record_seconds_mean
            );
        }
        print_refinement(&params, &stats);
        if !params.has_grids() {
            println!("face grids      none (--no-grids)");
        } else {
            println!(
                "face grids      {} records with a grid, {} cells ({} fully lit, {} umbra), {} cell blocker references",
                stats.grids,
                plie.cells.len(),
                stats.grid_cells_lit,
                stats.grid_cells_umbra,
                plie.cell_blockers.len()
            );
        }
        println!("build           {build_seconds:.3} s");
        println!("memory          {memory} bytes (octree {} + P-LIE {})", octree.memory_bytes(), plie.memory_bytes());
        if let Some(p) = peak {
            println!("peak memory     {p} bytes (VmHWM)");
        }
        println!("file            {} ({file_bytes} bytes, written in {write_seconds:.3} s)", a.output.display());
    }
    Ok(())
}

/// The summary lines of refinement (SPEC §4.8): leaves added per criterion, and what it changed.
fn print_refinement(params: &plie::PlieParams, stats: &plie::BuildStats) {
    let (Some(u), true) = (stats.unrefined, params.refine.enabled()) else {
        println!("refinement      none (--refine to enable)");
        return;
    };
    let added: usize = 7 * stats.refine_splits.values().sum::<usize>();
    let by: Vec<String> =
        stats.refine_splits.iter().map(|(c, n)| format!("{c} {n} splits (+{} leaves)", 7 * n)).collect();
    println!(
        "refinement      +{added} leaves in {} rounds (max split depth {}){}{}",
        stats.refine_rounds,
        params.refine.max_split_depth,
        if by.is_empty() { "" } else { ": " },
        by.join(", ")
    );
    println!(
        "                leaves {} -> {}, records {} -> {}, blockers {} -> {}, construction {:.3} s -> {:.3} s",
        u.leaves,
        stats.leaves,
        u.records,
        stats.records,
        u.blockers_total,
        stats.blockers_total,
        u.seconds,
        stats.blockers_seconds
    );
}

/// The estimated construction time propagation saved, in words: a loss is said as one, and less than
/// half a millisecond either way as under a millisecond (never "-0.000 s").
fn time_saved(seconds: f64) -> String {
    if seconds >= 0.0005 {
        format!("time saved ≈ {seconds:.3} s")
    } else if seconds <= -0.0005 {
        format!("time lost ≈ {:.3} s (propagating cost more than it saved)", -seconds)
    } else {
        "time saved under a millisecond".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::time_saved;

    #[test]
    fn time_saved_never_reads_minus_zero() {
        assert_eq!(time_saved(0.0123), "time saved ≈ 0.012 s");
        assert_eq!(time_saved(-0.0000004), "time saved under a millisecond");
        assert_eq!(time_saved(0.0004), "time saved under a millisecond");
        assert_eq!(time_saved(-0.25), "time lost ≈ 0.250 s (propagating cost more than it saved)");
    }
}
