#!/usr/bin/env bash
# Builds every fuzz target on the stable toolchain (libFuzzer's driver, no coverage
# instrumentation) and runs each over a copy of its corpus plus RUNS random
# mutations. Not a fuzzing campaign (that is fuzz/campaign.sh): a check that the
# targets build and that the parsers survive the corpus and its mutations.
# Usage: fuzz/smoke.sh [RUNS]   (default 20000)
set -euo pipefail
cd "$(dirname "$0")"
runs="${1:-20000}"
cargo build --quiet --bins
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
status=0
for src in fuzz_targets/*.rs; do
    name="$(basename "$src" .rs)"
    [ "$name" = common ] && continue
    mkdir -p "$work/$name" "$work/artifacts/$name"
    cp -r "corpus/$name/." "$work/$name/" 2>/dev/null || true
    if out="$(./target/debug/"$name" -runs="$runs" -max_len=16384 -seed=1 \
            -artifact_prefix="$work/artifacts/$name/" "$work/$name" 2>&1)"; then
        printf 'fuzz %-26s ok   (%s)\n' "$name" "$(grep -E '^Done' <<<"$out" | head -1)"
    else
        printf 'fuzz %-26s FAIL\n%s\n' "$name" "$(tail -n 40 <<<"$out")"
        status=1
    fi
done
exit "$status"
