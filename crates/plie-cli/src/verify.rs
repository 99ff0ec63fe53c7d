//! `plie verify FILE.plie --scene S [--full]`: checks a P-LIE file against a rebuild (SPEC §4), for
//! files that pass the checksum but may have been altered (`plie::internals::verify`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};

use crate::scene_arg::SceneArgs;

/// Options of `plie verify`.
#[derive(clap::Args)]
pub struct Args {
    /// The P-LIE file to check.
    #[arg(value_name = "FILE.plie")]
    file: PathBuf,
    #[command(flatten)]
    scene: SceneArgs,
    /// Rebuild the whole P-LIE and compare every record (as long as `plie build`).
    #[arg(long)]
    full: bool,
    /// Without --full: how many records to check (chosen at random with --seed).
    #[arg(long, default_value_t = 256, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    records: u32,
    /// Without --full: shadow rays per checked record, each compared with brute force.
    #[arg(long, default_value_t = 16, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    rays: u32,
    /// Seed of the sample.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[command(flatten)]
    threads: crate::threads_arg::ThreadsArg,
}

pub fn run(a: &Args) -> Result<()> {
    a.threads.install()?;
    let t = Instant::now();
    let scene = a.scene.load()?;
    let env = plie::Environment::load(&a.file, &scene, None)
        .with_context(|| format!("cannot use P-LIE file {}", a.file.display()))?;
    let (octree, plie) = (env.octree(), env.plie());
    let report = if a.full {
        plie::internals::verify::verify_full(&scene, plie)
    } else {
        plie::internals::verify::verify_sample(&scene, octree, plie, a.records as usize, a.rays as usize, a.seed)
    };
    match report {
        Ok(r) if a.full => {
            println!("{}: OK, all {} records equal a rebuild ({:.2} s)", a.file.display(), r.records, t.elapsed().as_secs_f64());
        }
        Ok(r) => println!(
            "{}: OK, {} records sampled, {} shadow rays answered as brute force in every P-LIE mode ({:.2} s; --full rebuilds every record)",
            a.file.display(),
            r.records,
            r.rays,
            t.elapsed().as_secs_f64()
        ),
        Err(m) => bail!("{}: does not match a rebuild: {m}; rebuild it with `plie build`", a.file.display()),
    }
    Ok(())
}
