//! The tolerances every stage agrees on (SPEC §3, §5): the open range of a shadow segment and the
//! construction's tolerance. Every test that prunes errs toward keeping by these.

/// The open parameter range of a shadow segment `x + t (y - x)`: `(SEGMENT_EPS, 1 - SEGMENT_EPS)`.
/// Keeps the shaded surface's neighbours and whatever touches the light sample from counting.
pub const SEGMENT_EPS: f32 = 1e-4;

/// Relative tolerance of the construction (times the scene size): every test errs toward keeping.
pub const TOLERANCE_REL: f32 = 1e-5;

/// The rounding the tolerance allows for, per unit of the largest absolute coordinate: a light
/// sample `o + e1 u + e3 v` is rounded to `f32` twice per coordinate (at most one ulp in all, and an
/// ulp is at most `f32::EPSILON` times the coordinate), so it may lie `sqrt(3)` such units off the
/// light's polygon, whose tilted plane no `f32` point need lie on; and a triangle's corner taken
/// relative to a ray's origin moves by up to half an ulp per coordinate. Sixteen leaves room for the
/// rest. For a scene far from the origin against its size this, not [`TOLERANCE_REL`], sets the
/// tolerance: a panel a few ulps behind a tilted light there blocks some samples, brute force says.
pub const ROUNDING_REL: f32 = 16.0 * f32::EPSILON;

/// The absolute tolerance of a scene of size `size` (its largest extent) whose coordinates reach
/// `far` from the origin: [`TOLERANCE_REL`] of the size, or [`ROUNDING_REL`] of `far` where that is
/// larger (a scene more than about five times its size from the origin).
pub fn tolerance_of(size: f32, far: f32) -> f32 {
    (size * TOLERANCE_REL).max(far * ROUNDING_REL)
}
