#!/usr/bin/env python3
"""Inputs for measuring `crowdtouch edit check` and `edit apply --ops` on large or
hostile inputs (issue 27, finding 4 and the script item of finding 7); the figures
in docs/motion-editing.md come from these files.

    edit_inputs.py point N OUT.csv        N people at (5, 5) m at t = 0 s and 1 s
    edit_inputs.py random N OUT.csv       N walkers: at t = 0 s uniform in a square
                                          of side sqrt(N) m (one person per m²), at
                                          t = 1 s up to 1.4 m away in a uniform
                                          direction; seed 27
    edit_inputs.py jitter N OUT.csv       N people standing within 0.05 m each way
                                          of (5, 5) at t = 0 s and 1 s, places to
                                          0.1 mm (mostly not one identical track);
                                          seed 27
    edit_inputs.py script N OUT.ron       N Select+Drag pairs for the 20 people of
                                          `edit_inputs.py group`
    edit_inputs.py group OUT.csv          20 people walking +x for 10 s, 0.5 s steps

Plain Python 3, no packages; the same seed gives the same file.
"""
import math
import random
import sys


def point(n, out):
    with open(out, "w") as f:
        f.write("t,id,x,y\n")
        for i in range(n):
            f.write(f"0,{i},5,5\n1,{i},5,5\n")


def walkers(n, out):
    rng = random.Random(27)
    side = math.sqrt(n)
    with open(out, "w") as f:
        f.write("t,id,x,y\n")
        rows = []
        for i in range(n):
            x, y = rng.uniform(0, side), rng.uniform(0, side)
            a, r = rng.uniform(0, 2 * math.pi), rng.uniform(0, 1.4)
            rows.append(f"0,{i},{x:.3f},{y:.3f}\n")
            rows.append(f"1,{i},{x + r * math.cos(a):.3f},{y + r * math.sin(a):.3f}\n")
        f.writelines(rows)


def jitter(n, out):
    rng = random.Random(27)
    with open(out, "w") as f:
        f.write("t,id,x,y\n")
        for i in range(n):
            x, y = 5 + rng.uniform(-0.05, 0.05), 5 + rng.uniform(-0.05, 0.05)
            f.write(f"0,{i},{x:.4f},{y:.4f}\n1,{i},{x:.4f},{y:.4f}\n")


def group(out):
    with open(out, "w") as f:
        f.write("t,id,x,y\n")
        for k in range(21):
            t = k * 0.5
            for i in range(20):
                f.write(f"{t},{i},{(i % 5) * 1.0 + t:.2f},{(i // 5) * 1.0:.2f}\n")


def script(n, out):
    with open(out, "w") as f:
        f.write("(\n    ops: [\n")
        for k in range(n):
            i = k % 20
            x, y = (i % 5) * 1.0 + 5.0, (i // 5) * 1.0
            f.write(f"        Select(ids: Some([{i}])),\n")
            f.write(f"        Drag(from: ({x}, {y}), to: ({x + 0.01}, {y + 0.01}), correct_speeds: false),\n")
        f.write("    ],\n)\n")


def main(argv):
    if len(argv) >= 2 and argv[0] == "group":
        return group(argv[1])
    if len(argv) != 3:
        sys.exit(__doc__)
    kind, n, out = argv[0], int(argv[1]), argv[2]
    {"point": point, "random": walkers, "jitter": jitter, "script": script}[kind](n, out)


if __name__ == "__main__":
    main(sys.argv[1:])
