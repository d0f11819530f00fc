"""Cost of the attractor census: one point at large K, and the default CLI sweep with K disturbances per point.

Prints what it measured and the settings; ratios are against the same sweep without the census,
run in the same process (the machines are shared: absolute seconds drift with their load).

    python benches/bench_census.py                 # one point K = 1024, 2,000-point sweep at K = 16
    python benches/bench_census.py --sweep-points 120 --samples 16 --threads 2
    python benches/bench_census.py --scipy 128 --sweep-points 0   # labels against scipy, 128 starts
    python benches/bench_census.py --compare --sweep-points 0     # the stationarity stop against t_max
    python benches/bench_census.py --compare --blocks 128,256 --sweep-points 0   # two block sizes
    python benches/bench_census.py --recurrence --sweep-points 0  # recurrence on the pilots' attractors, on/off
    python benches/bench_census.py --rtol 1e-6,1e-8,1e-10 --sweep-points 0   # the census's accuracy and cost
    python benches/bench_census.py --stop-tol 1e-5,1e-3 --law switch --sweep-points 0   # first stops, Stribeck sweep
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import tribosweep as ts
from tribosweep._settings import DEFAULTS
from tribosweep.bench.workprecision import machine_line


def one_point(k: int, threads: int | None) -> None:
    m = ts.SliderModel(contact="unilateral")
    t0 = time.perf_counter()
    ds = ts.census(m, samples=k, threads=threads)
    dt = time.perf_counter() - t0
    p, se = ds.basin_fraction.values, ds.basin_fraction_se.values
    frac = ", ".join(f"{n} {a:.3f}+-{b:.3f}" for n, a, b in zip(ts.ATTRACTOR_NAMES, p, se))
    t_end = ds.t_end.values
    print(f"seed census, K = {k}: {dt:.2f} s ({k / dt:.0f} disturbances/s), {frac}")
    print(f"  simulated time per disturbance: mean {t_end.mean():.2f} s, max {t_end.max():.1f} s; "
          f"rhs per disturbance {ds.n_rhs.values.mean():.0f}")  # fmt: skip


def scipy_agreement(n: int, horizon: float = 1.5) -> None:
    """The census's labels at the seed against the independent scipy classification, with its cost."""
    from concurrent.futures import ProcessPoolExecutor

    from tribosweep.bench import census_check

    m = ts.SliderModel(contact="unilateral")
    t0 = time.perf_counter()
    ds = ts.census(m, samples=n, threads=1)
    t_core = time.perf_counter() - t0
    params = {k: float(v) for k, v in m.values().items()}
    orbit, _ = ts.follow_cycle(m)
    half = census_check.cycle_half_range(params, orbit.state0.values)
    sad = float(ds.attrs["saddle_a1"])
    t0 = time.perf_counter()
    with ProcessPoolExecutor(os.cpu_count()) as pool:
        labels = list(pool.map(census_check.classify_unilateral, [params] * n, ds.y0.values, [horizon] * n,
                               [sad] * n, [half] * n, chunksize=4))  # fmt: skip
    t_scipy = time.perf_counter() - t0
    core = [ts.ATTRACTOR_NAMES[a] for a in ds.attractor_reached.values]
    both = [(a, b) for a, b in zip(core, labels) if b != "unsettled" and a != "irregular"]
    agree = sum(a == b for a, b in both)
    print(f"scipy classification of the seed census, {n} starts, horizon {horizon} s: {len(both)} settled in both, "
          f"{agree} agree ({100 * agree / max(len(both), 1):.1f} %); census {t_core:.2f} s on one thread (to the "
          f"attractor), scipy {t_scipy:.1f} s on {os.cpu_count()} processes (to the horizon only)")  # fmt: skip
    for i, (a, b) in enumerate(zip(core, labels)):
        if b != "unsettled" and a != "irregular" and a != b:
            print(f"  disagree: sample {i}: census {a}, scipy {b}")


