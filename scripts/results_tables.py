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
    p.add_argument("--modes", default="octree,bvh,lie,grid")
    a = p.parse_args()
    cons, shade = thesis(a.shared)
    scenes = [(s, t, []) for s, t in BUILTIN]
    scenes.append((os.path.join(a.shared, "scenes/cornell-dragon.obj"), "Dragon", CAMERA))
    plie_file = "/tmp/plie-results.plie"

    print("### Construction (blockers only, no regions)\n")
    print("| scene | triangles | leaves | records | blockers/record (max) | build s | build + write s | load s | file bytes | build with grids s | thesis blockers-only s | thesis full s (leaves) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    total_build = total_grid = 0.0
    for scene, tname, cam in scenes:
        bs = [run(a.binary, ["build", "--scene", scene, "-o", plie_file, "--json", "--no-grids"]) for _ in range(a.runs)]
        gs = [run(a.binary, ["build", "--scene", scene, "-o", plie_file + ".g", "--json"]) for _ in range(a.runs)]
        b = bs[0]
        build = med(x["build_seconds"] for x in bs)
        write = med(x["build_seconds"] + x["write_seconds"] for x in bs)
        loads = [run(a.binary, ["render", "--scene", scene, "-o", "/tmp/plie-results.pfm", "--width", "1", "--height", "1",
                                "--visibility", "lie", "--plie", plie_file, "--no-grids", "--json", "--quiet"] + cam)["plie_load_seconds"]
                 for _ in range(a.runs)]
        grid_build = med(x["build_seconds"] for x in gs)
        total_build += build if not scene.endswith(".obj") else 0.0
        total_grid += grid_build if not scene.endswith(".obj") else 0.0
        tb = cons.get((tname, "blockers_only"), (None, ""))[0]
        tf, tl = cons.get((tname, "full"), (None, ""))
        name = os.path.basename(scene)
        print(f"| {name} | {b['triangles']} | {b['leaves']} | {b['records']} | {b['blockers_mean']:.1f} ({b['blockers_max']}) "
              f"| {build:.4f} | {write:.4f} | {med(loads):.4f} | {b['file_bytes']} | {grid_build:.4f} | {tb} | {tf} ({tl}) |", flush=True)
    print(f"\nTen built-in scenes, total build time: **{total_build:.3f} s** without grids, **{total_grid:.3f} s** with face grids (thesis Table 8.4: 39.7 s without regions).\n")

    modes = a.modes.split(",")
    print("### Shading (pass 2 only): 254x254 pixels, 1 eye ray each, 4 shadow rays per light\n")
    print("| scene | triangles | " + " | ".join(f"{m} s" for m in modes) + " | grid tests/ray | thesis OCTREE s | thesis LIE s |")
    print("|---|---|" + "---|" * len(modes) + "---|---|---|")
    tot = {m: 0.0 for m in modes}
    ttot = {"OCTREE": 0.0, "LIE": 0.0}
    for scene, tname, cam in scenes:
        r = {}
        for m in modes:
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
        tests = r["grid"][1]["triangle_tests_per_shadow_ray"] if "grid" in r else 0.0
        print(f"| {os.path.basename(scene)} | {r[modes[0]][1]['triangles']} | " + " | ".join(f"{r[m][0]:.4f}" for m in modes)
              + f" | {tests:.2f} | {to} | {tl} |", flush=True)
    print("| **ten scenes** | | " + " | ".join(f"**{tot[m]:.4f}**" for m in modes) + f" | | **{ttot['OCTREE']:.2f}** | **{ttot['LIE']:.2f}** |")
    print()
    o = tot.get("octree")
    for m in modes:
        if m != "octree" and o:
            print(f"- {m}: weighted speed-up over octree 1 - sum(t_{m})/sum(t_octree) = **{100 * (1 - tot[m] / o):.1f}%** ({o / tot[m]:.2f}x)")
    print(f"- thesis, same setting (Table A.4, LIE over OCTREE): {100 * (1 - ttot['LIE'] / ttot['OCTREE']):.1f}% ({ttot['OCTREE'] / ttot['LIE']:.2f}x)")
    if "bvh" in tot:
        for m in modes:
            if m != "bvh":
                print(f"- {m} takes {tot[m] / tot['bvh']:.2f}x the bvh's time")

if __name__ == "__main__":
    main()
