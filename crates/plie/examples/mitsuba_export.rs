//! Writes a plie scene as a Mitsuba 3 scene: one OBJ per material (`twosided` diffuse, as plie shades
//! both sides; an `area` emitter on a light's triangles, one-sided like plie's lights), a perspective
//! sensor with plie's camera and a box pixel filter, and the `path` integrator with the given
//! `max_depth`. Used by `scripts/mitsuba_reference.py` for the independent reference of the path tracer.
//!
//! `cargo run --release -p plie --example mitsuba_export -- SCENE OUT_DIR MAX_DEPTH SPP SIZE [EYE TARGET UP FOV]`
//! (SCENE: a built-in name or a scene file; EYE, TARGET, UP as `X,Y,Z`.)

use std::fmt::Write as _;
use std::path::Path;

use glam::Vec3;
use plie::scene::builtin;
use plie::Camera;

/// A group of triangles written to one OBJ: (material index, light index).
type GroupKey = (usize, Option<u32>);

fn vec3(s: &str) -> Vec3 {
    let v: Vec<f32> = s.split(',').map(|p| p.trim().parse().expect("a number")).collect();
    assert_eq!(v.len(), 3, "expected X,Y,Z, got {s}");
    Vec3::new(v[0], v[1], v[2])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 5 && args.len() != 9 {
        return Err("usage: mitsuba_export SCENE OUT_DIR MAX_DEPTH SPP SIZE [EYE TARGET UP FOV]".into());
    }
    let scene = if builtin::NAMES.contains(&args[0].as_str()) {
        builtin::load(&args[0])?
    } else {
        plie::io::load_scene(Path::new(&args[0]))?
    };
    let out = Path::new(&args[1]);
    let (max_depth, spp, size): (i32, u32, u32) = (args[2].parse()?, args[3].parse()?, args[4].parse()?);
    let camera = if args.len() == 9 {
        Camera::new(vec3(&args[5]), vec3(&args[6]), vec3(&args[7]), args[8].parse()?)?
    } else {
        scene.camera_or_default()
    };
    std::fs::create_dir_all(out)?;

    let mut xml = String::new();
    writeln!(xml, "<scene version=\"3.0.0\">")?;
    writeln!(xml, "  <integrator type=\"path\"><integer name=\"max_depth\" value=\"{max_depth}\"/>")?;
    writeln!(xml, "    <integer name=\"rr_depth\" value=\"1000\"/></integrator>")?;
    let (e, t, u) = (camera.eye, camera.target, camera.up);
    writeln!(xml, "  <sensor type=\"perspective\"><float name=\"fov\" value=\"{}\"/>", camera.fov_deg)?;
    writeln!(xml, "    <string name=\"fov_axis\" value=\"y\"/>")?;
    // Mitsuba's camera looks down +z with +x to the image's left; plie's image right is forward x up.
    writeln!(
        xml,
        "    <transform name=\"to_world\"><lookat origin=\"{},{},{}\" target=\"{},{},{}\" up=\"{},{},{}\"/></transform>",
        e.x, e.y, e.z, t.x, t.y, t.z, u.x, u.y, u.z
    )?;
    writeln!(xml, "    <sampler type=\"independent\"><integer name=\"sample_count\" value=\"{spp}\"/></sampler>")?;
    writeln!(xml, "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"{size}\"/>")?;
    writeln!(xml, "      <integer name=\"height\" value=\"{size}\"/><rfilter type=\"box\"/>")?;
    writeln!(xml, "      <string name=\"pixel_format\" value=\"rgb\"/></film></sensor>")?;

    // One OBJ per (material, light): a light's triangles carry its emitter.
    let mut groups: Vec<(GroupKey, Vec<usize>)> = Vec::new();
    for (i, (m, l)) in scene.tri_material.iter().zip(&scene.tri_light).enumerate() {
        let k = (m.idx(), l.map(|l| l.0));
        match groups.iter_mut().find(|g| g.0 == k) {
            Some(g) => g.1.push(i),
            None => groups.push((k, vec![i])),
        }
    }
    for (g, ((m, light), tris)) in groups.iter().enumerate() {
        let mut obj = String::new();
        for &i in tris {
            for v in scene.triangles[i].v {
                writeln!(obj, "v {} {} {}", v.x, v.y, v.z)?;
            }
        }
        for k in 0..tris.len() {
            writeln!(obj, "f {} {} {}", 3 * k + 1, 3 * k + 2, 3 * k + 3)?;
        }
        let name = format!("part{g}.obj");
        std::fs::write(out.join(&name), obj)?;
        let mat = &scene.materials[*m];
        let a = mat.albedo;
        writeln!(xml, "  <shape type=\"obj\"><string name=\"filename\" value=\"{name}\"/>")?;
        writeln!(xml, "    <boolean name=\"face_normals\" value=\"true\"/>")?;
        writeln!(
            xml,
            "    <bsdf type=\"twosided\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"{},{},{}\"/></bsdf></bsdf>",
            a.x, a.y, a.z
        )?;
        if let Some(l) = light {
            let r = scene.lights[*l as usize].radiance;
            writeln!(
                xml,
                "    <emitter type=\"area\"><rgb name=\"radiance\" value=\"{},{},{}\"/></emitter>",
                r.x, r.y, r.z
            )?;
        }
        writeln!(xml, "  </shape>")?;
    }
    writeln!(xml, "</scene>")?;
    std::fs::write(out.join("scene.xml"), xml)?;
    println!("{}", out.join("scene.xml").display());
    Ok(())
}
