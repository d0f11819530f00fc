"""Figures of sweep results. Every function returns a :class:`matplotlib.figure.Figure`.

matplotlib is optional (``pip install 'tribosweep[plot]'``) and imported only inside these
functions. Figures are built without ``pyplot`` (no global state, no GUI backend, never
``plt.show()``); ``fig.savefig`` renders them with the Agg canvas.
"""

from __future__ import annotations

import os
import textwrap

import numpy as np
import xarray as xr

from ._codes import REGIME_NAMES

#: Colour of each regime (colour-blind-safe Okabe-Ito palette plus greys).
REGIME_COLORS: dict[str, str] = {
    "steady_sliding": "#56B4E9",
    "self_excited": "#D55E00",
    "contact_loss": "#E69F00",
    "stick_slip": "#CC79A7",
    "diverged": "#000000",
    "failed": "#999999",
    "unstable_undetermined": "#F0E442",
    "irregular": "#009E73",
    "crashed": "#882255",
}
_PREFERRED = ("normal_load", "arm_length", "sliding_speed")


def _matplotlib():
    try:
        from matplotlib.figure import Figure
        from matplotlib.patches import Patch
    except ImportError as e:  # pragma: no cover - exercised only without matplotlib
        raise ImportError(
            "tribosweep.plot needs matplotlib: install it with pip install 'tribosweep[plot]' (or matplotlib)"
        ) from e
    return Figure, Patch


#: Census coexistence drawn over the regime colours: ``bistable`` code -> (key, hatch, legend label).
_COEXISTING = {
    1: ("coexisting", "//", "another attractor coexists\n(attractor census)"),
}


def _edges(c: np.ndarray, log: bool = False) -> np.ndarray:
    """Cell edges around centres ``c`` (midpoints, of the logarithms with ``log``; a single centre
    gets a +-5 % cell)."""
    c = np.asarray(c, dtype=np.float64)
    if log:
        return 10.0 ** _edges(np.log10(c))
    if c.size == 1:
        half = 0.05 * abs(c[0]) or 0.5
        return np.array([c[0] - half, c[0] + half])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])


def _label(ds: xr.Dataset, dim: str) -> str:
    a = ds[dim].attrs
    name = a.get("long_name", dim)
    return f"{name} [{a['units']}]" if "units" in a else name


def _choose_dims(ds: xr.Dataset, x, y, facet) -> tuple[str, str, str | None, list[str]]:
    dims = list(ds.regime.dims)
    order = [d for d in _PREFERRED if d in dims] + [d for d in dims if d not in _PREFERRED]
    given = [d for d in (x, y, facet) if d is not None]
    for d in given:
        if d not in dims:
            raise ValueError(f"dimension {d!r} is not in the sweep: its dimensions are {tuple(dims)}")
    if len(set(given)) != len(given):
        raise ValueError(f"x, y and facet must be different dimensions, got {given}")
    free = [d for d in order if d not in given]
    # Swept dimensions first, in the preferred order, then the singleton ones.
    free = [d for d in free if ds.sizes[d] > 1] + [d for d in free if ds.sizes[d] == 1]
    x = x or free.pop(0)
    y = y or free.pop(0)
    if facet is None and free:  # the next swept dimension, else a singleton one
        facet = free.pop(0)
    rest = [d for d in free if d != facet]
    return x, y, facet, rest


#: How a Hopf curve is drawn, by criticality (l1 > 0: subcritical, a saddle cycle surrounds stable
#: sliding and the two coexist; l1 < 0: supercritical, a small stable cycle is born).
_HOPF_STYLE: dict[str, tuple[str, str]] = {
    "hopf_subcritical": ("-", "Hopf curve, subcritical\n(l1 > 0: a saddle cycle)"),
    "hopf_supercritical": (":", "Hopf curve, supercritical\n(l1 < 0)"),
}


