//! Mitsuba scene files, PLY and serialized meshes and textures (issue 18): every shape, transform,
//! texture path, warning and error of `plie::io::mitsuba`, on the scenes of `tests/data/mitsuba/`
//! (written by `scripts/mitsuba_test_scenes.py`) and on small scenes written here; the same scene as
//! XML and as OBJ/MTL renders to the same image; textured images are bit-identical across visibility
//! modes; and Mitsuba 3 itself, where it is importable, renders the Cornell box to the same mean
//! radiance within 1.5%.

mod support;

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use plie::internals::lie::PlieParams;
use plie::internals::render::RenderSettings;
use plie::io::{load_scene, load_scene_with, LoadOptions};
use plie::scene::texture::srgb_to_linear;
use plie::visibility::Mode;
use plie::{Scene, TriId};
use support::Built;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba").join(name)
}

fn load(name: &str) -> Scene {
    load_scene(&data(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Renders with `mode` (a P-LIE built for the P-LIE modes) from the scene's camera.
fn image(scene: &Scene, mode: Mode, settings: &RenderSettings) -> Vec<Vec3> {
    let built = Built::new(scene, PlieParams::default());
    let vis = built.vis(scene, mode);
    let camera = scene.camera.expect("the scene has a camera");
    support::render(scene, &camera, settings, &built.bvh, Some(built.octree()), vis.as_ref())
}

fn small() -> RenderSettings {
    RenderSettings { width: 40, height: 40, eye_rays: 1, shadow_rays: 4, seed: 3 }
}

fn bits(p: &[Vec3]) -> Vec<[u32; 3]> {
    p.iter().map(|v| v.to_array().map(f32::to_bits)).collect()
}

/// A scene folder with `files` written into it (name, contents).
fn folder(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    dir
}

/// A 3.x scene: `body` plus a light, so that it loads.
fn scene3(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="4"/></transform>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
{body}
</scene>"#
    )
}

/// Loads `xml` as `scene.xml` in a folder with `files`; the error text, if any.
fn try_xml(xml: &str, files: &[(&str, &str)]) -> Result<Scene, String> {
    let mut all = files.to_vec();
    all.push(("scene.xml", xml));
    let dir = folder(&all);
    load_scene(&dir.path().join("scene.xml")).map_err(|e| e.to_string())
}

fn error(xml: &str) -> String {
    try_xml(xml, &[]).expect_err("should not load")
}

/// The triangles added after the light (2 triangles), as vertex arrays.
fn body_triangles(s: &Scene) -> Vec<[Vec3; 3]> {
    s.triangles[2..].iter().map(|t| t.v).collect()
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

#[test]
fn cornell_box_in_3x_syntax() {
    let s = load("cornell-3.xml");
    assert_eq!(s.triangle_count(), 32, "5 walls, 10 box faces, 1 light: 2 triangles each");
    assert_eq!(s.lights.len(), 1);
    assert_eq!(s.lights[0].radiance, Vec3::new(17.0, 12.0, 4.0));
    assert!(s.lights[0].normal.y < -0.99, "the light faces down: {}", s.lights[0].normal);
    assert_eq!(s.image_size, Some((128, 128)), "film size through $res");
    let c = s.camera.unwrap();
    assert!(close(c.eye, Vec3::new(0.0, 1.0, 3.8)) && close(c.up, Vec3::Y), "{c:?}");
    assert!((c.fov_deg - 39.3).abs() < 1e-3, "square film: fov_axis x is also vertical: {}", c.fov_deg);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let white = s.materials.iter().find(|m| m.name == "white").expect("the included, referenced BSDF");
    assert_eq!(white.albedo, Vec3::new(0.725, 0.71, 0.68));
}

#[test]
fn cornell_box_in_0_6_syntax_is_the_same_box() {
    let old = load("cornell-0.6.xml");
    let new = load("cornell-3.xml");
    assert_eq!(old.triangle_count(), 36, "walls and light as rectangles, the boxes as cubes (6 faces)");
    assert!(close(old.bounds.min, new.bounds.min) && close(old.bounds.max, new.bounds.max));
    assert_eq!(old.camera.map(|c| c.fov_deg), new.camera.map(|c| c.fov_deg), "fovAxis read");
    assert!(close(old.camera.unwrap().eye, new.camera.unwrap().eye), "toWorld read");
    assert_eq!(old.lights.len(), 1);
    assert!(
        close(old.lights[0].normal, new.lights[0].normal) && (old.lights[0].area - new.lights[0].area).abs() < 1e-6
    );
    let area = |s: &Scene, m: &str| -> f32 {
        (0..s.triangle_count())
            .filter(|&t| s.material_of(TriId(t as u32)).name == m)
            .map(|t| s.triangles[t].area())
            .sum()
    };
    assert!((area(&old, "red") - 4.0).abs() < 1e-4 && (area(&old, "green") - 4.0).abs() < 1e-4);
}

#[test]
fn xml_and_obj_of_one_scene_render_the_same_image() {
    let xml = load("cornell-3.xml");
    let mut obj = load("cornell.obj");
    obj.camera = xml.camera;
    let a = image(&xml, Mode::Bvh, &small());
    let b = image(&obj, Mode::Bvh, &small());
    assert!(a.iter().filter(|p| p.max_element() > 0.0).count() > 1000, "the image is lit");
    assert_eq!(bits(&a), bits(&b), "the XML and the OBJ/MTL scene render differently");
}

#[test]
fn meshes_instances_and_built_in_shapes() {
    let s = load("meshes.xml");
    // rectangle 2, disk 64, tetra.ply 4, pyramid.ply 6, serialized mesh 1 (pyramid) 6,
    // 2 instances of (cube 12 + octahedron.obj 8), sphere 960; the glass sphere is dropped.
    assert_eq!(s.triangle_count(), 2 + 64 + 4 + 6 + 6 + 2 * 20 + 960);
    assert_eq!(s.lights.len(), 1, "the disk's 64 coplanar triangles are one light");
    assert_eq!(s.lights[0].vertices.len(), 64);
    assert!((s.lights[0].area - 0.25 * std::f32::consts::PI).abs() < 0.01, "{}", s.lights[0].area);
    assert_eq!(s.image_size, Some((160, 120)));
    assert!((s.camera.unwrap().fov_deg - 50.0).abs() < 1e-4, "fov_axis y");
    // The sphere: centre (2, 0.5, 0.5), radius 0.5.
    let sphere = &s.triangles[s.triangle_count() - 960..];
    for t in sphere {
        for v in t.v {
            assert!(((v - Vec3::new(2.0, 0.5, 0.5)).length() - 0.5).abs() < 1e-5);
        }
        assert!(t.normal().dot(t.v[0] - Vec3::new(2.0, 0.5, 0.5)) > 0.0, "the sphere faces out");
    }
    // Instances: two cubes of half-size 0.2, one moved by (0.5, 0, 1).
    let cube_min = |first: usize| {
        s.triangles[first..first + 12].iter().flat_map(|t| t.v).fold(Vec3::splat(f32::MAX), |a, b| a.min(b))
    };
    let first_instance = 2 + 64 + 4 + 6 + 6;
    assert!(close(cube_min(first_instance), Vec3::new(0.3, 0.0, 0.8)), "{}", cube_min(first_instance));
    // The serialized file's second mesh (shape_index 1) is the pyramid: apex at (1, 1, -1).
    let ser = &s.triangles[2 + 64 + 4 + 6..2 + 64 + 4 + 6 + 6];
    assert!(ser.iter().flat_map(|t| t.v).any(|v| close(v, Vec3::new(1.0, 1.0, -1.0))));
}

#[test]
fn warnings_for_what_plie_changes_or_ignores() {
    let s = load("meshes.xml");
    assert_eq!(s.warnings.len(), 3, "{:#?}", s.warnings);
    let w = s.warnings.join("\n");
    assert!(w.contains("ignored 1 emitter") && w.contains("point (") && w.contains("meshes.xml:16"), "{w}");
    let changed: Vec<&String> = s.warnings.iter().filter(|w| w.contains("diffuse part")).collect();
    assert_eq!(changed.len(), 1, "one warning lists every changed material: {w}");
    assert!(
        changed[0].contains("'blue-plastic' (plastic: its diffuse reflectance")
            && changed[0].contains("'metal' (conductor: black")
    );
    assert!(w.contains("dropped 1 shape") && w.contains("glass (dielectric)"), "{w}");
    let plastic = s.materials.iter().find(|m| m.name == "blue-plastic").unwrap();
    assert_eq!(plastic.albedo, Vec3::new(0.1, 0.2, 0.7), "a plastic renders its diffuse reflectance");
    assert_eq!(s.materials.iter().find(|m| m.name == "metal").unwrap().albedo, Vec3::ZERO);
    // A glass-only scene part casts no shadow: nothing within the dropped sphere's radius.
    let inside = s.triangles.iter().flat_map(|t| t.v).any(|v| (v - Vec3::new(0.0, 0.4, 0.0)).length() < 0.39);
    assert!(!inside, "the dielectric sphere is dropped from the scene");
}

#[test]
fn point_light_alone_is_an_error_naming_it() {
    let e = error(
        r#"<scene version="3.0.0">
<shape type="cube"/>
<emitter type="point"><point name="position" value="0, 3, 0"/></emitter>
</scene>"#,
    );
    assert!(e.contains("emitter point") && e.contains(":3)") && e.contains("area lights only"), "{e}");
    for ty in ["spot", "envmap", "sun", "constant", "directional"] {
        let e = error(&format!("<scene version=\"3.0.0\"><shape type=\"cube\"/><emitter type=\"{ty}\"/></scene>"));
        assert!(e.contains(&format!("emitter {ty}")), "{e}");
    }
}

#[test]
fn every_transform_step() {
    let t = |steps: &str| -> Vec<[Vec3; 3]> {
        let s = try_xml(
            &scene3(&format!(r#"<shape type="rectangle"><transform name="to_world">{steps}</transform></shape>"#)),
            &[],
        )
        .unwrap();
        body_triangles(&s)
    };
    let v = Vec3::new;
    // The rectangle's first corner is (-1, -1, 0), its third (1, 1, 0).
    assert!(close(t(r#"<translate x="1" y="2" z="3"/>"#)[0][0], v(0.0, 1.0, 3.0)));
    assert!(close(t(r#"<translate value="1, 2, 3"/>"#)[0][0], v(0.0, 1.0, 3.0)), "3.x value form");
    assert!(close(t(r#"<scale value="2"/>"#)[0][0], v(-2.0, -2.0, 0.0)));
    assert!(close(t(r#"<scale x="2" y="3"/>"#)[0][0], v(-2.0, -3.0, 0.0)));
    assert!(close(t(r#"<rotate z="1" angle="90"/>"#)[0][0], v(1.0, -1.0, 0.0)));
    assert!(close(t(r#"<rotate value="0, 0, 1" angle="90"/>"#)[0][0], v(1.0, -1.0, 0.0)), "3.x axis as value");
    assert!(close(t(r#"<matrix value="1 0 0 5  0 1 0 0  0 0 1 0  0 0 0 1"/>"#)[0][0], v(4.0, -1.0, 0.0)), "row-major");
    assert!(close(t(r#"<scale value="2"/><translate x="1"/>"#)[0][0], v(-1.0, -2.0, 0.0)), "steps apply in order");
    let look = t(r#"<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>"#);
    assert!(close(look[0][0], v(1.0, -1.0, 5.0)), "lookat: +z toward the target, +x left: {}", look[0][0]);
    assert!(close(look[0][0].cross(Vec3::ZERO) * 0.0, Vec3::ZERO));
    // A mirroring transform keeps a rectangle facing where Mitsuba's normal points (+z here).
    let m = t(r#"<scale x="-1"/>"#);
    assert!(m.iter().all(|tri| (tri[1] - tri[0]).cross(tri[2] - tri[0]).z > 0.0));
    let f = try_xml(&scene3(r#"<shape type="rectangle"><boolean name="flip_normals" value="true"/></shape>"#), &[])
        .unwrap();
    assert!(body_triangles(&f).iter().all(|tri| (tri[1] - tri[0]).cross(tri[2] - tri[0]).z < 0.0), "flip_normals");
}

#[test]
fn defaults_substitution_include_and_ref() {
    let inc = r#"<scene version="3.0.0"><bsdf type="diffuse" id="m"><rgb name="reflectance" value="$r, 0.25, 0.5"/></bsdf></scene>"#;
    let xml = scene3(
        r#"<default name="r" value="0.75"/><include filename="inc.xml"/>
        <shape type="cube"><ref id="m"/></shape>"#,
    );
    let s = try_xml(&xml, &[("inc.xml", inc)]).unwrap();
    assert_eq!(s.materials.iter().find(|m| m.name == "m").unwrap().albedo, Vec3::new(0.75, 0.25, 0.5));
    let e = error(&scene3(
        r#"<shape type="cube"><bsdf type="diffuse"><float name="reflectance" value="$nope"/></bsdf></shape>"#,
    ));
    assert!(e.contains("$nope") && e.contains("not defined"), "{e}");
    let e = error(&scene3(r#"<shape type="cube"><ref id="missing"/></shape>"#));
    assert!(e.contains("no element has the id 'missing'"), "{e}");
    let cyc = r#"<scene version="3.0.0"><include filename="scene.xml"/></scene>"#;
    let e = try_xml(cyc, &[]).unwrap_err();
    assert!(e.contains("nest more than"), "{e}");
}

#[test]
fn errors_name_the_element_and_line() {
    let cases: &[(&str, &str)] = &[
        ("<scene version=\"3.0.0\">\n<shape type=\"cylinder\"/>\n</scene>", "scene.xml:2: <shape type=\"cylinder\">: shape type 'cylinder' is not supported"),
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\">\n<bsdf type=\"velvet\"/></shape></scene>", ":3: <bsdf type=\"velvet\">: BSDF type 'velvet' is not supported"),
        ("<scene version=\"3.0.0\">\n<teapot/>\n</scene>", ":2: <teapot>: <teapot> is not a scene element"),
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\">\n<transform name=\"to_world\"><skew/></transform></shape></scene>", ":3: <skew>"),
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\"><transform name=\"to_world\">\n<translate x=\"nan\"/></transform></shape></scene>", ":3: <translate>: 'nan' is not a finite number"),
        ("<scene version=\"3.0.0\">\n<shape type=\"ply\">\n<string name=\"filename\" value=\"missing.ply\"/></shape></scene>", ":2: <shape type=\"ply\">: cannot read"),
        ("<scene version=\"3.0.0\">\n<shape type=\"obj\"><string name=\"filename\" value=\"../../etc/passwd\"/></shape></scene>", "outside the scene's folder"),
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\"/>\n<sensor type=\"perspective\"><string name=\"fov_axis\" value=\"z\"/></sensor></scene>", ":3: <sensor type=\"perspective\">: fov_axis 'z'"),
        ("<scene version=\"3.0.0\">\n<sensor type=\"orthographic\"/></scene>", "sensor type 'orthographic' is not supported"),
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\"/></scene>", "no lights"),
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\">\n</scene>", "scene.xml:3: malformed XML"),
        ("<!DOCTYPE x [<!ENTITY a \"aaaa\">]><scene version=\"3.0.0\">&a;</scene>", "malformed XML"),
        ("<scene>\n<shape type=\"cube\"/></scene>", "has no 'version'"),
        ("<scene version=\"9.0.0\"/>", "version '9.0.0' is not supported"),
        ("<mesh/>", "the root element is <mesh>"),
        ("<scene version=\"3.0.0\">\n<shape type=\"sphere\"><float name=\"radius\" value=\"-1\"/></shape></scene>", "radius -1 must be positive"),
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\"><bsdf type=\"diffuse\"><texture type=\"checkerboard\" name=\"reflectance\"/></bsdf></shape></scene>", "texture type 'checkerboard' is not supported"),
        ("<scene version=\"3.0.0\"><shape type=\"cube\" id=\"a\"/>\n<shape type=\"cube\" id=\"a\"/></scene>", ":2: <shape type=\"cube\" id=\"a\">: the id 'a' is used twice"),
    ];
    let deep = format!("<scene version=\"3.0.0\">{}{}</scene>", "<a>".repeat(100_000), "</a>".repeat(100_000));
    let selfref = "<scene version=\"3.0.0\"><bsdf type=\"twosided\" id=\"a\"><ref id=\"a\"/></bsdf>\n\
                   <shape type=\"cube\"><ref id=\"a\"/></shape></scene>";
    let more = [(deep.as_str(), "nest more than 64 levels"), (selfref, "BSDFs nest more than 16 levels deep")];
    for (xml, want) in cases.iter().chain(&more) {
        let e = try_xml(xml, &[]).expect_err(xml);
        assert!(e.contains(want), "\n{xml}\ngave: {e}\nwanted: {want}");
    }
}

#[test]
fn mesh_files_with_errors_name_their_file() {
    let xml = scene3(r#"<shape type="ply"><string name="filename" value="bad.ply"/></shape>"#);
    let e = try_xml(&xml, &[("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n")])
        .unwrap_err();
    assert!(e.contains("bad.ply") && e.contains("no x, y, z"), "{e}");
    let xml = scene3(r#"<shape type="serialized"><string name="filename" value="bad.serialized"/></shape>"#);
    let e = try_xml(&xml, &[("bad.serialized", "not zlib at all")]).unwrap_err();
    assert!(e.contains("bad.serialized") && e.contains("magic"), "{e}");
}

#[test]
fn mitsuba_bitmap_textures() {
    let s = load("textured.xml");
    assert_eq!(s.textures.len(), 2);
    let checker = s.textures.iter().find(|t| t.name == "checker.png").unwrap();
    assert_eq!((checker.width, checker.height, checker.scale), (8, 8, Vec2::splat(2.0)));
    assert_eq!(
        checker.texels.get(0),
        Vec3::new(230.0, 220.0, 200.0).map(|c| srgb_to_linear(c / 255.0)),
        "sRGB decoded"
    );
    let stripes = s.textures.iter().find(|t| t.name == "stripes.png").unwrap();
    assert_eq!(stripes.filter, plie::scene::texture::Filter::Nearest);
    assert_eq!(stripes.wrap, [plie::scene::texture::Wrap::Clamp; 2]);
    // The back wall (PLY with uvs): its top row of texels is darker, near x = -1 red.
    let wall = (0..s.triangle_count() as u32)
        .map(TriId)
        .find(|&t| s.material_of(t).name == "striped")
        .expect("the striped wall");
    let top_left = s.albedo_at(wall, Vec3::new(-0.9, 1.95, -1.0));
    let low_left = s.albedo_at(wall, Vec3::new(-0.9, 0.5, -1.0));
    assert_eq!(low_left, Vec3::new(200.0, 40.0, 30.0).map(|c| srgb_to_linear(c / 255.0)), "nearest texel, red stripe");
    assert_eq!(top_left, Vec3::new(100.0, 20.0, 15.0).map(|c| srgb_to_linear(c / 255.0)), "top row: darker");
    // The floor: repeat with to_uv scale 2, so the 8x8 checker repeats twice over the floor.
    let floor = (0..s.triangle_count() as u32).map(TriId).find(|&t| s.material_of(t).name == "checkered").unwrap();
    let a = s.albedo_at(floor, Vec3::new(-0.99, 0.0, 0.99));
    let b = s.albedo_at(floor, Vec3::new(0.01, 0.0, 0.99));
    assert!((a - b).abs().max_element() < 0.05, "period of half the floor: {a} {b}");
    assert!(s.textures.iter().all(|t| t.texels.iter().all(|v| v.is_finite())));
}

#[test]
fn textured_images_are_bit_identical_across_modes() {
    let s = load("textured.xml");
    let reference = bits(&image(&s, Mode::Brute, &small()));
    for mode in [Mode::Bvh, Mode::Octree, Mode::Lie, Mode::Grid] {
        assert_eq!(bits(&image(&s, mode, &small())), reference, "{mode} differs from brute");
    }
    let flat = {
        let mut f = s.clone();
        f.tri_uv.clear();
        image(&f, Mode::Bvh, &small())
    };
    assert_ne!(bits(&flat), reference, "the textures change the image");
}

#[test]
fn texture_on_a_shape_without_uvs_uses_its_mean() {
    let png = std::fs::read(data("checker.png")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("c.png"), png).unwrap();
    let xml = scene3(
        r#"<shape type="cube"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="c.png"/></texture></bsdf></shape>"#,
    );
    std::fs::write(dir.path().join("scene.xml"), xml).unwrap();
    let s = load_scene(&dir.path().join("scene.xml")).unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("without texture coordinates")), "{:?}", s.warnings);
    let m = s.material_of(TriId(5));
    assert!(m.texture.is_none() && m.albedo.min_element() > 0.0);
}

#[test]
fn obj_map_kd_textures() {
    let png = std::fs::read(data("stripes.png")).unwrap();
    let dir = folder(&[
        (
            "q.obj",
            "mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl tex\nf 1/1 2/2 3/3 4/4\n\
             v 0 0 2\nv 1 0 2\nv 1 1 2\nusemtl lamp\nf 7 6 5\n",
        ),
        ("q.mtl", "newmtl tex\nKd 1 1 1\nmap_Kd s.png\nnewmtl lamp\nKe 1 1 1\n"),
    ]);
    std::fs::write(dir.path().join("s.png"), png).unwrap();
    let s = load_scene(&dir.path().join("q.obj")).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.textures.len(), 1);
    // OBJ's v = 0 is the image's bottom: the top row (darker) is at y near 1.
    // Texel centres (bilinear filtering then reads one texel): u = 1/8, v = 1/8 and 7/8.
    let low = s.albedo_at(TriId(0), Vec3::new(0.125, 0.125, 0.0));
    let high = s.albedo_at(TriId(1), Vec3::new(0.125, 0.875, 0.0));
    let red = Vec3::new(200.0, 40.0, 30.0).map(|c| srgb_to_linear(c / 255.0));
    assert!((low - red).abs().max_element() < 1e-5, "{low} vs {red}");
    let dark = Vec3::new(100.0, 20.0, 15.0).map(|c| srgb_to_linear(c / 255.0));
    assert!((high - dark).abs().max_element() < 1e-5, "the top texel row is darker: {high} vs {dark}");
    let outside = folder(&[
        ("q.obj", "mtllib q.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl l\nf 1 2 3\n"),
        ("q.mtl", "newmtl l\nKe 1 1 1\nmap_Kd ../../x.png\n"),
    ]);
    let e = load_scene(&outside.path().join("q.obj")).unwrap_err().to_string();
    assert!(e.contains("map_Kd") && e.contains("outside the scene's folder"), "{e}");
}

#[test]
fn outside_paths_only_when_allowed() {
    let parent = tempfile::tempdir().unwrap();
    let inner = parent.path().join("scene");
    std::fs::create_dir(&inner).unwrap();
    std::fs::write(parent.path().join("o.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        inner.join("scene.xml"),
        scene3(r#"<shape type="obj"><string name="filename" value="../o.obj"/></shape>"#),
    )
    .unwrap();
    let e = load_scene(&inner.join("scene.xml")).unwrap_err().to_string();
    assert!(e.contains("outside the scene's folder"), "{e}");
    let s = load_scene_with(&inner.join("scene.xml"), LoadOptions { allow_outside_paths: true }).unwrap();
    assert_eq!(s.triangle_count(), 3);
}

/// Mitsuba 3 (`pip install mitsuba`), where importable, renders cornell-3.xml and textured.xml; plie's
/// lit pixels' mean radiance must agree within 1.5%. The Python is `$PLIE_MITSUBA_PYTHON`, else
/// `/tmp/mitsuba-venv/bin/python`, else `python3`.
#[test]
fn mitsuba_3_agrees_on_the_cornell_boxes() {
    let python = std::env::var("PLIE_MITSUBA_PYTHON").ok().or_else(|| {
        let venv = "/tmp/mitsuba-venv/bin/python";
        Path::new(venv).exists().then(|| venv.to_string())
    });
    let python = python.unwrap_or_else(|| "python3".into());
    let importable = std::process::Command::new(&python)
        .args(["-c", "import mitsuba, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !importable {
        eprintln!("notice: Mitsuba 3 is not importable by {python}: skipping the reference comparison");
        return;
    }
    for scene in ["cornell-3.xml", "textured.xml"] {
        let diff = against_mitsuba(&python, scene, 32);
        assert!(diff.abs() < 0.015, "{scene}: plie differs from Mitsuba 3 by {:+.2}%", diff * 100.0);
    }
}

/// Renders `scene` with Mitsuba 3 (scalar_rgb, its `direct` integrator, 1024 samples per pixel, box
/// filter) and with plie (16 x 16 regular eye rays per pixel, 16 shadow rays per light) at `size` x
/// `size`; the relative difference of plie's summed radiance over the pixels Mitsuba finds lit.
fn against_mitsuba(python: &str, scene: &str, size: u32) -> f64 {
    let out = tempfile::tempdir().unwrap();
    let reference = out.path().join("mitsuba.txt");
    let script = format!(
        "import mitsuba as mi, numpy as np\nmi.set_variant('scalar_rgb')\n\
         s = mi.load_file(r'{}', res={size}, spp=1024)\nimg = np.array(mi.render(s))\n\
         np.savetxt(r'{}', img.reshape(-1, 3))\n",
        data(scene).display(),
        reference.display()
    );
    let run = std::process::Command::new(python).args(["-c", &script]).output().unwrap();
    assert!(run.status.success(), "mitsuba failed: {}", String::from_utf8_lossy(&run.stderr));
    let text = std::fs::read_to_string(&reference).unwrap();
    let mitsuba: Vec<Vec3> = text
        .lines()
        .map(|l| {
            let v: Vec<f32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            Vec3::new(v[0], v[1], v[2])
        })
        .collect();
    assert_eq!(mitsuba.len(), (size * size) as usize);
    let s = load(scene);
    // Many regular eye rays per pixel: the light's edges are then covered as Mitsuba's random
    // samples cover them (at 4 x 4 the aliasing of those bright edges alone was about -1.7%).
    let settings = RenderSettings { width: size, height: size, eye_rays: 16, shadow_rays: 16, seed: 1 };
    let plie = image(&s, Mode::Bvh, &settings);
    let (mut a, mut b) = (0.0f64, 0.0f64);
    for (m, p) in mitsuba.iter().zip(&plie) {
        if m.max_element() > 0.0 {
            a += m.element_sum() as f64;
            b += p.element_sum() as f64;
        }
    }
    let diff = b / a - 1.0;
    eprintln!(
        "{scene}: summed radiance of the lit pixels: Mitsuba {a:.3}, plie {b:.3}, difference {:+.3}%",
        diff * 100.0
    );
    diff
}

#[test]
fn fov_axes_and_focal_length() {
    let fov = |sensor: &str| -> f32 {
        let xml = scene3(&format!(
            r#"<shape type="cube"/><sensor type="perspective">{sensor}
               <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/></film></sensor>"#
        ));
        try_xml(&xml, &[]).unwrap().camera.unwrap().fov_deg
    };
    let vertical = |h_deg: f32, ratio: f32| 2.0 * ((h_deg.to_radians() / 2.0).tan() * ratio).atan().to_degrees();
    let near = |a: f32, b: f32| (a - b).abs() < 1e-3;
    assert!(near(fov(r#"<float name="fov" value="60"/>"#), vertical(60.0, 0.5)), "fov_axis x is the default");
    assert!(near(fov(r#"<float name="fov" value="60"/><string name="fov_axis" value="y"/>"#), 60.0));
    assert!(near(fov(r#"<float name="fov" value="60"/><string name="fov_axis" value="smaller"/>"#), 60.0));
    assert!(near(
        fov(r#"<float name="fov" value="60"/><string name="fov_axis" value="larger"/>"#),
        vertical(60.0, 0.5)
    ));
    let diag = 100.0 / (200.0f32 * 200.0 + 100.0 * 100.0).sqrt();
    assert!(near(
        fov(r#"<float name="fov" value="60"/><string name="fov_axis" value="diagonal"/>"#),
        vertical(60.0, diag)
    ));
    assert!(near(
        fov(r#"<string name="focal_length" value="50mm"/>"#),
        vertical(2.0 * (18.0f32 / 50.0).atan().to_degrees(), 0.5)
    ));
    let e =
        error(&scene3(r#"<shape type="cube"/><sensor type="perspective"><float name="fov" value="180"/></sensor>"#));
    assert!(e.contains("fov 180 must be between 0 and 180"), "{e}");
}
