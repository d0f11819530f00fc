"""The Stribeck sweep's own settings: speed against agreement (issue 10).

The issue-10 Stribeck sweep (`contact="unilateral"`, the switch friction law, `mu_static=0.3`,
loads 10-150 N x 10, arms 5-12.7 cm x 4, speeds 0.2-1 m/s x 5: 200 points, `census=False`,
`t_max=20`) spends its time on the transients of its irregular points. Two settings set that cost:
the transients' tolerance `transient_rtol` and `transient_irregular_block`, the sections per block of
the stationarity test that ends an irregular transient before `t_max` (0: it runs to `t_max`). The
measurement tolerance `rtol` stays at its default (cycles are measured by shooting at ten times
tighter, irregular motion on the exponent's runs at `ftle_rtol`). This module runs the sweep over both and compares
every run with a reference that runs every transient to `t_max` with `rtol` and `transient_rtol` at
1e-10:

- the regimes that differ from the reference's, against the **noise floor**: the reference's own
  regimes at both tolerances moved by +-1 %. A chaotic transient's fate (which attractor it ends on, and when it
  settles) depends on its last bits, so labels near `t_max` or between coexisting attractors move
  with any change of the arithmetic: a setting whose labels differ no more than the floor's is as
  good as the reference for the labels (the attractor census, not one transient, is the answer
  where attractors coexist);
- the cycle amplitude `z1_amplitude`'s relative error at the points where both runs found the same
  cycle (the same regime and `cycle_omega` within 1e-3; a point whose run lands on another of
  coexisting cycles is counted apart);
- the irregular points' `z` range, `irregular_z_max - irregular_z_min`, its median relative
  difference against the floor's.

Speed is points per second of the whole sweep on ``threads`` threads (best of ``repeat`` runs),
and right-hand sides per point (machine-independent).
"""

from __future__ import annotations

import os
import pathlib
import time

import numpy as np

from .. import _cycles
from .._codes import REGIME
from .._settings import DEFAULTS
from .._sweep import sweep

#: The issue-10 sweep's axes.
AXES = dict(normal_load=np.linspace(10, 150, 10), arm_length=np.linspace(0.05, 0.127, 4),
            sliding_speed=np.linspace(0.2, 1.0, 5))  # fmt: skip
#: The settings compared: `transient_rtol` x `transient_irregular_block`.
RTOLS = (1e-6, 1e-7, 1e-8, 1e-9)
BLOCKS = (64, 128, 256, 0)
#: The reference: every transient to `t_max`, `rtol` and `transient_rtol` at this.
REF_RTOL = 1e-10
#: The issue's goal for this sweep on 2 cores: 10x the 76 points/s of the issue's day, on the issue's
#: machine. On another machine the line is only a guide: ``benches/bench_issue_day.py`` measures the
#: ratio itself.
GOAL_POINTS_PER_S = 760.0
#: Cycles compared for amplitude: the same regime and `cycle_omega` within this relative difference.
SAME_CYCLE = 1e-3

_CYCLES = (REGIME["self_excited"], REGIME["contact_loss"], REGIME["stick_slip"])


def _run(model, threads: int, repeat: int, **kw):
    walls, ds = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        ds = sweep(model=model, census=False, t_max=20.0, threads=threads, progress=False, **AXES, **kw)
        walls.append(time.perf_counter() - t0)
    return ds, min(walls)


def compare(ds, ref) -> dict:
    """Agreement of sweep ``ds`` with ``ref`` (the same grid): differing regimes, cycle amplitude
    errors, irregular z-range differences."""
    r, rr = ds.regime.values.ravel(), ref.regime.values.ravel()
    w, wr = ds.cycle_omega.values.ravel(), ref.cycle_omega.values.ravel()
    a, ar = ds.z1_amplitude.values.ravel(), ref.z1_amplitude.values.ravel()
    both = np.isin(rr, _CYCLES) & (r == rr) & np.isfinite(a) & np.isfinite(ar)
    same = both & (np.abs(w / np.where(both, wr, 1.0) - 1) <= SAME_CYCLE)
    amp = np.abs(a[same] / ar[same] - 1)
    irr = (r == REGIME["irregular"]) & (rr == REGIME["irregular"])

    def z_range(d):
        return (d.irregular_z_max - d.irregular_z_min).values.ravel()[irr]

    dz = np.abs(z_range(ds) / z_range(ref) - 1)
    return {
        "regimes_differ": int((r != rr).sum()),
        "irregular": int((r == REGIME["irregular"]).sum()),
        "cycles_same": int(same.sum()),
        "cycles_other": int((both & ~same).sum()),
        "a1_error_median": float(np.median(amp)) if amp.size else float("nan"),
        "a1_error_max": float(amp.max()) if amp.size else float("nan"),
        "z_range_diff_median": float(np.median(dz)) if dz.size else float("nan"),
    }


