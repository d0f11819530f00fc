"""The cost of each model: the describing function against shooting, `auto` against always-`transient`.

Over a sweep around the seed (normal load x arm length, seed speed, unilateral transients):
- TIDF vs shooting at every point with a physical root: the DF's A1 error against the orbit and the
  time of each (per point);
- `auto` (cheapest valid model per point) vs `transient` (every point integrated): regime
  agreement where the transient settled, and the speed-up.

    python benches/bench_auto.py [--loads 12] [--arms 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import tribosweep as ts


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--loads", type=int, default=12)
    ap.add_argument("--arms", type=int, default=3)
    ap.add_argument("--t-max", type=float, default=30.0)
    a = ap.parse_args(argv)
    axes = dict(normal_load=np.linspace(10, 150, a.loads), arm_length=np.linspace(0.05, 0.11, a.arms),
                sliding_speed=[0.46], progress=False, threads=1, t_max=a.t_max)
    t0 = time.perf_counter()
    tidf = ts.sweep(strategy="tidf", **axes)
    t_tidf = time.perf_counter() - t0
    t0 = time.perf_counter()
    shoot = ts.sweep(strategy="shooting", **axes)
    t_shoot = time.perf_counter() - t0
    err = shoot.tidf_a1_error.values.ravel()
    has = np.isfinite(err)
    n = tidf.regime.size
    print(f"{n} points; {has.sum()} with a physical describing-function root and its shooting orbit")
    print(f"  describing function: {t_tidf / n * 1e3:.2f} ms/point (linear + all roots); "
          f"+ shooting: {(t_shoot - t_tidf) / max(has.sum(), 1) * 1e3:.2f} ms/orbit")
    if has.any():
        e = np.abs(err[has])
        print(f"  DF A1 error vs the orbit: median {np.median(e):.1%}, max {e.max():.1%}; "
              f"within 5 %: {(e < 0.05).mean():.0%} of the roots")
        print(f"  orbits stable: {(shoot.orbit_stable.values.ravel()[has] == 1).sum()} of {has.sum()} "
              f"(bilateral saddles around stable sliding are unstable)")
    t0 = time.perf_counter()
    auto = ts.sweep(strategy="auto", **axes)
    t_auto = time.perf_counter() - t0
    t0 = time.perf_counter()
    lean = ts.sweep(strategy="auto", census=False, **axes)
    t_lean = time.perf_counter() - t0
    assert np.array_equal(lean.regime.values, ts.sweep(strategy="auto", **axes).regime.values)
    t0 = time.perf_counter()
    full = ts.sweep(strategy="transient", **axes)
    t_full = time.perf_counter() - t0
    ra, rt = auto.regime.values.ravel(), full.regime.values.ravel()
    settled = (full.status.values.ravel() == 0) & ~np.isin(
        rt, [ts.REGIME_NAMES.index("unstable_undetermined"), ts.REGIME_NAMES.index("irregular")])
    agree = (ra[settled] == rt[settled]).mean() if settled.any() else float("nan")
    decided = np.bincount(auto.decided_by.values.ravel(), minlength=4)
    print(f"auto vs transient over {n} points: regime agreement {agree:.1%} at the {settled.sum()} points where the "
          f"transient settled")
    print(f"  wall time: transient {t_full:.2f} s, auto {t_auto:.2f} s ({t_full / t_auto:.1f}x; with the bistability "
          f"check), auto without it {t_lean:.2f} s ({t_full / t_lean:.1f}x)")
    print(f"  auto decided by linear/tidf/shooting/transient: {decided.tolist()}; bistable points: "
          f"{int((auto.bistable.values == 1).sum())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
