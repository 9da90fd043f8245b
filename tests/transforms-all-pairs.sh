#!/usr/bin/env bash
# Every ordered pair of shipped formations through `crowdtouch transform` (issue 16:
# "transforms between every pair of shipped formations ... end with every agent at
# a distinct target and no overlapping pair").
#
#   tests/transforms-all-pairs.sh BIN [AGENTS]
#
# BIN is a crowdtouch binary (release, for speed), AGENTS defaults to 100. Prints
# one line per pair and exits 1 when any pair has arrived_fraction < 1, an
# overlapping pair (closer than two radii less 5 mm), or fails to run.
set -uo pipefail

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
    echo "usage: $0 BIN [AGENTS]" >&2
    exit 2
fi
bin=$1
agents=${2:-100}
if [ ! -x "$bin" ]; then
    echo "$0: $bin is not an executable" >&2
    exit 2
fi
if ! command -v python3 >/dev/null 2>&1; then
    echo "$0: python3 is needed to read the JSON reports" >&2
    exit 2
fi

# `crowdtouch formations` prints a header, then one formation a line, its name in
# the first column; `start` is the crowd's start grid, not a shape.
listing=$("$bin" formations) || { echo "$0: '$bin formations' failed" >&2; exit 2; }
mapfile -t names < <(awk 'NR > 1 && NF > 1 && $1 != "start" { print $1 }' <<<"$listing")
if [ "${#names[@]}" -lt 2 ]; then
    echo "$0: fewer than two formations listed by '$bin formations'" >&2
    exit 2
fi

pairs=0
failed=0
for a in "${names[@]}"; do
    for b in "${names[@]}"; do
        [ "$a" = "$b" ] && continue
        pairs=$((pairs + 1))
        if ! out=$("$bin" transform --from "$a" --to "$b" --agents "$agents" --json 2>&1); then
            failed=$((failed + 1))
            printf 'FAIL %-10s -> %-10s did not run: %s\n' "$a" "$b" "$out"
            continue
        fi
        line=$(python3 -c '
import json, sys
v = json.loads(sys.argv[1])
ok = v["arrived_fraction"] >= 1.0 and v["overlapping_pairs"] == 0
md = v["min_distance_m"]
print("%s %-10s -> %-10s arrived %5.1f %%  overlapping pairs %3d  closest %s m  %6.2f s  swaps %4d%s" % (
    "ok  " if ok else "FAIL", sys.argv[2], sys.argv[3], 100.0 * v["arrived_fraction"],
    v["overlapping_pairs"], "%.3f" % md if md is not None else "-", v["simulated_s"],
    v["swaps"], " (timed out)" if v["timed_out"] else ""))
' "$out" "$a" "$b") || { line="FAIL $a -> $b: unreadable report: $out"; }
        printf '%s\n' "$line"
        case "$line" in FAIL*) failed=$((failed + 1)) ;; esac
    done
done

echo "$((pairs - failed)) of $pairs ordered pairs at $agents agents arrived without overlap; $failed failed"
[ "$failed" -eq 0 ]
