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
    for name in builtin::NAMES {
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

/// Sets the global rayon pool size (`--threads`), bounded ([`crate::checks::set_threads`]).
pub fn set_threads(threads: Option<usize>) -> Result<()> {
    crate::checks::set_threads(threads)
}
