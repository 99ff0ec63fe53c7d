//! `--integrator`, `--max-path-depth`, `--rr-depth`, `--spp` and `--nee`: the options of `plie render`
//! that choose between direct light (SPEC §2) and the path tracer (global illumination, SPEC §8
//! point 6), and how many samples each takes.

use anyhow::{bail, Result};
use plie::{Nee, PathSettings};

/// Which estimator renders the image.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Direct light only: K x K regular eye rays per pixel, N shadow rays per light each.
    Direct,
    /// Path tracing: global illumination with next-event estimation through the visibility mode.
    Path,
}

/// A value of `--nee`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum NeeArg {
    /// N samples on every light at every vertex.
    All,
    /// N samples on one light at every vertex, chosen with probability proportional to its power.
    Power,
}

/// Options of the estimator.
#[derive(clap::Args, Clone, Debug)]
pub struct PathArgs {
    /// `direct` (direct light only, light -> surface -> eye) or `path` (global illumination: light also
    /// bounces between surfaces).
    #[arg(long, value_enum, default_value_t = Integrator::Direct)]
    pub integrator: Integrator,
    /// Path: longest path, counted as Mitsuba 3's `max_depth`: 1 is emission seen directly, 2 direct
    /// light only, 3 adds one indirect bounce, -1 is unbounded. (`--max-depth` is the octree's.)
    #[arg(long, default_value_t = 5, value_name = "D", allow_hyphen_values = true)]
    pub max_path_depth: i32,
    /// Path: Russian roulette from this many bounces on (default: never).
    #[arg(long, value_name = "K")]
    pub rr_depth: Option<u32>,
    /// Samples per pixel. Path: S paths per pixel, each through a random point of the pixel
    /// (default K x K from --eye-rays), with --shadow-rays N light samples at every vertex (on one
    /// light or on each, see --nee).
    /// Direct: S must be a square K x K and replaces --eye-rays K.
    #[arg(long, value_name = "S", conflicts_with = "eye_rays")]
    pub spp: Option<u32>,
    /// Path: which lights next-event estimation samples at a vertex.
    #[arg(long, value_enum, default_value_t = NeeArg::Power)]
    pub nee: NeeArg,
}

impl PathArgs {
    /// `--eye-rays` K for direct mode: from `--spp` if given (which must be a square), else `k`.
    pub fn eye_rays(&self, k: u32) -> Result<u32> {
        let Some(s) = self.spp else { return Ok(k) };
        let r = (s as f64).sqrt().round() as u32;
        if r * r != s || s == 0 {
            bail!("--spp {s}: direct light takes K x K eye rays per pixel, so --spp must be a square (1, 4, 9, ...)");
        }
        Ok(r)
    }

    /// The path tracer's settings; `k` is --eye-rays.
    pub fn settings(&self, k: u32) -> Result<PathSettings> {
        let p = PathSettings {
            spp: self.spp.unwrap_or(k * k),
            max_depth: self.max_path_depth,
            rr_depth: self.rr_depth,
            nee: match self.nee {
                NeeArg::All => Nee::All,
                NeeArg::Power => Nee::Power,
            },
        };
        p.validate()?;
        Ok(p)
    }
}
