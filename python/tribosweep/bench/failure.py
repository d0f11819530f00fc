"""Failure maps: where each integrator fails or struggles, over two parameters at a time.

A failure map is a Dataset with an integer ``status`` variable (CF ``flag_values`` /
``flag_meanings``) over two dimensions, optionally faceted over a third (``method``), and a cost
variable (``n_rhs``) (a third dimension, ``integrator``, gives one panel each). :func:`draw_status_map` draws any such Dataset, so the describing-function
and shooting failure maps can use it too: give it a 2-D Dataset with a flag variable and it draws a
heat map of the cost (or the categories when there is no cost) and marks every cell whose flag is
not "success" with a short code.

Maps computed here (through :func:`tribosweep.ensemble`, every core; the cost measure is ``n_rhs``,
not wall time):

* :func:`stiffness_map` -- the stick-slip scene over (rtol x friction regularisation) for each
  integrator: a small ``eps`` makes sticking stiff, explicit steppers pay ~1/eps steps and run into
  ``max_steps`` (the core's budget is 10^7 steps, not settable from Python).
* :func:`load_mu_map` -- (normal load x mu) for the explicit integrators on the stick-slip and the
  unilateral scenes.
"""

from __future__ import annotations

import os
import pathlib
import sys
from collections.abc import Sequence

import numpy as np
import xarray as xr

from .._codes import STATUS_NAMES, flag_attrs
from .._model import PARAM_LONG_NAMES, PARAM_UNITS, SliderModel
from .._simulate import ensemble
from .status_map import _flag_names, draw_status_map

EXPLICIT_METHODS: tuple[str, ...] = ("dopri5", "dop853")

_COST_VARS = {
    "n_rhs": "right-hand-side evaluations",
    "n_accept": "accepted steps",
    "n_reject": "rejected steps",
}


def _scale(model: SliderModel) -> np.ndarray:
    z_st, _ = model.static_point()
    zs, wt, arm = abs(z_st), model.omega_torsion, model.moment_arm
    return np.array([zs, zs * wt, zs, zs * wt, zs / arm, zs / arm * wt])


def _coord(name: str, values) -> tuple:
    attrs = {"units": PARAM_UNITS.get(name, "1"), "long_name": PARAM_LONG_NAMES.get(name, name)}
    if name == "rtol":
        attrs = {"units": "1", "long_name": "relative tolerance"}
    return (name, np.asarray(values, dtype=np.float64), attrs)


def _grid_run(model: SliderModel, t_end: float, y0, grid: dict[str, np.ndarray], method: str, rtol: float,
              threads: int | None) -> dict:  # fmt: skip
    """One ensemble over the outer product of ``grid`` (2 axes), reshaped to the grid."""
    (a, av), (b, bv) = grid.items()
    A, B = np.meshgrid(av, bv, indexing="ij")
    ds = ensemble(model, t_end, {a: A.ravel(), b: B.ravel()}, y0=y0, method=method, rtol=rtol,
                  atol=rtol * _scale(model), threads=threads)  # fmt: skip
    shape = A.shape
    out = {"status": ds.status.values.reshape(shape)}
    for k in (*_COST_VARS, "min_slip_velocity", "max_gap"):
        out[k] = ds[k].values.reshape(shape)
    return out


def _assemble(results: dict, methods: Sequence[str], dims: tuple[str, str], coords: dict, attrs: dict) -> xr.Dataset:
    """Stack per-method grids into a Dataset over (integrator, *dims)."""
    full = ("integrator", *dims)
    data = {
        "status": (full, np.stack([results[m]["status"] for m in methods]).astype(np.uint8),
                   flag_attrs(STATUS_NAMES, "status of the integration")),
    }  # fmt: skip
    for k, text in _COST_VARS.items():
        data[k] = (full, np.stack([results[m][k] for m in methods]).astype(np.int64), {"units": "1", "long_name": text})
    data["min_slip_velocity"] = (full, np.stack([results[m]["min_slip_velocity"] for m in methods]),
                                 {"units": "m s-1", "long_name": "minimum sliding velocity v_r (<= 0: stick-slip)"})
    data["max_gap"] = (full, np.stack([results[m]["max_gap"] for m in methods]),
                       {"units": "m", "long_name": "largest zc = z_st + z (> 0: contact open)"})
    c = {"integrator": ("integrator", np.asarray(methods, dtype=str), {"long_name": "integration method"})}
    c.update({d: _coord(d, coords[d]) for d in dims})
    return xr.Dataset(data, coords=c, attrs=attrs)


