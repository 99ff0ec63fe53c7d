//! glTF 2.0 export of an inspection (`plie inspect -o OUT.gltf|OUT.glb`): the same content as the
//! inspect picture ([`crate::inspect::overlay`]) as coloured meshes any glTF viewer opens.
//!
//! Meshes (and one node each, of the same name):
//! - `scene`: the scene's triangles except the blockers, one primitive per material (base colour =
//!   albedo; lights emissive, radiance as `emissiveFactor` x `KHR_materials_emissive_strength`).
//! - `blockers`: the blockers of the faces shown, [`BLOCKER_REST_COLOUR`]; `clipped blockers`: their
//!   parts in the shafts of the faces shown (§4.4 step 3), [`BLOCKER_COLOUR`], once on each side of
//!   the blocker, a hair off it, so they show over it from either side.
//! - `octree leaves`: every leaf edge once (mode LINES), [`LEAF_COLOUR`], except the inspected leaf's;
//!   `leaf N`: the inspected leaf's 12 edges, [`HIGHLIGHT_COLOUR`].
//! - `umbra FACE` / `penumbra FACE` per face shown (when not empty): the region triangles, lifted a
//!   thousandth of the leaf's size off the face to the outside, [`UMBRA_COLOUR`] / [`PENUMBRA_COLOUR`].
//! - a `camera` node with the image's camera, when one is given.
//!
//! Markers (lines and regions) are unlit (`KHR_materials_unlit`, base colour as is) and every material
//! is double-sided. Positions only (viewers compute flat normals), no indices. `.gltf` embeds the
//! buffer as a base64 data URI (one self-contained file); `.glb` is the binary container written by the
//! `gltf` crate. The JSON is made with `gltf::json` (gltf-json, the crate the loader reads with), and
//! the file is written atomically.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashSet};
use std::path::Path;

use glam::{Mat3, Quat, Vec3};
use gltf::json::{self, validation::Checked::Valid, validation::USize64, Index};

use super::atomic::write_atomic;
use crate::error::{Error, Result};
use crate::inspect::overlay::box_edges;
use crate::inspect::{
    Inspection, BLOCKER_COLOUR, BLOCKER_LIFT, BLOCKER_REST_COLOUR, HIGHLIGHT_COLOUR, LEAF_COLOUR, PENUMBRA_COLOUR,
    REGION_LIFT, UMBRA_COLOUR,
};
use crate::octree::Octree;
use crate::scene::{Camera, Scene};

/// The glTF container, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GltfFormat {
    /// `.gltf`: JSON with the buffer embedded as a data URI.
    Gltf,
    /// `.glb`: binary glTF.
    Glb,
}

impl GltfFormat {
    /// The format for a path's extension (case-insensitive), `None` for any other extension.
    pub fn from_path(path: &Path) -> Option<GltfFormat> {
        match path.extension()?.to_string_lossy().to_ascii_lowercase().as_str() {
            "gltf" => Some(GltfFormat::Gltf),
            "glb" => Some(GltfFormat::Glb),
            _ => None,
        }
    }
}

/// Writes `ins` (with the scene and the octree's leaves) to `path` as `.gltf` or `.glb`, atomically.
/// `camera`, with the image's aspect ratio, becomes the file's camera.
pub fn save_inspection_gltf(
    path: &Path,
    scene: &Scene,
    octree: &Octree,
    ins: &Inspection,
    camera: Option<(&Camera, f32)>,
) -> Result<()> {
    let format = GltfFormat::from_path(path).ok_or_else(|| {
        let ext = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
        Error::InvalidParameter(format!("{}: unknown glTF format '.{ext}'; supported: .gltf, .glb", path.display()))
    })?;
    let size = scene.scale().max(octree.root_bounds().size().max_element());
    let mut b = Builder::default();
    b.root.asset.generator = Some(format!("plie {} inspect", env!("CARGO_PKG_VERSION")));
    b.root.extensions_used.push("KHR_materials_unlit".into());
    b.scene_mesh(scene, ins);
    b.blocker_meshes(scene, ins, size * BLOCKER_LIFT);
    b.leaf_meshes(octree, ins);
    b.region_meshes(ins);
    if let Some((c, aspect)) = camera {
        b.camera(c, aspect, size);
    }
    let nodes: Vec<Index<json::Node>> = (0..b.root.nodes.len() as u32).map(Index::new).collect();
    let name = format!("plie inspect: {}, leaf {}, light {}", scene.name, ins.leaf.0, ins.light.0);
    let s = b.root.push(json::Scene { extensions: None, extras: Default::default(), name: Some(name), nodes });
    b.root.scene = Some(s);
    b.write(path, format)
}

/// Accumulates the JSON document and its one binary buffer.
#[derive(Default)]
struct Builder {
    root: json::Root,
    bin: Vec<u8>,
}

