"""Settings of the analyses, typed once: the one home of every default and its range check.

Each group is a frozen dataclass whose fields are checked on construction (a bad value raises
``ValueError`` naming the argument as the user knows it, its value and the valid range). The
public functions (:func:`tribosweep.sweep`, :func:`tribosweep.census`, :func:`tribosweep.ensemble`
...) take flat keyword arguments whose defaults are read from here, build these objects, and pass
them down; a sweep chunk receives them as plain data (:meth:`SweepSettings.to_options`, the JSON
form written to the resume manifest and to the netCDF ``solver_*`` attributes) and rebuilds them
with :meth:`SweepSettings.from_options`.

Groups:

:class:`Integration`  the time integrator and its tolerances
:class:`Steady`       a run to steady state (how long, when it repeats, when it has decayed)
:class:`Shooting`     the sweep's describing-function and shooting stages
:class:`Census`       the attractor census (disturbances per point, their size, their run time)
:class:`Irregular`    the measurement of sustained irregular motion (window, spectrum, FTLE)
:class:`SweepSettings` all of the above plus the sweep's disturbance and wear reference
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from . import _checks

#: Time integrators of the core (``tribosweep._core.method_names()``).
INTEGRATORS: tuple[str, ...] = _checks.METHODS
#: Initial disturbance of transient runs: ``z = 1 um`` off steady sliding (docs/model.md §5).
DEFAULT_Y0: tuple[float, ...] = (1e-6, 0.0, 0.0, 0.0, 0.0, 0.0)


def _count(name: str, value, low: int, high: int = 1_000_000) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise ValueError(f"{name} = {value!r} is out of range: must be an integer in [{low}, {high}]")
    return int(value)


def _set(obj, name: str, value) -> None:
    object.__setattr__(obj, name, value)  # frozen dataclasses normalise their fields in __post_init__


@dataclass(frozen=True)
class Integration:
    """Time integration of every run.

    Parameters
    ----------
    integrator : {"dop853", "dopri5", "rodas4"}
        DOP853 by default: on the unilateral (impacting) transients it is about twice as fast as
        Dopri5 at rtol 1e-8 and about 7x more accurate (the work-precision charts of
        ``tribosweep bench``).
    rtol : float
        Relative tolerance, in (0, 1).
    atol : float or 6 floats, optional
        Absolute tolerance per state component (default: ``rtol`` times each component's
        characteristic size).
    """

    integrator: str = "dop853"
    rtol: float = 1e-8
    atol: tuple[float, ...] | None = None

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator = {self.integrator!r} is not valid: must be one of {INTEGRATORS}")
        _set(self, "rtol", _checks.rtol(self.rtol))
        a = _checks.atol(self.atol)
        _set(self, "atol", None if a is None else tuple(float(x) for x in a))


@dataclass(frozen=True)
class Steady:
    """A run to steady state.

    Parameters
    ----------
    t_max : float, s
        Longest simulated time (100: near a Hopf point the growth rate is small, 0.07 1/s at
        10 N and 7.6 cm, and a run costs about 2.5 ms of wall time per simulated second).
    periodic_tol : float
        Relative repetition tolerance of the Poincare-section state that declares a cycle.
    decay_amplitude : float, m, optional
        Amplitude below which a motion has decayed (default ``1e-3 |z_st|``).
    approach_periods : int
        ``auto`` transients: periods per block of the slow-approach test. Once the largest
        repetition residual of the section state (``x`` left out: the check shoots on the whole
        state) over a block has shrunk three blocks in a row,
        to at most 1e-3 (the core's ``APPROACH_TOL``), the run shoots from there, inside the run:
        a stable orbit of that period ends it, measured on the orbit (verified); near an unstable
        one it goes on with a hold, and where shooting fails, on without the test. 0: every run
        waits for the repetition to ``periodic_tol``. A cycle whose slowest multiplier is 0.993
        (the lightly damped ``x`` mode under speed-dependent friction) takes some 660 periods
        from a repetition to 1e-3 to one to 1e-5. Measured (2026-11-28): the Stribeck sweep at
        491-508 -> 563-578 points/s (switch law, right-hand sides -14 %; tanh law -11 %, 443 ->
        448), the 2,000-point grid's transients 1.52 -> 1.18 s, no regime changed.
    rtol : float
        Relative tolerance of the transients (``transient_rtol``, 1e-6; the integrator is
        ``integrator``'s), in (0, 1). A transient finds which attractor a point reaches; it does
        not measure it: a cycle it stops on is converged by shooting and measured on the orbit at
        the checks' tolerance (ten times tighter than ``rtol``, 1e-9 by default), and irregular
        motion is measured over a window on the exponent's runs (``ftle_rtol``), so the
        tolerance here sets no reported number, only where a chaotic transient happens to end
        (as the census's ``census_rtol``).
        On the issue-10 Stribeck sweep (``python benches/bench_stribeck.py --settings``,
        2026-11-29) no regime at 1e-6 differs from the reference (every transient to ``t_max``
        at 1e-10; it differs from itself at +-1 % in 1-2), at 0.73x the right-hand sides of 1e-8,
        and the cycles' median amplitude error is 2.2e-9 (1.1e-8 when everything ran at 1e-8).
    """

    t_max: float = 100.0
    periodic_tol: float = 1e-5
    decay_amplitude: float | None = None
    approach_periods: int = 10
    rtol: float = 1e-6

    def __post_init__(self):
        try:
            _set(self, "rtol", _checks.rtol(self.rtol))
        except ValueError as e:
            raise ValueError(str(e).replace("rtol", "transient_rtol", 1)) from None
        _set(self, "t_max", _checks.positive("t_max", self.t_max))
        _set(self, "periodic_tol", _checks.positive("periodic_tol", self.periodic_tol))
        _set(self, "approach_periods", _checks.approach_periods("approach_periods", self.approach_periods))
        if self.decay_amplitude is not None:
            _set(self, "decay_amplitude", _checks.positive("decay_amplitude", self.decay_amplitude))


@dataclass(frozen=True)
class Shooting:
    """The sweep's describing-function and shooting stages.

    Parameters
    ----------
    rtol : float
        Integration tolerance of the shooting runs (1e-10: the orbit's ``A1`` is compared with
        the describing function's to a few 1e-3, and the monodromy matrix needs a few more digits).
    tol : float
        Newton tolerance of the shooting residual (relative).
    tidf_grid : int
        Frequencies of the describing function's root search in 150-3000 rad/s.
    """

    rtol: float = 1e-10
    tol: float = 1e-8
    tidf_grid: int = 1000

    def __post_init__(self):
        try:
            _set(self, "rtol", _checks.rtol(self.rtol))
        except ValueError as e:
            raise ValueError(str(e).replace("rtol", "shooting_rtol", 1)) from None
        _set(self, "tol", _checks.positive("shooting_tol", self.tol))
        _set(self, "tidf_grid", _count("tidf_grid", self.tidf_grid, 16))


def stop_tol(name: str, value) -> float | None:
    """A census's first-stop tolerance: a relative repetition of the section state in (0, 0.1], or
    None (the friction law's default, :func:`tribosweep._census.first_stop_tol`)."""
    if value is None:
        return None
    v = _checks.positive(name, value)
    if v > 0.1:
        raise ValueError(f"{name} = {value!r} is out of range: must be in (0, 0.1] (a relative repetition of the "
                         "section state)")
    return v


@dataclass(frozen=True)
class Census:
    """The attractor census (:func:`tribosweep.census`).

    Parameters
    ----------
    enabled : bool
        ``auto`` sweeps take it at stable points with a saddle cycle.
    samples : int
        Disturbances per point ``K`` in [1, 100000]; fractions carry ``sqrt(p (1 - p) / K)``.
    t_max : float, s
        Longest simulated time of one disturbance (30).
    disturbance_scale : float
        Largest modal amplitude of a disturbance in units of ``|z_st|``, the size at which the
        contact opens (3: at the seed the saddle cycle's A1 is 1.35 |z_st| and the bouncing
        cycle's 1.43 |z_st|, so the box reaches past both).
    rtol : float
        Relative tolerance of the disturbances' runs (1e-6). A census reports where each
        disturbance goes, not its path: on the default grid (361 censused points, K = 16) the
        labels at rtol 1e-6 agree with those at 1e-10 for 98.3-98.5 % of the samples (98.6-98.8 % at 1e-8;
        the rest are boundary samples, whose fate is a coin toss at any tolerance), no point's
        fraction moves by 2 standard errors, and the census costs 0.78-0.86x that at 1e-8
        (``benches/bench_census.py --rtol``).
    stop_tol : float, optional
        The repetition tolerance at which a sample after its point's two pilots first stops on a
        cycle; every such stop is shot from, and the sample is on the stable orbit shooting
        converges to, measured there, or goes on from its stop at ``periodic_tol`` (see
        ``tribosweep._census``; ``x`` and ``xd`` need only repeat to ten times it). None
        (default): 1e-3 under speed-dependent friction, where the lightly damped ``x`` mode
        (multiplier 0.993 per period) holds a repetition to ``periodic_tol`` back by seconds (the
        switch-law Stribeck sweep's census 0.77-0.84x the time, no fraction moving by more than
        1 standard error); ``periodic_tol`` (no first stops) under constant friction, whose census compares the fast components only and settles within
        a few periods (the 2,000-point grid took 42.0 s with first stops at 1e-3, against 36.7 s).
    recurrence : bool
        Let the samples after each point's two pilots stop as irregular once they keep to an
        irregular attractor a pilot established: 32 sections in a row in its cells, or one block
        of sections that matches its statistics (True; see ``tribosweep._census``): on the default
        grid 0.70x the right-hand sides, 12 of 5,776 labels changed (``benches/bench_census.py
        --recurrence``). False: each sample decides by its own blocks.

    Notes
    -----
    Near a Hopf point a disturbance decays at 0.07 1/s; such a slow approach is reported as
    ``irregular`` by ``t_max`` (say so when reading fractions there).
    """

    enabled: bool = True
    samples: int = 32
    t_max: float = 30.0
    disturbance_scale: float = 3.0
    rtol: float = 1e-6
    recurrence: bool = True
    stop_tol: float | None = None

    def __post_init__(self):
        _set(self, "enabled", bool(self.enabled))
        if not isinstance(self.recurrence, (bool, np.bool_)):
            raise ValueError(f"census_recurrence = {self.recurrence!r} is not valid: must be true or false")
        _set(self, "recurrence", bool(self.recurrence))
        if isinstance(self.samples, bool) or not isinstance(self.samples, (int, np.integer)) or not (
            1 <= self.samples <= 100_000
        ):
            raise ValueError(
                f"samples = {self.samples!r} is out of range: must be an integer in [1, 100000] (disturbances per point)"
            )
        _set(self, "samples", int(self.samples))
        _set(self, "t_max", _checks.positive("census_t_max", self.t_max))
        _set(self, "disturbance_scale", _checks.positive("disturbance_scale", self.disturbance_scale))
        _set(self, "stop_tol", stop_tol("census_stop_tol", self.stop_tol))
        try:
            _set(self, "rtol", _checks.rtol(self.rtol))
        except ValueError as e:
            raise ValueError(str(e).replace("rtol", "census_rtol", 1)) from None


@dataclass(frozen=True)
class Irregular:
    """Sustained irregular motion: when a run stops as such, and its measurement (:mod:`tribosweep._irregular`).

    Parameters
    ----------
    block : int
        Sections per block of the stationarity test (256; 0: off) of the census's disturbances
        (the ``auto`` transients' is ``transient_block``). A run in bounded motion that neither repeats nor decays stops
        as irregular once three consecutive blocks of Poincare sections agree: the mean distance of
        each section state to the nearest of the 8 before it within 25 % (and above
        ``max(100 periodic_tol, 1e-3)`` of the characteristic sizes), and the largest excursion of
        each component within 5 % or, where chaotic motion spreads it more, drifting by less than
        5 % per two blocks (a least-squares line through its eight sub-blocks' largest excursions
        per block). Off, it runs to ``t_max`` (``census_t_max`` in the census).
    transient_block : int
        The same for the ``auto`` transients (128; 0: off). Half the census's: on the issue-10
        Stribeck sweep (``python benches/bench_stribeck.py --settings [--law coulomb]``, 2026-11-27)
        the transients' regimes at 128 agree with runs to ``t_max`` at rtol 1e-10 as at 256 (0 of
        200 differ under either law; the reference differs from itself at rtol +-1 % in 2), at
        1.15x the points per second (478 against 414 switch law, 454 against 393 coulomb). The
        census keeps 256: its later samples stop by recurrence on the pilots' attractors anyway
        (128 is no cheaper there), and at 128 twice as many of its labels differ from runs to
        ``t_max`` (124 against 74 of 5,776 on the default grid, ``python benches/bench_census.py
        --compare --blocks 128,256 --sweep-points 0``).
    window : float, s
        Window after the transient (0.5: about 50 torsion periods; the spectrum's bins are
        12.6 rad/s apart and the parabola refines the peak well within one).
    sample_dt : float, s
        Sampling interval of the window (1e-4: about 100 samples per torsion period).
    ftle_tau : float, s
        Segment of the largest finite-time Lyapunov exponent (0.05: about 5 torsion periods).
    ftle_segments : int
        Segments averaged at most (40, >= 2).
    ftle_min_segments : int
        Segments averaged at least (10, >= 2; ``ftle_segments`` where that is fewer): a point
        whose exponent is then 5 standard errors or more from 0 (clearly chaotic) stops, the
        others run on until it is or ``ftle_segments`` are done. ``ftle_min_segments >=
        ftle_segments``: every point runs them all, as before 2026-11-26.
    ftle_warmup : int
        Segments run first and not averaged (2, >= 0: the separation turns into the most
        unstable direction; 4 until 2026-11-29, see ``ftle_rtol``).
    ftle_d0 : float
        Separation of the two trajectories in units of the characteristic sizes (1e-8, < 1e-3).
    ftle_rtol : float
        Relative tolerance of the exponent's runs (1e-7; 1e-11, then 1e-9, until 2026-11-29):
        two runs ``ftle_d0`` apart take the same steps, so their step errors cancel in the
        separation. Chosen on replicates (:mod:`tribosweep._irregular`, ``python
        benches/bench_stribeck.py --ftle``): the Stribeck sweep's 31 exponents, each the mean of
        8 runs along its attractor, agree with those at 1e-11 within 1.8 combined replicate
        standard errors at 1e-7 with ``ftle_warmup`` 2, against 3.2 at 1e-9 (the reference's
        own two halves: 2.7).
    """

    block: int = 256
    transient_block: int = 128
    window: float = 0.5
    sample_dt: float = 1e-4
    ftle_tau: float = 0.05
    ftle_segments: int = 40
    ftle_min_segments: int = 10
    ftle_warmup: int = 2
    ftle_d0: float = 1e-8
    ftle_rtol: float = 1e-7

    def __post_init__(self):
        try:
            rt = _checks.rtol(self.ftle_rtol)
        except ValueError as e:
            raise ValueError(str(e).replace("rtol", "ftle_rtol", 1)) from None
        _set(self, "ftle_rtol", rt)
        _set(self, "block", _checks.block("irregular_block", self.block))
        _set(self, "transient_block", _checks.block("transient_irregular_block", self.transient_block))
        _set(self, "window", _checks.positive("irregular_window", self.window))
        _set(self, "sample_dt", _checks.positive("irregular_sample_dt", self.sample_dt))
        _set(self, "ftle_tau", _checks.positive("ftle_tau", self.ftle_tau))
        _set(self, "ftle_segments", _count("ftle_segments", self.ftle_segments, 2))
        _set(self, "ftle_warmup", _count("ftle_warmup", self.ftle_warmup, 0))
        _set(self, "ftle_min_segments", _count("ftle_min_segments", self.ftle_min_segments, 2))
        d0 = _checks.positive("ftle_d0", self.ftle_d0)
        if not d0 < 1e-3:
            raise ValueError(f"ftle_d0 = {self.ftle_d0!r} is out of range: must be in (0, 1e-3) (a separation small "
                             "enough to stay linear)")  # fmt: skip
        _set(self, "ftle_d0", d0)
        if self.window < 16 * self.sample_dt:
            raise ValueError(f"irregular_window = {self.window!r} is out of range: must be at least 16 "
                             f"irregular_sample_dt = {16 * self.sample_dt:g} s (a spectrum needs samples)")  # fmt: skip


def disturbance(value) -> tuple[float, ...]:
    """A transient's initial state from a ``z`` offset [m] or a full state (default ``DEFAULT_Y0``)."""
    if value is None:
        return DEFAULT_Y0
    if np.ndim(value) == 0:
        z0 = float(value)
        if not math.isfinite(z0):
            raise ValueError(f"disturbance = {value!r} must be finite: a z offset [m] or a state of 6 values")
        return (z0, 0.0, 0.0, 0.0, 0.0, 0.0)
    return tuple(float(x) for x in _checks.state("disturbance", value))


#: Keys of the flat options (JSON) form, in the order they are written, with their group and field.
_FLAT: tuple[tuple[str, str, str], ...] = (
    ("t_max", "steady", "t_max"),
    ("integrator", "integration", "integrator"),
    ("rtol", "integration", "rtol"),
    ("atol", "integration", "atol"),
    ("periodic_tol", "steady", "periodic_tol"),
    ("approach_periods", "steady", "approach_periods"),
    ("transient_rtol", "steady", "rtol"),
    ("decay_amplitude", "steady", "decay_amplitude"),
    ("census", "census", "enabled"),
    ("samples", "census", "samples"),
    ("census_t_max", "census", "t_max"),
    ("disturbance_scale", "census", "disturbance_scale"),
    ("census_rtol", "census", "rtol"),
    ("census_recurrence", "census", "recurrence"),
    ("census_stop_tol", "census", "stop_tol"),
    ("unstable_disturbance", "", "unstable_disturbance"),
    ("irregular_block", "irregular", "block"),
    ("transient_irregular_block", "irregular", "transient_block"),
    ("irregular_window", "irregular", "window"),
    ("irregular_sample_dt", "irregular", "sample_dt"),
    ("ftle_tau", "irregular", "ftle_tau"),
    ("ftle_segments", "irregular", "ftle_segments"),
    ("ftle_min_segments", "irregular", "ftle_min_segments"),
    ("ftle_warmup", "irregular", "ftle_warmup"),
    ("ftle_d0", "irregular", "ftle_d0"),
    ("ftle_rtol", "irregular", "ftle_rtol"),
    ("shooting_rtol", "shooting", "rtol"),
    ("shooting_tol", "shooting", "tol"),
    ("tidf_grid", "shooting", "tidf_grid"),
    ("y0", "", "y0"),
)


@dataclass(frozen=True)
class SweepSettings:
    """Everything a sweep point's analysis depends on besides the model and the grid.

    ``wear`` is the reference point of the relative wear rate as plain data (``normal_load``,
    ``sliding_speed``, ``frequency_hz``, optional ``calibration``); ``threads`` is how many Rust
    threads a chunk uses (results do not depend on it, so it is not part of :meth:`to_options`).
    """

    integration: Integration = field(default_factory=Integration)
    steady: Steady = field(default_factory=Steady)
    shooting: Shooting = field(default_factory=Shooting)
    census: Census = field(default_factory=Census)
    irregular: Irregular = field(default_factory=Irregular)
    y0: tuple[float, ...] = DEFAULT_Y0
    unstable_disturbance: float = 1.0
    wear: Mapping | None = None
    threads: int | None = None

    def __post_init__(self):
        _set(self, "unstable_disturbance", _checks.positive("unstable_disturbance", self.unstable_disturbance))
        _set(self, "y0", disturbance(self.y0))

    @classmethod
    def from_flat(cls, **kw) -> SweepSettings:
        """From the flat keyword names of :func:`tribosweep.sweep` (``rtol``, ``census_t_max``, ...)."""
        groups: dict[str, dict] = {"integration": {}, "steady": {}, "shooting": {}, "census": {}, "irregular": {}}
        top = {}
        for key, group, name in _FLAT:
            if key in kw:
                (groups[group] if group else top)[name] = kw.pop(key)
        for key in ("wear", "threads"):
            if key in kw:
                top[key] = kw.pop(key)
        if kw:
            raise TypeError(f"unknown settings {sorted(kw)}")
        return cls(
            integration=Integration(**groups["integration"]), steady=Steady(**groups["steady"]),
            shooting=Shooting(**groups["shooting"]), census=Census(**groups["census"]),
            irregular=Irregular(**groups["irregular"]), **top,
        )  # fmt: skip

    def to_options(self) -> dict:
        """The flat, JSON-serialisable form (resume manifest and netCDF ``solver_*`` attributes)."""
        out = {}
        for key, group, name in _FLAT:
            v = getattr(getattr(self, group) if group else self, name)
            out[key] = list(v) if isinstance(v, tuple) else v
        out["wear"] = None if self.wear is None else dict(self.wear)
        return out

    @classmethod
    def from_options(cls, options: Mapping) -> SweepSettings:
        """Rebuild from :meth:`to_options` (plus an optional ``threads``)."""
        kw = {k: v for k, v in options.items() if k != "wear"}
        if kw.get("atol") is not None:
            kw["atol"] = tuple(kw["atol"])
        if "y0" in kw:
            kw["y0"] = tuple(kw["y0"])
        return cls.from_flat(**kw, wear=options.get("wear"))

    def replace(self, **changes) -> SweepSettings:
        return dataclasses.replace(self, **changes)


#: The defaults, for signatures that restate none of them.
DEFAULTS = SweepSettings()
