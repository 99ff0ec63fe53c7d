//! The tolerances every stage agrees on (SPEC §3, §5): the open range of a shadow segment and the
//! construction's relative tolerance. Every test that prunes errs toward keeping by these.

/// The open parameter range of a shadow segment `x + t (y - x)`: `(SEGMENT_EPS, 1 - SEGMENT_EPS)`.
/// Keeps the shaded surface's neighbours and whatever touches the light sample from counting.
pub const SEGMENT_EPS: f32 = 1e-4;

/// Relative tolerance of the construction (times the scene size): every test errs toward keeping.
pub const TOLERANCE_REL: f32 = 1e-5;
