"""The cost of each model over a sweep around the seed (issue 5): describing function, shooting,
transient, and `auto` against always-`transient`.

One sweep grid (normal load x arm length at the seed speed) is computed with each method, all on one
thread, timed as the stages' wall clock per point (best of 3; without the boundary curves, whose fixed
cost per sweep is reported apart; speed-ups are of whole sweeps):

- the describing function's A1 against the shooting orbit's (its error) at every physical root, and
  the cost of each model per point, drawn as error against cost (log-log; the shooting orbit is the
  reference, so its own error is its Newton residual; the transient reports no error here because the
  bilateral saddle cycle is unstable and a transient cannot converge onto it);
- `auto` (cheapest valid model per point) against `transient` (every point integrated): regime
  agreement where the transient settled, the cycle-amplitude error where both found a cycle, and the
  speed-up, with and without the attractor census.
"""

from __future__ import annotations

import os
import pathlib
import time

import numpy as np

from .._sweep import sweep


def _timed(repeat: int = 3, **kw):
    """The sweep, its best wall time of ``repeat`` runs, and the best sum of its points' stage times
    (``wall_time``: the stages alone, without the sweep's set-up and assembly, which every strategy
    shares). Without the boundary curves unless asked: they are a fixed cost of the sweep's box (about
    1.5 s here, 32 continuations), not of any model, and on a small grid they hid every model's cost
    (the describing function came out at 120 ms a point: the curves' time over 12 points)."""
    kw.setdefault("boundaries", False)
    walls, stages = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        ds = sweep(progress=False, threads=1, **kw)
        walls.append(time.perf_counter() - t0)
        stages.append(float(ds.wall_time.sum()))
    return ds, min(walls), min(stages)


