//! `--width`, `--height`, `--eye-rays`, `--shadow-rays`, `--seed` and `--exposure`: the image options
//! shared by `plie render` and `plie inspect` (SPEC §2's hit buffer and N-rooks shadow rays).

use anyhow::{bail, Result};
use plie::render::RenderSettings;

/// Options that set the rendered image.
#[derive(clap::Args, Clone, Debug)]
pub struct ImageArgs {
    /// Image width in pixels (1 to 32768).
    #[arg(long, default_value_t = 398, value_parser = clap::value_parser!(u32).range(1..=32768))]
    pub width: u32,
    /// Image height in pixels (1 to 32768).
    #[arg(long, default_value_t = 398, value_parser = clap::value_parser!(u32).range(1..=32768))]
    pub height: u32,
    /// K: K x K regular eye rays per pixel.
    #[arg(long, default_value_t = 2, value_name = "K")]
    pub eye_rays: u32,
    /// N: N-rooks shadow rays per light per eye ray.
    #[arg(long, default_value_t = 25, value_name = "N")]
    pub shadow_rays: u32,
    /// Seed of the random streams (same seed, same image, in every exact mode).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// PNG only: scale radiance by 2^EV before tone mapping (EXR and PFM keep the exact values; the
    /// overlay colours of `plie inspect` stay as they are).
    #[arg(long, default_value_t = 0.0, value_name = "EV", allow_hyphen_values = true)]
    pub exposure: f32,
}

impl ImageArgs {
    /// The validated render settings (and a finite exposure).
    pub fn settings(&self) -> Result<RenderSettings> {
        let s = RenderSettings {
            width: self.width,
            height: self.height,
            eye_rays: self.eye_rays,
            shadow_rays: self.shadow_rays,
            seed: self.seed,
        };
        s.validate()?;
        if !self.exposure.is_finite() {
            bail!("--exposure must be a finite number");
        }
        Ok(s)
    }
}
