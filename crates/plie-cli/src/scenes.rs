//! `plie scenes`: the built-in scenes of SPEC §6, one line each.

use anyhow::Result;
use plie::scene::builtin;

/// Options of `plie scenes`.
#[derive(clap::Args)]
pub struct Args {
    /// Print one JSON object per scene instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<()> {
    if !args.json {
        println!("{:<16} {:>9} {:>6}", "name", "triangles", "lights");
    }
    for name in builtin::NAMES.into_iter().chain(builtin::STRESS) {
        let s = builtin::load(name)?;
        if args.json {
            let v = serde_json::json!({"name": name, "triangles": s.triangle_count(), "lights": s.lights.len()});
            println!("{v}");
        } else {
            println!("{:<16} {:>9} {:>6}", name, s.triangle_count(), s.lights.len());
        }
    }
    Ok(())
}

/// Sets the global rayon pool size (`--threads`).
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        if t == 0 {
            anyhow::bail!("--threads must be at least 1");
        }
        rayon::ThreadPoolBuilder::new().num_threads(t).build_global()?;
    }
    Ok(())
}
