"""Work-precision charts (log-log, error on x, time on y, one marked line per method) and the markdown summary."""
from __future__ import annotations

import math

from .analysis import fastest, law_comparison, speed_ratios, times_at
from .scenes import FASTEST_AT, MATCHED_ERRORS, RATIO_PAIRS

_STYLE = {
    "rust dopri5": ("o", "-", "#0072B2"),
    "rust dop853": ("s", "-", "#D55E00"),
    "rust rodas4": ("D", "-", "#009E73"),
    # The switch friction law on the stick-slip scene: the same method colours, open markers, dashed.
    "switch dopri5": ("o", (0, (4, 2)), "#0072B2"),
    "switch dop853": ("s", (0, (4, 2)), "#D55E00"),
    "switch rodas4": ("D", (0, (4, 2)), "#009E73"),
    "numba DP5": ("^", ":", "#56B4E9"),
    "scipy RK45": ("o", "--", "#7f7f7f"),
    "scipy DOP853": ("s", "--", "#CC79A7"),
    "scipy Radau": ("D", "--", "#E69F00"),
    "diffrax Dopri5": ("v", "-.", "#000000"),
}
_ERR_FLOOR = 1e-16  # errors below this (identical to the reference) are drawn at the floor
_FAIL_X = 20.0  # failed rungs are drawn in a band right of error 1


