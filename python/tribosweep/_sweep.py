"""Sweeps over normal load x arm length x sliding speed (and any other real model field).

A sweep is an ensemble: the grid's points, numbered in C order, are cut into chunks, and each
chunk is one call of the pure function :func:`tribosweep._chunk.compute_chunk`. The loop runs
in-process or through any executor with a ``map`` method (``concurrent.futures``, dask). With an
output file, every finished chunk is saved at once to ``<output>.parts/chunk_NNNNNN.npz``
(atomically) next to a manifest of the configuration, so an interrupted sweep keeps its work and
``resume=True`` finishes it with results identical to an uninterrupted run. The final netCDF file
is assembled chunk by chunk (memory does not grow with the sweep) through ``<output>.tmp``.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import math
import os
import shutil
import sys
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from . import _apparatus, _census, _checks, _chunk, _irregular, _netcdf, _wear
from ._model import PARAM_LONG_NAMES, PARAM_NAMES, PARAM_UNITS, SliderModel
from ._simulate import DEFAULT_Y0

#: The three physics dimensions, always present (length 1 at the seed value when not swept).
PHYSICS_DIMS: tuple[str, ...] = ("normal_load", "arm_length", "sliding_speed")
#: Seed value of each physics dimension (SI units).
SEED_AXES: dict[str, float] = {"normal_load": 84.46, "arm_length": _apparatus.L_SEED, "sliding_speed": 0.46}
_AXIS_ATTRS: dict[str, dict[str, str]] = {
    "normal_load": {"units": "N", "long_name": "normal load F_st"},
    "arm_length": {"units": "m", "long_name": "clamped arm length l"},
    "sliding_speed": {"units": "m s-1", "long_name": "sliding speed V"},
}
#: Fields an extra axis may not sweep: set by the physics dimensions through the apparatus model.
RESERVED_FIELDS: tuple[str, ...] = ("normal_load", "sliding_speed", "omega_normal", "omega_friction", "omega_torsion")
#: Default points per chunk: the eigenvalue-only method is cheap, time integration is not.
DEFAULT_CHUNK_SIZE: dict[str, int] = {"linear": 4096}
DEFAULT_CHUNK_SIZE_OTHER: int = 64
#: Version of the parts-directory layout.
PARTS_FORMAT: int = 2  # 2: the attractor census replaced the one-run bistability check

HOPF_CAVEAT: str = (
    "In this model (MODEL.md section 4) steady sliding is linearly unstable BELOW a Hopf load (24.90 N at the "
    "seed's mu = 0.215, with K_phi, C_zc and mu fixed), so self-excitation appears at low loads: the opposite "
    "of the 1985 report's experiments, where self-excitation starts above a critical load. Stable sliding can "
    "also coexist with a stable bouncing cycle (as at the seed point), so a point's regime can depend on the "
    "initial disturbance; the bistable variable says whether that was checked."
)
REFERENCES: str = (
    "Interactions between friction-induced vibration and wear, Illinois Institute of Technology report, 1985 "
    "(chapter IV; appendix 3: self-excited vibrations; appendix 4: wear model)"
)


def _check_axis(name: str, values, *, positive: bool = True, units: str = "") -> np.ndarray:
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


def _check_extra_axes(model: SliderModel, extra_axes) -> dict[str, np.ndarray]:
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
        a = _check_axis(f"extra_axes[{name!r}]", values, positive=False, units=PARAM_UNITS[name])
        for v in a:  # each value must make a valid model; its message names field, value and range
            try:
                model.replace(**{name: float(v)})
            except ValueError as e:
                raise ValueError(f"extra_axes[{name!r}]: {e}") from None
        out[name] = a
    return out


def _disturbance(value) -> np.ndarray:
    if value is None:
        return DEFAULT_Y0.copy()
    if np.ndim(value) == 0:
        z0 = float(value)
        if not math.isfinite(z0):
            raise ValueError(f"disturbance = {value!r} must be finite: a z offset [m] or a state of 6 values")
        return np.array([z0, 0.0, 0.0, 0.0, 0.0, 0.0])
    return _checks.state("disturbance", value)


class _Plan:
    """Everything that fixes a sweep's results, as plain data (its JSON form is the manifest)."""

    def __init__(self, model, axes, method, options, chunk_size, wear_reference, wear_calibration):
        self.model = model
        self.axes = axes  # {dim: array}, in dimension order
        self.dims = tuple(axes)
        self.shape = tuple(a.size for a in axes.values())
        self.n_points = int(np.prod(self.shape))
        self.method = method
        self.options = options
        self.chunk_size = chunk_size
        self.n_chunks = -(-self.n_points // chunk_size)
        self.wear_reference = wear_reference
        self.wear_calibration = wear_calibration
        self.model_values = model.values()
        from . import __version__

        self.config = {
            "format": PARTS_FORMAT,
            "tribosweep_version": __version__,
            "dims": list(self.dims),
            "axes": {d: a.tolist() for d, a in axes.items()},
            "model": self.model_values,
            "contact": model.contact,
            "friction_law": model.friction_law,
            "mu_static_follows_mu": model.mu_static is None,
            "method": method,
            "options": options,
            "chunk_size": chunk_size,
        }
        text = json.dumps(self.config, sort_keys=True, allow_nan=False)
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

    def task(self, k: int, threads: int | None) -> tuple:
        start, stop = self.chunk_range(k)
        options = dict(self.options, threads=threads)
        return (self.model_values, self.model.contact, self.model.friction_law, self.point_params(start, stop),
                self.method, options)  # fmt: skip


def _run_task(task: tuple) -> dict[str, np.ndarray]:
    """Module-level (picklable) wrapper for executors."""
    return _chunk.compute_chunk(*task)


def _compare_configs(saved: dict, now: dict, where: str) -> None:
    """Raise ValueError naming the first difference between a saved and the current configuration."""

    missing = object()

    def show(v):
        if v is missing:
            return "(absent)"
        s = json.dumps(v)
        return s if len(s) < 120 else s[:117] + "..."

    for key in sorted(set(saved) | set(now)):
        a, b = saved.get(key, missing), now.get(key, missing)
        if a == b:
            continue
        if isinstance(a, dict) and isinstance(b, dict):
            for sub in sorted(set(a) | set(b)):
                if a.get(sub, missing) != b.get(sub, missing):
                    raise ValueError(
                        f"cannot resume {where}: {key} {sub!r} differs (saved {show(a.get(sub, missing))}, now "
                        f"{show(b.get(sub, missing))}); use the saved configuration, or delete the directory to "
                        "start over"
                    )
        raise ValueError(
            f"cannot resume {where}: {key} differs (saved {show(a)}, now {show(b)}); use the saved "
            "configuration, or delete the directory to start over"
        )


class _Parts:
    """The sidecar directory of finished chunks: ``manifest.json`` and ``chunk_NNNNNN.npz``."""

    def __init__(self, output: Path, plan: _Plan, resume: bool):
        self.dir = Path(str(output) + ".parts")
        self.plan = plan
        manifest = self.dir / "manifest.json"
        if self.dir.exists():
            if not resume:
                raise FileExistsError(
                    f"{self.dir} holds chunks of an unfinished sweep: pass resume=True (--resume) to finish it, "
                    "or delete the directory to start over"
                )
            try:
                saved = json.loads(manifest.read_text())
            except (OSError, ValueError) as e:
                raise ValueError(f"cannot resume {self.dir}: its manifest is unreadable ({e})") from None
            _compare_configs(saved.get("config", {}), plan.config, str(self.dir))
        else:
            self.dir.mkdir()
            self._atomic_write(manifest, lambda f: f.write(self._manifest_text().encode()))

    def _manifest_text(self) -> str:
        p = self.plan
        body = {"hash": p.hash, "n_points": p.n_points, "n_chunks": p.n_chunks, "shape": list(p.shape), "config": p.config}
        return json.dumps(body, indent=1, sort_keys=True)

    def path(self, k: int) -> Path:
        return self.dir / f"chunk_{k:06d}.npz"

    @staticmethod
    def _atomic_write(path: Path, write) -> None:
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)

    def save(self, k: int, arrays: Mapping[str, np.ndarray]) -> None:
        start, stop = self.plan.chunk_range(k)
        meta = {"__hash__": np.array(self.plan.hash), "__range__": np.array([start, stop])}
        self._atomic_write(self.path(k), lambda f: np.savez(f, **meta, **arrays))

    def load(self, k: int) -> dict[str, np.ndarray]:
        with np.load(self.path(k), allow_pickle=False) as z:
            return {name: z[name] for name in z.files if not name.startswith("__")}

    def is_done(self, k: int) -> bool:
        """True for a readable chunk file of this configuration and range (a bad one is removed)."""
        p = self.path(k)
        if not p.exists():
            return False
        try:
            with np.load(p, allow_pickle=False) as z:
                ok = str(z["__hash__"]) == self.plan.hash and list(z["__range__"]) == list(self.plan.chunk_range(k))
        except Exception:  # noqa: BLE001 - any unreadable file is simply recomputed
            ok = False
        if not ok:
            p.unlink()
        return ok

    def remove(self) -> None:
        shutil.rmtree(self.dir)


