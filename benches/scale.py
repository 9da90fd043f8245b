#!/usr/bin/env python3
"""The scale table of docs/benchmarks.md: the daemon end to end at 1,000 / 5,000 /
10,000 / 20,000 agents, plain and in two shipped scenes, one `crowdtouch bench e2e
--json` run per row.

    cargo build --release
    python3 benches/scale.py [--seconds 10] [--agents 1000,5000,10000,20000] \
        [--scenes obstacle_course,street] [--binary]

Prints a Markdown table: end-to-end p50 / p99 (input timestamp -> bytes written),
control tick p50 / p99, assignment refreshes per second (worker solve p99), and the
machine's load average before each run (the figures need an idle machine). With
`--binary` each plain row is also run with binary snapshots. Rows above the default
limit (10,000 agents) run with the embedded config as `bench e2e` does; the daemon
itself takes them only with the large-crowd budgets (`MAX_AGENTS_LARGE`).
"""

import argparse
import json
import os
import re
import subprocess
import sys

BIN = os.path.join(os.path.dirname(__file__), "..", "target", "release", "crowdtouch")


def run(agents, seconds, scene=None, binary=False):
    cmd = [BIN, "bench", "e2e", "--agents", str(agents), "--seconds", str(seconds), "--json"]
    if scene:
        cmd += ["--scene", scene]
    if binary:
        cmd += ["--format", "binary"]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    rows = {r["workload"].split(" ")[0]: r for r in json.loads(out)}
    return rows


def refreshes(note):
    m = re.search(r"refreshed ([0-9.]+) times/s", note)
    return float(m.group(1)) if m else float("nan")


def ms(us):
    return f"{us / 1000:.2f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=int, default=10)
    ap.add_argument("--agents", default="1000,5000,10000,20000")
    ap.add_argument("--scenes", default="obstacle_course,street")
    ap.add_argument("--binary", action="store_true")
    a = ap.parse_args()
    if not os.path.exists(BIN):
        sys.exit(f"{BIN} is missing: run `cargo build --release` first")
    counts = [int(x) for x in a.agents.split(",") if x]
    scenes = [None] + [s for s in a.scenes.split(",") if s]
    print("| agents | scene | format | end-to-end p50 / p99 ms | control tick p50 / p99 ms "
          "| assignment refreshes/s (worker p99 ms) | load |")
    print("|---|---|---|---|---|---|---|")
    for scene in scenes:
        for n in counts:
            for binary in ([False, True] if a.binary and scene is None else [False]):
                load = os.getloadavg()[0]
                r = run(n, a.seconds, scene, binary)
                e, c, w = r["end_to_end"], r["control"], r["assignment"]
                print(
                    f"| {n:,} | {scene or 'plain'} | {'binary' if binary else 'json'} "
                    f"| {ms(e['p50_us'])} / {ms(e['p99_us'])} "
                    f"| {ms(c['p50_us'])} / {ms(c['p99_us'])} "
                    f"| {refreshes(w['note']):.1f} ({ms(w['p99_us'])}) | {load:.2f} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
