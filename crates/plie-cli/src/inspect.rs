//! `plie inspect`: what the P-LIE stores for one cell (SPEC §4), as a picture rendered by plie (the
//! octree's leaves, the inspected leaf highlighted, its blockers, umbra and penumbra), as a glTF scene,
//! or as a per-leaf summary.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use glam::Vec3;
use plie::internals::inspect::overlay::{camera_on_box, render_inspection, OverlayStyle};
use plie::internals::inspect::summary::{FaceSummary, Filter, Summary};
use plie::internals::inspect::{FaceStatus, Inspection, Inspector};
use plie::internals::io::gltf_export::{save_inspection_gltf, GltfFormat};
use plie::octree::{Dir, Octree};
use serde_json::{json, Value};

use crate::image_args::ImageArgs;
use crate::plie_args::{build, load_file, Loaded, PlieArgs};
use crate::progress::Bar;
use crate::scene_arg::{parse_vec3, CameraArgs, SceneArgs};

/// Options of `plie inspect`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    camera: CameraArgs,
    /// A point in the cell to show: the octree leaf containing it is inspected (and, with --summary,
    /// the only leaf listed).
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_vec3, allow_hyphen_values = true)]
    cell: Option<Vec3>,
    /// The light (index from 0). Default: 0 for the picture; every light for --summary.
    #[arg(long, value_name = "I")]
    light: Option<u32>,
    /// Only this face: left, right, down, up, back, front. Default: every face that sees the light.
    #[arg(long, value_name = "DIR")]
    face: Option<String>,
    /// Output: .png (rendered by plie), .gltf or .glb (a glTF scene with the same content).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    output: Option<PathBuf>,
    /// Print, per leaf, the data object of each face and light, its blockers and its umbra and
    /// penumbra area fractions (only the leaf of --cell, the light of --light, the face of --face
    /// when given).
    #[arg(long)]
    summary: bool,
    /// Print one JSON object on stdout instead of text: `scene`, `summary` (with --summary),
    /// `inspection` and `output` (with -o).
    #[arg(long)]
    json: bool,
    /// Move the camera (the scene's, or --eye/--target) along its line of sight so it looks at the
    /// inspected leaf and the leaf fills about half of the picture (PNG and the glTF's camera).
    #[arg(long)]
    frame: bool,
    /// The PNG's image settings.
    #[command(flatten)]
    image: ImageArgs,
    /// PNG: width of the leaf edges in pixels (the inspected leaf's are twice as wide).
    #[arg(long, default_value_t = 1.5, value_name = "PX")]
    line_width: f32,
    #[command(flatten)]
    threads: crate::threads_arg::ThreadsArg,
    #[command(flatten)]
    params: PlieArgs,
    /// Inspect this P-LIE file (from `plie build`) instead of building one; its build parameters come
    /// from the file (an option given that contradicts it is an error).
    #[arg(long, value_name = "FILE.plie")]
    plie: Option<PathBuf>,
    /// No progress bar, no description of the inspected cell on stderr.
    #[arg(long, short)]
    quiet: bool,
}

/// What `-o` writes.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Output {
    Png,
    Gltf,
}

/// The output kind of `path`, and that its directory exists.
fn output_kind(path: &Path) -> Result<Output> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    let kind = match ext.as_str() {
        "png" => Output::Png,
        _ if GltfFormat::from_path(path).is_some() => Output::Gltf,
        _ => bail!("{}: unknown output format '.{ext}'; plie inspect writes .png, .gltf or .glb", path.display()),
    };
    Ok(kind)
}

