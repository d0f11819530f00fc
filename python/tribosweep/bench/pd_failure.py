"""Where shooting fails near a period doubling: a failure map and a bifurcation diagram.

The unilateral model's bouncing cycle loses its stability by a flip at high friction: at 80 N a
complex pair of Floquet multipliers meets on the negative real axis near ``mu = 0.418`` and one
real multiplier crosses -1 near ``mu = 0.4206``; a stable period-2 cycle takes over (period
19.24 ms against 9.62 ms). Shooting a period-1 orbit does not notice: ``M - I`` stays regular at
``rho = -1``, so Newton converges to the unstable period-1 orbit, which is not what the slider
does. Only the multipliers tell (``period_doubling``, ``instability = flip``); and a solve for
the doubled orbit is singular at the crossing (``rho^2 = 1``).

``shooting_pd_map``
    Over normal load x mu: a transient to the attractor (unilateral contact, from
    ``z = |z_st|``), then period-1 shooting from the transient's section state with the linear
    mode's period as the guess, the way a user would start it. Codes: ``valid`` (converged,
    stable, no real multiplier near -1), ``near_flip`` (converged, stable, a real multiplier
    within ``FLIP_TOL`` of -1), ``flip_unstable`` (converged to an orbit unstable by a flip: past
    the period doubling, not the attractor), ``other_unstable`` (a fold or torus instability),
    ``not_converged`` (Newton did not converge from the transient's state), ``no_cycle`` (the
    transient decayed, diverged or did not settle: nothing to shoot from).
``bifurcation_diagram``
    Along mu at one load: the transient's peaks of z (two per period-1 cycle, four per period-2)
    and the flip multiplier of the period-1 branch followed by continuation (each solve starts
    from the previous orbit), through the crossing and beyond.
"""

from __future__ import annotations

import os
import pathlib

import numpy as np
import xarray as xr

from .. import _core
from .._codes import INSTABILITY_NAMES, OUTCOME_NAMES, flag_attrs
from .._frequency import FLIP_TOL
from .._model import SliderModel
from .._simulate import STATE_VARS, ensemble

SHOOTING_NAMES = ("valid", "near_flip", "flip_unstable", "other_unstable", "not_converged", "no_cycle")
#: Simulated time allowed to the transients [s]: near the flip the approach to the cycle is slow
#: (multipliers of modulus 0.99), 26 s at 80 N and mu = 0.4225.
T_MAX = 40.0


def _unilateral(model: SliderModel | None) -> SliderModel:
    m = model or SliderModel(contact="unilateral")
    if m.contact != "unilateral":
        raise ValueError(f"model.contact = {m.contact!r}: the period doubling is a unilateral-contact effect")
    return m


def _start(m: SliderModel, loads: np.ndarray) -> np.ndarray:
    """``z = |z_st|`` at each load: the pin just lifted to the disk's surface."""
    y0 = np.zeros((loads.size, 6))
    y0[:, 0] = [abs(m.replace(normal_load=float(f)).static_point()[0]) for f in loads]
    return y0


