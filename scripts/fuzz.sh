#!/usr/bin/env bash
# The long fuzz run (docs/fuzzing.md): every cargo-fuzz target of fuzz/, one after the other, for
# SECONDS_PER_TARGET seconds each (default 600), then a table of the results.
#
#   scripts/fuzz.sh                 # all sixteen targets, 10 minutes each
#   SECONDS_PER_TARGET=60 scripts/fuzz.sh exr ies
#
# Needs cargo-fuzz (`cargo install cargo-fuzz --locked`); on a stable toolchain the targets build
# with RUSTC_BOOTSTRAP=1 (libFuzzer's sanitizer flags are nightly-only). The starting corpora are
# the smoke test's seeds, exported to fuzz/seeds/<target>/; what libFuzzer finds is kept in
# fuzz/corpus/<target>/ (both git-ignored), crashes in fuzz/artifacts/<target>/. Logs go to
# fuzz/logs/<target>.log. Exits 1 if any target found a crash, a leak, a timeout or an OOM.
set -euo pipefail
cd "$(dirname "$0")/.."
SECS=${SECONDS_PER_TARGET:-600}
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(scene obj gltf mitsuba_xml ply compiled exr ies ldt sensors scene_info peer texture_png texture_jpeg texture_exr texture_encoded)
export RUSTC_BOOTSTRAP=1
# jpeg-decoder's package carries a rust-toolchain file (1.61.0): under cargo-fuzz, rustup would
# pick it up when compiling that crate unless the toolchain is named in the environment.
RUSTUP_TOOLCHAIN=${RUSTUP_TOOLCHAIN:-$(rustup show active-toolchain | cut -d' ' -f1)}
export RUSTUP_TOOLCHAIN

command -v cargo-fuzz >/dev/null || {
    echo "error: cargo-fuzz is not installed: cargo install cargo-fuzz --locked" >&2
    exit 1
}
LUXEST_FUZZ_SEEDS="$PWD/fuzz/seeds" cargo test -q -p luxest-fuzz --test smoke -- --ignored export_seeds >/dev/null
cargo fuzz build
mkdir -p fuzz/logs
failed=0
rows=()
for t in "${TARGETS[@]}"; do
    mkdir -p "fuzz/corpus/$t"
    log="fuzz/logs/$t.log"
    # -timeout: an input running 10 s is a hang; -rss_limit_mb: 2 GB is an unbounded allocation.
    if cargo fuzz run "$t" "fuzz/corpus/$t" "fuzz/seeds/$t" -- -max_total_time="$SECS" \
        -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 >"$log" 2>&1; then
        result="clean"
    else
        result="FAILED (see $log, fuzz/artifacts/$t/)"
        failed=1
    fi
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
    rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
    rows+=("| $t | ${SECS} s | $execs | $rate | $result |")
done
echo "| target | duration | execs | exec/s | result |"
echo "|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
exit $failed
