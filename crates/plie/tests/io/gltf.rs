//! glTF 2.0 loading: documents are generated here (a floor quad and a quad light, with a camera), as
//! `.gltf` with an embedded or external buffer and as `.glb`, then broken in one way per test.

use glam::Vec3;
use plie::io::load_scene;
use serde_json::{json, Value};

use super::{load_from, parse_error, temp_files};

/// Floor quad (y = 0, facing up) then light quad (local y = 0, facing down): positions, then u16
/// indices.
fn buffer() -> Vec<u8> {
    let floor = [[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 0.0, -1.0]];
    let light = [[-0.5, 0.0, -0.5], [0.5, 0.0, -0.5], [0.5, 0.0, 0.5], [-0.5, 0.0, 0.5]];
    let mut b: Vec<u8> = floor.iter().chain(&light).flatten().flat_map(|x: &f32| x.to_le_bytes()).collect();
    b.extend([0u16, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    assert_eq!(b.len(), 120);
    b
}

fn data_uri() -> String {
    format!("data:application/octet-stream;base64,{}", base64::encode(buffer()))
}

/// The document; `buffer` is the buffer object (its `uri`, if any, and `byteLength`).
fn document(buffer: Value) -> Value {
    let vec3 = |offset: usize, h: f32| {
        json!({"bufferView": 0, "byteOffset": offset, "count": 4, "type": "VEC3", "componentType": 5126,
               "min": [-h, 0.0, -h], "max": [h, 0.0, h]})
    };
    let scalar = |offset: usize| json!({"bufferView": 1, "byteOffset": offset, "count": 6, "type": "SCALAR", "componentType": 5123});
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "buffers": [buffer],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96}, {"buffer": 0, "byteOffset": 96, "byteLength": 24}],
        "accessors": [vec3(0, 1.0), vec3(48, 0.5), scalar(0), scalar(12)],
        "materials": [
            {"name": "grey", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 2.0, 1.0]}},
            {"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.25],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8.0}}}
        ],
        "meshes": [
            {"name": "floor", "primitives": [{"attributes": {"POSITION": 0}, "indices": 2, "material": 0}]},
            {"name": "lamp", "primitives": [{"attributes": {"POSITION": 1}, "indices": 3, "material": 1}]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}],
        "nodes": [
            {"mesh": 0},
            {"mesh": 1, "translation": [0.0, 2.0, 0.0]},
            {"camera": 0, "translation": [0.0, 1.0, 5.0]}
        ],
        "scenes": [{"nodes": [0, 1, 2]}],
        "scene": 0
    })
}

fn embedded() -> Value {
    document(json!({"uri": data_uri(), "byteLength": 120}))
}

/// The embedded-buffer document, for other test modules.
pub fn embedded_document() -> Value {
    embedded()
}

/// The same scene as a `.glb` file, for other test modules.
pub fn glb_file() -> Vec<u8> {
    glb(&document(json!({"byteLength": 120})), &buffer())
}

fn load_json(doc: &Value) -> plie::Result<plie::Scene> {
    load_from(&[("s.gltf", doc.to_string().as_bytes())], "s.gltf")
}

fn check_scene(s: &plie::Scene) {
    assert_eq!((s.triangle_count(), s.lights.len()), (4, 1));
    let l = &s.lights[0];
    assert_eq!(l.vertices.len(), 4);
    assert!(l.vertices.iter().all(|v| v.y == 2.0), "node translation applied: {:?}", l.vertices);
    assert!((l.normal - Vec3::NEG_Y).length() < 1e-6);
    assert_eq!(l.radiance, Vec3::new(8.0, 4.0, 2.0), "emissiveFactor x emissiveStrength");
    let grey = s.materials.iter().find(|m| m.name == "grey").unwrap();
    assert_eq!(grey.albedo, Vec3::new(0.5, 0.25, 1.0), "base colour, clamped");
    let c = s.camera.expect("the file's camera");
    assert_eq!(c.eye, Vec3::new(0.0, 1.0, 5.0));
    assert!((c.target - Vec3::new(0.0, 1.0, 4.0)).length() < 1e-6, "looks along -z");
    assert_eq!(c.up, Vec3::Y);
    assert!((c.fov_deg - 0.7f32.to_degrees()).abs() < 1e-4);
}

#[test]
fn embedded_buffer() {
    let s = load_json(&embedded()).unwrap();
    assert_eq!(s.name, "s");
    check_scene(&s);
}

