"""Where the describing function fails: validity over (load, arm length), Newton from poor guesses.

Two maps, drawn with :func:`tribosweep._failure.draw_status_map`:

``tidf_validity``
    Over normal load x arm length (bilateral law, the report's model): at each point the physical
    describing-function root is checked against the shooting orbit of the full ODE. Codes: ``valid``
    (contact closed on the root's waveform and its A1 within ``ACCURACY`` of the orbit's),
    ``no_root`` (no root near the torsion mode: nothing predicted), ``contact_opens`` (the waveform
    leaves the disk: the bilateral law and the DF built on it are outside their validity),
    ``inaccurate`` (|A1 error| > ``ACCURACY``: far from harmonic), ``orbit_not_found`` (shooting from
    the root failed: the prediction is not confirmed).
``newton_basin``
    Warm-started Newton from guesses around the seed root, offset in frequency and scaled in
    amplitude: ``converged`` (to the root), ``other_root`` (to another root), ``not_converged``.
"""

from __future__ import annotations

import os
import pathlib

import numpy as np
import xarray as xr

from .. import _core
from .._codes import flag_attrs
from .._model import SliderModel
from .._sweep import sweep

#: |A1 error| of the describing function against the orbit above which a root counts as inaccurate.
ACCURACY = 0.05
VALIDITY_NAMES = ("valid", "no_root", "contact_opens", "inaccurate", "orbit_not_found")
NEWTON_NAMES = ("converged", "other_root", "not_converged")


def tidf_validity_map(normal_load, arm_length, *, mu: float = 0.215, threads: int | None = None) -> xr.Dataset:
    """Validity code of the describing function over normal load [N] x arm length [m] (see module doc)."""
    ds = sweep(normal_load=normal_load, arm_length=arm_length, strategy="shooting", progress=False, threads=threads,
               model=SliderModel(contact="bilateral", mu=mu))
    ds = ds.isel(sliding_speed=0)
    err = ds.tidf_a1_error.values
    code = np.full(err.shape, VALIDITY_NAMES.index("valid"), dtype=np.uint8)
    no_root = ~np.isfinite(ds.tidf_a1.values)
    code[~np.isfinite(ds.orbit_a1.values)] = VALIDITY_NAMES.index("orbit_not_found")
    code[np.isfinite(err) & (np.abs(err) > ACCURACY)] = VALIDITY_NAMES.index("inaccurate")
    code[ds.tidf_contact_opens.values == 1] = VALIDITY_NAMES.index("contact_opens")
    code[no_root] = VALIDITY_NAMES.index("no_root")
    out = xr.Dataset(
        {
            "tidf_validity": (ds.tidf_a1.dims, code, flag_attrs(VALIDITY_NAMES, "validity of the describing function")),
            "tidf_a1_error": ds.tidf_a1_error,
            "newton_iterations": ds.newton_iterations,
        },
        coords={"normal_load": ds.normal_load, "arm_length": ds.arm_length},
        attrs={"title": f"describing function against shooting orbits, bilateral, mu = {mu}"},
    )
    return out


def newton_basin_map(frequency_offset, amplitude_factor, *, model: SliderModel | None = None) -> xr.Dataset:
    """Outcome of warm-started Newton from the seed root's guess offset by ``frequency_offset`` (relative)
    and with amplitudes scaled by ``amplitude_factor``."""
    m = model or SliderModel(contact="bilateral")  # the describing function's own law
    df_ = _core.describing_function(m.values(), "bilateral", m.friction_law, ["mu"], np.array([[m.mu]]))
    k = int(np.argmax(df_["physical"][0]))
    root = np.array([df_[v][0, k] for v in ("omega", "A0", "A1", "A2", "theta")])
    fo, af = np.asarray(frequency_offset, float), np.asarray(amplitude_factor, float)
    g = np.empty((af.size, fo.size, 5))
    g[..., 0] = root[0] * (1 + fo)[None, :]
    g[..., 1:4] = root[1:4][None, None, :] * af[:, None, None]
    g[..., 4] = root[4]
    out = _core.tidf_solve(m.values(), m.friction_law, g.reshape(-1, 5), threads=1)
    x, st = out["x"].reshape(af.size, fo.size, 5), out["status"].reshape(af.size, fo.size)
    same = (np.abs(x[..., 0] - root[0]) < 1e-6 * root[0]) & (np.abs(x[..., 2] - root[2]) < 1e-6 * root[2])
    code = np.where(st != 0, 2, np.where(same, 0, 1)).astype(np.uint8)
    return xr.Dataset(
        {
            "newton": (("amplitude_factor", "frequency_offset"), code, flag_attrs(NEWTON_NAMES, "Newton outcome")),
            "iterations": (("amplitude_factor", "frequency_offset"), out["iterations"].reshape(af.size, fo.size),
                           {"units": "1", "long_name": "Newton iterations"}),
        },
        coords={"frequency_offset": ("frequency_offset", fo, {"units": "1", "long_name": "relative frequency offset of the guess"}),
                "amplitude_factor": ("amplitude_factor", af, {"units": "1", "long_name": "amplitude factor of the guess"})},
        attrs={"title": "warm-started Newton from guesses around the seed root"},
    )


def tidf_failure_maps(out_dir: os.PathLike, *, quick: bool = False, threads: int | None = None) -> dict:
    """Compute and draw both maps into ``out_dir``; return ``files``, ``counts`` and ``markdown``."""
    from .status_map import draw_status_map

    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    n = 6 if quick else 16
    maps = {
        "failure_tidf_validity": (tidf_validity_map(np.linspace(30, 150, n), np.linspace(0.05, 0.127, max(3, n // 2)),
                                                    threads=threads), "tidf_validity", "newton_iterations", "valid"),
        "failure_tidf_newton": (newton_basin_map(np.linspace(-0.3, 0.3, 2 * n + 1), np.geomspace(0.1, 10, n + 1)),
                                "newton", "iterations", "converged"),
    }
    files, counts, md = {}, {}, ["## Describing-function failure maps", ""]
    for name, (ds, var, cost, ok) in maps.items():
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6.4, 4.6), layout="constrained")
        draw_status_map(ds, var, cost=cost, ax=fig.add_subplot(), title=ds.attrs["title"], success=ok)
        png, nc = out / f"{name}.png", out / f"{name}.nc"
        fig.savefig(png, dpi=100)
        ds.to_netcdf(nc)
        files[name], files[name + "_nc"] = png, nc
        names = ds[var].attrs["flag_meanings"].split()
        counts[name] = {nm: int((ds[var].values == i).sum()) for i, nm in enumerate(names)}
        md += [f"### `{name}`: {ds.attrs['title']}", "", f"![{name}]({png.name})", "",
               ", ".join(f"{k}: {v}" for k, v in counts[name].items()), ""]
    return {"files": files, "counts": counts, "markdown": "\n".join(md)}
