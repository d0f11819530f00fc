"""The issue-10 Stribeck sweep against the build of the issue's own day, on this machine.

Issue 10 set its sweep goal as a ratio: at least 10x the 76 points/s it measured, on 2 cores,
on the machine of that day. A figure from another machine is no ratio: these machines differ
by 2x in speed per core. This bench builds the commit of that day (``--rev``, default
``bbf7fbf``, the last commit of 2026-11-22, whose sweep gives the issue's regimes: 29 points
``unstable_undetermined``) in a git worktree under ``--cache``, and runs the issue's sweep
(`contact="unilateral"`, `mu_static=0.3`, 10 loads x 4 arms x 5 speeds, `auto` without the
bistability check or census, `t_max=20`, ``--threads`` threads) on that build and on this one,
each in its own process, alternating. Each process runs the sweep once to warm up and then
``--repeat`` times. The old build has only the tanh law (``coulomb``); this one runs both.

    python benches/bench_issue_day.py [--rounds 3] [--repeat 2] [--threads 2] [--rev bbf7fbf]

The first run builds the old commit (about 1-3 minutes on 2 cores); later runs reuse it.
Prints points/s (best over all runs) of each, and the ratio of this build's best to the old
build's best, with the range of the per-round ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from bench_stribeck import AXES  # the grid, one definition for both benches

ROOT = Path(__file__).resolve().parent.parent

CHILD = r"""
import inspect, json, sys, time
import numpy as np
import tribosweep as ts
law, repeat, threads = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
axes = {k: np.array(v) for k, v in json.loads(sys.argv[4]).items()}
model = ts.SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
params = inspect.signature(ts.sweep).parameters
kw = dict(census=False) if "census" in params else dict(check_bistability=False)
runs = []
for i in range(repeat + 1):
    t0 = time.perf_counter()
    ds = ts.sweep(model=model, t_max=20.0, threads=threads, progress=False, **kw, **axes)
    if i:
        runs.append(time.perf_counter() - t0)
reg = ds["regime"]
names, values = reg.attrs["flag_meanings"].split(), [int(v) for v in reg.attrs["flag_values"]]
counts = {names[values.index(int(v))]: int((reg.values == v).sum()) for v in np.unique(reg.values)}
print(json.dumps({"file": ts.__file__, "n": int(reg.size), "runs": runs, "regimes": counts}))
"""


def build_old(rev: str, cache: Path) -> Path:
    """The package of commit ``rev`` with its extension built here: ``cache/pkg`` (reused if there)."""
    pkg = cache / "pkg"
    stamp = pkg / "REV"
    if stamp.exists() and stamp.read_text() == rev:
        return pkg
    src = cache / "src"
    if src.exists():
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(src)], check=False)
        shutil.rmtree(src, ignore_errors=True)
    subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-f", str(src), rev], check=True)
    env = dict(os.environ, PYO3_PYTHON=sys.executable, CARGO_TARGET_DIR=str(cache / "target"))
    print(f"building {rev} (cargo build --release -p tribosweep-py) ...", flush=True)
    subprocess.run(["cargo", "build", "-q", "--release", "-p", "tribosweep-py"], cwd=src, env=env, check=True)
    shutil.rmtree(pkg, ignore_errors=True)
    shutil.copytree(src / "python" / "tribosweep", pkg / "tribosweep")
    shutil.copy2(cache / "target" / "release" / "lib_core.so", pkg / "tribosweep" / "_core.abi3.so")
    stamp.write_text(rev)
    return pkg


def child(law: str, repeat: int, threads: int, path: Path | None) -> dict:
    env = dict(os.environ)
    if path is not None:  # the old package first; a PYTHONPATH already set (run.sh of device_carry.sh) after it
        env["PYTHONPATH"] = os.pathsep.join([str(path)] + [p for p in [env.get("PYTHONPATH")] if p])
    axes = json.dumps({k: [float(x) for x in v] for k, v in AXES.items()})
    out = subprocess.run([sys.executable, "-c", CHILD, law, str(repeat), str(threads), axes], env=env, check=True,
                         capture_output=True, text=True, cwd=path or ROOT / "benches")  # fmt: skip
    res = json.loads(out.stdout.strip().splitlines()[-1])
    want = path is not None
    if (str(path) in res["file"]) != want:
        raise RuntimeError(f"the {'old' if want else 'current'} run imported {res['file']}")
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rev", default="bbf7fbf", help="the commit of the issue's day")
    ap.add_argument("--cache", default="bench_out/issue_day", help="where the old build lives")
    ap.add_argument("--rounds", type=int, default=3, help="rounds of (old, switch, tanh) processes")
    ap.add_argument("--repeat", type=int, default=2, help="timed sweeps per process, after one warm-up")
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)
    for name in ("rounds", "repeat", "threads"):
        if getattr(args, name) < 1:
            ap.error(f"--{name} must be >= 1, got {getattr(args, name)}")
    from tribosweep.bench.workprecision import machine_line

    pkg = build_old(args.rev, (ROOT / args.cache).resolve())
    print(f"{machine_line()}; threads {args.threads}")
    rows = {"old tanh": [], "switch": [], "tanh": []}
    regimes = {}
    for _ in range(args.rounds):
        for key, law, path in (("old tanh", "coulomb", pkg), ("switch", "switch", None), ("tanh", "coulomb", None)):
            res = child(law, args.repeat, args.threads, path)
            rows[key].append(min(res["runs"]))
            regimes[key] = res["regimes"]
            n = res["n"]
    old = rows["old tanh"]
    for key, best in rows.items():
        line = f"{key:8s} {n / min(best):7.1f} points/s (rounds' best {', '.join(f'{n / b:.1f}' for b in best)})"
        if key != "old tanh":
            per = [o / b for o, b in zip(old, best)]
            line += f"; {min(old) / min(best):.2f}x the old build (per round {min(per):.2f}-{max(per):.2f}x)"
        print(line + f"; {regimes[key]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
