#!/bin/sh
# The pictures of docs/gestures.md, "Keeping the formation": one generated gesture
# of each class (the first of `library test-set --per-class 5`, the test set's own
# seed and devices, that lands in open space and is recognised as its class)
# replayed on the default crowd of 40 agents, once with the paper's
# `gestures.apply: as_sampled` and once with `keep_formation` (the default).
# `replay --svg` draws the mesh before (grey) and after (blue), each agent's path
# and the fingers (red, ringed where they lifted).
#
#   docs/gestures/make-figures.sh [OUT_DIR]   (default: this folder; builds
#                                             target/release if missing)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=$(mkdir -p "${1:-$here}" && cd "${1:-$here}" && pwd)
bin="${CROWDTOUCH:-$root/target/release/crowdtouch}"
if [ ! -x "$bin" ]; then
    (cd "$root" && cargo build --release)
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$bin" library test-set "$work/set" --per-class 5 >/dev/null
sed 's/^        apply: keep_formation,$/        apply: as_sampled,/' "$root/config/crowdtouch.ron" >"$work/as_sampled.ron"
grep -q '^        apply: as_sampled,$' "$work/as_sampled.ron" || {
    echo "make-figures: config/crowdtouch.ron has no 'apply: keep_formation,' line" >&2
    exit 1
}
draw() { # recording, config, picture
    "$bin" replay "$1" -c "$2" --agents 40 --settle 12 -o /dev/null --svg "$3" 2>"$work/log"
}
for dir in "$work"/set/*/; do
    class=$(basename "$dir")
    found=""
    for rec in "$dir"*.jsonl; do
        draw "$rec" "$root/config/crowdtouch.ron" "$out/$class-keep_formation.svg"
        if grep -q "gesture 1: $class," "$work/log"; then
            found="$rec"
            break
        fi
    done
    if [ -z "$found" ]; then
        echo "make-figures: no $class gesture of the test set lands in open space" >&2
        rm -f "$out/$class-keep_formation.svg"
        exit 1
    fi
    draw "$found" "$work/as_sampled.ron" "$out/$class-as_sampled.svg"
    echo "$class: $(basename "$found")"
done
