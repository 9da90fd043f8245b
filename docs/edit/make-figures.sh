#!/bin/sh
# The example tracks and pictures of docs/motion-editing.md, made by crowdtouch
# itself: `edit path` writes the groups (awk only renumbers the second group of
# the crossing), `edit render` runs and draws every edit.
#
#   docs/edit/make-figures.sh [OUT_DIR]
#
# From anywhere; builds target/release if missing (CROWDTOUCH=PATH runs another
# binary). The tracks and pictures go into docs/edit, or into OUT_DIR with the same
# names (the edit scripts *.ron are still read from docs/edit; docs/edit is then
# left as it is).
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
bin="${CROWDTOUCH:-$root/target/release/crowdtouch}"
if [ ! -x "$bin" ]; then
    (cd "$root" && cargo build --release)
fi
out="${1:-$here}"
mkdir -p "$out"
cd "$out"

# One group of 9 (three rows of three, 0.6 m apart) walking east for 9 m, in the
# open part of the corridor scene.
"$bin" edit path --scene corridor --from 1,2 --to 10,2 --people 9 --step 0.25 \
    -o group.jsonl --force
# Two groups of 9 crossing at (5.5, 4.5) at the same time: the second one's ids
# start at 100.
"$bin" edit path --scene corridor --from 1,4.5 --to 10,4.5 --people 9 --step 0.25 \
    -o /tmp/crowdtouch-east.$$.jsonl --force
"$bin" edit path --scene corridor --from 5.5,0.2 --to 5.5,8.8 --people 9 --step 0.25 \
    -o /tmp/crowdtouch-north.$$.jsonl --force
{
    cat /tmp/crowdtouch-east.$$.jsonl
    awk 'NR > 1 { match($0, /"id":[0-9]+/); id = substr($0, RSTART + 5, RLENGTH - 5);
                  print substr($0, 1, RSTART - 1) "\"id\":" id + 100 substr($0, RSTART + RLENGTH) }' \
        /tmp/crowdtouch-north.$$.jsonl
} > crossing.jsonl
rm -f /tmp/crowdtouch-east.$$.jsonl /tmp/crowdtouch-north.$$.jsonl
# 25 people, five abreast (2.4 m wide), through the corridor scene's 2 m passage.
"$bin" edit path --scene corridor --from 5,4.5 --to 15.5,4.5 --people 25 --step 0.25 \
    -o corridor-group.jsonl --force

r() { "$bin" edit render "$@" --force; }
r group.jsonl --ops "$here/a-drag.ron" --title "(a) a drag without fixed points (eq. 1)" -o a-drag.svg
r group.jsonl --ops "$here/b-drag-fixed.ron" --title "(b) a drag with the ends fixed (eq. 6)" -o b-drag-fixed.svg
r group.jsonl --ops "$here/c-retime.ron" --at 4 --title "(c) a retime (section 3.3): everyone at 4 s, before and after" -o c-retime.svg
r crossing.jsonl --avoid-collisions --threshold 0.4 --at 3.5 \
    --title "(d) two crossing groups kept 0.4 m apart by retiming (section 4.1.2)" -o d-avoid-collisions.svg
r corridor-group.jsonl --avoid-obstacles corridor --at 6 \
    --title "(e) a group wider than the passage kept out of the walls (section 4.2)" -o e-avoid-obstacles.svg
r "$root/tests/fixtures/crowd/crowds_zara01.txt" --ops "$here/f-zara.ron" \
    --title "(f) UCY zara01: the samples of 100-130 s dragged from (5, 6) to (6, 7)" -o f-zara.svg
r group.jsonl --ops "$here/g-turn.ron" --title "(g) the path's start held, its end dragged 90 degrees around it (eq. 6)" -o g-turn.svg
