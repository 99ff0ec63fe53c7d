//! The scene model of SPEC §1: triangles with Lambertian materials, convex polygonal one-sided area
//! lights (which are geometry too), and a pinhole camera. A [`Scene`] is validated when it is built, so
//! every later stage can trust it.

pub mod builtin;
pub mod camera;
mod dropped;
pub mod ids;
pub mod light;
pub mod material;
#[allow(clippy::module_inception)]
mod scene;
pub mod texture;

pub use camera::Camera;
pub use ids::{LightId, MaterialId, TextureId, TriId};
pub use light::Light;
pub use material::Material;
pub use scene::{Scene, SceneBuilder};
pub use texture::Texture;
