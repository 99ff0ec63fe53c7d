#!/usr/bin/env python3
"""Table for docs/results.md: records removed by umbra propagation (SPEC §4.7) and P-LIE construction
time with and without it, per scene, by running the `plie` binary.

Usage: scripts/propagation_table.py [--runs N] [--binary PATH] [--shared DIR] [--threads T] [--big]
Each figure is the median of N `plie build --json` runs: wall seconds of the construction alone
(`blockers_seconds`: octree excluded) and CPU seconds (user + system) of the whole process; the runs
with and without `--no-propagation` are interleaved so that load on a shared machine hits both alike. Default parameters (200 and 24 triangles per leaf, face grids on). `--big`
adds cornell-bunny (69k triangles, minutes per run).
"""
import argparse, json, os, resource, statistics, subprocess, tempfile, time

BUILTIN = ["cornell-cube-1", "cornell-cube-2", "cornell-cube-3", "cornell-cube-4", "cornell-cube-5",
           "huis-a", "huis-b", "huis-c", "dragon", "boot"]
SHARED = ["CornellBox-Original.obj", "cornell-dragon.obj", "boat-lit.obj"]
BIG = ["cornell-bunny.obj"]


def build(binary, scene, max_triangles, propagation, threads, out):
    args = [binary, "build", "--scene", scene, "--max-triangles", str(max_triangles), "-o", out, "--json"]
    if not propagation:
        args.append("--no-propagation")
    if threads:
        args += ["--threads", str(threads)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    v = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    # CPU seconds of the whole process (scene, octree, construction, file): less sensitive to other load.
    v["cpu_seconds"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return v


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--binary", default="target/release/plie")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--shared", default="../shared")
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--big", action="store_true")
    a = p.parse_args()
    scenes = list(BUILTIN)
    shared = os.path.join(a.shared, "scenes")
    for f in SHARED + (BIG if a.big else []):
        path = os.path.join(shared, f)
        if os.path.exists(path):
            scenes.append(path)
        else:
            print(f"notice: {path} not found, skipped")
    loads = [os.getloadavg()[0]]
    t0 = time.time()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "x.plie")
        for scene in scenes:
            for mt in (200, 24):
                on, off = [], []
                for _ in range(a.runs):
                    on.append(build(a.binary, scene, mt, True, a.threads, out))
                    off.append(build(a.binary, scene, mt, False, a.threads, out))
                    loads.append(os.getloadavg()[0])
                rows.append((scene, mt, on, off))
    name = lambda s: os.path.basename(s).removesuffix(".obj")
    med = lambda runs, key: statistics.median(r[key] for r in runs)
    print(f"command: scripts/propagation_table.py --runs {a.runs}" + (f" --threads {a.threads}" if a.threads else "")
          + (" --big" if a.big else ""))
    print(f"threads: {on[0]['threads']}; 1-minute load average during the runs: "
          f"min {min(loads):.2f}, median {statistics.median(loads):.2f}, max {max(loads):.2f}; "
          f"{time.time() - t0:.0f} s in all\n")
    print("| scene | triangles per leaf | leaves | records kept | dark, without propagation | dark: computed + propagated | "
          "principle tests | without s | with s | change | CPU without s | CPU with s | CPU change | propagating s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    tot_on = tot_off = cpu_on = cpu_off = 0.0
    for scene, mt, on, off in rows:
        r, q = on[-1], off[-1]
        prop = r["propagation"]
        s_on, s_off = med(on, "blockers_seconds"), med(off, "blockers_seconds")
        c_on, c_off = med(on, "cpu_seconds"), med(off, "cpu_seconds")
        tot_on, tot_off, cpu_on, cpu_off = tot_on + s_on, tot_off + s_off, cpu_on + c_on, cpu_off + c_off
        pct = lambda x, y: f"{100 * (x - y) / y:+.1f}%" if y > 0 else ""
        print(f"| {name(scene)} | {mt} | {r['leaves']} | {r['records']} | {q['records_removed_umbra']} | "
              f"{r['records_removed_umbra']} + {prop['records_removed']} | {prop['tests']} | {s_off:.3f} | {s_on:.3f} | "
              f"{pct(s_on, s_off)} | {c_off:.2f} | {c_on:.2f} | {pct(c_on, c_off)} | "
              f"{statistics.median(x['propagation']['seconds'] for x in on):.4f} |")
    print(f"| **total** | | | | | | | **{tot_off:.3f}** | **{tot_on:.3f}** | **{pct(tot_on, tot_off)}** | "
          f"**{cpu_off:.2f}** | **{cpu_on:.2f}** | **{pct(cpu_on, cpu_off)}** | |")


if __name__ == "__main__":
    main()