def shooting_pd_map(normal_load, mu, *, model: SliderModel | None = None, t_max: float = T_MAX,
                    threads: int | None = None) -> xr.Dataset:  # fmt: skip
    """Period-1 shooting from the transient's state over normal load [N] x mu (see module doc)."""
    m = _unilateral(model)
    loads, mus = np.asarray(normal_load, float), np.asarray(mu, float)
    ll, mm = np.meshgrid(loads, mus, indexing="ij")
    pl, pm = ll.ravel(), mm.ravel()
    tr = ensemble(m, t_max, {"normal_load": pl, "mu": pm}, y0=_start(m, pl), steady=True, rtol=1e-9,
                  periodic_tol=1e-6, threads=threads)  # fmt: skip
    lin = _core.linear_stability(m.values(), m.contact, m.friction_law, ["normal_load", "mu"],
                                 np.column_stack([pl, pm]), threads=threads)  # fmt: skip
    t_guess = 2.0 * np.pi / np.asarray(lin["linear_frequency"])
    n = pl.size
    code = np.full(n, SHOOTING_NAMES.index("no_cycle"), dtype=np.uint8)
    flip = np.full(n, np.nan)
    iters = np.zeros(n, dtype=np.int64)
    period1 = np.full(n, np.nan)
    attractor = np.full(n, -1, dtype=np.int8)
    periodic = tr.outcome.values == OUTCOME_NAMES.index("periodic")
    ends = np.column_stack([tr[f"{name}_end"].values for name, _, _ in STATE_VARS])
    idx = np.flatnonzero(periodic)
    if idx.size:
        vals = np.column_stack([pl[idx], pm[idx]])

        def shoot(periods):
            return _core.periodic_orbits(m.values(), m.contact, m.friction_law, ["normal_load", "mu"], vals,
                                         y0=ends[idx], periods=periods, threads=threads)  # fmt: skip

        o1 = shoot(t_guess[idx])  # the linear mode's period: the guess a user would make
        oa = shoot(tr.period.values[idx])  # the attractor's own period (twice the mode's past a doubling)
        attractor[idx] = np.where(oa["status"] == 0, oa["stable"].astype(np.int8), -1)
        iters[idx] = o1["newton_iterations"]
        ok = o1["status"] == 0
        flip[idx] = np.where(ok, o1["flip_multiplier"], np.nan)
        period1[idx] = np.where(ok, o1["period"], np.nan)
        kind = np.array([INSTABILITY_NAMES[k] for k in o1["instability"]])
        near = np.isfinite(flip[idx]) & (flip[idx] < -1.0 + FLIP_TOL)
        c = np.select([~ok, kind == "flip", kind != "stable", near],
                      [SHOOTING_NAMES.index(x) for x in ("not_converged", "flip_unstable", "other_unstable", "near_flip")],
                      SHOOTING_NAMES.index("valid"))  # fmt: skip
        code[idx] = c.astype(np.uint8)
    dims = ("normal_load", "mu")
    shape = ll.shape
    ratio = np.where(periodic, tr.period.values / t_guess, np.nan)
    return xr.Dataset(
        {
            "shooting": (dims, code.reshape(shape), flag_attrs(SHOOTING_NAMES, "period-1 shooting from the transient's state")),
            "flip_multiplier": (dims, flip.reshape(shape), {
                "units": "1", "long_name": "most negative real Floquet multiplier of the period-1 orbit"}),
            "newton_iterations": (dims, iters.reshape(shape), {"units": "1", "long_name": "Newton iterations"}),
            "attractor_orbit_stable": (dims, attractor.reshape(shape), {
                "long_name": "shooting with the transient's own period from its state: the attractor's orbit",
                "flag_values": np.array([-1, 0, 1], dtype=np.int8), "flag_meanings": "not_converged unstable stable"}),
            "orbit_period": (dims, period1.reshape(shape), {"units": "s", "long_name": "period of the shooting orbit"}),
            "attractor_period_ratio": (dims, ratio.reshape(shape), {
                "units": "1", "long_name": "period of the transient's cycle in periods of the least stable linear mode",
                "comment": "about 1 for the ordinary cycle, about 2 after a period doubling"}),
        },
        coords={"normal_load": ("normal_load", loads, {"units": "N", "long_name": "normal load"}),
                "mu": ("mu", mus, {"units": "1", "long_name": "friction coefficient"})},
        attrs={"title": "period-1 shooting from the attractor near a period doubling (unilateral)"},
    )


