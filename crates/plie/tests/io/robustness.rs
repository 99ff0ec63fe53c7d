//! No input makes a loader panic: randomly damaged OBJ, MTL, glTF, GLB and PFM files (fixed seeds via
//! proptest's persisted defaults) must give `Ok` or `Err`, never a panic.

use plie::io::image::decode_pfm;
use proptest::prelude::*;
use serde_json::Value;

use super::load_from;

const OBJ: &str = "mtllib l.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1\ng floor\nusemtl grey\nf 1 2 3 4\n\
                   usemtl lamp\nf -1 -2/1 -3//2\nf 1 3 4\n";
const MTL: &str = "newmtl grey\nKd 0.5 0.5 0.5 # c\nKa 1\nnewmtl lamp\nKe 1 2 3\nd 1\nTr 0\n";
const TOKENS: &[&str] = &[
    " ",
    "\n",
    "\r",
    "#",
    "/",
    "//",
    "-",
    "0",
    "1",
    "-1",
    "99999999999999999999",
    "nan",
    "inf",
    "1e39",
    "0.5",
    "v",
    "vt",
    "vn",
    "f",
    "l",
    "p",
    "o",
    "g",
    "usemtl",
    "mtllib",
    "newmtl",
    "Kd",
    "Ke",
    "Ka",
    "lamp",
    "l.mtl",
    "\u{e9}",
    "\t",
];

/// One damage to a text: truncate, delete a range, insert a token, or overwrite a byte.
#[derive(Clone, Debug)]
enum Damage {
    Truncate(usize),
    Delete(usize, usize),
    Insert(usize, usize),
    Byte(usize, u8),
}

fn damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        any::<usize>().prop_map(Damage::Truncate),
        (any::<usize>(), 1usize..8).prop_map(|(a, n)| Damage::Delete(a, n)),
        (any::<usize>(), 0..TOKENS.len()).prop_map(|(a, t)| Damage::Insert(a, t)),
        (any::<usize>(), any::<u8>()).prop_map(|(a, b)| Damage::Byte(a, b)),
    ]
}

fn apply(text: &str, damages: &[Damage]) -> Vec<u8> {
    let mut b = text.as_bytes().to_vec();
    for d in damages {
        let at = |a: usize, len: usize| if len == 0 { 0 } else { a % (len + 1) };
        match *d {
            Damage::Truncate(a) => b.truncate(at(a, b.len())),
            Damage::Delete(a, n) => {
                let s = at(a, b.len());
                b.drain(s..(s + n).min(b.len()));
            }
            Damage::Insert(a, t) => {
                let s = at(a, b.len());
                b.splice(s..s, TOKENS[t].bytes());
            }
            Damage::Byte(a, v) if !b.is_empty() => {
                let s = a % b.len();
                b[s] = v;
            }
            Damage::Byte(..) => {}
        }
    }
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn damaged_obj_never_panics(d in prop::collection::vec(damage(), 1..6)) {
        let obj = apply(OBJ, &d);
        let _ = load_from(&[("t.obj", &obj), ("l.mtl", MTL.as_bytes())], "t.obj");
    }

    #[test]
    fn damaged_mtl_never_panics(d in prop::collection::vec(damage(), 1..6)) {
        let mtl = apply(MTL, &d);
        let _ = load_from(&[("t.obj", OBJ.as_bytes()), ("l.mtl", &mtl)], "t.obj");
    }

    #[test]
    fn damaged_gltf_never_panics(edits in prop::collection::vec((0..POINTERS.len(), 0..VALUES.len()), 1..4)) {
        let mut doc = super::gltf::embedded_document();
        let values = values();
        for (p, v) in edits {
            if let Some(slot) = doc.pointer_mut(POINTERS[p]) {
                *slot = values[v].clone();
            }
        }
        let _ = load_from(&[("s.gltf", doc.to_string().as_bytes())], "s.gltf");
    }

    #[test]
    fn damaged_glb_never_panics(cut in any::<usize>(), flips in prop::collection::vec((any::<usize>(), any::<u8>()), 0..4)) {
        let mut bytes = super::gltf::glb_file();
        for (at, v) in flips {
            let i = at % bytes.len();
            bytes[i] = v;
        }
        bytes.truncate(cut % (bytes.len() + 1));
        let _ = load_from(&[("s.glb", &bytes)], "s.glb");
    }

    #[test]
    fn random_pfm_never_panics(header in 0..4usize, body in prop::collection::vec(any::<u8>(), 0..64)) {
        let mut bytes = ["PF\n2 1\n-1.0\n", "Pf\n1 1\n1\n", "PF 4294967295 4294967295 -1 ", ""][header].as_bytes().to_vec();
        bytes.extend(body);
        let _ = decode_pfm(&bytes);
    }
}

const POINTERS: &[&str] = &[
    "/accessors/0/count",
    "/accessors/0/byteOffset",
    "/accessors/0/componentType",
    "/accessors/0/type",
    "/accessors/2/count",
    "/accessors/2/componentType",
    "/accessors/3/byteOffset",
    "/bufferViews/0/byteOffset",
    "/bufferViews/0/byteLength",
    "/bufferViews/1/byteStride",
    "/buffers/0/byteLength",
    "/buffers/0/uri",
    "/meshes/0/primitives/0/mode",
    "/meshes/1/primitives/0/indices",
    "/nodes/1/scale",
    "/nodes/1/children",
    "/nodes/2/rotation",
    "/cameras/0/perspective/yfov",
    "/materials/1/emissiveFactor",
    "/scene",
];

fn values() -> Vec<Value> {
    VALUES.iter().map(|v| serde_json::from_str(v).unwrap()).collect()
}

const VALUES: &[&str] = &[
    "0",
    "1",
    "-1",
    "3",
    "7",
    "4294967295",
    "18446744073709551615",
    "1e20",
    "3.5",
    "null",
    "\"VEC4\"",
    "\"SCALAR\"",
    "5121",
    "5125",
    "5126",
    "[0, 0, 0]",
    "[1]",
    "[2]",
    "[0, 0, 0, 0]",
    "\"%FF.bin\"",
    "\"missing.bin\"",
    "\"data:application/octet-stream;base64,@@@\"",
];

#[test]
fn the_values_parse() {
    assert_eq!(values().len(), VALUES.len());
}