pub fn run(a: &Args, matches: &clap::ArgMatches) -> Result<()> {
    a.threads.install()?;
    if a.output.is_none() && !a.summary {
        bail!("nothing to do: give -o OUT (.png, .gltf, .glb) with --cell X,Y,Z, or --summary");
    }
    if a.output.is_some() && a.cell.is_none() {
        bail!("-o needs --cell X,Y,Z: a point in the octree leaf to show");
    }
    let kind = a.output.as_deref().map(output_kind).transpose()?;
    if let Some(out) = &a.output {
        let inputs: Vec<&Path> = a.scene.file().into_iter().chain(a.plie.as_deref()).collect();
        crate::checks::output_is_not_input(out, &inputs)?;
    }
    let face: Option<Dir> = a.face.as_deref().map(str::parse).transpose().map_err(anyhow::Error::msg)?;
    let mut settings = a.image.settings()?;
    if !(a.line_width.is_finite() && a.line_width > 0.0) {
        bail!("--line-width must be a positive number of pixels");
    }

    let scene = a.scene.load()?;
    crate::checks::outputs_are_not_sources(a.output.as_slice(), &scene.sources)?;
    if !a.quiet && !a.json {
        crate::scene_arg::warn_about(&scene);
    }
    let camera = a.camera.camera(&scene)?;
    a.image.size_for(&mut settings, &scene)?;
    let params = a.params.params(false)?;
    let bar = Bar::new(a.quiet || a.json);
    let Loaded { env, .. } = match a.plie.as_deref() {
        Some(file) => load_file(&scene, file, &a.params, matches)?,
        None => build(&scene, params, &a.params, &bar)?,
    };
    let (octree, plie) = (env.octree(), env.plie());
    let inspector = Inspector::new(&scene, octree, plie)?;
    let light = a.light.map(|i| inspector.light(i)).transpose()?;
    let leaf = a.cell.map(|p| inspector.leaf_at(p)).transpose()?;
    let inspection = match a.cell.filter(|_| a.output.is_some()) {
        Some(p) => Some(inspector.inspect(p, light.unwrap_or(plie::LightId(0)), face)?),
        None => None,
    };
    let summary = a.summary.then(|| inspector.summary(Filter { leaf, light, face }));
    if let Some(s) = summary.as_ref().filter(|_| !a.json) {
        print_summary(s)?;
    }

    if let (Some(ins), Some(path), Some(kind)) = (&inspection, &a.output, kind) {
        if !a.quiet && !a.json {
            describe(octree, ins, plie.params.has_regions());
        }
        let camera = if a.frame { camera_on_box(&camera, &ins.bounds) } else { camera };
        match kind {
            Output::Png => {
                let style = OverlayStyle { line_px: a.line_width, exposure_ev: a.image.exposure };
                let out = render_inspection(&scene, octree, ins, &camera, &settings, &style, &bar)?;
                plie::io::save_image(path, settings.width, settings.height, &out.pixels)
                    .with_context(|| format!("cannot write {}", path.display()))?;
            }
            Output::Gltf => {
                let aspect = settings.width as f32 / settings.height as f32;
                save_inspection_gltf(path, &scene, octree, ins, Some((&camera, aspect)))
                    .with_context(|| format!("cannot write {}", path.display()))?;
            }
        }
        if !a.quiet && !a.json {
            eprintln!("wrote {}", path.display());
        }
    }
    if a.json {
        let mut v = json!({ "scene": scene.name });
        if let Some(s) = &summary {
            v["summary"] = serde_json::to_value(s)?;
        }
        if let (Some(ins), Some(path)) = (&inspection, &a.output) {
            v["inspection"] = inspection_json(octree, ins, plie.params.has_regions());
            v["output"] = json!(path.display().to_string());
        }
        println!("{v}");
    }
    Ok(())
}

/// A percentage, or `-`.
fn pct(f: Option<f64>) -> String {
    f.map_or("-".into(), |f| format!("{:.1}%", 100.0 * f))
}

/// A status in words.
fn status_text(s: FaceStatus) -> &'static str {
    match s {
        FaceStatus::Record(_) => "record",
        FaceStatus::Removed => "removed (fully in umbra)",
        FaceStatus::CannotSeeLight => "none: cannot see the light",
    }
}

/// A box corner.
fn point(p: Vec3) -> String {
    format!("({}, {}, {})", p.x, p.y, p.z)
}

const HEADER: &str = "  face   light  data object                 blockers     umbra  penumbra";

fn row(f: &FaceSummary) -> String {
    format!(
        "  {:<6} {:>5}  {:<26} {:>9} {:>9} {:>9}",
        f.face.name(),
        f.light,
        status_text(f.status),
        f.blockers.map_or("-".into(), |b| b.to_string()),
        pct(f.umbra_fraction),
        pct(f.penumbra_fraction)
    )
}

