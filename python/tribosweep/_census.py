"""Attractor census (basin stability): what a point does after many disturbances, as fractions.

One run from one start cannot say how likely each outcome is, and where the basins of the
impacting motion are intertwined its verdict flips with the last bit of a float (a different
libm, BLAS kernel or rtol). The census runs ``K`` disturbances per point to their attractors and
reports the fraction that reaches each, with its binomial standard error (Menck et al., Nature
Physics 9, 2013). A flipped trajectory then moves a fraction by ``1/K`` instead of flipping a verdict.

The disturbances (documented distribution)
    Each sample is a start on the two modes that matter at a point, from steady sliding::

        y0 = Re(a_t e^{i theta_t} v_t + a_n e^{i theta_n} v_n)

    ``v_t``, ``v_n``: the torsion-dominated and the normal mode of the linearisation, scaled to
    ``z = 1``; ``a_t, a_n`` uniform in ``[0, scale |z_st|)``; ``theta`` uniform in ``[0, 2 pi)``.
    The torsion mode is the one that self-excites (the saddle cycle and the bouncing cycle lie
    along it); the heavily damped normal mode adds a disturbance in ``z`` alone. ``x`` does not act
    back on ``z`` and ``phi`` under constant friction; it starts on the modes' own ``x``.
    ``(a_t, theta_t, a_n, theta_n) / (scale |z_st|, 2 pi, scale |z_st|, 2 pi)`` is the 4-D Halton
    sequence (bases 2, 3, 5, 7, indices 1..K) shifted modulo 1 by a Cranley-Patterson rotation
    drawn from a hash of the point's own parameters (the float64 bytes of every field that enters
    the dynamics, in name order). A point's samples therefore depend on nothing but the point:
    not on chunking, threads, executor, the sweep around it, or the machine; the first ``K`` of
    a larger census are the same samples.

What each sample reaches (``ATTRACTOR_NAMES``)
    ``sliding`` (decayed), ``cycle`` (a periodic state; cycles are told apart by period
    multiplicity, frequency and first-harmonic amplitude within ``CYCLE_TOL``; each distinct
    cycle of a point is then checked by shooting from its first sample's stop: where it is an
    unstable orbit, its samples had stopped near it (close to a saddle, or lingering in irregular
    motion) and go on with the time they have left, :class:`tribosweep._cycles.CensusCheck`;
    the largest cycle's ``largest_cycle_*`` are measured on its converged orbit), ``irregular``
    (bounded, neither periodic nor decaying, and stationary over three blocks of sections, or still
    so at ``t_max``: quasi-periodic or chaotic bouncing, or an approach slower than ``t_max``),
    ``escape`` (``|z|`` past the escape limit: outside the model's validity). A sample whose
    integration failed is counted apart (``census_failed``) and left out of the fractions.

Early stops
    A cycle stops once its section state has repeated to ``periodic_tol`` twice. Under constant
    friction the test compares ``(z, zd, phi, phid)`` only: ``x`` and ``xd`` are slaved (nothing in
    the ``z`` and ``phi`` equations depends on them), so they cannot change which attractor is
    reached, while their own ring-down (``zeta_x omega_x``, about 1 1/s) would hold a cycle's
    recognition back by some 10 s. The same holds for the decay test. A sample at a
    stable point with a saddle cycle stops as ``sliding`` once its motion is below
    ``RETURN_FRACTION`` (0.4) of the saddle's own first-harmonic amplitude in every component
    (``A1`` for z, ``omega A1`` for zd, ``phi1`` for phi...; capped at ``|z_st|/2`` in z) and
    shrinking (the largest over a window of 8 sections below the 8 before): the pin is then on the
    disk, the law is the smooth bilateral one, and the motion is well inside the saddle cycle that
    bounds sliding's basin in the normal-form (centre-manifold) picture of the subcritical Hopf
    point (:func:`return_thresholds`). This is not a proof for the full 6-D state; the strict
    quadratic-Lyapunov ball of the linearisation is about a thousand times smaller at the seed
    (the torsion mode's damping margin is 0.33 1/s against nonlinear rates of order
    ``K_a |z| / (m w)``), so it would not stop anything earlier. The fraction was 0.2 until
    2026-11-26; at 0.4 (a margin of 2.5 in amplitude; the cap binds first at the seed, at 0.385)
    the default sweep's 361 censused points at K = 16 change 12 labels of 5,776, each from a
    bounded motion still unsettled at ``t_max`` = 30 s to ``sliding``; run on to 120 s at 0.2,
    all 12 return to sliding (at 31-61 s). No other label moves, and the simulated time falls by
    7 % (28,285 -> 26,200 s). 0.5 saves 1 % more.

    Sustained irregular motion stops once its section statistics are stationary
    (``irregular_block`` sections per block, 256 by default; 0 runs it to ``t_max``): over three
    consecutive blocks the mean distance of each section state to the nearest of the 8 before it
    (zero on any cycle of multiplicity up to 8, so an approach to a cycle shrinks it block after
    block) agrees within 25 % and stays above ``max(100 periodic_tol, 1e-3)`` (in characteristic
    sizes: a cycle that cannot repeat to a tight ``periodic_tol`` is not irregular), and each
    component's largest excursion agrees within 5 % (a slow decay or growth shows there) or,
    where chaotic motion spreads it more, drifts by less than 5 % per two blocks (a least-squares
    line through the largest excursions of the blocks' eight sub-blocks each).
    Measured on the default sweep's 361 censused points at K = 16 (5,776 samples,
    ``benches/bench_census.py --compare``, 2026-11-26), the simulated time falls from 65,281 s to
    26,200 s and 59 labels (1.0 %) differ from runs to ``t_max`` = 30 s: 46 cycles and 13 returns
    to sliding that came after a chaotic transient longer than the three blocks (about 6 s at
    130 Hz) are reported ``irregular``; no sample escapes either way. A transient's lifetime has no
    upper bound, so ``t_max`` = 30 s draws the same line later, not more truly.

    Recurrence on a known attractor (the idea of Attractors.jl's recurrence method: a trajectory
    that keeps visiting an attractor already found is on it). The first ``PILOTS`` (2) samples of
    each point run first, with the stationarity test alone. Each one that ends irregular leaves its
    fingerprint: the mean residual and each component's largest excursion over its three blocks,
    and the cells of state space its sections visited over them (a 24^3 grid over the bounding box
    of ``(z, phi, phid)`` on the section, each visited cell and its neighbours marked). The other
    samples then also stop as ``irregular`` once 32 sections in a row fall in a pilot's cells with
    a mean residual of at least half the pilot's (and above the floor: a cycle approached through
    the cells does not match), or on one block of their own that matches a fingerprint's statistics
    within the same tolerances (25 % and 5 %). The pilots are fixed samples of the point, so this
    depends on nothing but the point. ``recurrence=False`` (or ``irregular_block=0``) turns it off.
    Measured on the default sweep's 361 censused points at K = 16 (``python benches/bench_census.py
    --recurrence --sweep-points 0``, 2026-11-26): the simulated time falls from 25,640 s to
    18,637 s (right-hand sides 0.70x; 1,098 samples stop by recurrence, median 1.1 s); 12 of 5,776
    labels change (7 cycles and 5 returns to sliding that came after a chaotic transient are
    reported ``irregular``), no point's fraction moves by 2 standard errors. The block match alone
    gave 20,617 s and 6 labels; the cells cut the grid's census right-hand sides by a further
    11 % and the 2,000-point sweep from 6.5-6.7 s to 5.6-5.8 s on this (busier) machine. Against
    runs to ``t_max`` = 30 s (``--compare``): 79 labels differ (73 with the block match alone), 5
    points move by more than 2 standard errors and 4 by more than 3 (4 and 2): the cells stop more
    samples that shadow a pilot's chaotic motion for a while before settling, a chaotic transient
    longer than the recurrence window. 128 sections in a row: 77 labels, 5 and 3 points, 3 % more
    simulated time; 64: the same labels as 32, 1.5 % more. A third phase
    (``PHASE_STARTS = (0, 2, 6)``: samples 2-5 establishing attractors for the rest, block match
    only) saved 9 % more right-hand sides but relabelled 19 samples instead of 3 (13 cycles, 5
    returns to sliding), 9 points moving by 2 standard errors against runs to ``t_max``: where the
    pilots are not irregular, irregular motion is rarer and more often a long transient, whose
    fingerprint then stops samples that would have settled. Not kept. Nor were pilots chosen by
    size (the two largest torsion amplitudes of the first 8 samples, 2026-11-26): they find
    irregular motion at 210 of the 246 grid points that have any, against 168, and cut the right-hand
    sides to 0.642x of the own-test census instead of 0.702x, but relabel 44 samples instead of 12
    (large disturbances more often start with a chaotic transient). A looser ``periodic_tol`` for
    the census (1e-4) saves 7 % of the simulated time but turns 32 slowly decaying samples and 67
    irregular ones into cycles.

    First stops (speed-dependent friction, :func:`first_stop_tol`): the samples after the pilots
    stop on a cycle once their section state repeats to 1e-3, and every such stop is shot from
    (:meth:`tribosweep._cycles.CensusCheck.resolve`): a stable orbit of its period is the
    sample's cycle, measured on the orbit; the others go on, repeating to ``periodic_tol``.
    Those first stops hold ``x`` and ``xd`` to ten times ``stop_tol`` only (the core's
    ``checked_stops``): shooting converges on the whole state, and the friction mode's slow
    ring-down no longer holds the trigger back (the Stribeck sweep's census 8.2 -> 7.6 s).

    Re-measured after the first-step rule of the integrators (``ModeSteps``, 2026-11-26): the
    simulated time with recurrence 18,467 s (25,612 s without); 10 labels differ from the
    own-test census (28 at rtol 1.01e-6, against 11-16 for the previous build), 72 from runs to
    ``t_max`` (66-83 for the previous build), and one point's fraction moves by more than 3
    standard errors against runs to ``t_max`` (2-4 before).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping

import numpy as np

from . import _core
from . import _cycles as cyc
from ._codes import ATTRACTOR_NAMES, OUTCOME_NAMES, STATUS, STATUS_NAMES
from ._irregular import characteristic_sizes
from ._modes import jacobians, mode_shape
from ._modes import mode_shape_numeric as _mode_shape_numeric
from ._modes import static as _static
from ._settings import DEFAULTS
from ._settings import stop_tol as _stop_tol

#: Steady-state outcome name -> attractor index (-1: failed, left out of the fractions).
_ATTRACTOR_OF: dict[str, int] = {"decayed": 0, "periodic": 1, "unsettled": 2, "diverged": 3, "failed": -1,
                                 "irregular": 2}

#: Relative tolerance within which two cycles (same period multiplicity) are the same: frequency,
#: and the first three harmonic amplitudes of z in units of the motion (:func:`_cycles.cluster`).
CYCLE_TOL: float = 1e-2
#: A returning sample stops once its motion is below this fraction of the saddle cycle's A1 (and
#: half of |z_st|), and shrinking.
RETURN_FRACTION: float = 0.4

#: The census runs each point's samples in phases starting at these indices (then ``K``). The
#: first phase (the pilots, Halton indices 1, 2) decides by the three-block stationarity test
#: alone; each later phase also stops once it keeps to an irregular attractor an earlier phase
#: established (recurrence: in its cells, or a block matching its statistics). The phases are
#: fixed samples of the point, so nothing depends on threads, chunking or order.
PHASE_STARTS: tuple[int, ...] = (0, 2)
#: Pilots: the samples of the first phase.
PILOTS: int = PHASE_STARTS[1]
#: Most known irregular attractors a sample compares its blocks with (the core's ``KNOWN_MAX``).
KNOWN: int = 2

_HALTON_BASES = (2, 3, 5, 7)

#: Fields of the model that enter the dynamics (and so the sample's seed). ``sliding_speed``
#: enters only through the friction law's speed dependence; it is dropped for constant friction.
_SEED_FIELDS = (
    "mass", "inertia", "moment_arm", "omega_normal", "omega_friction", "omega_torsion", "zeta_normal",
    "zeta_friction", "zeta_torsion", "contact_stiffness", "contact_quadratic", "contact_damping",
    "twist_coupling", "mu", "normal_load", "sliding_speed", "torsion_sign", "friction_regularization",
    "mu_static", "stribeck_velocity", "escape_limit",
)  # fmt: skip


def halton(n: int, base: int) -> np.ndarray:
    """Radical-inverse (van der Corput) sequence in ``base`` at indices ``1..n``, exact to rounding.

    Examples
    --------
    >>> halton(4, 2).tolist()
    [0.5, 0.25, 0.75, 0.125]
    """
    out = np.zeros(n)
    idx = np.arange(1, n + 1, dtype=np.int64)
    f = 1.0
    while np.any(idx):
        f /= base
        out += f * (idx % base)
        idx //= base
    return out


def point_shift(values: Mapping[str, float], friction_law: str) -> np.ndarray:
    """Cranley-Patterson shift (4 numbers in ``[0, 1)``) from the point's own parameters.

    The hash reads the IEEE float64 bytes (little-endian) of every field in ``_SEED_FIELDS``
    present in ``values``, in that order, so it is the same on every machine.
    """
    h = hashlib.blake2b(digest_size=32)
    h.update(friction_law.encode())
    for k in _SEED_FIELDS:
        if k == "sliding_speed" and friction_law == "constant":
            continue
        if k in values:
            h.update(k.encode())
            h.update(np.asarray(values[k], dtype="<f8").tobytes())
    words = np.frombuffer(h.digest(), dtype="<u8")
    return (words >> np.uint64(11)).astype(np.float64) / float(2**53)


def starts(
    full: Mapping[str, np.ndarray], friction_law: str, samples: int, scale: float, eigenvalues: np.ndarray
) -> np.ndarray:
    """Start states ``(n, samples, 6)`` of the census of ``n`` points (see the module docstring).

    ``full`` holds every model field per point (arrays of length ``n``); ``eigenvalues`` is the
    core's ``(n, 6)`` array in the order friction, torsion, normal (pairs, +Im first).
    """
    n = eigenvalues.shape[0]
    v = {k: np.broadcast_to(np.asarray(full[k], dtype=np.float64), (n,)) for k in full}
    lam_t, lam_n = eigenvalues[:, 2], eigenvalues[:, 4]
    if friction_law == "constant":
        vt, vn = mode_shape(v, lam_t), mode_shape(v, lam_n)
    else:
        j = jacobians(v, friction_law)
        vt, vn = _mode_shape_numeric(j, lam_t), _mode_shape_numeric(j, lam_n)
    z_abs = np.abs(_static(v)[0])
    u = np.column_stack([halton(samples, b) for b in _HALTON_BASES])  # (K, 4)
    y0 = np.empty((n, samples, 6))
    for i in range(n):
        shift = point_shift({k: v[k][i] for k in _SEED_FIELDS if k in v}, friction_law)
        w = np.mod(u + shift, 1.0)
        amp = scale * z_abs[i]
        ct = amp * w[:, 0] * np.exp(2j * np.pi * w[:, 1])
        cn = amp * w[:, 2] * np.exp(2j * np.pi * w[:, 3])
        y0[i] = (ct[:, None] * vt[i] + cn[:, None] * vn[i]).real
    return y0


#: Per-point census output: name -> (dtype, units or None, long name, has the attractor dimension).
CENSUS_VARIABLES: dict[str, tuple[str, str | None, str, bool]] = {
    "basin_fraction": ("f8", "1", "fraction of the census disturbances that reach each attractor", True),
    "basin_fraction_se": ("f8", "1", "binomial standard error of basin_fraction, sqrt(p (1 - p) / K)", True),
    "basin_fraction_low": ("f8", "1", "lower end of the 95 % Wilson score interval of basin_fraction", True),
    "basin_fraction_high": ("f8", "1", "upper end of the 95 % Wilson score interval of basin_fraction", True),
    "basin_stability": ("f8", "1", "fraction of the census disturbances that return to steady sliding", False),
    "n_attractors": ("i8", "1", "coexisting attractors seen by the census: sliding, each distinct cycle, irregular "
                     "motion (-1: no census)", False),
    "n_cycles": ("i8", "1", "distinct periodic cycles the census found (-1: no census)", False),
    "census_samples": ("i8", "1", "census disturbances counted in the fractions (0: no census)", False),
    "census_failed": ("i8", "1", "census disturbances whose integration failed (left out of the fractions)", False),
    "largest_cycle_omega": ("f8", "rad s-1", "angular frequency of the census cycle with the largest basin", False),
    "largest_cycle_a1": ("f8", "m", "first-harmonic amplitude of z of the census cycle with the largest basin",
                         False),
    "largest_cycle_period_ratio": ("f8", "1", "period of the census cycle with the largest basin in periods of the "
                                   "least stable linear mode", False),
    "largest_cycle_fraction_off_disk": ("f8", "1", "fraction of the period the pin is off the disk on the census "
                                        "cycle with the largest basin", False),
    "irregular_max_abs_z": ("f8", "m", "largest |z| reached by the census samples in irregular motion", False),
    "largest_cycle_verified": ("i1", None, "whether shooting converged the census cycle with the largest basin to a "
                               "stable orbit, on which the largest_cycle_* variables were measured", False),
}  # fmt: skip


#: Normal quantile of the basin fractions' two-sided 95 % Wilson score interval.
WILSON_Z: float = 1.959963984540054


def wilson(p: np.ndarray, n: int, z: float = WILSON_Z) -> tuple[np.ndarray, np.ndarray]:
    """Wilson score interval of binomial fractions ``p`` of ``n`` samples: ``(low, high)``.

    Where no sample (or every one) reached an attractor, ``sqrt(p (1 - p) / n)`` is 0, as if the
    fraction were known exactly; the score interval is not: ``[0, z^2 / (n + z^2)]`` (0.107 for
    K = 32), and its coverage stays near 95 % at small ``n`` and extreme ``p``.
    """
    p = np.asarray(p, dtype=np.float64)
    z2n = z * z / n
    centre = (p + 0.5 * z2n) / (1.0 + z2n)
    half = z * np.sqrt(p * (1.0 - p) / n + 0.25 * z2n / n) / (1.0 + z2n)
    return np.clip(centre - half, 0.0, 1.0), np.clip(centre + half, 0.0, 1.0)


#: Flags of ``largest_cycle_verified``.
VERIFIED_FLAGS: tuple[tuple[int, ...], tuple[str, ...]] = ((-1, 0, 1), ("no_census_cycle", "not_verified", "verified"))


def empty(n: int) -> dict[str, np.ndarray]:
    """Census output of ``n`` points that had no census."""
    k = len(ATTRACTOR_NAMES)
    out: dict[str, np.ndarray] = {}
    for name, (dtype, _u, _l, per_attractor) in CENSUS_VARIABLES.items():
        shape = (n, k) if per_attractor else (n,)
        out[name] = np.full(shape, np.nan) if dtype == "f8" else np.zeros(shape, dtype=dtype)
    out["n_attractors"][:] = -1
    out["n_cycles"][:] = -1
    out["largest_cycle_verified"][:] = -1
    return out


def run(
    model_values: Mapping[str, float],
    contact: str,
    friction_law: str,
    point_params: Mapping[str, np.ndarray],
    sel: np.ndarray,
    *,
    samples: int,
    scale: float,
    t_max: float,
    integrator: str,
    rtol: float,
    atol,
    periodic_tol: float,
    threads: int | None,
    eigenvalues: np.ndarray,
    linear_frequency: np.ndarray,
    saddle: np.ndarray | None = None,
    cycle_tol: float = CYCLE_TOL,
    irregular_block: int = DEFAULTS.irregular.block,
    recurrence: bool = True,
    shooting_rtol: float = DEFAULTS.shooting.rtol,
    shooting_tol: float = DEFAULTS.shooting.tol,
    stop_tol: float | None = DEFAULTS.census.stop_tol,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Census of the points ``sel`` of a chunk: one batched call per phase (``PHASE_STARTS``) for those
    samples of every point.

    Parameters
    ----------
    eigenvalues, linear_frequency : arrays over ``sel``
        The core's eigenvalues ``(m, 6)`` and the least stable mode's frequency of each point.
    saddle : array ``(m, 6)`` over ``sel``, optional
        The saddle cycle's first-harmonic amplitude in each component (:func:`saddle_row`) at
        stable points (NaN elsewhere): sets the early return to sliding (:func:`return_thresholds`).
    stop_tol : float, optional
        The repetition tolerance at which the samples after the pilots first stop on a cycle
        (:func:`first_stop_tol`); each such stop is then shot from
        (:meth:`tribosweep._cycles.CensusCheck.resolve`). At ``periodic_tol`` or below: the plain stops.

    Returns
    -------
    (dict, dict)
        Per-point census variables over ``sel`` (``CENSUS_VARIABLES``) and per-sample arrays
        (``outcome``, ``attractor``, ``cycle``, ``omega``, ``z1_amplitude``, ``t_end``, ``n_rhs``, ``y0``).
    """
    m = sel.size
    out = empty(m)
    names = sorted(point_params)
    n = len(next(iter(point_params.values())))
    full = {k: np.full(n, float(v)) for k, v in model_values.items()}
    for k, a in point_params.items():
        full[k] = np.asarray(a, dtype=np.float64)
    sub = {k: np.asarray(full[k])[sel] for k in full}
    y0 = starts(sub, friction_law, samples, scale, eigenvalues)  # (m, K, 6)
    values = np.column_stack([np.asarray(point_params[k], dtype=np.float64)[sel] for k in names])
    decay = return_thresholds(sub, saddle)

    base = {kk: float(v) for kk, v in model_values.items()}

    def steady(rows: np.ndarray, starts: np.ndarray, known, restart: np.ndarray | None = None,
               tol: float = periodic_tol) -> dict:  # fmt: skip
        """Runs to steady state of points ``rows`` (indices into ``sel``, one per run) from ``starts``,
        stopping on cycles that repeat to ``tol``. A looser ``tol`` than ``periodic_tol`` marks first
        stops, each of which is shot from (:meth:`tribosweep._cycles.CensusCheck.resolve`): there ``x``
        and ``xd`` need only repeat to ten times ``tol`` (the core's ``checked_stops``)."""
        return _core.ensemble(
            base, contact, friction_law, names, np.ascontiguousarray(values[rows]), np.ascontiguousarray(starts),
            float(t_max), integrator, float(rtol), atol=None if atol is None else np.asarray(atol, dtype=np.float64),
            threads=threads, kind="steady", periodic_tol=float(tol), stationary_tol=float(periodic_tol), n_fourier=512,
            decay_thresholds=np.ascontiguousarray(decay[rows]),
            watch_x=False,  # x is left out only where it is slaved (constant friction); the core decides
            irregular_block=int(irregular_block), checked_stops=bool(tol > periodic_tol),
            restart=None if restart is None else np.ascontiguousarray(restart, dtype=np.float64),
            **({} if known is None else {name: np.ascontiguousarray(a[rows]) for name, a in
                                         zip(("known_irregular", "known_cells", "known_cell_extent"), known)
                                         if a is not None}),
        )  # fmt: skip

    def batch(cols: slice, known: tuple[np.ndarray, np.ndarray, np.ndarray] | None, tol: float) -> dict[str, np.ndarray]:
        """The samples ``cols`` of every point, in one call; arrays shaped ``(m, k, ...)``."""
        k = len(range(samples)[cols])
        r = steady(np.repeat(np.arange(m), k), y0[:, cols].reshape(m * k, 6), known, tol=tol)
        return {key: np.asarray(v).reshape((m, k) + np.shape(v)[1:]) for key, v in r.items()}

    # Phases: the pilots establish each point's irregular attractors; the later samples stop as
    # soon as a block of their sections matches one (recurrence), instead of three blocks.
    # The samples after the pilots stop at stop_tol (the pilots at periodic_tol: their cycles are
    # checked as cluster heads, and their irregular runs leave the fingerprints).
    recur = irregular_block > 0 and recurrence
    loose = max(first_stop_tol(stop_tol, friction_law, periodic_tol), float(periodic_tol))
    cuts = phases(samples) if recur or loose > periodic_tol else [0, samples]
    res: dict[str, np.ndarray] = {}
    for a, b in zip(cuts[:-1], cuts[1:]):
        part = batch(slice(a, b), fingerprints(res) if res and recur else None, periodic_tol if a < PILOTS else loose)
        res = {key: _join(res[key], part[key]) for key in part} if res else part
    res = {key: np.array(v, dtype=object) if key == "reason" else v for key, v in res.items()}
    check = cyc.CensusCheck(res, cycle_tol, steady, lambda: fingerprints(res) if recur else None, float(t_max),
                            cyc.check_rtol(rtol, shooting_rtol), float(shooting_tol))  # fmt: skip

    def shoot(rows, y, p, z1, size):
        return cyc.shoot(base, contact, friction_law, names, values[rows], y, p, z1, size, rtol=check.rtol,
                         tol=check.tol, threads=threads)  # fmt: skip

    if loose > periodic_tol and samples > PILOTS:
        first = np.zeros((m, samples), dtype=bool)
        first[:, PILOTS:] = True
        check.resolve(shoot, np.flatnonzero((first & (res["outcome"] == cyc.PERIODIC)).ravel()))
    check.settle(shoot)
    outcome, status = res["outcome"], res["status"]
    attractor = np.vectorize(lambda o: _ATTRACTOR_OF[OUTCOME_NAMES[o]], otypes=[np.int64])(outcome)
    # A run that stopped at t_max is bounded motion (irregular) only if it was not a numerical failure.
    unsettled = outcome == OUTCOME_NAMES.index("unsettled")
    attractor[unsettled & (status != STATUS["not_converged"])] = -1
    omega = res["omega"]
    a1 = res["z1_amplitude"]
    mult = res["multiplicity"]
    off = res["fraction_off_disk"]
    max_z = res["max_abs_z"]
    cycle = np.full((m, samples), -1)
    k = len(ATTRACTOR_NAMES)
    largest: list[tuple[int, int]] = []
    for i in range(m):
        a = attractor[i]
        valid = a >= 0
        nv = int(valid.sum())
        out["census_samples"][i] = nv
        out["census_failed"][i] = samples - nv
        if nv == 0:
            continue
        counts = np.bincount(a[valid], minlength=k)
        p = counts / nv
        out["basin_fraction"][i] = p
        out["basin_fraction_se"][i] = np.sqrt(p * (1.0 - p) / nv)
        out["basin_fraction_low"][i], out["basin_fraction_high"][i] = wilson(p, nv)
        out["basin_stability"][i] = p[0]
        per = np.flatnonzero(a == 1)
        label, heads = cyc.cluster_of(res, i, per, cycle_tol)
        cycle[i, per] = label
        out["n_cycles"][i] = len(heads)
        out["n_attractors"][i] = int(counts[0] > 0) + len(heads) + int(counts[2] > 0)
        if heads:
            big = int(np.argmax(np.bincount(label)))  # ties: the first found
            s = per[heads[big]]
            out["largest_cycle_omega"][i] = omega[i, s]
            out["largest_cycle_a1"][i] = a1[i, s]
            out["largest_cycle_fraction_off_disk"][i] = off[i, s]
            out["largest_cycle_verified"][i] = 0
            largest.append((i, s))
        if counts[2]:
            out["irregular_max_abs_z"][i] = float(np.max(max_z[i, a == 2]))
    check.measure(largest, out)
    out["largest_cycle_period_ratio"] = linear_frequency / out["largest_cycle_omega"]
    per_sample = {
        "outcome": outcome, "status": status, "attractor": attractor, "cycle": cycle, "omega": omega,
        "z1_amplitude": a1, "z2_amplitude": res["z2_amplitude"], "multiplicity": mult, "fraction_off_disk": off,
        "max_abs_z": max_z,
        "t_end": res["t_end"], "matched": res["irregular_matched"],
        "n_rhs": res["n_rhs"].astype(np.int64), "y0": y0,
        "reason": res["reason"].astype(str),
    }  # fmt: skip
    return out, per_sample


