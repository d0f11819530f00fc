"""Independent numpy/scipy reference of the pin-on-disk slider (docs/model.md §2-3).

This module is the trusted check the tests hold the Rust core against. It is written from
docs/model.md, not from the Rust sources, and it deliberately stays small: plain functions on a
``dict`` of parameters, :func:`scipy.integrate.solve_ivp` for time integration and
finite differences for the Jacobian. It imports nothing from ``tribosweep._core``.

State ``y = [z, zd, x, xd, phi, phid]`` (m, m/s, m, m/s, rad, rad/s): dynamic parts measured
from the static equilibrium. ``zc = z_st + z`` is the pin position relative to the disk
surface (``zc < 0``: penetration). SI units throughout; frequencies in rad/s.

Equations (docs/model.md §2)::

    z''   + 2 zeta_z w_z zd   + w_z^2 z   = F_z / m
    x''   + 2 zeta_x w_x xd   + w_x^2 x   = F_x / m
    phi'' + 2 zeta_t w_t phid + w_t^2 phi = s (L / I) F_x
    F_z = N - F_st,   F_x = mu F_z   (constant mu)

with the contact law's total normal force
``N_law = F_st - K_s z + K_a z^2 - C_zc zd + K_phi phi`` (identical to
``-K_s0 zc + K_a zc^2 - C_zc zd + K_phi phi``). The *bilateral* model uses ``N = N_law``
everywhere; the *unilateral* model uses ``N = N_law`` in contact (``zc <= 0`` and
``N_law >= 0``) and ``N = 0`` otherwise.

Examples
--------
>>> p = seed_parameters()
>>> z_st, k_s = static_point(p)
>>> round(z_st * 1e6, 4), round(k_s / 1e6, 4)
(-16.5612, 5.4607)
"""

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

__all__ = [
    "PARAM_ORDER",
    "STATE_SCALE",
    "UnilateralSolution",
    "contact_indicator",
    "default_atol",
    "linear_eigenvalues",
    "linear_jacobian",
    "normal_law_force",
    "params_to_array",
    "rhs",
    "seed_parameters",
    "solve",
    "solve_unilateral",
    "static_point",
]

#: Parameter names, in the column order used by :func:`params_to_array` (same names as
#: the Rust ``Params`` fields).
PARAM_ORDER = (
    "mass",  # m [kg]
    "inertia",  # I [kg m^2]
    "moment_arm",  # L [m]
    "omega_normal",  # w_z [rad/s]
    "omega_friction",  # w_x [rad/s]
    "omega_torsion",  # w_t [rad/s]
    "zeta_normal",  # zeta_z [-]
    "zeta_friction",  # zeta_x [-]
    "zeta_torsion",  # zeta_t [-]
    "contact_stiffness",  # K_s0 [N/m]
    "contact_quadratic",  # K_a [N/m^2]
    "contact_damping",  # C_zc [N s/m]
    "twist_coupling",  # K_phi [N/rad]
    "mu",  # [-]
    "normal_load",  # F_st [N]
    "sliding_speed",  # V [m/s]
    "torsion_sign",  # s, -1 or +1
)

#: Typical small amplitude of each state component (m, m/s, m, m/s, rad, rad/s), used to
#: build the default absolute tolerance: about 1 um in z at the seed's normal frequency,
#: and the x and phi amplitudes the describing function gives for it.
STATE_SCALE = np.array([1e-6, 1e-3, 1e-7, 1e-4, 1e-5, 1e-2])

_MODES = ("contact", "free")


def seed_parameters() -> dict:
    """Seed configuration of docs/model.md §3 (report chapter IV).

    Returns
    -------
    dict
        Keys of :data:`PARAM_ORDER`, SI values: ``mass`` kg, ``inertia`` kg m^2,
        ``moment_arm`` m, ``omega_*`` rad/s, ``zeta_*`` dimensionless,
        ``contact_stiffness`` (K_s0) N/m, ``contact_quadratic`` (K_a) N/m^2,
        ``contact_damping`` (C_zc) N s/m, ``twist_coupling`` (K_phi) N/rad,
        ``mu`` dimensionless, ``normal_load`` (F_st) N, ``sliding_speed`` (V) m/s,
        ``torsion_sign`` (s) -1.0.
    """
    two_pi = 2.0 * math.pi
    return {
        "mass": 2.48,
        "inertia": 3.147e-3,
        "moment_arm": 0.065,
        "omega_normal": two_pi * 55.00,
        "omega_friction": two_pi * 48.75,
        "omega_torsion": two_pi * 98.75,
        "zeta_normal": 0.01129,
        "zeta_friction": 0.00378,
        "zeta_torsion": 0.00253,
        "contact_stiffness": 4.739e6,
        "contact_quadratic": 2.179e10,
        "contact_damping": 222.63,
        "twist_coupling": -47.64e3,
        "mu": 0.215,
        "normal_load": 84.46,
        "sliding_speed": 0.46,
        "torsion_sign": -1.0,
    }


