#!/bin/sh
# Draws every SVG figure of docs/ again, each with the command the docs give next
# to it (README.md, docs/transforms.md, docs/scenes-and-formations.md,
# docs/scenes/README.md; docs/edit/make-figures.sh for docs/edit/,
# docs/gestures/make-figures.sh for docs/gestures/).
#
#   scripts/docs-figures.sh [--bin PATH] [--out DIR]
#
#   --bin PATH  the crowdtouch binary (default: target/release/crowdtouch, built
#               when missing)
#   --out DIR   write the figures into DIR with docs/'s layout (DIR/*.svg,
#               DIR/scenes/, DIR/edit/ with the track files make-figures.sh
#               writes) and leave docs/ as it is; then say which figures came out
#               byte-identical to docs/'s (default: write into docs/)
#
# Whether the figures still show the same data as others (the committed ones, or
# the ones a binary before a change drew), whatever their style:
#
#   CROWDTOUCH_PICTURES_BEFORE=/tmp/docs-before CROWDTOUCH_PICTURES_AFTER=/tmp/docs-after \
#       cargo test --release --test pictures -- --ignored
#
# The PNG screenshots of the viewer in docs/ are not drawn here (docs/testing.md).
# About 20 s on two cores, most of it the λ sweep of 10 seeds.
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
bin=""
out=""
while [ $# -gt 0 ]; do
    case "$1" in
        --bin) bin="$2"; shift 2 ;;
        --out) out="$2"; shift 2 ;;
        -h|--help) sed -n '2,24p' "$0"; exit 0 ;;
        *) echo "usage: scripts/docs-figures.sh [--bin PATH] [--out DIR]" >&2; exit 2 ;;
    esac
done
absolute() { case "$1" in /*) echo "$1" ;; *) echo "$PWD/$1" ;; esac; }
if [ -z "$bin" ]; then
    bin="$root/target/release/crowdtouch"
    if [ ! -x "$bin" ]; then
        (cd "$root" && cargo build --release)
    fi
fi
bin=$(absolute "$bin")
[ -x "$bin" ] || { echo "docs-figures: no binary at $bin" >&2; exit 1; }
if [ -n "$out" ]; then
    mkdir -p "$out"
    out=$(cd "$out" && pwd)
else
    out="$root/docs"
fi
mkdir -p "$out/scenes" "$out/edit"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
# No user or system config: every command runs on the embedded default or the
# config it names.
unset CROWDTOUCH_CONFIG RUST_LOG
export XDG_CONFIG_HOME="$scratch"
cd "$root"

say() { echo "wrote $1"; }
ct() { "$bin" "$@" > "$scratch/stdout" 2> "$scratch/stderr" < /dev/null || {
    cat "$scratch/stderr" >&2; echo "docs-figures: failed: crowdtouch $*" >&2; exit 1; }; }

# README.md: "Drawn by `crowdtouch replay config/recordings/NAME.jsonl --svg docs/NAME.svg`".
for n in 01-point-drag 02-line-drag 03-line-pinch 04-area-drag 05-area-twist 06-two-hands; do
    ct replay "config/recordings/$n.jsonl" --svg "$out/$n.svg"
    say "$out/$n.svg"
done
# README.md, the gesture figure.
ct replay config/recordings/07-open-space-swipe.jsonl --settle 10 --svg "$out/07-gesture-translate.svg"
say "$out/07-gesture-translate.svg"
# docs/transforms.md: the run at the top, the measures of transform compare, the λ sweep.
ct transform --from square --to arrow --agents 300 --svg "$out/08-transform-square-arrow.svg"
say "$out/08-transform-square-arrow.svg"
ct transform compare --from square --to arrow --agents 300 --svg "$out/08-transform-compare-square-arrow.svg"
say "$out/08-transform-compare-square-arrow.svg"
ct transform compare --from square --to arrow --agents 300 --seeds 10 --seed 1 \
    --lambdas 0,0.05,0.1,0.25,0.5,0.75,1 --svg "$out/08-transform-lambda-sweep.svg"
say "$out/08-transform-lambda-sweep.svg"
# docs/scenes-and-formations.md.
ct formations --config config/crowdtouch.ron -o "$out/formations.svg"
say "$out/formations.svg"
# docs/scenes/README.md: every shipped scene with the defaults.
for f in config/scenes/*.ron; do
    ct scene render "$f" -o "$out/scenes/$(basename "$f" .ron).svg"
    say "$out/scenes/$(basename "$f" .ron).svg"
done
# docs/motion-editing.md: the track files and pictures of docs/edit/.
CROWDTOUCH="$bin" docs/edit/make-figures.sh "$out/edit" > "$scratch/stdout" 2> "$scratch/stderr" || {
    cat "$scratch/stderr" >&2; echo "docs-figures: docs/edit/make-figures.sh failed" >&2; exit 1; }
for f in "$out"/edit/*.svg; do say "$f"; done
# docs/gestures.md, "Keeping the formation": each class as_sampled and keep_formation.
mkdir -p "$out/gestures"
CROWDTOUCH="$bin" docs/gestures/make-figures.sh "$out/gestures" > "$scratch/stdout" 2> "$scratch/stderr" || {
    cat "$scratch/stderr" >&2; echo "docs-figures: docs/gestures/make-figures.sh failed" >&2; exit 1; }
for f in "$out"/gestures/*.svg; do say "$f"; done

if [ "$out" != "$root/docs" ]; then
    same=0; differ=0
    for f in "$out"/*.svg "$out"/scenes/*.svg "$out"/edit/*.svg "$out"/gestures/*.svg; do
        rel=${f#"$out"/}
        if cmp -s "$f" "docs/$rel"; then
            same=$((same + 1))
        elif [ -e "docs/$rel" ]; then
            differ=$((differ + 1)); echo "$rel: differs from docs/$rel"
        else
            differ=$((differ + 1)); echo "$rel: not in docs/"
        fi
    done
    echo "$((same + differ)) figures in $out: $same byte-identical to docs/, $differ not"
fi