def stiffness_map(*, rtols: Sequence[float], regularizations: Sequence[float],
                  methods: Sequence[str] = ("dopri5", "dop853", "rodas4"), model: SliderModel | None = None,
                  t_end: float = 0.1, z0: float = 1e-6, threads: int | None = None) -> xr.Dataset:  # fmt: skip
    """Status and cost of the stick-slip scene over (friction_regularization x rtol), per integrator.

    Parameters
    ----------
    rtols : sequence of float
        Relative tolerances (atol = rtol x characteristic sizes).
    regularizations : sequence of float, m/s
        ``eps`` of the tanh friction regularisation.
    methods : sequence of str
        Integrators.
    model : SliderModel, optional
        Base model (default: the work-precision stick-slip scene's).
    t_end : float, s
        Simulated time of each point.
    z0 : float, m
        Initial normal disturbance.
    threads : int, optional
        Worker threads (default all cores).

    Returns
    -------
    xarray.Dataset
        ``status``, ``n_rhs``, ``n_accept``, ``n_reject``, ``min_slip_velocity``, ``max_gap`` over
        ``(integrator, friction_regularization, rtol)``.
    """
    from .scenes import STICK_SLIP_MODEL

    model = model or STICK_SLIP_MODEL
    eps = np.asarray(regularizations, dtype=np.float64)
    rt = np.asarray(rtols, dtype=np.float64)
    y0 = np.array([z0, 0, 0, 0, 0, 0])
    results = {}
    for m in methods:
        per_rtol = [_grid_run(model, t_end, y0, {"friction_regularization": eps, "mu": [model.mu]}, m, r, threads)
                    for r in rt]  # fmt: skip
        results[m] = {k: np.stack([p[k][:, 0] for p in per_rtol], axis=1) for k in per_rtol[0]}
    attrs = {"title": "stick-slip scene: integrator status and cost over friction regularisation x rtol",
             "scene": "stick_slip", "t_end": t_end, "z0": z0, "sliding_speed": model.sliding_speed,
             "mu_static": model.values()["mu_static"], "stribeck_velocity": model.stribeck_velocity}  # fmt: skip
    return _assemble(results, list(methods), ("friction_regularization", "rtol"),
                     {"friction_regularization": eps, "rtol": rt}, attrs)  # fmt: skip


def load_mu_map(model: SliderModel, *, loads: Sequence[float], mus: Sequence[float], t_end: float, z0: float,
                rtol: float = 1e-6, methods: Sequence[str] = EXPLICIT_METHODS, threads: int | None = None,
                scene: str = "") -> xr.Dataset:  # fmt: skip
    """Status and cost over (normal_load x mu) for each integrator at one ``rtol``.

    Returns
    -------
    xarray.Dataset
        As :func:`stiffness_map`, over ``(integrator, normal_load, mu)``.
    """
    loads = np.asarray(loads, dtype=np.float64)
    mus = np.asarray(mus, dtype=np.float64)
    y0 = np.array([z0, 0, 0, 0, 0, 0])
    results = {m: _grid_run(model, t_end, y0, {"normal_load": loads, "mu": mus}, m, rtol, threads) for m in methods}
    attrs = {"title": f"{scene}: integrator status and cost over normal load x mu (rtol {rtol:g})", "scene": scene,
             "t_end": t_end, "z0": z0, "rtol": rtol, "contact": model.contact, "friction_law": model.friction_law}
    return _assemble(results, list(methods), ("normal_load", "mu"), {"normal_load": loads, "mu": mus}, attrs)


# --- drawing ---------------------------------------------------------------------------------------


