#!/usr/bin/env bash
# Prepare .device-carry/ for a benchmark on a machine that reaches no package index (the 16-core
# device of docs/performance.md): the package with this checkout's release-built extension, and the
# runtime dependencies as wheels at the versions of this .venv. On that machine, with
# .device-carry named in the device tool's `carry`:
#
#     bash .device-carry/run.sh python benches/bench_stribeck.py --threads 16 --repeat 3
#
# run.sh installs the wheels with pip (no index), puts the package on PYTHONPATH and runs the rest
# of its arguments. About 50 MB; the tool carries 64 MiB with the working tree. Needs `make
# install-test` first (it builds the extension into .venv).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
OUT=.device-carry
rm -rf "$OUT" && mkdir -p "$OUT/wheels" "$OUT/pkg"
# The runtime dependencies (pyproject's, and theirs) at this venv's versions, no test extras.
pins=$($PY - <<'PYEOF'
from importlib.metadata import version
print(" ".join(f"{n}=={version(n)}" for n in
               ("numpy", "pandas", "xarray", "netCDF4", "cftime", "tqdm", "python-dateutil", "tzdata", "packaging",
                "certifi")))
PYEOF
)
# shellcheck disable=SC2086
$PY -m pip download -q --no-deps -d "$OUT/wheels" $pins
site=$($PY -c "import tribosweep, os; print(os.path.dirname(tribosweep.__file__))")
cp -r "$site" "$OUT/pkg/tribosweep"
find "$OUT/pkg" -name __pycache__ -prune -exec rm -rf {} +
strip "$OUT/pkg/tribosweep/"_core*.so 2>/dev/null || true
cat > "$OUT/run.sh" <<'RUNEOF'
#!/usr/bin/env bash
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
python3 -m pip install -q --no-index "$here"/wheels/*.whl
export PYTHONPATH="$here/pkg${PYTHONPATH:+:$PYTHONPATH}"
nproc; lscpu | grep -m1 "Model name" || true
"$@"
RUNEOF
chmod +x "$OUT/run.sh"
du -sh "$OUT"
