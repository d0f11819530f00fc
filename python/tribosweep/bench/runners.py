"""Work-precision runners: one batch of a scene through the Rust core or a baseline (scipy, numba, diffrax), timed best-of-repeat in this process."""

from __future__ import annotations

import importlib.util
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .._codes import STATUS, STATUS_NAMES
from .._simulate import ensemble
from .scenes import MAX_ERROR, Scene


@dataclass
class BatchRun:
    """What one method returned for a batch at one tolerance (arrays over trajectories)."""

    z_end: np.ndarray
    status: np.ndarray
    n_rhs: np.ndarray
    steps: np.ndarray
    n_reject: np.ndarray
    seconds: float  # best-of-repeat wall time of the whole batch, s
    reason: str = ""
    extra: dict = field(default_factory=dict)


def _best_of(f: Callable[[], object], repeat: int) -> tuple[float, object]:
    best, out = math.inf, None
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run_rust(scene: Scene, method: str, rtol: float, *, repeat: int = 3, threads: int = 1) -> BatchRun:
    """The batch through :func:`tribosweep.ensemble` (``threads`` Rust threads), best of ``repeat``."""
    atol = scene.atol(rtol)

    def f():
        return ensemble(scene.model, scene.t_end, scene.params, y0=scene.y0, method=method, rtol=rtol, atol=atol,
                        threads=threads)  # fmt: skip

    seconds, ds = _best_of(f, repeat)
    status = ds.status.values.astype(int)
    reasons = sorted({str(r) for r, s in zip(ds.reason.values, status) if s != 0 and str(r)})
    return BatchRun(
        z_end=ds.z_end.values.copy(), status=status, n_rhs=ds.n_rhs.values, steps=ds.n_accept.values,
        n_reject=ds.n_reject.values, seconds=seconds, reason="; ".join(reasons)[:200],
        extra={k: ds[k].values.copy() for k in ("max_abs_z", "max_gap", "min_slip_velocity", "min_normal_force",
                                                  "n_events")},
    )  # fmt: skip


def _scipy_batch(scene: Scene, method: str, rtol: float, repeat: int) -> BatchRun:
    """scipy: ``reference.solve`` (bilateral) or ``reference.solve_unilateral`` (event-driven), one by one."""
    from . import reference

    params = scene.reference_params()
    atol = scene.atol(rtol)
    unilateral = scene.is_unilateral_constant()

    def f():
        n = scene.n
        z = np.full(n, np.nan)
        status = np.zeros(n, dtype=int)
        nfev = np.zeros(n, dtype=np.int64)
        steps = np.zeros(n, dtype=np.int64)
        reasons = []
        for i, p in enumerate(params):
            try:
                if unilateral:
                    sol = reference.solve_unilateral(p, scene.y0[i], scene.t_end, rtol=rtol, atol=atol, method=method)
                    z[i], nfev[i], steps[i] = sol.y_end[0], sol.nfev, sol.t.size - 1
                else:
                    sol = reference.solve(p, scene.y0[i], scene.t_end, method=method, rtol=rtol, atol=atol)
                    z[i], nfev[i], steps[i] = sol.y[0, -1], sol.nfev, sol.t.size - 1
            except RuntimeError as e:  # solve_ivp's only failure: the step size underflowed
                status[i] = STATUS["event_chatter"] if "chatter" in str(e) else STATUS["step_too_small"]
                reasons.append(str(e))
        return z, status, nfev, steps, reasons

    seconds, (z, status, nfev, steps, reasons) = _best_of(f, repeat)
    return BatchRun(z_end=z, status=status, n_rhs=nfev, steps=steps, n_reject=np.zeros_like(steps),
                    seconds=seconds, reason="; ".join(sorted(set(reasons)))[:200])  # fmt: skip


def _scipy_switch_batch(scene: Scene, rtol: float) -> BatchRun:
    """End states of the switch law by the independent ``reference_switch.SwitchReference`` (bilateral; untimed)."""
    from . import reference_switch

    base = scene.model.values()
    z = np.full(scene.n, np.nan)
    for i in range(scene.n):
        values = dict(base, **{k: float(v[i]) for k, v in scene.params.items()})
        y, _ = reference_switch.SwitchReference(values).solve(scene.y0[i], scene.t_end, [scene.t_end], rtol=rtol,
                                                       atol=scene.atol(rtol))  # fmt: skip
        z[i] = y[-1, 0]
    zeros = np.zeros(scene.n, dtype=np.int64)
    return BatchRun(z_end=z, status=np.where(np.isfinite(z), 0, STATUS["non_finite"]), n_rhs=zeros, steps=zeros,
                    n_reject=zeros, seconds=math.nan)  # fmt: skip


def find_baselines_module():
    """The numba Dormand-Prince kernel (:mod:`tribosweep.bench.baselines`), or None without numba."""
    import importlib.util

    if importlib.util.find_spec("numba") is None:
        return None
    from . import baselines

    return baselines


