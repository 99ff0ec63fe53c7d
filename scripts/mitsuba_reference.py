#!/usr/bin/env python3
"""The path tracer against an independent reference: Mitsuba 3's `path` integrator.

For each scene and depth (Mitsuba's `max_depth`, 3 and 5), this script
  1. (with --reference) writes the scene as Mitsuba XML with plie's exporter
     (`cargo run --release -p plie --example mitsuba_export`), renders it with Mitsuba 3 (variant
     scalar_rgb, box pixel filter, Russian roulette pushed past the depth) and saves
     docs/mitsuba/SCENE-dD.exr;
  2. renders the same view with `plie render --integrator path --max-path-depth D` (EXR, linear);
  3. compares the mean radiance of the lit pixels (non-zero in the reference), per channel and in sum.

Needs Mitsuba 3 and numpy for both steps (Mitsuba reads the EXR files): `python3 -m venv /tmp/mi &&
/tmp/mi/bin/pip install mitsuba numpy`, then run this script with that Python from the worktree's root:

    /tmp/mi/bin/python scripts/mitsuba_reference.py [--reference] [--plie target/release/plie]

Prints a Markdown table (the one in docs/results.md). Exits with status 1 if a scene misses 1.5%.
"""

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

SHARED = os.path.join("..", "shared", "scenes")
# (name, plie scene argument, camera options or [])
SCENES = [
    ("cornell-cube-1", "cornell-cube-1", []),
    ("cornell-cube-2", "cornell-cube-2", []),
    ("CornellBox-Original", os.path.join(SHARED, "CornellBox-Original.obj"),
     ["0,1,3.9", "0,1,0", "0,1,0", "39.3"]),
]
DEPTHS = [3, 5]
SIZE = 64
MITSUBA_SPP = 1024
PLIE_SPP = 256
PLIE_SHADOW_RAYS = 4
TOLERANCE = 0.015


def camera_options(cam):
    if not cam:
        return []
    return ["--eye", cam[0], "--target", cam[1], "--up", cam[2], "--fov", cam[3]]


def reference(mi, exporter, scene, cam, depth, out):
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(exporter + [scene, tmp, str(depth), str(MITSUBA_SPP), str(SIZE)] + cam, check=True,
                       stdout=subprocess.DEVNULL)
        s = mi.load_file(os.path.join(tmp, "scene.xml"))
        img = mi.render(s, seed=1)
        mi.Bitmap(img).write(out)


def load(mi, path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reference", action="store_true", help="re-render the Mitsuba references")
    ap.add_argument("--plie", default=os.path.join("target", "release", "plie"))
    ap.add_argument("--visibility", default="grid")
    ap.add_argument("--exporter", help="the built mitsuba_export example (default: cargo run it)")
    a = ap.parse_args()
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    os.makedirs(os.path.join("docs", "mitsuba"), exist_ok=True)
    print(f"Mitsuba {mi.__version__}, {SIZE}x{SIZE}, Mitsuba {MITSUBA_SPP} spp; "
          f"plie {PLIE_SPP} spp, {PLIE_SHADOW_RAYS} shadow rays per light, --visibility {a.visibility}\n")
    print("| scene | max_depth | Mitsuba mean (R, G, B) | plie mean (R, G, B) | difference of the sum |")
    print("|---|---|---|---|---|")
    worst = 0.0
    for name, scene, cam in SCENES:
        if scene.startswith(SHARED) and not os.path.exists(scene):
            print(f"notice: {scene} absent, skipping {name}", file=sys.stderr)
            continue
        for depth in DEPTHS:
            ref_path = os.path.join("docs", "mitsuba", f"{name}-d{depth}.exr")
            if a.reference or not os.path.exists(ref_path):
                exporter = [a.exporter] if a.exporter else [
                    "cargo", "run", "-q", "--release", "-p", "plie", "--example", "mitsuba_export", "--"]
                reference(mi, exporter, scene, cam, depth, ref_path)
            with tempfile.TemporaryDirectory() as tmp:
                out = os.path.join(tmp, "plie.exr")
                subprocess.run([a.plie, "render", "--scene", scene, "-o", out, "--quiet",
                                "--integrator", "path", "--max-path-depth", str(depth),
                                "--spp", str(PLIE_SPP), "--shadow-rays", str(PLIE_SHADOW_RAYS),
                                "--width", str(SIZE), "--height", str(SIZE), "--visibility", a.visibility]
                               + camera_options(cam), check=True)
                ours = load(mi, out)
            ref = load(mi, ref_path)
            lit = ref.sum(axis=2) > 0
            m_ref = ref[lit].mean(axis=0)
            m_ours = ours[lit].mean(axis=0)
            # Orientation check: per-pixel agreement as is and mirrored (a wrong camera mirrors).
            d_same = np.abs(ours - ref).mean()
            d_flip = np.abs(ours[:, ::-1] - ref).mean()
            rel = m_ours.sum() / m_ref.sum() - 1.0
            worst = max(worst, abs(rel))
            fmt = lambda m: ", ".join(f"{x:.4f}" for x in m)
            note = "" if d_same <= d_flip else " (images mirrored)"
            print(f"| {name} | {depth} | {fmt(m_ref)} | {fmt(m_ours)} | {100 * rel:+.2f}%{note} |")
    print(f"\nlargest difference {100 * worst:.2f}% (tolerance {100 * TOLERANCE:.1f}%)")
    sys.exit(0 if worst <= TOLERANCE else 1)


if __name__ == "__main__":
    main()
