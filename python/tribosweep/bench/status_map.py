"""A status (or other flag) map over two parameters as a Figure: the drawing shared by every failure map."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._codes import STATUS_NAMES
from ..plot import _edges

#: Two-letter codes drawn into failing cells.
STATUS_SHORT: dict[str, str] = {
    "max_steps": "MS",
    "step_too_small": "SS",
    "non_finite": "NF",
    "newton_not_converged": "NC",
    "diverged": "DV",
    "event_chatter": "EC",
    "invalid_input": "II",
    "panic": "PA",
    "not_converged": "NV",
    "not_computed": "--",
}


def _flag_names(da: xr.DataArray) -> dict[int, str]:
    meanings = str(da.attrs.get("flag_meanings", "")).split()
    values = da.attrs.get("flag_values", np.arange(len(meanings)))
    if not meanings:
        meanings, values = list(STATUS_NAMES), np.arange(len(STATUS_NAMES))
    return {int(v): n for v, n in zip(np.atleast_1d(values), meanings)}


def _is_log(v: np.ndarray) -> bool:
    v = np.asarray(v, dtype=np.float64)
    return v.size > 1 and bool(np.all(v > 0)) and v.max() / v.min() >= 30.0


def _axis_label(ds: xr.Dataset, dim: str) -> str:
    a = ds[dim].attrs if dim in ds.coords else {}
    name = a.get("long_name", dim)
    units = a.get("units", "")
    return f"{name} [{units}]" if units and units != "1" else name


def draw_status_map(ds: xr.Dataset, var: str = "status", *, x: str | None = None, y: str | None = None,
                    cost: str | None = "n_rhs", ax=None, title: str | None = None, success: str = "success",
                    cost_range: tuple[float, float] | None = None, annotate: bool | None = None):  # fmt: skip
    """Draw a flag variable over two dimensions: the hook for any failure map.

    Parameters
    ----------
    ds : xarray.Dataset
        Holds ``var`` (integer codes, CF ``flag_values``/``flag_meanings``; default: the status codes)
        over exactly two dimensions (after dropping length-1 ones), and optionally ``cost``.
    var : str
        The flag variable.
    x, y : str, optional
        Dimensions on the axes (default: the last and the first of ``var``'s).
    cost : str or None
        Variable drawn as a log-scaled heat map (e.g. ``n_rhs``); None or missing: the flag categories
        are drawn as colours instead.
    ax : matplotlib Axes, optional
        Draw into it (default: a new Figure).
    title : str, optional
    success : str
        Flag meaning that is not a failure (cells with any other meaning get their code written in).
    cost_range : (float, float), optional
        Colour range of ``cost`` (share it between panels to compare them); default the data's.
    annotate : bool, optional
        Write each cell's cost into it (default: when there are at most 64 cells).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm
    from matplotlib.figure import Figure

    da = ds[var].squeeze(drop=True)
    if da.ndim != 2:
        raise ValueError(f"{var} has dimensions {da.dims} after dropping length-1 ones: draw_status_map needs two")
    dims = list(da.dims)
    x = x or dims[-1]
    y = y or next(d for d in dims if d != x)
    if {x, y} != set(dims):
        raise ValueError(f"x = {x!r}, y = {y!r} must be the two dimensions of {var}: {dims}")
    da = da.transpose(y, x)
    codes = np.asarray(da.values).astype(int)
    xv = np.asarray(ds[x].values, dtype=np.float64)
    yv = np.asarray(ds[y].values, dtype=np.float64)
    xlog, ylog = _is_log(xv), _is_log(yv)
    xe, ye = _edges(xv, xlog), _edges(yv, ylog)
    if ax is None:
        fig = Figure(figsize=(6.0, 4.6), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    names = _flag_names(ds[var])
    ok_codes = [c for c, n in names.items() if n == success]

    if cost is not None and cost in ds:
        cv = np.asarray(ds[cost].squeeze(drop=True).transpose(y, x).values, dtype=np.float64)
        pos = cv[np.isfinite(cv) & (cv > 0)]
        lo, hi = cost_range if cost_range is not None else ((pos.min(), pos.max()) if pos.size else (1.0, 10.0))
        norm = LogNorm(vmin=max(lo, 1.0), vmax=max(hi, lo * 10))
        mesh = ax.pcolormesh(xe, ye, np.where(cv > 0, cv, np.nan), norm=norm, cmap="viridis", shading="flat")
        fig.colorbar(mesh, ax=ax, label=ds[cost].attrs.get("long_name", cost) + " (log)")
        if annotate if annotate is not None else cv.size <= 64:
            for i in range(cv.shape[0]):
                for j in range(cv.shape[1]):
                    if np.isfinite(cv[i, j]):
                        cx = math.sqrt(xe[j] * xe[j + 1]) if xlog else 0.5 * (xe[j] + xe[j + 1])
                        cy = math.sqrt(ye[i] * ye[i + 1]) if ylog else 0.5 * (ye[i] + ye[i + 1])
                        dark = norm(max(cv[i, j], norm.vmin)) < 0.6
                        ax.text(cx, cy, f"{cv[i, j]:.2g}", ha="center", va="bottom", fontsize=6,
                                color="white" if dark else "black")  # fmt: skip
    else:
        present = sorted(set(codes.ravel().tolist()))
        palette = ["#56B4E9", "#D55E00", "#E69F00", "#CC79A7", "#000000", "#999999", "#F0E442", "#009E73",
                   "#0072B2", "#882255", "#44AA99"]  # fmt: skip
        colors = [palette[i % len(palette)] for i in range(len(present))]
        index = np.searchsorted(present, codes)
        cmap = ListedColormap(colors)
        mesh = ax.pcolormesh(xe, ye, index, cmap=cmap, norm=BoundaryNorm(np.arange(len(present) + 1) - 0.5, cmap.N),
                             shading="flat")  # fmt: skip
        from matplotlib.patches import Patch

        ax.legend(handles=[Patch(color=c, label=names.get(p, str(p))) for c, p in zip(colors, present)], fontsize=7,
                  loc="upper left", bbox_to_anchor=(1.01, 1.0))  # fmt: skip
    fails = 0
    for i in range(codes.shape[0]):
        for j in range(codes.shape[1]):
            c = int(codes[i, j])
            if c in ok_codes:
                continue
            fails += 1
            name = names.get(c, str(c))
            cx = math.sqrt(xe[j] * xe[j + 1]) if xlog else 0.5 * (xe[j] + xe[j + 1])
            cy = math.sqrt(ye[i] * ye[i + 1]) if ylog else 0.5 * (ye[i] + ye[i + 1])
            ax.add_patch(_rect(xe[j], ye[i], xe[j + 1] - xe[j], ye[i + 1] - ye[i]))
            ax.text(cx, cy, STATUS_SHORT.get(name, name[:2].upper()), ha="center", va="top", fontsize=8,
                    color="white", fontweight="bold",
                    bbox={"boxstyle": "round,pad=0.15", "facecolor": "#B2182B", "edgecolor": "none"})  # fmt: skip
    if xlog:
        ax.set_xscale("log")
    if ylog:
        ax.set_yscale("log")
    ax.set_xlim(xe[0], xe[-1])
    ax.set_ylim(ye[0], ye[-1])
    ax.set_xlabel(_axis_label(ds, x))
    ax.set_ylabel(_axis_label(ds, y))
    ax.set_title(title if title is not None else f"{var}: {fails} of {codes.size} cells failed", fontsize=9)
    return fig


def _rect(x, y, w, h):
    from matplotlib.patches import Rectangle

    return Rectangle((x, y), w, h, fill=False, hatch="xx", edgecolor="#B2182B", linewidth=0.0)