def plot_work_precision(rows: list[dict], scene: dict | str, *, ax=None):
    """One scene's work-precision chart: error (x) against wall time per trajectory (y), log-log.

    One marked line per method through its successful rungs (ladder order); failed rungs are drawn as
    ``x`` in the method's colour in the grey band right of error 1, at their measured time, so nothing
    is dropped. Errors below the reference's own check are shaded (not resolved).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    info = scene if isinstance(scene, dict) else {"name": scene, "title": scene}
    name = info["name"]
    if ax is None:
        fig = Figure(figsize=(9.0, 5.0), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    labels = list(dict.fromkeys(r["label"] for r in rows if r["scene"] == name))
    any_fail = False
    for label in labels:
        marker, ls, color = _STYLE.get(label, ("o", "-", None))
        rs = sorted((r for r in rows if r["scene"] == name and r["label"] == label), key=lambda r: -r["rtol"])
        ok = [r for r in rs if not r["failed"]]
        bad = [r for r in rs if r["failed"]]
        hollow = {"markerfacecolor": "white", "markeredgewidth": 1.5} if label.startswith("switch ") else {}
        # Beside variant lines, say which law the scene's own Rust lines integrate.
        shown = f"{label} ({'tanh' if info.get('friction_law') == 'coulomb' else info.get('friction_law')} law)" \
            if info.get("variants") and label.startswith("rust ") else label
        line = ax.plot([max(r["error"], _ERR_FLOOR) for r in ok], [r["seconds_per_traj"] for r in ok],
                       marker=marker, linestyle=ls, color=color, label=shown, markersize=5, **hollow)  # fmt: skip
        color = line[0].get_color()
        if bad:
            any_fail = True
            ax.plot([_FAIL_X] * len(bad), [r["seconds_per_traj"] for r in bad], linestyle="none", marker="x",
                    color=color, markersize=8, markeredgewidth=2)  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axvspan(2.0, 60.0, color="0.9", zorder=0)
    ax.text(4.0, 0.5, "failed rungs (status != 0, NaN or error > 1)", transform=ax.get_xaxis_transform(),
            ha="center", va="center", rotation=90, fontsize=7, color="0.35")  # fmt: skip
    chk = (info.get("reference") or {}).get("check_value")
    if chk is not None and math.isfinite(chk) and chk > 0:
        ax.axvspan(_ERR_FLOOR / 3, max(chk, _ERR_FLOOR), color="0.95", hatch="//", zorder=0, linewidth=0,
                   label=f"below reference check ({chk:.0e})")  # fmt: skip
    for key, var in (info.get("variants") or {}).items():
        vchk = var["reference"].get("check_value")
        if vchk is not None and math.isfinite(vchk) and vchk > 0:
            ax.axvline(vchk, color="0.4", linestyle=":", linewidth=1.2, zorder=0,
                       label=f"{key} lines: reference check ({vchk:.0e})")  # fmt: skip
    ax.set_xlim(_ERR_FLOOR / 3, 60.0)
    ax.set_xlabel("error  max |z(t_end) - z_ref| / max|z_ref|")
    ax.set_ylabel("wall time per trajectory [s] (1 thread)")
    ax.set_title(f"{name}: {info.get('title', '')}", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    if any_fail:
        ax.plot([], [], linestyle="none", marker="x", color="k", label="failed rung (status, NaN or error > 1)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return fig


def _fmt_s(s: float) -> str:
    if not math.isfinite(s):
        return "n/a"
    if s >= 1.0:
        return f"{s:.2f} s"
    if s >= 1e-3:
        return f"{s * 1e3:.3g} ms"
    return f"{s * 1e6:.3g} us"


def render_summary(payload: dict, *, images: dict[str, str] | None = None, extra: str = "",
                   command: str | None = None) -> str:  # fmt: skip
    """Markdown summary of a work-precision payload: ratios at matched error, fastest methods, failures.

    Parameters
    ----------
    payload : dict
        From :func:`measure` or :func:`load_payload`.
    images : dict of str to str, optional
        ``{scene name: relative image path}`` to embed (the docs page embeds none).
    extra : str
        Markdown appended (e.g. the failure-map section).
    command : str, optional
        The command that produced the data.
    """
    meta, rows = payload["meta"], payload["rows"]
    scenes = payload["scenes"]
    L = ["# Work-precision benchmarks", ""]
    L.append(f"Generated by `{command or 'tribosweep bench'}` on {meta['date']}"
             + (f" (commit {meta['commit']})" if meta.get("commit") else "") + ".")  # fmt: skip
    L.append(f"Machine: {meta['machine']}. Versions: "
             + ", ".join(f"{k} {v}" for k, v in meta["versions"].items()) + ".")  # fmt: skip
    mode = "quick" if meta["quick"] else "full"
    L.append(f"Mode: **{mode}**; rtol ladder {', '.join(f'{r:.0e}' for r in meta['ladder'])}; "
             f"every timed rung is the best of {meta['repeat']} interleaved passes (scipy: best of "
             f"{meta['scipy_repeat']} back to back, on "
             f"{meta['scipy_n']} trajectories); one thread everywhere; total {meta['seconds']:.0f} s.")  # fmt: skip
    if meta.get("loadavg") and None not in meta["loadavg"]:
        a, b = meta["loadavg"]
        cores = meta.get("cores") or 1
        L.append(f"1-minute load average at start / end: {a:g} / {b:g} on {cores} cores"
                 + (" (other work competed for the cores: absolute times are inflated and noisy)."
                    if max(a, b) > cores - 0.8 else "."))  # fmt: skip
    L += ["",
          ("Error = max over the batch of |z(t_end) - z_ref(t_end)| / max|z_ref| with the Rust DOP853 at rtol "
           "1e-13 as reference; time = wall time per trajectory through `tribosweep.ensemble(threads=1)` (its "
           "fixed per-call Python/xarray overhead is included and spread over the batch: see the scenes table). "
           "All methods get the same atol: rtol times each component's characteristic size. Times are from one "
           "run on a possibly shared machine: read the ratios, not the absolute numbers."), ""]  # fmt: skip

    L += ["## Scenes", "",
          ("| scene | trajectories | what it exercises | reference check | events/traj | max gap | min v_r | "
           "ensemble call overhead |"), "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for s in scenes:
        ref = s["reference"]
        chk = ref.get("check_value")
        chk_s = f"{chk:.1e} vs {ref.get('check_method')} ({ref.get('check_n')} traj)" if chk is not None and \
            math.isfinite(chk) else str(ref.get("check_method"))  # fmt: skip
        over = ref.get("api_overhead_per_call")
        over_s = f"{_fmt_s(over)} per call = {_fmt_s(ref['api_overhead_per_traj'])}/traj" if over else "n/a"
        L.append(f"| `{s['name']}` | {s['n_traj']} | {s['description']} | {chk_s} | {ref['n_events']:.0f} | "
                 f"{ref['max_gap'] * 1e6:+.2f} um | {ref['min_slip_velocity']:+.3g} m/s | {over_s} |")  # fmt: skip
    ss = [s for s in scenes if s["friction_law"] == "coulomb"]
    for s in ss:
        v = s["reference"]["min_slip_velocity"]
        L.append("")
        L.append(f"Stick-slip check (`{s['name']}`): the reference's minimum sliding velocity is {v:+.3g} m/s "
                 + ("<= 0: the contact point sticks." if v <= 0 else "> 0: NO sticking; the scene does not test "
                    "what it should."))  # fmt: skip
        for key, var in (s.get("variants") or {}).items():
            v, eta = var["reference"]["min_slip_velocity"], var.get("stick_band", math.nan)
            L.append(f"With the {var['friction_law']} law (`{key}` lines) the minimum is {v:+.3g} m/s, "
                     + (f"within the stick band {eta:g} m/s: it sticks." if v <= eta * (1 + 1e-6) else
                        f"outside the stick band {eta:g} m/s: NO sticking."))  # fmt: skip
    laws = law_comparison(rows, scenes)
    if laws:
        L += ["", "## Friction laws at matched error", "",
              ("Each line read at the same error (against its own law's reference) as in the ratios below; "
               "ratio = tanh / switch (> 1: the switch law is cheaper). The right-hand-side counts are the "
               "integrator's own (event location adds none), so their ratio does not depend on the machine."),
              "", "| scene | method | error | tanh time | switch time | time ratio | tanh rhs | switch rhs | "
              "rhs ratio |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for q in laws:
            L.append(f"| `{q['scene']}` | {q['method']} | {q['error']:.0e} | {_fmt_s(q['base_seconds'])} | "
                     f"{_fmt_s(q['variant_seconds'])} | **{q['time_ratio']:.3g}x** | {q['base_rhs']:.3g} | "
                     f"{q['variant_rhs']:.3g} | **{q['rhs_ratio']:.3g}x** |")  # fmt: skip

    L += ["", "## Speed ratio of the Rust core at matched error", "",
          ("Ratio = baseline time / Rust time per trajectory, both read off their work-precision lines "
           "(linear interpolation in log error - log time, no extrapolation) at the same error; > 1: Rust "
           "faster. Rust runs through `ensemble` with one thread; numba is the one-core DP5 kernel of "
           "`tribosweep.bench.baselines` (same scheme as `dopri5`); scipy is `solve_ivp` on the independent "
           "`tribosweep.reference` (event-driven `solve_unilateral` for unilateral scenes)."), ""]  # fmt: skip
    ratios = speed_ratios(rows)
    if ratios:
        L += ["| scene | error | Rust | baseline | Rust time | baseline time | ratio |", "|---|---|---|---|---|---|---|"]
        for q in ratios:
            rl = q["rust_label"] + (" (fastest Rust)" if q["rust"] == "rust (fastest)" else "")
            bl = q["baseline_label"] + (" (fastest scipy)" if q["baseline"] == "scipy (fastest)" else "")
            L.append(f"| `{q['scene']}` | {q['error']:.0e} | {rl} | {bl} | "
                     f"{_fmt_s(q['rust_seconds'])} | {_fmt_s(q['baseline_seconds'])} | **{q['ratio']:.3g}x** |")
    else:
        L.append("No pair of lines reaches a common error (too few rungs, or baselines skipped).")
    missing = []
    for s in scenes:
        for target in MATCHED_ERRORS:
            at = times_at(rows, s["name"], target)
            for rust, base in RATIO_PAIRS:
                have_base = any(r["scene"] == s["name"] and r["label"] == base for r in rows) or \
                    (base == "scipy (fastest)" and any(r["scene"] == s["name"] and r["impl"] == "scipy" for r in rows))
                if have_base and not (rust in at and base in at):
                    missing.append(f"`{s['name']}` {target:.0e}: {rust} / {base}")
    if missing:
        L += ["", "Not quoted (a line does not reach that error): " + "; ".join(missing) + "."]

    L += ["", "## Fastest method per scene", "", "| scene | " + " | ".join(f"error {e:.0e}" for e in FASTEST_AT)
          + " |", "|---|" + "---|" * len(FASTEST_AT)]  # fmt: skip
    fast = fastest(rows)
    for s in scenes:
        cells = []
        for e in FASTEST_AT:
            f = next(x for x in fast if x["scene"] == s["name"] and x["error"] == e)
            if f["label"] is None:
                cells.append(f.get("why", "not reached"))
            else:
                nxt = f" ({f['next_seconds'] / f['seconds']:.2g}x ahead of the next)" if math.isfinite(
                    f["next_seconds"]) else ""  # fmt: skip
                cells.append(f"{f['label']}, {_fmt_s(f['seconds'])}{nxt}")
        L.append(f"| `{s['name']}` | " + " | ".join(cells) + " |")

    fails = [r for r in rows if r["failed"]]
    L += ["", "## Failed rungs", ""]
    if fails:
        L += ["Recorded and drawn (x in the grey band), never dropped:", "",
              "| scene | method | rtol | status | failed/traj | error | reason |", "|---|---|---|---|---|---|---|"]
        for r in fails:
            L.append(f"| `{r['scene']}` | {r['label']} | {r['rtol']:.0e} | {r['status']} | {r['n_failed']}/"
                     f"{r['n_traj']} | {r['error']:.2e} | {r['reason'] or ''} |")  # fmt: skip
    else:
        L.append("None: every rung of every method finished with status 0 and an error below 1.")
    if payload.get("notes"):
        L += ["", "## Notes", ""] + [f"- {n}" for n in payload["notes"]]

    L += ["", "## Work-precision data", ""]
    for s in scenes:
        L.append(f"### `{s['name']}`: {s['title']}")
        L.append("")
        if images and s["name"] in images:
            L += [f"![work-precision {s['name']}]({images[s['name']]})", ""]
        L += ["<details><summary>every rung</summary>", "",
              "| method | rtol | time/traj | error | rhs/traj | steps/traj | status |", "|---|---|---|---|---|---|---|"]
        for r in rows:
            if r["scene"] == s["name"]:
                L.append(f"| {r['label']} | {r['rtol']:.0e} | {_fmt_s(r['seconds_per_traj'])} | {r['error']:.2e} | "
                         f"{r['n_rhs']:.0f} | {r['steps']:.0f} | {r['status']} |")  # fmt: skip
        L += ["", "</details>", ""]
    if extra:
        L += [extra.rstrip(), ""]
    return "\n".join(L).rstrip() + "\n"
