//! `plie inspect`'s library part: face statuses and summaries agree with the builder, a removed
//! face's blockers are the builder's, regions and clipped blockers are where they belong, and the
//! overlay picture shades the scene exactly as `render` does (markers cast no shadows).

use glam::Vec3;
use plie::internals::inspect::overlay::{overlay_scene, render_inspection, OverlayStyle};
use plie::internals::inspect::summary::Filter;
use plie::internals::inspect::{FaceStatus, Inspector};
use plie::internals::lie::{Plie, PlieParams, Regions};
use plie::internals::render::{HitBuffer, NoProgress, RenderSettings};
use plie::octree::{Dir, Octree};
use plie::visibility::bvh::Bvh;
use plie::visibility::BvhVisibility;
use plie::{LightId, Scene};

fn build(scene: &Scene, params: PlieParams) -> (Octree, Plie, plie::internals::construct::BuildStats) {
    let (env, stats) = plie::Environment::build(scene, &params).unwrap();
    let (octree, plie) = env.into_parts();
    (octree, plie, stats)
}

fn scenes() -> Vec<Scene> {
    ["cornell-cube-1", "cornell-cube-2", "cornell-cube-5"].map(|n| plie::scene::builtin::load(n).unwrap()).to_vec()
}

#[test]
fn statuses_and_summary_agree_with_the_builder() {
    for scene in scenes() {
        let (octree, plie, stats) = build(&scene, PlieParams::default());
        let ins = Inspector::new(&scene, &octree, &plie).unwrap();
        let s = ins.summary(Filter::default());
        assert_eq!(s.records, stats.blockers.records, "{}", scene.name);
        assert_eq!(s.removed, stats.regions.records_removed_umbra, "{}", scene.name);
        assert_eq!(s.cannot_see_light, stats.blockers.records_removed_face_cannot_see_light, "{}", scene.name);
        // Fractions summed from the stored triangles match the builder's polygon areas.
        let rows: Vec<_> = s.leaves.iter().flat_map(|l| &l.faces).filter(|f| f.blockers.is_some()).collect();
        let mean = |get: fn(&plie::internals::inspect::summary::FaceSummary) -> f64| {
            rows.iter().map(|f| get(f)).sum::<f64>() / rows.len() as f64
        };
        let umbra = mean(|f| f.umbra_fraction.unwrap());
        let penumbra = mean(|f| f.penumbra_fraction.unwrap());
        assert!(
            (umbra - stats.regions.umbra_fraction_mean).abs() < 1e-3,
            "{}: {umbra} vs {}",
            scene.name,
            stats.regions.umbra_fraction_mean
        );
        assert!((penumbra - stats.regions.penumbra_fraction_mean).abs() < 1e-3, "{}: {penumbra}", scene.name);
    }
}

#[test]
fn removed_faces_show_the_builders_blockers_in_full_umbra() {
    let mut removed = 0;
    for scene in scenes() {
        let (octree, plie, _) = build(&scene, PlieParams::default());
        let (_, bare, _) = build(&scene, PlieParams { regions: Regions::Skip, ..PlieParams::default() });
        let ins = Inspector::new(&scene, &octree, &plie).unwrap();
        for leaf in octree.leaves() {
            for face in Dir::ALL {
                for l in 0..scene.lights.len() as u32 {
                    let light = LightId(l);
                    let status = ins.status(leaf, face, light);
                    assert_eq!(status.sees_light(), bare.record(leaf, face, light).is_some());
                    if status != FaceStatus::Removed {
                        continue;
                    }
                    removed += 1;
                    let v = ins.face_view(leaf, face, light);
                    // The file keeps long lists in Morton order: compare as sets.
                    let mut kept = bare.blockers_of(bare.record(leaf, face, light).unwrap()).to_vec();
                    kept.sort_unstable();
                    let mut shown = v.blockers.clone();
                    shown.sort_unstable();
                    assert_eq!(shown, kept);
                    assert_eq!((v.umbra.len(), v.umbra_fraction, v.penumbra.len()), (2, 1.0, 0));
                }
            }
        }
    }
    assert!(removed >= 8, "Cornell Cube 1 and 5 have removed faces: {removed}");
}