impl Builder {
    /// The scene's triangles, blockers left out, one primitive per material.
    fn scene_mesh(&mut self, scene: &Scene, ins: &Inspection) {
        let mut by_material: Vec<Vec<Vec3>> = vec![Vec::new(); scene.materials.len()];
        let mut is_blocker = vec![false; scene.triangles.len()];
        ins.blockers.iter().for_each(|t| is_blocker[t.idx()] = true);
        for (t, tri) in scene.triangles.iter().enumerate().filter(|(t, _)| !is_blocker[*t]) {
            by_material[scene.tri_material[t].idx()].extend(tri.v);
        }
        let mut prims = Vec::new();
        for (m, pos) in scene.materials.iter().zip(&by_material).filter(|(_, p)| !p.is_empty()) {
            let mat = self.material(&m.name, m.albedo, false, m.emission);
            prims.push(self.primitive(pos, json::mesh::Mode::Triangles, mat));
        }
        self.mesh("scene", prims);
    }

    /// The blockers, and their clipped parts `off` to either side of them.
    fn blocker_meshes(&mut self, scene: &Scene, ins: &Inspection, off: f32) {
        let blockers: Vec<Vec3> = ins.blockers.iter().flat_map(|t| scene.triangle(*t).v).collect();
        self.single("blockers", &blockers, json::mesh::Mode::Triangles, BLOCKER_REST_COLOUR, false);
        let mut clipped = Vec::new();
        for (t, poly) in ins.faces.iter().flat_map(|f| &f.clipped) {
            let n = scene.triangle(*t).normal();
            for side in [off, -off] {
                for i in 1..poly.len() - 1 {
                    clipped.extend([poly[0], poly[i], poly[i + 1]].map(|p| p + n * side));
                }
            }
        }
        self.single("clipped blockers", &clipped, json::mesh::Mode::Triangles, BLOCKER_COLOUR, false);
    }

    /// Every leaf edge once, and the inspected leaf's edges.
    fn leaf_meshes(&mut self, octree: &Octree, ins: &Inspection) {
        let mut seen = HashSet::new();
        let mut lines = Vec::new();
        for leaf in octree.leaves().filter(|&l| l != ins.leaf) {
            for (p, q) in box_edges(&octree.leaf_bounds(leaf)) {
                if seen.insert((p.to_array().map(f32::to_bits), q.to_array().map(f32::to_bits))) {
                    lines.extend([p, q]);
                }
            }
        }
        self.single("octree leaves", &lines, json::mesh::Mode::Lines, LEAF_COLOUR, true);
        let leaf_lines: Vec<Vec3> = box_edges(&ins.bounds).into_iter().flat_map(|(p, q)| [p, q]).collect();
        self.single(&format!("leaf {}", ins.leaf.0), &leaf_lines, json::mesh::Mode::Lines, HIGHLIGHT_COLOUR, true);
    }

    /// Umbra and penumbra of each face shown, lifted off the face to the outside.
    fn region_meshes(&mut self, ins: &Inspection) {
        let lift = ins.bounds.size().max_element() * REGION_LIFT;
        for f in &ins.faces {
            let n = f.face.normal();
            for (what, tris, colour, h) in
                [("penumbra", &f.penumbra, PENUMBRA_COLOUR, lift), ("umbra", &f.umbra, UMBRA_COLOUR, 2.0 * lift)]
            {
                let pos: Vec<Vec3> = tris.iter().flat_map(|t| t.map(|p| p + n * h)).collect();
                self.single(&format!("{what} {}", f.face.name()), &pos, json::mesh::Mode::Triangles, colour, true);
            }
        }
    }

    /// A material: lit (albedo as base colour, optional emission) or unlit; always double-sided.
    fn material(&mut self, name: &str, colour: Vec3, unlit: bool, emission: Vec3) -> Index<json::Material> {
        let mut m = json::Material { name: Some(name.to_string()), double_sided: true, ..Default::default() };
        let c = colour.clamp(Vec3::ZERO, Vec3::ONE);
        m.pbr_metallic_roughness.base_color_factor = json::material::PbrBaseColorFactor([c.x, c.y, c.z, 1.0]);
        m.pbr_metallic_roughness.metallic_factor = json::material::StrengthFactor(0.0);
        m.pbr_metallic_roughness.roughness_factor = json::material::StrengthFactor(1.0);
        let mut ext = json::extensions::material::Material::default();
        if unlit {
            ext.unlit = Some(json::extensions::material::Unlit {});
        }
        let strength = emission.max_element();
        if strength > 0.0 {
            m.emissive_factor = json::material::EmissiveFactor((emission / strength.max(1.0)).to_array());
            if strength > 1.0 {
                if !self.root.extensions_used.iter().any(|e| e == "KHR_materials_emissive_strength") {
                    self.root.extensions_used.push("KHR_materials_emissive_strength".into());
                }
                ext.emissive_strength = Some(json::extensions::material::EmissiveStrength {
                    emissive_strength: json::extensions::material::EmissiveStrengthFactor(strength),
                });
            }
        }
        if ext.unlit.is_some() || ext.emissive_strength.is_some() {
            m.extensions = Some(ext);
        }
        self.root.push(m)
    }