/// glTF's default metallic factor is 1: a material that does not set it to 0 would look metallic in
/// a glTF viewer, so the loader says plie shades it as diffuse; the same for textures.
#[test]
fn metallic_roughness_and_textures_are_reported() {
    let s = load_json(&embedded()).unwrap();
    assert_eq!(s.warnings.len(), 1, "{:?}", s.warnings);
    let w = &s.warnings[0];
    assert!(w.starts_with("materials 'grey', 'lamp': metallic-roughness is not rendered"), "{w}");

    let mut doc = embedded();
    doc["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(0.0);
    doc["materials"][1]["pbrMetallicRoughness"] = json!({"metallicFactor": 0.0});
    assert!(load_json(&doc).unwrap().warnings.is_empty());

    doc["materials"][1]["emissiveTexture"] = json!({"index": 0});
    doc["textures"] = json!([{"source": 0}]);
    doc["images"] = json!([{"uri": format!("data:image/png;base64,{}", base64::encode(stripes_png()))}]);
    let s = load_json(&doc).unwrap();
    assert_eq!(s.warnings, ["material 'lamp': emissive textures are not rendered: the flat emissive factor is used"]);
}

/// The 4x4 stripes texture of the Mitsuba test data: columns red, white, blue, white; the top row
/// at half the value.
fn stripes_png() -> Vec<u8> {
    std::fs::read(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba/stripes.png")).unwrap()
}

/// The floor with `baseColorTexture` and `TEXCOORD_0` (a second buffer): the albedo at a point is the
/// base colour factor times the sRGB-decoded texel there (glTF: uv (0, 0) is the image's top left).
#[test]
fn base_color_texture() {
    let srgb = |c: f32| plie::scene::texture::srgb_to_linear(c / 255.0);
    let uv: Vec<u8> =
        [[0.0f32, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]].iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let mut doc = embedded();
    doc["buffers"].as_array_mut().unwrap().push(
        json!({"uri": format!("data:application/octet-stream;base64,{}", base64::encode(&uv)), "byteLength": 32}),
    );
    doc["bufferViews"].as_array_mut().unwrap().push(json!({"buffer": 1, "byteOffset": 0, "byteLength": 32}));
    doc["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": 2, "count": 4, "type": "VEC2", "componentType": 5126}));
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(4);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    doc["textures"] = json!([{"source": 0, "sampler": 0}]);
    doc["samplers"] = json!([{"magFilter": 9728, "wrapS": 33071, "wrapT": 33648}]);
    doc["images"] = json!([{"uri": "stripes.png"}]);
    let text = doc.to_string();
    let s = load_from(&[("s.gltf", text.as_bytes()), ("stripes.png", &stripes_png())], "s.gltf").unwrap();
    assert_eq!(s.textures.len(), 1);
    let t = &s.textures[0];
    assert_eq!(t.filter, plie::scene::texture::Filter::Nearest);
    assert_eq!(t.wrap, [plie::scene::texture::Wrap::Clamp, plie::scene::texture::Wrap::Mirror]);
    let factor = Vec3::new(0.5, 0.25, 1.0);
    let top_left = s.albedo_at(plie::TriId(0), Vec3::new(-0.8, 0.0, -0.8));
    assert_eq!(top_left, factor * Vec3::new(srgb(100.0), srgb(20.0), srgb(15.0)), "dark red, top row");
    let lower = s.albedo_at(plie::TriId(0), Vec3::new(0.1, 0.0, 0.5));
    assert_eq!(lower, factor * Vec3::new(srgb(40.0), srgb(70.0), srgb(200.0)), "blue column, lower rows");

    // Without TEXCOORD_0: a warning, and the flat factor.
    let mut flat = doc.clone();
    flat["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("TEXCOORD_0");
    let text = flat.to_string();
    let s = load_from(&[("s.gltf", text.as_bytes()), ("stripes.png", &stripes_png())], "s.gltf").unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("without its TEXCOORD")), "{:?}", s.warnings);
    assert_eq!(s.albedo_at(plie::TriId(0), Vec3::new(-0.8, 0.0, -0.8)), factor);

    // A missing image or one outside the folder is an error naming it.
    let text = doc.to_string();
    let e = parse_error(load_from(&[("s.gltf", text.as_bytes())], "s.gltf"), "s.gltf", None);
    assert!(e.contains("image 0"), "{e}");
    doc["images"] = json!([{"uri": "../../etc/passwd"}]);
    let text = doc.to_string();
    let e = parse_error(load_from(&[("s.gltf", text.as_bytes())], "s.gltf"), "s.gltf", None);
    assert!(e.contains("outside the scene's folder"), "{e}");
}

