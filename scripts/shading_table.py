#!/usr/bin/env python3
"""Shading-time table for docs/results.md: runs `plie render --json` per scene and visibility mode.

Usage: scripts/shading_table.py [--runs N] [--size S] [--shadow-rays N] [--modes a,b] [SCENE ...]
Reports the median shading time (pass 2 only, SPEC §7) over N runs and shadow rays per second.
"""
import argparse, json, statistics, subprocess, sys

BUILTIN = ["cornell-cube-1", "cornell-cube-2", "cornell-cube-3", "cornell-cube-4", "cornell-cube-5",
           "huis-a", "huis-b", "huis-c", "dragon", "boot"]

def run(binary, scene, mode, a):
    cmd = [binary, "render", "--scene", scene, "-o", "/tmp/plie-bench.pfm", "--width", str(a.size),
           "--height", str(a.size), "--eye-rays", "1", "--shadow-rays", str(a.shadow_rays),
           "--visibility", mode, "--json", "--quiet"]
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out)

def main():
    p = argparse.ArgumentParser()
    p.add_argument("--binary", default="target/release/plie")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--size", type=int, default=254)
    p.add_argument("--shadow-rays", type=int, default=4)
    p.add_argument("--modes", default="octree,bvh")
    p.add_argument("scenes", nargs="*")
    a = p.parse_args()
    modes = a.modes.split(",")
    scenes = a.scenes or BUILTIN
    head = "| scene | triangles | " + " | ".join(f"{m} s | {m} Mrays/s | {m} tests/ray" for m in modes) + " |"
    print(head)
    print("|" + "---|" * (2 + 3 * len(modes)))
    totals = {m: 0.0 for m in modes}
    for s in scenes:
        cells = []
        tris = None
        for m in modes:
            rs = [run(a.binary, s, m, a) for _ in range(a.runs)]
            t = statistics.median(r["shading_seconds"] for r in rs)
            rays = rs[0]["shadow_rays"]
            tris = rs[0]["triangles"]
            totals[m] += t
            cells += [f"{t:.4f}", f"{rays / t / 1e6:.2f}", f"{rs[0]['triangle_tests_per_shadow_ray']:.2f}"]
        name = s.split("/")[-1]
        print(f"| {name} | {tris} | " + " | ".join(cells) + " |")
        sys.stdout.flush()
    print("| **total** | | " + " | ".join(f"**{totals[m]:.4f}** | |" for m in modes) + " |")

if __name__ == "__main__":
    main()