    /// A primitive of `pos` (non-indexed) drawn in `mode` with `material`.
    fn primitive(
        &mut self,
        pos: &[Vec3],
        mode: json::mesh::Mode,
        material: Index<json::Material>,
    ) -> json::mesh::Primitive {
        let offset = self.bin.len();
        pos.iter().flat_map(|p| p.to_array()).for_each(|c| self.bin.extend_from_slice(&c.to_le_bytes()));
        let view = self.root.push(json::buffer::View {
            buffer: Index::new(0),
            byte_length: USize64::from(pos.len() * 12),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            extensions: None,
            extras: Default::default(),
            name: None,
            target: Some(Valid(json::buffer::Target::ArrayBuffer)),
        });
        let lo = pos.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let hi = pos.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        let accessor = self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(pos.len()),
            component_type: Valid(json::accessor::GenericComponentType(json::accessor::ComponentType::F32)),
            extensions: None,
            extras: Default::default(),
            type_: Valid(json::accessor::Type::Vec3),
            min: Some(json::Value::from(lo.to_array().to_vec())),
            max: Some(json::Value::from(hi.to_array().to_vec())),
            name: None,
            normalized: false,
            sparse: None,
        });
        json::mesh::Primitive {
            attributes: BTreeMap::from([(Valid(json::mesh::Semantic::Positions), accessor)]),
            extensions: None,
            extras: Default::default(),
            indices: None,
            material: Some(material),
            mode: Valid(mode),
            targets: None,
        }
    }

    /// A mesh named `name` and a node showing it; nothing when there are no primitives.
    fn mesh(&mut self, name: &str, primitives: Vec<json::mesh::Primitive>) {
        if primitives.is_empty() {
            return;
        }
        let mesh = self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(name.to_string()),
            primitives,
            weights: None,
        });
        self.root.push(json::Node { mesh: Some(mesh), name: Some(name.to_string()), ..Default::default() });
    }

    /// A one-primitive mesh of one colour (named like the mesh); nothing when `pos` is empty.
    fn single(&mut self, name: &str, pos: &[Vec3], mode: json::mesh::Mode, colour: Vec3, unlit: bool) {
        if pos.is_empty() {
            return;
        }
        let m = self.material(name, colour, unlit, Vec3::ZERO);
        let p = self.primitive(pos, mode, m);
        self.mesh(name, vec![p]);
    }

    /// A perspective camera node: glTF cameras look down their local -z with +y up.
    fn camera(&mut self, c: &Camera, aspect: f32, scale: f32) {
        let forward = (c.target - c.eye).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        let rotation = Quat::from_mat3(&Mat3::from_cols(right, up, -forward)).normalize();
        let cam = self.root.push(json::Camera {
            name: Some("camera".into()),
            orthographic: None,
            perspective: Some(json::camera::Perspective {
                aspect_ratio: Some(aspect),
                yfov: c.fov_deg.to_radians(),
                zfar: None,
                znear: scale * 1e-3,
                extensions: None,
                extras: Default::default(),
            }),
            type_: Valid(json::camera::Type::Perspective),
            extensions: None,
            extras: Default::default(),
        });
        self.root.push(json::Node {
            camera: Some(cam),
            name: Some("camera".into()),
            rotation: Some(json::scene::UnitQuaternion(rotation.to_array())),
            translation: Some(c.eye.to_array()),
            ..Default::default()
        });
    }

    /// Finishes the buffer and writes the file.
    fn write(mut self, path: &Path, format: GltfFormat) -> Result<()> {
        let uri = match format {
            GltfFormat::Gltf => Some(format!("data:application/octet-stream;base64,{}", base64::encode(&self.bin))),
            GltfFormat::Glb => None,
        };
        self.root.push(json::Buffer {
            byte_length: USize64::from(self.bin.len()),
            name: None,
            uri,
            extensions: None,
            extras: Default::default(),
        });
        let io = |e: std::io::Error| Error::Io { path: path.to_path_buf(), source: e };
        let json = self.root.to_vec().map_err(|e| io(std::io::Error::other(e)))?;
        write_atomic(path, |w| match format {
            GltfFormat::Gltf => w.write_all(&json).map_err(io),
            GltfFormat::Glb => {
                let glb = gltf::binary::Glb {
                    header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
                    json: Cow::Borrowed(&json),
                    bin: Some(Cow::Borrowed(&self.bin)),
                };
                glb.to_writer(w).map_err(|e| io(std::io::Error::other(e.to_string())))
            }
        })
    }
}
