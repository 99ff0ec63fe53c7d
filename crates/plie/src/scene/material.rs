//! Lambertian materials (SPEC §1): `f_r = albedo / pi`, plus the radiance a surface emits (non-zero only
//! for lights).

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::TextureId;

/// A diffuse material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name (from the MTL file, or given by a built-in scene).
    pub name: String,
    /// Diffuse albedo `rho`, linear RGB in [0, 1].
    pub albedo: Vec3,
    /// Emitted radiance `L_e` from the front side, linear RGB (zero for non-emitters).
    pub emission: Vec3,
    /// A texture the albedo is multiplied by at each hit ([`crate::Scene::albedo_at`]); shading only.
    #[serde(default)]
    pub texture: Option<TextureId>,
}

impl Material {
    /// A non-emitting diffuse material.
    pub fn diffuse(name: &str, albedo: Vec3) -> Material {
        Material { name: name.to_string(), albedo, emission: Vec3::ZERO, texture: None }
    }

    /// True if the material emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
