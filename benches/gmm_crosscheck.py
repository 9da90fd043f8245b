#!/usr/bin/env python3
"""Cross-check of crowd::motion's Gaussian mixture fit against scikit-learn.

Fits the fixed dataset that the ignored Rust test `gmm_crosscheck_dataset` writes
(`target/gmm_crosscheck/data.csv`: 300 samples in 3 dimensions from two overlapping
Gaussians) with scikit-learn's `GaussianMixture` (2 components, full covariances,
negligible regularisation, 20 initialisations) and compares the mean log-likelihood
per sample with the Rust fit's (`target/gmm_crosscheck/rust.json`).

    python3 benches/gmm_crosscheck.py

scikit-learn is imported if installed; otherwise it is pip-installed into a venv
under `target/gmm-venv` and the script re-runs itself there. Without network or pip
the check is skipped with a message (exit 0). Exit 1 when the two disagree by more
than 1e-6 nats per sample.
"""
import json
import os
import sys

from sklearn_check import ROOT, ensure_sklearn, rust_dataset

OUT = os.path.join(ROOT, "target", "gmm_crosscheck")
VENV = os.path.join(ROOT, "target", "gmm-venv")
TOL = 1e-6


def main():
    ensure_sklearn(os.path.abspath(__file__), VENV, "GMM_CROSSCHECK_IN_VENV")
    import numpy as np
    from sklearn.mixture import GaussianMixture

    rust_dataset(os.path.join(OUT, "rust.json"), "gmm_crosscheck_dataset")
    x = np.loadtxt(os.path.join(OUT, "data.csv"), delimiter=",")
    rust = json.load(open(os.path.join(OUT, "rust.json")))
    gm = GaussianMixture(
        n_components=rust["k"],
        covariance_type="full",
        reg_covar=1e-12,
        tol=1e-12,
        max_iter=5000,
        n_init=20,
        random_state=0,
    ).fit(x)
    sk = gm.score(x)
    diff = rust["ll_per_sample"] - sk
    print(f"samples {len(x)}, dims {x.shape[1]}, components {rust['k']}")
    print(f"log-likelihood per sample: rust {rust['ll_per_sample']:.9f}  sklearn {sk:.9f}  diff {diff:.2e}")
    print(f"weights: rust {rust['weights']}  sklearn {sorted(gm.weights_.round(6).tolist())}")
    if abs(diff) > TOL:
        print(f"FAIL: differ by more than {TOL}")
        sys.exit(1)
    print("PASS")


if __name__ == "__main__":
    main()
