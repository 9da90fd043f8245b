#!/usr/bin/env python3
"""The reproduction report of formation-transform's comparisons (section 5.2,
Table 2; 5.3; 5.4, Table 3), made by `crowdtouch transform compare`.

For each formation pair and each preset (the project's movement model, and
`--preset paper`: only what the paper has), it runs `transform compare --seeds N
--json` and writes a Markdown section: per variant the arrival time and the three
measures of section 5.1 and the heading-change rate (section 5.3's fluctuation)
over a common window, each a mean with its 95 % confidence interval over the
seeds, the exchanges of targets per run, the
subgroups' convergence and locality, and for each of Table 2's orderings whether
it is reproduced (the intervals are apart in the paper's direction), reversed
(apart the other way) or not told apart. The Table 2 tables have the rows
least-effort, travel-only, euclidean, manhattan, no-feedback and orca; one more
table (Table 3) puts least effort with `--preset paper` against the baselines
ORCA, RVO and steering on square → arrow, with 5 seeds and a 30 s timeout (RVO
steps cost about 60 ms at 300 agents and its runs go to the timeout).

    python3 benches/transform_report.py [--binary B] [--seeds N] [--agents N]
                                        [--timeout S] [--scenario NAME] [--out FILE | --check FILE]

With --out FILE (docs/transforms.md) the text between the markers
`<!-- transform-report:begin -->` and `<!-- transform-report:end -->` is replaced;
otherwise the section is printed. With --check FILE nothing is written: the runs
are made again (they are seeded: the same seeds give the same runs) and every
verdict of the report in FILE (reproduced, reversed, not told apart) must come out
the same, and every row must carry its switches and swap count, the ORCA row
without feedback or exchanges of targets; exit status 1 and the differences
otherwise. CI runs it with the release build. BINARY defaults to target/release/crowdtouch
(`cargo build --release` first).
"""
import argparse
import json
import subprocess
import sys
import time

PAIRS = [("square", "arrow"), ("ring", "two_groups"), ("line", "heart")]
PRESETS = [None, "paper"]
BEGIN = "<!-- transform-report:begin -->"
END = "<!-- transform-report:end -->"

# Table 2 of the paper: least effort lowest on every column (arrival time, I_d,
# "Minimum" = σ_min_dis, "Effort" = σ_curr_eft), against Euclidean and Manhattan.
# Table 3 of the paper: "our method" against these rows of `compare`.
BASELINES = [("orca", "ORCA"), ("rvo", "RVO"), ("steering", "OpenSteer-style steering")]

# The rows of the Table 2 tables; the slow baselines (RVO above all) get a table
# of their own with fewer seeds (`BASELINE_*`).
TABLE2_VARIANTS = "least-effort,travel-only,euclidean,manhattan,no-feedback,orca"
BASELINE_PAIR = ("square", "arrow")
BASELINE_VARIANTS = "least-effort,orca,rvo,steering"
BASELINE_SEEDS = 5
BASELINE_TIMEOUT_S = 30.0

ORDERINGS = [
    ("finish_s", "time (arrival, or rest)"),
    ("i_d", "I_d"),
    ("sigma_min_dis", "σ_min_dis"),
    ("sigma_curr_eft", "σ_curr_eft"),
]


def compare(binary, frm, to, agents, seeds, preset, timeout, scenario="direct",
            variants=TABLE2_VARIANTS):
    cmd = [binary, "transform", "compare", "--from", frm, "--to", to,
           "--agents", str(agents), "--seeds", str(seeds), "--seed", "1", "--json",
           "--scenario", scenario, "--variants", variants]
    if preset:
        cmd += ["--preset", preset]
    if timeout:
        cmd += ["--timeout", str(timeout)]
    t0 = time.monotonic()
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return json.loads(out), time.monotonic() - t0


def iv(x, digits):
    if x is None or x.get("mean") is None:
        return "–"
    return f"{x['mean']:.{digits}f} ± {(x.get('ci95') or 0.0):.{digits}f}"


def verdict(a, b):
    """Least effort `a` against `b`, lower is the paper's better."""
    if a.get("mean") is None or b.get("mean") is None or a.get("n", 0) < 2 or b.get("n", 0) < 2:
        return "not measured"
    if a["mean"] + a["ci95"] < b["mean"] - b["ci95"]:
        return "reproduced"
    if b["mean"] + b["ci95"] < a["mean"] - a["ci95"]:
        return "reversed"
    return "not told apart"


