"""A sweep's plan: its axes (checked), its points in C order, its chunks, and the configuration that fixes its results.

:class:`Plan` is plain data; its JSON form (``config``) is the resume manifest and its hash marks
every saved chunk. :meth:`Plan.task` is the argument tuple of one call of the pure chunk function
(:func:`tribosweep._sweep.chunk.compute_chunk`).
"""

from __future__ import annotations

import functools
import hashlib
import json
from collections.abc import Mapping

import numpy as np

from .. import _apparatus
from .._model import PARAM_NAMES, PARAM_UNITS, SliderModel
from .._settings import SweepSettings

#: Version of the parts-directory layout (the resume manifest).
PARTS_FORMAT: int = 7  # 2: the attractor census; 3: typed settings, "strategy" (was "method"), shooting settings;
# 4: text as UTF-8 bytes, the hash without the code identity (checked on its own), crashed points;
# 5: mild_wear_fraction (wear from the census fractions); 6: irregular_intermittent_period/_multiplier/_instability;
# 7: the census also where sliding is unstable

#: The three physics dimensions, always present (length 1 at the seed value when not swept).
PHYSICS_DIMS: tuple[str, ...] = ("normal_load", "arm_length", "sliding_speed")
#: Seed value of each physics dimension (SI units).
SEED_AXES: dict[str, float] = {"normal_load": 84.46, "arm_length": _apparatus.L_SEED, "sliding_speed": 0.46}
AXIS_ATTRS: dict[str, dict[str, str]] = {
    "normal_load": {"units": "N", "long_name": "normal load F_st"},
    "arm_length": {"units": "m", "long_name": "clamped arm length l"},
    "sliding_speed": {"units": "m s-1", "long_name": "sliding speed V"},
}
#: Fields an extra axis may not sweep: set by the physics dimensions through the apparatus model.
RESERVED_FIELDS: tuple[str, ...] = ("normal_load", "sliding_speed", "omega_normal", "omega_friction", "omega_torsion")
#: Default points per chunk: the eigenvalue-only method is cheap, time integration is not. 256
#: for time integration: a chunk's census is one batched call whose lanes idle while its longest
#: samples finish, and that tail costs less the more samples a call has (the default 2,000-point
#: grid at K = 16 on 2 cores: 12.5 s with chunks of 64, 10.5 s with 256, 10.0 s with one chunk).
DEFAULT_CHUNK_SIZE: dict[str, int] = {"linear": 4096}
DEFAULT_CHUNK_SIZE_OTHER: int = 256
#: Under constant friction the points that differ only in sliding speed share one computation
#: (`chunk.dynamics`), so a chunk of 256 points holds only 256 / n_speeds computations and its
#: census batches run mostly on their longest samples: time-integrating sweeps then default to
#: 256 computations per chunk (256 n_speeds points), at most this many points. A quarter of the
#: 10^5-point bench grid (25,392 points, 23 speeds, K = 16, 2 cores): 26.6 s with chunks of 256,
#: 23.1 s with 2,048 and 22.5 s with 8,192.
MAX_SHARED_CHUNK_SIZE: int = 8192


def default_chunk_size(strategy: str, friction_law: str, n_speeds: int) -> int:
    """Points per chunk when the caller gives none (see ``DEFAULT_CHUNK_SIZE_OTHER`` and
    ``MAX_SHARED_CHUNK_SIZE``).

    Examples
    --------
    >>> default_chunk_size("linear", "constant", 5), default_chunk_size("auto", "constant", 5)
    (4096, 1280)
    >>> default_chunk_size("auto", "coulomb", 5), default_chunk_size("auto", "constant", 100)
    (256, 8192)
    """
    if strategy in DEFAULT_CHUNK_SIZE:
        return DEFAULT_CHUNK_SIZE[strategy]
    if friction_law == "constant":
        return min(MAX_SHARED_CHUNK_SIZE, DEFAULT_CHUNK_SIZE_OTHER * max(1, n_speeds))
    return DEFAULT_CHUNK_SIZE_OTHER

def check_axis(name: str, values, *, positive: bool = True, units: str = "") -> np.ndarray:
    """A non-empty, finite, strictly increasing 1-D float array (and > 0 if ``positive``)."""
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {values!r} is not an array of numbers") from None
    if a.ndim == 0:
        a = a.reshape(1)
    if a.ndim != 1:
        raise ValueError(f"{name} has shape {a.shape}: must be a 1-D array")
    if a.size == 0:
        raise ValueError(f"{name} is empty: give at least one value")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise ValueError(f"{name} contains {float(a[bad[0]])} at index {bad[0]}: every value must be finite")
    if positive:
        bad = np.flatnonzero(a <= 0)
        if bad.size:
            u = f" {units}" if units else ""
            raise ValueError(f"{name} contains {float(a[bad[0]])!r}{u} at index {bad[0]}: every value must be > 0")
    d = np.diff(a)
    if np.any(d == 0):
        i = int(np.flatnonzero(d == 0)[0]) + 1
        raise ValueError(
            f"{name} has the duplicate value {float(a[i])!r} at index {i}: values must be strictly increasing"
        )
    if np.any(d < 0):
        i = int(np.flatnonzero(d < 0)[0]) + 1
        raise ValueError(
            f"{name} is not sorted ({float(a[i])!r} at index {i} follows {float(a[i - 1])!r}): "
            "values must be strictly increasing"
        )
    return a


