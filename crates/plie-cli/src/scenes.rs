//! `plie scenes`: the built-in scenes of SPEC §6, one line each (name, triangles, lights, what it is);
//! and two helpers every subcommand uses (`--threads`, counted nouns).

use anyhow::Result;
use plie::scene::builtin;

/// Options of `plie scenes`.
#[derive(clap::Args)]
pub struct Args {
    /// Print one JSON object per scene (name, triangles, lights, description) instead of a table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<()> {
    if !args.json {
        println!("{:<16} {:>9} {:>6}  what", "name", "triangles", "lights");
    }
    for name in builtin::NAMES.into_iter().chain(builtin::STRESS) {
        let s = builtin::load(name)?;
        let what = builtin::description(name).unwrap_or("");
        if args.json {
            let v = serde_json::json!({
                "name": name,
                "triangles": s.triangle_count(),
                "lights": s.lights.len(),
                "description": what,
            });
            println!("{v}");
        } else {
            println!("{:<16} {:>9} {:>6}  {what}", name, s.triangle_count(), s.lights.len());
        }
    }
    Ok(())
}

/// `n` and `noun`, plural unless `n` is 1: "1 light", "2 lights".
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}