def sweep_settings(out_dir: os.PathLike, *, quick: bool = False, threads: int = 2, law: str = "switch") -> dict:
    """Measure, draw ``sweep_settings.png`` into ``out_dir``; return ``numbers``, ``markdown``, ``files``.

    ``quick`` times each setting once (else best of 2).
    """
    from .._model import SliderModel

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    repeat = 1 if quick else 2
    model = SliderModel(contact="unilateral", friction_law=law, mu_static=0.3)
    _run(model, threads, 1, transient_irregular_block=256)  # warm-up (first call's imports and caches)
    ref, t_ref = _run(model, threads, 1, rtol=REF_RTOL, transient_rtol=REF_RTOL, transient_irregular_block=0)
    n = int(ref.regime.size)
    floor = []
    for f in (1.01, 0.99):
        ds, t = _run(model, threads, 1, rtol=REF_RTOL * f, transient_rtol=REF_RTOL * f, transient_irregular_block=0)
        floor.append(
            dict(compare(ds, ref), rtol=REF_RTOL * f, points_per_s=n / t, rhs_per_point=float(ds.n_rhs.mean()))
        )
    rows = []
    for rtol in RTOLS:
        for block in BLOCKS:
            ds, t = _run(model, threads, repeat, transient_rtol=rtol, transient_irregular_block=block)
            rows.append(dict(compare(ds, ref), transient_rtol=rtol, block=block, points_per_s=n / t,
                             rhs_per_point=float(ds.n_rhs.mean())))  # fmt: skip
    numbers = {"law": law, "threads": threads, "points": n, "reference_points_per_s": n / t_ref,
               "reference_rhs_per_point": float(ref.n_rhs.mean()),
               "reference_irregular": int((ref.regime.values == REGIME["irregular"]).sum()),
               "floor": floor, "rows": rows}  # fmt: skip
    png = out / "sweep_settings.png"
    _chart(numbers).savefig(png, dpi=100)
    return {"numbers": numbers, "markdown": _markdown(numbers, png.name), "files": {"sweep_settings": png}}