/// The summary as text on stdout. A closed pipe (`plie inspect --summary | head`) ends the listing
/// quietly.
fn print_summary(s: &Summary) -> Result<()> {
    match write_summary(&mut std::io::stdout().lock(), s) {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        r => r.context("cannot write to stdout"),
    }
}

/// The summary as text.
fn write_summary(w: &mut impl Write, s: &Summary) -> std::io::Result<()> {
    writeln!(
        w,
        "scene {}: {} leaves, {} light{}, umbra/penumbra {}",
        s.scene,
        s.octree_leaves,
        s.lights,
        if s.lights == 1 { "" } else { "s" },
        if s.regions { "computed" } else { "not computed (--no-regions)" }
    )?;
    writeln!(
        w,
        "listed: {} lea{}; {} data objects, {} removed (fully in umbra), {} faces that cannot see the light",
        s.leaves.len(),
        if s.leaves.len() == 1 { "f" } else { "ves" },
        s.records,
        s.removed,
        s.cannot_see_light
    )?;
    for l in &s.leaves {
        writeln!(
            w,
            "leaf {}  depth {}  {} to {}  {} triangles",
            l.leaf,
            l.depth,
            point(Vec3::from(l.min)),
            point(Vec3::from(l.max)),
            l.triangles
        )?;
        writeln!(w, "{HEADER}")?;
        for f in &l.faces {
            writeln!(w, "{}", row(f))?;
        }
    }
    w.flush()
}

/// What the picture or glTF file shows, on stderr.
fn describe(octree: &Octree, ins: &Inspection, regions: bool) {
    eprintln!(
        "leaf {} (depth {}, {} to {}, {} triangles), light {}:",
        ins.leaf.0,
        ins.depth,
        point(ins.bounds.min),
        point(ins.bounds.max),
        octree.leaf_triangles(ins.leaf).len(),
        ins.light.0
    );
    if ins.faces.is_empty() {
        eprintln!("  no face of this leaf sees light {}: nothing to show but the leaf", ins.light.0);
        return;
    }
    eprintln!("{HEADER}");
    for f in &ins.faces {
        let line = row(&FaceSummary {
            face: f.face,
            light: ins.light.0,
            status: f.status,
            blockers: Some(f.blockers.len() as u32),
            umbra_fraction: regions.then_some(f.umbra_fraction),
            penumbra_fraction: regions.then_some(f.penumbra_fraction),
        });
        let note = if f.status == FaceStatus::Removed { "  (blockers gathered again)" } else { "" };
        eprintln!("{line}{note}");
    }
    eprintln!(
        "  {} blockers: blue where they cross a face's shaft, pale blue elsewhere; umbra green, penumbra yellow",
        ins.blockers.len()
    );
}

/// The inspection as JSON (fractions `null` without regions).
fn inspection_json(octree: &Octree, ins: &Inspection, regions: bool) -> Value {
    let faces: Vec<Value> = ins
        .faces
        .iter()
        .map(|f| {
            json!({
                "face": f.face.name(),
                "status": f.status.name(),
                "blockers": f.blockers.iter().map(|t| t.0).collect::<Vec<_>>(),
                "clipped_blockers": f.clipped.len(),
                "umbra_fraction": regions.then_some(f.umbra_fraction),
                "penumbra_fraction": regions.then_some(f.penumbra_fraction),
                "umbra_triangles": f.umbra.len(),
                "penumbra_triangles": f.penumbra.len(),
            })
        })
        .collect();
    json!({
        "point": ins.point.to_array(),
        "leaf": ins.leaf.0,
        "depth": ins.depth,
        "min": ins.bounds.min.to_array(),
        "max": ins.bounds.max.to_array(),
        "triangles": octree.leaf_triangles(ins.leaf).len(),
        "light": ins.light.0,
        "faces": faces,
        "blockers": ins.blockers.iter().map(|t| t.0).collect::<Vec<_>>(),
    })
}