def _draw_hopf(ax, ds: xr.Dataset, x: str, y: str) -> set[str]:
    """Draw the stored Hopf curves (one line per curve and criticality run); return legend keys."""
    crit_names = str(ds.hopf_criticality.attrs.get("flag_meanings", "")).split()
    crit = np.asarray(ds.hopf_criticality.values).astype(int)
    curve = np.asarray(ds.hopf_curve_index.values)
    px, py = ds[f"hopf_{x}"].values, ds[f"hopf_{y}"].values
    keys = set()
    for c in np.unique(curve):
        idx = np.flatnonzero(curve == c)
        # Split where criticality changes (a Bautin point), drawing each run in its style.
        runs = np.split(idx, np.flatnonzero(np.diff(crit[idx]) != 0) + 1)
        for k, r in enumerate(runs):
            name = crit_names[crit[r[0]]] if crit[r[0]] < len(crit_names) else "undetermined"
            # Only a proven l1 < 0 is drawn supercritical; degenerate or undetermined stretches are
            # drawn as the conservative case (coexistence possible).
            key = "hopf_supercritical" if name == "supercritical" else "hopf_subcritical"
            if k + 1 < len(runs):
                r = np.r_[r, runs[k + 1][0]]  # join the run to the next at their shared point
            ax.plot(px[r], py[r], color="k", lw=1.4, ls=_HOPF_STYLE[key][0])
            keys.add(key)
    return keys


#: How the fold and grazing curves of the cycles born at a Hopf curve are drawn, in drawing order:
#: line keywords and legend label. The fold's markers are the arm lengths where its points were located.
#: The grazing curve is a white band edged in black and the fold a black dashed line, so that a
#: fold lying on the grazing curve (a grazing where the branch turns back) shows as both.
_CURVE_STYLE: dict[str, tuple[dict, str]] = {
    "grazing": ({"color": "white", "lw": 2.4},
                "grazing: the saddle cycle\nfirst leaves the disk"),
    "fold": ({"color": "k", "lw": 1.1, "ls": (0, (3, 2)), "marker": "s", "ms": 2.5},
             "fold of cycles: the\nsaddle cycle ends"),
    "stick": ({"color": "#6a3d9a", "lw": 1.6, "ls": "-.", "marker": "^", "ms": 3.5},
              "stick: the cycle from the\nHopf curve first sticks"),
}  # fmt: skip


def _curve_line(kind: str) -> dict:
    from matplotlib import patheffects

    style = dict(_CURVE_STYLE[kind][0])
    if kind == "grazing":
        style["path_effects"] = [patheffects.Stroke(linewidth=4.0, foreground="k"), patheffects.Normal()]
    elif kind == "stick":
        # A white halo: the line crosses the regime map's stick-slip cells, of a similar hue.
        style["path_effects"] = [patheffects.Stroke(linewidth=3.4, foreground="white"), patheffects.Normal()]
    return style


def _draw_curves(ax, ds: xr.Dataset, x: str, y: str) -> set[str]:
    """Draw the stored fold, grazing and stick curves (one polyline per Hopf curve they start from); return legend keys."""
    keys = set()
    for kind in _CURVE_STYLE:
        if f"{kind}_{x}" not in ds or f"{kind}_{y}" not in ds:
            continue
        idx = np.asarray(ds[f"{kind}_curve_index"].values)
        px, py = ds[f"{kind}_{x}"].values, ds[f"{kind}_{y}"].values
        for c in np.unique(idx):
            on = idx == c
            ax.plot(px[on], py[on], zorder=2.5, **_curve_line(kind))
            keys.add(kind)
    return keys


def _curve_handles(present: set[str]) -> list:
    """Legend entries of the fold, grazing and stick curves drawn."""
    from matplotlib.lines import Line2D

    return [Line2D([], [], label=label, **_curve_line(kind))
            for kind, (_, label) in _CURVE_STYLE.items() if kind in present]  # fmt: skip