def sweep(n_loads: int, n_arms: int, n_speeds: int, k: int, threads: int | None) -> None:
    axes = dict(normal_load=np.linspace(10, 150, n_loads), arm_length=np.linspace(0.05, 0.127, n_arms),
                sliding_speed=np.linspace(0.3, 0.6, n_speeds), progress=False, threads=threads)  # fmt: skip
    t0 = time.perf_counter()
    ts.sweep(census=False, **axes)
    t_lean = time.perf_counter() - t0
    t0 = time.perf_counter()
    ds = ts.sweep(samples=k, **axes)
    t_full = time.perf_counter() - t0
    n = int(ds.regime.size)
    censused = int((ds.census_samples.values > 0).sum())
    coexist = int((ds.bistable.values == 1).sum())
    print(f"sweep {n} points ({n_loads} loads x {n_arms} arms x {n_speeds} speeds), K = {k}, threads {threads}: "
          f"{t_full:.1f} s with the census ({n / t_full:.0f} points/s), {t_lean:.2f} s without "
          f"({t_full / t_lean:.1f}x); census at {censused} points (shared across speeds: "
          f"{censused // n_speeds} computed), coexisting attractors at {coexist}")  # fmt: skip


def compare_irregular_stop(n_loads: int, n_arms: int, k: int, threads: int | None,
                           blocks: tuple[int, ...] = (DEFAULTS.irregular.block,)) -> None:  # fmt: skip
    """The census with the stationarity stop of irregular motion (each of ``blocks`` sections per
    block) against runs to t_max, sample by sample.

    The points are those the default sweep censuses (stable, with a saddle cycle) at 0.3 m/s; the
    census there is the same at every speed under constant friction.
    """
    import dataclasses

    pts = grid_points(n_loads, n_arms, threads)
    out = {}
    for block in (0, *blocks):
        t0 = time.perf_counter()
        runs = [ts.census(dataclasses.replace(ts.apparatus_model(a, b, 0.3), contact="unilateral"), samples=k,
                          irregular_block=block, threads=threads) for a, b in pts]  # fmt: skip
        out[block] = (time.perf_counter() - t0, np.array([r.attractor_reached.values for r in runs]),
                      np.array([r.t_end.values for r in runs]))  # fmt: skip
    names = ts.ATTRACTOR_NAMES
    w0, a0, t0_ = out[0]
    for block, (w, a, t) in out.items():
        label = "to t_max" if block == 0 else f"block {block}"
        counts = ", ".join(f"{n} {int((a == i).sum())}" for i, n in enumerate(names))
        print(f"census {label}: {len(pts)} points x K = {k}: {w:.1f} s, simulated {t.sum():.0f} s; {counts}")
        if block == 0:
            continue
        moved = a0 != a
        pairs: dict[str, int] = {}
        for x, y in zip(a0[moved], a[moved]):
            key = f"{names[x] if x >= 0 else 'failed'} -> {names[y] if y >= 0 else 'failed'}"
            pairs[key] = pairs.get(key, 0) + 1
        print(f"  labels that differ from t_max: {int(moved.sum())} of {a0.size} ({100 * moved.mean():.1f} %): "
              f"{pairs}; cost {w0 / w:.2f}x lower, simulated time {t0_.sum() / t.sum():.2f}x")  # fmt: skip
        z = fraction_shift(a0, a, k)
        load, arm = pts[int(np.argmax(z))]
        print(f"  points where a fraction moves by more than 2 / 3 standard errors: {int((z > 2).sum())} / "
              f"{int((z > 3).sum())} of {len(pts)} (largest {z.max():.2f}, "
              f"at {load:.1f} N, {100 * arm:.1f} cm)")  # fmt: skip


