//! The one entry point for what the P-LIE is (SPEC §0, §4): an [`Environment`] is the octree of a
//! scene with its preprocessed local illumination environments and the parameters they were built
//! with. Build it ([`Environment::build`], refinement included), save and load it (`.plie` files),
//! check it ([`Environment::validate`]) and ask it shadow rays ([`Environment::visibility`]).

use std::path::Path;
use std::sync::OnceLock;

use crate::construct::{BuildStats, Limits};
use crate::error::{Error, Result};
use crate::io::plie_file;
use crate::lie::{Plie, PlieParams};
use crate::octree::{Octree, OctreeReport};
use crate::progress::{NoProgress, Progress};
use crate::scene::Scene;
use crate::visibility::bvh::Bvh;
use crate::visibility::{Mode, Visibility};

/// A scene's octree and P-LIE, built together with one set of [`PlieParams`].
///
/// An environment belongs to the scene it was built or loaded for: every method that takes the
/// scene checks that it is that scene (by a fingerprint of its geometry and lights).
pub struct Environment {
    octree: Octree,
    plie: Plie,
    scene_fingerprint: u64,
    /// The scene BVH, built the first time a mode needs it (records answered by the scene, mode
    /// `bvh`).
    bvh: OnceLock<Bvh>,
}

/// How [`Environment::build_with`] builds: a budget and a progress reporter.
#[derive(Clone, Copy)]
pub struct BuildOptions<'p> {
    /// Bytes the blocker lists may take ([`Limits::list_bytes`]); records over it are answered by
    /// the scene BVH (exactly). `None`: no limit.
    pub list_bytes: Option<usize>,
    /// Candidate clips per scene triangle the build may spend giving records over the blocker cap
    /// their full lists anyway, with a cap up to 16 times larger
    /// ([`Limits::lift_clips`]); `None`: records over the cap stay answered by the scene BVH.
    pub lift_clips: Option<usize>,
    /// Candidate clips per scene triangle the build may spend on the grid cells of the records
    /// still over the cap after that: each cell under a small cap keeps its full list (empty: fully
    /// lit) instead of leaving its rays to the scene BVH ([`Limits::cell_clips`]); `None`: none.
    pub cell_clips: Option<usize>,
    /// Reports progress; [`Progress::cancelled`] stops the build with [`Error::Interrupted`].
    pub progress: &'p dyn Progress,
}

impl Default for BuildOptions<'_> {
    fn default() -> Self {
        BuildOptions {
            list_bytes: None,
            lift_clips: Some(crate::DEFAULT_LIFT_CLIPS),
            cell_clips: Some(crate::DEFAULT_CELL_CLIPS),
            progress: &NoProgress,
        }
    }
}

/// What [`Environment::validate`] found: the octree's report and the P-LIE's first inconsistency.
#[derive(Clone, Debug, PartialEq)]
pub struct Report {
    /// Counts and violations of the octree's invariants.
    pub octree: OctreeReport,
    /// The first inconsistency of the P-LIE's tables (an index out of range, a list out of order,
    /// sizes that do not match the octree or the scene), if any.
    pub plie: Option<String>,
}

impl Report {
    /// True if neither the octree nor the P-LIE breaks an invariant.
    pub fn is_ok(&self) -> bool {
        self.octree.is_ok() && self.plie.is_none()
    }
}

impl std::fmt::Display for Report {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.octree)?;
        match &self.plie {
            None => writeln!(f, "P-LIE: consistent"),
            Some(p) => writeln!(f, "P-LIE: {p}"),
        }
    }
}

impl Environment {
    /// Builds the octree of `scene` and its P-LIE with `params` (SPEC §3, §4), refining the octree
    /// as `params.refine` asks (§4.8). Fails if the parameters are invalid.
    pub fn build(scene: &Scene, params: &PlieParams) -> Result<(Environment, BuildStats)> {
        Environment::build_with(scene, params, BuildOptions::default())
    }

    /// [`Environment::build`] within a memory budget, reporting progress; fails with
    /// [`Error::Interrupted`] when `options.progress` says it is cancelled.
    pub fn build_with(scene: &Scene, params: &PlieParams, options: BuildOptions) -> Result<(Environment, BuildStats)> {
        params.validate()?;
        let t = std::time::Instant::now();
        let octree = Octree::build_valid(scene, params.octree());
        let octree_seconds = t.elapsed().as_secs_f64();
        let lift_clips = options.lift_clips.map(|c| c.saturating_mul(scene.triangles.len()));
        let cell_clips = options.cell_clips.map(|c| c.saturating_mul(scene.triangles.len()));
        let limits = Limits { list_bytes: options.list_bytes, lift_clips, cell_clips };
        let built = crate::construct::build_bounded(scene, octree, *params, limits, options.progress)
            .map_err(|_| Error::Interrupted)?;
        let mut stats = built.stats;
        stats.octree.octree_seconds = octree_seconds;
        stats.bounded.list_budget = options.list_bytes;
        stats.bounded.lift_clips = options.lift_clips;
        stats.bounded.cell_clips = options.cell_clips;
        Ok((Environment::from_parts(scene, built.octree, built.plie), stats))
    }