def draw_failure_maps(ds: xr.Dataset, *, facet: str = "integrator", var: str = "status", cost: str | None = "n_rhs",
                      x: str | None = None, y: str | None = None, suptitle: str | None = None):  # fmt: skip
    """One :func:`draw_status_map` panel per value of ``facet``; returns the Figure."""
    from matplotlib.figure import Figure

    values = ds[facet].values if facet in ds.dims else [None]
    cost_range = None
    if cost is not None and cost in ds:
        cv = np.asarray(ds[cost].values, dtype=np.float64)
        pos = cv[np.isfinite(cv) & (cv > 0)]
        cost_range = (float(pos.min()), float(pos.max())) if pos.size else None  # one colour scale for all panels
    fig = Figure(figsize=(5.2 * len(values), 4.4), layout="constrained")
    axes = fig.subplots(1, len(values), squeeze=False)[0]
    for ax, v in zip(axes, values):
        sub = ds.sel({facet: v}) if v is not None else ds
        codes = np.asarray(sub[var].values)
        names = _flag_names(ds[var])
        bad = {names.get(int(c), str(c)): int(n) for c, n in zip(*np.unique(codes, return_counts=True))
               if names.get(int(c)) != "success"}  # fmt: skip
        extra = ", ".join(f"{k} {n}" for k, n in bad.items()) or "no failure"
        draw_status_map(sub, var, x=x, y=y, cost=cost, ax=ax, title=f"{v}: {extra}" if v is not None else extra,
                        cost_range=cost_range)  # fmt: skip
    fig.suptitle(suptitle or ds.attrs.get("title", ""), fontsize=10)
    return fig


# --- the maps of `tribosweep bench` ----------------------------------------------------------------


def _counts(ds: xr.Dataset) -> dict:
    out = {}
    for m in ds.integrator.values:
        codes = ds.status.sel(integrator=m).values.ravel()
        out[str(m)] = {
            "status": {STATUS_NAMES[int(c)]: int(n) for c, n in zip(*np.unique(codes, return_counts=True))},
            "max_n_rhs": int(ds.n_rhs.sel(integrator=m).max()),
            "median_n_rhs": float(np.median(ds.n_rhs.sel(integrator=m).values)),
        }
    return out


def _failing_cells(ds: xr.Dataset) -> list[str]:
    """``"<integrator>: <status> at dim=value, dim=value"`` for every cell with a non-zero status."""
    out = []
    st = ds.status
    for idx in zip(*np.nonzero(st.values)):
        where = {d: ds[d].values[i] for d, i in zip(st.dims, idx)}
        name = STATUS_NAMES[int(st.values[idx])]
        coords = ", ".join(f"{d} {v:.3g}" for d, v in where.items() if d != "integrator")
        out.append(f"{where.get('integrator', '')}: {name} at {coords}")
    return out


