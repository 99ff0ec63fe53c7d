//! Point location (SPEC §3): the leaf containing a point, e.g. the hit point of an eye ray
//! (SPEC §2, hit buffer).
//!
//! Tie-break on cell boundaries: at every inner node, a coordinate **greater than or equal to** the
//! split plane goes to the upper child. So a point is located in the cell that is closed below and
//! open above (`min <= p < max`), except on the root's upper faces, which belong to the cells touching
//! them (the root is closed). The returned leaf's closed box always contains the point.

use glam::Vec3;

use super::{child_box, LeafId, NodeKind, Octree};

impl Octree {
    /// The leaf containing `p`, or `None` if `p` lies outside the closed root cube (or is NaN).
    /// Points on a split plane go to the upper side (see the module doc).
    pub fn locate(&self, p: Vec3) -> Option<LeafId> {
        let mut b = self.root_bounds();
        if !b.contains(p) {
            return None;
        }
        let mut node = 0usize;
        loop {
            match self.nodes[node].kind() {
                NodeKind::Leaf(l) => return Some(l),
                NodeKind::Inner(first) => {
                    let c = b.center();
                    let i = p.cmpge(c).bitmask() as usize;
                    b = child_box(&b, i);
                    node = first as usize + i;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use crate::octree::{Octree, OctreeParams};
    use crate::SceneBuilder;

    #[test]
    fn split_plane_goes_to_upper_child() {
        let mut b = SceneBuilder::new("box");
        let m = b.diffuse("grey", Vec3::splat(0.5));
        b.quad(
            Vec3::new(-1.0, -1.0, -1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
            m,
        );
        b.light("l", &[Vec3::new(-0.1, 1.0, 0.0), Vec3::new(0.1, 1.0, 0.0), Vec3::new(0.1, 1.0, 0.1)], Vec3::ONE);
        let s = b.build().expect("valid scene");
        let o = Octree::build(&s, OctreeParams::default()).expect("valid octree parameters");
        let c = o.root_bounds().center();
        let l = o.locate(c).expect("inside");
        assert_eq!(o.leaf_bounds(l).min, c, "the center belongs to the all-upper child");
        let r = o.root_bounds();
        let top = o.locate(r.max).expect("root is closed");
        assert_eq!(o.leaf_bounds(top).max, r.max);
        assert!(o.locate(r.max + Vec3::new(0.0, 1e-3, 0.0)).is_none());
        assert!(o.locate(Vec3::NAN).is_none());
    }
}