def _join(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Two phases' per-sample arrays ``(m, k, ...)`` side by side; the cell arrays of a phase that left
    no cells have no columns, and are padded with zeros (no cell) to the other's width."""
    if a.ndim == 3 and a.shape[2] != b.shape[2]:
        w = max(a.shape[2], b.shape[2])
        a, b = (np.pad(x, ((0, 0), (0, 0), (0, w - x.shape[2]))) for x in (a, b))
    return np.concatenate([a, b], axis=1)


#: The first-stop tolerance of the census under speed-dependent friction (:func:`first_stop_tol`).
FIRST_STOP_TOL: float = 1e-3


def first_stop_tol(stop_tol: float | None, friction_law: str, periodic_tol: float) -> float:
    """The repetition tolerance of a census sample's first stop on a cycle: ``stop_tol``, or by default
    :data:`FIRST_STOP_TOL` under speed-dependent friction and ``periodic_tol`` (no first stops)
    under constant friction.

    Under speed-dependent friction ``x`` acts back through the sliding velocity and is watched,
    and its light damping (a Floquet multiplier of about 0.993 per period) holds a repetition to
    ``periodic_tol`` back by seconds; a stop at 1e-3, then shot from, saves that. Measured on the
    Stribeck sweep of ``benches/bench_stribeck.py`` with its census (105 censused points, K = 32,
    2026-11-28, ``python benches/bench_census.py --stop-tol 1e-5,1e-3 --law switch``): switch law
    4.85-5.27 s -> 4.08-4.32 s (right-hand sides 451-453 -> 343-348 million), tanh law 4.74-5.18 ->
    4.04-4.20 s; no point's fraction moves by more than 1.0 standard error, no cycle count
    changes. 3e-3: 4.53 s, 1e-2: 6.42 s (more first stops near unstable orbits, which go on).
    Under constant friction the census compares ``(z, zd, phi, phid)`` only, which repeat to
    ``periodic_tol`` within a few periods: the 2,000-point grid's census took 42.0 s with first
    stops at 1e-3 against 36.7 s without (4 % fewer right-hand sides, paid back in shooting and in
    the runs going on).
    """
    if stop_tol is not None:
        return float(stop_tol)
    return FIRST_STOP_TOL if friction_law != "constant" else float(periodic_tol)


def phases(samples: int) -> list[int]:
    """Sample indices at which the census's phases start, and ``samples``: ``PHASE_STARTS`` below ``samples``."""
    return [c for c in PHASE_STARTS if c < samples] + [samples]


def fingerprints(done: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The irregular attractors the samples ``done`` established, as the core's ``known_irregular``
    ``(m, KNOWN, 7)``, ``known_cells`` ``(m, KNOWN, words)`` and ``known_cell_extent`` ``(m, KNOWN, 6)``:
    per point, the fingerprints (residual, then the six largest excursions) and the section cells
    of its first ``KNOWN`` samples that ended stationary-irregular, in sample order; NaN rows (and
    zero cells) for empty slots. No cells (``None``, ``None``) where no sample left any (the core's
    cell array then has no columns)."""
    res, peaks = done["irregular_residual"], done["irregular_peaks"]
    cells, extent = done["irregular_cells"], done["irregular_cell_extent"]
    own = np.isfinite(res) & ~done["irregular_matched"]
    m, has_cells = res.shape[0], cells.shape[-1] > 0
    out = np.full((m, KNOWN, 7), np.nan)
    out_cells = np.zeros((m, KNOWN, cells.shape[-1]), dtype=np.uint64)
    out_extent = np.full((m, KNOWN, 6), np.nan)
    for i, j in zip(*np.nonzero(own)):
        slot = int(np.sum(own[i, :j]))
        if slot < KNOWN:
            out[i, slot, 0], out[i, slot, 1:] = res[i, j], peaks[i, j]
            out_cells[i, slot], out_extent[i, slot] = cells[i, j], extent[i, j]
    return (out, out_cells, out_extent) if has_cells else (out, None, None)


def saddle_row(df: Mapping[str, np.ndarray], j: int, k: int) -> np.ndarray:
    """First-harmonic amplitudes ``[A1, w A1, x1, w x1, phi1, w phi1]`` of root ``k`` of point ``j`` of a describing-function result."""
    w, a1 = df["omega"][j, k], df["A1"][j, k]
    x1, p1 = df["x1_amplitude"][j, k], df["phi1_amplitude"][j, k]
    return np.array([a1, w * a1, x1, w * x1, p1, w * p1], dtype=np.float64)


def return_thresholds(v: Mapping[str, np.ndarray], saddle: np.ndarray | None) -> np.ndarray:
    """Per-component amplitudes ``(n, 6)`` below which a shrinking census sample counts as returned to sliding.

    ``RETURN_FRACTION`` of the saddle cycle's own first-harmonic amplitude in every component
    (capped so that ``|z|`` stays below ``|z_st|/2``: the pin on the disk), never below the plain
    decay test (``1e-3`` of the characteristic sizes); the plain decay test where no saddle is known.
    Measured in the saddle's own shape, not in characteristic sizes: at the seed the saddle's phi
    amplitude is 9 ``|z_st|/L`` against A1 = 1.3 ``|z_st|``, so a common size scale demanded a
    torsion motion 7x smaller than intended and kept returning samples running for about 5 s
    longer (decaying at 0.33 1/s).
    """
    sizes = characteristic_sizes(v)
    plain = 1e-3 * sizes
    if saddle is None:
        return plain
    sad = np.asarray(saddle, dtype=np.float64).reshape(-1, 6)
    known = np.all(np.isfinite(sad) & (sad > 0), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        f = np.minimum(RETURN_FRACTION, 0.5 * sizes[:, 0] / np.where(known, sad[:, 0], 1.0))
    thr = np.where(known[:, None], f[:, None] * np.where(known[:, None], sad, 0.0), 0.0)
    return np.maximum(thr, plain)


def failed_reason(per_sample: Mapping[str, np.ndarray], i: int) -> str:
    """Why every sample of point ``i`` failed (the first sample's status and reason)."""
    st = int(per_sample["status"][i, 0])
    name = STATUS_NAMES[st] if st < len(STATUS_NAMES) else str(st)
    detail = str(per_sample["reason"][i, 0])
    return f"census: every disturbance failed (status {name}{': ' + detail if detail else ''})"


def saddle_amplitudes(base: Mapping[str, float], friction_law: str, names, values: np.ndarray, stable: np.ndarray,
                      threads: int | None, grid: int = 1000) -> np.ndarray:
    """The describing function's physical root (the saddle cycle) at the stable points: :func:`saddle_row` ``(n, 6)``, NaN elsewhere.

    The same call as the sweep's describing-function stage, so a point's census is the same in a
    sweep and alone.
    """  # fmt: skip
    out = np.full((values.shape[0], 6), np.nan)
    sel = np.flatnonzero(stable)
    if sel.size:
        df = _core.describing_function(dict(base), "bilateral", friction_law, list(names), values[sel],
                                       variant="consistent", w_min=150.0, w_max=3000.0, n_base=grid, threads=threads)  # fmt: skip
        for j, i in enumerate(sel):
            k = np.flatnonzero(df["physical"][j] == 1)
            if df["status"][j] == STATUS["success"] and k.size:
                out[i] = saddle_row(df, j, k[0])
    return out


def census(
    model,
    *,
    samples: int = DEFAULTS.census.samples,
    disturbance_scale: float = DEFAULTS.census.disturbance_scale,
    t_max: float = DEFAULTS.census.t_max,
    integrator: str = DEFAULTS.integration.integrator,
    rtol: float = DEFAULTS.census.rtol,
    periodic_tol: float = DEFAULTS.steady.periodic_tol,
    cycle_tol: float = CYCLE_TOL,
    threads: int | None = None,
    irregular_block: int = DEFAULTS.irregular.block,
    recurrence: bool = True,
    stop_tol: float | None = DEFAULTS.census.stop_tol,
):
    """Attractor census of one model: ``samples`` disturbances, each run to its attractor.

    See the module ``tribosweep._census`` for the distribution of the disturbances (the torsion
    and normal modes, amplitudes up to ``disturbance_scale |z_st|``, a Halton sequence seeded by
    the model's parameters) and the early stops. A sweep's census at a point equals this one for
    the same model and settings.

    Parameters
    ----------
    model : SliderModel
        The point (use ``contact="unilateral"`` for the physical contact law).
    samples : int
        Number of disturbances ``K`` (1 to 1,000,000).
    disturbance_scale : float
        Largest modal amplitude of a disturbance, in units of the static penetration ``|z_st|`` (> 0).
    t_max : float, s
        Longest simulated time of one disturbance (> 0).
    integrator : {"dop853", "dopri5", "rodas4"}
        Time integrator.
    rtol : float
        Relative tolerance of the integration (1e-6: the census's default, see
        ``tribosweep._settings.Census``).
    periodic_tol : float
        Relative repetition tolerance of the section state that declares a cycle.
    cycle_tol : float
        Relative tolerance in frequency and first-harmonic amplitude within which cycles are one.
    irregular_block : int
        Sections per block of the stationarity test that stops sustained irregular motion before
        ``t_max``, and of the recurrence test against the pilots' attractors (0: both off; see the
        module's early stops).
    recurrence : bool
        Let the samples after the pilots stop once they keep to a pilot's irregular attractor: 32
        sections in a row in the cells its sections visited, or one block that matches its
        statistics (the default); ``False``: every sample decides by its own three blocks.
    stop_tol : float, optional
        The repetition tolerance at which a sample after the pilots first stops on a cycle, each
        such stop then shot from (:func:`first_stop_tol`): by default 1e-3 under speed-dependent
        friction, none (``periodic_tol``) under constant friction. The attribute ``stop_tol`` says
        which applied.
    threads : int, optional
        Rust worker threads (results do not depend on it).

    Returns
    -------
    xarray.Dataset
        ``basin_fraction``, ``basin_fraction_se`` and the 95 % Wilson interval
        ``basin_fraction_low`` .. ``basin_fraction_high`` (:func:`wilson`) on ``attractor``
        (sliding, cycle, irregular, escape); ``basin_stability``, ``n_attractors``, ``n_cycles`` and the largest cycle's
        frequency and amplitude; per ``sample``: the start ``y0``, the ``attractor`` reached, its
        ``cycle`` label (-1 if none), ``omega``, ``z1_amplitude``, ``t_end``, ``n_rhs`` and
        ``recurrence`` (1 where irregular motion was recognised by matching a pilot's attractor).

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.census(ts.SliderModel(contact="unilateral", normal_load=20.0), samples=4, t_max=5.0)
    >>> ds.basin_fraction.sizes["attractor"], int(ds.census_samples)
    (4, 4)
    """
    import xarray as xr

    from . import _checks
    from ._model import SliderModel

    if not isinstance(model, SliderModel):
        raise TypeError(f"model = {model!r} must be a tribosweep.SliderModel")
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 1 <= samples <= 1_000_000:
        raise ValueError(f"samples = {samples!r} is out of range: must be an integer in [1, 1000000]")
    scale = _checks.positive("disturbance_scale", disturbance_scale)
    t_max = _checks.positive("t_max", t_max)
    integrator = _checks.method(integrator)
    rtol = _checks.rtol(rtol)
    periodic_tol = _checks.positive("periodic_tol", periodic_tol)
    cycle_tol = _checks.positive("cycle_tol", cycle_tol)
    stop_tol = _stop_tol("stop_tol", stop_tol)
    irregular_block = _checks.block("irregular_block", irregular_block)
    threads = _checks.threads(threads)
    base = model.values()
    names = ["normal_load"]
    values = np.array([[base["normal_load"]]])
    lin = _core.linear_stability(base, model.contact, model.friction_law, names, values, threads=threads)
    stable = np.asarray(lin["stable"], dtype=bool)
    sad = saddle_amplitudes(base, model.friction_law, names, values, stable, threads)
    res, per = run(
        base, model.contact, model.friction_law, {"normal_load": values[:, 0]}, np.array([0]), samples=int(samples),
        scale=scale, t_max=t_max, integrator=integrator, rtol=rtol, atol=None, periodic_tol=periodic_tol,
        threads=threads, eigenvalues=np.asarray(lin["eigenvalues"]), linear_frequency=lin["linear_frequency"],
        saddle=sad, cycle_tol=cycle_tol, irregular_block=irregular_block, recurrence=bool(recurrence),
        stop_tol=stop_tol,
    )  # fmt: skip
    from ._simulate import STATE_VARS

    data = {}
    for name, (_dtype, units, long_name, per_attractor) in CENSUS_VARIABLES.items():
        attrs = {"long_name": long_name} | ({} if units is None else {"units": units})
        if name == "largest_cycle_verified":
            attrs = {"long_name": long_name, "flag_values": np.array(VERIFIED_FLAGS[0], dtype=np.int8),
                     "flag_meanings": " ".join(VERIFIED_FLAGS[1])}  # fmt: skip
        data[name] = (("attractor",), res[name][0], attrs) if per_attractor else ((), res[name][0], attrs)
    flag = {"flag_values": np.arange(-1, len(ATTRACTOR_NAMES), dtype=np.int8),
            "flag_meanings": "failed " + " ".join(ATTRACTOR_NAMES)}  # fmt: skip
    data["attractor_reached"] = (("sample",), per["attractor"][0].astype(np.int8),
                                 {"long_name": "attractor each disturbance reached"} | flag)  # fmt: skip
    data["cycle"] = (("sample",), per["cycle"][0], {"long_name": "label of the distinct cycle reached (-1: none)"})
    for k, units, text in (("omega", "rad s-1", "angular frequency of the motion at the end of the run"),
                           ("z1_amplitude", "m", "first-harmonic amplitude of z on the cycle (NaN if not periodic)"),
                           ("t_end", "s", "simulated time when the attractor was recognised"),
                           ("n_rhs", "1", "right-hand-side evaluations")):  # fmt: skip
        data[k] = (("sample",), per[k][0], {"long_name": text, "units": units})
    data["recurrence"] = (("sample",), per["matched"][0].astype(np.int8),
                          {"long_name": "1 where the irregular attractor was recognised by recurrence: one block of "
                           "sections matched an attractor that a pilot sample established", "flag_values":
                           np.array([0, 1], dtype=np.int8), "flag_meanings": "own_test recurrence"})  # fmt: skip
    data["y0"] = (("sample", "state"), per["y0"][0], {"long_name": "start state [z, zd, x, xd, phi, phid]"})
    coords = {
        "attractor": ("attractor", np.arange(len(ATTRACTOR_NAMES), dtype=np.int8),
                      {"long_name": "attractor", "flag_values": np.arange(len(ATTRACTOR_NAMES), dtype=np.int8),
                       "flag_meanings": " ".join(ATTRACTOR_NAMES)}),
        "attractor_name": ("attractor", np.array(ATTRACTOR_NAMES)),
        "sample": ("sample", np.arange(samples)),
        "state": ("state", np.array([s[0] for s in STATE_VARS])),
    }  # fmt: skip
    attrs = {f"model_{k}": v for k, v in base.items()}
    attrs.update(model_contact=model.contact, model_friction_law=model.friction_law, samples=int(samples),
                 disturbance_scale=scale, t_max=t_max, integrator=integrator, rtol=rtol, periodic_tol=periodic_tol,
                 cycle_tol=cycle_tol, irregular_block=irregular_block,
                 stop_tol=max(first_stop_tol(stop_tol, model.friction_law, periodic_tol), periodic_tol),
                 pilots=min(PILOTS, int(samples)) if recurrence and irregular_block else int(samples),
                 sliding_stable=int(stable[0]),
                 saddle_a1=float(sad[0, 0]),
                 saddle_phi1=float(sad[0, 4]),
                 disturbances="y0 = Re(a_t e^(i theta_t) v_t + a_n e^(i theta_n) v_n), v_t, v_n the torsion and normal "
                 "modes with z = 1, a uniform in [0, disturbance_scale |z_st|), theta uniform in [0, 2 pi); a Halton "
                 "sequence shifted by a hash of the model's parameters")  # fmt: skip
    return xr.Dataset(data, coords=coords, attrs=attrs)
