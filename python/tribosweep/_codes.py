"""Every categorical code of tribosweep, defined once, with its CF attributes.

The numerical status, the outcome of a run to steady state and the kind of an orbit's instability
come from the Rust core (``rust_core/src/status.rs``, ``steady.rs``, ``shooting.rs``), so the two
languages cannot disagree; the sweep's own categories (regime, deciding stage, coexistence, wear
applicability, census attractor) are defined here. A netCDF variable of one of them carries
``flag_values`` and ``flag_meanings`` (:func:`flag_attrs`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from . import _core

#: Status names in code order: ``STATUS_NAMES[code]``.
STATUS_NAMES: tuple[str, ...] = tuple(_core.status_names())
#: Status code by name.
STATUS: dict[str, int] = {name: i for i, name in enumerate(STATUS_NAMES)}
#: Status of a sweep point whose computation killed its process (quarantined by the sweep's
#: supervisor, ``tribosweep._sweep.runner``). A sweep's own code, far from the core's, which count up from 0.
STATUS_CRASHED: int = 255
#: The codes and names of a sweep's ``status`` variable: the core's, then ``crashed``.
SWEEP_STATUS_VALUES: tuple[int, ...] = (*range(len(STATUS_NAMES)), STATUS_CRASHED)
SWEEP_STATUS_NAMES: tuple[str, ...] = (*STATUS_NAMES, "crashed")
#: Outcome names of a run to steady state, in code order.
OUTCOME_NAMES: tuple[str, ...] = tuple(_core.steady_outcome_names())
#: How a periodic orbit is unstable (its largest non-trivial Floquet multiplier), in code order.
INSTABILITY_NAMES: tuple[str, ...] = tuple(_core.instability_names())


def flag_attrs(names: Sequence[str], long_name: str, values: Sequence[int] | None = None, dtype: str = "u1") -> dict:
    """CF attributes of a categorical variable: value ``values[i]`` (default ``i``) means ``names[i]``.

    ``flag_values`` has the variable's own type ``dtype`` (CF requires it).

    Examples
    --------
    >>> a = flag_attrs(("no", "yes"), "a flag")
    >>> a["flag_values"].tolist(), a["flag_meanings"]
    ([0, 1], 'no yes')
    """
    return {
        "long_name": long_name,
        "flag_values": np.asarray(range(len(names)) if values is None else values, dtype=dtype),
        "flag_meanings": " ".join(names),
    }


#: Regime of a sweep point, in code order (the netCDF ``flag_values`` of ``regime``).
REGIME_NAMES: tuple[str, ...] = (
    "steady_sliding",
    "self_excited",
    "contact_loss",
    "stick_slip",
    "diverged",
    "failed",
    "unstable_undetermined",
    "irregular",
    "crashed",
)
#: One-line meaning of every regime, for documentation and the ``regime`` variable's ``comment``.
REGIME_DOC: dict[str, str] = {
    "steady_sliding": "steady sliding: linearly stable, or a disturbance decayed",
    "self_excited": "a periodic cycle with the pin always on the disk and the contact always sliding",
    "contact_loss": "a periodic cycle on which the pin leaves the disk (bouncing)",
    "stick_slip": "the sliding velocity reached zero (outside the constant-friction law)",
    "diverged": "|z| reached the escape limit",
    "failed": "the computation failed (see status and reason)",
    "unstable_undetermined": "sliding unstable and the motion not determined: strategy=linear computes no motion (by "
    "choice), or the run was bounded but its measurement failed numerically (see status and reason)",
    "irregular": "sustained irregular motion: bounded, neither periodic nor decayed, and stationary over three blocks "
    "of Poincare sections or still so at t_max (quasi-periodic: "
    "irregular_ftle about 0; chaotic: irregular_ftle > 0; see irregular_*)",
    "crashed": "computing the point killed its process again and again (an abort or a crash in native code): it was "
    "quarantined so that the rest of the sweep could finish (see reason)",
}
REGIME: dict[str, int] = {name: i for i, name in enumerate(REGIME_NAMES)}

#: Which stage decided a point's regime, in code order.
DECIDED_BY_NAMES: tuple[str, ...] = ("linear", "tidf", "shooting", "transient", "quarantine")
DECIDED_BY: dict[str, int] = {name: i for i, name in enumerate(DECIDED_BY_NAMES)}

#: Coexistence at a point (int8), derived from the attractor census (``tribosweep._census``):
#: not checked (no census: the method does not take one, ``census=False``, sliding is unstable,
#: or the point failed); one attractor seen; more than one attractor seen (coexistence, with the
#: evidence counted in ``basin_fraction`` and ``reason``); no census because the describing
#: function predicts no saddle cycle around stable sliding (nothing to find).
BISTABLE_VALUES: tuple[int, ...] = (-1, 0, 1, 2)
BISTABLE_NAMES: tuple[str, ...] = ("not_checked", "one_attractor", "coexisting", "no_saddle")
BISTABLE: dict[str, int] = dict(zip(BISTABLE_NAMES, BISTABLE_VALUES))

#: Whether the mild-wear model applies at a point, in code order. ``mild_wear_in_part``: steady
#: sliding is stable but coexists with vibration (census): mild wear holds after the fraction
#: ``mild_wear_fraction`` of disturbances that return to sliding, not after the others.
WEAR_APPLICABILITY_NAMES: tuple[str, ...] = (
    "mild_wear_regime", "outside_mild_wear_regime", "undetermined", "mild_wear_in_part",
)  # fmt: skip

#: What a census sample reaches, in code order (the ``attractor`` dimension).
ATTRACTOR_NAMES: tuple[str, ...] = ("sliding", "cycle", "irregular", "escape")
#: One-line meaning of each, for the netCDF ``comment``.
ATTRACTOR_DOC: dict[str, str] = {
    "sliding": "the disturbance decayed to steady sliding",
    "cycle": "the run settled on a periodic cycle",
    "irregular": "bounded motion, neither periodic nor decayed, and stationary over three blocks of Poincare "
    "sections or still so at the census t_max (quasi-periodic or chaotic bouncing, or a slower approach)",
    "escape": "|z| passed the escape limit (outside the model's validity)",
}
ATTRACTOR: dict[str, int] = {name: i for i, name in enumerate(ATTRACTOR_NAMES)}


def labels(da):
    """The names of a categorical (CF flag) variable's values, as a DataArray of strings.

    Works on any variable with ``flag_values`` and ``flag_meanings`` (``regime``, ``status``,
    ``decided_by``, ``bistable``, ``wear_applicability``, ...); a value outside the table is
    labelled ``"?<value>"``.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.sweep(normal_load=[10.0, 50.0], strategy="linear", progress=False)
    >>> ts.labels(ds.regime).values.ravel().tolist()
    ['unstable_undetermined', 'steady_sliding']
    """
    import xarray as xr

    if "flag_values" not in da.attrs or "flag_meanings" not in da.attrs:
        raise ValueError(f"{da.name!r} is not a categorical variable: it has no flag_values/flag_meanings")
    table = dict(zip(np.atleast_1d(da.attrs["flag_values"]).tolist(), str(da.attrs["flag_meanings"]).split()))
    flat = [table.get(v, f"?{v}") for v in np.asarray(da.values).ravel().tolist()]
    out = np.asarray(flat, dtype=object).reshape(np.shape(da.values)).astype(str)
    return xr.DataArray(out, coords=da.coords, dims=da.dims, name=da.name, attrs={"long_name": da.attrs.get("long_name", "")})