def _numba_batch(bl, scene: Scene, rtol: float, repeat: int) -> BatchRun:
    """The numba Dormand-Prince 5(4) kernel of :mod:`tribosweep.bench.baselines` (one core, bilateral constant mu)."""
    from . import reference

    P = reference.params_to_array(scene.reference_params())
    atol = scene.atol(rtol)
    seconds, (y_end, n_steps, n_rhs) = _best_of(lambda: bl.numba_dp5_batch(P, scene.y0, scene.t_end, rtol, atol),
                                                repeat)  # fmt: skip
    z = y_end[:, 0]
    bad = ~np.isfinite(z)
    status = np.where(bad, STATUS["step_too_small"], 0)
    reason = "numba kernel returned NaN (step underflow or its MAX_STEPS)" if bad.any() else ""
    return BatchRun(z_end=z, status=status, n_rhs=n_rhs, steps=n_steps, n_reject=np.zeros_like(n_steps),
                    seconds=seconds, reason=reason)  # fmt: skip


def diffrax_available() -> bool:
    """True when diffrax (and jax) can be imported."""
    return importlib.util.find_spec("diffrax") is not None and importlib.util.find_spec("jax") is not None


_DIFFRAX_COMPILED: dict = {}


def _diffrax_batch(scene: Scene, rtol: float, repeat: int) -> BatchRun:
    """diffrax Dopri5 (jax, float64, ``vmap`` over the batch), bilateral constant mu.

    The solve is compiled once per scene (the controller's tolerances are traced arguments, so a new rung
    does not recompile) and run once before timing.
    """
    import diffrax
    import jax
    import jax.numpy as jnp

    from . import reference

    jax.config.update("jax_enable_x64", True)
    key = (scene.name, scene.t_end, scene.n)
    if key not in _DIFFRAX_COMPILED:

        def rhs(t, y, c):
            f_z = -c[7] * y[0] + c[8] * y[0] ** 2 - c[9] * y[1] + c[10] * y[4]
            f_x = c[11] * f_z
            return jnp.stack([y[1], f_z / c[0] - c[4] * y[1] - c[1] * y[0], y[3],
                              f_x / c[0] - c[5] * y[3] - c[2] * y[2], y[5], c[12] * f_x - c[6] * y[5] - c[3] * y[4]])

        term, solver = diffrax.ODETerm(rhs), diffrax.Dopri5()

        def one(c, y0, rtol, atol):
            ctrl = diffrax.PIDController(rtol=rtol, atol=atol)
            sol = diffrax.diffeqsolve(term, solver, 0.0, scene.t_end, None, y0, args=c, stepsize_controller=ctrl,
                                      max_steps=1_000_000, throw=False)  # fmt: skip
            ok = sol.result == diffrax.RESULTS.successful
            return sol.ys[-1], ok, sol.stats["num_accepted_steps"], sol.stats["num_rejected_steps"]

        _DIFFRAX_COMPILED[key] = jax.jit(jax.vmap(one, in_axes=(0, 0, None, None)))
    f = _DIFFRAX_COMPILED[key]
    names = ("m", "wz2", "wx2", "wt2", "cz", "cx", "ct", "k_s", "k_a", "c_zc", "k_phi", "mu", "torque_gain")
    C = jnp.asarray([[getattr(reference._Coeffs.of(p), k) for k in names] for p in scene.reference_params()])
    args = (C, jnp.asarray(scene.y0), jnp.asarray(rtol), jnp.asarray(scene.atol(rtol)))
    jax.block_until_ready(f(*args))  # compile (first rung) and warm up outside the timing
    seconds, out = _best_of(lambda: jax.block_until_ready(f(*args)), repeat)
    ys, ok, steps, rejected = (np.asarray(a) for a in out)
    status = np.where(ok, 0, STATUS["max_steps"])
    # Dopri5 is FSAL: 6 new right-hand sides per attempted step (plus the first one).
    return BatchRun(z_end=ys[:, 0], status=status, n_rhs=6 * (steps + rejected) + 1, steps=steps,
                    n_reject=rejected, seconds=seconds, reason="diffrax result != successful" if status.any() else "")


# --- rows ------------------------------------------------------------------------------------------


def error_of(z_end: np.ndarray, z_ref: np.ndarray, scale: np.ndarray) -> float:
    """``max_i |z_i - z_ref,i| / scale_i``; NaN when any trajectory is not finite."""
    z_end, z_ref, scale = (np.asarray(a, dtype=np.float64) for a in (z_end, z_ref, scale))
    k = z_end.size
    d = np.abs(z_end - z_ref[:k]) / scale[:k]
    if not np.all(np.isfinite(d)):
        return math.nan
    return float(np.max(d))


def _status_name(status: np.ndarray) -> str:
    bad = status[status != 0]
    if bad.size == 0:
        return "success"
    codes, counts = np.unique(bad, return_counts=True)
    return STATUS_NAMES[int(codes[np.argmax(counts)])]


def is_failed(row: dict) -> bool:
    """A rung failed: some trajectory has a non-zero status, the error is NaN, or it exceeds ``MAX_ERROR``."""
    err = row.get("error")
    return bool(row.get("n_failed", 0) > 0 or err is None or not math.isfinite(err) or err > MAX_ERROR)
