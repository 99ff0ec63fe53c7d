#!/usr/bin/env python3
"""Tables for docs/results.md: P-LIE construction (beside the thesis' Tables 8.3/8.4) and shading
times of octree / bvh / lie (beside the thesis' Table A.4 times), by running the `plie` binary.

Usage: scripts/results_tables.py [--runs N] [--binary PATH] [--shared DIR]
Shading: 254x254 pixels, 1 eye ray per pixel, 4 shadow rays per light (the thesis' 254x254 eye rays),
median of N runs of the shading pass alone (SPEC §7). Construction: median of N `plie build` runs.
"""
import argparse, csv, json, os, statistics, subprocess

BUILTIN = [("cornell-cube-1", "Cornell Cube 1"), ("cornell-cube-2", "Cornell Cube 2"),
           ("cornell-cube-3", "Cornell Cube 3"), ("cornell-cube-4", "Cornell Cube 4"),
           ("cornell-cube-5", "Cornell Cube 5"), ("huis-a", "Huis A"), ("huis-b", "Huis B"),
           ("huis-c", "Huis C"), ("dragon", "Dragon"), ("boot", "Boot")]
CAMERA = ["--eye", "278,273,-800", "--target", "278,273,0", "--up", "0,1,0", "--fov", "39.3"]

def thesis(shared):
    cons, shade = {}, {}
    with open(os.path.join(shared, "thesis/construction.tsv")) as f:
        for row in csv.reader((l for l in f if not l.startswith("#")), delimiter="\t"):
            cons[(row[0], row[3])] = (float(row[4]), row[5])
    with open(os.path.join(shared, "thesis/shading-times.tsv")) as f:
        for row in csv.reader((l for l in f if not l.startswith("#")), delimiter="\t"):
            scene, method, rays, umbra, eye, refined, secs = row
            if rays == "4" and eye == "254" and refined == "no" and umbra == "no":
                shade[(scene, method)] = float(secs)
    return cons, shade

def run(binary, args):
    out = subprocess.run([binary] + args, check=True, capture_output=True, text=True).stdout
    return json.loads(out)

def med(xs):
    return statistics.median(xs)

def main():
    p = argparse.ArgumentParser()
    p.add_argument("--binary", default="target/release/plie")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--shared", default="../shared")
    a = p.parse_args()
    cons, shade = thesis(a.shared)
    scenes = [(s, t, []) for s, t in BUILTIN]
    scenes.append((os.path.join(a.shared, "scenes/cornell-dragon.obj"), "Dragon", CAMERA))
    plie_file = "/tmp/plie-results.plie"

    print("### Construction (blockers only, no regions)\n")
    print("| scene | triangles | leaves | records | blockers/record (max) | build s | build + write s | load s | file bytes | thesis blockers-only s | thesis full s (leaves) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    total_build = 0.0
    for scene, tname, cam in scenes:
        bs = [run(a.binary, ["build", "--scene", scene, "-o", plie_file, "--json"]) for _ in range(a.runs)]
        b = bs[0]
        build = med(x["build_seconds"] for x in bs)
        write = med(x["build_seconds"] + x["write_seconds"] for x in bs)
        loads = [run(a.binary, ["render", "--scene", scene, "-o", "/tmp/plie-results.pfm", "--width", "1", "--height", "1",
                                "--visibility", "lie", "--plie", plie_file, "--json", "--quiet"] + cam)["plie_load_seconds"]
                 for _ in range(a.runs)]
        total_build += build if not scene.endswith(".obj") else 0.0
        tb = cons.get((tname, "blockers_only"), (None, ""))[0]
        tf, tl = cons.get((tname, "full"), (None, ""))
        name = os.path.basename(scene)
        print(f"| {name} | {b['triangles']} | {b['leaves']} | {b['records']} | {b['blockers_mean']:.1f} ({b['blockers_max']}) "
              f"| {build:.4f} | {write:.4f} | {med(loads):.4f} | {b['file_bytes']} | {tb} | {tf} ({tl}) |", flush=True)
    print(f"\nTen built-in scenes, total build time: **{total_build:.3f} s** (thesis Table 8.4: 39.7 s without regions).\n")

    print("### Shading (pass 2 only): 254x254 pixels, 1 eye ray each, 4 shadow rays per light\n")
    print("| scene | triangles | octree s | bvh s | lie s | lie tests/ray | lie vs octree | thesis OCTREE s | thesis LIE s | thesis LIE vs OCTREE |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    tot = {"octree": 0.0, "bvh": 0.0, "lie": 0.0}
    ttot = {"OCTREE": 0.0, "LIE": 0.0}
    for scene, tname, cam in scenes:
        r = {}
        for m in ["octree", "bvh", "lie"]:
            rs = [run(a.binary, ["render", "--scene", scene, "-o", "/tmp/plie-results.pfm", "--width", "254", "--height", "254",
                                 "--eye-rays", "1", "--shadow-rays", "4", "--visibility", m, "--json", "--quiet"] + cam)
                  for _ in range(a.runs)]
            r[m] = (med(x["shading_seconds"] for x in rs), rs[0])
        builtin = not scene.endswith(".obj")
        if builtin:
            for m in tot:
                tot[m] += r[m][0]
        to, tl = shade.get((tname, "OCTREE")), shade.get((tname, "LIE"))
        if builtin and to and tl:
            ttot["OCTREE"] += to
            ttot["LIE"] += tl
        tcmp = f"{to / tl:.2f}x" if to and tl else ""
        print(f"| {os.path.basename(scene)} | {r['lie'][1]['triangles']} | {r['octree'][0]:.4f} | {r['bvh'][0]:.4f} | {r['lie'][0]:.4f} "
              f"| {r['lie'][1]['triangle_tests_per_shadow_ray']:.2f} | {r['octree'][0] / r['lie'][0]:.2f}x | {to} | {tl} | {tcmp} |", flush=True)
    print(f"| **ten scenes** | | **{tot['octree']:.4f}** | **{tot['bvh']:.4f}** | **{tot['lie']:.4f}** | | "
          f"**{tot['octree'] / tot['lie']:.2f}x** | **{ttot['OCTREE']:.2f}** | **{ttot['LIE']:.2f}** | **{ttot['OCTREE'] / ttot['LIE']:.2f}x** |")
    print(f"\nWeighted speed-up of lie over octree, 1 - sum(t_lie)/sum(t_octree): **{100 * (1 - tot['lie'] / tot['octree']):.1f}%** "
          f"(thesis, same setting: {100 * (1 - ttot['LIE'] / ttot['OCTREE']):.1f}%). "
          f"bvh over octree: {100 * (1 - tot['bvh'] / tot['octree']):.1f}%; lie vs bvh: {tot['lie'] / tot['bvh']:.2f}x the bvh's time.")

if __name__ == "__main__":
    main()
