#!/usr/bin/env python3
"""Cross-checks crowdtouch's DTW and LB_Keogh against the dtaidistance package.

    python3 benches/dtw_crosscheck.py            # from the repository root

Runs `cargo run --example dtw_pairs -- target/dtw_pairs.json` (random 1-D and 2-D
random-walk pairs, equal and unequal lengths, with and without a Sakoe-Chiba band, and
crowdtouch's values for each), then recomputes every value with dtaidistance:

    1-D DTW   dtaidistance.dtw.distance(a, b, window=r + 1)      (window=None unbanded)
    2-D DTW   dtaidistance.dtw_ndim.distance(a, b, window=r + 1)
    LB_Keogh  dtaidistance.dtw.lb_keogh(a, b, window=r + 1)       (1-D, equal lengths)

the DTWs with use_c=False (Python) and use_c=True (C); LB_Keogh with the Python
implementation only: in dtaidistance 2.5.1 the C lb_keogh disagrees with the Python
one for about a third of the banded cases (smaller values: a looser but still valid
bound), so the Python code, which reads as the definition, is the reference; the
script also checks that our LB_Keogh never exceeds dtaidistance's DTW. (`dtw.distance_fast` is not used:
in dtaidistance 2.5.1 it returned inf for some plain inputs where both of the above
agree, e.g. a = [0, 1, 2, 1, 0], b = [1, 1, 1, 1, 1].)

crowdtouch's band radius r allows |i - j| <= r; dtaidistance's window w allows
|i - j| < w, hence w = r + 1. Prints the largest absolute difference of each kind and
exits 1 if any exceeds 1e-9.

dtaidistance is installed with pip into a virtual environment under target/ when it
is not importable; without pip or a network the script says so and exits 0 (skipped).
"""

import json
import os
import subprocess
import sys

TOL = 1e-9
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(ROOT, "target", "dtw-venv")


def ensure_dtaidistance():
    """Re-runs this script inside a venv with dtaidistance when it is not importable."""
    try:
        import dtaidistance  # noqa: F401
        import numpy  # noqa: F401
        return
    except ImportError:
        pass
    py = os.path.join(VENV, "bin", "python")
    if os.environ.get("CROWDTOUCH_DTW_VENV") == "1":
        print("SKIPPED: dtaidistance is not importable even in", VENV)
        sys.exit(0)
    try:
        if not os.path.exists(py):
            subprocess.run([sys.executable, "-m", "venv", VENV], check=True)
        subprocess.run([py, "-m", "pip", "install", "-q", "dtaidistance", "numpy"], check=True)
    except (subprocess.CalledProcessError, OSError) as e:
        print(f"SKIPPED: cannot install dtaidistance with pip ({e})")
        sys.exit(0)
    env = dict(os.environ, CROWDTOUCH_DTW_VENV="1")
    sys.exit(subprocess.run([py] + sys.argv, env=env).returncode)


def main():
    ensure_dtaidistance()
    import numpy as np
    import dtaidistance
    from dtaidistance import dtw, dtw_ndim

    out = os.path.join(ROOT, "target", "dtw_pairs.json")
    subprocess.run(["cargo", "run", "--quiet", "--example", "dtw_pairs", "--", out], cwd=ROOT, check=True)
    with open(out) as f:
        cases = json.load(f)

    worst = {"dtw 1-D": 0.0, "dtw 1-D banded": 0.0, "dtw 2-D": 0.0, "dtw 2-D banded": 0.0, "lb_keogh": 0.0}
    counts = {k: 0 for k in worst}
    for c in cases:
        window = None if c["band"] is None else c["band"] + 1
        a = np.array(c["a"], dtype=np.double)
        b = np.array(c["b"], dtype=np.double)
        kind = "dtw 1-D" if c["dim"] == 1 else "dtw 2-D"
        if window is not None:
            kind += " banded"
        # Both of dtaidistance's implementations: Python and C.
        module = dtw if c["dim"] == 1 else dtw_ndim
        for use_c in (False, True):
            ref = module.distance(a, b, window=window, use_c=use_c)
            worst[kind] = max(worst[kind], abs(ref - c["dtw"]))
            counts[kind] += 1
        if c["lb_keogh"] is not None:
            lb = dtw.lb_keogh(a, b, window=window, use_c=False)
            worst["lb_keogh"] = max(worst["lb_keogh"], abs(lb - c["lb_keogh"]))
            counts["lb_keogh"] += 1
            # Ours must also be a lower bound of dtaidistance's DTW.
            if c["lb_keogh"] > ref + TOL:
                print(f"LB_Keogh {c['lb_keogh']} above DTW {ref}")
                worst["lb_keogh"] = float("inf")

    print(f"dtaidistance {dtaidistance.__version__}, {len(cases)} cases")
    for k, v in worst.items():
        print(f"  {k:16} {counts[k]:4} values, max |ours - dtaidistance| = {v:.3e}")
    bad = max(worst.values()) > TOL
    print("FAIL" if bad else "OK", f"(tolerance {TOL})")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
