"""How well posed is the bistability verdict? The same seed sweep at several integration settings.

The ``auto`` bistability check runs one unilateral transient started outside the saddle cycle and
records where it goes (returned to sliding, a stable cycle, sustained non-periodic motion, escape).
A found cycle proves coexistence; a return to sliding does not prove its absence. This bench counts
the points whose verdict changes between runs that differ only in integration error, and with
the start's distance from the saddle.

    python benches/bench_bistability.py [--loads 46 --arms 23 --threads 2]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import tribosweep as ts
from tribosweep._chunk import BISTABLE_NAMES, BISTABLE_VALUES


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--loads", type=int, default=46)
    ap.add_argument("--arms", type=int, default=23)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--starts", type=float, nargs="*", default=[1.5], help="bistability_start factors")
    a = ap.parse_args(argv)
    grid = dict(normal_load=np.linspace(10, 150, a.loads), arm_length=np.linspace(0.05, 0.127, a.arms),
                sliding_speed=[0.46], method="auto", threads=a.threads, progress=False, t_max=20.0)  # fmt: skip
    settings = [("dopri5", 1e-8), ("dop853", 1e-8), ("dop853", 1e-11), ("dop853", 1e-12)]
    for start in a.starts:
        verdicts = {}
        for integ, rtol in settings:
            t0 = time.perf_counter()
            ds = ts.sweep(integrator=integ, rtol=rtol, bistability_start=start, **grid)
            v = ds.bistable.values.ravel()
            verdicts[(integ, rtol)] = v
            counts = ", ".join(f"{name} {int((v == code).sum())}" for code, name in zip(BISTABLE_VALUES, BISTABLE_NAMES))
            print(f"start {start:4.1f} x A1  {integ:6} rtol {rtol:.0e} ({time.perf_counter() - t0:5.1f} s): {counts}",
                  flush=True)  # fmt: skip
        keys = list(verdicts)
        for i in range(len(keys)):
            for j in range(i + 1, len(keys)):
                a, b = verdicts[keys[i]], verdicts[keys[j]]
                n = int((a != b).sum())
                # The question that matters first: does a large disturbance return to sliding?
                nr = int(((a == 0) != (b == 0)).sum())
                print(f"    {keys[i][0]} {keys[i][1]:.0e} vs {keys[j][0]} {keys[j][1]:.0e}: verdict differs at {n:3d} "
                      f"points, returned-or-not at {nr:3d}")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