#[test]
fn external_buffer_and_missing_buffer() {
    let doc = document(json!({"uri": "data.bin", "byteLength": 120}));
    let text = doc.to_string();
    let s = load_from(&[("s.gltf", text.as_bytes()), ("data.bin", &buffer())], "s.gltf").unwrap();
    check_scene(&s);
    let msg = parse_error(load_from(&[("s.gltf", text.as_bytes())], "s.gltf"), "s.gltf", None);
    assert!(msg.contains("data.bin") && msg.contains("buffer 0"), "{msg}");
    let msg = parse_error(
        load_from(&[("s.gltf", text.as_bytes()), ("data.bin", &buffer()[..100])], "s.gltf"),
        "s.gltf",
        None,
    );
    assert!(msg.contains("100 bytes"), "{msg}");
}

/// A GLB container: header, JSON chunk, BIN chunk (each padded to 4 bytes).
fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = json.to_string().into_bytes();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&j);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

#[test]
fn binary_glb() {
    let bytes = glb(&document(json!({"byteLength": 120})), &buffer());
    check_scene(&load_from(&[("s.glb", &bytes)], "s.glb").unwrap());
    let msg = parse_error(load_from(&[("t.glb", &bytes[..bytes.len() - 30])], "t.glb"), "t.glb", None);
    assert!(!msg.is_empty());
}

#[test]
fn glb_length_must_be_the_files() {
    let bytes = glb_file();
    let n = bytes.len();
    // Bytes after the GLB's end were ignored; now they are an error, as a truncated file is.
    let mut longer = bytes.clone();
    longer.extend([0u8; 4]);
    let msg = parse_error(load_from(&[("s.glb", &longer)], "s.glb"), "s.glb", None);
    assert!(msg.contains(&format!("GLB header says {n} bytes, but the file has {}", n + 4)), "{msg}");
    let mut header = bytes.clone();
    header[8..12].copy_from_slice(&(n as u32 - 4).to_le_bytes());
    let msg = parse_error(load_from(&[("s.glb", &header)], "s.glb"), "s.glb", None);
    assert!(msg.contains(&format!("GLB header says {} bytes, but the file has {n}", n - 4)), "{msg}");
    header[8..12].copy_from_slice(&(n as u32 + 4).to_le_bytes());
    let msg = parse_error(load_from(&[("s.glb", &header)], "s.glb"), "s.glb", None);
    assert!(msg.contains(&format!("GLB header says {} bytes, but the file has {n}", n + 4)), "{msg}");
}

#[test]
fn inputs_the_gltf_crate_would_panic_on() {
    // A GLB length field smaller than the header underflows inside the crate.
    let mut bytes = glb_file();
    bytes[8..12].copy_from_slice(&5u32.to_le_bytes());
    let msg = parse_error(load_from(&[("s.glb", &bytes)], "s.glb"), "s.glb", None);
    assert!(msg.contains("GLB header says 5 bytes"), "{msg}");
    // A relative URI that is not UTF-8 after percent-decoding makes the crate unwrap an error.
    let doc = document(json!({"uri": "%FF.bin", "byteLength": 120}));
    let msg = parse_error(load_json(&doc), "s.gltf", None);
    assert!(msg.contains("percent-decoding"), "{msg}");
}

#[test]
fn non_indexed_fan_and_mirrored_node() {
    let mut doc = embedded();
    doc["meshes"][1]["primitives"][0] = json!({"attributes": {"POSITION": 1}, "material": 1, "mode": 6});
    let s = load_json(&doc).unwrap();
    assert_eq!((s.triangle_count(), s.lights[0].vertices.len()), (4, 4));
    assert!((s.lights[0].normal - Vec3::NEG_Y).length() < 1e-6);
    // A mirroring node transform (negative determinant) flips the winding: the mirrored light faces up.
    let mut doc = embedded();
    doc["nodes"][1]["scale"] = json!([1.0, -1.0, 1.0]);
    let s = load_json(&doc).unwrap();
    assert!((s.lights[0].normal - Vec3::Y).length() < 1e-6, "{}", s.lights[0].normal);
}

#[test]
fn without_strength_or_camera() {
    let mut doc = embedded();
    doc["materials"][1].as_object_mut().unwrap().remove("extensions");
    doc["scenes"][0]["nodes"] = json!([0, 1]);
    let s = load_json(&doc).unwrap();
    assert_eq!(s.lights[0].radiance, Vec3::new(1.0, 0.5, 0.25));
    assert!(s.camera.is_none());
}