def bifurcation_diagram(mu, *, normal_load: float = 80.0, model: SliderModel | None = None,
                        t_max: float = T_MAX, n_peaks: int = 24, threads: int | None = None) -> xr.Dataset:  # fmt: skip
    """Transient peaks of z and the continued period-1 branch's flip multiplier along ``mu`` (see module doc)."""
    m = _unilateral(model).replace(normal_load=float(normal_load))
    mus = np.asarray(mu, float)
    if mus.ndim != 1 or mus.size < 2 or np.any(np.diff(mus) <= 0):
        raise ValueError(f"mu = {mu!r} must be a strictly increasing 1-D sequence of at least 2 values")
    # Peaks: sample the last stretch of each transient densely (40 samples per 9.6 ms cycle).
    lin = _core.linear_stability(m.values(), m.contact, m.friction_law, ["mu"], mus[:, None], threads=threads)
    period = 2.0 * np.pi / float(np.median(lin["linear_frequency"]))
    span = 0.5 * n_peaks * period * 1.05
    t_eval = np.linspace(t_max - span, t_max, int(40 * span / period) + 1)
    tr = ensemble(m, t_max, {"mu": mus}, y0=_start(m, np.full(mus.size, normal_load)), t_eval=t_eval, rtol=1e-9,
                  threads=threads)  # fmt: skip
    peaks = np.full((mus.size, n_peaks), np.nan)
    for i in range(mus.size):
        z = tr.z.values[i]
        if tr.status.values[i] != 0 or not np.all(np.isfinite(z)):
            continue
        k = np.flatnonzero((z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:])) + 1
        # Parabolic refinement of each sampled maximum.
        a, b, c = z[k - 1], z[k], z[k + 1]
        den = a - 2 * b + c
        zmax = b - 0.125 * (a - c) ** 2 / np.where(den == 0, -np.inf, den)
        zmax = zmax[-n_peaks:]
        peaks[i, : zmax.size] = zmax
    # Continuation of the period-1 branch from the first transient that settled on a cycle.
    flip = np.full(mus.size, np.nan)
    inst = np.full(mus.size, INSTABILITY_NAMES.index("unknown"), dtype=np.uint8)
    p1 = np.full(mus.size, np.nan)
    st = np.full(mus.size, 255, dtype=np.uint8)
    y, t = None, period
    ends = np.column_stack([tr[f"{name}_end"].values for name, _, _ in STATE_VARS])
    for i, mu_i in enumerate(mus):
        if y is None:
            if tr.status.values[i] != 0:
                continue
            y = ends[i]
        o = _core.periodic_orbit(m.replace(mu=float(mu_i)).values(), m.contact, m.friction_law, y0=y, period=t)
        st[i] = o["status"]
        if o["status"] != 0:
            break  # the branch is lost (a fold or a grazing); later points stay not computed
        y, t = np.asarray(o["state0"]), o["period"]
        flip[i], inst[i], p1[i] = o["flip_multiplier"], o["instability"], o["period"]
    return xr.Dataset(
        {
            "z_peaks": (("mu", "peak"), peaks, {"units": "m", "long_name": "local maxima of z at the end of the transient"}),
            "flip_multiplier": ("mu", flip, {"units": "1", "long_name": "most negative real multiplier, period-1 branch"}),
            "instability": ("mu", inst, flag_attrs(INSTABILITY_NAMES, "instability of the period-1 branch")),
            "branch_period": ("mu", p1, {"units": "s", "long_name": "period of the period-1 branch"}),
            "branch_status": ("mu", st, {"long_name": "status of the continuation solve (255: not computed)"}),
        },
        coords={"mu": ("mu", mus, {"units": "1", "long_name": "friction coefficient"}), "peak": np.arange(n_peaks)},
        attrs={"title": f"period doubling of the bouncing cycle at {normal_load:g} N (unilateral)",
               "normal_load": float(normal_load)},
    )


def flip_crossing(bd: xr.Dataset) -> float:
    """mu where the branch's flip multiplier crosses -1 (linear interpolation; NaN if it does not)."""
    f, mu = bd.flip_multiplier.values, bd.mu.values
    for i in range(f.size - 1):
        if np.isfinite(f[i]) and np.isfinite(f[i + 1]) and f[i] > -1.0 >= f[i + 1]:
            return float(mu[i] + (-1.0 - f[i]) * (mu[i + 1] - mu[i]) / (f[i + 1] - f[i]))
    return float("nan")


def draw_bifurcation(bd: xr.Dataset, ax=None):
    """Peaks of z against mu, with the period-1 branch's flip multiplier on a second axis."""
    from matplotlib.figure import Figure

    fig = None
    if ax is None:
        fig = Figure(figsize=(6.4, 4.6), layout="constrained")
        ax = fig.add_subplot()
    mu = bd.mu.values
    for j in range(bd.sizes["peak"]):
        ax.plot(mu, bd.z_peaks.values[:, j] * 1e6, ".", ms=2.5, color="C0")
    ax.set_xlabel("friction coefficient mu")
    ax.set_ylabel("local maxima of z [um] (transient)", color="C0")
    ax2 = ax.twinx()
    ax2.plot(mu, bd.flip_multiplier.values, "-", color="C3", marker="s", ms=3, label="flip multiplier, period-1 branch")
    ax2.axhline(-1.0, color="C3", lw=0.8, ls="--")
    ax2.set_ylabel("most negative real multiplier", color="C3")
    mu_pd = flip_crossing(bd)
    if np.isfinite(mu_pd):
        ax.axvline(mu_pd, color="0.4", lw=0.8, ls=":")
        ax.set_title(f"{bd.attrs['title']}\nflip at mu = {mu_pd:.4f}", fontsize=9)
    else:
        ax.set_title(bd.attrs["title"], fontsize=9)
    return fig or ax.figure


