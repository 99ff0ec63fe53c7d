//! Which (leaf, face, light) get a data object (SPEC §4.1).
//!
//! **Correction** of the thesis' `dot(n_face, n_light) <= 0` rule: a record is needed when some face
//! point `f` and light point `y` have `(y - f) . n_face > 0` (the light lies beyond the face, outside
//! the cell) and `(f - y) . n_light > 0` (the face point is in front of the one-sided light). Both
//! planes are fixed, so the two conditions separate: the first depends on `y` only, the second on `f`
//! only. Hence a record exists iff some light vertex lies beyond the face plane and some face corner
//! lies in front of the light plane — evaluated with a tolerance that errs toward creating the record.

use glam::Vec3;

use crate::scene::Light;

/// True if light can leave `light` and enter the cell through the face with these corners and outward
/// normal `n_face` (the exact condition, grown by `tol`).
pub fn face_sees_light(face: &[Vec3; 4], n_face: Vec3, light: &Light, tol: f32) -> bool {
    let beyond = light.vertices.iter().any(|v| (*v - face[0]).dot(n_face) > -tol);
    let in_front = face.iter().any(|f| (*f - light.vertices[0]).dot(light.normal) > -tol);
    beyond && in_front
}

/// The thesis' rule (§5.2), kept only to show where it fails: the light must face the face
/// (`n_face . n_light <= 0`) and the face must be in front of the light.
pub fn thesis_face_sees_light(face: &[Vec3; 4], n_face: Vec3, light: &Light) -> bool {
    n_face.dot(light.normal) <= 0.0 && face.iter().any(|f| (*f - light.vertices[0]).dot(light.normal) > 0.0)
}