def regime_map(ds: xr.Dataset, *, x: str | None = None, y: str | None = None, facet: str | None = None,
               ncols: int = 4, mark_points: bool = False):  # fmt: skip
    """Regime map of a sweep over two dimensions, one panel per value of a third.

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`tribosweep.sweep` result (needs ``regime``).
    x, y : str, optional
        Dimensions on the axes (default: the swept dimensions in the order normal load, arm
        length, sliding speed, extras).
    facet : str, optional
        Dimension with one panel per value (default: the next swept one).
    ncols : int
        Panels per row: a longer facet dimension wraps into rows, and every value gets its panel.
    mark_points : bool
        Mark each computed grid point with a dot (the cells are drawn around the points).

    Returns
    -------
    matplotlib.figure.Figure
        Other dimensions are taken at their first value (said in the title). The contact law's
        identification range (22-93 N) is marked when ``x`` or ``y`` is the normal load.

    Examples
    --------
    >>> import tribosweep as ts
    >>> from tribosweep.plot import regime_map
    >>> ds = ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], strategy="linear", progress=False)
    >>> fig = regime_map(ds)
    >>> len(fig.axes)
    1
    """
    Figure, Patch = _matplotlib()
    from matplotlib.colors import BoundaryNorm, ListedColormap

    x, y, facet, rest = _choose_dims(ds, x, y, facet)
    fixed = [f"{d} = {ds[d].values[0]:g} {ds[d].attrs.get('units', '')}".strip() for d in rest]
    fvals = [None] if facet is None else list(range(ds.sizes[facet]))
    n = len(fvals)
    nc = max(1, min(int(ncols), n))
    nr = -(-n // nc)
    fig = Figure(figsize=(3.6 * nc + 1.8, 3.6 * nr), layout="constrained")
    grid = fig.subplots(nr, nc, squeeze=False, sharex=True, sharey=True).ravel()
    for ax in grid[n:]:
        ax.set_visible(False)
    axes = grid[:n]
    for k, ax in enumerate(axes):  # the lowest panel of each column carries the x axis, the first of a row the y
        if k + nc >= n:
            ax.xaxis.set_tick_params(labelbottom=True)
            ax.set_xlabel(_label(ds, x))
        if k % nc == 0:
            ax.set_ylabel(_label(ds, y))
    cmap = ListedColormap([REGIME_COLORS[r] for r in REGIME_NAMES])
    norm = BoundaryNorm(np.arange(len(REGIME_NAMES) + 1) - 0.5, cmap.N)
    present = set()
    xe, ye = _edges(ds[x].values), _edges(ds[y].values)

    def panel(name: str, fi) -> np.ndarray:
        """Variable ``name`` on panel ``fi``: ``(y, x)`` values at the first value of the other dims."""
        v = ds[name].isel({d: 0 for d in rest})
        return (v if fi is None else v.isel({facet: fi})).transpose(y, x).values

    for ax, fi in zip(axes, fvals):
        z = panel("regime", fi)
        present.update(np.unique(z).tolist())
        ax.pcolormesh(xe, ye, z, cmap=cmap, norm=norm, shading="flat")
        if mark_points:
            present.add(_mark_points(ax, ds, x, y))
        if "bistable" in ds:
            # Coexisting attractors: hatched, since the regime then depends on the initial
            # disturbance (docs/model.md §6: the seed point is such a case; past the stability
            # boundary, a second cycle or irregular motion beside the transient's).
            b = panel("bistable", fi)
            for code, (key, hatch, _) in _COEXISTING.items():
                from matplotlib.patches import Rectangle

                for j, i in zip(*np.nonzero(b == code)):
                    present.add(key)
                    ax.add_patch(Rectangle((xe[i], ye[j]), xe[i + 1] - xe[i], ye[j + 1] - ye[j], fill=False,
                                           hatch=hatch, edgecolor="k", lw=0.0))  # fmt: skip
        if {"regime_fraction", "growth_rate"} <= set(ds.data_vars):
            # Unstable points whose label (one transient's motion) most census disturbances do not
            # reach: a ring in the cell's upper right corner.
            weak = (panel("regime_fraction", fi) < WEAK_LABEL) & (panel("growth_rate", fi) > 0)
            if weak.any():
                present.add("weak_label")
                jj, ii = np.nonzero(weak)
                ax.scatter(xe[ii] + 0.8 * (xe[ii + 1] - xe[ii]), ye[jj] + 0.78 * (ye[jj + 1] - ye[jj]), s=20,
                           marker="o", facecolors="w", edgecolors="k", linewidths=0.6, zorder=4)  # fmt: skip
        if "cycle_period_ratio" in ds:
            # Cycles of several mode periods (past a period doubling, or subharmonic bouncing).
            r = panel("cycle_period_ratio", fi)
            k = np.where(np.isfinite(r), np.rint(r), 0)
            multi = k >= 2
            if multi.any():
                if multi.shape[1] <= MAX_LABELLED_COLUMNS:
                    present.add("multi_period")
                    for j, i in zip(*np.nonzero(multi)):
                        ax.text(0.5 * (xe[i] + xe[i + 1]), 0.5 * (ye[j] + ye[j + 1]), f"{int(k[j, i])}T",
                                ha="center", va="center", fontsize=6, color="k")  # fmt: skip
                else:  # too narrow a cell for a label: a mark (labels in neighbouring cells would run together)
                    present.add("multi_period_mark")
                    jj, ii = np.nonzero(multi)
                    ax.scatter(0.5 * (xe[ii] + xe[ii + 1]), 0.5 * (ye[jj] + ye[jj + 1]), s=5, marker="x", c="k",
                               linewidths=0.5, zorder=3)  # fmt: skip
        if fi is not None:
            ax.set_title(f"{facet} = {ds[facet].values[fi]:.4g} {ds[facet].attrs.get('units', '')}".strip(), fontsize=9)
        if "hopf_normal_load" in ds and {x, y} == {"normal_load", "arm_length"}:
            present.update(_draw_hopf(ax, ds, x, y))
        present.update(_draw_curves(ax, ds, x, y))
        for dim, line in ((x, ax.axvline), (y, ax.axhline)):
            if dim == "normal_load":
                edges = _edges(ds[dim].values)
                for bound in (22.0, 93.0):  # only inside the map: a bound outside would widen the axis
                    if edges.min() <= bound <= edges.max():
                        line(bound, color="k", lw=0.6, ls="--")
                        present.add("law_range")
    handles = [Patch(facecolor=REGIME_COLORS[r], edgecolor="k", lw=0.3, label=r.replace("_", " "))
               for i, r in enumerate(REGIME_NAMES) if i in present]  # fmt: skip
    for key, hatch, label in _COEXISTING.values():
        if key in present:
            handles.append(Patch(facecolor="none", edgecolor="k", hatch=hatch, lw=0.3, label=label))
    if "law_range" in present:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], color="k", lw=0.6, ls="--", label="contact law identified\n(22-93 N)"))
    for key, (style, label) in _HOPF_STYLE.items():
        if key in present:
            from matplotlib.lines import Line2D

            handles.append(Line2D([], [], color="k", lw=1.4, ls=style, label=label))
    handles += _curve_handles(present)
    if "grid_points" in present:
        handles.append(_points_handle())
    if "multi_period_mark" in present:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], ls="none", marker="x", ms=3, mec="k", mew=0.6,
                              label="a cycle of 2 or more mode periods\n(period doubling, subharmonic)"))
    if "weak_label" in present:
        from matplotlib.lines import Line2D

        handles.append(Line2D([], [], ls="none", marker="o", ms=4, mfc="w", mec="k", mew=0.6,
                              label="sliding unstable: fewer than half\nthe census disturbances reach\nthis motion"))
    if "multi_period" in present:
        handles.append(Patch(facecolor="none", edgecolor="none", label="nT: a cycle of n mode periods\n(period doubling, subharmonic)"))
    fig.legend(handles=handles, loc="outside right center", fontsize=8, frameon=False)
    title = f"regime ({ds.attrs.get('strategy', ds.attrs.get('method', '?'))})"
    if fixed:
        title += "; " + ", ".join(fixed)
    fig.suptitle(title, fontsize=10)
    return fig