def compare_recurrence(k: int, threads: int | None) -> None:
    """The census with recurrence on the pilots' attractors against each sample deciding by its own
    blocks, sample by sample, on the points the default sweep censuses."""
    import dataclasses

    pts = grid_points(40, 10, threads)
    models = [dataclasses.replace(ts.apparatus_model(a, b, 0.3), contact="unilateral") for a, b in pts]
    out = {}
    for rec in (False, True):
        t0 = time.perf_counter()
        runs = [ts.census(m, samples=k, recurrence=rec, threads=threads) for m in models]
        out[rec] = (time.perf_counter() - t0, np.array([r.attractor_reached.values for r in runs]),
                    np.array([r.t_end.values for r in runs]), np.array([r.n_rhs.values for r in runs]),
                    int(sum(int(r.recurrence.sum()) for r in runs)))  # fmt: skip
    (w0, a0, t0_, r0, _), (w1, a1, t1_, r1, n_rec) = out[False], out[True]
    names = ts.ATTRACTOR_NAMES
    moved = a0 != a1
    pairs: dict[str, int] = {}
    for x, y in zip(a0[moved], a1[moved]):
        key = f"{names[x] if x >= 0 else 'failed'} -> {names[y] if y >= 0 else 'failed'}"
        pairs[key] = pairs.get(key, 0) + 1
    z = fraction_shift(a0, a1, k)
    print(f"census of {len(pts)} grid points x K = {k}, own blocks -> recurrence: {w0:.1f} -> {w1:.1f} s, simulated "
          f"{t0_.sum():.0f} -> {t1_.sum():.0f} s, right-hand sides {r1.sum() / r0.sum():.3f}x; {n_rec} samples "
          f"stopped by recurrence; labels that differ: {int(moved.sum())} of {a0.size}: {pairs}; points where a "
          f"fraction moves by more than 2 / 3 standard errors: {int((z > 2).sum())} / {int((z > 3).sum())}")  # fmt: skip


def fractions(labels: np.ndarray) -> np.ndarray:
    """Per point (rows of ``labels``, K samples each), the fraction of its valid samples on each attractor."""
    n = len(ts.ATTRACTOR_NAMES)
    return np.array([np.bincount(r[r >= 0], minlength=n) / max(int((r >= 0).sum()), 1) for r in labels])


def fraction_shift(a: np.ndarray, b: np.ndarray, k: int) -> np.ndarray:
    """Per point, the largest move of a fraction between two censuses of the same samples, in standard
    errors of the difference (floored at one sample)."""
    fa, fb = fractions(a), fractions(b)
    se = np.maximum(np.sqrt((fa * (1 - fa) + fb * (1 - fb)) / k), 1.0 / k)
    return np.max(np.abs(fa - fb) / se, axis=1)


def grid_points(n_loads: int, n_arms: int, threads: int | None) -> list[tuple[float, float]]:
    """The (load, arm) pairs the default sweep censuses (stable, with a saddle cycle) at 0.3 m/s."""
    loads, arms = np.linspace(10, 150, n_loads), np.linspace(0.05, 0.127, n_arms)
    ds = ts.sweep(normal_load=loads, arm_length=arms, sliding_speed=[0.3], samples=1, progress=False, threads=threads)
    return [(a, b) for a in loads for b in arms if int(ds.census_samples.sel(normal_load=a, arm_length=b).item()) > 0]


def rtol_agreement(rtols: list[float], k: int, threads: int | None) -> None:
    """The census of the grid's points at each rtol, labels against the tightest rtol's, sample by sample.

    A census is a work-precision problem like any other: its cost against the error of what it
    reports (labels, fractions), the reference being the tightest tolerance.
    """
    import dataclasses

    pts = grid_points(40, 10, threads)
    models = [dataclasses.replace(ts.apparatus_model(a, b, 0.3), contact="unilateral") for a, b in pts]
    runs = {}
    for rt in sorted(rtols, reverse=True):
        t0 = time.perf_counter()
        res = [ts.census(m, samples=k, rtol=rt, threads=threads) for m in models]
        runs[rt] = (time.perf_counter() - t0, np.array([r.attractor_reached.values for r in res]),
                    np.array([r.t_end.values for r in res]))  # fmt: skip
    ref = runs[min(rtols)][1]
    names = ts.ATTRACTOR_NAMES
    print(f"census of {len(pts)} grid points x K = {k} by rtol (reference: rtol {min(rtols):g})")
    print("  rtol    wall [s]  simulated [s]  " + "  ".join(f"{n:>9}" for n in names) + "  agree [%]  points >2/3 SE")
    for rt, (w, a, t) in runs.items():
        z = fraction_shift(a, ref, k)
        counts = "  ".join(f"{int((a == i).sum()):>9}" for i in range(len(names)))
        print(f"  {rt:<7g} {w:8.1f}  {t.sum():13.0f}  {counts}  {100 * (a == ref).mean():9.1f}  "
              f"{int((z > 2).sum())}/{int((z > 3).sum())}")  # fmt: skip


