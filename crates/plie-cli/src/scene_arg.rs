//! `--scene NAME|FILE` (every subcommand) and `--eye`, `--target`, `--up`, `--fov` (those that render a
//! picture).

use std::path::Path;

use anyhow::{bail, Context, Result};
use glam::Vec3;
use plie::scene::builtin;
use plie::{Camera, Scene};

/// The option that chooses the scene.
#[derive(clap::Args, Clone, Debug)]
pub struct SceneArgs {
    /// A built-in scene name (see `plie scenes`) or a scene file (.obj with its .mtl, .gltf, .glb, or a
    /// Mitsuba scene .xml).
    #[arg(long, value_name = "NAME|FILE")]
    pub scene: String,
    /// Let the scene file name files outside its own folder (absolute paths, `..`, `file:` URIs in
    /// `mtllib` lines, glTF buffer URIs, Mitsuba includes, meshes and textures). Off by default: a
    /// scene from elsewhere cannot make plie read other files.
    #[arg(long)]
    pub allow_outside_paths: bool,
}

/// Options that set the camera (subcommands that render a picture).
#[derive(clap::Args, Clone, Debug)]
pub struct CameraArgs {
    /// Camera position (default: the scene's camera, or one framing the whole scene).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub eye: Option<Vec3>,
    /// Point the camera looks at.
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub target: Option<Vec3>,
    /// Camera up vector (image right = viewing direction x up).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees.
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub fov: Option<f32>,
}

impl SceneArgs {
    /// Loads the scene: a built-in name, else a file.
    pub fn load(&self) -> Result<Scene> {
        if builtin::exists(&self.scene) {
            return Ok(builtin::load(&self.scene)?);
        }
        self.check_exists()?;
        let path = Path::new(&self.scene);
        let opts = plie::io::LoadOptions { allow_outside_paths: self.allow_outside_paths };
        plie::io::load_scene_with(path, opts).with_context(|| format!("cannot load scene {}", path.display()))
    }

    /// Fails as [`SceneArgs::load`] would if the scene is neither a built-in name nor a file, without
    /// loading it (a command that loads its scenes late checks them all first).
    pub fn check_exists(&self) -> Result<()> {
        let path = Path::new(&self.scene);
        if builtin::exists(&self.scene) || path.exists() {
            return Ok(());
        }
        if path.extension().is_none() {
            return Err(builtin::load(&self.scene).unwrap_err().into());
        }
        bail!("{}: no such file", path.display());
    }

    /// The scene file, when the scene is a file (an output must never overwrite it).
    pub fn file(&self) -> Option<&Path> {
        let builtin = builtin::exists(&self.scene);
        (!builtin).then(|| Path::new(&self.scene))
    }
}

/// Warns (on stderr) about what the loader skipped or read without rendering.
pub fn warn_about(scene: &Scene) {
    if scene.degenerate_skipped > 0 {
        eprintln!("warning: skipped {} degenerate (zero-area) triangles", scene.degenerate_skipped);
    }
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
}

impl CameraArgs {
    /// The camera: the scene's (or a framing default), with any option given overriding a part.
    pub fn camera(&self, scene: &Scene) -> Result<Camera> {
        let base = scene.camera_or_default();
        let c = Camera {
            eye: self.eye.unwrap_or(base.eye),
            target: self.target.unwrap_or(base.target),
            up: self.up.unwrap_or(base.up),
            fov_deg: self.fov.unwrap_or(base.fov_deg),
        };
        c.validate()?;
        Ok(c)
    }
}

/// Parses `X,Y,Z`.
pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("expected X,Y,Z, got '{s}'"));
    }
    let mut v = [0.0f32; 3];
    for (o, p) in v.iter_mut().zip(&parts) {
        *o = p.parse::<f32>().map_err(|_| format!("'{p}' is not a number"))?;
        if !o.is_finite() {
            return Err(format!("'{p}' is not finite"));
        }
    }
    Ok(Vec3::from_array(v))
}
