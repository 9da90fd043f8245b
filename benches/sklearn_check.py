"""What the scikit-learn cross-checks share (`ap_crosscheck.py`, `gmm_crosscheck.py`).

`ensure_sklearn` returns when scikit-learn is importable; otherwise it pip-installs it
into a venv under `target/` and re-runs the calling script there, or skips (exit 0)
without network or pip. `rust_dataset` runs the ignored Rust test that writes a
cross-check's data set when its file is missing.
"""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def ensure_sklearn(script, venv, in_venv_var):
    """Makes scikit-learn importable for `script` (its absolute path), installing it
    into `venv` and re-running `script` there with `in_venv_var` set when needed."""
    try:
        import sklearn  # noqa: F401
        return
    except ImportError:
        pass
    if os.environ.get(in_venv_var):
        print("SKIPPED: scikit-learn is not importable even in", venv)
        sys.exit(0)
    py = os.path.join(venv, "bin", "python")
    try:
        if not os.path.exists(py):
            subprocess.run([sys.executable, "-m", "venv", venv], check=True)
        subprocess.run([py, "-m", "pip", "install", "-q", "scikit-learn"], check=True)
    except (subprocess.CalledProcessError, OSError) as e:
        print(f"SKIPPED: cannot install scikit-learn into {venv}: {e}")
        sys.exit(0)
    env = dict(os.environ, **{in_venv_var: "1"})
    sys.exit(subprocess.run([py, script], env=env).returncode)


def rust_dataset(path, test):
    """Runs the ignored library test `test` when `path`, the file it writes, is missing."""
    if not os.path.exists(path):
        subprocess.run(
            ["cargo", "test", "--lib", test, "--", "--ignored"],
            cwd=ROOT,
            check=True,
        )
