//! The thesis' propagation rules (chapter 6, SPEC §4.7) as *candidate generators*: from the lit and
//! dark faces of a source cell, which neighbour to look at and which of its faces may be dark. No
//! candidate is deleted on the rule's word: each one must pass the principle test of
//! [`super::principle`], which replaces the thesis' 45° conditions on shaft-plane angles.

use serde::Serialize;

use super::principle::Source;
use crate::octree::Dir;

/// A thesis propagation rule (chapter 6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Rule {
    /// §6.2: every lit face dark: in `neighbour(F.inv)` the face `F`, for each lit face `F`.
    General,
    /// §6.3: one lit face `F`, dark: every face of `neighbour(F.inv)`.
    OneFace,
    /// §6.4.1: two lit faces, both dark: every face of `neighbour(A.inv, B.inv)`.
    TwoFacesBothDark,
    /// §6.4.2: two lit faces, only `A` dark: face `A` of `neighbour(A.inv, B.inv)`.
    TwoFacesOneDark,
    /// §6.5.1: three lit faces, all dark: every face of `neighbour(A.inv, B.inv, C.inv)`.
    ThreeFacesAllDark,
    /// §6.5.2: three lit faces, `A` and `B` dark: faces `A` and `B` of that corner neighbour.
    ThreeFacesTwoDark,
    /// §6.5.3: three lit faces, only `A` dark: face `A` of that corner neighbour.
    ThreeFacesOneDark,
}

impl Rule {
    /// Every rule, in the order they are tried.
    pub const ALL: [Rule; 7] = [
        Rule::OneFace,
        Rule::TwoFacesBothDark,
        Rule::TwoFacesOneDark,
        Rule::ThreeFacesAllDark,
        Rule::ThreeFacesTwoDark,
        Rule::ThreeFacesOneDark,
        Rule::General,
    ];

    /// Short name (thesis section).
    pub fn name(self) -> &'static str {
        match self {
            Rule::General => "general (6.2)",
            Rule::OneFace => "one face (6.3)",
            Rule::TwoFacesBothDark => "two faces, both dark (6.4.1)",
            Rule::TwoFacesOneDark => "two faces, one dark (6.4.2)",
            Rule::ThreeFacesAllDark => "three faces, all dark (6.5.1)",
            Rule::ThreeFacesTwoDark => "three faces, two dark (6.5.2)",
            Rule::ThreeFacesOneDark => "three faces, one dark (6.5.3)",
        }
    }

    /// Index in [`Rule::ALL`].
    pub fn index(self) -> usize {
        Rule::ALL.iter().position(|&r| r == self).unwrap_or(0)
    }
}

/// Bit set of faces (bit `d.index()`).
pub type Faces = u8;

/// Every face.
pub const ALL_FACES: Faces = 0b11_1111;

/// One candidate: step along `dirs[..n]` from the source, and try `faces` of the leaves there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Candidate {
    /// The neighbour's directions (first `n`).
    pub dirs: [Dir; 3],
    /// How many directions: 1, 2 or 3.
    pub n: usize,
    /// Faces to try.
    pub faces: Faces,
    /// The rule that proposes it.
    pub rule: Rule,
}

fn bit(d: Dir) -> Faces {
    1 << d.index()
}

/// The candidates the thesis' rules propose for a source: the specific rules for one, two or three
/// lit faces first (with every sub-case of which are dark), then the general rule.
pub fn candidates(src: &Source) -> Vec<Candidate> {
    let lit: Vec<Dir> = Dir::ALL.into_iter().filter(|&d| src.lit[d.index()]).collect();
    let dark: Vec<Dir> = lit.iter().copied().filter(|&d| src.dark(d)).collect();
    let mut out = Vec::new();
    if dark.is_empty() {
        return out;
    }
    let distinct_axes = lit.iter().map(|d| 1u8 << d.axis()).fold(0u8, |m, b| m | b).count_ones() as usize == lit.len();
    let inv = |ds: &[Dir]| -> ([Dir; 3], usize) {
        let mut a = [Dir::Left; 3];
        for (o, d) in a.iter_mut().zip(ds) {
            *o = d.inverse();
        }
        (a, ds.len())
    };
    let mut push = |faces: Faces, rule: Rule| {
        let (dirs, n) = inv(&lit);
        out.push(Candidate { dirs, n, faces, rule });
    };
    if distinct_axes {
        let dark_bits = dark.iter().fold(0, |m, &d| m | bit(d));
        match (lit.len(), dark.len()) {
            (1, 1) => push(ALL_FACES, Rule::OneFace),
            (2, 2) => push(ALL_FACES, Rule::TwoFacesBothDark),
            (2, 1) => push(dark_bits, Rule::TwoFacesOneDark),
            (3, 3) => push(ALL_FACES, Rule::ThreeFacesAllDark),
            (3, 2) => push(dark_bits, Rule::ThreeFacesTwoDark),
            (3, 1) => push(dark_bits, Rule::ThreeFacesOneDark),
            _ => {}
        }
    }
    if dark.len() == lit.len() {
        for &f in &lit {
            out.push(Candidate { dirs: [f.inverse(), Dir::Left, Dir::Left], n: 1, faces: bit(f), rule: Rule::General });
        }
    }
    out
}
