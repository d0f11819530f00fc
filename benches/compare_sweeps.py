"""Compare two sweep files bit for bit: every variable's bytes and every attribute.

For refactors that must not change a number: save a sweep before the change and one after, then

    python benches/compare_sweeps.py before.nc after.nc

prints each difference (``wall_time`` is a measurement and always differs; global ``history`` and
``date_created`` are skipped) and exits 1 if any other variable differs.
"""

from __future__ import annotations

import sys

import numpy as np
import xarray as xr

SKIP_ATTRS = ("history", "date_created")


def compare(path_a: str, path_b: str) -> list[str]:
    a = xr.open_dataset(path_a, decode_cf=False)
    b = xr.open_dataset(path_b, decode_cf=False)
    out = []
    for name in sorted(set(a.variables) | set(b.variables)):
        if name not in a.variables or name not in b.variables:
            out.append(f"only in {'first' if name in a.variables else 'second'}: {name}")
            continue
        x, y = a[name].values, b[name].values
        same = x.shape == y.shape and (
            np.array_equal(x.view(np.uint8), y.view(np.uint8)) if x.dtype.kind == "f" else np.array_equal(x, y))
        if not same:
            out.append(f"values differ: {name}")
        if str(dict(a[name].attrs)) != str(dict(b[name].attrs)):
            out.append(f"attributes differ: {name}")
    for k in sorted((set(a.attrs) | set(b.attrs)) - set(SKIP_ATTRS)):
        if str(a.attrs.get(k)) != str(b.attrs.get(k)):
            out.append(f"global attribute differs: {k}: {a.attrs.get(k)!r} | {b.attrs.get(k)!r}")
    return out


if __name__ == "__main__":
    diffs = compare(sys.argv[1], sys.argv[2])
    print("\n".join(diffs) or "identical")
    sys.exit(int(any(d != "values differ: wall_time" and not d.startswith("global") for d in diffs)))
