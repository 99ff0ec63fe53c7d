#!/usr/bin/env bash
# Stress test (issue 16): N processes at once each build the P-LIE of one scene and render with it,
# every process under an address-space limit and a time limit; all must succeed and every .plie file
# and every image must be byte-identical.
#
#   scripts/stress.sh [SCENE] [N]      (default: ../shared/scenes/conference-lit.obj, the largest shared
#                                      scene, and 8 processes)
# Environment: PLIE (the binary; default target/release/plie), STRESS_MEM_MB (per-process address-space
# limit, default 4096), STRESS_SECONDS (per-process time limit, default 900), STRESS_SIZE (image side,
# default 32), STRESS_THREADS (threads per process, default 1).
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-../shared/scenes/conference-lit.obj}
n=${2:-8}
bin=${PLIE:-target/release/plie}
mem_mb=${STRESS_MEM_MB:-4096}
seconds=${STRESS_SECONDS:-900}
size=${STRESS_SIZE:-32}
threads=${STRESS_THREADS:-1}
if [ ! -e "$scene" ] && [[ "$scene" == */* ]]; then
    echo "stress: notice: $scene is absent; skipping"
    exit 0
fi
[ -x "$bin" ] || { echo "stress: $bin not found; run cargo build --release first" >&2; exit 1; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "stress: $n x (build + render) of $scene, ${mem_mb} MiB and ${seconds} s each, $threads thread(s)"
start=$(date +%s)
pids=()
for i in $(seq 1 "$n"); do
    (
        ulimit -v $((mem_mb * 1024))
        step() {
            local what=$1 rc=0
            shift
            timeout "$seconds" "$bin" "$@" || rc=$?
            [ "$rc" = 124 ] && echo "$what: killed after the time limit of $seconds s"
            [ "$rc" = 0 ] || { echo "$what: exit code $rc"; exit 1; }
        }
        step build build --scene "$scene" -o "$out/$i.plie" --threads "$threads" --quiet
        step render render --scene "$scene" --plie "$out/$i.plie" --visibility lie -o "$out/$i.pfm" \
            --width "$size" --height "$size" --eye-rays 1 --shadow-rays 4 --threads "$threads" --quiet
    ) >"$out/$i.log" 2>&1 &
    pids+=($!)
done
fail=0
for i in $(seq 1 "$n"); do
    if ! wait "${pids[$((i - 1))]}"; then
        echo "stress: process $i failed:" >&2
        cat "$out/$i.log" >&2
        fail=1
    fi
done
[ "$fail" = 0 ] || exit 1
for i in $(seq 2 "$n"); do
    cmp -s "$out/1.plie" "$out/$i.plie" || { echo "stress: $i.plie differs from 1.plie" >&2; exit 1; }
    cmp -s "$out/1.pfm" "$out/$i.pfm" || { echo "stress: $i.pfm differs from 1.pfm" >&2; exit 1; }
done
echo "stress: OK, $n identical .plie files ($(stat -c %s "$out/1.plie") bytes) and images in $(($(date +%s) - start)) s"