#: Census fraction below which an unstable point's label (its transient's motion) is marked on the
#: regime map as one that most disturbances do not reach (``regime_fraction``).
WEAK_LABEL: float = 0.5

#: Widest grid (cells along x per panel) whose multi-period cycles are labelled "nT" in the cell;
#: a wider one gets a mark per cell (a 3.6-inch panel leaves under 0.2 inch per cell past this).
MAX_LABELLED_COLUMNS: int = 16


def _mark_points(ax, ds: xr.Dataset, x: str, y: str) -> str:
    """A dot at every computed grid point (white with a dark edge: visible on every fill colour)."""
    gx, gy = np.meshgrid(ds[x].values, ds[y].values)
    size = 6.0 if gx.size <= 400 else 2.0
    ax.scatter(gx.ravel(), gy.ravel(), s=size, c="w", edgecolors="k", linewidths=0.3, zorder=3)
    return "grid_points"


def _points_handle():
    from matplotlib.lines import Line2D

    return Line2D([], [], ls="none", marker="o", ms=3, mfc="w", mec="k", mew=0.4, label="computed point")


#: Colours of a categorical variable's values (Okabe-Ito, colour-blind safe), in flag order.
_CATEGORY_COLORS = ("#56B4E9", "#E69F00", "#009E73", "#F0E442", "#0072B2", "#D55E00", "#CC79A7", "#000000",
                    "#999999", "#882255", "#44AA99")  # fmt: skip


