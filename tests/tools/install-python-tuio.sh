#!/bin/sh
# Makes the independent TUIO 1.1 decoder python-tuio (PyPI, on python-osc) importable
# for tests/tuio_output.rs. Exit 0 when `import pythontuio` works (already there or
# installed with `pip install --user`), else 1 with the reason on stderr, which the
# test prints as its reason to skip.
set -u
if ! command -v python3 >/dev/null 2>&1; then
    echo "python3 is not installed" >&2
    exit 1
fi
if python3 -c 'import pythontuio, pythonosc' 2>/dev/null; then
    exit 0
fi
if ! python3 -m pip --version >/dev/null 2>&1; then
    echo "python3 has no pip to install python-tuio with" >&2
    exit 1
fi
if ! out=$(python3 -m pip install --user --quiet 'python-tuio==0.0.9' 'python-osc>=1.8' 2>&1) &&
   ! out=$(python3 -m pip install --user --quiet --break-system-packages 'python-tuio==0.0.9' 'python-osc>=1.8' 2>&1); then
    echo "pip install --user python-tuio python-osc failed (no network?): $(echo "$out" | tail -n 1)" >&2
    exit 1
fi
python3 -c 'import pythontuio, pythonosc' 2>/dev/null || {
    echo "python-tuio installed but does not import" >&2
    exit 1
}