def params_to_array(params_list) -> np.ndarray:
    """Stack parameter dicts into an array, columns in :data:`PARAM_ORDER`.

    Parameters
    ----------
    params_list : iterable of dict
        Parameter sets as returned by :func:`seed_parameters` (SI units).

    Returns
    -------
    ndarray, shape (n, 17)
    """
    return np.array([[float(p[k]) for k in PARAM_ORDER] for p in params_list], dtype=float)


def static_point(params: dict) -> tuple[float, float]:
    """Static penetration and dynamic contact stiffness (docs/model.md §3).

    ``z_st < 0`` solves ``F_st = -K_s0 z_st + K_a z_st^2``; ``K_s = K_s0 - 2 K_a z_st``.

    Parameters
    ----------
    params : dict
        Needs ``contact_stiffness`` (K_s0, N/m), ``contact_quadratic`` (K_a, N/m^2) and
        ``normal_load`` (F_st, N).

    Returns
    -------
    z_st : float
        Static penetration, m (negative).
    k_s : float
        Dynamic contact stiffness, N/m.

    Raises
    ------
    ValueError
        If ``normal_load`` is not a positive finite number.
    """
    k0 = float(params["contact_stiffness"])
    ka = float(params["contact_quadratic"])
    f = float(params["normal_load"])
    if not (math.isfinite(f) and f > 0.0):
        raise ValueError(f"normal_load = {f!r} N: must be a positive finite number")
    # Negative root of K_a z^2 - K_s0 z - F_st = 0, written as F/(...) so that it has no
    # cancellation and stays valid for K_a = 0 (where it is -F_st/K_s0).
    z_st = -2.0 * f / (k0 + math.sqrt(k0 * k0 + 4.0 * ka * f))
    return z_st, k0 - 2.0 * ka * z_st


@dataclass(frozen=True)
class _Coeffs:
    """Derived constants of one parameter set (so the RHS does no dict lookups)."""

    m: float
    wz2: float
    wx2: float
    wt2: float
    cz: float  # 2 zeta_z w_z [1/s]
    cx: float
    ct: float
    k_s: float
    k_a: float
    c_zc: float
    k_phi: float
    mu: float
    f_st: float
    z_st: float
    torque_gain: float  # s L / I [1/(kg m)]

    @classmethod
    def of(cls, p: dict) -> "_Coeffs":
        z_st, k_s = static_point(p)
        wz, wx, wt = p["omega_normal"], p["omega_friction"], p["omega_torsion"]
        return cls(
            m=p["mass"],
            wz2=wz * wz,
            wx2=wx * wx,
            wt2=wt * wt,
            cz=2.0 * p["zeta_normal"] * wz,
            cx=2.0 * p["zeta_friction"] * wx,
            ct=2.0 * p["zeta_torsion"] * wt,
            k_s=k_s,
            k_a=p["contact_quadratic"],
            c_zc=p["contact_damping"],
            k_phi=p["twist_coupling"],
            mu=p["mu"],
            f_st=p["normal_load"],
            z_st=z_st,
            torque_gain=p["torsion_sign"] * p["moment_arm"] / p["inertia"],
        )

    def normal_law(self, y) -> float:
        z = y[0]
        return self.f_st - self.k_s * z + self.k_a * z * z - self.c_zc * y[1] + self.k_phi * y[4]

    def deriv(self, y, n: float) -> np.ndarray:
        """dy/dt given the total normal force ``n`` [N]."""
        f_z = n - self.f_st
        f_x = self.mu * f_z
        return np.array(
            [
                y[1],
                f_z / self.m - self.cz * y[1] - self.wz2 * y[0],
                y[3],
                f_x / self.m - self.cx * y[3] - self.wx2 * y[2],
                y[5],
                self.torque_gain * f_x - self.ct * y[5] - self.wt2 * y[4],
            ]
        )


