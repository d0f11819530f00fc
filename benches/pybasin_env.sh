#!/usr/bin/env bash
# A Python 3.12 environment with tribosweep and pybasin[jax] 0.2.0, for benches/bench_pybasin.py.
# pybasin needs Python >= 3.12; the project itself runs on 3.11. Set PYTHON312 to the interpreter
# (default: the first python3.12 found, then pyenv's 3.12). Builds tribosweep from this checkout.
set -euo pipefail
cd "$(dirname "$0")/.."
py="${PYTHON312:-$(command -v python3.12 2>/dev/null || true)}"
if [ -z "$py" ] || ! "$py" -c 'import sys; assert sys.version_info[:2] == (3, 12)' 2>/dev/null; then
  py="$(ls -d "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.12*/bin/python3.12 2>/dev/null | tail -n 1 || true)"
fi
if [ -z "$py" ]; then
  echo "pybasin_env.sh: no Python 3.12 found; set PYTHON312=/path/to/python3.12" >&2
  exit 2
fi
"$py" -m venv .venv-pybasin
.venv-pybasin/bin/pip install -q --upgrade pip
.venv-pybasin/bin/pip install -q "pybasin[jax]==0.2.0" ".[bench]"
.venv-pybasin/bin/python -c 'import pybasin, jax, tribosweep; print("pybasin", pybasin.__name__, "jax", jax.__version__, "tribosweep ok")'
