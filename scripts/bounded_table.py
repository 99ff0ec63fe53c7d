#!/usr/bin/env python3
"""Tables for docs/results.md (issue 15): time, peak memory and file size of `plie build` (default
options) per scene, before and after the blocker cap, and for several caps.

Usage: scripts/bounded_table.py --binary target/release/plie [--before PATH] [--caps default,1024,none]
       [--scenes A,B] [--shared DIR] [--timeout S] [--threads T] [--repeat N] [--before-label L]
Each build runs under `/usr/bin/time -v` (peak RSS, CPU time of the whole process) with a timeout,
`--repeat N` times interleaved with the other binaries' (the row shows the run with the median
seconds); a build that does not finish is reported with its elapsed time. Prints one markdown row per (scene, binary, cap) and writes the raw
figures as JSON lines to stderr.
"""
import argparse, json, os, re, subprocess, sys, tempfile, time

SHARED = ["CornellBox-Original.obj", "cornell-dragon.obj", "boat-lit.obj", "cornell-bunny.obj",
          "cornell-dragon-100k.obj", "conference-lit.obj"]
STRESS = ["balusters"]


def run(binary, scene, cap, timeout, threads, out):
    args = ["/usr/bin/time", "-v", binary, "build", "--scene", scene, "-o", out, "--json"]
    if cap is not None:
        args += ["--blocker-cap", cap]
    if threads:
        args += ["--threads", str(threads)]
    t0 = time.time()
    try:
        p = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"scene": scene, "cap": cap, "timeout": True, "wall": time.time() - t0}
    wall = time.time() - t0
    if p.returncode != 0:
        return {"scene": scene, "cap": cap, "error": p.stderr.strip().splitlines()[-1:], "wall": wall}
    v = json.loads(p.stdout)
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
    v["max_rss"] = int(m.group(1)) * 1024 if m else None
    cpu = [re.search(rf"{k} time \(seconds\): ([0-9.]+)", p.stderr) for k in ("User", "System")]
    v["cpu"] = sum(float(c.group(1)) for c in cpu) if all(cpu) else None
    v["wall"] = wall
    v["cap"] = cap
    os.remove(out)
    return v


def row(label, v):
    if v.get("timeout"):
        return f"| {v['scene']} | {label} | > {v['wall']:.0f} (stopped) | | | | | |"
    if "error" in v:
        return f"| {v['scene']} | {label} | error: {v['error']} | | | | | |"
    tri = v["triangles"]
    mb = lambda b: f"{b / 2**20:,.0f}" if b is not None else "?"
    cpu = f"{v['cpu']:.2f} | {1e6 * v['cpu'] / tri:.1f}" if v.get("cpu") is not None else "? | ?"
    return (f"| {os.path.basename(v['scene'])} | {label} | {v['build_seconds']:.2f} | {1e6 * v['build_seconds'] / tri:.1f} | "
            f"{cpu} | {mb(v['max_rss'])} | {mb(v['file_bytes'])} | {v['blockers_total'] + v['grid_blockers_total']:,} | "
            f"{v.get('records_scene', '-')} of {v['records']:,} |")


def median_run(runs):
    """The run with the median `build_seconds` (the first if any failed or timed out)."""
    if any(r.get("timeout") or "error" in r for r in runs):
        return runs[0]
    return sorted(runs, key=lambda r: r["build_seconds"])[len(runs) // 2]


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--binary", default="target/release/plie")
    p.add_argument("--before", default=None)
    p.add_argument("--caps", default="1024")
    p.add_argument("--scenes", default=None)
    p.add_argument("--shared", default="../shared")
    p.add_argument("--timeout", type=float, default=600)
    p.add_argument("--threads", type=int, default=None)
    p.add_argument("--repeat", type=int, default=1, help="runs per build, interleaved; the median is shown")
    p.add_argument("--before-label", default="before")
    a = p.parse_args()
    if a.scenes:
        scenes = a.scenes.split(",")
    else:
        scenes = [os.path.join(a.shared, "scenes", s) for s in SHARED] + STRESS
    print("| scene | build | seconds | µs per triangle | CPU s | CPU µs per triangle | peak RSS (MiB) | file (MiB) | "
          "blocker refs | scene records |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "x.plie")
        for s in scenes:
            runs = []
            if a.before:
                runs.append((a.before_label, a.before, None))
            # `default`: the binary's default options (no --blocker-cap).
            runs += [("default", a.binary, None) if c == "default" else (f"cap {c}", a.binary, c)
                     for c in a.caps.split(",")]
            results = [[] for _ in runs]
            for _ in range(a.repeat):
                for k, (label, binary, cap) in enumerate(runs):
                    v = run(binary, s, cap, a.timeout, a.threads, out)
                    print(json.dumps({k: v.get(k) for k in ["scene", "cap", "build_seconds", "wall", "cpu", "max_rss",
                          "file_bytes", "records", "records_scene", "records_over_budget", "blockers_total",
                          "grid_blockers_total", "peak_memory_bytes", "timeout", "leaves"]} | {"label": label}),
                          file=sys.stderr)
                    results[k].append(v)
            for (label, _, _), rs in zip(runs, results):
                print(row(label, median_run(rs)), flush=True)


if __name__ == "__main__":
    main()
