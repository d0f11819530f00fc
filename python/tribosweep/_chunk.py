"""The work of one sweep chunk: a pure, picklable function of its inputs.

:func:`compute_chunk` is the only thing a worker runs. It is a module-level function of plain
data (dicts of floats, strings and 1-D numpy arrays) with no closures and no global state, so
the same call runs in-process, in a ``concurrent.futures`` pool or on a dask cluster, and gives
the same numbers everywhere (apart from the measured ``wall_time``).

Stages (MODEL.md §4, §6):

``linear``
    Eigenvalues of the 6x6 Jacobian of steady sliding, for every point (cheap, vectorised numpy;
    to move to the Rust core). Gives the growth rate, the frequency of the least stable mode and
    the normal-mode frequency the wear model needs (MODEL.md §8).
``transient``
    A run to steady state in the Rust core (``tribosweep._core.ensemble(kind="steady")``), from
    a small disturbance, classified from its summary.
``irregular`` (after a transient)
    A run that stayed bounded but neither repeated nor decayed by ``t_max`` is sustained irregular
    motion, an answer: ``tribosweep._irregular`` measures it from where it ended (the range and
    dominant frequency of ``z`` over a window, the largest finite-time Lyapunov exponent with its
    standard error), in batched core calls. A failed measurement leaves the point
    ``unstable_undetermined`` (``failed`` where sliding is stable) with its failure status and reason.

``tidf``
    The triple-input describing function of the bilateral model (Rust, all roots in 150-3000
    rad/s). At a linearly stable point a physical root is the subcritical saddle cycle around stable
    sliding (MODEL.md §6): a disturbance smaller than it decays.
``shooting``
    The periodic orbit of the full ODE near the describing-function root, with Floquet multipliers:
    the root's own error (its ``A1`` against the orbit's) and the saddle's true size.

The sweep methods combine them, modelling no more than each point needs:

- ``linear``: eigenvalues only; an unstable point is ``unstable_undetermined`` (by choice: this
  method simulates nothing, and says so in the point's reason).
- ``tidf``: linear, then the describing function at every point. Stable points: steady sliding,
  with the saddle amplitude when there is a root. Unstable points: a root without contact opening
  is a predicted cycle (``self_excited``, decided by tidf, flagged as a prediction); otherwise
  ``unstable_undetermined``.
- ``shooting``: as ``tidf``, then the orbit of every physical root (its stability and the DF error).
- ``transient``: every point integrated from the disturbance ``y0`` (``irregular`` where it neither
  repeats nor decays).
- ``auto``: linear; at stable points the describing function; shooting only where the disturbance
  is within a factor ``SHOOT_MARGIN`` of the describing function's amplitude (there the DF's error
  matters); a transient only where those cannot decide: unstable sliding (the DF has no cycle
  there: the bifurcation is subcritical), a disturbance at or beyond the saddle, or a failed stage.
  With ``census`` (default on), a stable point with a saddle cycle also gets the attractor
  census (``tribosweep._census``): K disturbances, each run to its attractor, reported as
  fractions with standard errors; ``bistable`` (coexistence) is derived from it.

Transients of linearly unstable points start on the unstable (torsion) mode with
``|z| = unstable_disturbance |z_st|`` (default 1: the size at which the contact opens) instead of ``y0``: a small disturbance
grows at the linear rate (0.07 /s near the Hopf load), which would cost about 100 s of simulated
time for nothing. The attractor reached is the same when it is the only one; where it is not, the
attractor census is what tells.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Mapping

import numpy as np

from . import _census, _core, _irregular
from ._flags import OUTCOME_NAMES, STATUS, STATUS_NAMES

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
)
#: One-line meaning of every regime, for documentation and the ``regime`` variable's ``comment``.
REGIME_DOC: dict[str, str] = {
    "steady_sliding": "steady sliding: linearly stable, or a disturbance decayed",
    "self_excited": "a periodic cycle with the pin always on the disk and the contact always sliding",
    "contact_loss": "a periodic cycle on which the pin leaves the disk (bouncing)",
    "stick_slip": "the sliding velocity reached zero (outside the constant-friction law)",
    "diverged": "|z| reached the escape limit",
    "failed": "the computation failed (see status and reason)",
    "unstable_undetermined": "sliding unstable and the motion not determined: method=linear computes no motion (by "
    "choice), or the run was bounded but its measurement failed numerically (see status and reason)",
    "irregular": "sustained irregular motion: bounded, neither periodic nor decayed by t_max (quasi-periodic: "
    "irregular_ftle about 0; chaotic: irregular_ftle > 0; see irregular_*)",
}
REGIME: dict[str, int] = {name: i for i, name in enumerate(REGIME_NAMES)}

#: Which stage decided a point's regime, in code order.
DECIDED_BY_NAMES: tuple[str, ...] = ("linear", "tidf", "shooting", "transient")
DECIDED_BY: dict[str, int] = {name: i for i, name in enumerate(DECIDED_BY_NAMES)}

#: Coexistence at a point (int8), derived from the attractor census (``tribosweep._census``):
#: not checked (no census: the method does not take one, ``census=False``, sliding is unstable,
#: or the point failed); one attractor seen; more than one attractor seen (coexistence, with the
#: evidence counted in ``basin_fraction`` and ``reason``); no census because the describing
#: function predicts no saddle cycle around stable sliding (nothing to find).
BISTABLE_VALUES: tuple[int, ...] = (-1, 0, 1, 2)
BISTABLE_NAMES: tuple[str, ...] = ("not_checked", "one_attractor", "coexisting", "no_saddle")
BISTABLE: dict[str, int] = dict(zip(BISTABLE_NAMES, BISTABLE_VALUES))

#: Whether the mild-wear model applies at a point, in code order.
WEAR_APPLICABILITY_NAMES: tuple[str, ...] = ("mild_wear_regime", "outside_mild_wear_regime", "undetermined")

#: Default longest simulated time of a transient run [s]: near a Hopf point the growth rate is
#: small (0.07 1/s at 10 N and 7.6 cm), and a run costs about 2.5 ms of wall time per simulated second.
T_MAX: float = 100.0

#: A bounded run that did not settle, at a linearly stable point, whose z stays below this fraction
#: of the static penetration |z_st| is taken for sliding's own mode still decaying (not irregular).
SLOW_DECAY_FRACTION: float = 0.5

#: Analysis methods of a sweep.
METHODS: tuple[str, ...] = ("auto", "linear", "tidf", "shooting", "transient")
#: Methods whose stages exist so far.
IMPLEMENTED_METHODS: tuple[str, ...] = METHODS

#: ``auto`` shoots the saddle orbit when the disturbance's z exceeds the describing function's A1
#: divided by this margin (the DF's A1 error grows with amplitude: 10-20 % at tens of um).
SHOOT_MARGIN: float = 2.0

#: Per-point output of :func:`compute_chunk`: name -> (dtype, units or None, long name).
#: Flag variables carry their meanings in ``FLAG_MEANINGS``. Every name here is an output key.
POINT_VARIABLES: dict[str, tuple[str, str | None, str]] = {
    "regime": ("u1", None, "dynamic regime of the slider"),
    "status": ("u1", None, "status of the computation that decided the regime"),
    "reason": ("str", None, "reason for a failed or undetermined point (empty otherwise)"),
    "decided_by": ("u1", None, "analysis stage that decided the regime"),
    "bistable": ("i1", None, "coexistence of attractors seen by the census"),
    "growth_rate": ("f8", "s-1", "largest real part of the eigenvalues of steady sliding (> 0: unstable)"),
    "linear_frequency": ("f8", "rad s-1", "angular frequency of the least stable linear mode"),
    "normal_mode_frequency": ("f8", "Hz", "frequency Im(lambda_normal)/2 pi of the linearised normal mode"),
    "cycle_omega": ("f8", "rad s-1", "angular frequency of the steady cycle (NaN if none)"),
    "cycle_period_ratio": ("f8", "1", "period of the cycle in periods of the least stable linear mode: about 1 "
                                      "for the ordinary cycle, about 2 past a period doubling"),
    "z1_amplitude": ("f8", "m", "amplitude of the first harmonic of z on the cycle"),
    "z2_amplitude": ("f8", "m", "amplitude of the second harmonic of z on the cycle"),
    "phi1_amplitude": ("f8", "rad", "amplitude of the first harmonic of the twist phi on the cycle"),
    "min_normal_force": ("f8", "N", "minimum total normal force (over the cycle if periodic, else the run)"),
    "fraction_off_disk": ("f8", "1", "fraction of the cycle with the pin off the disk"),
    "min_slip_velocity": ("f8", "m s-1", "minimum sliding velocity of the contact point"),
    "wear_rate_relative": ("f8", "1", "mild-wear rate per sliding distance relative to the reference point"),
    "wear_applicability": ("u1", None, "whether the mild-wear model applies"),
    "wall_time": ("f8", "s", "wall-clock time of the point (its chunk's stage times shared evenly)"),
    "n_rhs": ("i8", "1", "right-hand-side evaluations of the time integration (0: none run)"),
    "tidf_roots": ("i8", "1", "describing-function roots in 150-3000 rad/s (-1: not computed)"),
    "tidf_omega": ("f8", "rad s-1", "angular frequency of the physical describing-function root"),
    "tidf_a1": ("f8", "m", "first-harmonic amplitude of z of the physical describing-function root"),
    "tidf_contact_opens": ("i1", None, "the physical root's waveform leaves the disk (outside the law's validity)"),
    "orbit_a1": ("f8", "m", "first-harmonic amplitude of z of the shooting orbit near the root"),
    "orbit_stable": ("i1", None, "stability of the shooting orbit (Floquet multipliers)"),
    "tidf_a1_error": ("f8", "1", "relative error of the describing function's A1 against the shooting orbit"),
    "newton_iterations": ("i8", "1", "Newton iterations of the TIDF and shooting stages (0: none run)"),
    **_irregular.IRREGULAR_VARIABLES,
}
#: Optional per-point output (present only when configured).
OPTIONAL_POINT_VARIABLES: dict[str, tuple[str, str | None, str]] = {
    "wear_rate": ("f8", "kg m-1", "mild-wear mass loss per sliding distance (eq. 8, calibrated)"),
}
#: Flag meanings of the categorical per-point variables.
FLAG_MEANINGS: dict[str, tuple[tuple[int, ...], tuple[str, ...]]] = {
    "regime": (tuple(range(len(REGIME_NAMES))), REGIME_NAMES),
    "status": (tuple(range(len(STATUS_NAMES))), STATUS_NAMES),
    "decided_by": (tuple(range(len(DECIDED_BY_NAMES))), DECIDED_BY_NAMES),
    "bistable": (BISTABLE_VALUES, BISTABLE_NAMES),
    "wear_applicability": (tuple(range(len(WEAR_APPLICABILITY_NAMES))), WEAR_APPLICABILITY_NAMES),
    "tidf_contact_opens": ((-1, 0, 1), ("not_computed", "closed", "opens")),
    "orbit_stable": ((-1, 0, 1), ("not_computed", "unstable", "stable")),
}

_LINEAR_FIELDS = (
    "mass", "inertia", "moment_arm", "omega_normal", "omega_friction", "omega_torsion", "zeta_normal",
    "zeta_friction", "zeta_torsion", "contact_stiffness", "contact_quadratic", "contact_damping",
    "twist_coupling", "mu", "normal_load", "sliding_speed", "torsion_sign", "friction_regularization",
    "mu_static", "stribeck_velocity",
)  # fmt: skip
_PERMUTATIONS = np.array(list(itertools.permutations(range(3))))  # (6, 3): mode -> dof label
_DOF_NORMAL = 2  # participation order [x, phi, z], as in rust_core/src/linear.rs


def jacobians(values: Mapping[str, np.ndarray | float], friction_law: str = "constant") -> np.ndarray:
    """Jacobians of steady sliding ``y = 0`` (in contact), shape ``(n, 6, 6)``, MODEL.md §2.

    Parameters
    ----------
    values : mapping of str to float or 1-D array
        Every real SliderModel field (SI units); arrays of one length ``n`` and scalars broadcast.
    friction_law : {"constant", "coulomb", "switch"}
        Friction law (the Coulomb law adds the Stribeck slope and the tanh regularisation; the
        switch law the Stribeck slope).

    Returns
    -------
    numpy.ndarray, shape (n, 6, 6), 1/s and 1/s^2
        ``d rhs / dy`` for the state ``[z, zd, x, xd, phi, phid]``.
    """
    v = {k: np.asarray(values[k], dtype=np.float64) for k in _LINEAR_FIELDS}
    n = int(np.broadcast_shapes(*(a.shape for a in v.values()), (1,))[0])
    v = {k: np.broadcast_to(a, (n,)) for k, a in v.items()}
    f, k0, ka = v["normal_load"], v["contact_stiffness"], v["contact_quadratic"]
    z_st = -2.0 * f / (k0 + np.sqrt(k0 * k0 + 4.0 * ka * f))  # cancellation-free root, MODEL.md §3
    k_s = k0 - 2.0 * ka * z_st
    dfz = np.zeros((n, 6))
    dfz[:, 0] = -k_s
    dfz[:, 1] = -v["contact_damping"]
    dfz[:, 4] = v["twist_coupling"]
    s, arm = v["torsion_sign"], v["moment_arm"]
    if friction_law == "constant":
        dfx = dfz * v["mu"][:, None]
    elif friction_law in ("coulomb", "switch"):
        # F_x = mu(v_r) N tanh(v_r/eps) - mu(V) F_st, v_r = V - xd - s L phid (MODEL.md §2); the
        # switch law slips at y = 0 (V > eta) with sign(v_r) = 1 in place of the tanh.
        vel, vs, mus, eps = v["sliding_speed"], v["stribeck_velocity"], v["mu_static"], v["friction_regularization"]
        e = np.exp(-vel / vs)
        mu_k = (v["mu"] - mus * e) / (1.0 - e)
        mu_v = mu_k + (mus - mu_k) * e
        th = np.tanh(vel / eps) if friction_law == "coulomb" else np.ones_like(vel)
        dmu = -(mus - mu_k) / vs * e
        dg = dmu * th + mu_v * (1.0 - th * th) / eps
        dfx = dfz * (mu_v * th)[:, None]
        dfx[:, 3] -= f * dg
        dfx[:, 5] -= f * dg * s * arm
    else:
        raise ValueError(f"friction_law = {friction_law!r} is not valid: must be 'constant', 'coulomb' or 'switch'")
    m = v["mass"]
    wz, wx, wt = v["omega_normal"], v["omega_friction"], v["omega_torsion"]
    j = np.zeros((n, 6, 6))
    j[:, 0, 1] = j[:, 2, 3] = j[:, 4, 5] = 1.0
    j[:, 1, :] = dfz / m[:, None]
    j[:, 3, :] = dfx / m[:, None]
    j[:, 5, :] = (s * arm / v["inertia"])[:, None] * dfx
    j[:, 1, 0] -= wz * wz
    j[:, 1, 1] -= 2.0 * v["zeta_normal"] * wz
    j[:, 3, 2] -= wx * wx
    j[:, 3, 3] -= 2.0 * v["zeta_friction"] * wx
    j[:, 5, 4] -= wt * wt
    j[:, 5, 5] -= 2.0 * v["zeta_torsion"] * wt
    return j


def _eig_batch(j: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues/vectors of a stack; a point whose QR iteration fails gets NaN and ``ok = False``."""
    n = j.shape[0]
    w = np.full((n, 6), np.nan + 0j)
    vec = np.full((n, 6, 6), np.nan + 0j)
    ok = np.all(np.isfinite(j), axis=(1, 2))
    if not ok.any():
        return w, vec, ok
    try:
        w[ok], vec[ok] = np.linalg.eig(j[ok])
    except np.linalg.LinAlgError:
        for i in np.flatnonzero(ok):
            try:
                w[i], vec[i] = np.linalg.eig(j[i])
            except np.linalg.LinAlgError:
                ok[i] = False
    return w, vec, ok