def pd_failure_maps(out_dir: os.PathLike, *, quick: bool = False, threads: int | None = None) -> dict:
    """Compute and draw the shooting map and the bifurcation diagram into ``out_dir``.

    Returns ``files``, ``counts``, ``numbers`` (the flip's mu, the map's codes) and ``markdown``.
    """
    from matplotlib.figure import Figure

    from .status_map import draw_status_map

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if quick:
        loads, mus, mus_bd = np.array([75.0, 80.0, 85.0]), np.linspace(0.39, 0.43, 9), np.linspace(0.405, 0.43, 11)
    else:
        loads, mus, mus_bd = np.arange(72.0, 86.5, 1.0), np.linspace(0.39, 0.44, 21), np.linspace(0.40, 0.435, 36)
    smap = shooting_pd_map(loads, mus, threads=threads)
    bd = bifurcation_diagram(mus_bd, threads=threads)
    files, counts = {}, {}
    fig = Figure(figsize=(6.4, 4.6), layout="constrained")
    ax = fig.add_subplot()
    draw_status_map(smap, "shooting", cost="newton_iterations", ax=ax, title=smap.attrs["title"], success="valid")
    # Where the transient settled on a cycle of twice the period.
    jl, jm = np.nonzero(np.abs(smap.attractor_period_ratio.values - 2.0) < 0.3)
    if jl.size:
        ax.plot(smap.mu.values[jm], smap.normal_load.values[jl], "o", ms=4, mfc="none", mec="w", mew=1.2,
                label="period-2 attractor")  # fmt: skip
        ax.legend(loc="lower left", fontsize=7, framealpha=0.6)
    for name, ds, f in (("failure_shooting_pd", smap, fig), ("bifurcation_pd", bd, draw_bifurcation(bd))):
        png, nc = out / f"{name}.png", out / f"{name}.nc"
        f.savefig(png, dpi=100)
        ds.to_netcdf(nc)
        files[name], files[name + "_nc"] = png, nc
    counts["failure_shooting_pd"] = {nm: int((smap.shooting.values == i).sum()) for i, nm in enumerate(SHOOTING_NAMES)}
    mu_pd = flip_crossing(bd)
    n_double = int(np.sum(np.abs(smap.attractor_period_ratio.values - 2.0) < 0.3))
    numbers = {"flip_mu": mu_pd, "normal_load": bd.attrs["normal_load"], "period_2_points": n_double}
    md = ["## Shooting near a period doubling", "",
          "![failure_shooting_pd](failure_shooting_pd.png) ![bifurcation_pd](bifurcation_pd.png)", "",
          ", ".join(f"{k}: {v}" for k, v in counts["failure_shooting_pd"].items()), "",
          "Codes (cell labels): NE near_flip (stable, a real multiplier within 0.05 of -1), FL flip_unstable "
          "(converged to a period-1 orbit past the flip), NV not_converged (Newton from the period-2 attractor's "
          "state with the mode's period ends on steady sliding), NO no_cycle (the transient decayed or diverged: "
          "the unilateral model escapes past 1 mm here). White circles: the transient settled on a period-2 cycle; "
          "shooting with that cycle's own period finds it stable (`attractor_orbit_stable`).", "",
          f"At {bd.attrs['normal_load']:g} N the period-1 branch's real multiplier crosses -1 at mu = {mu_pd:.4f}; "
          f"past it Newton still converges (M - I is regular at rho = -1) to an orbit the slider does not follow. "
          f"Map points on a period-2 cycle: {n_double}. The run-time check is `period_doubling` "
          f"(a real multiplier below -1 + {FLIP_TOL}) and `instability = flip` on every shooting result.", ""]
    return {"files": files, "counts": counts, "numbers": numbers, "markdown": "\n".join(md)}
