#!/usr/bin/env python3
"""The comparisons of `crowdtouch transform compare` over ten seeds.

One seed is one draw of the sampling, the desired speeds and the fluctuation; this
runs `transform compare --seed 1..10 --json` and prints, per variant, how many runs
had every agent arrive, the mean arrival time of those, and the mean ± standard
deviation of the three measures of formation-transform section 5.1 (each averaged
over its run). docs/transforms.md shows its output.

    python3 benches/transform_seeds.py FROM TO AGENTS [BINARY]

BINARY defaults to target/release/crowdtouch (`cargo build --release` first).
"""
import json
import statistics as st
import subprocess
import sys


def main() -> int:
    if len(sys.argv) not in (4, 5):
        print(__doc__, file=sys.stderr)
        return 2
    frm, to, agents = sys.argv[1:4]
    binary = sys.argv[4] if len(sys.argv) == 5 else "target/release/crowdtouch"
    seeds = range(1, 11)
    rows: dict[str, list[dict]] = {}
    for seed in seeds:
        out = subprocess.run(
            [binary, "transform", "compare", "--from", frm, "--to", to,
             "--agents", agents, "--seed", str(seed), "--json"],
            capture_output=True, text=True, check=True).stdout
        for v in json.loads(out)["variants"]:
            rows.setdefault(v["variant"], []).append(v)
    print(f"{frm} -> {to}, {agents} agents, seeds {seeds.start}-{seeds.stop - 1} (mean ± sd)")
    for name, vs in rows.items():
        arrived = [v["arrival_s"] for v in vs if v["arrival_s"] is not None]
        when = f"{st.mean(arrived):.2f} s" if arrived else "-"

        def ms(key: str) -> str:
            xs = [v[key] for v in vs]
            return f"{st.mean(xs):.3f} ± {st.pstdev(xs):.3f}"

        print(f"{name:13s} all arrived in {len(arrived)}/{len(vs)} runs, arrival {when}, "
              f"arrived {st.mean(v['arrived_fraction'] for v in vs):.3f}, I_d {ms('I_d')}, "
              f"sigma_min_dis {ms('sigma_min_dis')}, sigma_curr_eft {ms('sigma_curr_eft')}, "
              f"overlapping pairs {sum(v['overlapping_pairs'] for v in vs)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
