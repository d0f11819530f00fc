"""Speed baselines for the tribosweep ensemble benchmark, measured in the caller's process.

Two baselines for the bilateral, constant-``mu`` slider (docs/model.md §2) over the seed ensemble:

* :func:`scipy_seed_batch`: one :func:`scipy.integrate.solve_ivp` call per parameter set
  (DOP853 or RK45), what a user without tribosweep would write;
* :func:`numba_dp5_batch`: a hand-written adaptive Dormand–Prince 5(4) compiled with numba,
  one core (``parallel=False``: the per-core rate is what the Rust core is compared with),
  plus :func:`numba_dp5_batch_parallel` (``prange`` over trajectories).

:func:`seed_ensemble_params` gives the benchmark's parameter sets. The numba kernel uses the
step control of Hairer's DOPRI5 (PI controller, beta = 0.04, safety 0.9, factor limits
0.2..10) and its RMS error norm ``sqrt(mean((err_i / (atol_i + rtol max(|y_old,i|, |y_new,i|)))^2))``.

Run ``python -m tribosweep.bench.baselines [--n 200]`` for a timing table. Nothing here asserts a time.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from . import reference

PARAM_ORDER = reference.PARAM_ORDER
params_to_array = reference.params_to_array

#: Benchmark defaults (docs/model.md §3 seed; 0.5 s of motion from a 1 um normal disturbance).
T_END = 0.5  # s
Z0 = 1e-6  # m
MU_RANGE = (0.15, 0.30)
LOAD_RANGE = (17.0, 152.0)  # N


def seed_ensemble_params(n: int, seed: int = 0):
    """Parameter sets and initial states of the ensemble benchmark.

    The seed configuration with ``mu`` uniform in [0.15, 0.30] and ``normal_load`` uniform
    in [17, 152] N (``numpy.random.default_rng(seed)``: first ``n`` draws for ``mu``, then
    ``n`` for the load); every run starts from ``z = 1e-6 m``, other states 0, for 0.5 s.

    Parameters
    ----------
    n : int
        Number of parameter sets.
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    params_list : list of dict
        Parameter sets (SI, keys of ``reference.PARAM_ORDER``).
    y0 : ndarray, shape (n, 6)
        Initial states (m, m/s, m, m/s, rad, rad/s).
    t_end : float
        Integration time, s (0.5).
    """
    rng = np.random.default_rng(seed)
    mu = rng.uniform(*MU_RANGE, size=n)
    load = rng.uniform(*LOAD_RANGE, size=n)
    base = reference.seed_parameters()
    params_list = [dict(base, mu=float(m), normal_load=float(f)) for m, f in zip(mu, load)]
    y0 = np.zeros((n, 6))
    y0[:, 0] = Z0
    return params_list, y0, T_END


def _atol_vector(atol, rtol) -> np.ndarray:
    if atol is None:
        return reference.default_atol(rtol).astype(float)
    return np.ascontiguousarray(np.broadcast_to(np.asarray(atol, dtype=float), (6,)))


# --- (a) scipy -----------------------------------------------------------------------------------


def scipy_seed_batch(params_list, t_end: float, rtol: float, atol=None, y0=None, method: str = "DOP853"):
    """Integrate each parameter set with solve_ivp (bilateral model), one after the other.

    Parameters
    ----------
    params_list : list of dict
        Parameter sets (SI).
    t_end : float
        End time, s.
    rtol : float
        Relative tolerance.
    atol : float or array_like, optional
        Absolute tolerance (SI per state component); default ``rtol * STATE_SCALE``.
    y0 : array_like, shape (n, 6), optional
        Initial states; default ``z = 1e-6 m``, others 0.
    method : {"DOP853", "RK45", ...}
        solve_ivp method.

    Returns
    -------
    dict
        ``y_end`` (n, 6) final states; ``n_rhs`` (n,) RHS evaluations; ``n_steps`` (n,)
        accepted steps; ``seconds`` wall time of the whole batch, s;
        ``seconds_per_trajectory`` s.
    """
    n = len(params_list)
    if y0 is None:
        y0 = np.zeros((n, 6))
        y0[:, 0] = Z0
    y0 = np.asarray(y0, dtype=float)
    atol = _atol_vector(atol, rtol)
    y_end = np.empty((n, 6))
    n_rhs = np.empty(n, dtype=np.int64)
    n_steps = np.empty(n, dtype=np.int64)
    t0 = time.perf_counter()
    for i, p in enumerate(params_list):
        sol = reference.solve(p, y0[i], t_end, method=method, rtol=rtol, atol=atol)
        y_end[i] = sol.y[:, -1]
        n_rhs[i] = sol.nfev
        n_steps[i] = sol.t.size - 1
    seconds = time.perf_counter() - t0
    return {"y_end": y_end, "n_rhs": n_rhs, "n_steps": n_steps, "seconds": seconds,
            "seconds_per_trajectory": seconds / max(n, 1)}


# --- (b) numba Dormand–Prince 5(4) ---------------------------------------------------------------

try:
    import numba
except ImportError:  # the scipy baseline still works
    numba = None

# Dormand & Prince (1980) 5(4) tableau, FSAL; E = b5 - b4 (the error estimate's weights).
_C2, _C3, _C4, _C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
_A21 = 1.0 / 5.0
_A31, _A32 = 3.0 / 40.0, 9.0 / 40.0
_A41, _A42, _A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_A51, _A52, _A53, _A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_A61, _A62, _A63, _A64, _A65 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0
_B1, _B3, _B4, _B5, _B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
_E1, _E3, _E4, _E5, _E6, _E7 = (71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0,
                                22.0 / 525.0, -1.0 / 40.0)

# Step control (Hairer, DOPRI5 defaults).
_SAFE, _FAC_MIN, _FAC_MAX, _BETA = 0.9, 0.2, 10.0, 0.04
_EXPO1 = 0.2 - _BETA * 0.75
MAX_STEPS = 10_000_000

# Layout of the derived-coefficient vector the kernel's RHS reads.
_NC = 14  # m, wz2, wx2, wt2, cz, cx, ct, k_s, k_a, c_zc, k_phi, mu, torque_gain, (unused)


def _derive(P):
    """Derived coefficients of one parameter row (PARAM_ORDER columns)."""
    (m, inertia, arm, wz, wx, wt, zz, zx, zt, k0, ka, czc, kphi, mu, f_st, _v, s) = (
        P[0], P[1], P[2], P[3], P[4], P[5], P[6], P[7], P[8], P[9], P[10], P[11], P[12], P[13], P[14],
        P[15], P[16])
    z_st = -2.0 * f_st / (k0 + math.sqrt(k0 * k0 + 4.0 * ka * f_st))
    c = np.empty(_NC)
    c[0] = m
    c[1] = wz * wz
    c[2] = wx * wx
    c[3] = wt * wt
    c[4] = 2.0 * zz * wz
    c[5] = 2.0 * zx * wx
    c[6] = 2.0 * zt * wt
    c[7] = k0 - 2.0 * ka * z_st  # K_s
    c[8] = ka
    c[9] = czc
    c[10] = kphi
    c[11] = mu
    c[12] = s * arm / inertia
    c[13] = 0.0
    return c


def _rhs(c, y, out):
    """Bilateral constant-mu slider: dy/dt into ``out`` (no allocation)."""
    z = y[0]
    f_z = -c[7] * z + c[8] * z * z - c[9] * y[1] + c[10] * y[4]  # dynamic normal force [N]
    f_x = c[11] * f_z
    out[0] = y[1]
    out[1] = f_z / c[0] - c[4] * y[1] - c[1] * z
    out[2] = y[3]
    out[3] = f_x / c[0] - c[5] * y[3] - c[2] * y[2]
    out[4] = y[5]
    out[5] = c[12] * f_x - c[6] * y[5] - c[3] * y[4]


def _dp5_one(P, y0, t_end, rtol, atol, y_out):
    """Integrate one trajectory from 0 to ``t_end``; returns (n_steps, n_rhs); NaN on failure."""
    c = _derive(P)
    n = 6
    y = y0.copy()
    y1 = np.empty(n)
    yt = np.empty(n)
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    k5 = np.empty(n)
    k6 = np.empty(n)
    k7 = np.empty(n)
    _rhs(c, y, k1)
    n_rhs = 1
    # Initial step (Hairer's HINIT).
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        sk = atol[i] + rtol * abs(y[i])
        d0 += (y[i] / sk) ** 2
        d1 += (k1[i] / sk) ** 2
    d0 = math.sqrt(d0 / n)
    d1 = math.sqrt(d1 / n)
    h0 = 1e-6 if (d0 < 1e-10 or d1 < 1e-10) else 0.01 * d0 / d1
    h0 = min(h0, t_end)
    for i in range(n):
        yt[i] = y[i] + h0 * k1[i]
    _rhs(c, yt, k2)
    n_rhs += 1
    d2 = 0.0
    for i in range(n):
        sk = atol[i] + rtol * abs(y[i])
        d2 += ((k2[i] - k1[i]) / sk) ** 2
    d2 = math.sqrt(d2 / n) / h0
    dm = max(d1, d2)
    h1 = max(1e-6, h0 * 1e-3) if dm <= 1e-15 else (0.01 / dm) ** 0.2
    h = min(100.0 * h0, h1, t_end)

    t = 0.0
    fac_old = 1e-4
    last_rejected = False
    n_steps = 0
    while t < t_end:
        if n_steps >= MAX_STEPS or 0.1 * h <= 2.220446049250313e-16 * t:  # step size underflow
            for i in range(n):
                y_out[i] = np.nan
            return n_steps, n_rhs
        last = False
        if t + 1.01 * h >= t_end:
            h = t_end - t
            last = True
        for i in range(n):
            yt[i] = y[i] + h * _A21 * k1[i]
        _rhs(c, yt, k2)
        for i in range(n):
            yt[i] = y[i] + h * (_A31 * k1[i] + _A32 * k2[i])
        _rhs(c, yt, k3)
        for i in range(n):
            yt[i] = y[i] + h * (_A41 * k1[i] + _A42 * k2[i] + _A43 * k3[i])
        _rhs(c, yt, k4)
        for i in range(n):
            yt[i] = y[i] + h * (_A51 * k1[i] + _A52 * k2[i] + _A53 * k3[i] + _A54 * k4[i])
        _rhs(c, yt, k5)
        for i in range(n):
            yt[i] = y[i] + h * (_A61 * k1[i] + _A62 * k2[i] + _A63 * k3[i] + _A64 * k4[i] + _A65 * k5[i])
        _rhs(c, yt, k6)
        for i in range(n):
            y1[i] = y[i] + h * (_B1 * k1[i] + _B3 * k3[i] + _B4 * k4[i] + _B5 * k5[i] + _B6 * k6[i])
        _rhs(c, y1, k7)  # FSAL: k7 is k1 of the next step
        n_rhs += 6
        err = 0.0
        for i in range(n):
            e = h * (_E1 * k1[i] + _E3 * k3[i] + _E4 * k4[i] + _E5 * k5[i] + _E6 * k6[i] + _E7 * k7[i])
            sk = atol[i] + rtol * max(abs(y[i]), abs(y1[i]))
            err += (e / sk) ** 2
        err = math.sqrt(err / n)
        fac11 = err**_EXPO1 if err > 0.0 else 0.0
        if err <= 1.0:
            # PI control (Lund stabilisation): fac = err^expo1 / err_old^beta.
            fac = fac11 / fac_old**_BETA
            fac = max(1.0 / _FAC_MAX, min(1.0 / _FAC_MIN, fac / _SAFE))
            h_new = h / fac
            fac_old = max(err, 1e-4)
            t = t_end if last else t + h
            for i in range(n):
                y[i] = y1[i]
                k1[i] = k7[i]
            n_steps += 1
            if last_rejected:
                h_new = min(h_new, h)
            last_rejected = False
            h = h_new
        else:
            h = h / min(1.0 / _FAC_MIN, fac11 / _SAFE)
            last_rejected = True
    for i in range(n):
        y_out[i] = y[i]
    return n_steps, n_rhs


def _dp5_batch(P, Y0, t_end, rtol, atol):
    m = P.shape[0]
    y_end = np.empty((m, 6))
    n_steps = np.zeros(m, dtype=np.int64)
    n_rhs = np.zeros(m, dtype=np.int64)
    for j in range(m):
        s, r = _dp5_one(P[j], Y0[j], t_end, rtol, atol, y_end[j])
        n_steps[j] = s
        n_rhs[j] = r
    return y_end, n_steps, n_rhs


def _dp5_batch_prange(P, Y0, t_end, rtol, atol):
    m = P.shape[0]
    y_end = np.empty((m, 6))
    n_steps = np.zeros(m, dtype=np.int64)
    n_rhs = np.zeros(m, dtype=np.int64)
    for j in numba.prange(m):
        s, r = _dp5_one(P[j], Y0[j], t_end, rtol, atol, y_end[j])
        n_steps[j] = s
        n_rhs[j] = r
    return y_end, n_steps, n_rhs


if numba is not None:
    _derive = numba.njit(cache=False)(_derive)
    _rhs = numba.njit(inline="always")(_rhs)
    _dp5_one = numba.njit(_dp5_one)
    dp5_batch_kernel = numba.njit(parallel=False)(_dp5_batch)
    dp5_batch_kernel_parallel = numba.njit(parallel=True)(_dp5_batch_prange)
else:
    dp5_batch_kernel = dp5_batch_kernel_parallel = None


def _kernel_args(P, y0, rtol, atol):
    P = np.ascontiguousarray(P, dtype=float)
    if P.ndim != 2 or P.shape[1] != len(PARAM_ORDER):
        raise ValueError(f"P has shape {P.shape}: must be (n, {len(PARAM_ORDER)}) with columns PARAM_ORDER")
    y0 = np.ascontiguousarray(np.broadcast_to(np.asarray(y0, dtype=float), (P.shape[0], 6)))
    return P, y0, float(rtol), _atol_vector(atol, rtol)


def numba_dp5_batch(P, y0, t_end: float, rtol: float, atol=None):
    """Adaptive Dormand–Prince 5(4) over a batch, numba, one core.

    Parameters
    ----------
    P : ndarray, shape (n, 17)
        Parameter sets, columns in ``reference.PARAM_ORDER`` (SI; see
        ``reference.params_to_array``).
    y0 : ndarray, shape (n, 6) or (6,)
        Initial states (m, m/s, m, m/s, rad, rad/s).
    t_end : float
        End time, s.
    rtol : float
        Relative tolerance.
    atol : float or array_like of 6, optional
        Absolute tolerance per state component (SI); default ``rtol * STATE_SCALE``.

    Returns
    -------
    Y_end : ndarray, shape (n, 6)
        Final states (NaN where the step size underflowed or MAX_STEPS was hit).
    n_steps : ndarray of int64, shape (n,)
        Accepted steps.
    n_rhs : ndarray of int64, shape (n,)
        Right-hand-side evaluations.
    """
    if numba is None:
        raise ImportError("numba is not installed: numba_dp5_batch needs it")
    P, y0, rtol, atol = _kernel_args(P, y0, rtol, atol)
    return dp5_batch_kernel(P, y0, float(t_end), rtol, atol)


def numba_dp5_batch_parallel(P, y0, t_end: float, rtol: float, atol=None):
    """As :func:`numba_dp5_batch`, with ``prange`` over trajectories (all numba threads)."""
    if numba is None:
        raise ImportError("numba is not installed: numba_dp5_batch_parallel needs it")
    P, y0, rtol, atol = _kernel_args(P, y0, rtol, atol)
    return dp5_batch_kernel_parallel(P, y0, float(t_end), rtol, atol)


def warmup() -> None:
    """Compile the numba kernels (both variants) on a two-trajectory batch."""
    if numba is None:
        return
    params_list, y0, _ = seed_ensemble_params(2)
    P = params_to_array(params_list)
    numba_dp5_batch(P, y0, 1e-3, 1e-6)
    numba_dp5_batch_parallel(P, y0, 1e-3, 1e-6)


def time_numba(P, y0, t_end, rtol, atol=None, parallel=False, repeat=3):
    """Best-of-``repeat`` wall time of a numba batch (JIT warmed up first).

    Returns
    -------
    dict
        ``y_end``, ``n_steps``, ``n_rhs`` as :func:`numba_dp5_batch`; ``seconds`` (best), s;
        ``seconds_per_trajectory``, s.
    """
    warmup()
    f = numba_dp5_batch_parallel if parallel else numba_dp5_batch
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        y_end, n_steps, n_rhs = f(P, y0, t_end, rtol, atol)
        best = min(best, time.perf_counter() - t0)
    return {"y_end": y_end, "n_steps": n_steps, "n_rhs": n_rhs, "seconds": best,
            "seconds_per_trajectory": best / max(P.shape[0], 1)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200, help="trajectories (numba)")
    ap.add_argument("--n-scipy", type=int, default=20, help="trajectories (scipy; slow)")
    ap.add_argument("--rtol", type=float, nargs="+", default=[1e-6, 1e-9])
    args = ap.parse_args(argv)
    params_list, y0, t_end = seed_ensemble_params(args.n)
    P = params_to_array(params_list)
    ns = min(args.n_scipy, args.n)
    # Truth for the accuracy column: DOP853 at rtol 1e-13 on the scipy subset.
    truth = scipy_seed_batch(params_list[:ns], t_end, 1e-13, y0=y0[:ns])["y_end"]
    print(f"seed ensemble: n = {args.n} (scipy: {ns}), t_end = {t_end} s, atol = rtol * STATE_SCALE")
    print(f"{'method':<22}{'rtol':>8}{'ms/traj':>10}{'steps':>9}{'n_rhs':>9}{'max err z / max|z_end|':>26}")
    for rtol in args.rtol:
        rows = []
        for method in ("DOP853", "RK45"):
            r = scipy_seed_batch(params_list[:ns], t_end, rtol, y0=y0[:ns], method=method)
            rows.append((f"scipy {method}", r, r["y_end"]))
        if numba is not None:
            r = time_numba(P, y0, t_end, rtol)
            rows.append(("numba DP5 (1 core)", r, r["y_end"][:ns]))
            r = time_numba(P, y0, t_end, rtol, parallel=True)
            rows.append((f"numba DP5 prange x{numba.get_num_threads()}", r, r["y_end"][:ns]))
        for name, r, ye in rows:
            err = np.max(np.abs(ye[:, 0] - truth[:, 0])) / np.max(np.abs(truth[:, 0]))
            print(f"{name:<22}{rtol:>8.0e}{1e3 * r['seconds_per_trajectory']:>10.3f}"
                  f"{np.mean(r['n_steps']):>9.0f}{np.mean(r['n_rhs']):>9.0f}{err:>26.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
