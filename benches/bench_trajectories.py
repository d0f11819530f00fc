"""Trajectories per second per core: the Rust core against numba and scipy, with the error of each.

The benchmark of issue 2: 1000 trajectories of the seed configuration with mu uniform in
[0.15, 0.30] and normal load uniform in [17, 152] N, over 0.5 s from z = 1 um, at rtol 1e-6 and
1e-9. Every method gets the same absolute tolerances (``reference.default_atol``). Error: the
largest |z(0.5) - z_ref(0.5)| / max|z_ref| over the ensemble, against the Rust DOP853 at rtol 1e-13
(itself checked against scipy DOP853 at 1e-13 on a subset). All baselines run in this process, so
the printed ratios hold on a noisy shared machine; absolute times do not.

    python benches/bench_trajectories.py [--n 1000] [--n-scipy 20] [--json out.json]
    python benches/bench_trajectories.py --scaling-only --threads 1,8,16 --scaling-n 128000  # many cores

The scaling table (``--threads``) ends with the machine's own ceiling, measured in the same run: as
many separate one-thread processes as the largest thread count, started together, each running the
ensemble; their rates summed. One call's threads can at best match it.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys
import time

import numpy as np

import tribosweep as ts  # noqa
from tribosweep.bench import baselines  # noqa: E402
from tribosweep.bench.workprecision import machine_line  # noqa: E402


def best_of(f, repeat=3):
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--n-scipy", type=int, default=20)
    ap.add_argument("--json", type=pathlib.Path)
    ap.add_argument("--threads", default="",
                    help="comma-separated thread counts for a scaling table (e.g. 1,2,4,8,16); empty: none")
    ap.add_argument("--scaling-n", type=int, default=0,
                    help="trajectories per call of the scaling table (default 2,000 per thread of the largest count)")
    ap.add_argument("--scaling-only", action="store_true", help="only the scaling table")
    ap.add_argument("--child", nargs=3, metavar=("N", "CONTACT", "START"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        n, contact, start = args.child
        print(child_rate(int(n), contact, float(start)))
        return 0
    print(machine_line())
    if args.scaling_only:
        if not args.threads:
            ap.error("--scaling-only needs --threads")
        args.n = 1000
        params_list, y0, _ = baselines.seed_ensemble_params(args.n)
        grid = {"mu": np.array([p["mu"] for p in params_list]),
                "normal_load": np.array([p["normal_load"] for p in params_list])}  # fmt: skip
        scaling_table(args, ts.SliderModel(contact="bilateral"), grid, y0, baselines.seed_ensemble_params(1)[2],
                      [int(x) for x in args.threads.split(",")])  # fmt: skip
        return 0

    params_list, y0, t_end = baselines.seed_ensemble_params(args.n)
    mu = np.array([p["mu"] for p in params_list])
    load = np.array([p["normal_load"] for p in params_list])
    P = baselines.params_to_array(params_list)
    model = ts.SliderModel(contact="bilateral")  # the issue-2 ensemble: the report's bilateral model
    grid = {"mu": mu, "normal_load": load}

    def rust(method, rtol, threads=1):
        atol = baselines.reference.default_atol(rtol)
        return ts.ensemble(model, t_end, grid, y0=y0, method=method, rtol=rtol, atol=atol, threads=threads)

    t_ref, ref = best_of(lambda: rust("dop853", 1e-13), repeat=1)
    z_ref = ref.z_end.values
    # The scale of the error: the largest |z| of each run (z starts at 1 um and decays or grows).
    zscale = np.maximum(np.abs(ref.max_abs_z.values), 1e-12)
    sc = baselines.scipy_seed_batch(params_list[: args.n_scipy], t_end, 1e-13, y0=y0[: args.n_scipy])
    ref_check = np.max(np.abs(sc["y_end"][:, 0] - z_ref[: args.n_scipy]) / zscale[: args.n_scipy])
    rows = []
    print(f"reference: Rust DOP853 rtol 1e-13, {t_ref / args.n * 1e3:.2f} ms/trajectory; "
          f"vs scipy DOP853 1e-13 on {args.n_scipy}: max rel. diff {ref_check:.1e}")
    baselines.warmup()
    for rtol in (1e-6, 1e-9):
        for method in ("dopri5", "dop853", "rodas4"):
            t, ds = best_of(lambda method=method, rtol=rtol: rust(method, rtol))
            err = np.max(np.abs(ds.z_end.values - z_ref) / zscale)
            rows.append(dict(impl="rust", method=method, rtol=rtol, threads=1, per_s_core=args.n / t,
                             err=float(err), n_rhs=float(ds.n_rhs.mean()), failed=int((ds.status != 0).sum())))
        t2, ds2 = best_of(lambda rtol=rtol: rust("dopri5", rtol, threads=2))
        rows.append(dict(impl="rust", method="dopri5", rtol=rtol, threads=2, per_s_core=args.n / t2 / 2,
                         err=rows[-3]["err"], n_rhs=float(ds2.n_rhs.mean()), failed=int((ds2.status != 0).sum())))
        assert np.array_equal(ds2.z_end.values, rust("dopri5", rtol).z_end.values), "1 vs 2 threads differ"
        tn = baselines.time_numba(P, y0, t_end, rtol)
        err = np.nanmax(np.abs(tn["y_end"][:, 0] - z_ref) / zscale)
        rows.append(dict(impl="numba", method="dp5", rtol=rtol, threads=1, per_s_core=1 / tn["seconds_per_trajectory"],
                         err=float(err), n_rhs=float(np.mean(tn["n_rhs"])), failed=int(np.isnan(tn["y_end"][:, 0]).sum())))
        k = args.n_scipy
        ss = baselines.scipy_seed_batch(params_list[:k], t_end, rtol, y0=y0[:k])
        err = np.max(np.abs(ss["y_end"][:, 0] - z_ref[:k]) / zscale[:k])
        rows.append(dict(impl="scipy", method="DOP853", rtol=rtol, threads=1, per_s_core=1 / ss["seconds_per_trajectory"],
                         err=float(err), n_rhs=float(np.mean(ss["n_rhs"])), failed=0))
    by = {(r["impl"], r["method"], r["rtol"], r["threads"]): r for r in rows}
    print(f"{'impl':6} {'method':7} {'rtol':>6} {'thr':>3} {'traj/s/core':>12} {'vs numba':>9} {'vs scipy':>9} "
          f"{'max err':>9} {'rhs/traj':>9} {'failed':>6}")
    for r in rows:
        nb = by[("numba", "dp5", r["rtol"], 1)]["per_s_core"]
        sp = by[("scipy", "DOP853", r["rtol"], 1)]["per_s_core"]
        print(f"{r['impl']:6} {r['method']:7} {r['rtol']:6.0e} {r['threads']:3d} {r['per_s_core']:12.0f} "
              f"{r['per_s_core'] / nb:9.2f} {r['per_s_core'] / sp:9.1f} {r['err']:9.1e} {r['n_rhs']:9.0f} {r['failed']:6d}")
    for rtol in (1e-6, 1e-9):
        one = by[("rust", "dopri5", rtol, 1)]["per_s_core"]
        two = by[("rust", "dopri5", rtol, 2)]["per_s_core"]
        print(f"2-thread efficiency at rtol {rtol:.0e}: {two / one:.2f} (per-core rate, 2 threads / 1 thread)")
    rows += paths_table(args, model, grid, y0, t_end, by)
    if args.threads:
        rows += scaling_table(args, model, grid, y0, t_end, [int(x) for x in args.threads.split(",")])
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


def paths_table(args, model, grid, y0, t_end, by) -> list[dict]:
    """Issue 10's paths at rtol 1e-6, one thread, against the numba DP5 end-state rate of this run:
    the end state, t_eval = [t_end], t_eval of 501 points, unilateral contact and its t_eval of 501
    points (all lane-batched), each with DP5 and with DOP853."""
    rtol = 1e-6
    atol = baselines.reference.default_atol(rtol)
    nb = by[("numba", "dp5", rtol, 1)]["per_s_core"]
    uni = model.replace(contact="unilateral")
    ref_u = ts.ensemble(uni, t_end, grid, y0=y0, method="dop853", rtol=1e-13, atol=baselines.reference.default_atol(1e-13))
    ref_b = ts.ensemble(model, t_end, grid, y0=y0, method="dop853", rtol=1e-13,
                        atol=baselines.reference.default_atol(1e-13))
    # Each path with DP5 and with DOP853 (the sweeps' default; more accurate at the same rtol).
    cases = [
        (f"{name}, {short}", m, te, ref, method)
        for method, short in (("dopri5", "DP5"), ("dop853", "DOP853"))
        for name, m, te, ref in (
            ("bilateral end state", model, None, ref_b),
            ("bilateral t_eval=[t_end]", model, np.array([t_end]), ref_b),
            ("bilateral t_eval 501 points", model, np.linspace(0.0, t_end, 501), ref_b),
            ("unilateral end state", uni, None, ref_u),
            ("unilateral t_eval 501 points", uni, np.linspace(0.0, t_end, 501), ref_u),
        )
    ]
    out = []
    print(f"\nlane-batched paths, rtol {rtol:.0e}, 1 thread ({args.n} trajectories; numba DP5 end state "
          f"{nb:.0f} traj/s in this run)")
    print(f"{'path':38} {'traj/s/core':>12} {'vs numba':>9} {'max err':>9} {'rhs/traj':>9}")
    for name, m, te, ref, method in cases:
        t, ds = best_of(lambda m=m, te=te, method=method: ts.ensemble(m, t_end, grid, y0=y0, rtol=rtol, atol=atol,
                                                                      t_eval=te, threads=1, method=method))
        scale = np.maximum(np.abs(ref.max_abs_z.values), 1e-12)
        err = float(np.max(np.abs(ds.z_end.values - ref.z_end.values) / scale))
        r = dict(impl="rust", method=name, rtol=rtol, threads=1, per_s_core=args.n / t, err=err,
                 n_rhs=float(ds.n_rhs.mean()), failed=int((ds.status != 0).sum()))
        print(f"{name:38} {r['per_s_core']:12.0f} {r['per_s_core'] / nb:9.2f} {err:9.1e} {r['n_rhs']:9.0f}")
        out.append(r)
    return out


def big_ensemble(n: int):
    """The issue-2 ensemble of 1,000 repeated to ``n`` trajectories: (grid, y0, t_end)."""
    params_list, y0, t_end = baselines.seed_ensemble_params(1000)
    reps = max(1, n // 1000)
    grid = {"mu": np.tile([p["mu"] for p in params_list], reps),
            "normal_load": np.tile([p["normal_load"] for p in params_list], reps)}  # fmt: skip
    yb = np.tile(y0, (reps, 1)) if np.ndim(y0) == 2 else y0
    return grid, yb, t_end


def rate(model, t_end, grid, y0, threads: int) -> float:
    """Trajectories per second of one ``ensemble`` call at rtol 1e-6, best of 3."""
    atol = baselines.reference.default_atol(1e-6)
    t, _ = best_of(lambda: ts.ensemble(model, t_end, grid, y0=y0, rtol=1e-6, atol=atol, threads=threads))
    return len(grid["mu"]) / t


def child_rate(n: int, contact: str, start: float) -> float:
    """One process of the ceiling: waits for the common start (every process imported and ready),
    then the one-thread rate of its own ensemble."""
    grid, yb, t_end = big_ensemble(n)
    model = ts.SliderModel(contact=contact)
    rate(model, t_end, {k: v[:1000] for k, v in grid.items()}, yb[:1000] if np.ndim(yb) == 2 else yb, 1)  # warm
    time.sleep(max(0.0, start - time.time()))
    return rate(model, t_end, grid, yb, 1)


def ceiling(processes: int, n: int, contact: str) -> float:
    """The summed one-thread rates of ``processes`` separate processes running together."""
    start = time.time() + 10.0
    procs = [subprocess.Popen([sys.executable, __file__, "--child", str(n), contact, repr(start)],
                              stdout=subprocess.PIPE, text=True) for _ in range(processes)]  # fmt: skip
    return sum(float(p.communicate()[0].strip().splitlines()[-1]) for p in procs)


def scaling_table(args, model, grid, y0, t_end, threads: list[int]) -> list[dict]:
    """Trajectories per second, all threads together, bilateral and unilateral end states at rtol 1e-6
    (the ensemble repeated to keep every thread busy), and the machine's ceiling: separate
    processes, one per thread of the largest count."""
    n = args.scaling_n or max(threads) * 2000
    big, yb, t_end = big_ensemble(n)
    n = len(big["mu"])
    models = (("bilateral", model.replace(contact="bilateral")), ("unilateral", model.replace(contact="unilateral")))
    print(f"\nscaling ({n} trajectories per call, rtol 1e-06; total trajectories/s over all threads)")
    print(f"{'threads':>7} {'bilateral':>12} {'unilateral':>12}")
    out = []
    base = {}
    for th in threads:
        rates = []
        for name, m in models:
            r = rate(m, t_end, big, yb, th)
            rates.append(r)
            base.setdefault(name, r)
            out.append(dict(impl="rust", method=f"{name} end state", rtol=1e-6, threads=th, per_s_total=r))
        print(f"{th:7d} {rates[0]:12.0f} {rates[1]:12.0f}   (x{rates[0] / base['bilateral']:.1f}, "
              f"x{rates[1] / base['unilateral']:.1f} of 1 thread)")
    p = max(threads)
    if p > 1:
        per = max(1000, n // p)
        ceil = [ceiling(p, per, name) for name, _ in models]
        last = {r["method"].split()[0]: r["per_s_total"] for r in out if r["threads"] == p}
        print(f"{'ceiling':>7} {ceil[0]:12.0f} {ceil[1]:12.0f}   ({p} one-thread processes of {per} trajectories "
              f"at once; {p} threads reach {last['bilateral'] / ceil[0]:.0%}, {last['unilateral'] / ceil[1]:.0%})")
        for (name, _), c in zip(models, ceil):
            out.append(dict(impl="processes", method=f"{name} end state", rtol=1e-6, threads=p, per_s_total=c))
    return out

if __name__ == "__main__":
    raise SystemExit(main())
