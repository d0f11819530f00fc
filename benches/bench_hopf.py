"""Hopf curves: speed of the continuation, and its accuracy against a grid of the same cost.

Issue 12's benchmark, in the (normal load, arm length) box of the apparatus at the seed's mu.

1. One Hopf curve of about 200 points: wall time and points/s, against the route a user has
   without it in the same process: ``hopf_load`` (a load grid plus Brent) at each of the curve's
   arm lengths through ``apparatus_model``.
2. The curve from a 64 x 64 grid of growth-rate evaluations (the sign change of the largest real
   part interpolated linearly along each grid line of constant arm length) against the
   continuation given the same number of eigenvalue computations (its step shrunk until it
   spends them), both judged on the same lines against ``hopf_load`` at tight tolerance. Also
   the continuation at its defaults (a fraction of the cost).

Nothing is asserted about time.

    python benches/bench_hopf.py [--repeat 5] [--grid 64]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import tribosweep as ts
from tribosweep import _core
from tribosweep._apparatus import arm_frequencies

SEED = ts.SliderModel(contact="bilateral")  # as measured in the README (Hopf points do not depend on it)
BOX = {"x": ("normal_load", 1.0, 250.0), "y": ("arm_length", 0.05, 0.127)}
WIDTH = BOX["x"][2] - BOX["x"][1]


def best_of(repeat: int, fn):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def exact_load(arm: float, n_grid: int = 400) -> float:
    (h,) = ts.hopf_load(ts.apparatus_model(50.0, arm, 0.46, base=SEED), (1.0, 250.0), n_grid=n_grid)
    return h["normal_load"]


def grid_curve(n: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Sign changes of the largest growth rate along the grid's lines of constant arm length."""
    loads = np.linspace(BOX["x"][1], BOX["x"][2], n)
    arms = np.linspace(BOX["y"][1], BOX["y"][2], n)
    f, a = np.meshgrid(loads, arms, indexing="ij")
    w = arm_frequencies(a.ravel(), SEED)
    names = ["normal_load", "omega_normal", "omega_friction", "omega_torsion"]
    vals = np.column_stack([f.ravel(), w["omega_normal"], w["omega_friction"], w["omega_torsion"]])
    t0 = time.perf_counter()
    out = _core.linear_stability(SEED.values(), SEED.contact, SEED.friction_law, names, vals, 1)
    elapsed = time.perf_counter() - t0
    g = out["growth_rate"].reshape(n, n)
    arm_pts, load_pts = [], []
    for j, arm in enumerate(arms):
        col = g[:, j]
        for i in np.nonzero(np.sign(col[:-1]) != np.sign(col[1:]))[0]:
            t = col[i] / (col[i] - col[i + 1])
            arm_pts.append(arm)
            load_pts.append(loads[i] + t * (loads[i + 1] - loads[i]))
    return np.array(arm_pts), np.array(load_pts), elapsed


def polyline_at(ds, arms: np.ndarray) -> np.ndarray:
    """The continuation's curve, drawn as its polyline, at the given arm lengths."""
    order = np.argsort(ds.arm_length.values)
    return np.interp(arms, ds.arm_length.values[order], ds.normal_load.values[order])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--grid", type=int, default=64)
    a = ap.parse_args(argv)

    # 1. A curve of about 200 points.
    t_curve, ds = best_of(a.repeat, lambda: ts.hopf_curve(SEED, **BOX, step_max=0.0025))
    n = ds.sizes["curve_point"]
    print(f"Hopf curve in {BOX['x'][0]} x {BOX['y'][0]}: {n} points in {t_curve * 1e3:.1f} ms "
          f"({n / t_curve:,.0f} points/s; {ds.attrs['n_eigenvalue_computations']} eigenvalue computations, "
          f"{ds.attrs['n_jacobian_evaluations']} Jacobians)")  # fmt: skip
    arms = ds.arm_length.values
    for n_grid in (400, 60):
        t0 = time.perf_counter()
        loads = np.array([exact_load(float(x), n_grid) for x in arms])
        t_loop = time.perf_counter() - t0
        err = np.max(np.abs(loads - ds.normal_load.values) / loads)
        print(f"  baseline: hopf_load(n_grid={n_grid}) at the same {n} arm lengths: {t_loop * 1e3:.0f} ms "
              f"-> continuation {t_loop / t_curve:.0f}x faster (largest relative difference {err:.1e})")  # fmt: skip

    # 2. Accuracy at the same cost.
    arm_pts, grid_loads, t_grid = grid_curve(a.grid)
    exact = np.array([exact_load(float(x)) for x in arm_pts])
    err_grid = np.abs(grid_loads - exact) / WIDTH
    cost = a.grid * a.grid
    print(f"\n{a.grid} x {a.grid} grid: {cost} eigenvalue computations in {t_grid * 1e3:.1f} ms (one thread); "
          f"{arm_pts.size} crossings on lines of constant arm length")  # fmt: skip
    print(f"  grid error (box units): max {err_grid.max():.2e}, rms {np.sqrt(np.mean(err_grid**2)):.2e}")
    # The continuation spending the same eigenvalue computations: shrink the step until it does.
    step, same = 0.05, None
    while step > 1e-6:
        t_c, c = best_of(1, lambda s=step: ts.hopf_curve(SEED, **BOX, step_max=s))
        if c.attrs["n_eigenvalue_computations"] > cost:
            break
        same, t_same = c, t_c
        step *= 0.7
    print("  continuation work-precision (chord_tol, step_max): points, eigenvalue computations, ms, max polyline error")
    for chord, smax in ((1e-4, 0.05), (1e-5, 0.05), (1e-6, 0.02), (1e-7, 0.01), (1e-8, 0.005)):
        t, c = best_of(a.repeat, lambda c=chord, m=smax: ts.hopf_curve(SEED, **BOX, chord_tol=c, step_max=m))
        err = np.abs(polyline_at(c, arm_pts) - exact) / WIDTH
        print(f"    ({chord:.0e}, {smax}): {c.sizes['curve_point']:5d} {c.attrs['n_eigenvalue_computations']:6d} "
              f"{t * 1e3:7.1f} {err.max():.2e}  (grid: {cost} {t_grid * 1e3:.1f} {err_grid.max():.2e})")  # fmt: skip
    t_default, default = best_of(a.repeat, lambda: ts.hopf_curve(SEED, **BOX))
    for label, c, t in (("same cost", same, t_same), ("defaults", default, t_default)):
        err = np.abs(polyline_at(c, arm_pts) - exact) / WIDTH
        rms = np.sqrt(np.mean(err**2))
        print(f"  continuation ({label}): {c.sizes['curve_point']} points, {c.attrs['n_eigenvalue_computations']} "
              f"eigenvalue computations, {t * 1e3:.1f} ms; polyline error on the same lines: max {err.max():.2e}, "
              f"rms {rms:.2e} -> grid/continuation error ratio {err_grid.max() / err.max():.0f} (max), "
              f"{np.sqrt(np.mean(err_grid**2)) / rms:.0f} (rms); time ratio grid/continuation {t_grid / t:.1f}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
