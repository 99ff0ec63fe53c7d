//! # plie: Preprocessed Local Illumination Environments
//!
//! Direct lighting from area lights with exact shadows.
//!
//! Conventions: right-handed coordinates, y up; triangles are counter-clockwise around their front
//! normal; angles in degrees at the API (fields named `_deg`), radians inside; radiance in linear RGB.
#![warn(missing_docs)]

pub mod error;
pub mod geometry;
pub mod io;
pub mod scene;

pub use error::{Error, Result};
pub use scene::{Camera, Light, LightId, Material, MaterialId, Scene, SceneBuilder, TriId};
pub mod construct;
pub mod lie;
pub mod octree;
pub mod visibility;
pub mod render;