def _check_contact(contact: str) -> None:
    if contact not in ("bilateral", "unilateral"):
        raise ValueError(f"contact = {contact!r}: must be 'bilateral' or 'unilateral'")


def normal_law_force(y, params: dict) -> float:
    """Total normal force of the contact law at state ``y`` [N].

    ``N_law = F_st - K_s z + K_a z^2 - C_zc zd + K_phi phi`` (may be negative: tension).

    Parameters
    ----------
    y : array_like, shape (6,)
        State ``[z m, zd m/s, x m, xd m/s, phi rad, phid rad/s]``.
    params : dict
        Parameter set (SI).
    """
    return _Coeffs.of(params).normal_law(np.asarray(y, dtype=float))


def contact_indicator(y, params: dict) -> float:
    """``min(-K_s zc, N_law)`` [N]: non-negative exactly where the unilateral contact acts.

    The gap is scaled by ``K_s`` so that both arguments are forces; the function is
    continuous, so its zero crossings can be located by a root finder.
    """
    c = _Coeffs.of(params)
    y = np.asarray(y, dtype=float)
    return min(-c.k_s * (c.z_st + y[0]), c.normal_law(y))


def _make_rhs(params: dict, contact: str = "bilateral", mode: str | None = None):
    """Return ``f(t, y)`` for :func:`solve_ivp` (see :func:`rhs` for the arguments)."""
    _check_contact(contact)
    c = _Coeffs.of(params)
    if contact == "bilateral":
        return lambda t, y: c.deriv(y, c.normal_law(y))
    if mode == "contact":
        return lambda t, y: c.deriv(y, c.normal_law(y))
    if mode == "free":
        return lambda t, y: c.deriv(y, 0.0)
    if mode is not None:
        raise ValueError(f"mode = {mode!r}: must be None, 'contact' or 'free'")

    def f_pointwise(t, y):
        n = c.normal_law(y)
        return c.deriv(y, n if (c.z_st + y[0] <= 0.0 and n >= 0.0) else 0.0)

    return f_pointwise


def rhs(t: float, y, params: dict, contact: str = "bilateral", mode: str | None = None) -> np.ndarray:
    """Right-hand side ``dy/dt`` of docs/model.md §2 with constant ``mu``.

    Parameters
    ----------
    t : float
        Time, s (the system is autonomous; ``t`` is ignored).
    y : array_like, shape (6,)
        State ``[z m, zd m/s, x m, xd m/s, phi rad, phid rad/s]``.
    params : dict
        Parameter set (SI, keys of :data:`PARAM_ORDER`).
    contact : {"bilateral", "unilateral"}
        ``bilateral``: the contact law everywhere. ``unilateral``: ``N = 0`` off the disk
        (``zc > 0``) and ``N = max(N_law, 0)`` otherwise.
    mode : {None, "contact", "free"}
        Unilateral only: force the contact mode (what :func:`solve_unilateral` integrates
        between events). ``None`` applies the pointwise switching law, which is
        discontinuous at ``zc = 0``; integrate it only with event location.

    Returns
    -------
    ndarray, shape (6,)
        ``[zd m/s, zdd m/s^2, xd m/s, xdd m/s^2, phid rad/s, phidd rad/s^2]``.
    """
    return _make_rhs(params, contact, mode)(t, np.asarray(y, dtype=float))


def default_atol(rtol: float) -> np.ndarray:
    """Default absolute tolerance ``rtol * STATE_SCALE`` (per state component, SI)."""
    return rtol * STATE_SCALE