#: Values beyond these are far outside what the model means and most likely a unit mistake:
#: name -> (largest sensible value, SI unit, the likely mistake). The report's arms are 5-12.7 cm
#: and its loads 17-152 N.
UNIT_HINTS: dict[str, tuple[float, str, str]] = {
    "arm_length": (1.0, "m", "centimetres or millimetres given as metres? the report's arms are 0.05-0.127 m"),
    "normal_load": (5000.0, "N", "newtons expected, not grams or millinewtons; the report's loads are 17-152 N"),
    "sliding_speed": (50.0, "m/s", "metres per second expected, not mm/s or rpm; the report's speeds are 0.1-1 m/s"),
}


def warn_units(name: str, a: np.ndarray) -> None:
    """Warn (``UserWarning``) when an axis reaches values no pin-on-disk rig has: a likely unit mistake."""
    if name in UNIT_HINTS:
        limit, unit, hint = UNIT_HINTS[name]
        if np.max(a) > limit:
            import warnings

            warnings.warn(f"{name} reaches {float(np.max(a)):g} {unit}, above {limit:g} {unit}: {hint}", UserWarning,
                          stacklevel=3)  # fmt: skip


def check_extra_axes(model: SliderModel, extra_axes) -> dict[str, np.ndarray]:
    if extra_axes is None:
        return {}
    if not isinstance(extra_axes, Mapping):
        raise TypeError(f"extra_axes = {extra_axes!r} must be a dict {{SliderModel field: 1-D array}}")
    out = {}
    for name, values in extra_axes.items():
        if name in RESERVED_FIELDS:
            hint = "pass it as its own argument" if name in PHYSICS_DIMS else "it follows arm_length"
            raise ValueError(f"extra_axes[{name!r}] is set by the apparatus model ({hint}): it cannot be an extra axis")
        if name not in PARAM_NAMES:
            valid = tuple(n for n in PARAM_NAMES if n not in RESERVED_FIELDS)
            raise ValueError(f"extra_axes has unknown field {name!r}: valid names are {valid}")
        a = check_axis(f"extra_axes[{name!r}]", values, positive=False, units=PARAM_UNITS[name])
        for v in a:  # each value must make a valid model; its message names field, value and range
            try:
                model.replace(**{name: float(v)})
            except ValueError as e:
                raise ValueError(f"extra_axes[{name!r}]: {e}") from None
        out[name] = a
    return out


#: Keys of the configuration that identify the code (a resume with other code is refused unless forced).
CODE_IDENTITY: tuple[str, ...] = ("tribosweep_version", "core_build")


@functools.cache
def core_build() -> str:
    """Identity of the compiled core: the SHA-256 (first 16 hex digits) of the extension's file.

    A rebuilt core with other numerics has another identity, so a sweep refuses to resume parts
    it computed (the manifest names the difference).
    """
    from .. import _core

    with open(_core.__file__, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()[:16]


class Plan:
    """Everything that fixes a sweep's results, as plain data (its JSON form is the manifest)."""

    def __init__(self, model, axes, strategy, settings: SweepSettings, chunk_size, wear_reference, wear_calibration):
        self.model = model
        self.axes = axes  # {dim: array}, in dimension order
        self.dims = tuple(axes)
        self.shape = tuple(a.size for a in axes.values())
        self.n_points = int(np.prod(self.shape))
        self.strategy = strategy
        self.settings = settings
        self.options = settings.to_options()
        self.chunk_size = chunk_size
        self.n_chunks = -(-self.n_points // chunk_size)
        self.wear_reference = wear_reference
        self.wear_calibration = wear_calibration
        self.model_values = model.values()
        from .. import __version__

        self.config = {
            "format": PARTS_FORMAT,
            "tribosweep_version": __version__,
            "core_build": core_build(),
            "dims": list(self.dims),
            "axes": {d: a.tolist() for d, a in axes.items()},
            "model": self.model_values,
            "contact": model.contact,
            "friction_law": model.friction_law,
            "mu_static_follows_mu": model.mu_static is None,
            "strategy": strategy,
            "options": self.options,
            "chunk_size": chunk_size,
        }
        # The hash marks every part; the code identity is checked on its own (a forced resume accepts another).
        fixed = {k: v for k, v in self.config.items() if k not in CODE_IDENTITY}
        text = json.dumps(fixed, sort_keys=True, allow_nan=False)
        self.hash = hashlib.sha256(text.encode()).hexdigest()

    def chunk_range(self, k: int) -> tuple[int, int]:
        return k * self.chunk_size, min((k + 1) * self.chunk_size, self.n_points)

    def point_params(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """Per-point SliderModel fields of the points ``[start, stop)``."""
        idx = np.unravel_index(np.arange(start, stop), self.shape)
        at = {d: self.axes[d][i] for d, i in zip(self.dims, idx)}
        params = {"normal_load": at["normal_load"], "sliding_speed": at["sliding_speed"]}
        params.update(_apparatus.arm_frequencies(at["arm_length"], self.model))
        for d in self.dims[len(PHYSICS_DIMS) :]:
            params[d] = at[d]
        if "mu" in params and self.model.mu_static is None:
            params["mu_static"] = params["mu"]  # "no Stribeck effect" follows the swept mu
        return params

    def point_values(self, i: int) -> tuple[float, ...]:
        """The axis values of point ``i`` (C-order flat index), in dimension order."""
        return tuple(float(self.axes[d][j]) for d, j in zip(self.dims, np.unravel_index(i, self.shape)))

    def task(self, k: int, threads: int | None) -> tuple:
        return self.task_range(*self.chunk_range(k), threads)

    def task_range(self, start: int, stop: int, threads: int | None) -> tuple:
        """The arguments of :func:`tribosweep._sweep.chunk.compute_chunk` for the points ``[start, stop)``."""
        options = dict(self.options, threads=threads)
        return (self.model_values, self.model.contact, self.model.friction_law, self.point_params(start, stop),
                self.strategy, options)  # fmt: skip


