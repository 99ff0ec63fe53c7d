#!/usr/bin/env python3
"""Shading table for docs/results.md (issue 15): per scene, P-LIE build seconds and shading seconds
(254x254 eye rays, 1 per pixel, 64 shadow rays per light) with `grid` on the P-LIE built before
issue 15 and with blocker caps, beside `embree` (and `bvh`), and the break-even number of images
after which build + shading with `grid` beats `embree` alone.

Usage: scripts/bounded_shading.py --binary target/release/plie [--before PATH] [--caps 64,1024]
       [--shared DIR] [--threads T] [--scenes NAME,...] [--before-label L] [--repeat N]
With `--threads 1` the grid shading's CPU seconds (`shading_cpu_seconds`) are the least noisy figure on
a shared machine; `--repeat N` renders each P-LIE N times and shows the median.
The binary must be built with `--features embree`. One run per figure; the machine is shared.
"""
import argparse, json, os, subprocess, sys, tempfile

CAMERAS = {
    "cornell": ["--eye", "278,273,-800", "--target", "278,273,0", "--up", "0,1,0", "--fov", "39.3"],
    "boat-lit.obj": ["--eye", "9,4,-9", "--target", "0,1,0", "--up", "0,1,0", "--fov", "40"],
    "conference-lit.obj": ["--eye", "1550,380,550", "--target", "400,150,-150", "--up", "0,1,0", "--fov", "60"],
    "balusters": ["--eye", "2,2.6,0.05", "--target", "2,0.6,3", "--up", "0,1,0", "--fov", "70"],
}
SCENES = ["cornell-dragon.obj", "boat-lit.obj", "cornell-bunny.obj", "cornell-dragon-100k.obj", "conference-lit.obj"]


def camera(scene):
    b = os.path.basename(scene)
    for k, v in CAMERAS.items():
        if b.startswith(k):
            return v
    return []


def run(args):
    p = subprocess.run(args, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"{' '.join(args)}: {p.stderr.strip()}")
    return json.loads(p.stdout)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--binary", default="target/release/plie")
    p.add_argument("--before", default=None)
    p.add_argument("--caps", default="64,1024")
    p.add_argument("--shared", default="../shared")
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--scenes", default=None)
    p.add_argument("--before-label", default="before")
    p.add_argument("--repeat", type=int, default=1, help="renders per P-LIE; the median grid shading is shown")
    a = p.parse_args()
    scenes = a.scenes.split(",") if a.scenes else [os.path.join(a.shared, "scenes", s) for s in SCENES]
    thr = ["--threads", str(a.threads)] if a.threads else []
    img = ["--width", "254", "--height", "254", "--eye-rays", "1", "--shadow-rays", "64", "--json", "-q"] + thr
    print("| scene | P-LIE | build s | grid shading s | grid shading CPU s | embree shading s | bvh shading s | scene_bvh rays "
          "| break-even (images) |")
    print("|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        out, pl = os.path.join(d, "x.pfm"), os.path.join(d, "x.plie")
        for s in scenes:
            cam = camera(s)
            base = lambda binary: [binary, "render", "--scene", s, "-o", out] + cam + img
            emb = run(base(a.binary) + ["--visibility", "embree"])["shading_seconds"]
            bvh = run(base(a.binary) + ["--visibility", "bvh"])["shading_seconds"]
            runs = ([(a.before_label, a.before, [])] if a.before else []) + \
                   [(f"cap {c}", a.binary, ["--blocker-cap", c]) for c in a.caps.split(",")]
            for label, binary, extra in runs:
                b = run([binary, "build", "--scene", s, "-o", pl, "--json"] + thr + extra)
                rs = sorted((run(base(binary) + ["--visibility", "grid", "--plie", pl] + extra) for _ in range(a.repeat)),
                            key=lambda r: r["shading_seconds"])
                r = rs[len(rs) // 2]
                g = r["shading_seconds"]
                gc = r.get("shading_cpu_seconds")
                gc = f"{gc:.3f}" if gc is not None else "?"
                sb = r.get("answers", {}).get("scene_bvh", "-")
                gain = emb - g
                be = f"{b['build_seconds'] / gain:.1f}" if gain > 0 else "never"
                print(f"| {os.path.basename(s)} | {label} | {b['build_seconds']:.2f} | {g:.3f} | {gc} | {emb:.2f} | {bvh:.2f} | {sb} "
                      f"| {be} |", flush=True)
                print(json.dumps({"scene": s, "label": label, "build": b["build_seconds"], "grid": g, "embree": emb,
                                  "bvh": bvh, "answers": r.get("answers")}), file=sys.stderr)


if __name__ == "__main__":
    main()