def solve(params: dict, y0, t_end: float, t_eval=None, method: str = "DOP853", rtol: float = 1e-13,
          atol=None, **kwargs):
    """Integrate the bilateral model with :func:`scipy.integrate.solve_ivp`.

    Parameters
    ----------
    params : dict
        Parameter set (SI).
    y0 : array_like, shape (6,)
        Initial state (m, m/s, m, m/s, rad, rad/s).
    t_end : float
        End time, s (from t = 0).
    t_eval : array_like, optional
        Output times, s.
    method : str
        solve_ivp method; DOP853 (default) for reference accuracy.
    rtol : float
        Relative tolerance.
    atol : float or array_like, optional
        Absolute tolerance per component (SI); default :func:`default_atol` ``(rtol)``.
    **kwargs
        Passed to solve_ivp (e.g. ``dense_output``, ``max_step``).

    Returns
    -------
    scipy.integrate._ivp.ivp.OdeResult
        ``t`` s, ``y`` shape (6, n_t), ``nfev`` right-hand-side evaluations.

    Raises
    ------
    RuntimeError
        If solve_ivp does not reach ``t_end``.
    """
    if atol is None:
        atol = default_atol(rtol)
    sol = solve_ivp(_make_rhs(params, "bilateral"), (0.0, float(t_end)), np.asarray(y0, dtype=float),
                    method=method, t_eval=t_eval, rtol=rtol, atol=atol, **kwargs)
    if sol.status != 0:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    return sol


# --- unilateral contact: piecewise integration between located events ----------------------------


@dataclass
class UnilateralSolution:
    """Result of :func:`solve_unilateral`.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Sample times, s.
    y : ndarray, shape (6, n)
        States at ``t``.
    mode : ndarray of str, shape (n,)
        Contact mode of the segment each sample belongs to (``"contact"`` or ``"free"``).
    t_switch : ndarray
        Times of the mode switches, s.
    y_switch : ndarray, shape (6, n_switch)
        States at the switches.
    modes : list of str
        Mode of each segment (``len(t_switch) + 1`` entries).
    y_end : ndarray, shape (6,)
        State at ``t_end``.
    min_normal_force : float
        Minimum of the applied normal force ``N = max(N_law, 0)`` over the samples, N
        (0 if the contact opened at a sample).
    nfev : int
        Right-hand-side evaluations over all segments.
    """

    t: np.ndarray
    y: np.ndarray
    mode: np.ndarray
    t_switch: np.ndarray
    y_switch: np.ndarray
    modes: list = field(default_factory=list)
    y_end: np.ndarray | None = None
    min_normal_force: float = float("nan")
    nfev: int = 0


def _events(c: _Coeffs, mode: str):
    """Terminal events that end a segment integrated in ``mode``.

    In contact, either the gap ``zc`` rising through 0 (the pin lifts off) or the law force
    ``N_law`` falling through 0 (the law would pull) ends it. Free, the contact resumes when
    ``min(-K_s zc, N_law)`` rises through 0: the pin is on or in the disk *and* the law pushes
    (a landing with a pulling law force keeps it free until ``N_law`` turns positive).
    """
    if mode == "contact":
        def gap(t, y):
            return c.z_st + y[0]

        def normal(t, y):
            return c.normal_law(y)

        gap.terminal, gap.direction = True, 1.0
        normal.terminal, normal.direction = True, -1.0
        return [gap, normal]

    def touch(t, y):
        return min(-c.k_s * (c.z_st + y[0]), c.normal_law(y))

    touch.terminal, touch.direction = True, 1.0
    return [touch]


def _event_values(c: _Coeffs, mode: str, y: np.ndarray) -> np.ndarray:
    """The terminal events of :func:`_events` at the states ``y`` (6, n), one row per event, in trigger sign.

    Each row is the event function times its direction, so a trigger is a rise through 0, in
    units of its scale (``|z_st|`` for the gap, ``F_st`` for forces).
    """
    if mode == "contact":
        return np.vstack([(c.z_st + y[0]) / abs(c.z_st), -c.normal_law(y) / c.f_st])
    return (np.minimum(-c.k_s * (c.z_st + y[0]), c.normal_law(y)) / c.f_st)[None, :]


@dataclass
class _Pass:
    nfev: int
    t_samples: np.ndarray
    y_samples: np.ndarray


#: Length of the eventless step taken at every restart, s (a ten-millionth of a torsion period at
#: the seed: far below any flight or contact phase the model resolves).
GRAZING_STEP: float = 1e-9