def measure_table(rows, last_label, last_cell):
    """A table's rows: per variant the time, the share in, the offset, the
    measures with their intervals, and a last column `last_label` (`last_cell(r)`)."""
    out = ["| variant | time (s) [n, at rest] | all in (%) | off target (m) | I_d (bits) | σ_min_dis (m) | σ_curr_eft (m) | turn (rad/s) | "
           + last_label + " |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        af = r["arrived_fraction"]["mean"]
        out.append(f"| {r['variant']} | {iv(r['finish_s'], 2)} [{r['finished_runs']}, {r['rest_runs']}] | "
                   f"{100 * af:.1f} | {iv(r['mean_offset_m'], 3)} | {iv(r['i_d'], 3)} | "
                   f"{iv(r['sigma_min_dis'], 4)} | {iv(r['sigma_curr_eft'], 3)} | "
                   f"{iv(r.get('heading_change_rad_s'), 3)} | {last_cell(r)} |")
    return out


def check_rows(v, where):
    """The JSON contract the report relies on; a list of what is wrong."""
    bad = []
    for r in v["rows"]:
        name = f"{where}: row {r.get('variant')}"
        for k in ["feedback", "exchanges", "contacts", "settling", "fades"]:
            if not isinstance(r.get(k), bool):
                bad.append(f"{name}: `{k}` is not a boolean")
        if not isinstance((r.get("swaps") or {}).get("mean"), (int, float)):
            bad.append(f"{name}: no swap count")
        for k in ["finish_s", "arrival_s", "i_d", "sigma_min_dis", "sigma_curr_eft"]:
            if not isinstance(r.get(k), dict) or "mean" not in r[k] or "ci95" not in r[k]:
                bad.append(f"{name}: `{k}` has no mean and ci95")
        if r.get("mover") == "orca" and (r.get("feedback") or r.get("exchanges")):
            bad.append(f"{name}: ORCA runs with feedback or exchanges of targets")
    return bad


def verdicts(text):
    """(section heading, verdict row) for every verdict row of a report."""
    out, heading, in_table = [], None, False
    for line in text.splitlines():
        if line.startswith("#### "):
            heading, in_table = line[5:].strip(), False
        elif line.startswith("| Table 2 ordering") or line.startswith("| Table 3 ordering"):
            in_table = True
        elif in_table and line.startswith("|") and not line.startswith("|---"):
            out.append((heading, " ".join(line.split())))
        elif not line.startswith("|"):
            in_table = False
    return out


def section(results, seeds, agents, timeout, scenario="direct"):
    lines = []
    say = lines.append
    say(f"Made by `python3 benches/transform_report.py --seeds {seeds} --agents {agents}"
        + (f" --timeout {timeout}" if timeout else "")
        + (f" --scenario {scenario}" if scenario != "direct" else "")
        + " --out docs/transforms.md`"
        " (release build); seeds 1 to " + str(seeds) + ". ± is the 95 % confidence interval "
        "of the mean over the seeds (Student's t). The measures are averaged over the "
        "common window: the first seconds that every run of every row of that table lasted. "
        "Time is the paper's simulation time: until every agent arrived (within "
        "`arrive_m` of its target; with `--preset paper`, within one agent radius) or, "
        "without settling, until the crowd came to rest (no agent faster than 0.1 m/s "
        "for 1 s) short of its targets; over the runs that did either (`n`), with how "
        "many ended at rest, and the mean distance from target at the end.")
    say("")
    for (frm, to, preset), (v, secs) in results.items():
        name = "the project's model" if preset is None else "`--preset paper`"
        say(f"#### {frm} → {to}, {v['agents']} agents, {name}")
        say("")
        say(f"Window {v['window_s']:.2f} s; timeout {v['timeout_s']:.0f} s; "
            f"{secs:.0f} s to run. Subgroups: {iv(v['subgroups']['count'], 1)}, "
            f"converged in {v['subgroups']['converged_runs']} of {v['seeds']} seeds, locality "
            f"{iv(v['subgroups']['locality'], 2)}.")
        say("")
        lines += measure_table(v["rows"], "exchanges a run", lambda r: f"{r['swaps']['mean']:.1f}")
        say("")
        rows = {r["variant"]: r for r in v["rows"]}
        le = rows["least-effort"]
        say("| Table 2 ordering (least effort lower) | against Euclidean | against Manhattan |")
        say("|---|---|---|")
        for key, label in ORDERINGS:
            say(f"| {label} | {verdict(le[key], rows['euclidean'][key])} | "
                f"{verdict(le[key], rows['manhattan'][key])} |")
        fb = verdict(le["i_d"], rows["no-feedback"]["i_d"])
        say(f"| §5.3: feedback lowers I_d (least effort against no-feedback) | {fb} | |")
        if "heading_change_rad_s" in le:
            turn = verdict(le["heading_change_rad_s"], rows["no-feedback"]["heading_change_rad_s"])
            say(f"| §5.3, Fig. 12: feedback lowers the heading-change rate | {turn} | |")
        # Table 3's baselines, those the binary has rows for.
        for base, label in BASELINES:
            if base in rows:
                b = verdict(le["sigma_min_dis"], rows[base]["sigma_min_dis"])
                say(f"| §5.4: σ_min_dis of social forces below {label}'s | {b} | |")
        say("")
    return "\n".join(lines) + "\n"


def baseline_section(v, secs, scenario="direct"):
    """Table 3: the paper's method (least effort, `--preset paper`) against the
    baselines, fewer seeds."""
    lines = []
    say = lines.append
    frm, to = BASELINE_PAIR
    say(f"#### Table 3: {frm} → {to}, {v['agents']} agents, `--preset paper` against the baselines")
    say("")
    say(f"`transform compare --from {frm} --to {to} --agents {v['agents']} --seeds {v['seeds']} "
        f"--seed 1 --preset paper --timeout {BASELINE_TIMEOUT_S:.0f} --variants {BASELINE_VARIANTS}"
        + (f" --scenario {scenario}" if scenario != "direct" else "")
        + f" --json`: {v['seeds']} seeds (the RVO rows run to the timeout at about 60 ms a "
        f"step), window {v['window_s']:.2f} s; {secs:.0f} s to run.")
    say("")
    lines += measure_table(v["rows"], "overlapping pairs a run",
                           lambda r: iv(r.get("overlapping_pairs"), 1))
    say("")
    rows = {r["variant"]: r for r in v["rows"]}
    le = rows["least-effort"]
    present = [(b, label) for b, label in BASELINES if b in rows]
    say("| Table 3 ordering (social forces lower) | "
        + " | ".join(f"against {label}" for _, label in present) + " |")
    say("|---" * (len(present) + 1) + "|")
    for key, label in ORDERINGS:
        say(f"| {label} | " + " | ".join(verdict(le[key], rows[b][key]) for b, _ in present) + " |")
    say("")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--binary", default="target/release/crowdtouch")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--agents", type=int, default=300)
    ap.add_argument("--timeout", type=float, default=None)
    ap.add_argument("--scenario", default="direct",
                    help="where every row runs: direct, path, obstacles or crossing")
    ap.add_argument("--out", default=None)
    ap.add_argument("--check", default=None, metavar="FILE")
    a = ap.parse_args()
    results = {}
    for frm, to in PAIRS:
        for preset in PRESETS:
            results[(frm, to, preset)] = compare(a.binary, frm, to, a.agents, a.seeds, preset,
                                                 a.timeout, a.scenario)
            print(f"{frm} -> {to} {preset or 'default'}: {results[(frm, to, preset)][1]:.1f} s", file=sys.stderr)
    frm, to = BASELINE_PAIR
    base = compare(a.binary, frm, to, a.agents, min(a.seeds, BASELINE_SEEDS), "paper",
                   BASELINE_TIMEOUT_S, a.scenario, BASELINE_VARIANTS)
    print(f"{frm} -> {to} baselines: {base[1]:.1f} s", file=sys.stderr)
    text = section(results, a.seeds, a.agents, a.timeout, a.scenario) + "\n" + baseline_section(*base, a.scenario)
    if a.check is not None:
        bad = []
        for (frm, to, preset), (v, _) in results.items():
            bad += check_rows(v, f"{frm} -> {to} {preset or 'default'}")
        bad += check_rows(base[0], "baselines")
        doc = open(a.check, encoding="utf-8").read()
        if BEGIN not in doc or END not in doc:
            print(f"{a.check}: no {BEGIN} … {END} markers", file=sys.stderr)
            return 1
        claimed = verdicts(doc.split(BEGIN, 1)[1].split(END, 1)[0])
        now = verdicts(text)
        if not claimed:
            bad.append(f"{a.check}: the report has no verdicts")
        for c, n in zip(claimed, now):
            if c != n:
                bad.append(f"{c[0]}: the docs say {c[1]!r}, the runs give {n[1]!r}")
        if len(claimed) != len(now):
            bad.append(f"{len(claimed)} verdicts in the docs, {len(now)} from the runs")
        for b in bad:
            print(f"transform report: {b}", file=sys.stderr)
        print(f"transform report: {len(now)} verdicts checked, {len(bad)} problems",
              file=sys.stderr)
        return 1 if bad else 0
    if a.out is None:
        sys.stdout.write(text)
        return 0
    doc = open(a.out, encoding="utf-8").read()
    if BEGIN not in doc or END not in doc:
        print(f"{a.out}: no {BEGIN} … {END} markers", file=sys.stderr)
        return 1
    head, rest = doc.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    open(a.out, "w", encoding="utf-8").write(head + BEGIN + "\n" + text + END + tail)
    return 0


if __name__ == "__main__":
    sys.exit(main())
