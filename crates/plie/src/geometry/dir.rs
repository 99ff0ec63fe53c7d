//! Directions and cell faces (SPEC §3, thesis §6.1): Left/Right along x, Down/Up along y, Back/Front
//! along z. A cell face is named by the direction of its outward normal.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::Aabb;

/// One of the six axis directions; also names the cell face whose outward normal points that way.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Dir {
    /// -x
    Left,
    /// +x
    Right,
    /// -y
    Down,
    /// +y
    Up,
    /// -z
    Back,
    /// +z
    Front,
}

impl Dir {
    /// All six, in index order.
    pub const ALL: [Dir; 6] = [Dir::Left, Dir::Right, Dir::Down, Dir::Up, Dir::Back, Dir::Front];

    /// Index 0..6 (axis * 2 + positive).
    #[inline]
    pub fn index(self) -> usize {
        self as usize
    }

    /// The direction with this index.
    #[inline]
    pub fn from_index(i: usize) -> Dir {
        Dir::ALL[i]
    }

    /// The direction along `axis` (0 = x, 1 = y, 2 = z), positive or negative.
    #[inline]
    pub fn from_axis(axis: usize, positive: bool) -> Dir {
        Dir::ALL[axis * 2 + positive as usize]
    }

    /// Axis: 0 = x, 1 = y, 2 = z.
    #[inline]
    pub fn axis(self) -> usize {
        self.index() / 2
    }

    /// True for Right, Up, Front.
    #[inline]
    pub fn is_positive(self) -> bool {
        self.index() % 2 == 1
    }

    /// The opposite direction.
    #[inline]
    pub fn inverse(self) -> Dir {
        Dir::ALL[self.index() ^ 1]
    }

    /// Unit vector.
    pub fn normal(self) -> Vec3 {
        let mut v = Vec3::ZERO;
        v[self.axis()] = if self.is_positive() { 1.0 } else { -1.0 };
        v
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        ["left", "right", "down", "up", "back", "front"][self.index()]
    }

    /// The face of box `b` in this direction, as 4 corners counter-clockwise around the outward normal.
    pub fn face_corners(self, b: &Aabb) -> [Vec3; 4] {
        let k = self.axis();
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let w = if self.is_positive() { b.max[k] } else { b.min[k] };
        let corner = |a: f32, c: f32| {
            let mut p = Vec3::ZERO;
            p[k] = w;
            p[u] = a;
            p[v] = c;
            p
        };
        let (u0, u1, v0, v1) = (b.min[u], b.max[u], b.min[v], b.max[v]);
        // (u, v, k) is right-handed, so (u0,v0) -> (u1,v0) -> (u1,v1) is counter-clockwise around +k.
        let q = [corner(u0, v0), corner(u1, v0), corner(u1, v1), corner(u0, v1)];
        if self.is_positive() {
            q
        } else {
            [q[0], q[3], q[2], q[1]]
        }
    }
}

impl std::str::FromStr for Dir {
    type Err = String;
    fn from_str(s: &str) -> Result<Dir, String> {
        Dir::ALL
            .into_iter()
            .find(|d| d.name() == s.to_lowercase())
            .ok_or_else(|| format!("unknown face '{s}' (left, right, down, up, back, front)"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_wind_counter_clockwise_around_their_outward_normal() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        for d in Dir::ALL {
            let q = d.face_corners(&b);
            let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize();
            assert!((n - d.normal()).length() < 1e-6, "{d:?}: {n}");
            assert_eq!(d.inverse().inverse(), d);
            assert_eq!(Dir::from_axis(d.axis(), d.is_positive()), d);
        }
    }
}