def _grazing_pass(params: dict, c: _Coeffs, mode: str, t: float, y: np.ndarray, t_end: float, rtol: float, atol,
                  method: str, t_eval) -> tuple[str, float, np.ndarray, _Pass]:
    """Step ``GRAZING_STEP`` past a restart point without events, in the first consistent mode.

    ``mode`` (the new one) is tried first, then the old one (a grazing touch: the pin meets the
    disk with no normal speed, or the law force touches 0 and rises again). A mode is consistent
    if none of its events is triggered at the end of the step (all below 0 in trigger sign).
    Raises RuntimeError if neither is (a sticking contact).
    """
    t1 = min(t + GRAZING_STEP, t_end)
    for m in (mode, "free" if mode == "contact" else "contact"):
        sol = solve_ivp(_make_rhs(params, "unilateral", m), (t, t1), y, method=method, rtol=rtol, atol=atol,
                        dense_output=True)  # fmt: skip
        y1 = sol.y[:, -1].copy()
        if sol.status == 0 and np.all(_event_values(c, m, y1[:, None]) < 0.0):
            if t_eval is None:
                samples = np.array([t1])
            else:
                samples = t_eval[(t_eval > t) & (t_eval <= t1)]
            ys = sol.sol(samples) if samples.size else np.empty((6, 0))
            return m, t1, y1, _Pass(int(sol.nfev), samples, ys)
    raise RuntimeError(f"contact chatter (grazing) at t = {t} s: neither mode is consistent past it")


def solve_unilateral(params: dict, y0, t_end: float, rtol: float = 1e-12, atol=None, t_eval=None,
                     method: str = "DOP853", max_switches: int = 100_000,
                     min_segment: float = 1e-12) -> UnilateralSolution:
    """Integrate the unilateral model piecewise, restarting at every contact switch.

    Each segment is integrated in one fixed mode (smooth right-hand side) until a terminal
    event of :func:`_events` is located by solve_ivp (root of the dense output to machine
    precision); the integration restarts from the event state in the other mode.

    Grazing guard: the events are *directional* and the restart happens exactly at the
    located root, so the event function of the new mode starts at zero (to rounding) and
    moving away from its trigger direction; a crossing at the restart point is therefore not
    re-detected. A restart exactly on the root (an event function of exactly 0) would re-trigger
    at once in solve_ivp and skip a whole contact phase, so every restart first takes one short
    eventless step (:func:`_grazing_pass`) in the mode that stays consistent: the new mode, or
    the old one at a grazing touch. If a grazing contact still produces segments shorter than
    ``min_segment``
    seconds 20 times in a row, the run is declared chattering and a RuntimeError is raised
    (a sticking-contact model would be needed there).

    Parameters
    ----------
    params : dict
        Parameter set (SI).
    y0 : array_like, shape (6,)
        Initial state (m, m/s, m, m/s, rad, rad/s).
    t_end : float
        End time, s (from t = 0).
    rtol : float
        Relative tolerance of each segment.
    atol : float or array_like, optional
        Absolute tolerance (SI per component); default :func:`default_atol` ``(rtol)``.
    t_eval : array_like, optional
        Sample times, s; default: the integrator's own steps.
    method : str
        solve_ivp method.
    max_switches : int
        Limit on the number of mode switches.
    min_segment : float
        Segment length below which a segment counts as a grazing re-trigger, s.

    Returns
    -------
    UnilateralSolution
    """
    if atol is None:
        atol = default_atol(rtol)
    c = _Coeffs.of(params)
    y = np.asarray(y0, dtype=float).copy()
    mode = "contact" if (c.z_st + y[0] <= 0.0 and c.normal_law(y) >= 0.0) else "free"
    t_eval = None if t_eval is None else np.asarray(t_eval, dtype=float)
    t = 0.0
    ts, ys, ms = [], [], []
    t_sw, y_sw, modes = [], [], [mode]
    nfev, n_short = 0, 0
    while True:
        sol = solve_ivp(_make_rhs(params, "unilateral", mode), (t, t_end), y, method=method, rtol=rtol,
                        atol=atol, events=_events(c, mode), dense_output=t_eval is not None)
        if sol.status < 0:
            raise RuntimeError(f"solve_ivp failed at t = {t} s: {sol.message}")
        nfev += sol.nfev
        t_seg_end, y = sol.t[-1], sol.y[:, -1].copy()  # t_end, or the located event
        if t_eval is None:
            keep = slice(1, None) if ts else slice(None)  # the restart point is already stored
            seg_t, seg_y = sol.t[keep], sol.y[:, keep]
        else:
            # Samples in (t, t_seg_end]; the first segment also takes t = 0.
            sel = (t_eval > t) | ((t_eval == t) & (not t_sw))
            seg_t = t_eval[sel & (t_eval <= t_seg_end)]
            seg_y = sol.sol(seg_t) if seg_t.size else np.empty((6, 0))
        ts.append(seg_t)
        ys.append(seg_y)
        ms.append(np.full(seg_t.shape, mode))
        if sol.status == 0:  # reached t_end
            break
        # Terminal event: restart at the located root in the other mode.
        n_short = n_short + 1 if t_seg_end - t < min_segment else 0
        if n_short >= 20:
            raise RuntimeError(f"contact chatter (grazing) at t = {t_seg_end} s: "
                               f"{n_short} segments shorter than {min_segment} s")
        t = t_seg_end
        mode = "free" if mode == "contact" else "contact"
        # At the restart the new mode's events are 0 to rounding (exactly 0 re-triggers at once in
        # solve_ivp, a zero-length segment that skips a whole contact phase). Step past it without
        # events in the mode that stays consistent: the new one, or at a grazing touch (the pin
        # meets the disk with no normal speed, or the law force touches 0) the old one.
        t_sw.append(t)
        y_sw.append(y.copy())
        mode, t, y, seg = _grazing_pass(params, c, mode, t, y, t_end, rtol, atol, method, t_eval)
        nfev += seg.nfev
        if seg.t_samples.size:
            ts.append(seg.t_samples)
            ys.append(seg.y_samples)
            ms.append(np.full(seg.t_samples.shape, mode))
        if mode == modes[-1]:  # passed a grazing touch: no switch after all
            t_sw.pop()
            y_sw.pop()
        else:
            modes.append(mode)
        if len(t_sw) > max_switches:
            raise RuntimeError(f"more than max_switches = {max_switches} contact switches")
        if t >= t_end:
            break
    t_all = np.concatenate(ts)
    y_all = np.concatenate(ys, axis=1)
    m_all = np.concatenate(ms)
    # Applied N: max(N_law, 0) in contact (N_law is 0 to rounding at a located N event).
    n_applied = [max(c.normal_law(y_all[:, i]), 0.0) if m_all[i] == "contact" else 0.0
                 for i in range(t_all.size)]
    return UnilateralSolution(
        t=t_all,
        y=y_all,
        mode=m_all,
        t_switch=np.array(t_sw),
        y_switch=np.array(y_sw).T.reshape(6, -1),
        modes=modes,
        y_end=y,
        min_normal_force=float(min(n_applied)) if n_applied else float("nan"),
        nfev=int(nfev),
    )