class _Progress:
    """tqdm if installed, else one updating stderr line; nothing when disabled."""

    def __init__(self, enabled: bool, total: int, initial: int):
        self.total, self.done, self.bar = total, initial, None
        self.enabled = enabled
        if not enabled:
            return
        try:
            from tqdm import tqdm
        except ImportError:
            self._line()
        else:
            self.bar = tqdm(total=total, initial=initial, unit="pt", desc="sweep", file=sys.stderr, dynamic_ncols=True)

    def _line(self) -> None:
        pct = 100.0 * self.done / self.total if self.total else 100.0
        sys.stderr.write(f"\rsweep: {self.done}/{self.total} points ({pct:.0f} %)")
        sys.stderr.flush()

    def update(self, n: int) -> None:
        self.done += n
        if self.bar is not None:
            self.bar.update(n)
        elif self.enabled:
            self._line()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
        elif self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()


def _coords(plan: _Plan) -> dict:
    out = {}
    for d, a in plan.axes.items():
        attrs = dict(_AXIS_ATTRS[d]) if d in _AXIS_ATTRS else {"units": PARAM_UNITS[d], "long_name": PARAM_LONG_NAMES[d]}
        out[d] = (a, attrs)
    return out


def _static_vars(plan: _Plan) -> dict:
    arm = plan.axes["arm_length"]
    w = _apparatus.arm_frequencies(arm, plan.model)
    out = {}
    for mode, field in _apparatus.MODE_FIELDS.items():
        out[field] = (
            ("arm_length",),
            np.asarray(w[field], dtype=np.float64).reshape(arm.shape),
            {"units": "rad s-1", "long_name": f"{PARAM_LONG_NAMES[field]} (arm-length power law, exponent "
             f"{_apparatus.ARM_EXPONENTS[mode]:.3f})"},
        )  # fmt: skip
    flag = ("within_identified_range", "extrapolated")
    out["normal_load_extrapolated"] = (
        ("normal_load",),
        _apparatus.load_extrapolated(plan.axes["normal_load"]).astype(np.uint8),
        _netcdf.flag_attributes((0, 1), flag, "u1", "load outside the contact law's identification range 22-93 N"),
    )
    out["arm_length_extrapolated"] = (
        ("arm_length",),
        _apparatus.arm_extrapolated(arm).astype(np.uint8),
        _netcdf.flag_attributes((0, 1), flag, "u1", "arm length outside the report's tables 0.05-0.127 m"),
    )
    return out