def linear_stability(values: Mapping[str, np.ndarray | float], friction_law: str = "constant") -> dict[str, np.ndarray]:
    """Linear stability of steady sliding at many points (MODEL.md §4), vectorised numpy.

    The modes are labelled by the energy participation ``[m |u_x|^2, I |u_phi|^2, m |u_z|^2]`` of
    their eigenvectors, choosing the labelling with the largest total participation (as the Rust
    core's ``linear.rs``), so the normal mode is found even where frequencies cross.

    Parameters
    ----------
    values : mapping of str to float or 1-D array
        Every real SliderModel field (SI units).
    friction_law : {"constant", "coulomb", "switch"}
        Friction law.

    Returns
    -------
    dict of str to numpy.ndarray
        ``growth_rate`` [1/s] (largest real part), ``linear_frequency`` [rad/s] (``|Im|`` of the
        least stable eigenvalue), ``normal_mode_frequency`` [Hz] (``Im(lambda_normal)/2 pi``),
        ``stable`` (bool), ``status`` (uint8: success, non_finite or not_converged) and
        ``eigenvalues`` (complex, ``(n, 6)``).

    Examples
    --------
    >>> from tribosweep import SliderModel
    >>> out = linear_stability(SliderModel().values())
    >>> round(float(out["normal_mode_frequency"][0]), 1), bool(out["stable"][0])
    (229.2, True)
    """
    v = {k: np.asarray(values[k], dtype=np.float64) for k in _LINEAR_FIELDS}
    j = jacobians(v, friction_law)
    n = j.shape[0]
    w, vec, ok = _eig_batch(j)
    status = np.where(np.all(np.isfinite(j), axis=(1, 2)), STATUS["not_converged"], STATUS["non_finite"])
    status = np.where(ok, STATUS["success"], status).astype(np.uint8)
    growth = np.full(n, np.nan)
    freq = np.full(n, np.nan)
    normal_hz = np.full(n, np.nan)
    if ok.any():
        wo = w[ok]
        k = np.argmax(wo.real, axis=1)
        growth[ok] = wo.real[np.arange(wo.shape[0]), k]
        freq[ok] = np.abs(wo.imag[np.arange(wo.shape[0]), k])
        # Displacement part u = [z, x, phi] of each eigenvector -> energies in [x, phi, z] order.
        mass = np.broadcast_to(v["mass"], (n,))[ok]
        inertia = np.broadcast_to(v["inertia"], (n,))[ok]
        u = vec[ok][:, [0, 2, 4], :]
        energy = np.stack(
            [mass[:, None] * np.abs(u[:, 1]) ** 2, inertia[:, None] * np.abs(u[:, 2]) ** 2,
             mass[:, None] * np.abs(u[:, 0]) ** 2],
            axis=2,
        )  # fmt: skip  (points, eigenvalue, dof)
        part = energy / energy.sum(axis=2, keepdims=True)
        upper = wo.imag > 0
        three = upper.sum(axis=1) == 3
        idx_ok = np.flatnonzero(ok)
        if three.any():
            # The three eigenvalues with Im > 0, sorted by frequency; best label permutation.
            order = np.argsort(np.where(upper, wo.imag, np.inf), axis=1, kind="stable")[three][:, :3]
            p3 = np.take_along_axis(part[three], order[:, :, None], axis=1)  # (k, mode, dof)
            score = p3[:, np.arange(3)[None, :], _PERMUTATIONS].sum(axis=2)  # (k, perm)
            perm = _PERMUTATIONS[np.argmax(score, axis=1)]  # (k, mode) -> dof label
            mode_normal = np.argmax(perm == _DOF_NORMAL, axis=1)
            lam = np.take_along_axis(wo[three], order, axis=1)[np.arange(order.shape[0]), mode_normal]
            normal_hz[idx_ok[three]] = lam.imag / (2.0 * np.pi)
        for i in np.flatnonzero(~three):
            # Overdamped pairs (real eigenvalues): the normal mode is the upper eigenvalue with the
            # largest z participation, frequency 0 if it is real.
            cand = np.flatnonzero(wo[i].imag >= 0)
            best = cand[np.argmax(part[i, cand, _DOF_NORMAL])]
            normal_hz[idx_ok[i]] = wo[i, best].imag / (2.0 * np.pi)
    return {
        "growth_rate": growth,
        "linear_frequency": freq,
        "normal_mode_frequency": normal_hz,
        "stable": ok & (growth < 0),
        "status": status,
        "eigenvalues": w,
    }