def variable_map(ds: xr.Dataset, var: str, *, x: str | None = None, y: str | None = None, facet: str | None = None,
                 ncols: int = 4, mark_points: bool = False):  # fmt: skip
    """Map of any per-point variable of a sweep over two dimensions, one panel per value of a third.

    A categorical variable (CF ``flag_values``/``flag_meanings``) gets one colour per value and a
    legend of the names present; a continuous one a colour bar labelled with its long name and
    units (logarithmic where its finite values are positive and span more than three decades).
    Panels wrap into rows of ``ncols``; every facet value gets its panel. A variable with a
    trailing dimension (``basin_fraction`` over ``attractor``) is drawn at its first value unless
    that dimension is the facet. ``mark_points=True`` marks each computed grid point with a dot.

    Examples
    --------
    >>> import tribosweep as ts
    >>> from tribosweep.plot import variable_map
    >>> ds = ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], strategy="linear", progress=False)
    >>> fig = variable_map(ds, "growth_rate")
    >>> fig.axes[-1].get_ylabel().replace("\\n", " ")
    'largest real part of the eigenvalues of steady sliding (> 0: unstable) [s-1]'
    """
    Figure, Patch = _matplotlib()
    from matplotlib.colors import BoundaryNorm, ListedColormap, LogNorm, Normalize

    if var not in ds:
        names = sorted(v for v in ds.data_vars if set(ds.regime.dims) <= set(ds[v].dims))
        raise ValueError(f"var = {var!r} is not in the sweep: its per-point variables are {names}")
    da = ds[var]
    extra = [d for d in da.dims if d not in ds.regime.dims]
    if extra and facet is None:
        facet = extra[0]  # one panel per attractor (say): the sweep's other dimensions at their first value
    if facet in extra:
        x, y, _, rest = _choose_dims(ds, x, y, None)
        rest = [d for d in ds.regime.dims if d not in (x, y)]
    else:
        x, y, facet, rest = _choose_dims(ds, x, y, facet)
    da = da.isel({d: 0 for d in rest + [d for d in extra if d != facet]})
    fvals = [None] if facet is None else list(range(ds.sizes[facet]))
    n = len(fvals)
    nc = max(1, min(ncols, n))
    nr = -(-n // nc)
    fig = Figure(figsize=(3.4 * nc + 2.2, 3.2 * nr + 0.6), layout="constrained")
    axes = fig.subplots(nr, nc, squeeze=False, sharex=True, sharey=True).ravel()
    for ax in axes[n:]:
        ax.set_visible(False)
    for k in range(max(0, n - nc), n):  # the lowest panel of each column shows its x ticks
        axes[k].xaxis.set_tick_params(labelbottom=True)
    flags = "flag_values" in da.attrs and "flag_meanings" in da.attrs
    values = np.asarray(da.values, dtype=np.float64)
    if flags:
        codes = np.atleast_1d(da.attrs["flag_values"]).astype(np.float64).tolist()
        names = str(da.attrs["flag_meanings"]).split()
        cmap = ListedColormap([_CATEGORY_COLORS[i % len(_CATEGORY_COLORS)] for i in range(len(codes))])
        index = np.full(values.shape, np.nan)
        for i, c in enumerate(codes):
            index[values == c] = i
        values, norm = index, BoundaryNorm(np.arange(len(codes) + 1) - 0.5, cmap.N)
    else:
        finite = values[np.isfinite(values)]
        log = finite.size and finite.min() > 0 and finite.max() / finite.min() > 1e3
        norm = LogNorm(finite.min(), finite.max()) if log else Normalize(*(
            (finite.min(), finite.max()) if finite.size else (0.0, 1.0)))  # fmt: skip
        cmap = "viridis"
    da = da.copy(data=values)
    mesh = None
    for k, (ax, fi) in enumerate(zip(axes, fvals)):
        sub = da if fi is None else da.isel({facet: fi})
        mesh = ax.pcolormesh(_edges(ds[x].values), _edges(ds[y].values), sub.transpose(y, x).values, cmap=cmap,
                             norm=norm, shading="flat")  # fmt: skip
        if mark_points:
            _mark_points(ax, ds, x, y)
        if fi is not None:
            coord = ds[facet].values[fi]
            label = f"{coord:.4g}" if np.issubdtype(np.asarray(coord).dtype, np.number) else str(coord)
            if facet == "attractor" and "flag_meanings" in ds[facet].attrs:
                label = str(ds[facet].attrs["flag_meanings"]).split()[fi]
            ax.set_title(f"{facet} = {label} {ds[facet].attrs.get('units', '')}".strip(), fontsize=9)
        if k // nc == nr - 1 or k + nc >= n:
            ax.set_xlabel(_label(ds, x))
        if k % nc == 0:
            ax.set_ylabel(_label(ds, y))
    long = da.attrs.get("long_name", var)
    unit = da.attrs.get("units")
    if flags:
        present = sorted({int(v) for v in np.unique(values[np.isfinite(values)])})
        handles = [Patch(facecolor=cmap(i), edgecolor="k", lw=0.3, label=names[i].replace("_", " ")) for i in present]
        if mark_points:
            handles.append(_points_handle())
        fig.legend(handles=handles, loc="outside right center", fontsize=8, frameon=False, title=var)
    else:
        bar = fig.colorbar(mesh, ax=axes[:n].tolist(), shrink=0.9)
        # Wrapped to the bar's height (about 42 characters of 8 pt per 3.2-inch row), never cut off.
        text = f"{long} [{unit}]" if unit else long
        bar.ax.set_ylabel(textwrap.fill(text, 42 * nr, break_long_words=False), fontsize=8)
        if mark_points:
            fig.legend(handles=[_points_handle()], loc="outside lower center", fontsize=8, frameon=False)
    fixed = [f"{d} = {ds[d].values[0]:.4g} {ds[d].attrs.get('units', '')}".strip() for d in rest if ds.sizes[d] > 1]
    blank = "; white: no value there" if np.isnan(values).any() else ""
    fig.suptitle(var + ("; " + ", ".join(fixed) if fixed else "") + blank, fontsize=10)
    return fig


def save_regime_map(ds_or_path, path: str | os.PathLike, **kwargs) -> None:
    """Write :func:`regime_map` of a Dataset (or of a sweep file) to an image file (PNG, PDF, SVG).

    Parameters
    ----------
    ds_or_path : xarray.Dataset or path-like
        A sweep result or its netCDF file.
    path : path-like
        Image file; the format follows its extension.
    **kwargs
        Passed to :func:`regime_map`, or with ``var`` (any per-point variable but ``regime``) to
        :func:`variable_map`.
    """
    var = kwargs.pop("var", None)

    def draw(ds):
        return regime_map(ds, **kwargs) if var in (None, "regime") else variable_map(ds, var, **kwargs)

    if isinstance(ds_or_path, xr.Dataset):
        fig = draw(ds_or_path)
    else:
        with xr.open_dataset(ds_or_path, engine="netcdf4") as ds:
            fig = draw(ds)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=120)


