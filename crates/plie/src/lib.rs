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
//! assert!(stats.blockers.records > 0);
//! println!("{stats}"); // a line or two per phase; `serde_json::to_string(&stats)` for JSON
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
pub mod octree;
pub mod progress;
pub mod renderer;
pub mod scene;
pub mod visibility;

pub(crate) mod compare;
pub(crate) mod construct;
pub(crate) mod inspect;
pub(crate) mod lie;
pub(crate) mod render;
pub(crate) mod verify;

pub use construct::lift::DEFAULT_LIFT_CLIPS;
pub use construct::scene_cells::DEFAULT_CELL_CLIPS;
pub use construct::{
    BlockerStats, BoundedStats, BuildStats, GridStats, OctreeStats, PropagationStats, RefinementStats, RegionStats,
    RoundStats,
};
pub use environment::{BuildOptions, Environment, Report};
pub use error::{Error, PlieFileError, Result, SceneElement};
pub use lie::{Criterion, Grids, MaxBlockers, PlieParams, Propagation, RefineParams, Regions, DEFAULT_BLOCKER_CAP};
pub use progress::{NoProgress, Progress};
pub use render::path::{Nee, PathSettings, PathStats};
pub use render::RenderSettings;
pub use renderer::{Image, Integrator, Renderer, Timing};
pub use scene::{Camera, Light, LightId, Material, MaterialId, Scene, SceneBuilder, TriId};
pub use visibility::{Mode, QueryCtx, QueryStats, ShadowRay, Shadows, Visibility};

/// The library's internal stages, for its own tests, benchmarks and fuzz targets and for the tools
/// of the `plie` command that look inside a P-LIE (`plie bench`, `plie inspect`, `plie verify`).
///
/// **Not a stable API**: anything here may change or go away in any release. Programs that use plie
/// need only the items at the crate root ([`Environment`], [`Renderer`], [`Shadows`],
/// [`Visibility`] and what they take and return).
#[doc(hidden)]
pub mod internals {
    /// Comparing one mode's shadow-ray answers with another's.
    pub mod compare {
        pub use crate::compare::*;
    }
    /// The P-LIE construction's stages.
    pub mod construct {
        pub use crate::construct::*;
    }
    /// What `plie inspect` shows of a cell.
    pub mod inspect {
        pub use crate::inspect::*;
    }
    /// The P-LIE data structure and its vocabulary.
    pub mod lie {
        pub use crate::lie::*;
    }
    /// The renderer's passes: hit buffer, shading, path tracing.
    pub mod render {
        pub use crate::render::*;
    }
    /// Checking a P-LIE file against a rebuild.
    pub mod verify {
        pub use crate::verify::*;
    }
    /// `.plie` files and the glTF export of `plie inspect`.
    pub mod io {
        /// The glTF scene `plie inspect` writes.
        pub mod gltf_export {
            pub use crate::io::gltf_export::*;
        }
        /// The `.plie` file format.
        pub mod plie_file {
            pub use crate::io::plie_file::*;
        }
    }
    /// The P-LIE modes' query internals.
    pub mod visibility {
        /// The P-LIE modes.
        pub mod lie {
            pub use crate::visibility::lie::exit_face;
        }
    }
}