def empty_result(n: int, *, wear_rate: bool = False) -> dict[str, np.ndarray]:
    """Output arrays of ``n`` points with fill values (NaN, 0, empty strings)."""
    out: dict[str, np.ndarray] = {}
    spec = dict(POINT_VARIABLES)
    if wear_rate:
        spec.update(OPTIONAL_POINT_VARIABLES)
    for name, (dtype, _units, _long) in spec.items():
        if dtype == "str":
            out[name] = np.full(n, "", dtype="<U1")
        elif dtype == "f8":
            out[name] = np.full(n, np.nan)
        else:
            out[name] = np.zeros(n, dtype=dtype)
    out.update(_census.empty(n))
    out["bistable"][:] = -1
    out["tidf_roots"][:] = -1
    out["tidf_contact_opens"][:] = -1
    out["orbit_stable"][:] = -1
    return out


def _classify(summary: dict, stable: np.ndarray, t_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Regime, status, reason and deciding stage of transient runs from their steady-state summaries.

    A run that stayed bounded (no escape, a finite end state) but neither repeated nor decayed by
    ``t_max`` (outcome ``unsettled``) is an answer: sustained ``irregular`` motion, decided by the
    transient, status ``success`` (its measurement, :mod:`tribosweep._irregular`, follows in
    :func:`_dynamics`). Only a failed integration makes a point ``failed``.
    """
    status = np.asarray(summary["status"], dtype=np.uint8).copy()
    outcome = np.asarray(summary["outcome"], dtype=np.uint8)
    off = np.asarray(summary["fraction_off_disk"])
    vmin = np.asarray(summary["min_slip_velocity"])
    y_end = summary.get("y_end")
    names = [OUTCOME_NAMES[o] for o in outcome]
    n = len(names)
    regime = np.full(n, REGIME["failed"], dtype=np.uint8)
    decided = np.full(n, DECIDED_BY["transient"], dtype=np.uint8)
    reason = np.asarray(summary["reason"], dtype=str).astype(object)
    for i, name in enumerate(names):
        st = STATUS_NAMES[status[i]] if status[i] < len(STATUS_NAMES) else str(status[i])
        finite = y_end is None or bool(np.all(np.isfinite(np.asarray(y_end)[i])))
        if name == "diverged" or st == "diverged":
            regime[i] = REGIME["diverged"]
        elif name == "unsettled" and st == "not_converged" and finite:
            regime[i] = REGIME["irregular"]
            status[i] = STATUS["success"]
            reason[i] = f"bounded motion, neither periodic nor decayed by t_max = {t_max:g} s" + (
                "" if not stable[i] else " (sliding is linearly stable: this motion coexists with it, or is a slow "
                "transient)")  # fmt: skip
        elif st != "success" or name in ("failed", "unsettled"):
            regime[i] = REGIME["failed"]
            if st == "success":
                status[i] = STATUS["non_finite"]
                st = "non_finite"
            detail = f": {reason[i]}" if reason[i] else ""
            reason[i] = f"transient {name}, status {st}{detail}"
        elif name == "decayed":
            regime[i] = REGIME["steady_sliding"]
        elif name == "periodic":
            if not (vmin[i] > 0):
                regime[i] = REGIME["stick_slip"]
            elif off[i] > 0:
                regime[i] = REGIME["contact_loss"]
            else:
                regime[i] = REGIME["self_excited"]
    return regime, status, reason.astype(str), decided


#: Sweep options of the irregular-motion measurement -> ``_irregular.settings`` argument.
IRREGULAR_OPTIONS: dict[str, str] = {
    "irregular_window": "window",
    "irregular_sample_dt": "sample_dt",
    "ftle_tau": "tau",
    "ftle_segments": "segments",
    "ftle_warmup": "warmup",
    "ftle_d0": "d0",
    "ftle_rtol": "rtol",
}


def irregular_settings(options: Mapping) -> dict:
    """The measurement settings of a sweep's ``options`` (defaults where absent), checked."""
    kw = {arg: options[opt] for opt, arg in IRREGULAR_OPTIONS.items() if opt in options}
    return _irregular.settings(**kw, names={arg: opt for opt, arg in IRREGULAR_OPTIONS.items()})


def _static_penetration(full: Mapping[str, np.ndarray], sel: np.ndarray) -> np.ndarray:
    """Static penetration z_st [m] of the selected points (MODEL.md §3, cancellation-free form)."""
    n = max(np.size(v) for v in full.values())
    sub = {k: np.broadcast_to(full[k], (n,))[sel] for k in ("contact_stiffness", "contact_quadratic", "normal_load")}
    return _census._static(sub)[0]


def _mode_start(full: Mapping[str, np.ndarray], friction_law: str, sel: np.ndarray, z_amp: np.ndarray,
                eigenvalues: np.ndarray) -> np.ndarray:
    """Initial states on the least stable linear mode of each selected point, with ``|z| = z_amp``.

    A disturbance along the mode that self-excites (the torsion mode) reaches the attractor far
    sooner than one in ``z`` alone, which mostly excites the heavily damped normal mode. The mode
    shape is the census's closed form (no LAPACK: the same bits on every machine's BLAS);
    ``eigenvalues`` are the core's, ``(sel.size, 6)``.
    """
    n = max(np.size(v) for v in full.values())
    sub = {k: np.broadcast_to(np.asarray(full[k], dtype=np.float64), (n,))[sel] for k in full}
    lam = np.asarray(eigenvalues)
    k = np.argmax(lam.real + 1e-9 * lam.imag, axis=1)  # least stable; the +Im member of the pair
    lam = lam[np.arange(sel.size), k]
    if friction_law == "constant":
        v = _census.mode_shape(sub, lam)
    else:
        v = _census._mode_shape_numeric(jacobians(sub, friction_law), lam)
    # Rotate so that z is real and positive at t = 0 (zd then follows from the mode), scale |z|.
    v = v * np.exp(-1j * np.angle(v[:, 0]))[:, None]
    y0 = v.real / np.maximum(np.abs(v[:, :1].real), 1e-300) * np.asarray(z_amp)[:, None]
    return np.ascontiguousarray(y0)


def _transient(model_values, contact, friction_law, point_params, sel, options, y0=None, decay=None) -> dict:
    names = sorted(point_params)
    values = np.column_stack([np.asarray(point_params[k], dtype=np.float64)[sel] for k in names])
    if y0 is None:
        y0 = np.asarray(options.get("y0", [1e-6, 0, 0, 0, 0, 0]), dtype=np.float64).reshape(1, 6)
    atol = options.get("atol")
    return _core.ensemble(
        {k: float(v) for k, v in model_values.items()}, contact, friction_law, names, values,
        np.ascontiguousarray(y0, dtype=np.float64),
        float(options.get("t_max", T_MAX)), options.get("integrator", "dop853"), float(options.get("rtol", 1e-8)),
        atol=None if atol is None else np.asarray(atol, dtype=np.float64), threads=options.get("threads"), kind="steady",
        periodic_tol=float(options.get("periodic_tol", 1e-5)), decay_amplitude=options.get("decay_amplitude"), n_fourier=512,
        decay_amplitudes=None if decay is None else np.ascontiguousarray(decay, dtype=np.float64),
    )  # fmt: skip


def _dynamics(model_values, contact, friction_law, point_params, method, options, *, n_points: int) -> dict:
    """Regime and cycle of each point by the staged models (everything but wear)."""
    n = n_points
    full = {k: np.asarray(v, dtype=np.float64) for k, v in model_values.items()}
    for k, a in point_params.items():
        full[k] = np.asarray(a, dtype=np.float64)
    out = empty_result(n)
    reason = np.full(n, "", dtype=object)
    base = {k: float(v) for k, v in model_values.items()}
    names = sorted(point_params)
    values = np.column_stack([np.asarray(point_params[k], dtype=np.float64) for k in names])
    threads = options.get("threads")
    y0 = np.asarray(options.get("y0", [1e-6, 0, 0, 0, 0, 0]), dtype=np.float64)
    disturbance = float(np.abs(y0[0]))

    # Stage 1: linear stability of steady sliding (every point).
    t0 = time.perf_counter()
    lin = _core.linear_stability(base, contact, friction_law, names, values, threads=threads)
    out["growth_rate"] = lin["max_growth_rate"]
    out["linear_frequency"] = lin["least_stable_frequency"]
    out["normal_mode_frequency"] = lin["normal_mode_frequency_hz"]
    stable = np.asarray(lin["stable"], dtype=bool)
    out["status"][:] = lin["status"]
    out["decided_by"][:] = DECIDED_BY["linear"]
    out["regime"][:] = np.where(stable, REGIME["steady_sliding"], REGIME["unstable_undetermined"])
    lin_failed = lin["status"] != STATUS["success"]
    out["regime"][lin_failed] = REGIME["failed"]
    reason[lin_failed] = "linear stability: eigenvalues failed"
    wall = np.full(n, (time.perf_counter() - t0) / max(n, 1))
    to_transient = np.zeros(n, dtype=bool)

    if method == "linear":
        reason[out["regime"] == REGIME["unstable_undetermined"]] = (
            "sliding unstable; the motion was not computed (method=linear: eigenvalues only, by choice)")
    elif method == "transient":
        to_transient[:] = True
    else:
        # Stage 2: the describing function (bilateral: the report's model). auto needs it only at
        # stable points (at unstable ones the Hopf bifurcation is subcritical: no cycle to find).
        sel = np.flatnonzero(~lin_failed & (stable | (method != "auto")))
        phys = np.full(n, -1)
        if sel.size:
            t1 = time.perf_counter()
            df = _core.describing_function(base, "bilateral", friction_law, names, values[sel], variant="consistent",
                                           w_min=150.0, w_max=3000.0, n_base=int(options.get("tidf_grid", 1000)), threads=threads)
            wall[sel] += (time.perf_counter() - t1) / sel.size
            out["tidf_roots"][sel] = df["n_roots"]
            iters = np.where(df["newton_iterations"] > 0, df["newton_iterations"], 0).sum(axis=1)
            out["newton_iterations"][sel] += iters
            for j, i in enumerate(sel):
                k = np.flatnonzero(df["physical"][j] == 1)
                if df["status"][j] != STATUS["success"]:
                    to_transient[i] = method == "auto"
                    reason[i] = f"describing function failed: {STATUS_NAMES[df['status'][j]]}"
                    continue
                if k.size:
                    phys[i] = k[0]
                    out["tidf_omega"][i] = df["omega"][j, k[0]]
                    out["tidf_a1"][i] = df["A1"][j, k[0]]
                    out["tidf_contact_opens"][i] = df["contact_opens"][j, k[0]]
                if stable[i]:
                    out["decided_by"][i] = DECIDED_BY["tidf"]
                    if k.size and disturbance * SHOOT_MARGIN >= out["tidf_a1"][i] and method == "auto":
                        phys[i] = -2 - k[0]  # mark for shooting: the disturbance is near the saddle
                    elif df["search_outcome"][j] == "below_resolution":
                        reason[i] = "near a Hopf point: the describing function is below resolution"
                elif k.size and method in ("tidf", "shooting") and not out["tidf_contact_opens"][i]:
                    out["regime"][i] = REGIME["self_excited"]
                    out["decided_by"][i] = DECIDED_BY["tidf"]
                    out["cycle_omega"][i] = out["tidf_omega"][i]
                    out["z1_amplitude"][i] = out["tidf_a1"][i]
                    out["z2_amplitude"][i] = df["A2"][j, k[0]]
                    out["phi1_amplitude"][i] = df["phi1_amp"][j, k[0]]
                    reason[i] = "cycle predicted by the describing function"
                elif method in ("tidf", "shooting"):
                    reason[i] = "sliding unstable; no describing-function cycle within the law's validity"
            # Stage 3: shooting where the describing function's error matters.
            shoot = np.array([i for i in range(n) if phys[i] <= -2 or (method == "shooting" and phys[i] >= 0)], dtype=int)
            orbs = None
            if shoot.size:
                js = np.searchsorted(sel, shoot)
                ks = np.where(phys[shoot] <= -2, -2 - phys[shoot], phys[shoot])
                roots = np.column_stack([df[v][js, ks] for v in ("omega", "A0", "A1", "A2", "theta")])
                t2 = time.perf_counter()
                orbs = _core.periodic_orbits(base, "bilateral", friction_law, names, values[shoot], roots=roots,
                                             rtol=1e-10, tol=1e-8, threads=threads)  # fmt: skip
                wall[shoot] += (time.perf_counter() - t2) / shoot.size
            for r, i in enumerate(shoot):
                orb = {k: v[r] for k, v in orbs.items()}
                out["newton_iterations"][i] += orb["newton_iterations"]
                out["n_rhs"][i] += orb["n_rhs"]
                if orb["status"] != STATUS["success"]:
                    if method == "auto":
                        to_transient[i] = True
                        reason[i] = f"shooting from the describing-function root failed: {STATUS_NAMES[orb['status']]}"
                    continue
                out["orbit_a1"][i] = orb["A1"]
                out["orbit_stable"][i] = int(orb["stable"])
                out["tidf_a1_error"][i] = out["tidf_a1"][i] / orb["A1"] - 1
                if stable[i]:
                    if disturbance < orb["A1"]:
                        out["decided_by"][i] = DECIDED_BY["shooting"]
                        reason[i] = ""
                    elif method == "auto":
                        to_transient[i] = True
                        reason[i] = "the disturbance reaches the saddle cycle: integrated"

    # Stage 4: transient integration where the cheaper models cannot decide.
    if method == "auto":
        to_transient |= ~lin_failed & ~stable
    sel = np.flatnonzero(to_transient)
    if sel.size:
        y0s = np.tile(y0, (sel.size, 1))
        if method == "auto":
            unstable = ~stable[sel]
            z_st = _static_penetration(full, sel)
            zd = float(options.get("unstable_disturbance", 1.0))
            if unstable.any():
                y0s[unstable] = _mode_start(full, friction_law, sel[unstable], zd * np.abs(z_st[unstable]),
                                            np.asarray(lin["eigenvalues"])[sel[unstable]])
        t1 = time.perf_counter()
        summary = _transient(model_values, contact, friction_law, point_params, sel, options, y0s)
        wall[sel] += (time.perf_counter() - t1) / sel.size
        t_max = float(options.get("t_max", T_MAX))
        regime, status, why, decided = _classify(summary, stable[sel], t_max)
        out["regime"][sel] = regime
        out["status"][sel] = status
        reason[sel] = np.where(why != "", why, reason[sel].astype(str))
        out["decided_by"][sel] = decided
        periodic = np.isin(regime, [REGIME["self_excited"], REGIME["contact_loss"], REGIME["stick_slip"]])
        for key, src in (("z1_amplitude", "z1_amp"), ("z2_amplitude", "z2_amp"), ("phi1_amplitude", "phi1_amp"),
                         ("fraction_off_disk", "fraction_off_disk")):  # fmt: skip
            out[key][sel] = np.where(periodic, summary[src], np.nan)
        out["cycle_omega"][sel] = np.where(periodic, summary["omega"], np.nan)
        out["min_normal_force"][sel] = summary["min_normal_force"]
        out["min_slip_velocity"][sel] = summary["min_slip_velocity"]
        out["n_rhs"][sel] += np.asarray(summary["n_rhs"], dtype=np.int64)

        # Stage 4b: what an irregular run measured (tribosweep._irregular), from where it ended:
        # the range and dominant frequency of z over a window, and the largest finite-time
        # Lyapunov exponent (about 0: quasi-periodic; > 0: chaotic). A failed measurement leaves
        # the motion undetermined: a failure status and its reason.
        irr = regime == REGIME["irregular"]
        if irr.any():
            pts = sel[irr]
            t1 = time.perf_counter()
            meas = _irregular.measure(
                model_values, contact, friction_law, point_params, pts, np.asarray(summary["y_end"])[irr],
                integrator=options.get("integrator", "dop853"), rtol=float(options.get("rtol", 1e-8)),
                threads=threads, settings_=irregular_settings(options),
            )  # fmt: skip
            wall[pts] += (time.perf_counter() - t1) / pts.size
            out["n_rhs"][pts] += meas["n_rhs"]
            # At a linearly stable point, a motion that stays well inside the contact (|z| below
            # SLOW_DECAY_FRACTION |z_st|: the law nearly linear, no opening) is sliding's own
            # least-damped mode still decaying, at the linear rate (0.03 1/s near a Hopf load): too
            # slow for t_max, not sustained motion. Sliding, as linear stability says.
            amp = np.maximum(np.abs(meas["irregular_z_min"]), np.abs(meas["irregular_z_max"]))
            slow = stable[pts] & (amp < SLOW_DECAY_FRACTION * np.abs(_static_penetration(full, pts)))
            if slow.any():
                q = pts[slow]
                out["regime"][q] = REGIME["steady_sliding"]
                out["decided_by"][q] = DECIDED_BY["linear"]
                out["status"][q] = STATUS["not_converged"]
                reason[q] = [f"the transient did not settle by t_max = {t_max:g} s; sliding is linearly stable and the "
                             f"motion small (|z| <= {a:.3g} m, below {SLOW_DECAY_FRACTION:g} |z_st|): still decaying"
                             for a in amp[slow]]  # fmt: skip
            pts, meas = pts[~slow], {k: v[~slow] for k, v in meas.items()}
            # Transient chaos: bounded until t_max, the motion left through the escape limit during
            # the measurement window. That is an answer (the run diverged), not a failure.
            esc = meas["status"] == STATUS["diverged"]
            if esc.any():
                q = pts[esc]
                out["regime"][q] = REGIME["diverged"]
                out["status"][q] = STATUS["success"]
                reason[q] = [f"bounded until t_max = {t_max:g} s without settling (irregular), then |z| reached the "
                             "escape limit during the measurement window after it: transient chaos"] * q.size
            pts, meas = pts[~esc], {k: v[~esc] for k, v in meas.items()}
            for key in _irregular.IRREGULAR_VARIABLES:
                out[key][pts] = meas[key]
            bad = meas["status"] != STATUS["success"]
            if bad.any():
                out["status"][pts[bad]] = meas["status"][bad]
                out["regime"][pts[bad]] = np.where(stable[pts[bad]], REGIME["failed"], REGIME["unstable_undetermined"])
                reason[pts[bad]] = [f"{a}; {b}" for a, b in zip(reason[pts[bad]], meas["reason"][bad])]
            for j in np.flatnonzero(~bad):
                f, se = meas["irregular_ftle"][j], meas["irregular_ftle_se"][j]
                reason[pts[j]] += f"; largest FTLE {f:.3g} +- {se:.2g} 1/s"

    # Stage 5 (auto): the attractor census where a saddle cycle surrounds stable sliding: K
    # disturbances, each run to its attractor with the point's contact law; fractions with
    # standard errors (tribosweep._census). Stable points without a saddle have nothing to find.
    if method == "auto" and options.get("census", True):
        ok = stable & ~lin_failed
        no_saddle = ok & ~np.isfinite(out["tidf_a1"])
        out["bistable"][no_saddle] = BISTABLE["no_saddle"]
        cand = np.flatnonzero(ok & (out["regime"] == REGIME["steady_sliding"]) & np.isfinite(out["tidf_a1"]))
        if cand.size:
            t1 = time.perf_counter()
            res, per = _census.run(
                model_values, contact, friction_law, point_params, cand,
                samples=int(options.get("samples", _census.SAMPLES)),
                scale=float(options.get("disturbance_scale", _census.DISTURBANCE_SCALE)),
                t_max=float(options.get("census_t_max", _census.CENSUS_T_MAX)),
                integrator=options.get("integrator", "dop853"), rtol=float(options.get("rtol", 1e-8)),
                atol=options.get("atol"), periodic_tol=float(options.get("periodic_tol", 1e-5)), threads=threads,
                eigenvalues=np.asarray(lin["eigenvalues"])[cand], linear_frequency=out["linear_frequency"][cand],
                saddle_a1=out["tidf_a1"][cand],
            )  # fmt: skip
            wall[cand] += (time.perf_counter() - t1) / cand.size
            out["n_rhs"][cand] += per["n_rhs"].sum(axis=1)
            for key, arr in res.items():
                out[key][cand] = arr
            for j, i in enumerate(cand):
                nv = int(res["census_samples"][j])
                if nv == 0:
                    reason[i] = _census.failed_reason(per, j)
                    continue
                out["bistable"][i] = BISTABLE["coexisting"] if res["n_attractors"][j] > 1 else BISTABLE["one_attractor"]
                counts = np.rint(res["basin_fraction"][j] * nv).astype(int)
                seen = ", ".join(f"{a} {c}/{nv}" for a, c in zip(_census.ATTRACTOR_NAMES, counts) if c)
                if res["n_attractors"][j] > 1:
                    reason[i] = f"coexisting attractors (census): {seen}"
                elif counts[0] < nv:
                    reason[i] = f"census: {seen}"

    with np.errstate(invalid="ignore", divide="ignore"):
        out["cycle_period_ratio"] = out["linear_frequency"] / out["cycle_omega"]
    out["wall_time"] = wall
    out["reason"] = reason.astype(str)
    return out


def compute_chunk(
    model_values: dict,
    contact: str,
    friction_law: str,
    point_params: dict[str, np.ndarray],
    method: str,
    options: dict,
) -> dict[str, np.ndarray]:
    """Compute one chunk of sweep points: pure, deterministic, picklable.

    Parameters
    ----------
    model_values : dict of str to float
        Base parameters (``SliderModel.values()``, SI units).
    contact : {"bilateral", "unilateral"}
        Contact model of the transient runs.
    friction_law : {"constant", "coulomb", "switch"}
        Friction law.
    point_params : dict of str to 1-D numpy.ndarray
        Per-point overrides of real SliderModel fields, all of length ``n``.
    method : {"auto", "linear", "transient"}
        Analysis method (see the module docstring).
    options : dict
        Plain data: ``t_max`` [s], ``integrator``, ``rtol``, ``atol``, ``periodic_tol``,
        ``decay_amplitude`` [m], ``y0`` (initial disturbance, 6 values), ``threads``, and ``wear``
        (``{"normal_load": N, "sliding_speed": m/s, "frequency_hz": Hz}`` of the reference point,
        optional ``"calibration"``: ``WearCalibration.as_dict()``).

    Returns
    -------
    dict of str to numpy.ndarray
        The per-point variables of ``POINT_VARIABLES`` (and ``wear_rate`` when calibrated), each
        of length ``n``.
    """
    if method not in IMPLEMENTED_METHODS:
        raise NotImplementedError(f"method = {method!r} is not available: use one of {IMPLEMENTED_METHODS}")
    from . import _wear  # _wear imports this module for its normal-mode frequency

    full = {k: np.asarray(v, dtype=np.float64) for k, v in model_values.items()}
    n = len(next(iter(point_params.values())))
    for k, a in point_params.items():
        full[k] = np.asarray(a, dtype=np.float64)
    wear = options.get("wear") or {}

    # With the constant friction law the sliding speed enters neither the equations nor the
    # static point: it only shifts the sliding velocity v_r = V - (xd + s L phid). Points that differ
    # only in V share their dynamics, computed once (in a load x arm x speed sweep this divides the
    # work by the number of speeds); min_slip_velocity is then shifted by V - V_rep and the
    # stick-slip test redone.
    keys = sorted(point_params)
    shared = [k for k in keys if not (friction_law == "constant" and k == "sliding_speed")]
    if len(shared) < len(keys) and n > 1:
        rows = np.column_stack([np.asarray(point_params[k], dtype=np.float64) for k in shared]) if shared else np.zeros((n, 1))
        _, first, inverse = np.unique(rows, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.ravel()
        sub = {k: np.asarray(point_params[k], dtype=np.float64)[first] for k in keys}
        uniq = _dynamics(model_values, contact, friction_law, sub, method, options, n_points=first.size)
        out = {k: v[inverse] for k, v in uniq.items()}
        v_rep = np.asarray(point_params["sliding_speed"], dtype=np.float64)[first][inverse]
        dv = np.asarray(point_params["sliding_speed"], dtype=np.float64) - v_rep
        out["min_slip_velocity"] = out["min_slip_velocity"] + dv
        cyc = np.isin(out["regime"], [REGIME["self_excited"], REGIME["contact_loss"], REGIME["stick_slip"]])
        off = np.nan_to_num(out["fraction_off_disk"]) > 0
        out["regime"] = np.where(
            cyc & ~(out["min_slip_velocity"] > 0), REGIME["stick_slip"],
            np.where(cyc & off, REGIME["contact_loss"], np.where(cyc, REGIME["self_excited"], out["regime"])),
        ).astype(np.uint8)  # fmt: skip
        # Work done once is shared evenly among the points that share it.
        share = np.bincount(inverse)[inverse]
        out["wall_time"] = out["wall_time"] / share
    else:
        out = _dynamics(model_values, contact, friction_law, point_params, method, options, n_points=n)
    out = {k: v.copy() for k, v in out.items()}
    if wear.get("calibration"):
        out.update({k: np.full(n, np.nan) for k in OPTIONAL_POINT_VARIABLES})

    # Wear (MODEL.md §8): only in the mild (steady-sliding) regime.
    mild = out["regime"] == REGIME["steady_sliding"]
    undetermined = out["regime"] == REGIME["failed"]
    out["wear_applicability"][:] = np.where(mild, 0, np.where(undetermined, 2, 1))
    if wear:
        rel = _wear.relative_wear_rate(
            full["normal_load"], full["sliding_speed"], out["normal_mode_frequency"],
            reference_load=wear["normal_load"], reference_speed=wear["sliding_speed"],
            reference_frequency_hz=wear["frequency_hz"],
        )  # fmt: skip
        out["wear_rate_relative"] = np.where(mild, np.broadcast_to(rel, (n,)), np.nan)
        calibration = wear.get("calibration")
        if calibration:
            absolute = _wear.calibrated_wear_rate(
                calibration, full["normal_load"], full["sliding_speed"], out["normal_mode_frequency"]
            )
            out["wear_rate"] = np.where(mild, np.broadcast_to(absolute, (n,)), np.nan)
    return out
