#!/usr/bin/env python3
"""Cross-check of crowd::transform's affinity propagation against scikit-learn.

The ignored Rust test `ap_crosscheck_dataset` writes four dense instances
(`target/ap_crosscheck/cases.json`: 40, 80, 150 and 300 agents in the unit square,
targets turned with the right half stretched; similarity -Δdis of
formation-transform eq. 20 with Manhattan edge weights; damping 0.7, 0.5, 0.7, 0.9;
at most 1,000 iterations, converged after 15 unchanged) with our labels. This script
runs scikit-learn's `AffinityPropagation(affinity='precomputed', damping=...,
preference=<our median>, max_iter=..., convergence_iter=15, random_state=0)` on the
same similarity matrices and compares the two partitions by the adjusted Rand index
(ARI; 1 = the same partition). The preference is passed as the value our code
computed (the median of the off-diagonal similarities) because scikit-learn's own
default takes the median over the whole matrix, diagonal included. scikit-learn
perturbs S by noise at rounding level (seeded by random_state) and we by a hash of
the pair, so labels are compared as partitions, not index by index.

    python3 benches/ap_crosscheck.py

scikit-learn is imported if installed; otherwise it is pip-installed into a venv
under `target/ap-venv` and the script re-runs itself there. Without network or pip
the check is skipped with a message (exit 0). Exit 1 when a partition differs
(ARI < 1 - 1e-9).

Recorded result (scikit-learn 1.9.1, 2026-12-02): all four partitions identical
(ARI 1.000000), the same exemplars and the same iteration counts:

    n   40 damping 0.7: clusters rust 5 (iterations 53) sklearn 5 (iterations 53); ARI 1
    n   80 damping 0.5: clusters rust 6 (iterations 27) sklearn 6 (iterations 27); ARI 1
    n  150 damping 0.7: clusters rust 9 (iterations 32) sklearn 9 (iterations 32); ARI 1
    n  300 damping 0.9: clusters rust 11 (iterations 69) sklearn 11 (iterations 69); ARI 1
"""
import json
import os
import sys

from sklearn_check import ROOT, ensure_sklearn, rust_dataset

OUT = os.path.join(ROOT, "target", "ap_crosscheck")
VENV = os.path.join(ROOT, "target", "ap-venv")


def main():
    ensure_sklearn(os.path.abspath(__file__), VENV, "AP_CROSSCHECK_IN_VENV")
    import numpy as np
    import sklearn
    from sklearn.cluster import AffinityPropagation
    from sklearn.metrics import adjusted_rand_score

    data = os.path.join(OUT, "cases.json")
    rust_dataset(data, "ap_crosscheck_dataset")
    cases = json.load(open(data))
    print(f"scikit-learn {sklearn.__version__}")
    bad = 0
    for c in cases:
        s = np.array(c["S"], dtype=float)
        ap = AffinityPropagation(
            affinity="precomputed",
            damping=c["damping"],
            preference=c["preference"],
            max_iter=c["max_iter"],
            convergence_iter=c["convergence_iter"],
            random_state=0,
        ).fit(s)
        ours = np.array(c["labels"])
        ari = adjusted_rand_score(ours, ap.labels_)
        same_ex = sorted(ap.cluster_centers_indices_.tolist()) == sorted(c["exemplars"])
        print(
            f"n {c['n']:4d} damping {c['damping']:.1f}: clusters rust {len(c['exemplars'])} "
            f"(iterations {c['iterations']}, converged {c['converged']}) sklearn "
            f"{len(ap.cluster_centers_indices_)} (iterations {ap.n_iter_}); "
            f"ARI {ari:.6f}; same exemplars {same_ex}"
        )
        if ari < 1 - 1e-9:
            bad += 1
    if bad:
        print(f"FAIL: {bad} of {len(cases)} partitions differ")
        sys.exit(1)
    print("PASS")


if __name__ == "__main__":
    main()