#[test]
fn camera_orientation_and_parent_transforms() {
    // The camera hangs under a parent turned 90 degrees about +y and moved: it looks along -x.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let mut doc = embedded();
    let parent = json!({"rotation": [0.0, h, 0.0, h], "translation": [10.0, 0.0, 0.0], "children": [2]});
    doc["nodes"].as_array_mut().unwrap().push(parent);
    doc["scenes"][0]["nodes"] = json!([0, 1, 3]);
    let c = load_json(&doc).unwrap().camera.unwrap();
    assert!((c.eye - Vec3::new(15.0, 1.0, 0.0)).length() < 1e-5, "{}", c.eye);
    assert!((c.target - c.eye - Vec3::NEG_X).length() < 1e-5, "{}", c.target - c.eye);
    assert!((c.up - Vec3::Y).length() < 1e-5);
    // A full matrix works like TRS: the light moved up by a column-major translation.
    let mut doc = embedded();
    doc["nodes"][1] = json!({"mesh": 1, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,3,0,1]});
    let s = load_json(&doc).unwrap();
    assert!(s.lights[0].vertices.iter().all(|v| v.y == 3.0));
}

#[test]
fn malformed_json() {
    let text = "{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [ {\"mesh\": 0,,} ]\n}";
    let msg = parse_error(load_from(&[("s.gltf", text.as_bytes())], "s.gltf"), "s.gltf", Some(3));
    assert!(msg.contains("malformed glTF JSON"), "{msg}");
    let msg = parse_error(load_from(&[("e.gltf", b"")], "e.gltf"), "e.gltf", None);
    assert!(msg.contains("empty"), "{msg}");
    let mut doc = embedded();
    doc["nodes"][0]["mesh"] = json!(7);
    let msg = parse_error(load_json(&doc), "s.gltf", None);
    assert!(msg.contains("invalid glTF"), "{msg}");
    // Geometry in an extension plie cannot decode.
    let mut doc = embedded();
    doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    let msg = parse_error(load_json(&doc), "s.gltf", None);
    assert!(msg.contains("extensionsRequired") && msg.contains("KHR_draco_mesh_compression"), "{msg}");
}

#[test]
fn non_triangle_mode() {
    let mut doc = embedded();
    doc["meshes"][0]["primitives"][0]["mode"] = json!(1);
    let msg = parse_error(load_json(&doc), "s.gltf", None);
    assert!(msg.contains("mesh 'floor'") && msg.contains("not a triangle mode"), "{msg}");
}

#[test]
fn bad_accessors_are_errors_not_panics() {
    let cases: [(&str, Value, &str); 5] = [
        ("/accessors/1/count", json!(2), "out of range"),
        ("/accessors/0/count", json!(100), "past the end of bufferView 0"),
        ("/accessors/0/type", json!("VEC2"), "expected Vec3 of F32"),
        ("/accessors/2/componentType", json!(5126), "expected Scalar"),
        ("/bufferViews/1/byteLength", json!(2000), "past the end of buffer 0"),
    ];
    for (pointer, value, needle) in cases {
        let mut doc = embedded();
        *doc.pointer_mut(pointer).unwrap() = value;
        let msg = parse_error(load_json(&doc), "s.gltf", None);
        assert!(msg.contains(needle), "{pointer}: {msg}");
    }
    let mut doc = embedded();
    doc["accessors"][3]["count"] = json!(5);
    let msg = parse_error(load_json(&doc), "s.gltf", None);
    assert!(msg.contains("multiple of 3"), "{msg}");
}

#[test]
fn no_lights_and_node_cycles() {
    let mut doc = embedded();
    doc["materials"][1] = json!({"name": "dull"});
    assert!(parse_error(load_json(&doc), "s.gltf", None).contains("no lights"));
    let mut doc = embedded();
    doc["nodes"][2]["children"] = json!([1]);
    match load_json(&doc) {
        Err(plie::Error::SceneElement { element: plie::SceneElement::Node(1), message, .. }) => {
            assert!(message.contains("appears twice"), "{message}")
        }
        other => panic!("expected node 1's error: {:?}", other.err()),
    }
}

#[test]
fn gltf_files_on_disk_keep_their_directory() {
    // The external buffer is found relative to the .gltf, not the working directory.
    let doc = document(json!({"uri": "sub.bin", "byteLength": 120})).to_string();
    let dir = temp_files(&[("scene.gltf", doc.as_bytes()), ("sub.bin", &buffer())]);
    assert!(load_scene(&dir.path().join("scene.gltf")).is_ok());
}