def _global_attrs(plan: _Plan, command: str, f_ref: float) -> dict:
    from . import __version__

    now = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    attrs = {
        "Conventions": "CF-1.11",
        "title": "tribosweep regime map of the 1985 pin-on-disk slider over normal load, arm length and sliding speed",
        "institution": "tribosweep",
        "source": f"tribosweep {__version__}",
        "history": f"{now} {command}",
        "references": REFERENCES,
        "comment": HOPF_CAVEAT,
        "method": plan.method,
    }
    for k, v in plan.model_values.items():
        attrs[f"model_{k}"] = v
    attrs["model_contact"] = plan.model.contact
    attrs["model_friction_law"] = plan.model.friction_law
    for k, v in plan.options.items():
        if k != "wear":
            attrs[f"solver_{k}"] = v
    attrs["arm_length_seed"] = _apparatus.L_SEED
    for mode, p in _apparatus.ARM_EXPONENTS.items():
        attrs[f"arm_exponent_{mode}"] = p
    for (mode, table), err in _apparatus.ARM_FIT_MAX_REL_ERROR.items():
        attrs[f"arm_fit_max_rel_error_{mode}_{table}"] = err
    attrs["load_identification_range"] = np.asarray(_apparatus.LOAD_RANGE)
    ref = plan.wear_reference
    attrs["wear_reference_normal_load"] = ref.normal_load
    attrs["wear_reference_arm_length"] = ref.arm_length
    attrs["wear_reference_sliding_speed"] = ref.sliding_speed
    attrs["wear_reference_frequency_hz"] = f_ref
    attrs["wear_l1"] = _wear.L1
    if plan.wear_calibration is not None:
        for k, v in plan.wear_calibration.as_dict().items():
            attrs[f"wear_calibration_{k}"] = v
    attrs["wear_model_caveats"] = _wear.WEAR_CAVEATS
    return attrs