# --- linear stability ---------------------------------------------------------------------------


def linear_jacobian(params: dict) -> np.ndarray:
    """6x6 Jacobian of the bilateral RHS at ``y = 0`` (steady sliding), by central differences.

    The RHS is at most quadratic in the state (the ``K_a z^2`` term), so a central difference
    at ``y = 0`` is exact up to rounding; the step of each component is ``1e-3 STATE_SCALE``.

    Parameters
    ----------
    params : dict
        Parameter set (SI).

    Returns
    -------
    ndarray, shape (6, 6)
        ``J[i, j] = d(dy_i/dt)/dy_j`` in SI units.
    """
    f = _make_rhs(params, "bilateral")
    jac = np.empty((6, 6))
    for j in range(6):
        h = 1e-3 * STATE_SCALE[j]
        e = np.zeros(6)
        e[j] = h
        jac[:, j] = (f(0.0, e) - f(0.0, -e)) / (2.0 * h)
    return jac


def linear_eigenvalues(params: dict) -> np.ndarray:
    """Eigenvalues of the linearisation at steady sliding (docs/model.md §4), 1/s.

    Parameters
    ----------
    params : dict
        Parameter set (SI).

    Returns
    -------
    ndarray of complex, shape (6,)
        Sorted by imaginary part's magnitude, then imaginary part (conjugate pairs adjacent,
        negative imaginary part first). Sliding is linearly stable when all real parts are
        negative.
    """
    lam = np.linalg.eigvals(linear_jacobian(params))
    return lam[np.lexsort((lam.imag, np.abs(lam.imag)))]
