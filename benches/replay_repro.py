#!/usr/bin/env python3
"""Replays issue 14's recording reproductions and prints peak RSS and wall time.

Usage: benches/replay_repro.py [BINARY] [--run SECONDS]

BINARY defaults to target/release/crowdtouch. For each reproduction it runs
`BINARY replay FILE > /dev/null` under `/usr/bin/time -v` (2-minute timeout) and
prints one markdown row: file, exit status, maximum resident set (MB), wall time
(s), bytes written. With --run it also starts `BINARY run` on a config replaying
each file (looped) for SECONDS and prints its maximum resident set. The files are
generated in a temporary directory (about 170 MB).
"""

import math
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHIPPED = os.path.join(ROOT, "config", "recordings", "01-point-drag.jsonl")
DELL = os.path.join(ROOT, "tests", "fixtures", "dell-canvas-27-touch.evemu")


def generate(d):
    """Writes the reproductions into `d`; returns their paths in order."""
    src = open(SHIPPED).read().splitlines()
    head6 = "\n".join(src[:6]) + "\n"
    hdr = src[0]
    files = [("baseline: 01-point-drag.jsonl", SHIPPED)]

    def put(name, write):
        p = os.path.join(d, name)
        with open(p, "w") as f:
            write(f)
        files.append((name, p))

    for name, t in [("gap-max.jsonl", 2**64 - 1), ("gap-1e8.jsonl", 10**8), ("gap-1e9.jsonl", 10**9)]:
        put(name, lambda f, t=t: f.write(head6 + '{"t_us":%d,"contacts":[]}\n' % t))

    # The Dell Canvas recording with 10^9 s added to the second half of its events.
    lines = open(DELL).read().splitlines()
    ev = [i for i, l in enumerate(lines) if l.startswith("E:")]
    mid = ev[len(ev) // 2]
    while lines[mid].split("#")[0].split()[2:4] != ["0000", "0000"]:
        mid += 1

    def jump(f):
        for i, l in enumerate(lines):
            if l.startswith("E:") and i > mid:
                p = l.split(None, 2)
                sec, us = p[1].split(".")
                l = "E: %d.%s %s" % (int(sec) + 10**9, us, p[2])
            f.write(l + "\n")

    put("evemu-jump.evemu", jump)

    def empty(f):
        f.write(hdr + "\n")
        f.write('{"t_us":0,"contacts":[{"id":1,"x":16000,"y":16000}]}\n')
        for i in range(1, 1500000):
            f.write('{"t_us":%d,"contacts":[]}\n' % (i * 8333))

    put("empty-frames.jsonl", empty)

    def many(f):
        f.write(hdr + "\n")
        f.write('{"t_us":0,"contacts":[')
        f.write(",".join('{"id":%d,"x":1,"y":2}' % i for i in range(1900000)))
        f.write("]}\n")

    put("many-contacts.jsonl", many)

    def junk(f):
        f.write(hdr + "\n")
        f.write('{"t_us":0,"contacts":[{"id":1,"x":16000,"y":16000}],"junk":[')
        f.write(",".join(["0"] * 30000000))
        f.write("]}\n")
        f.write('{"t_us":8333,"contacts":[]}\n')

    put("unknown-key.jsonl", junk)

    def drag(f):
        f.write(hdr + "\n")
        for i in range(200000):
            a = i * 0.001
            f.write(
                '{"t_us":%d,"contacts":[{"id":1,"x":%.1f,"y":%.1f}]}\n'
                % (i * 8333, 16000 + 8000 * math.cos(a), 16000 + 8000 * math.sin(a))
            )
        f.write('{"t_us":%d,"contacts":[]}\n' % (200000 * 8333))

    put("frames-200k.jsonl", drag)
    return files


def timed(cmd, timeout):
    """Runs `cmd` under /usr/bin/time -v: (exit status, max RSS kB, wall s, stdout bytes, stderr)."""
    with tempfile.NamedTemporaryFile("r") as t, tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        full = ["/usr/bin/time", "-v", "-o", t.name, "timeout", "-s", "TERM", str(timeout)] + cmd
        rc = subprocess.call(full, stdout=out, stderr=err)
        report = open(t.name).read()
        rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", report).group(1))
        wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", report).group(1)
        secs = sum(float(x) * 60**i for i, x in enumerate(reversed(wall.split(":"))))
        out.seek(0, os.SEEK_END)
        err.seek(0)
        first = err.read().decode("utf-8", "replace").strip().splitlines()
        return rc, rss, secs, out.tell(), (first[0] if first else "")


def run_config(d, recording):
    text = open(os.path.join(ROOT, "config", "crowdtouch.ron")).read()
    start = text.index("            files: [")
    end = text.index("],", start) + 2
    text = text[:start] + '            files: ["%s"],' % recording + text[end:]
    text = text.replace("priority: Some(20)", "priority: None").replace("lock_memory: true", "lock_memory: false")
    p = os.path.join(d, "run-%s.ron" % os.path.basename(recording))
    open(p, "w").write(text)
    return p


def main():
    args = sys.argv[1:]
    run_secs = None
    if "--run" in args:
        i = args.index("--run")
        run_secs = int(args[i + 1])
        del args[i : i + 2]
    binary = args[0] if args else os.path.join(ROOT, "target", "release", "crowdtouch")
    with tempfile.TemporaryDirectory() as d:
        files = generate(d)
        print("| file | exit | max RSS (MB) | wall (s) | stdout (MB) | first stderr line |")
        print("|---|---|---|---|---|---|")
        for name, path in files:
            rc, rss, secs, out, err = timed([binary, "replay", path], 120)
            print("| %s | %s | %.1f | %.2f | %.1f | %s |" % (name, "timeout" if rc == 124 else rc, rss / 1024, secs, out / 1e6, err[:110]))
        if run_secs:
            print()
            print("| `run` replaying (looped, %d s) | max RSS (MB) |" % run_secs)
            print("|---|---|")
            for name, path in files:
                if name.startswith(("many", "unknown")):
                    continue
                cfg = run_config(d, path)
                rc, rss, _, _, _ = timed([binary, "run", "-c", cfg, "--socket", os.path.join(d, "ct.sock")], run_secs)
                print("| %s | %.1f |" % (name, rss / 1024))


if __name__ == "__main__":
    main()
