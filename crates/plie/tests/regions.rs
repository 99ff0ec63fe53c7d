//! Umbra and penumbra (SPEC §4.5), removal (§4.6) and the region-based modes (§5 c, d, grid).

mod support;

use plie::construct::regions::face_regions;
use plie::construct::shaft::Shaft;
use plie::lie::PlieParams;
use plie::octree::{Dir, Octree};

#[test]
fn debug_cube1() {
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let params = PlieParams::default();
    let octree = Octree::build(&scene, params.octree());
    let light = &scene.lights[0];
    let tol = scene.scale().max(octree.root_bounds().size().max_element()) * plie::construct::TOLERANCE_REL;
    for l in octree.leaves() {
        let b = octree.leaf_bounds(l);
        for face in Dir::ALL {
            let corners = face.face_corners(&b);
            if !plie::construct::data_objects::face_sees_light(&corners, face.normal(), light, tol) {
                continue;
            }
            let shaft = Shaft::new(&corners, &light.vertices, tol);
            let blockers: Vec<_> = (0..scene.triangles.len() as u32)
                .map(plie::TriId)
                .filter(|t| scene.tri_light[t.idx()].is_none() && shaft.clips_triangle(&scene.triangles[t.idx()].v))
                .collect();
            let r = face_regions(&scene, face, &b, light, &blockers, &shaft, tol, 800.0);
            eprintln!(
                "{l:?} {face:?} {b:?}: {} blockers, {} umbra blockers, umbra {:.3} full {}",
                blockers.len(),
                r.umbra_blockers,
                r.umbra_fraction,
                r.full_umbra
            );
        }
    }
    panic!();
}