def _irregular_options(**given) -> dict:
    """The irregular-motion settings as sweep options, checked (ValueError names the argument)."""
    _chunk.irregular_settings(given)
    return {k: (int(v) if k in ("ftle_segments", "ftle_warmup") else float(v)) for k, v in given.items()}


def _samples(value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= 100_000:
        raise ValueError(f"samples = {value!r} is out of range: must be an integer in [1, 100000] (disturbances per point)")
    return int(value)


def sweep(
    model: SliderModel | None = None,
    *,
    normal_load: Sequence[float] | None = None,
    arm_length: Sequence[float] | None = None,
    sliding_speed: Sequence[float] | None = None,
    extra_axes: Mapping[str, Sequence[float]] | None = None,
    method: str = "auto",
    output: str | os.PathLike | None = None,
    chunk_size: int | None = None,
    threads: int | None = None,
    executor=None,
    resume: bool = False,
    progress: bool = True,
    disturbance: float | Sequence[float] | None = None,
    wear_reference: _wear.WearReference | None = None,
    wear_calibration: _wear.WearCalibration | None = None,
    t_max: float = _chunk.T_MAX,
    integrator: str = "dop853",
    rtol: float = 1e-8,
    atol: float | Sequence[float] | None = None,
    periodic_tol: float = 1e-5,
    decay_amplitude: float | None = None,
    census: bool = True,
    samples: int = _census.SAMPLES,
    census_t_max: float = _census.CENSUS_T_MAX,
    disturbance_scale: float = _census.DISTURBANCE_SCALE,
    unstable_disturbance: float = 1.0,
    irregular_window: float = _irregular.WINDOW,
    irregular_sample_dt: float = _irregular.SAMPLE_DT,
    ftle_tau: float = _irregular.FTLE_TAU,
    ftle_segments: int = _irregular.FTLE_SEGMENTS,
    ftle_warmup: int = _irregular.FTLE_WARMUP,
    ftle_d0: float = _irregular.FTLE_D0,
    ftle_rtol: float = _irregular.FTLE_RTOL,
    check_bistability: bool | None = None,
    command: str | None = None,
) -> xr.Dataset:
    """Map the slider's regime over normal load x arm length x sliding speed (x extra axes).

    Every point is the apparatus at that load, arm length and speed (:func:`apparatus_model`);
    its regime is decided by ``method`` and recorded with how it was decided. A failed point is
    data (``regime = failed`` with a status and a reason), never an exception.

    Parameters
    ----------
    model : SliderModel, optional
        Everything not swept; its natural frequencies belong to the seed arm length 7.2 cm.
        Default: the seed with the physical ``contact="unilateral"``.
    normal_load : array_like, N, optional
        Strictly increasing loads > 0. Default ``[84.46]`` (a length-1 dimension).
    arm_length : array_like, m, optional
        Strictly increasing arm lengths > 0. Default ``[0.072]``.
    sliding_speed : array_like, m/s, optional
        Strictly increasing speeds > 0. Default ``[0.46]``.
    extra_axes : dict of str to array_like, optional
        More dimensions: any real SliderModel field except those the three above set, e.g.
        ``{"mu": [0.2, 0.25, 0.3]}`` (units of ``tribosweep._model.PARAM_UNITS``).
    method : {"auto", "linear", "transient", "tidf", "shooting"}
        ``linear``: eigenvalues only (an unstable point is ``unstable_undetermined``);
        ``tidf``: eigenvalues, then the describing function at every point; ``shooting``: also the
        periodic orbit of every physical root; ``transient``: run every point to its steady state
        from ``disturbance``; ``auto``: each point gets the cheapest model that decides it
        (eigenvalues; the describing function at stable points; shooting where the disturbance
        nears the saddle cycle; a transient where sliding is unstable or the others cannot
        decide), see ``tribosweep._chunk``.
    output : path-like, optional
        netCDF file to write (through ``<output>.tmp``); finished chunks are kept in
        ``<output>.parts/`` until it is complete. Without it the Dataset is built in memory.
    chunk_size : int, optional
        Points per chunk (default 4096 for ``linear``, 64 otherwise). Part of the configuration
        a resumed sweep must match.
    threads : int, optional
        Rust worker threads inside a chunk (default ``TRIBOSWEEP_THREADS`` or all cores).
        Results do not depend on it.
    executor : object with ``map``, optional
        Runs the chunks, e.g. a ``concurrent.futures`` executor or a dask ``Client`` (results
        that are futures are waited for). Default: an in-process loop.
    resume : bool
        Finish the sweep whose chunks are in ``<output>.parts/`` (the configuration must match,
        else ``ValueError`` names the difference).
    progress : bool
        Progress bar on stderr (tqdm if installed, else a plain line).
    disturbance : float or array_like (6,), optional
        Initial state of the transient runs: a ``z`` offset [m] or a full state
        ``[z, zd, x, xd, phi, phid]`` (default ``z = 1 um``).
    wear_reference : WearReference, optional
        Reference point of ``wear_rate_relative`` (default the seed: 84.46 N, 7.2 cm, 0.46 m/s).
    wear_calibration : WearCalibration, optional
        Adds the absolute ``wear_rate`` [kg/m].
    t_max : float, s
        Longest simulated time of a transient run (100). A bounded run that has neither repeated
        nor decayed by then is ``irregular`` (measured: ``irregular_*``); at a linearly stable point
        a motion below ``|z_st|/2`` is sliding still decaying (``steady_sliding``, status ``not_converged``).
    integrator : {"dop853", "dopri5", "rodas4"}
        Time integrator of the transient runs. DOP853 by default: on the unilateral (impacting)
        transients it is about twice as fast as Dopri5 at rtol 1e-8 and about 7x more accurate
        (the work-precision charts of ``tribosweep bench``); a 1,058-point seed sweep takes 18 s
        instead of 34 s.
    rtol, atol
        Integration tolerances (as in :func:`tribosweep.simulate`).
    periodic_tol : float
        Relative repetition tolerance that declares a cycle.
    census : bool
        ``auto``: take the attractor census (``tribosweep.census``) at stable points with a saddle
        cycle: ``samples`` disturbances on the torsion and normal modes, each run to its attractor
        with the model's contact law; ``basin_fraction`` (with ``basin_fraction_se``) on the
        ``attractor`` dimension (sliding, cycle, irregular, escape), ``basin_stability``,
        ``n_attractors``, ``n_cycles`` and the largest cycle's frequency and amplitude. ``bistable``
        is derived from it: ``coexisting`` where more than one attractor was seen,
        ``one_attractor``, or ``no_saddle`` where the describing function predicts no saddle (no
        census: nothing to find). The census is most of an ``auto`` sweep's cost.
    samples : int
        Census disturbances per point ``K`` (default 32); fractions carry ``sqrt(p (1 - p) / K)``.
    census_t_max : float, s
        Longest simulated time of one census disturbance (30); bounded motion that has neither
        decayed nor repeated by then counts as ``irregular``.
    disturbance_scale : float
        Largest modal amplitude of a census disturbance in units of ``|z_st|`` (3).
    unstable_disturbance : float
        ``auto``: transients of linearly unstable points start on the unstable mode with
        ``|z| = unstable_disturbance |z_st|``.
    decay_amplitude : float, m, optional
        Amplitude below which a motion counts as decayed (default ``1e-3 |z_st|``).
    irregular_window, irregular_sample_dt : float, s
        A transient that stays bounded but neither repeats nor decays by ``t_max`` is regime
        ``irregular``; from where it ended, ``z`` is sampled every ``irregular_sample_dt`` (1e-4)
        over ``irregular_window`` (0.5) for ``irregular_z_min``, ``irregular_z_max`` and
        ``irregular_omega`` (the spectral peak).
    ftle_tau : float, s
        Segment length of its largest finite-time Lyapunov exponent ``irregular_ftle`` (0.05:
        about 5 torsion periods; see ``tribosweep._irregular``).
    ftle_segments, ftle_warmup : int
        Segments averaged (40, >= 2; the standard error ``irregular_ftle_se`` is their spread over
        ``sqrt(ftle_segments)``) and run first without counting (4, >= 0).
    ftle_d0 : float
        Separation of the two trajectories in units of the characteristic sizes (1e-8).
    ftle_rtol : float
        Relative tolerance of the exponent's runs (1e-11: well below ``ftle_d0``).
    command : str, optional
        Command recorded in the ``history`` attribute (the CLI passes its command line).

    Returns
    -------
    xarray.Dataset
        Dimensions ``normal_load``, ``arm_length``, ``sliding_speed`` (+ extras); per point
        ``regime``, ``status``, ``reason``, ``decided_by``, ``bistable``, linear stability,
        cycle summary, irregular motion (``irregular_z_min``, ``irregular_z_max``,
        ``irregular_omega``, ``irregular_ftle``, ``irregular_ftle_se``; NaN elsewhere), wear and cost
        variables (see ``tribosweep._chunk.POINT_VARIABLES``).
        With ``output`` the Dataset is opened lazily from the file.

    Raises
    ------
    ValueError
        A bad axis (empty, not strictly increasing, NaN, non-positive), option, or a resume
        whose configuration differs.
    TypeError
        ``model``, ``extra_axes``, ``wear_reference`` or ``wear_calibration`` of the wrong type.
    FileExistsError
        ``<output>.parts/`` exists and ``resume`` is false.
    KeyboardInterrupt
        Re-raised after an interruption; finished chunks stay in ``<output>.parts/``.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.sweep(normal_load=[10.0, 50.0], method="linear", progress=False)
    >>> [str(r) for r in ds.regime.attrs["flag_meanings"].split()[:2]]
    ['steady_sliding', 'self_excited']
    >>> ds.regime.sel(arm_length=0.072, sliding_speed=0.46).values.tolist()
    [6, 0]
    """
    if check_bistability is not None:
        warnings.warn("sweep(check_bistability=...) is renamed census=...; the old name goes away in 0.3",
                      DeprecationWarning, stacklevel=2)  # fmt: skip
        census = bool(check_bistability)
    if model is None:
        model = SliderModel(contact="unilateral")
    if not isinstance(model, SliderModel):
        raise TypeError(f"model = {model!r} must be a tribosweep.SliderModel or None")
    if method not in _chunk.METHODS:
        raise ValueError(f"method = {method!r} is not valid: must be one of {_chunk.METHODS}")
    if method not in _chunk.IMPLEMENTED_METHODS:
        raise NotImplementedError(f"method = {method!r} is not available yet: use one of {_chunk.IMPLEMENTED_METHODS}")
    axes = {}
    for name, values in (("normal_load", normal_load), ("arm_length", arm_length), ("sliding_speed", sliding_speed)):
        values = [SEED_AXES[name]] if values is None else values
        axes[name] = _check_axis(name, values, units=_AXIS_ATTRS[name]["units"])
    axes.update(_check_extra_axes(model, extra_axes))
    if chunk_size is None:
        chunk_size = DEFAULT_CHUNK_SIZE.get(method, DEFAULT_CHUNK_SIZE_OTHER)
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise ValueError(f"chunk_size = {chunk_size!r} is out of range: must be an integer >= 1")
    threads = _checks.threads(threads)
    wear_reference = _wear.WearReference() if wear_reference is None else wear_reference
    if not isinstance(wear_reference, _wear.WearReference):
        raise TypeError(f"wear_reference = {wear_reference!r} must be a tribosweep.WearReference or None")
    if wear_calibration is not None and not isinstance(wear_calibration, _wear.WearCalibration):
        raise TypeError(f"wear_calibration = {wear_calibration!r} must be a tribosweep.WearCalibration or None")
    if resume and output is None:
        raise ValueError("resume=True needs output: the finished chunks are kept next to the output file")
    atol_arr = _checks.atol(atol)
    if integrator not in _checks.METHODS:
        raise ValueError(f"integrator = {integrator!r} is not valid: must be one of {_checks.METHODS}")
    f_ref = wear_reference.frequency_hz(model)
    options = {
        "t_max": _checks.positive("t_max", t_max),
        "integrator": integrator,
        "rtol": _checks.rtol(rtol),
        "atol": None if atol_arr is None else atol_arr.tolist(),
        "periodic_tol": _checks.positive("periodic_tol", periodic_tol),
        "decay_amplitude": None if decay_amplitude is None else _checks.positive("decay_amplitude", decay_amplitude),
        "census": bool(census),
        "samples": _samples(samples),
        "census_t_max": _checks.positive("census_t_max", census_t_max),
        "disturbance_scale": _checks.positive("disturbance_scale", disturbance_scale),
        "unstable_disturbance": _checks.positive("unstable_disturbance", unstable_disturbance),
        **_irregular_options(irregular_window=irregular_window, irregular_sample_dt=irregular_sample_dt,
                             ftle_tau=ftle_tau, ftle_segments=ftle_segments, ftle_warmup=ftle_warmup, ftle_d0=ftle_d0,
                             ftle_rtol=ftle_rtol),
        "y0": _disturbance(disturbance).tolist(),
        "wear": {
            "normal_load": wear_reference.normal_load,
            "sliding_speed": wear_reference.sliding_speed,
            "frequency_hz": f_ref,
            "calibration": None if wear_calibration is None else wear_calibration.as_dict(),
        },
    }
    plan = _Plan(model, axes, method, options, int(chunk_size), wear_reference, wear_calibration)
    if command is None:
        command = f"tribosweep.sweep(shape={plan.shape}, dims={plan.dims}, method={method!r})"
    schema = (
        _coords(plan),
        _static_vars(plan),
        _netcdf.point_specs(plan.dims, wear_rate=wear_calibration is not None),
        _global_attrs(plan, command, f_ref),
    )

    if output is None:
        writer = _netcdf.MemoryWriter(*schema)
        _compute(plan, range(plan.n_chunks), threads, executor, progress, 0, writer.write)
        return writer.to_dataset()

    output = Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    parts = _Parts(output, plan, resume)
    done = [k for k in range(plan.n_chunks) if parts.is_done(k)]
    todo = [k for k in range(plan.n_chunks) if k not in set(done)]
    n_done = sum(plan.chunk_range(k)[1] - plan.chunk_range(k)[0] for k in done)

    def save(start, stop, arrays):
        parts.save(start // plan.chunk_size, arrays)

    try:
        _compute(plan, todo, threads, executor, progress, n_done, save)
    except KeyboardInterrupt:
        saved = sum(1 for k in range(plan.n_chunks) if parts.path(k).exists())
        sys.stderr.write(
            f"\ninterrupted: {saved} of {plan.n_chunks} chunks are saved in {parts.dir}; run again with "
            "resume=True (--resume) to finish\n"
        )
        raise
    writer = _netcdf.NetCDFWriter(output, *schema)
    try:
        for k in range(plan.n_chunks):
            writer.write(*plan.chunk_range(k), parts.load(k))
    except BaseException:
        writer.abort()
        raise
    writer.close()
    parts.remove()
    return xr.open_dataset(output, engine="netcdf4")


#: Chunks handed to an executor at a time: executors submit everything they are given at once, so
#: the tasks (each with its points' parameters) are fed in windows to keep memory bounded.
EXECUTOR_WINDOW: int = 256


def _windowed_map(executor, plan: _Plan, chunks: list[int], threads):
    for i in range(0, len(chunks), EXECUTOR_WINDOW):
        window = chunks[i : i + EXECUTOR_WINDOW]
        yield from executor.map(_run_task, [plan.task(k, threads) for k in window])


def _compute(plan: _Plan, chunks, threads, executor, progress: bool, n_done: int, sink) -> None:
    """Run ``chunks`` and hand each result to ``sink(start, stop, arrays)`` in order."""
    chunks = list(chunks)
    bar = _Progress(progress, plan.n_points, n_done)
    try:
        if executor is None:
            # Looked up at call time (not bound at import) so that tests can patch it.
            results = (_chunk.compute_chunk(*plan.task(k, threads)) for k in chunks)
        else:
            results = _windowed_map(executor, plan, chunks, threads)
        for k, res in zip(chunks, results):
            if hasattr(res, "result"):  # dask futures
                res = res.result()
            start, stop = plan.chunk_range(k)
            sink(start, stop, res)
            bar.update(stop - start)
    finally:
        bar.close()
