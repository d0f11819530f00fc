"""Branch speed: a branch of unilateral orbits with Floquet multipliers, against independent shooting.

Issue 12's benchmark: "a branch of 500 unilateral orbits with multipliers in under 5 s on one core".
The branch follows the seed's unilateral bouncing cycle (a flight and a 0.2 ms hop per period) down
in the normal load by pseudo-arclength continuation, every point with its monodromy matrix and
multipliers, special points located. Baseline in the same process: the same orbits by independent
calls of ``periodic_orbit`` (shooting from each branch point's own state and period, at the same
tolerances), which is what a natural-parameter scan costs at best. The core is single-threaded
for one branch and one orbit, so both run on one core.

    python benches/bench_branch.py [--points 500] [--repeat 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import tribosweep as ts


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=500)
    ap.add_argument("--repeat", type=int, default=3, help="best of this many runs (the machine is shared)")
    a = ap.parse_args(argv)
    model = ts.SliderModel(contact="unilateral")
    orb, _ = ts.follow_cycle(model)
    # ds_max 0.02 in scaled arclength: about 0.08 N per point near the seed load, so 500 points
    # span the bouncing cycle from the seed load down past its torus points.
    opts = dict(max_points=a.points, ds=0.02, ds_max=0.02)
    best = np.inf
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        ds = ts.branch(model, "normal_load", 1.0, orbit=orb, **opts)
        best = min(best, time.perf_counter() - t0)
    n = ds.sizes["branch_point"]
    special = [ts.BRANCH_POINT_TYPE_NAMES[int(t)] for t in ds.point_type.values if t not in (0, 6)]
    print(f"branch: {n} unilateral orbits with multipliers, {float(ds.parameter[0]):.2f} -> "
          f"{float(ds.parameter[-1]):.2f} N, special points {special}, status {ts.STATUS_NAMES[int(ds.status)]}")  # fmt: skip
    print(f"  {best:.3f} s (best of {a.repeat}), {n / best:.0f} orbits/s, {ds.attrs['n_flows']} flows, "
          f"{ds.attrs['n_rhs'] / n:.0f} rhs per orbit")  # fmt: skip

    pts = ds.where(ds.point_type == 0, drop=True)
    t0 = time.perf_counter()
    dev, fails = 0.0, 0
    for i in range(pts.sizes["branch_point"]):
        p = pts.isel(branch_point=i)
        o = ts.periodic_orbit(model.replace(normal_load=float(p.parameter)), (p.state0.values, float(p.period)))
        if ts.STATUS_NAMES[int(o.status)] != "success":
            fails += 1
            continue
        a_m = np.sort_complex(o.floquet_multipliers.values)
        b_m = np.sort_complex(p.floquet_multiplier_real.values + 1j * p.floquet_multiplier_imag.values)
        dev = max(dev, float(np.max(np.abs(a_m - b_m))))
    base = time.perf_counter() - t0
    m = pts.sizes["branch_point"]
    print(f"baseline: {m} independent periodic_orbit calls from the branch's own orbits: {base:.3f} s, "
          f"{m / base:.0f} orbits/s ({fails} failed)")  # fmt: skip
    print(f"ratio: the branch is {base / m / (best / n):.2f}x the baseline's rate per orbit; "
          f"largest multiplier difference {dev:.1e}")  # fmt: skip
    print(f"issue 12 target: {a.points} orbits in under 5 s -> {'met' if best < 5.0 else 'NOT met'} ({best:.2f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
