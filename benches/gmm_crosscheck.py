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
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "target", "gmm_crosscheck")
VENV = os.path.join(ROOT, "target", "gmm-venv")
TOL = 1e-6


def ensure_sklearn():
    try:
        import sklearn  # noqa: F401
        return
    except ImportError:
        pass
    if os.environ.get("GMM_CROSSCHECK_IN_VENV"):
        print("SKIPPED: scikit-learn is not importable even in", VENV)
        sys.exit(0)
    py = os.path.join(VENV, "bin", "python")
    try:
        if not os.path.exists(py):
            subprocess.run([sys.executable, "-m", "venv", VENV], check=True)
        subprocess.run([py, "-m", "pip", "install", "-q", "scikit-learn"], check=True)
    except (subprocess.CalledProcessError, OSError) as e:
        print(f"SKIPPED: cannot install scikit-learn into {VENV}: {e}")
        sys.exit(0)
    env = dict(os.environ, GMM_CROSSCHECK_IN_VENV="1")
    sys.exit(subprocess.run([py, os.path.abspath(__file__)], env=env).returncode)


def main():
    ensure_sklearn()
    import numpy as np
    from sklearn.mixture import GaussianMixture

    if not os.path.exists(os.path.join(OUT, "rust.json")):
        subprocess.run(
            ["cargo", "test", "--lib", "gmm_crosscheck_dataset", "--", "--ignored"],
            cwd=ROOT,
            check=True,
        )
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