def failure_maps(out_dir: os.PathLike, *, quick: bool = False, threads: int | None = None,
                 progress: bool = True) -> dict:  # fmt: skip
    """Compute the bench's failure maps, write ``failure_*.png`` and ``.nc`` into ``out_dir``.

    Returns
    -------
    dict
        ``files`` (name -> path), ``summary`` (status counts and rhs per map and method), ``markdown``.
    """
    from .scenes import STICK_SLIP_MODEL

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if quick:
        eps, rtols = [1e-3, 1e-4, 1e-5], [1e-3, 1e-6, 1e-9]
        loads, mus_ss, mus_uni = [20.0, 60.0, 100.0, 150.0], [0.2, 0.23, 0.26, 0.3], [0.2, 0.25, 0.3, 0.35]
    else:
        # eps 1e-8 drives the explicit steppers into the core's 10^7-step budget (max_steps).
        eps, rtols = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8], [1e-3, 1e-5, 1e-7, 1e-9, 1e-11]
        loads = list(np.linspace(20.0, 160.0, 8))
        mus_ss, mus_uni = list(np.linspace(0.19, 0.30, 8)), list(np.linspace(0.15, 0.40, 8))
    maps = {}
    if progress:
        print(f"  stiffness map: {len(eps)} eps x {len(rtols)} rtol x 3 methods", file=sys.stderr, flush=True)
    maps["failure_stick_slip_eps_rtol"] = stiffness_map(rtols=rtols, regularizations=eps, threads=threads)
    if progress:
        print(f"  load x mu maps: {len(loads)} x {len(mus_ss)}, explicit methods", file=sys.stderr, flush=True)
    maps["failure_stick_slip_load_mu"] = load_mu_map(STICK_SLIP_MODEL, loads=loads, mus=mus_ss, t_end=0.1, z0=1e-6,
                                                     threads=threads, scene="stick_slip")  # fmt: skip
    maps["failure_unilateral_load_mu"] = load_mu_map(SliderModel(contact="unilateral"), loads=loads, mus=mus_uni,
                                                     t_end=0.2, z0=30e-6, threads=threads, scene="unilateral")
    files, summary, md = {}, {}, ["## Failure maps", ""]
    md.append("Status of every grid point (red code: MS max_steps, SS step_too_small, NF non_finite, DV diverged, "
              "EC event_chatter) over a heat map of its right-hand-side evaluations; one point per cell, all "
              "cores. The core's step budget (10^7) is not settable from Python, so an explicit stepper on a "
              "very stiff point shows up as a cost explosion before it shows up as max_steps.")  # fmt: skip
    md.append("")
    for name, ds in maps.items():
        png, nc = out / f"{name}.png", out / f"{name}.nc"
        fig = draw_failure_maps(ds)
        fig.savefig(png, dpi=100)
        ds.to_netcdf(nc)
        files[name] = png
        files[name + "_nc"] = nc
        summary[name] = _counts(ds)
        md.append(f"### `{name}`: {ds.attrs['title']}")
        md.append("")
        md.append(f"![{name}]({png.name})")
        md.append("")
        md.append("| method | statuses | median rhs | max rhs |")
        md.append("|---|---|---|---|")
        for m, c in summary[name].items():
            st = ", ".join(f"{k} {v}" for k, v in c["status"].items())
            md.append(f"| {m} | {st} | {c['median_n_rhs']:.3g} | {c['max_n_rhs']:.3g} |")
        bad = _failing_cells(ds)
        if bad:
            md.append("")
            md.append("Failing cells: " + "; ".join(bad[:12]) + ("; ..." if len(bad) > 12 else "") + ".")
        if "diverged" in " ".join(bad):
            md.append("`diverged` is the model leaving its validity (|z| past the 1 mm escape limit), not an "
                      "integrator failure: e.g. the unilateral model at 20 N and mu 0.35 bounces to centimetres.")
        if "friction_regularization" in ds.dims:
            # From the most accurate run of each eps: the stiff-capable method at the tightest rtol.
            best = "rodas4" if "rodas4" in ds.integrator.values else str(ds.integrator.values[0])
            sub = ds.sel(integrator=best).isel(rtol=int(np.argmin(ds.rtol.values)))
            sticks = ", ".join(f"{e:.0e}: {v:+.2g}{'' if s == 0 else ' (' + STATUS_NAMES[int(s)] + ')'}"
                               for e, v, s in zip(ds.friction_regularization.values, sub.min_slip_velocity.values,
                                                  sub.status.values))  # fmt: skip
            md.append("")
            md.append(f"Minimum sliding velocity per eps ({best}, rtol {float(sub.rtol):.0e}; m/s, <= 0 means "
                      f"sticking): {sticks}.")  # fmt: skip
        md.append("")
    # The describing function's own failure maps (validity against shooting orbits, Newton basin).
    from .df_failure import tidf_failure_maps

    if progress:
        print("  describing-function maps: validity over load x arm, Newton basin", file=sys.stderr, flush=True)
    dfm = tidf_failure_maps(out, quick=quick, threads=threads)
    files.update(dfm["files"])
    summary.update(dfm["counts"])
    md.append(dfm["markdown"])
    # Shooting near a period doubling (unilateral contact, high friction).
    from .pd_failure import pd_failure_maps

    if progress:
        print("  shooting near a period doubling: load x mu map, bifurcation diagram", file=sys.stderr, flush=True)
    pdm = pd_failure_maps(out, quick=quick, threads=threads)
    files.update(pdm["files"])
    summary.update(pdm["counts"])
    summary["period_doubling"] = pdm["numbers"]
    md.append(pdm["markdown"])
    return {"files": files, "summary": summary, "markdown": "\n".join(md)}
