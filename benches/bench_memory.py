"""Memory of a sweep streamed to disk, and what its parts' checksums and fsyncs cost per chunk.

1. Peak RSS of linear sweeps of 10^6 (and 10^7) points written to a netCDF file: each sweep runs
   in its own process, so ``ru_maxrss`` is its own; the goal is flat in the sweep's size and under
   300 MB. Printed with the wall time, the file's size and the largest the parts directory got.
2. The cost of a part's safety per chunk: ``Parts.save`` (npz, SHA-256 checksum, fsync of the part,
   rename, fsync of the checksum ledger) against a plain ``np.savez`` to a file, in the same process,
   on a real chunk of a linear sweep (4096 points, its default chunk) and of an auto sweep without
   the census (64 points, its default chunk; the census makes chunks far slower); also as a
   fraction of computing that chunk.

    python benches/bench_memory.py                      # 10^6 points, overhead on 200 chunks
    python benches/bench_memory.py --points 1e6,1e7     # add 10^7 (about 10 minutes on 2 cores)
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
import threading
import time

import numpy as np


def child(points: int, folder: str) -> dict:
    import tribosweep as ts

    n_arm = 1000
    n_load = max(1, round(points / n_arm))
    out = pathlib.Path(folder) / "big.nc"
    parts = pathlib.Path(str(out) + ".parts")
    largest = [0]

    def watch():  # the parts directory's size, sampled (it is removed when the file is complete)
        while not stop.is_set():
            try:
                largest[0] = max(largest[0], sum(p.stat().st_size for p in parts.iterdir()))
            except OSError:
                pass
            stop.wait(1.0)

    stop = threading.Event()
    t = threading.Thread(target=watch, daemon=True)
    t.start()
    t0 = time.perf_counter()
    ds = ts.sweep(normal_load=np.linspace(10, 150, n_load), arm_length=np.linspace(0.05, 0.127, n_arm),
                  strategy="linear", output=out, progress=False, boundaries=False)  # fmt: skip
    wall = time.perf_counter() - t0
    stop.set()
    n = int(ds.regime.size)
    ds.close()
    return {"points": n, "wall_s": wall, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "file_mb": out.stat().st_size / 1e6, "parts_mb_sampled": largest[0] / 1e6}  # fmt: skip


def overhead(n_chunks: int, size: int, strategy: str) -> dict:
    """Per-chunk time of Parts.save against np.savez to a file, on a real chunk of ``size`` points."""
    import tribosweep as ts
    from tribosweep._settings import SweepSettings
    from tribosweep._sweep import chunk as _chunk
    from tribosweep._sweep.parts import Parts
    from tribosweep._sweep.plan import Plan

    model = ts.SliderModel(contact="unilateral")
    loads = np.linspace(10, 150, size)
    wear = {"normal_load": 84.46, "sliding_speed": 0.46, "frequency_hz": 229.2}
    settings = SweepSettings.from_flat(census=False, wear=wear)
    plan = Plan(model, {"normal_load": loads, "arm_length": np.array([0.072]), "sliding_speed": np.array([0.46])},
                strategy, settings, size, ts.WearReference(), None)  # fmt: skip
    t0 = time.perf_counter()
    arrays = _chunk.compute_chunk(*plan.task(0, None))
    compute = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        parts = Parts(pathlib.Path(tmp) / "o.nc", plan, resume=False)
        t0 = time.perf_counter()
        for _ in range(n_chunks):
            parts.save(0, arrays)
        safe = (time.perf_counter() - t0) / n_chunks
        plain_path = pathlib.Path(tmp) / "plain.npz"
        t0 = time.perf_counter()
        for _ in range(n_chunks):
            with open(plain_path, "wb") as f:
                np.savez(f, **arrays)
        plain = (time.perf_counter() - t0) / n_chunks
        size_bytes = parts.path(0).stat().st_size
    return {"points": size, "strategy": strategy, "part_kb": size_bytes / 1e3, "save_ms": 1e3 * safe, "plain_ms": 1e3 * plain,
            "overhead_ms": 1e3 * (safe - plain), "compute_ms": 1e3 * compute}  # fmt: skip


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", default="1e6", help="comma-separated sweep sizes (default 1e6)")
    ap.add_argument("--chunks", type=int, default=200, help="chunks saved per overhead measurement")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        print(json.dumps(child(int(float(a.child[0])), a.child[1])))
        return 0
    for size, strategy in ((4096, "linear"), (64, "auto")):
        r = overhead(a.chunks, size, strategy)
        print(f"{r['strategy']} part of {r['points']:>4} points ({r['part_kb']:6.1f} kB): Parts.save {r['save_ms']:6.2f} ms, plain "
              f"np.savez {r['plain_ms']:6.2f} ms -> checksum+fsync+rename {r['overhead_ms']:6.2f} ms per chunk "
              f"({r['save_ms'] / r['plain_ms']:.1f}x the plain write; {r['overhead_ms'] / r['compute_ms']:.1%} of "
              f"computing the chunk, {r['compute_ms']:.0f} ms)")  # fmt: skip
    for p in a.points.split(","):
        with tempfile.TemporaryDirectory(dir=os.environ.get("BENCH_TMP")) as tmp:
            proc = subprocess.run([sys.executable, __file__, "--child", p, tmp], capture_output=True, text=True,
                                  check=True)  # fmt: skip
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        print(f"linear sweep of {r['points']:>9} points to disk: peak RSS {r['peak_rss_mb']:6.0f} MB, wall "
              f"{r['wall_s']:7.1f} s ({r['points'] / r['wall_s']:,.0f} points/s), file {r['file_mb']:7.1f} MB, "
              f"parts up to {r['parts_mb_sampled']:7.1f} MB")  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
