//! # plie: Preprocessed Local Illumination Environments
//!
//! Direct lighting (and path tracing) from area lights with exact shadows. A P-LIE stores, per
//! octree cell face and per light, the triangles that can block the light and the umbra and
//! penumbra they cast; shadow rays are then answered from the cell a point lies in. Every
//! visibility [`Mode`] answers every shadow ray exactly as brute force does, so images rendered
//! with the same seed are bit-identical across modes and thread counts.
//!
//! Conventions: right-handed coordinates, y up; triangles are counter-clockwise around their front
//! normal; angles in degrees at the API (fields named `_deg`), radians inside; radiance in linear RGB.
//!
//! The public API in one page:
//! - a [`Scene`]: [`scene::builtin::load`], [`io::load_scene`] (OBJ + MTL, glTF), or a
//!   [`SceneBuilder`];
//! - an [`Environment`]: the scene's octree and P-LIE with its [`PlieParams`];
//!   [`Environment::build`] (refinement included), [`Environment::save`], [`Environment::load`],
//!   [`Environment::validate`], and [`Environment::visibility`] for shadow queries;
//! - a [`Renderer`]: image settings, camera and [`Integrator`] (direct light or path tracing), and
//!   one call to render;
//! - [`Shadows`]: the modes that need no P-LIE (`brute`, `octree`, `bvh`);
//! - the [`Visibility`] trait, to ask shadow rays from your own renderer.
//!
//! ```
//! use plie::{Environment, Mode, PlieParams, Renderer};
//!
//! let scene = plie::scene::builtin::load("cornell-cube-1")?;
//!
//! // Build the P-LIE once (independent of any camera), save it, load it back.
//! let (env, stats) = Environment::build(&scene, &PlieParams::default())?;
//! assert!(stats.records > 0);
//! let path = std::env::temp_dir().join(format!("plie-doc-{}.plie", std::process::id()));
//! env.save(&path, &scene)?;
//! let env = Environment::load(&path, &scene, Some(env.params()))?;
//! assert!(env.validate(&scene).is_ok());
//! # std::fs::remove_file(&path).ok();
//!
//! // Render with the BVH and with the P-LIE's face grids: the same image, bit for bit.
//! let renderer = Renderer::new().size(16, 16).eye_rays(1).shadow_rays(4).seed(1);
//! let bvh = renderer.render(&scene, Mode::Bvh, None)?;
//! let grid = renderer.render(&scene, Mode::Grid, Some(&env))?;
//! assert_eq!(bvh.pixels, grid.pixels);
//!
//! // Or ask single shadow rays: from a point on triangle 0 to a point on light 0.
//! use plie::visibility::{QueryCtx, ShadowRay};
//! let vis = env.visibility(Mode::Grid, &scene)?;
//! let x = scene.triangle(plie::TriId(0)).point(0.3, 0.3);
//! let y = scene.lights[0].sample(glam::Vec2::new(0.5, 0.5));
//! let ray = ShadowRay::new(x, y, plie::LightId(0), plie::TriId(0), env.octree().locate(x));
//! let mut ctx = QueryCtx::new(scene.triangle_count());
//! let _lit = !vis.occluded(&ray, &mut ctx);
//! # Ok::<(), plie::Error>(())
//! ```
#![warn(missing_docs)]

pub mod environment;
pub mod error;
pub mod geometry;
pub mod io;
pub mod scene;

pub use construct::BuildStats;
pub use environment::{BuildOptions, Environment, Report};
pub use error::{Error, PlieFileError, Result};
pub use lie::{Grids, PlieParams, Propagation, Regions};
pub use progress::{NoProgress, Progress};
pub use render::path::{Nee, PathSettings};
pub use render::RenderSettings;
pub use renderer::{Image, Integrator, Renderer, Timing};
pub use scene::{Camera, Light, LightId, Material, MaterialId, Scene, SceneBuilder, TriId};
pub use visibility::{Mode, Shadows, Visibility};
pub mod compare;
pub mod construct;
pub mod inspect;
pub mod lie;
pub mod octree;
pub mod progress;
pub mod render;
pub mod renderer;
pub mod verify;
pub mod visibility;