def compare_stop_tol(tols: list[float], law: str, k: int, threads: int | None) -> None:
    """The Stribeck sweep of ``benches/bench_stribeck.py`` under ``law`` with its census at each first-stop
    tolerance (``census_stop_tol``; the first is the reference, ``periodic_tol`` turning first stops
    off): wall time, right-hand sides, and per censused point the largest move of a fraction in
    standard errors of the difference, and the cycle counts that differ. Each setting runs twice, the
    wall time the faster."""
    from bench_stribeck import AXES

    model = ts.SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
    runs = {}
    for st in tols:
        best = np.inf
        for _ in range(2):
            t0 = time.perf_counter()
            ds = ts.sweep(model=model, t_max=20.0, threads=threads, progress=False, samples=k, census_stop_tol=st,
                          **AXES)  # fmt: skip
            best = min(best, time.perf_counter() - t0)
        runs[st] = (best, ds)
    ref = runs[tols[0]][1]
    on = ref.census_samples.values > 0
    names = ts.ATTRACTOR_NAMES
    print(f"Stribeck sweep ({law} law) with its census, K = {k}, {int(on.sum())} censused points; reference: "
          f"census_stop_tol {tols[0]:g}")  # fmt: skip
    for st, (w, ds) in runs.items():
        f, f0 = ds.basin_fraction.values[on], ref.basin_fraction.values[on]
        se = np.maximum(np.sqrt((f * (1 - f) + f0 * (1 - f0)) / k), 1.0 / k)
        z = np.max(np.abs(f - f0) / se, axis=-1)
        mean = ", ".join(f"{n} {x:.4f}" for n, x in zip(names, f.mean(axis=0)))
        print(f"  census_stop_tol {st:g}: {w:.2f} s, {int(ds.n_rhs.sum()) / 1e6:.0f} million right-hand sides; "
              f"fractions moving by more than 2 / 3 standard errors at {int((z > 2).sum())} / {int((z > 3).sum())} "
              f"points (largest {z.max():.2f}); cycle counts differing at "
              f"{int((ds.n_cycles.values[on] != ref.n_cycles.values[on]).sum())}; mean fractions {mean}")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples-one", type=int, default=1024)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--sweep-points", type=int, choices=(0, 120, 2000), default=2000)
    ap.add_argument("--scipy", type=int, default=0, help="compare this many census labels with scipy's")
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--rtol", type=str, default="",
                    help="comma-separated rtols: the census of the grid's points at each (K = --samples)")
    ap.add_argument("--compare", action="store_true",
                    help="the stationarity stop against runs to t_max (K = --samples)")
    ap.add_argument("--blocks", type=str, default=str(DEFAULTS.irregular.block),
                    help="with --compare: comma-separated irregular_block values to compare")
    ap.add_argument("--recurrence", action="store_true",
                    help="recurrence on the pilots' attractors against each sample's own blocks (K = --samples)")  # fmt: skip
    ap.add_argument("--stop-tol", type=str, default="",
                    help="comma-separated census_stop_tol values: the Stribeck sweep with its census at each (K = 32)")
    ap.add_argument("--law", choices=("switch", "coulomb"), default="switch", help="with --stop-tol: the friction law")
    a = ap.parse_args()
    print(machine_line())
    if a.stop_tol:
        compare_stop_tol([float(x) for x in a.stop_tol.split(",")], a.law, DEFAULTS.census.samples, a.threads)
        return
    one_point(a.samples_one, a.threads)
    if a.scipy:
        scipy_agreement(a.scipy)
    if a.rtol:
        rtol_agreement([float(x) for x in a.rtol.split(",")], a.samples, a.threads)
    if a.compare:
        compare_irregular_stop(40, 10, a.samples, a.threads, tuple(int(b) for b in a.blocks.split(",")))
    if a.recurrence:
        compare_recurrence(a.samples, a.threads)
    if a.sweep_points == 2000:
        sweep(40, 10, 5, a.samples, a.threads)
    elif a.sweep_points == 120:
        sweep(12, 10, 1, a.samples, a.threads)


if __name__ == "__main__":
    main()
