#!/usr/bin/env bash
# Issue 20's scaling figures (docs/results.md, "Walkthroughs on Ray"): frames per minute of
# `python -m plie.farm` with 1 and 2 local Ray workers on the conference room, and the per-task cost
# of fetching the P-LIE from Ray's object store against reading it from a file. Needs the release
# `plie` binary, ../shared/scenes, and a Python with the plie package and Ray (PY, default
# target/python-ci-venv/bin/python as scripts/python-ci.sh makes it). Prints one JSON line per run.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-target/python-ci-venv/bin/python}
out=${OUT:-/tmp/plie-farm-scaling}
scene=../shared/scenes/conference-lit.obj
path=docs/walkthrough/conference.json
mkdir -p "$out"
[ -f "$out/conference.plie" ] || target/release/plie build --scene "$scene" -o "$out/conference.plie" --quiet
summary='import json, statistics as st, sys
d = json.load(sys.stdin); t = [x for x in d["tasks"] if x["env_source"] != "cache"]
f = [x["fetch_seconds"] for x in t]; c = [x["decode_seconds"] for x in t]
print(json.dumps({"run": sys.argv[1], "frames": d["frames"], "seconds": round(d["seconds"], 2),
    "frames_per_minute": round(d["frames_per_minute"], 1), "env_loads": len(t), "source": sorted({x["env_source"] for x in t}),
    "fetch_median_s": round(st.median(f), 4), "decode_median_s": round(st.median(c), 3),
    "workers": len({x["pid"] for x in d["tasks"]})}))'
for rep in 1 2; do
    for n in 1 2; do
        rm -rf "$out/w$n"; mkdir -p "$out/w$n"
        $PY -m plie.farm --scene "$scene" --plie "$out/conference.plie" --camera-path "$path" \
            -o "$out/w$n/frame_####.png" --num-cpus "$n" --width 320 --height 240 --eye-rays 2 --shadow-rays 16 \
            --json 2>/dev/null | $PY -c "$summary" "scaling: $n worker(s), rep $rep"
    done
done
for src in store file; do
    extra=(); [ "$src" = file ] && extra=(--env-from-file)
    rm -rf "$out/o"; mkdir -p "$out/o"
    $PY -m plie.farm --scene "$scene" --plie "$out/conference.plie" --camera-path "$path" --frames 0..9 \
        -o "$out/o/frame_####.png" --num-cpus 1 --width 160 --height 120 --eye-rays 1 --shadow-rays 16 \
        --no-cache "${extra[@]}" --json 2>/dev/null | $PY -c "$summary" "overhead: every task loads the P-LIE from $src"
done
