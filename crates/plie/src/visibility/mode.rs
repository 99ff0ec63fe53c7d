//! The visibility modes a user can choose (`--visibility`).

use std::fmt;
use std::str::FromStr;

/// A visibility method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Every triangle: the reference.
    Brute,
    /// SPEC §5 mode (a): walk the octree leaves along the segment.
    Octree,
    /// A modern BVH (the peer).
    Bvh,
    /// SPEC §5 mode (b): the P-LIE's blocker lists.
    Lie,
    /// SPEC §5 mode (c): as `lie`, but a ray crossing the face in the umbra triangles is blocked.
    Umbra,
    /// SPEC §5 mode (d): as `umbra`, and a ray crossing outside umbra and penumbra skips the blockers.
    Penumbra,
    /// Ours: face grids. The cell where the ray crosses the face says umbra (blocked), or which
    /// blockers to test (none: lit).
    Grid,
    /// Native Intel Embree 3: its triangles, its triangle test, packets (cargo feature `embree`). The
    /// peer a user compares against. Not exact: a few answers may differ from `brute`.
    #[cfg(feature = "embree")]
    Embree,
    /// Intel Embree 3's BVH proposing candidates to the shared predicate (cargo feature `embree`).
    #[cfg(feature = "embree")]
    EmbreeExact,
    /// No shadow test at all: every shadow ray is unoccluded. Not exact: it exists to measure what
    /// shading costs without any visibility (the floor every other mode adds to).
    None,
}

impl Mode {
    /// Every exact mode: each answers every shadow ray as `brute` does. The exactness suites compare
    /// them all.
    #[cfg(not(feature = "embree"))]
    pub const EXACT: [Mode; 7] =
        [Mode::Brute, Mode::Octree, Mode::Bvh, Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid];
    /// Every exact mode: each answers every shadow ray as `brute` does. The exactness suites compare
    /// them all.
    #[cfg(feature = "embree")]
    pub const EXACT: [Mode; 8] =
        [Mode::Brute, Mode::Octree, Mode::Bvh, Mode::Lie, Mode::Umbra, Mode::Penumbra, Mode::Grid, Mode::EmbreeExact];

    /// The modes that are not exact, kept as references to measure against: native Embree (feature
    /// `embree`) and `none`.
    #[cfg(not(feature = "embree"))]
    pub const REFERENCE: [Mode; 1] = [Mode::None];
    /// The modes that are not exact, kept as references to measure against: native Embree (feature
    /// `embree`) and `none`.
    #[cfg(feature = "embree")]
    pub const REFERENCE: [Mode; 2] = [Mode::Embree, Mode::None];

    /// Every mode a user can choose: the exact ones and the references.
    pub fn all() -> impl Iterator<Item = Mode> {
        Mode::EXACT.into_iter().chain(Mode::REFERENCE)
    }

    /// True if the mode answers every shadow ray as `brute` does.
    pub fn is_exact(self) -> bool {
        !Mode::REFERENCE.contains(&self)
    }

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Brute => "brute",
            Mode::Octree => "octree",
            Mode::Bvh => "bvh",
            Mode::Lie => "lie",
            Mode::Umbra => "umbra",
            Mode::Penumbra => "penumbra",
            Mode::Grid => "grid",
            #[cfg(feature = "embree")]
            Mode::Embree => "embree",
            #[cfg(feature = "embree")]
            Mode::EmbreeExact => "embree-exact",
            Mode::None => "none",
        }
    }

    /// True if the mode answers from a P-LIE.
    pub fn needs_plie(self) -> bool {
        matches!(self, Mode::Lie | Mode::Umbra | Mode::Penumbra | Mode::Grid)
    }

    /// True if the mode needs the P-LIE's umbra and penumbra (built with `regions`).
    pub fn needs_regions(self) -> bool {
        matches!(self, Mode::Umbra | Mode::Penumbra)
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Mode, String> {
        Mode::all().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<_> = Mode::all().map(|m| m.name()).collect();
            if s == "embree" {
                return format!(
                    "this plie was built without Intel Embree; install Embree 3 (Debian: apt-get install \
                     libembree-dev) and build with `cargo build --release -p plie-cli --features embree` \
                     (or choose from {})",
                    names.join(", ")
                );
            }
            format!("unknown visibility mode '{s}' (choose from {})", names.join(", "))
        })
    }
}
