//! `--width`, `--height`, `--eye-rays`, `--shadow-rays`, `--seed` and `--exposure`: the image options
//! shared by `plie render` and `plie inspect` (SPEC §2's hit buffer and N-rooks shadow rays).

use anyhow::{bail, Result};
use plie::RenderSettings;
use plie::Scene;

/// Options that set the rendered image.
#[derive(clap::Args, Clone, Debug)]
pub struct ImageArgs {
    /// Image width in pixels (1 to 32768). Default: the scene file's own (a Mitsuba film), else 398.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=32768))]
    pub width: Option<u32>,
    /// Image height in pixels (1 to 32768). Default: the scene file's own (a Mitsuba film), else 398.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=32768))]
    pub height: Option<u32>,
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

/// The image size without a scene size or an option (SPEC §6, the thesis' images).
pub const DEFAULT_SIZE: u32 = 398;

impl ImageArgs {
    /// Sets the image size of `settings` for `scene`: each option given, else the scene's own size
    /// (a Mitsuba film), else [`DEFAULT_SIZE`].
    pub fn size_for(&self, settings: &mut RenderSettings, scene: &Scene) -> Result<()> {
        let (w, h) = scene.image_size.unwrap_or((DEFAULT_SIZE, DEFAULT_SIZE));
        settings.width = self.width.unwrap_or(w);
        settings.height = self.height.unwrap_or(h);
        settings.validate()?;
        Ok(())
    }

    /// The validated render settings (and a finite exposure), with the image size given, or 398 x 398
    /// until [`ImageArgs::size_for`] knows the scene.
    pub fn settings(&self) -> Result<RenderSettings> {
        let s = RenderSettings {
            width: self.width.unwrap_or(DEFAULT_SIZE),
            height: self.height.unwrap_or(DEFAULT_SIZE),
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
