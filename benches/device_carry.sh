#!/usr/bin/env bash
# Prepare .device-carry/ for a benchmark on a machine that reaches no package index (the 16-core
# device of docs/performance.md): the package with this checkout's release-built extension (abi3,
# so any CPython >= 3.10 loads it), the issue day's build of benches/bench_issue_day.py where it
# has been built here, and the runtime dependencies as wheels for that machine's CPython (3.12 by
# default, DEVICE_PY=3.11 for another). On that machine, with .device-carry named in the device
# tool's `carry`:
#
#     bash .device-carry/run.sh python benches/bench_stribeck.py --threads 16 --repeat 3
#
# run.sh installs only the carried wheels whose distribution that Python lacks (its own numpy,
# scipy and numba stay: the benches' baselines run on them), into /tmp/tribosweep-site, puts the
# package on PYTHONPATH and runs the rest of its arguments. About 55 MB; the tool carries 64 MiB
# with the working tree. Needs `make install-test` first (it builds the extension into .venv).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
OUT=.device-carry
DEVICE_PY=${DEVICE_PY:-3.12}
rm -rf "$OUT" && mkdir -p "$OUT/wheels" "$OUT/pkg"
# The runtime dependencies (pyproject's, and theirs), at this venv's versions where a wheel for the
# device's Python exists; run.sh skips those already there.
pins=$($PY - <<'PYEOF'
from importlib.metadata import version
print(" ".join(f"{n}=={version(n)}" for n in
               ("numpy", "pandas", "xarray", "netCDF4", "cftime", "tqdm", "python-dateutil", "tzdata", "packaging",
                "certifi")))
PYEOF
)
plat=()
for p in manylinux_2_28_x86_64 manylinux_2_27_x86_64 manylinux_2_17_x86_64 manylinux2014_x86_64; do
    plat+=(--platform "$p")
done
for pin in $pins; do
    $PY -m pip download -q --no-deps --only-binary=:all: --python-version "$DEVICE_PY" --implementation cp \
        "${plat[@]}" -d "$OUT/wheels" "$pin"
done
site=$($PY -c "import tribosweep, os; print(os.path.dirname(tribosweep.__file__))")
cp -r "$site" "$OUT/pkg/tribosweep"
if [ -f bench_out/issue_day/pkg/REV ]; then   # the old build of benches/bench_issue_day.py
    mkdir -p "$OUT/issue_day"
    cp -r bench_out/issue_day/pkg "$OUT/issue_day/pkg"
fi
find "$OUT" -name __pycache__ -prune -exec rm -rf {} +
find "$OUT" -name '_core*.so' -exec strip {} + 2>/dev/null || true
cat > "$OUT/run.sh" <<'RUNEOF'
#!/usr/bin/env bash
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
site=/tmp/tribosweep-site
missing=()
for whl in "$here"/wheels/*.whl; do
    name=$(basename "$whl" | cut -d- -f1)
    python3 -c "import importlib.metadata as m, sys; m.version(sys.argv[1])" "$name" 2>/dev/null || missing+=("$whl")
done
if [ ${#missing[@]} -gt 0 ]; then
    python3 -m pip install -q --no-index --no-deps --no-compile --target "$site" "${missing[@]}"
fi
export PYTHONPATH="$here/pkg:$site${PYTHONPATH:+:$PYTHONPATH}"
nproc; lscpu | grep -m1 "Model name" || true
python3 -c "import numpy, tribosweep; print('numpy', numpy.__version__, 'tribosweep', tribosweep.__file__)"
"$@"
RUNEOF
chmod +x "$OUT/run.sh"
du -sh "$OUT"
