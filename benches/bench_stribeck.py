"""The issue-10 Stribeck sweep: speed-dependent friction as a stiff tanh law against the switch model.

`contact="unilateral"`, `mu_static=0.3`, loads 10-150 N x 10, arms 5-12.7 cm x 4, speeds
0.2-1 m/s x 5 (200 points), `auto` without the census, `t_max=20`, on 2 threads; both laws in
the same process. Prints points/s, right-hand sides per point, where the points go, and the
regimes the two laws give at each point.

    python benches/bench_stribeck.py [--threads 2] [--repeat 2] [--stages]
    python benches/bench_stribeck.py --scaling [--law switch] [--threads 2] [--repeat 3]
    python benches/bench_stribeck.py --settings [--law switch] [--out bench_out]
    python benches/bench_stribeck.py --ftle [--law switch] [--threads 2]

``--stages`` also prints, for the last run of each law, the wall time of its batched core calls by
kind (``steady``: the transients; ``sampled``: the irregular points' measurement windows;
``final``: their Lyapunov-exponent segments, and the runs leaving an unstable cycle; ``shooting``:
the check of every cycle a transient stopped on), with their right-hand sides and accepted steps.

``--scaling`` instead runs one law's sweep on 1 thread and on ``--threads``, best of ``--repeat``
each, and prints each stage's wall time on both with the ratio (how far each stage is from a
perfect speed-up, and the points/s a perfect one would give).

``--settings`` instead runs one law's sweep over the transients' ``rtol`` x ``transient_irregular_block``
against a reference run to ``t_max`` at rtol 1e-10 (:mod:`tribosweep.bench.sweep_settings`), prints
its table and writes ``sweep_settings.png`` into ``--out``.

``--ftle`` instead measures the irregular points' Lyapunov exponents from 8 starts along each
attractor under several settings of the exponent's runs, against a reference at ``ftle_rtol``
1e-11 (:mod:`tribosweep.bench.ftle_settings`), and prints the table.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import tribosweep as ts
from tribosweep import _core
from tribosweep.bench.workprecision import machine_line

AXES = dict(normal_load=np.linspace(10, 150, 10), arm_length=np.linspace(0.05, 0.127, 4),
            sliding_speed=np.linspace(0.2, 1.0, 5))  # fmt: skip


def run(law: str, threads: int) -> tuple[float, object]:
    model = ts.SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
    t0 = time.perf_counter()
    ds = ts.sweep(model=model, census=False, t_max=20.0, threads=threads, progress=False, **AXES)
    return time.perf_counter() - t0, ds


class StageClock:
    """Wraps ``_core.ensemble`` and ``_core.periodic_orbits`` while active: wall time, calls,
    right-hand sides and accepted steps by kind (the orbits: ``shooting``, steps not counted)."""

    def __init__(self):
        self.rows: dict[str, list[float]] = {}
        self._orig: dict = {}

    def _wrap(self, name: str, kind_of):
        self._orig[name] = orig = getattr(_core, name)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            res = orig(*args, **kwargs)
            row = self.rows.setdefault(kind_of(kwargs), [0.0, 0, 0, 0])
            row[0] += time.perf_counter() - t0
            row[1] += 1
            row[2] += int(np.asarray(res["n_rhs"]).sum())
            row[3] += int(np.asarray(res["n_accept"]).sum()) if "n_accept" in res else 0
            return res

        setattr(_core, name, timed)

    def __enter__(self):
        self._wrap("ensemble", lambda kw: kw.get("kind", "final"))
        self._wrap("periodic_orbits", lambda kw: "shooting")
        return self

    def __exit__(self, *exc):
        for name, orig in self._orig.items():
            setattr(_core, name, orig)

    def report(self, total: float) -> str:
        parts = [f"{k} {v[0]:.3f} s ({v[1]} calls, {v[2] / 1e6:.1f}M rhs, {v[3] / 1e6:.2f}M steps)"
                 for k, v in sorted(self.rows.items(), key=lambda kv: -kv[1][0])]  # fmt: skip
        rest = total - sum(v[0] for v in self.rows.values())
        return "  stages: " + "; ".join(parts) + f"; outside the core calls {rest:.3f} s"


def scaling(law: str, threads: int, repeat: int) -> str:
    """One law's sweep on 1 thread and on ``threads``: the best run of each, its stages side by side."""
    best: dict[int, tuple[float, StageClock]] = {}
    for th in sorted({1, threads}):
        for _ in range(max(repeat, 1)):
            clock = StageClock()
            with clock:
                w, ds = run(law, th)
            if th not in best or w < best[th][0]:
                best[th] = (w, clock)
    (w1, c1), (wn, cn) = best[1], best[threads]
    n = int(ds.regime.size)
    kinds = sorted(set(c1.rows) | set(cn.rows), key=lambda k: -c1.rows.get(k, [0.0])[0])
    rows = [(k, c1.rows.get(k, [0.0])[0], cn.rows.get(k, [0.0])[0]) for k in kinds]
    rows.append(("outside the core calls", w1 - sum(r[1] for r in rows), wn - sum(r[2] for r in rows)))
    rows.append(("sweep", w1, wn))
    lines = [f"{law} law, {n} points: 1 thread {n / w1:.1f} points/s, {threads} threads {n / wn:.1f} points/s "
             f"({w1 / wn:.2f}x; a perfect {threads}x would give {threads * n / w1:.1f})",
             f"| stage | 1 thread [s] | {threads} threads [s] | speed-up |", "|---|---|---|---|"]  # fmt: skip
    lines += [f"| {k} | {t1:.3f} | {tn:.3f} | {t1 / tn:.2f}x |" for k, t1, tn in rows]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=2, help="best of this many runs of each law")
    ap.add_argument("--stages", action="store_true", help="time the core calls of each law's last run by kind")
    ap.add_argument("--settings", action="store_true", help="speed against agreement over rtol x transient_irregular_block")
    ap.add_argument("--scaling", action="store_true", help="each stage on 1 thread against --threads")
    ap.add_argument("--ftle", action="store_true", help="the exponent's settings on replicates against ftle_rtol 1e-11")
    ap.add_argument("--law", default="switch", choices=("switch", "coulomb"), help="the law of --settings, --scaling and --ftle")
    ap.add_argument("--out", default="bench_out", help="where --settings writes its chart")
    a = ap.parse_args(argv)
    print(f"{machine_line()}; threads {a.threads}")
    if a.settings:
        from tribosweep.bench.sweep_settings import sweep_settings

        res = sweep_settings(a.out, quick=a.repeat < 2, threads=a.threads, law=a.law)
        print(res["markdown"])
        print(f"chart: {res['files']['sweep_settings']}")
        return 0
    if a.ftle:
        from tribosweep.bench.ftle_settings import ftle_settings

        print(ftle_settings(threads=a.threads, law=a.law)["markdown"])
        return 0
    if a.scaling:
        print(scaling(a.law, a.threads, a.repeat))
        return 0
    out = {}
    for law in ("coulomb", "switch"):
        walls, ds = [], None
        for k in range(a.repeat):
            clock = StageClock()
            if a.stages and k == a.repeat - 1:
                with clock:
                    w, ds = run(law, a.threads)
            else:
                w, ds = run(law, a.threads)
            walls.append(w)
        out[law] = (min(walls), ds)
        n = int(ds.regime.size)
        regimes = ds.regime.values.ravel()
        counts = ", ".join(f"{name} {int((regimes == i).sum())}" for i, name in enumerate(ts.REGIME_NAMES)
                           if (regimes == i).any())  # fmt: skip
        rhs = ds.n_rhs.values.ravel()
        print(f"{law:8} {n} points: {min(walls):6.2f} s ({n / min(walls):6.1f} points/s; runs {np.round(walls, 2)}), "
              f"rhs per point mean {rhs.mean():,.0f} median {np.median(rhs):,.0f}; {counts}")  # fmt: skip
        if a.stages:
            print(clock.report(walls[-1]))
    (wc, dc), (ws, dsw) = out["coulomb"], out["switch"]
    same = dc.regime.values == dsw.regime.values
    print(f"switch against tanh: {wc / ws:.2f}x the points/s, {dc.n_rhs.values.sum() / dsw.n_rhs.values.sum():.2f}x "
          f"fewer right-hand sides; the same regime at {int(same.sum())} of {same.size} points")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