def model_cost(out_dir: os.PathLike, *, quick: bool = False, t_max: float = 30.0) -> dict:
    """Measure, draw ``model_cost.png`` into ``out_dir``, return ``numbers`` and ``markdown``."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    axes = dict(normal_load=np.linspace(10, 150, 6 if quick else 12), arm_length=np.linspace(0.05, 0.11, 2 if quick else 3),
                sliding_speed=[0.46], t_max=t_max)
    tidf, _, s_tidf = _timed(strategy="tidf", **axes)
    lin, _, s_lin = _timed(strategy="linear", **axes)
    shoot, _, s_shoot = _timed(strategy="shooting", **axes)
    auto, t_auto, _ = _timed(strategy="auto", **axes)
    lean, t_lean, _ = _timed(strategy="auto", census=False, **axes)
    full, t_full, s_full = _timed(strategy="transient", **axes)
    _, t_curves, _ = _timed(1, strategy="auto", census=False, boundaries=True, **axes)
    n = tidf.regime.size
    err = np.abs(shoot.tidf_a1_error.values.ravel())
    has = np.isfinite(err)
    n_orbit = max(int(has.sum()), 1)
    ra, rt = auto.regime.values.ravel(), full.regime.values.ravel()
    from .._codes import REGIME

    # Settled: a cycle, sliding or an escape (irregular motion has not settled; auto starts it elsewhere).
    settled = (full.status.values.ravel() == 0) & ~np.isin(rt, [REGIME["unstable_undetermined"], REGIME["irregular"]])
    both_cycle = np.isfinite(lean.z1_amplitude.values.ravel()) & np.isfinite(full.z1_amplitude.values.ravel())
    amp_err = np.abs(lean.z1_amplitude.values.ravel()[both_cycle] / full.z1_amplitude.values.ravel()[both_cycle] - 1)
    numbers = {
        "points": int(n),
        # A model's cost is the difference of two strategies' stage times (the describing function's
        # over the linear analysis it starts from, shooting's over the describing function that starts
        # it); on a busy machine a difference can come out at or below zero, which says "below the
        # noise": it is floored at the timer's 1 us.
        "tidf_ms_per_point": 1e3 * max(s_tidf - s_lin, 1e-6) / n,
        "shooting_ms_per_orbit": 1e3 * max(s_shoot - s_tidf, 1e-6) / n_orbit,
        "transient_ms_per_point": 1e3 * s_full / n,
        "boundary_curves_s": max(t_curves - t_lean, 1e-6),
        "tidf_a1_error_median": float(np.median(err[has])) if has.any() else float("nan"),
        "tidf_a1_error_max": float(err[has].max()) if has.any() else float("nan"),
        "orbits": int(has.sum()),
        "regime_agreement": float((ra[settled] == rt[settled]).mean()) if settled.any() else float("nan"),
        "settled_points": int(settled.sum()),
        "cycle_amplitude_error_max": float(amp_err.max()) if amp_err.size else float("nan"),
        "cycles_compared": int(both_cycle.sum()),
        "speedup_auto": t_full / t_auto,
        "speedup_auto_without_bistability": t_full / t_lean,
        "bistable_points": int((auto.bistable.values == 1).sum()),
        "irregular_points": int((np.nan_to_num(auto.basin_fraction.sel(attractor=2).values) > 0).sum()),
        "auto_decided_by": np.bincount(auto.decided_by.values.ravel(), minlength=4).tolist(),
    }
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.0, 4.4), layout="constrained")
    ax = fig.add_subplot()
    e_tidf = max(numbers["tidf_a1_error_median"], 1e-12)
    ax.loglog([e_tidf], [numbers["tidf_ms_per_point"] * 1e-3], "o", label="describing function (A1 error vs orbit, median)")
    ax.errorbar([e_tidf], [numbers["tidf_ms_per_point"] * 1e-3],
                xerr=[[0], [max(numbers["tidf_a1_error_max"] - e_tidf, 0)]], fmt="none", capsize=3)
    ax.loglog([1e-9], [numbers["shooting_ms_per_orbit"] * 1e-3], "s", label="shooting orbit (reference; residual 1e-9)")
    ax.axhline(numbers["transient_ms_per_point"] * 1e-3, ls="--", color="gray",
               label="transient (unilateral; no error: the saddle is unstable)")
    ax.set_xlabel("A1 error against the shooting orbit")
    ax.set_ylabel("wall time per point [s]")
    ax.set_title(f"cost of each model over {n} seed-sweep points")
    ax.legend(fontsize=7)
    png = out / "model_cost.png"
    fig.savefig(png, dpi=100)
    d = numbers
    md = "\n".join([
        "## The cost of each model", "",
        f"![model cost]({png.name})", "",
        f"Over {d['points']} points (normal load 10-150 N x arm length 5-11 cm, seed speed, one thread):",
        f"- describing function {d['tidf_ms_per_point']:.3g} ms/point, shooting {d['shooting_ms_per_orbit']:.3g} ms/orbit, "
        f"transient {d['transient_ms_per_point']:.1f} ms/point (each without the boundary curves, which a sweep over a "
        f"load x arm box stores by default: {d['boundary_curves_s']:.2f} s per sweep, whatever its number of points);",
        f"- describing-function A1 error against the {d['orbits']} orbits: median {d['tidf_a1_error_median']:.1%}, "
        f"max {d['tidf_a1_error_max']:.1%};",
        f"- auto vs transient: regime agreement {d['regime_agreement']:.0%} at the {d['settled_points']} points where "
        f"the transient settled; cycle amplitude error at most {d['cycle_amplitude_error_max']:.1%} over "
        f"{d['cycles_compared']} cycles; speed-up {d['speedup_auto_without_bistability']:.1f}x without the "
        f"attractor census, {d['speedup_auto']:.1f}x with it (which finds {d['bistable_points']} points with coexisting "
        f"attractors and {d['irregular_points']} where some disturbances sustain irregular motion, which a "
        "small-disturbance transient cannot see).",
        "",
    ])
    return {"numbers": numbers, "markdown": md, "files": {"model_cost": png}}
