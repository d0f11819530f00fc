"""Sweep throughput and memory: points per second of an `auto` sweep, peak memory of a streamed one.

Issue 4's benchmark. The grid spans normal load 10-150 N x arm length 5-12.7 cm x sliding speed
0.2-1.0 m/s around the seed configuration (unilateral contact, constant friction). Each run is a
separate process so that its peak RSS (ru_maxrss) is its own.

    python benches/bench_sweep.py --points 100000 --threads 2 [--memory-points 1000000] [--serial-chunks]

From 8 threads on a sweep computes several chunks at once (``tribosweep._sweep.runner.overlap``);
``--serial-chunks`` computes them one at a time, as below 8 threads, for a comparison.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time


def grid_for(points: int) -> tuple[int, int, int]:
    """Axis lengths (load, arm, speed) with a product close to ``points`` (ratio 4 : 2 : 1)."""
    k = (points / 8) ** (1 / 3)
    return max(2, round(4 * k)), max(2, round(2 * k)), max(1, round(k))


def child(points: int, method: str, threads: int, output: str | None, bistability: bool, samples: int,
          serial: bool = False) -> dict:  # fmt: skip
    import numpy as np

    import tribosweep as ts
    from tribosweep._sweep import runner

    if serial:
        runner.overlap = lambda threads: 1

    nl, na, nv = grid_for(points)
    t0 = time.perf_counter()
    ds = ts.sweep(
        normal_load=np.linspace(10, 150, nl), arm_length=np.linspace(0.05, 0.127, na),
        sliding_speed=np.linspace(0.2, 1.0, nv), strategy=method, threads=threads, output=output,
        progress=False, census=bistability, t_max=20.0, samples=samples,
    )
    wall = time.perf_counter() - t0
    regime = ds.regime.values.ravel()
    decided = ds.decided_by.values.ravel()
    n = regime.size
    out = {
        "points": int(n), "method": method, "threads": threads, "bistability": bistability, "samples": samples,
        "chunks_at_once": runner.overlap(threads),
        "censused": int((ds.census_samples.values > 0).sum()), "wall_s": wall,
        "points_per_s": n / wall, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "regimes": {name: int((regime == i).sum()) for i, name in enumerate(ts.REGIME_NAMES)},
        "decided_by": {name: int((decided == i).sum()) for i, name in enumerate(("linear", "tidf", "shooting", "transient"))},
    }
    ds.close()
    return out


def run_child(args: list[str]) -> dict:
    r = subprocess.run([sys.executable, __file__, "--child", *args], capture_output=True, text=True, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--memory-points", type=int, default=0, help="also stream a sweep of this many points (method linear) to disk")
    ap.add_argument("--no-bistability", action="store_true")
    ap.add_argument("--samples", type=int, default=16,
                    help="census disturbances per point K (the issue's 10^5-point goal: 16)")  # fmt: skip
    ap.add_argument("--serial-chunks", action="store_true", help="one chunk at a time on any thread count")
    ap.add_argument("--child", nargs=7, metavar=("POINTS", "METHOD", "THREADS", "OUTPUT", "BISTABILITY", "K", "SERIAL"),
                    help=argparse.SUPPRESS)  # fmt: skip
    ap.add_argument("--json", type=pathlib.Path)
    a = ap.parse_args(argv)
    if a.child:
        p, m, t, o, b, k, ser = a.child
        print(json.dumps(child(int(p), m, int(t), None if o == "-" else o, b == "1", int(k), ser == "1")))
        return 0
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for bist in ([False] if a.no_bistability else [False, True]):
            out = os.path.join(tmp, f"auto{int(bist)}.nc")
            rows.append(run_child([str(a.points), "auto", str(a.threads), out, str(int(bist)), str(a.samples),
                                   str(int(a.serial_chunks))]))  # fmt: skip
        if a.memory_points:
            rows.append(run_child([str(a.memory_points), "linear", str(a.threads), os.path.join(tmp, "big.nc"), "0", "1",
                                   str(int(a.serial_chunks))]))  # fmt: skip
    for r in rows:
        census = f"census K = {r['samples']} at {r['censused']} points" if r["bistability"] else "no census"
        print(f"{r['method']:6} points {r['points']:>8} threads {r['threads']} ({r['chunks_at_once']} chunks at once) {census}: "
              f"wall {r['wall_s']:8.1f} s  {r['points_per_s']:9.0f} points/s  peak RSS {r['peak_rss_mb']:7.0f} MB")
        print(f"       regimes {r['regimes']}\n       decided by {r['decided_by']}")
    if a.json:
        a.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
