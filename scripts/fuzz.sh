#!/usr/bin/env bash
# Runs the cargo-fuzz targets of fuzz/ (issue 16; docs/robustness.md) for SECONDS each, two at a time
# (the machine has 2 cores), on the stable toolchain: libFuzzer with coverage, no sanitizer (`-s none`;
# ASan needs a nightly compiler, and the code under test is safe Rust). Installs cargo-fuzz if absent.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]      default: 60 s, every target (`cargo fuzz list`)
#
# Each target starts from its committed seeds (fuzz/seeds/TARGET/) and the corpus it grew in earlier
# runs here (fuzz/corpus/TARGET/, not committed). A case fails on a panic, an abort, a case over 20 s
# (-timeout) or over 4096 MiB (-rss_limit_mb, -malloc_limit_mb). A failing input is copied to
# fuzz/regressions/TARGET/, which `cargo test -p plie --test fuzz` replays: commit it with the fix.
# Exits non-zero if any target found something. Per-target logs: fuzz/logs/TARGET.log.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"

seconds=${1:-60}
shift || true

if ! command -v cargo-fuzz >/dev/null; then
    echo "fuzz: installing cargo-fuzz"
    cargo install cargo-fuzz --locked
fi

# The committed lock file as it is (cargo fuzz has no --locked), then every target built once.
cargo metadata --locked --format-version 1 >/dev/null
cargo fuzz build -s none
if [ $# -gt 0 ]; then targets=("$@"); else mapfile -t targets < <(cargo fuzz list); fi

mkdir -p logs
run_one() {
    local t=$1
    # Earlier findings are in regressions/ already: keep only this run's.
    rm -rf "artifacts/$t"
    mkdir -p "corpus/$t" "artifacts/$t"
    # RAYON_NUM_THREADS=1: two targets share the two cores.
    if RAYON_NUM_THREADS=1 cargo fuzz run -s none "$t" "corpus/$t" "seeds/$t" -- \
        -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 -malloc_limit_mb=4096 \
        -print_final_stats=1 >"logs/$t.log" 2>&1; then
        echo "fuzz $t: $(grep -Eo 'Done [0-9]+ runs in [0-9]+ second' "logs/$t.log" | tail -1)s, nothing found"
    else
        mkdir -p "regressions/$t"
        local found=0
        for f in "artifacts/$t"/*; do
            [ -f "$f" ] || continue
            cp "$f" "regressions/$t/"
            found=$((found + 1))
            echo "fuzz $t: FOUND $(basename "$f") (copied to fuzz/regressions/$t/)"
        done
        [ "$found" -gt 0 ] || echo "fuzz $t: FAILED without an input saved"
        grep -E "ERROR|panicked|SUMMARY" "logs/$t.log" | head -5 || true
        return 1
    fi
}

failed=0
running=0
for t in "${targets[@]}"; do
    if [ "$running" -ge 2 ]; then
        wait -n || failed=1
        running=$((running - 1))
    fi
    run_one "$t" &
    running=$((running + 1))
done
while [ "$running" -gt 0 ]; do
    wait -n || failed=1
    running=$((running - 1))
done
if [ "$failed" != 0 ]; then
    echo "fuzz: a target found an input that fails (see above and fuzz/logs/)" >&2
    exit 1
fi
