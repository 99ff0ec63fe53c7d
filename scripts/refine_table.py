#!/usr/bin/env python3
"""Table for docs/results.md: what each refinement criterion (SPEC §4.8) does, per scene, by running the
`plie` binary: leaves, records, construction time with face grids, and shading time of modes `lie` and
`grid` at 254x254 eye rays (1 per pixel), 4 shadow rays per light.

Usage: scripts/refine_table.py [--runs N] [--binary PATH] [--scenes A,B,...]
Each figure is the median of N runs: `plie build --json` (`blockers_seconds`: the construction alone,
octree excluded) and `plie render --json` (`shading_seconds`: pass 2 alone) per mode, all threads.
The configurations are interleaved run by run so that load on a shared machine hits all alike.
"""
import argparse, json, statistics, subprocess, tempfile, os

BUILTIN = ["cornell-cube-1", "cornell-cube-2", "cornell-cube-3", "cornell-cube-4", "cornell-cube-5",
           "huis-a", "huis-b", "huis-c", "dragon", "boot"]
CONFIGS = [
    ("none", []),
    ("umbra-full", ["--refine", "umbra-full"]),
    ("umbra-free", ["--refine", "umbra-free"]),
    ("umbra", ["--refine", "umbra"]),
    ("blockers adaptive", ["--refine", "blockers", "--max-blockers", "adaptive"]),
]
MODES = ["lie", "grid"]


def run_json(args):
    return json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--binary", default="target/release/plie")
    ap.add_argument("--scenes", default=",".join(BUILTIN))
    a = ap.parse_args()
    scenes = a.scenes.split(",")
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        out_plie, out_img = os.path.join(tmp, "x.plie"), os.path.join(tmp, "x.pfm")
        for scene in scenes:
            samples = {c: {"build": [], **{m: [] for m in MODES}} for c, _ in CONFIGS}
            for _ in range(a.runs):
                for name, extra in CONFIGS:
                    b = run_json([a.binary, "build", "--scene", scene, "-o", out_plie, "--json", *extra])
                    samples[name]["build"].append(b["blockers_seconds"])
                    samples[name]["info"] = b
                    for m in MODES:
                        r = run_json([a.binary, "render", "--scene", scene, "--width", "254", "--height", "254",
                                      "--eye-rays", "1", "--shadow-rays", "4", "--visibility", m, "--plie",
                                      out_plie, "-o", out_img, "--json", *extra])
                        samples[name][m].append(r["shading_seconds"])
            rows[scene] = samples
    print("| scene | refinement | leaves | records | blockers | construction s | lie s | grid s |")
    print("|---|---|---|---|---|---|---|---|")
    totals = {c: [0.0, 0.0, 0.0] for c, _ in CONFIGS}
    for scene in scenes:
        for name, _ in CONFIGS:
            s = rows[scene][name]
            info = s["info"]
            med = [statistics.median(s["build"])] + [statistics.median(s[m]) for m in MODES]
            totals[name] = [t + x for t, x in zip(totals[name], med)]
            print(f"| {scene} | {name} | {info['leaves']} | {info['records']} | {info['blockers_total']} | "
                  f"{med[0]:.3f} | {med[1]:.4f} | {med[2]:.4f} |")
    for name, _ in CONFIGS:
        t = totals[name]
        print(f"| **total** | {name} | | | | **{t[0]:.3f}** | **{t[1]:.4f}** | **{t[2]:.4f}** |")


if __name__ == "__main__":
    main()
