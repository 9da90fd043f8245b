#!/usr/bin/env bash
# A coverage-guided fuzzing campaign on the stable toolchain: builds the fuzz targets
# with SanitizerCoverage (inline 8-bit counters, PC table, comparison tracing; the
# flags cargo-fuzz passes, without AddressSanitizer: the library forbids unsafe code
# outside src/sys.rs, which no target reaches), optimised, with debug assertions and
# overflow checks, in fuzz/target/coverage (apart from smoke.sh's debug build).
#
# Usage:
#   fuzz/campaign.sh build                  build every target
#   fuzz/campaign.sh run TARGET LIMIT [ARGS] fuzz TARGET for LIMIT: `600s` (seconds)
#                                           or `1000000` (executions); ARGS go to
#                                           libFuzzer. The growing corpus lives in
#                                           fuzz/target/coverage/corpus/TARGET (kept
#                                           between runs), seeded from fuzz/corpus/TARGET;
#                                           crashes in fuzz/target/coverage/artifacts/.
#   fuzz/campaign.sh merge TARGET           minimise seeds + grown corpus into a fresh
#                                           set (`-merge=1`) that replaces the hashed
#                                           inputs of fuzz/corpus/TARGET (named seeds stay)
#   fuzz/campaign.sh repro TARGET FILE [ARGS]  run one input (a crash, a timeout);
#                                           with `-minimize_crash=1 -runs=100000`
#                                           libFuzzer shrinks a crash
#
# One process at a time, `nice -n 19`: the campaign shares the machine. libFuzzer
# prints `INFO: Loaded 1 modules (N inline 8-bit counters)` and growing `cov:`/`ft:`
# when the build is instrumented; `run` refuses a build without counters.
set -euo pipefail
caller_dir="$PWD"
cd "$(dirname "$0")"
fuzz_dir="$PWD"
out="$fuzz_dir/target/coverage"
host="$(rustc -vV | sed -n 's/^host: //p')"
bin_dir="$out/$host/release"
flags=(
    -Cpasses=sancov-module
    -Cllvm-args=-sanitizer-coverage-level=4
    -Cllvm-args=-sanitizer-coverage-inline-8bit-counters
    -Cllvm-args=-sanitizer-coverage-pc-table
    -Cllvm-args=-sanitizer-coverage-trace-compares
    -Cllvm-args=-sanitizer-coverage-stack-depth
    --cfg fuzzing
    -Cdebug-assertions
    -Coverflow-checks
    -Cforce-frame-pointers
)
# Limits every run uses: text recordings and scenes need room; a slow input over
# 10 s is a finding, as is more than 2 GB resident.
lib_args=(-max_len=65536 -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048
    -print_final_stats=1)

build() {
    # `--target` keeps RUSTFLAGS off build scripts and proc macros, as cargo-fuzz does.
    RUSTFLAGS="${flags[*]}" CARGO_TARGET_DIR="$out" \
        cargo build --release --bins --target "$host"
}

need_bin() {
    local bin="$bin_dir/$1"
    [ -x "$bin" ] || { echo "no $bin: run fuzz/campaign.sh build" >&2; exit 2; }
    local info
    info="$("$bin" -runs=0 2>&1 || true)"
    if ! grep -q 'inline 8-bit counters' <<<"$info"; then
        echo "$bin is not coverage-instrumented" >&2
        exit 2
    fi
}

case "${1:-}" in
build)
    build
    ;;
run)
    target="$2" limit="$3"
    shift 3
    need_bin "$target"
    mkdir -p "$out/corpus/$target" "$out/artifacts/$target" "$out/logs"
    case "$limit" in
    *s) limit_arg="-max_total_time=${limit%s}" ;;
    *) limit_arg="-runs=$limit" ;;
    esac
    log="$out/logs/$target-$(date -u +%Y%m%dT%H%M%SZ).log"
    echo "fuzz $target $limit_arg, log $log"
    status=0
    nice -n 19 "$bin_dir/$target" "$limit_arg" "${lib_args[@]}" \
        -artifact_prefix="$out/artifacts/$target/" \
        "$out/corpus/$target" "corpus/$target" "$@" >"$log" 2>&1 || status=$?
    grep -E '^(INFO: Loaded 1 modules|#[0-9]+[[:space:]]+DONE|stat::|==[0-9]+== ERROR|SUMMARY)' "$log" || true
    grep -E '^artifact_prefix|Test unit written' "$log" || true
    exit "$status"
    ;;
merge)
    target="$2"
    need_bin "$target"
    fresh="$(mktemp -d)"
    trap 'rm -rf "$fresh"' EXIT
    nice -n 19 "$bin_dir/$target" -merge=1 "${lib_args[@]}" \
        "$fresh" "corpus/$target" "$out/corpus/$target" 2>&1 | grep -E 'MERGE-OUTER: [0-9]+ new'
    # Hand-named seeds stay; inputs named by their SHA-1 (libFuzzer's) are replaced.
    find "corpus/$target" -type f -regextype egrep -regex '.*/[0-9a-f]{40}' -delete
    cp "$fresh"/* "corpus/$target/"
    echo "corpus/$target: $(ls "corpus/$target" | wc -l) files, $(du -sh "corpus/$target" | cut -f1)"
    ;;
repro)
    need_bin "$2"
    input="$(cd "$caller_dir" && realpath "$3")"
    "$bin_dir/$2" "${lib_args[@]}" "${@:4}" "$input"
    ;;
*)
    sed -n '2,/^set -euo/p' "$fuzz_dir/$(basename "$0")" | sed '$d; s/^# \{0,1\}//'
    exit 2
    ;;
esac
