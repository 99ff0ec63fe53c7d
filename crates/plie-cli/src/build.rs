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
    #[command(flatten)]
    threads: crate::threads_arg::ThreadsArg,
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
    a.threads.install()?;
    crate::checks::plie_output(&a.output, &a.scene.file().into_iter().collect::<Vec<_>>())?;
    let scene = a.scene.load()?;
    crate::checks::outputs_are_not_sources(std::slice::from_ref(&a.output), &scene.sources)?;
    if !a.quiet {
        crate::scene_arg::warn_about(&scene);
    }
    let params = a.params.params(true)?;
    let budget = a.memory_budget.unwrap_or_else(crate::budget::default_bytes);
    crate::budget::check(budget, &scene)?;
    let list_budget = Some(crate::budget::list_bytes(budget, &scene));
    let bar = Bar::new(a.quiet || a.json);
    let t_all = Instant::now();
    let options = BuildOptions {
        list_bytes: list_budget,
        lift_clips: a.params.lift_clips(),
        cell_clips: a.params.cell_clips(),
        progress: &bar,
    };
    let (env, stats) = match Environment::build_with(&scene, &params, options) {
        Err(e @ plie::Error::Interrupted) => {
            return Err(anyhow::Error::new(e).context("P-LIE construction stopped by Ctrl-C; nothing was written"))
        }
        built => built?,
    };
    crate::budget::warn_over(&stats, &bar);
    let build_seconds = t_all.elapsed().as_secs_f64();
    let t = Instant::now();
    let file_bytes = env.save(&a.output, &scene).with_context(|| format!("cannot write {}", a.output.display()))?;
    let write_seconds = t.elapsed().as_secs_f64();
    let (octree, plie) = (env.octree(), env.plie());
    let peak = crate::budget::peak_bytes();
    let memory = plie.memory_bytes() + octree.memory_bytes();
    if a.json {
        // The construction's figures by phase as the library serialises them, and around them what
        // only the command knows: the scene, the parameters, the file, the memory.
        let mut v = serde_json::to_value(&stats)?;
        let extra = json!({
            "scene": scene.name,
            "triangles": scene.triangle_count(),
            "lights": scene.lights.len(),
            "max_triangles": params.max_triangles,
            "max_depth": params.max_depth,
            "threads": rayon::current_num_threads(),
            "build_seconds": build_seconds,
            "write_seconds": write_seconds,
            "bytes": memory,
            "file_bytes": file_bytes,
            "memory_budget": budget,
            "peak_memory_bytes": peak,
            "output": a.output.display().to_string(),
        });
        if let (Some(o), serde_json::Value::Object(e)) = (v.as_object_mut(), extra) {
            o.extend(e);
        }
        println!("{v}");
    } else if !a.quiet {
        println!(
            "scene           {} ({} triangles, {})",
            scene.name,
            scene.triangle_count(),
            crate::scenes::count(scene.lights.len(), "light")
        );
        print!("{stats}");
        println!("build           {build_seconds:.3} s");
        println!(
            "memory          {memory} bytes (octree {} + P-LIE {}); memory budget {budget} bytes (--memory-budget)",
            octree.memory_bytes(),
            plie.memory_bytes()
        );
        if let Some(p) = peak {
            println!("peak memory     {p} bytes (VmHWM)");
        }
        println!("file            {} ({file_bytes} bytes, written in {write_seconds:.3} s)", a.output.display());
    }
    Ok(())
}