    /// An environment of an octree and a P-LIE built on it for `scene` (as the construction returns
    /// them; for the crate's tests and tools: the P-LIE's type is internal, see `plie::internals`).
    #[doc(hidden)]
    pub fn from_parts(scene: &Scene, octree: Octree, plie: Plie) -> Environment {
        Environment { octree, plie, scene_fingerprint: plie_file::scene_fingerprint(scene), bvh: OnceLock::new() }
    }

    /// Saves the environment as a `.plie` file (atomically); returns the bytes written. The octree
    /// is not stored: [`Environment::load`] rebuilds it.
    pub fn save(&self, path: &Path, scene: &Scene) -> Result<u64> {
        self.check_scene(scene)?;
        plie_file::save_plie(path, scene, &self.octree, &self.plie)
    }

    /// Loads a `.plie` file for `scene`, rebuilding its octree. With `expect`, the file must have
    /// been built with the same octree and refinement parameters. Every problem with the file is an
    /// [`Error::PlieFile`] naming it ([`crate::error::PlieFileError`] says which).
    pub fn load(path: &Path, scene: &Scene, expect: Option<&PlieParams>) -> Result<Environment> {
        let (octree, plie) = plie_file::load_plie(path, scene, expect.copied())?;
        Ok(Environment::from_parts(scene, octree, plie))
    }

    /// [`Environment::load`] from the bytes of a `.plie` file already in memory (e.g. fetched from a
    /// distributed object store), with the same checks; `origin` names the bytes in errors.
    pub fn load_bytes(bytes: &[u8], origin: &str, scene: &Scene, expect: Option<&PlieParams>) -> Result<Environment> {
        let (octree, plie) = plie_file::load_plie_bytes(bytes, origin, scene, expect.copied())?;
        Ok(Environment::from_parts(scene, octree, plie))
    }

    /// Checks the octree's invariants and the P-LIE's tables against `scene`.
    pub fn validate(&self, scene: &Scene) -> Report {
        let plie = match self.check_scene(scene) {
            Err(e) => Some(e.to_string()),
            Ok(()) => self.plie.validate(scene, &self.octree).err(),
        };
        Report { octree: self.octree.validate(scene), plie }
    }

    /// The visibility `mode` over this environment: the P-LIE modes answer from the P-LIE, `octree`
    /// from the octree; `bvh` and the P-LIE's records answered by the scene use the scene BVH,
    /// built on first use and kept. Fails if `mode` needs what the P-LIE was built without (umbra
    /// and penumbra), or if `scene` is not the environment's scene.
    pub fn visibility<'a>(&'a self, mode: Mode, scene: &'a Scene) -> Result<Box<dyn Visibility + 'a>> {
        self.check_scene(scene)?;
        crate::visibility::make(mode, scene, || self.bvh(scene), || &self.octree, Some(&self.plie))
    }

    /// The scene BVH (built on first use). `scene` must be the environment's scene.
    pub fn bvh(&self, scene: &Scene) -> &Bvh {
        self.bvh.get_or_init(|| Bvh::build(scene))
    }

    /// The octree (refined if the parameters asked for refinement).
    pub fn octree(&self) -> &Octree {
        &self.octree
    }

    /// The P-LIE (its type is internal, see `plie::internals`).
    #[doc(hidden)]
    pub fn plie(&self) -> &Plie {
        &self.plie
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &PlieParams {
        &self.plie.params
    }

    /// The fastest exact mode this environment answers: `grid` with face grids, else `penumbra` with
    /// regions, else `lie`.
    pub fn best_mode(&self) -> Mode {
        let p = &self.plie.params;
        if p.has_grids() {
            Mode::Grid
        } else if p.has_regions() {
            Mode::Penumbra
        } else {
            Mode::Lie
        }
    }

    /// Bytes held in memory by the octree and the P-LIE.
    pub fn memory_bytes(&self) -> usize {
        self.plie.memory_bytes() + self.octree.memory_bytes()
    }

    /// The octree and the P-LIE (the P-LIE's type is internal, see `plie::internals`).
    #[doc(hidden)]
    pub fn into_parts(self) -> (Octree, Plie) {
        (self.octree, self.plie)
    }

    fn check_scene(&self, scene: &Scene) -> Result<()> {
        if plie_file::scene_fingerprint(scene) != self.scene_fingerprint {
            return Err(Error::InvalidParameter(format!(
                "this P-LIE environment was built for another scene, not '{}'",
                scene.name
            )));
        }
        Ok(())
    }
}