def boundary_map(ds: xr.Dataset, *, growth: xr.DataArray | None = None, title: str | None = None):
    """The stability boundaries of a normal load x arm length box, as :func:`tribosweep.boundary_curves` returns them.

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`tribosweep.boundary_curves` Dataset (or a sweep holding its variables).
    growth : xarray.DataArray, optional
        Largest growth rate of steady sliding on dims ``normal_load`` and ``arm_length``: shaded
        stable or unstable under the curves.
    title : str, optional
        The axes' title (default: the contact law).

    Returns
    -------
    matplotlib.figure.Figure
        The Hopf curves (by criticality), the fold, grazing and stick curves, the contact law's
        identified load range, and a legend of what is drawn.
    """
    Figure, Patch = _matplotlib()
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D

    x, y = "normal_load", "arm_length"
    fig = Figure(figsize=(6.6, 3.8), layout="constrained")
    ax = fig.add_subplot()
    handles = []
    if growth is not None:
        g = growth.transpose(y, x)
        unstable = (g.values > 0).astype(float)
        cmap = ListedColormap([REGIME_COLORS["steady_sliding"], REGIME_COLORS["self_excited"]])
        ax.pcolormesh(_edges(g[x].values), _edges(g[y].values), unstable, cmap=cmap, vmin=0, vmax=1, alpha=0.35,
                      shading="flat", linewidth=0, rasterized=True)  # fmt: skip
        for code, text in ((0, "steady sliding stable\n(linear)"), (1, "steady sliding unstable\n(growth rate > 0)")):
            if (unstable == code).any():
                handles.append(Patch(facecolor=cmap(code), alpha=0.35, edgecolor="k", lw=0.3, label=text))
    present = set()
    if "hopf_normal_load" in ds:
        present |= _draw_hopf(ax, ds, x, y)
    present |= _draw_curves(ax, ds, x, y)
    lo, hi = ds.attrs.get("boundary_normal_load_low"), ds.attrs.get("boundary_normal_load_high")
    if lo is not None:
        ax.set_xlim(lo, hi)
        ax.set_ylim(ds.attrs["boundary_arm_length_low"], ds.attrs["boundary_arm_length_high"])
    for bound in (22.0, 93.0):
        ax.axvline(bound, color="k", lw=0.6, ls="--")
    handles.append(Line2D([], [], color="k", lw=0.6, ls="--", label="contact law identified\n(22-93 N)"))
    handles += [Line2D([], [], color="k", lw=1.4, ls=style, label=label)
                for key, (style, label) in _HOPF_STYLE.items() if key in present]  # fmt: skip
    handles += _curve_handles(present)
    ax.set_xlabel("normal load F_st [N]")
    ax.set_ylabel("clamped arm length l [m]")
    ax.set_title(title or f"stability boundaries ({ds.attrs.get('boundary_contact', '?')} contact)", fontsize=10)
    fig.legend(handles=handles, loc="outside right center", fontsize=8, frameon=False)
    return fig