def _chart(d: dict):
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    fig = Figure(figsize=(10.5, 4.8), layout="constrained")
    ax_l, ax_a = fig.subplots(1, 2)
    default = (DEFAULTS.steady.rtol, DEFAULTS.irregular.transient_block)
    colors = dict(zip(RTOLS, ("tab:red", "tab:orange", "tab:green", "tab:blue")))
    markers = dict(zip(BLOCKS, ("v", "s", "o", "D")))
    lo = min(f["regimes_differ"] for f in d["floor"])
    hi = max(f["regimes_differ"] for f in d["floor"])
    ax_l.axhspan(lo - 0.5, hi + 0.5, color="0.85", zorder=0)
    for r in d["rows"]:
        kw = dict(color=colors[r["transient_rtol"]], marker=markers[r["block"]], ls="none", ms=7,
                  mec="k" if (r["transient_rtol"], r["block"]) == default else "none")  # fmt: skip
        ax_l.plot(r["points_per_s"], r["regimes_differ"], **kw)
        ax_a.plot(r["points_per_s"], r["a1_error_median"], **kw)
    for ax in (ax_l, ax_a):
        ax.axvline(GOAL_POINTS_PER_S, color="k", ls=":", lw=1)
        ax.set_xlabel(f"points/s ({d['threads']} threads, whole sweep)")
        ax.set_xlim(0, GOAL_POINTS_PER_S * 1.08)
        ax.grid(alpha=0.3)
    ax_l.set_ylim(-0.5, max(max(r["regimes_differ"] for r in d["rows"]), hi) + 2.5)
    ax_l.set_ylabel(f"regimes differing from the reference (of {d['points']})")
    ax_l.set_title("labels: grey = the reference itself at its tolerances +-1 %", fontsize=9)
    ax_a.set_yscale("log")
    errs = [r["a1_error_median"] for r in d["rows"] if np.isfinite(r["a1_error_median"]) and r["a1_error_median"] > 0]
    if errs:  # whole decades around the errors, at least two: a flat row of errors reads as flat
        lo, hi = np.floor(np.log10(min(errs))), np.ceil(np.log10(max(errs)))
        ax_a.set_ylim(10 ** min(lo, hi - 2), 10 ** max(hi, lo + 2))
    ax_a.set_ylabel("cycle amplitude z1: median relative error")
    check = _cycles.check_rtol(DEFAULTS.integration.rtol, DEFAULTS.shooting.rtol)
    ax_a.set_title(f"the same cycles' amplitude (on the orbit at rtol {check:g}; reference {REF_RTOL:g})",
                   fontsize=9)  # fmt: skip
    for ax in (ax_l, ax_a):
        ax.text(
            GOAL_POINTS_PER_S,
            0.98,
            f"issue goal {GOAL_POINTS_PER_S:.0f} (its machine) ",
            transform=ax.get_xaxis_transform(),
            fontsize=8,
            va="top",
            ha="right",
            rotation=90,
        )
    handles = [Line2D([], [], color=colors[t], marker="o", ls="none", label=f"transient_rtol {t:g}") for t in RTOLS]
    handles += [Line2D([], [], color="0.4", marker=markers[b], ls="none",
                       label=f"block {b}" if b else "no early stop") for b in BLOCKS]  # fmt: skip
    handles.append(Line2D([], [], color="0.4", marker="o", mec="k", ls="none", label=f"default ({default[0]:g}, {default[1]})"))
    fig.legend(handles=handles, fontsize=8, loc="outside lower center", ncol=5)
    fig.suptitle(f"The Stribeck sweep ({d['law']} law, {d['points']} points, t_max 20 s): "
                 "transient_rtol x transient_irregular_block, against a reference run to t_max at 1e-10", fontsize=10)  # fmt: skip
    return fig


def _markdown(d: dict, png: str) -> str:
    fl = d["floor"]
    lines = [
        "## The Stribeck sweep's settings: speed against agreement",
        "",
        f"![sweep settings]({png})",
        "",
        f"The issue-10 Stribeck sweep ({d['law']} law, {d['points']} points, `census=False`, `t_max=20`, "
        f"{d['threads']} threads, `rtol` {DEFAULTS.integration.rtol:g}) over `transient_rtol` and "
        f"`transient_irregular_block`, against a reference that runs every transient to `t_max` with `rtol` and "
        f"`transient_rtol` at {REF_RTOL:g} ({d['reference_points_per_s']:.0f} points/s, "
        f"{d['reference_rhs_per_point']:,.0f} right-hand sides per point, {d['reference_irregular']} irregular). "
        f"The reference itself at both tolerances +-1 % differs in {fl[0]['regimes_differ']} and {fl[1]['regimes_differ']} "
        f"regimes (the noise floor: chaotic transients' fates move with the last bits); its irregular points' "
        f"`z` range by {fl[0]['z_range_diff_median']:.1%} and {fl[1]['z_range_diff_median']:.1%} (median).",
        "",
        "| transient_rtol | transient_irregular_block | points/s | rhs/point | regimes differing | same cycle (other) | "
        "z1 error median | z1 error max | irregular z range, median diff |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in d["rows"]:
        lines.append(f"| {r['transient_rtol']:g} | {r['block'] or 'none (t_max)'} | {r['points_per_s']:.0f} | "
                     f"{r['rhs_per_point']:,.0f} | {r['regimes_differ']} | {r['cycles_same']} ({r['cycles_other']}) | "
                     f"{r['a1_error_median']:.1e} | {r['a1_error_max']:.1e} | {r['z_range_diff_median']:.1%} |")  # fmt: skip
    lines.append("")
    return "\n".join(lines)