#[test]
fn regions_lie_on_their_face_and_clipped_blockers_on_their_blocker() {
    let scene = plie::scene::builtin::load("cornell-cube-2").unwrap();
    let (octree, plie, _) = build(&scene, PlieParams::default());
    let ins = Inspector::new(&scene, &octree, &plie).unwrap();
    let (mut regions, mut clipped) = (0, 0);
    for leaf in octree.leaves() {
        let c = octree.leaf_bounds(leaf).center();
        let view = ins.inspect(c, LightId(0), None).unwrap();
        assert_eq!(view.leaf, leaf);
        let b = view.bounds;
        let slack = b.size().max_element() * 1e-4;
        for f in &view.faces {
            let k = f.face.axis();
            let plane = if f.face.is_positive() { b.max[k] } else { b.min[k] };
            for t in f.umbra.iter().chain(&f.penumbra) {
                regions += 1;
                let n = (t[1] - t[0]).cross(t[2] - t[0]);
                assert!(n.dot(f.face.normal()) > 0.0, "counter-clockwise around the outward normal");
                for p in t {
                    assert!((p[k] - plane).abs() <= slack, "{p} off the face plane {plane}");
                    assert!((0..3).all(|a| p[a] >= b.min[a] - slack && p[a] <= b.max[a] + slack), "{p} off the face");
                }
            }
            for (t, poly) in &f.clipped {
                clipped += 1;
                assert!(f.blockers.contains(t));
                let tri = scene.triangle(*t);
                for p in poly {
                    let d = (*p - tri.v[0]).dot(tri.normal());
                    assert!(d.abs() <= slack, "clipped point {p} off its blocker's plane by {d}");
                }
            }
        }
        assert_eq!(view.blockers.windows(2).filter(|w| w[0] >= w[1]).count(), 0, "sorted, no duplicates");
    }
    assert!(regions > 0 && clipped > 0);
}

#[test]
fn bad_points_lights_faces_and_mismatched_p_lies_are_errors() {
    let scene = plie::scene::builtin::load("cornell-cube-1").unwrap();
    let (octree, plie, _) = build(&scene, PlieParams::default());
    let ins = Inspector::new(&scene, &octree, &plie).unwrap();
    let c = octree.root_bounds().center();
    let msg = |r: plie::Result<plie::internals::inspect::Inspection>| r.unwrap_err().to_string();
    assert!(msg(ins.inspect(Vec3::splat(1e7), LightId(0), None)).contains("outside the octree"));
    assert!(msg(ins.inspect(Vec3::NAN, LightId(0), None)).contains("outside the octree"));
    assert!(msg(ins.inspect(c, LightId(1), None)).contains("light 1 does not exist"));
    let p = c + Vec3::new(1.0, -1.0, 1.0);
    let e = msg(ins.inspect(p, LightId(0), Some(Dir::Down)));
    assert!(e.contains("cannot see light 0") && e.contains("up"), "{e}");
    let other = plie::scene::builtin::load("cornell-cube-5").unwrap();
    assert!(Inspector::new(&other, &octree, &plie).is_err(), "the P-LIE has one light, the scene two");
}

#[test]
fn overlay_shades_the_scene_exactly_as_render_and_markers_cast_no_shadows() {
    let scene = plie::scene::builtin::load("cornell-cube-2").unwrap();
    let (octree, plie, _) = build(&scene, PlieParams::default());
    let ins = Inspector::new(&scene, &octree, &plie).unwrap();
    let view = ins.inspect(octree.root_bounds().center() + Vec3::new(1.0, -1.0, 1.0), LightId(0), None).unwrap();
    let camera = scene.camera_or_default();
    let settings = RenderSettings { width: 48, height: 48, eye_rays: 1, shadow_rays: 4, seed: 3 };
    let style = OverlayStyle::default();
    let picture = render_inspection(&scene, &octree, &view, &camera, &settings, &style, &NoProgress).unwrap();
    let bvh = Bvh::build(&scene);
    let plain = plie::Renderer::new().settings(settings).camera(camera);
    let plain = plain.render_with(&scene, &bvh, None, &BvhVisibility::new(&scene, &bvh)).unwrap();

    let overlay = overlay_scene(&scene, &octree, &view, &camera, settings.height, &style);
    assert_eq!(&overlay.triangles[..scene.triangles.len()].len(), &scene.triangles.len());
    assert_eq!(overlay.lights.len(), scene.lights.len());
    let hits = HitBuffer::build(&overlay, &camera, (48, 48, 1), &Bvh::build(&overlay), None);
    let (mut same, mut marked) = (0, 0);
    for (i, hit) in hits.hits.iter().enumerate() {
        let scene_tri = hit.is_some_and(|h| h.tri.idx() < scene.triangles.len() && !view.blockers.contains(&h.tri));
        if scene_tri {
            assert_eq!(picture.pixels[i], plain.pixels[i], "pixel {i}: the scene is shaded as by render");
            same += 1;
        } else {
            marked += 1;
        }
    }
    assert!(same > 100 && marked > 100, "{same} scene pixels, {marked} marked");
}
