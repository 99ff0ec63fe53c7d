//! `plie build`: construct the P-LIE of a scene (SPEC §4) for every leaf, face and light, independent of
//! any camera, and save it as a `.plie` file.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use plie::octree::Octree;
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
    crate::scenes::set_threads(a.threads)?;
    crate::checks::plie_output(&a.output, &a.scene.file().into_iter().collect::<Vec<_>>())?;
    let scene = a.scene.load()?;
    let params = a.params.params(true)?;
    let bar = Bar::new(a.quiet || a.json);
    let t_all = Instant::now();
    let t = Instant::now();
    let octree = Octree::build(&scene, params.octree());
    let octree_seconds = t.elapsed().as_secs_f64();
    let built = plie::construct::build_refined(&scene, octree, params, &bar);
    let (octree, plie, mut stats) = (built.octree, built.plie, built.stats);
    stats.octree_seconds = octree_seconds;
    let build_seconds = t_all.elapsed().as_secs_f64();
    let t = Instant::now();
    let file_bytes = plie::io::plie_file::save_plie(&a.output, &scene, &octree, &plie)
        .with_context(|| format!("cannot write {}", a.output.display()))?;
    let write_seconds = t.elapsed().as_secs_f64();
    let memory = plie.memory_bytes() + octree.memory_bytes();
    if a.json {
        let propagation = json!({
            "enabled": params.propagation,
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
        let v = json!({
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
            "regions": params.regions,
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
        println!("{v}");
    } else if !a.quiet {
        println!(
            "scene           {} ({} triangles, {} lights)",
            scene.name,
            scene.triangle_count(),
            scene.lights.len()
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
        if !params.regions {
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
        if !params.regions {
        } else if !params.propagation {
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
                "                time saved ≈ {:.3} s (estimate: {:.2} ms per record computed, over the threads, minus propagation)",
                stats.propagation_seconds_saved_estimate,
                1e3 * stats.record_seconds_mean
            );
        }
        print_refinement(&params, &stats);
        if !params.grids {
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
        println!("file            {} ({file_bytes} bytes, written in {write_seconds:.3} s)", a.output.display());
    }
    Ok(())
}

/// The summary lines of refinement (SPEC §4.8): leaves added per criterion, and what it changed.
fn print_refinement(params: &plie::lie::PlieParams, stats: &plie::construct::BuildStats) {
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
