//! Geometry shared by every stage: boxes, triangles, the one watertight segment/triangle test and the
//! exact triangle/box overlap test; Newell's normal of a polygon; Morton codes; the six face directions of a box; the tolerances.
//!
//! SPEC §3 (octree assignment needs the triangle/box test) and §5 (one watertight test everywhere, so
//! every visibility mode answers the same shadow ray identically).

pub mod aabb;
pub mod clip;
pub mod dir;
pub mod morton;
pub mod polygon;
pub mod ray_triangle;
pub mod segment;
pub mod tolerance;
pub mod tri_box;
pub mod triangle;

pub use aabb::Aabb;
pub use dir::Dir;
pub use polygon::newell;
pub use ray_triangle::RayTest;
pub use segment::Segment;
pub use tolerance::{tolerance_of, ROUNDING_REL, SEGMENT_EPS, TOLERANCE_REL};
pub use tri_box::triangle_overlaps_box;
pub use triangle::Triangle;
