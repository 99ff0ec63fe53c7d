//! [`TriMesh`]: an indexed triangle mesh with optional texture coordinates, what the mesh readers of
//! scene formats (PLY, Mitsuba's serialized format) return before a loader places it in a scene.

use glam::{Vec2, Vec3};

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Texture coordinates per vertex, or empty.
    pub uvs: Vec<Vec2>,
    /// Triangles: indices into `positions` (checked in range by the readers).
    pub triangles: Vec<[u32; 3]>,
}
