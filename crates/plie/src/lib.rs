//! # plie: Preprocessed Local Illumination Environments
//!
//! Direct lighting from area lights with exact shadows.
//!
//! Conventions: right-handed coordinates, y up; triangles are counter-clockwise around their front
//! normal; angles in degrees at the API (fields named `_deg`), radians inside; radiance in linear RGB.
//!
//! The pipeline (see `ARCHITECTURE.md`): a validated [`Scene`], an [`octree::Octree`] over it, the
//! P-LIE built by [`construct::build`] (or [`construct::build_refined`], which also refines the
//! octree, SPEC §4.8), a [`visibility::Visibility`] mode, and [`render::render`]
//! (hit buffer, then shading). Every mode answers every shadow ray exactly as brute force.
//!
//! ```
//! use plie::lie::PlieParams;
//! use plie::octree::Octree;
//! use plie::render::{render, NoProgress, RenderSettings};
//! use plie::visibility::{bvh::Bvh, for_mode, Mode};
//!
//! let scene = plie::scene::builtin::load("cornell-cube-1")?;
//! let params = PlieParams::thesis();
//! let octree = Octree::build(&scene, params.octree());
//! let (plie, stats) = plie::construct::build(&scene, &octree, params, &NoProgress);
//! assert!(stats.records > 0);
//! let bvh = Bvh::build(&scene);
//! let settings = RenderSettings { width: 16, height: 16, eye_rays: 1, shadow_rays: 4, seed: 1 };
//! let camera = scene.camera_or_default();
//! let mut images = Vec::new();
//! for mode in [Mode::Bvh, Mode::Lie] {
//!     let vis = for_mode(mode, &scene, &bvh, &octree, Some(&plie))?;
//!     images.push(render(&scene, &camera, &settings, &bvh, Some(&octree), vis.as_ref(), &NoProgress)?.pixels);
//! }
//! assert_eq!(images[0], images[1]); // exact: the same image from every mode
//! # Ok::<(), plie::Error>(())
//! ```
#![warn(missing_docs)]

pub mod error;
pub mod geometry;
pub mod io;
pub mod scene;

pub use error::{Error, Result};
pub use scene::{Camera, Light, LightId, Material, MaterialId, Scene, SceneBuilder, TriId};
pub mod compare;
pub mod construct;
pub mod inspect;
pub mod lie;
pub mod octree;
pub mod render;
pub mod verify;
pub mod visibility;
