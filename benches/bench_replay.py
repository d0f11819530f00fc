"""The Stribeck sweep's transients as one replayable core call: its time, its work, its bits.

On a shared machine a wall time moves by 20-40 % from one minute to the next, so a change worth
a few percent cannot be seen in a sweep's time. This bench freezes the largest core call of the
issue-10 Stribeck sweep (`contact="unilateral"`, `mu_static=0.3`, 10 x 4 x 5 points, `auto`
without the census, `t_max=20`: its 95 transients, `kind="steady"`) into a file, and replays it:

    python benches/bench_replay.py capture [--law switch] [--file bench_out/replay_switch.pkl]
    python benches/bench_replay.py run [--file ...] [--threads 1] [--repeat 5]
    python benches/bench_replay.py count [--file ...]

``run`` prints the best wall time, the work (right-hand sides, accepted steps, events) and a
SHA-256 digest of every output of the call: two builds that give the same digest give the same
bits. ``count`` runs the call once under valgrind's callgrind (one thread, instructions counted
only inside the core call) and prints the instructions executed: a deterministic measure of work
that does not depend on the machine's load (needs ``valgrind``; about a minute).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import pickle
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import tribosweep as ts
from bench_stribeck import AXES  # the grid, one definition for every bench
from tribosweep import _core

#: Where callgrind starts and stops counting: the core's entry for an ensemble (every thread).
COLLECT = "*ensemble::run_on*"


def capture(law: str, path: Path) -> str:
    """Run the sweep once and save the arguments of its largest ``kind="steady"`` core call."""
    calls: list[tuple[int, tuple, dict]] = []
    orig = _core.ensemble

    def spy(*args, **kwargs):
        if kwargs.get("kind") == "steady":
            calls.append((len(args[4]), args, dict(kwargs)))
        return orig(*args, **kwargs)

    _core.ensemble = spy
    try:
        model = ts.SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
        ts.sweep(model=model, census=False, t_max=20.0, threads=2, progress=False, **AXES)
    finally:
        _core.ensemble = orig
    n, args, kwargs = max(calls, key=lambda c: c[0])
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        pickle.dump({"law": law, "args": args, "kwargs": kwargs}, f)
    return f"captured the {law} law's transient call ({n} runs of {len(calls)} steady calls) into {path}"


def digest(res: dict) -> str:
    """SHA-256 over every output of a call, by sorted key (arrays by dtype, shape and bytes)."""
    h = hashlib.sha256()
    for k in sorted(res):
        v = np.asarray(res[k])
        h.update(k.encode())
        h.update(str(v.dtype).encode() + str(v.shape).encode())
        h.update(v.tobytes() if v.dtype != object else repr(v.tolist()).encode())
    return h.hexdigest()


def replay(path: Path, threads: int, repeat: int) -> str:
    with open(path, "rb") as f:
        saved = pickle.load(f)
    kwargs = dict(saved["kwargs"], threads=threads)
    best, res = np.inf, {}
    for _ in range(max(repeat, 1)):
        t0 = time.perf_counter()
        res = _core.ensemble(*saved["args"], **kwargs)
        best = min(best, time.perf_counter() - t0)
    work = {k: int(np.asarray(res[k]).sum()) for k in ("n_rhs", "n_accept", "n_events")}
    return (f"{saved['law']} law, {len(saved['args'][4])} runs, {threads} thread(s): best of {repeat} {best:.4f} s; "
            f"right-hand sides {work['n_rhs']:,}, accepted steps {work['n_accept']:,}, events {work['n_events']:,}; "
            f"outputs sha256 {digest(res)[:16]}")  # fmt: skip


def count(path: Path) -> str:
    if shutil.which("valgrind") is None:
        return "valgrind is not installed: no instruction count"
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", f"--toggle-collect={COLLECT}",
               sys.executable, __file__, "run", "--file", str(path), "--threads", "1", "--repeat", "1"]  # fmt: skip
        env = dict(os.environ, PYTHONPATH=str(Path(__file__).parent))
        done = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if done.returncode != 0:
            return f"callgrind failed ({done.returncode}): {done.stderr[-2000:]}"
        total = re.search(r"^summary:\s+(\d+)", out.read_text(), re.M)
        line = done.stdout.strip().splitlines()[-1]
    if total is None:
        return f"callgrind wrote no summary; the replay said: {line}"
    return f"{int(total.group(1)) / 1e9:.4f} G instructions inside the core call (callgrind); {line}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("capture", "run", "count"))
    ap.add_argument("--law", default="switch", choices=("switch", "coulomb"), help="the law of capture")
    ap.add_argument("--file", default=None, help="the captured call (default bench_out/replay_<law>.pkl)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args(argv)
    path = Path(a.file or f"bench_out/replay_{a.law}.pkl")
    if a.what == "capture":
        print(capture(a.law, path))
    elif a.what == "run":
        print(replay(path, a.threads, a.repeat))
    else:
        print(count(path))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
