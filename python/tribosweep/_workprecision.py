"""Work-precision: error against wall time over a tolerance ladder, per integrator and scene.

For each *scene* (a small batch of trajectories of one physical situation) and each method, the
batch is integrated once per rung of a relative-tolerance ladder; a rung records the best-of-``repeat``
wall time per trajectory, the error against a tight reference, and the work counters. The Rust core's
integrators (``dopri5``, ``dop853``, ``rodas4``, through :func:`tribosweep.ensemble` with one thread)
are measured beside baselines run in the same process: scipy ``solve_ivp`` (the independent
``tribosweep.reference``), the numba Dormand-Prince kernel of ``benches/baselines.py`` (found in a
checkout) and diffrax (only where it is importable). A failed rung (a non-zero status, a NaN, or an
error above 1) is recorded and drawn, never dropped.

Error of a rung: ``max_i |z_i(t_end) - z_ref,i(t_end)| / max|z_ref,i|`` over the batch, where the
reference is the Rust DOP853 at ``rtol = 1e-13`` and ``max|z_ref,i|`` the largest ``|z|`` of reference
run ``i``. Each reference is checked against a second solver (scipy DOP853 at 1e-13 for the bilateral
seed, the event-driven scipy solver for unilateral scenes, the Rust Dopri5 at 1e-12 where scipy has no
model); errors below that check are not resolved and the charts shade them.

Every method gets the same absolute tolerance, ``rtol`` times each component's characteristic size
(``|z_st|`` for z and x, ``|z_st|/L`` for phi, those times ``omega_torsion`` for rates).

Entry points: :func:`run_work_precision` (measure, write CSV/JSON/PNG/markdown),
:func:`render_summary` (markdown from the JSON table), :func:`time_at_error` (log-log interpolation
of a work-precision line), :func:`plot_work_precision` (one scene's chart as a Figure).
"""

from __future__ import annotations

import csv
import dataclasses
import datetime
import importlib.util
import json
import math
import os
import pathlib
import platform
import subprocess
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ._flags import STATUS, STATUS_NAMES
from ._model import SliderModel
from ._simulate import ensemble

#: Integrators of the Rust core, in the order they are drawn.
RUST_METHODS: tuple[str, ...] = ("dopri5", "dop853", "rodas4")
#: Tolerance of the reference runs (Rust DOP853).
REF_RTOL = 1e-13
#: Full ladder: rtol 1e-3 .. 1e-12, one rung per decade.
FULL_LADDER: tuple[float, ...] = tuple(10.0**-k for k in range(3, 13))
#: Quick ladder: every other decade, down to 1e-12 so that the explicit lines reach an error of 1e-9.
QUICK_LADDER: tuple[float, ...] = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
#: Errors at which speed ratios and the fastest method are quoted.
MATCHED_ERRORS: tuple[float, ...] = (1e-6, 1e-9)
#: Errors at which the fastest method per scene is quoted.
FASTEST_AT: tuple[float, ...] = (1e-3, 1e-6, 1e-9)
#: A rung with an error above this counts as failed.
MAX_ERROR = 1.0
#: Columns of the CSV table, in order.
COLUMNS: tuple[str, ...] = (
    "scene", "impl", "method", "label", "rtol", "n_traj", "seconds_per_traj", "error", "n_rhs", "steps",
    "n_reject", "status", "n_failed", "failed", "reason",
)  # fmt: skip
#: Pairs (Rust label, baseline label) whose speed ratio the summary quotes at matched error.
RATIO_PAIRS: tuple[tuple[str, str], ...] = (
    ("rust dopri5", "numba DP5"),
    ("rust dopri5", "scipy RK45"),
    ("rust dop853", "scipy DOP853"),
    ("rust rodas4", "scipy Radau"),
    ("rust (fastest)", "scipy (fastest)"),
    ("rust (fastest)", "numba DP5"),
    ("rust dopri5", "diffrax Dopri5"),
)
#: Wall-time cap per trajectory and rung of the scipy baselines (s): tighter rungs are skipped once
#: a rung exceeds it (scipy's Radau needs about 17 s per trajectory at rtol 1e-12 on the seed scene).
SCIPY_CAP_QUICK, SCIPY_CAP_FULL = 0.5, 5.0


# --- scenes ----------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Scene:
    """A batch of trajectories of one physical situation.

    Attributes
    ----------
    name : str
        Short identifier (file names, table keys).
    title : str
        One-line description for charts.
    model : SliderModel
        Base model; ``params`` override some of its fields per trajectory.
    t_end : float, s
        Integration time.
    params : dict of str to ndarray (n,)
        Per-trajectory parameter values (at least one name, as :func:`tribosweep.ensemble` needs).
    y0 : ndarray (n, 6)
        Initial states (m, m/s, m, m/s, rad, rad/s) from the static point.
    description : str
        What the scene exercises, for the summary.
    variants : dict of str to SliderModel
        Other models of the same physics (e.g. ``{"switch": ...}``, another friction law) run on the
        same batch with the Rust methods; their rows get ``impl`` = the key, their errors are
        against their own reference (the Rust DOP853 at ``REF_RTOL`` on that model).
    """

    name: str
    title: str
    model: SliderModel
    t_end: float
    params: dict
    y0: np.ndarray
    description: str = ""
    variants: dict = field(default_factory=dict)

    def variant(self, key: str) -> Scene:
        """The scene with the model of variant ``key`` (and no variants)."""
        return dataclasses.replace(self, model=self.variants[key], variants={})

    @property
    def n(self) -> int:
        """Number of trajectories."""
        return int(self.y0.shape[0])

    def head(self, k: int) -> Scene:
        """The first ``k`` trajectories (baselines that are too slow for the whole batch)."""
        k = max(1, min(int(k), self.n))
        return dataclasses.replace(self, params={n: v[:k] for n, v in self.params.items()}, y0=self.y0[:k])

    def state_scale(self) -> np.ndarray:
        """Characteristic size of each state component (the core's default ``atol / rtol``)."""
        z_st, _ = self.model.static_point()
        zs, wt, arm = abs(z_st), self.model.omega_torsion, self.model.moment_arm
        return np.array([zs, zs * wt, zs, zs * wt, zs / arm, zs / arm * wt])

    def atol(self, rtol: float) -> np.ndarray:
        """Absolute tolerance used by every method at ``rtol``."""
        return rtol * self.state_scale()

    def is_bilateral_constant(self) -> bool:
        """True when the scipy/numba bilateral reference models apply."""
        return self.model.contact == "bilateral" and self.model.friction_law == "constant"

    def is_unilateral_constant(self) -> bool:
        """True when ``reference.solve_unilateral`` applies."""
        return self.model.contact == "unilateral" and self.model.friction_law == "constant"

    def reference_params(self) -> list[dict]:
        """Parameter dicts of ``tribosweep.reference`` (keys ``reference.PARAM_ORDER``), one per trajectory."""
        from . import reference

        base = self.model.values()
        out = []
        for i in range(self.n):
            p = {k: float(base[k]) for k in reference.PARAM_ORDER}
            for k, v in self.params.items():
                if k in p:
                    p[k] = float(v[i])
            out.append(p)
        return out


def _spread(lo: float, hi: float, n: int) -> np.ndarray:
    return np.linspace(lo, hi, n) if n > 1 else np.array([0.5 * (lo + hi)])


def _y0(n: int, z0: float) -> np.ndarray:
    y0 = np.zeros((n, 6))
    y0[:, 0] = z0
    return y0


#: Stick-slip scene: low sliding speed, Stribeck curve falling from 0.3 to 0.215 at V, and a tanh
#: regularisation of 1e-5 m/s. Near v_r = 0 the friction slope mu N / eps makes the twist equation
#: stiff (about (L^2/I) mu N / eps = 3e6 1/s), so explicit steppers are held to ~1 us steps during
#: sticking: they need ~1e6 rhs calls where Rodas4 needs ~1e4 (at 1e-4 m/s the gap is only 4x).
STICK_SLIP_MODEL = SliderModel(
    friction_law="coulomb", friction_regularization=1e-5, sliding_speed=0.01, mu_static=0.3, stribeck_velocity=0.02
)
#: The same scene with the event-driven switch law (stick band 1e-6 m/s): no stiffness, every stick and
#: slip a located event.
STICK_SLIP_SWITCH_MODEL = STICK_SLIP_MODEL.replace(friction_law="switch")


def make_scenes(quick: bool = False, names: Iterable[str] | None = None, n: int | None = None) -> list[Scene]:
    """The benchmark scenes (MODEL.md §3, §6): seed, unilateral, stick_slip, large_amplitude.

    Parameters
    ----------
    quick : bool
        Fewer trajectories per scene.
    names : iterable of str, optional
        Keep only these scenes (in this module's order).
    n : int, optional
        Trajectories per scene (overrides the quick/full defaults).

    Returns
    -------
    list of Scene
    """
    def count(full, fast):
        return int(n) if n is not None else (fast if quick else full)

    seed = SliderModel()
    # Cheap scenes get large batches: the ~1 ms fixed cost of an ``ensemble`` call is then spread thin.
    k = count(64, 16)
    scenes = [
        Scene(
            "seed", "bilateral seed, z0 = 1 um, 0.5 s", seed, 0.5, {"mu": _spread(0.205, 0.225, k)}, _y0(k, 1e-6),
            "The report's model at the seed point (84.46 N, bilateral contact, constant mu 0.205-0.225): "
            "a 1 um disturbance decays slowly; smooth and non-stiff.",
        )
    ]
    k = count(64, 16)
    scenes.append(Scene(
        "unilateral", "unilateral, mu = 0.30, z0 = 30 um, 0.2 s", seed.replace(contact="unilateral"), 0.2,
        {"mu": _spread(0.29, 0.31, k)}, _y0(k, 30e-6),
        "Unilateral contact at mu 0.29-0.31 (sliding unstable) from a 30 um disturbance: the pin leaves the "
        "disk at once and bounces; every contact opening/closing and N = 0 is a located event.",
    ))  # fmt: skip
    k = count(8, 2)
    scenes.append(Scene(
        "stick_slip", "stick-slip, V = 0.01 m/s: tanh eps = 1e-5 m/s (rust) vs switch law (switch), 0.2 s",
        STICK_SLIP_MODEL, 0.2, {"mu": _spread(0.21, 0.22, k)}, _y0(k, 1e-6),
        "Regularised Coulomb friction with a Stribeck curve (mu_s 0.3, v_s 0.02 m/s, mu(V) 0.21-0.22) at "
        "V = 0.01 m/s: the falling curve destabilises sliding and v_r reaches 0 (sticking); eps = 1e-5 m/s "
        "makes the sticking phases stiff. The `switch` lines integrate the same scene with the event-driven "
        "switch law (stick band 1e-6 m/s), each against its own reference.",
        variants={"switch": STICK_SLIP_SWITCH_MODEL},
    ))  # fmt: skip
    k = count(64, 16)
    scenes.append(Scene(
        "large_amplitude", "unilateral, mu = 0.35, 150 N, z0 = 40 um, 0.2 s",
        seed.replace(contact="unilateral", mu=0.35), 0.2, {"normal_load": _spread(145.0, 155.0, k)}, _y0(k, 40e-6),
        "Large cycles at high load (145-155 N, mu 0.35, unilateral, sliding unstable below the 225 N Hopf "
        "load): far from harmonic, the contact opens every cycle.",
    ))  # fmt: skip
    if names is not None:
        names = list(names)
        unknown = set(names) - {s.name for s in scenes}
        if unknown:
            raise ValueError(f"unknown scenes {sorted(unknown)}: valid are {[s.name for s in scenes]}")
        scenes = [s for s in scenes if s.name in names]
    return scenes


# --- one batch, one rung ---------------------------------------------------------------------------


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
    """End states of the switch law by the independent ``reference.SwitchReference`` (bilateral; untimed)."""
    from . import reference

    base = scene.model.values()
    z = np.full(scene.n, np.nan)
    for i in range(scene.n):
        values = dict(base, **{k: float(v[i]) for k, v in scene.params.items()})
        y, _ = reference.SwitchReference(values).solve(scene.y0[i], scene.t_end, [scene.t_end], rtol=rtol,
                                                       atol=scene.atol(rtol))  # fmt: skip
        z[i] = y[-1, 0]
    zeros = np.zeros(scene.n, dtype=np.int64)
    return BatchRun(z_end=z, status=np.where(np.isfinite(z), 0, STATUS["non_finite"]), n_rhs=zeros, steps=zeros,
                    n_reject=zeros, seconds=math.nan)  # fmt: skip


def find_baselines_module(paths: Sequence[str | os.PathLike] | None = None):
    """Import ``benches/baselines.py`` (the numba kernel) from a checkout, or return None.

    Looked up in ``$TRIBOSWEEP_BENCHES``, ``./benches`` and the source tree next to this package
    (an installed wheel has no ``benches/``: the numba baseline is then skipped with a note).
    """
    if paths is None:
        here = pathlib.Path(__file__).resolve()
        paths = [os.environ.get("TRIBOSWEEP_BENCHES", ""), pathlib.Path.cwd() / "benches", here.parents[2] / "benches"]
    for d in paths:
        if not d:
            continue
        path = pathlib.Path(d) / "baselines.py"
        if path.is_file():
            name = "_tribosweep_bench_baselines"
            if name in sys.modules:
                return sys.modules[name]
            spec = importlib.util.spec_from_file_location(name, path)
            mod = importlib.util.module_from_spec(spec)
            sys.modules[name] = mod
            try:
                spec.loader.exec_module(mod)
            except Exception:
                del sys.modules[name]
                raise
            return mod
    return None


def _numba_batch(bl, scene: Scene, rtol: float, repeat: int) -> BatchRun:
    """The numba Dormand-Prince 5(4) kernel of ``benches/baselines.py`` (one core, bilateral constant mu)."""
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


def make_row(scene: str, impl: str, method: str, rtol: float, run: BatchRun, z_ref, scale) -> dict:
    """One table row of a rung (see ``COLUMNS``)."""
    n = int(run.z_end.size)
    err = error_of(run.z_end, z_ref, scale)
    row = {
        "scene": scene,
        "impl": impl,
        "method": method,
        "label": f"{impl} {method}",
        "rtol": float(rtol),
        "n_traj": n,
        "seconds_per_traj": run.seconds / max(n, 1),
        "error": err,
        "n_rhs": float(np.mean(run.n_rhs)),
        "steps": float(np.mean(run.steps)),
        "n_reject": float(np.mean(run.n_reject)),
        "status": _status_name(np.asarray(run.status)),
        "n_failed": int(np.count_nonzero(np.asarray(run.status) != 0)),
        "reason": run.reason,
    }
    if row["n_failed"] == 0 and not math.isfinite(err):
        row["status"], row["reason"] = "non_finite", row["reason"] or "non-finite final state"
    row["failed"] = is_failed(row)
    if row["failed"] and row["status"] == "success":
        row["status"] = "error_above_1"
    return row


# --- interpolation and quoting ---------------------------------------------------------------------


def time_at_error(errors: Sequence[float], times: Sequence[float], target: float) -> float:
    """Time of a work-precision line at error ``target``: linear in (log error, log time), no extrapolation.

    ``errors`` and ``times`` are the rungs in ladder order (loose to tight); NaN, zero or negative entries
    are skipped. The first pair of consecutive valid rungs whose errors bracket ``target`` is
    interpolated; NaN when no pair does.

    Examples
    --------
    >>> round(time_at_error([1e-3, 1e-5], [1.0, 100.0], 1e-4), 12)
    10.0
    """
    e = np.asarray(errors, dtype=np.float64)
    t = np.asarray(times, dtype=np.float64)
    ok = np.isfinite(e) & np.isfinite(t) & (e > 0) & (t > 0)
    e, t = e[ok], t[ok]
    if not (target > 0) or e.size == 0:
        return math.nan
    le, lt, lx = np.log(e), np.log(t), math.log(target)
    for i in range(e.size):
        if le[i] == lx:
            return float(t[i])
        if i + 1 < e.size and min(le[i], le[i + 1]) <= lx <= max(le[i], le[i + 1]) and le[i] != le[i + 1]:
            w = (lx - le[i]) / (le[i + 1] - le[i])
            return float(math.exp(lt[i] + w * (lt[i + 1] - lt[i])))
    return math.nan


def _lines(rows: list[dict], scene: str) -> dict[str, list[dict]]:
    """Successful rungs of each method label of ``scene``, in ladder order (loose to tight)."""
    out: dict[str, list[dict]] = {}
    for r in rows:
        if r["scene"] == scene:
            out.setdefault(r["label"], [])
            if not r["failed"]:
                out[r["label"]].append(r)
    for line in out.values():
        line.sort(key=lambda r: -r["rtol"])
    return out


def times_at(rows: list[dict], scene: str, target: float) -> dict[str, float]:
    """``{label: seconds per trajectory at error target}`` for every method of ``scene`` that brackets it.

    Adds ``"rust (fastest)"`` and ``"scipy (fastest)"``: the least time over that implementation's methods.
    """
    out = {}
    for label, line in _lines(rows, scene).items():
        v = time_at_error([r["error"] for r in line], [r["seconds_per_traj"] for r in line], target)
        if math.isfinite(v):
            out[label] = v
    for impl in ("rust", "scipy"):
        vals = {k: v for k, v in out.items() if k.startswith(impl + " ")}
        if vals:
            out[f"{impl} (fastest)"] = min(vals.values())
            out[f"_{impl}_fastest_label"] = min(vals, key=vals.get)
    return out


def speed_ratios(rows: list[dict], targets: Sequence[float] = MATCHED_ERRORS,
                 pairs: Sequence[tuple[str, str]] = RATIO_PAIRS) -> list[dict]:  # fmt: skip
    """Speed ratio ``t_baseline / t_rust`` at matched error, for every scene and pair where both lines reach it."""
    out, seen = [], set()
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for target in targets:
            at = times_at(rows, scene, target)
            for rust, base in pairs:
                if rust in at and base in at:
                    key = (scene, target, at.get("_rust_fastest_label", rust) if rust == "rust (fastest)" else rust,
                           at.get("_scipy_fastest_label", base) if base == "scipy (fastest)" else base)
                    if key in seen:  # "fastest" resolved to a pair already quoted
                        continue
                    seen.add(key)
                    out.append({
                        "scene": scene, "error": target, "rust": rust, "baseline": base,
                        "rust_label": key[2], "baseline_label": key[3],
                        "rust_seconds": at[rust], "baseline_seconds": at[base], "ratio": at[base] / at[rust],
                    })  # fmt: skip
    return out


def fastest(rows: list[dict], targets: Sequence[float] = FASTEST_AT) -> list[dict]:
    """Per scene and target error: the method with the least time per trajectory (all implementations)."""
    out = []
    for scene in dict.fromkeys(r["scene"] for r in rows):
        for target in targets:
            at = {k: v for k, v in times_at(rows, scene, target).items() if not k.startswith("_") and "(" not in k}
            if at:
                best = min(at, key=at.get)
                runner = sorted(at.values())[1] if len(at) > 1 else math.nan
                out.append({"scene": scene, "error": target, "label": best, "seconds": at[best],
                            "next_seconds": runner, "n_methods": len(at)})  # fmt: skip
            else:
                errs = [r["error"] for line in _lines(rows, scene).values() for r in line]
                why = ("every method is more accurate already at its loosest rung" if errs and max(errs) < target
                       else "no method reaches it" if errs and min(errs) > target else "no successful rung")
                out.append({"scene": scene, "error": target, "label": None, "seconds": math.nan,
                            "next_seconds": math.nan, "n_methods": 0, "why": why})  # fmt: skip
    return out


def law_comparison(rows: list[dict], scenes: list[dict], targets: Sequence[float] = FASTEST_AT) -> list[dict]:
    """Per scene with variants, method and target error: time and rhs calls of the base law and each variant.

    Both read off their own work-precision lines (log-log interpolation, no extrapolation); only pairs
    where both lines reach the error are listed.
    """
    out = []
    for s in scenes:
        lines = _lines(rows, s["name"])
        for key in s.get("variants") or {}:
            for method in RUST_METHODS:
                base, var = lines.get(f"rust {method}"), lines.get(f"{key} {method}")
                if not base or not var:
                    continue
                for target in targets:
                    def at(line, col, target=target):
                        return time_at_error([r["error"] for r in line], [r[col] for r in line], target)

                    tb, tv = at(base, "seconds_per_traj"), at(var, "seconds_per_traj")
                    nb, nv = at(base, "n_rhs"), at(var, "n_rhs")
                    if all(math.isfinite(v) for v in (tb, tv, nb, nv)):
                        out.append({"scene": s["name"], "variant": key, "method": method, "error": target,
                                    "base_seconds": tb, "variant_seconds": tv, "time_ratio": tb / tv,
                                    "base_rhs": nb, "variant_rhs": nv, "rhs_ratio": nb / nv})  # fmt: skip
            # The best method of each law against each other (least time and least rhs, taken separately).
            for target in targets:
                got = [q for q in out if q["scene"] == s["name"] and q["variant"] == key and q["error"] == target
                       and q["method"] in RUST_METHODS]  # fmt: skip
                if len(got) > 1:
                    tb, tv = min(q["base_seconds"] for q in got), min(q["variant_seconds"] for q in got)
                    nb, nv = min(q["base_rhs"] for q in got), min(q["variant_rhs"] for q in got)
                    out.append({"scene": s["name"], "variant": key, "method": "best of each", "error": target,
                                "base_seconds": tb, "variant_seconds": tv, "time_ratio": tb / tv,
                                "base_rhs": nb, "variant_rhs": nv, "rhs_ratio": nb / nv})  # fmt: skip
    return out


# --- the run ---------------------------------------------------------------------------------------


def _log(msg: str, progress: bool) -> None:
    if progress:
        print(msg, file=sys.stderr, flush=True)


def _reference(scene: Scene, *, check_k: int, progress: bool) -> dict:
    """Rust DOP853 at REF_RTOL over the batch, checked on ``check_k`` trajectories by a second solver."""
    t0 = time.perf_counter()
    ref = run_rust(scene, "dop853", REF_RTOL, repeat=1)
    seconds = time.perf_counter() - t0
    scale = np.maximum(np.abs(ref.extra["max_abs_z"]), 1e-300)
    info = {
        "method": "rust dop853", "rtol": REF_RTOL, "seconds_per_traj": seconds / scene.n,
        "status": _status_name(ref.status), "n_failed": int(np.count_nonzero(ref.status)),
        "max_abs_z": float(np.max(ref.extra["max_abs_z"])), "max_gap": float(np.max(ref.extra["max_gap"])),
        "min_slip_velocity": float(np.min(ref.extra["min_slip_velocity"])),
        "min_normal_force": float(np.min(ref.extra["min_normal_force"])),
        "n_events": float(np.mean(ref.extra["n_events"])), "n_rhs": float(np.mean(ref.n_rhs)),
    }  # fmt: skip
    # The fixed cost of one ensemble call over this batch (validation, GIL hand-off, Dataset building):
    # a run of 1 ns, best of 5. It is part of every Rust time; reported beside them.
    over, _ = _best_of(lambda: ensemble(scene.model, 1e-9, scene.params, y0=scene.y0, method="dopri5", rtol=1e-6,
                                        atol=scene.atol(1e-6), threads=1), 5)  # fmt: skip
    info["api_overhead_per_call"] = over
    info["api_overhead_per_traj"] = over / scene.n
    head = scene.head(check_k)
    try:
        if scene.is_bilateral_constant() and _has("scipy"):
            chk = _scipy_batch(head, "DOP853", REF_RTOL, 1)
            info["check_method"] = "scipy DOP853 rtol 1e-13"
        elif scene.is_unilateral_constant() and _has("scipy"):
            chk = _scipy_batch(head, "DOP853", 1e-12, 1)
            info["check_method"] = "scipy DOP853 rtol 1e-12, event-driven (reference.solve_unilateral)"
        elif scene.model.friction_law == "switch" and scene.model.contact == "bilateral" and _has("scipy"):
            chk = _scipy_switch_batch(head, 1e-13)
            info["check_method"] = "scipy DOP853 rtol 1e-13, event-driven switch law (reference.SwitchReference)"
        else:
            chk = run_rust(head, "dopri5", 1e-12, repeat=1)
            info["check_method"] = "rust dopri5 rtol 1e-12"
        info["check_value"] = error_of(chk.z_end, ref.z_end, scale)
    except Exception as e:  # noqa: BLE001 - a failed check is reported, not fatal
        info["check_method"], info["check_value"] = f"check failed: {e}", math.nan
    info["check_n"] = head.n
    _log(f"  reference {scene.name}: {info['seconds_per_traj'] * 1e3:.1f} ms/traj, status {info['status']}, "
         f"check ({info['check_method']}) {info['check_value']:.1e}", progress)  # fmt: skip
    return {"info": info, "z_end": ref.z_end, "scale": scale}


def _has(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


@dataclass
class BenchConfig:
    """What :func:`run_work_precision` measures.

    Attributes
    ----------
    quick : bool
        Fewer rungs and trajectories (about a minute on two cores, failure maps included).
    scenes : list of str, optional
        Scene names (default: all four).
    ladder : sequence of float, optional
        rtol rungs (default ``QUICK_LADDER`` or ``FULL_LADDER``).
    n_traj : int, optional
        Trajectories per scene (default per scene, see :func:`make_scenes`).
    methods : sequence of str
        Rust integrators.
    baselines : sequence of str
        Any of ``"scipy"``, ``"numba"``, ``"diffrax"`` (each skipped with a note when unavailable).
    repeat : int, optional
        Best-of repeats of each timed rung (Rust, numba: interleaved passes over the ladder; diffrax);
        default 3 quick, 5 full.
    scipy_repeat : int, optional
        Best-of repeats of the scipy rungs (default 1 quick, 3 full: scipy rungs are long).
    scipy_n : int, optional
        Trajectories of the scipy baselines (default 1 quick, 4 full).
    scipy_cap : float, optional
        Skip tighter scipy rungs once a rung takes longer than this per trajectory, s.
    check_n : int, optional
        Trajectories of the reference check (default 1 quick, 4 full).
    """

    quick: bool = False
    scenes: Sequence[str] | None = None
    ladder: Sequence[float] | None = None
    n_traj: int | None = None
    methods: Sequence[str] = RUST_METHODS
    baselines: Sequence[str] = ("scipy", "numba", "diffrax")
    repeat: int | None = None
    scipy_repeat: int | None = None
    scipy_n: int | None = None
    scipy_cap: float | None = None
    check_n: int | None = None

    def resolved(self) -> BenchConfig:
        """A copy with every default filled in."""
        q = self.quick
        return dataclasses.replace(
            self,
            ladder=tuple(float(r) for r in (self.ladder or (QUICK_LADDER if q else FULL_LADDER))),
            methods=tuple(self.methods),
            baselines=tuple(self.baselines),
            repeat=self.repeat or (3 if q else 5),
            scipy_repeat=self.scipy_repeat or (1 if q else 3),
            scipy_n=self.scipy_n or (1 if q else 4),
            scipy_cap=self.scipy_cap or (SCIPY_CAP_QUICK if q else SCIPY_CAP_FULL),
            check_n=self.check_n or (1 if q else 4),
        )


#: scipy methods per scene kind.
_SCIPY_BILATERAL = ("RK45", "DOP853", "Radau")
_SCIPY_UNILATERAL = ("RK45", "DOP853")


def measure(config: BenchConfig, *, progress: bool = True) -> dict:
    """Run the work-precision measurements; returns the JSON-ready payload (meta, scenes, rows, notes).

    Nothing is written; see :func:`run_work_precision`.
    """
    cfg = config.resolved()
    scenes = make_scenes(cfg.quick, cfg.scenes, cfg.n_traj)
    rows: list[dict] = []
    notes: list[str] = []
    scene_info = []
    bl = None
    if "numba" in cfg.baselines:
        if not _has("numba"):
            notes.append("numba baseline skipped: numba is not installed")
        else:
            bl = find_baselines_module()
            if bl is None:
                notes.append("numba baseline skipped: benches/baselines.py not found (run from a checkout or set "
                             "TRIBOSWEEP_BENCHES)")  # fmt: skip
            else:
                t0 = time.perf_counter()
                # Compile only the one-core kernel (baselines.warmup() also compiles the prange variant).
                bl.numba_dp5_batch(np.zeros((1, 17)) + _seed_row(), np.array([[1e-6, 0, 0, 0, 0, 0]]), 1e-3, 1e-3)
                _log(f"numba kernel compiled in {time.perf_counter() - t0:.1f} s", progress)
    if "scipy" in cfg.baselines and not _has("scipy"):
        notes.append("scipy baselines skipped: scipy is not installed")
    use_diffrax = "diffrax" in cfg.baselines and diffrax_available()
    if "diffrax" in cfg.baselines and not use_diffrax:
        notes.append("diffrax baseline skipped: diffrax/jax not importable")

    t_start = time.perf_counter()
    load_start = _loadavg()
    for scene in scenes:
        _log(f"scene {scene.name}: {scene.n} trajectories, {scene.t_end} s", progress)
        ref = _reference(scene, check_k=cfg.check_n, progress=progress)
        z_ref, scale = ref["z_end"], ref["scale"]
        info = {"name": scene.name, "title": scene.title, "description": scene.description, "t_end": scene.t_end,
                "n_traj": scene.n, "contact": scene.model.contact, "friction_law": scene.model.friction_law,
                "reference": ref["info"]}  # fmt: skip
        # Each variant (another friction law on the same batch) is measured against its own reference.
        refs = {}
        for key in scene.variants:
            _log(f"  variant {key}", progress)
            vref = _reference(scene.variant(key), check_k=cfg.check_n, progress=progress)
            refs[key] = (vref["z_end"], vref["scale"])
            info.setdefault("variants", {})[key] = {
                "friction_law": scene.variants[key].friction_law, "reference": vref["info"],
                "stick_band": scene.variants[key].stick_band}  # fmt: skip
        scene_info.append(info)

        def add(impl, method, rtol, run, scene=scene, z_ref=z_ref, scale=scale, refs=refs):
            if impl in refs:
                z_ref, scale = refs[impl]
            row = make_row(scene.name, impl, method, rtol, run, z_ref, scale)
            rows.append(row)
            flag = f"  FAILED ({row['status']})" if row["failed"] else ""
            _log(f"  {row['label']:<14} rtol {rtol:.0e}: {row['seconds_per_traj'] * 1e3:9.3f} ms/traj, "
                 f"error {row['error']:.2e}, {row['n_rhs']:.0f} rhs{flag}", progress)  # fmt: skip
            return row

        # Rust and numba rungs are short: time them in interleaved passes over every (method, rtol) and keep
        # each rung's fastest pass, so a burst of load from other processes hits different rungs in different
        # passes instead of all repeats of one rung.
        jobs = {("rust", m, r): (lambda m=m, r=r, sc=scene: run_rust(sc, m, r, repeat=1)) for m in cfg.methods
                for r in cfg.ladder}  # fmt: skip
        for key in scene.variants:
            vscene = scene.variant(key)
            jobs.update({(key, m, r): (lambda m=m, r=r, sc=vscene: run_rust(sc, m, r, repeat=1))
                         for m in cfg.methods for r in cfg.ladder})  # fmt: skip
        if bl is not None and scene.is_bilateral_constant():
            jobs.update({("numba", "DP5", r): (lambda r=r, sc=scene: _numba_batch(bl, sc, r, 1)) for r in cfg.ladder})
        best: dict = {}
        _log(f"  timing {len(jobs)} rungs (Rust, numba) in {cfg.repeat} interleaved passes", progress)
        for _ in range(max(1, cfg.repeat)):
            for key, job in jobs.items():
                run = job()
                if key not in best or run.seconds < best[key].seconds:
                    best[key] = run
        for (impl, method, rtol), run in best.items():
            add(impl, method, rtol, run)
        if use_diffrax and scene.is_bilateral_constant():
            for rtol in cfg.ladder:
                try:
                    add("diffrax", "Dopri5", rtol, _diffrax_batch(scene, rtol, cfg.repeat))
                except Exception as e:  # noqa: BLE001 - an optional baseline must not stop the run
                    notes.append(f"diffrax on {scene.name} at rtol {rtol:.0e} raised {type(e).__name__}: {e}")
                    break
        if "scipy" in cfg.baselines and _has("scipy"):
            methods = (_SCIPY_BILATERAL if scene.is_bilateral_constant()
                       else _SCIPY_UNILATERAL if scene.is_unilateral_constant() else ())  # fmt: skip
            head = scene.head(cfg.scipy_n)
            for method in methods:
                for i, rtol in enumerate(cfg.ladder):
                    row = add("scipy", method, rtol, _scipy_batch(head, method, rtol, cfg.scipy_repeat))
                    if row["seconds_per_traj"] > cfg.scipy_cap and i + 1 < len(cfg.ladder):
                        notes.append(f"{scene.name}: scipy {method} stopped after rtol {rtol:.0e} "
                                     f"({row['seconds_per_traj']:.2f} s per trajectory > cap {cfg.scipy_cap:g} s); "
                                     f"tighter rungs not run")  # fmt: skip
                        break
            if not methods:
                notes.append(f"{scene.name}: no scipy baseline (tribosweep.reference has no regularised "
                             f"Coulomb friction)")  # fmt: skip
    meta = _meta(cfg, time.perf_counter() - t_start)
    meta["loadavg"] = [load_start, _loadavg()]
    return {"meta": meta, "scenes": scene_info, "rows": rows, "notes": notes}


def _loadavg() -> float | None:
    """1-minute load average (other processes competing for the cores skew the times), None where unknown."""
    try:
        return round(os.getloadavg()[0], 2)
    except (OSError, AttributeError):
        return None


def _seed_row() -> np.ndarray:
    from . import reference

    return reference.params_to_array([reference.seed_parameters()])[0]


def _git_commit() -> str:
    try:
        here = pathlib.Path(__file__).resolve().parents[2]
        out = subprocess.run(["git", "-C", str(here), "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=5, check=False)  # fmt: skip
        return out.stdout.strip() if out.returncode == 0 else ""
    except (OSError, subprocess.SubprocessError):
        return ""


def _cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _versions() -> dict:
    from . import __version__

    out = {"tribosweep": __version__, "python": platform.python_version(), "numpy": np.__version__}
    for mod in ("scipy", "numba", "diffrax", "jax", "matplotlib"):
        if _has(mod):
            try:
                out[mod] = __import__(mod).__version__
            except Exception:  # noqa: BLE001
                out[mod] = "?"
    return out


def _meta(cfg: BenchConfig, seconds: float) -> dict:
    return {
        "quick": cfg.quick,
        "ladder": list(cfg.ladder),
        "methods": list(cfg.methods),
        "baselines": list(cfg.baselines),
        "repeat": cfg.repeat,
        "scipy_repeat": cfg.scipy_repeat,
        "scipy_n": cfg.scipy_n,
        "scipy_cap_s": cfg.scipy_cap,
        "reference": f"rust dop853 rtol {REF_RTOL:.0e}",
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": f"{_cpu_name()}, {os.cpu_count()} logical cores, {platform.system()} {platform.machine()}",
        "versions": _versions(),
        "commit": _git_commit(),
        "threads": 1,
        "cores": os.cpu_count(),
        "seconds": seconds,
    }


# --- output ----------------------------------------------------------------------------------------


def write_table(rows: list[dict], csv_path: os.PathLike) -> None:
    """Every row as CSV (``COLUMNS``; floats with full precision)."""
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})


def _json_safe(o):
    if isinstance(o, float) and not math.isfinite(o):
        return None
    if isinstance(o, dict):
        return {k: _json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_json_safe(v) for v in o]
    if isinstance(o, np.generic):
        return _json_safe(o.item())
    return o


def _json_load_rows(payload: dict) -> dict:
    """Undo ``_json_safe`` (None -> NaN in numeric columns)."""
    for r in payload["rows"]:
        for k in ("error", "seconds_per_traj", "n_rhs", "steps", "n_reject"):
            if r.get(k) is None:
                r[k] = math.nan
    return payload


def load_payload(path: os.PathLike) -> dict:
    """Read a ``work_precision.json`` written by :func:`run_work_precision`."""
    with open(path) as f:
        return _json_load_rows(json.load(f))


_STYLE = {
    "rust dopri5": ("o", "-", "#0072B2"),
    "rust dop853": ("s", "-", "#D55E00"),
    "rust rodas4": ("D", "-", "#009E73"),
    # The switch friction law on the stick-slip scene: the same method colours, open markers, dashed.
    "switch dopri5": ("o", (0, (4, 2)), "#0072B2"),
    "switch dop853": ("s", (0, (4, 2)), "#D55E00"),
    "switch rodas4": ("D", (0, (4, 2)), "#009E73"),
    "numba DP5": ("^", ":", "#56B4E9"),
    "scipy RK45": ("o", "--", "#7f7f7f"),
    "scipy DOP853": ("s", "--", "#CC79A7"),
    "scipy Radau": ("D", "--", "#E69F00"),
    "diffrax Dopri5": ("v", "-.", "#000000"),
}
_ERR_FLOOR = 1e-16  # errors below this (identical to the reference) are drawn at the floor
_FAIL_X = 20.0  # failed rungs are drawn in a band right of error 1


def plot_work_precision(rows: list[dict], scene: dict | str, *, ax=None):
    """One scene's work-precision chart: error (x) against wall time per trajectory (y), log-log.

    One marked line per method through its successful rungs (ladder order); failed rungs are drawn as
    ``x`` in the method's colour in the grey band right of error 1, at their measured time, so nothing
    is dropped. Errors below the reference's own check are shaded (not resolved).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    info = scene if isinstance(scene, dict) else {"name": scene, "title": scene}
    name = info["name"]
    if ax is None:
        fig = Figure(figsize=(9.0, 5.0), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    labels = list(dict.fromkeys(r["label"] for r in rows if r["scene"] == name))
    any_fail = False
    for label in labels:
        marker, ls, color = _STYLE.get(label, ("o", "-", None))
        rs = sorted((r for r in rows if r["scene"] == name and r["label"] == label), key=lambda r: -r["rtol"])
        ok = [r for r in rs if not r["failed"]]
        bad = [r for r in rs if r["failed"]]
        hollow = {"markerfacecolor": "white", "markeredgewidth": 1.5} if label.startswith("switch ") else {}
        # Beside variant lines, say which law the scene's own Rust lines integrate.
        shown = f"{label} ({'tanh' if info.get('friction_law') == 'coulomb' else info.get('friction_law')} law)" \
            if info.get("variants") and label.startswith("rust ") else label
        line = ax.plot([max(r["error"], _ERR_FLOOR) for r in ok], [r["seconds_per_traj"] for r in ok],
                       marker=marker, linestyle=ls, color=color, label=shown, markersize=5, **hollow)  # fmt: skip
        color = line[0].get_color()
        if bad:
            any_fail = True
            ax.plot([_FAIL_X] * len(bad), [r["seconds_per_traj"] for r in bad], linestyle="none", marker="x",
                    color=color, markersize=8, markeredgewidth=2)  # fmt: skip
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axvspan(2.0, 60.0, color="0.9", zorder=0)
    ax.text(4.0, 0.5, "failed rungs (status != 0, NaN or error > 1)", transform=ax.get_xaxis_transform(),
            ha="center", va="center", rotation=90, fontsize=7, color="0.35")  # fmt: skip
    chk = (info.get("reference") or {}).get("check_value")
    if chk is not None and math.isfinite(chk) and chk > 0:
        ax.axvspan(_ERR_FLOOR / 3, max(chk, _ERR_FLOOR), color="0.95", hatch="//", zorder=0, linewidth=0,
                   label=f"below reference check ({chk:.0e})")  # fmt: skip
    for key, var in (info.get("variants") or {}).items():
        vchk = var["reference"].get("check_value")
        if vchk is not None and math.isfinite(vchk) and vchk > 0:
            ax.axvline(vchk, color="0.4", linestyle=":", linewidth=1.2, zorder=0,
                       label=f"{key} lines: reference check ({vchk:.0e})")  # fmt: skip
    ax.set_xlim(_ERR_FLOOR / 3, 60.0)
    ax.set_xlabel("error  max |z(t_end) - z_ref| / max|z_ref|")
    ax.set_ylabel("wall time per trajectory [s] (1 thread)")
    ax.set_title(f"{name}: {info.get('title', '')}", fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    if any_fail:
        ax.plot([], [], linestyle="none", marker="x", color="k", label="failed rung (status, NaN or error > 1)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return fig


def _fmt_s(s: float) -> str:
    if not math.isfinite(s):
        return "n/a"
    if s >= 1.0:
        return f"{s:.2f} s"
    if s >= 1e-3:
        return f"{s * 1e3:.3g} ms"
    return f"{s * 1e6:.3g} us"


def render_summary(payload: dict, *, images: dict[str, str] | None = None, extra: str = "",
                   command: str | None = None) -> str:  # fmt: skip
    """Markdown summary of a work-precision payload: ratios at matched error, fastest methods, failures.

    Parameters
    ----------
    payload : dict
        From :func:`measure` or :func:`load_payload`.
    images : dict of str to str, optional
        ``{scene name: relative image path}`` to embed (the docs page embeds none).
    extra : str
        Markdown appended (e.g. the failure-map section).
    command : str, optional
        The command that produced the data.
    """
    meta, rows = payload["meta"], payload["rows"]
    scenes = payload["scenes"]
    L = ["# Work-precision benchmarks", ""]
    L.append(f"Generated by `{command or 'tribosweep bench'}` on {meta['date']}"
             + (f" (commit {meta['commit']})" if meta.get("commit") else "") + ".")  # fmt: skip
    L.append(f"Machine: {meta['machine']}. Versions: "
             + ", ".join(f"{k} {v}" for k, v in meta["versions"].items()) + ".")  # fmt: skip
    mode = "quick" if meta["quick"] else "full"
    L.append(f"Mode: **{mode}**; rtol ladder {', '.join(f'{r:.0e}' for r in meta['ladder'])}; "
             f"every timed rung is the best of {meta['repeat']} interleaved passes (scipy: best of "
             f"{meta['scipy_repeat']} back to back, on "
             f"{meta['scipy_n']} trajectories); one thread everywhere; total {meta['seconds']:.0f} s.")  # fmt: skip
    if meta.get("loadavg") and None not in meta["loadavg"]:
        a, b = meta["loadavg"]
        cores = meta.get("cores") or 1
        L.append(f"1-minute load average at start / end: {a:g} / {b:g} on {cores} cores"
                 + (" (other work competed for the cores: absolute times are inflated and noisy)."
                    if max(a, b) > cores - 0.8 else "."))  # fmt: skip
    L += ["",
          ("Error = max over the batch of |z(t_end) - z_ref(t_end)| / max|z_ref| with the Rust DOP853 at rtol "
           "1e-13 as reference; time = wall time per trajectory through `tribosweep.ensemble(threads=1)` (its "
           "fixed per-call Python/xarray overhead is included and spread over the batch: see the scenes table). "
           "All methods get the same atol: rtol times each component's characteristic size. Times are from one "
           "run on a possibly shared machine: read the ratios, not the absolute numbers."), ""]  # fmt: skip

    L += ["## Scenes", "",
          ("| scene | trajectories | what it exercises | reference check | events/traj | max gap | min v_r | "
           "ensemble call overhead |"), "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for s in scenes:
        ref = s["reference"]
        chk = ref.get("check_value")
        chk_s = f"{chk:.1e} vs {ref.get('check_method')} ({ref.get('check_n')} traj)" if chk is not None and \
            math.isfinite(chk) else str(ref.get("check_method"))  # fmt: skip
        over = ref.get("api_overhead_per_call")
        over_s = f"{_fmt_s(over)} per call = {_fmt_s(ref['api_overhead_per_traj'])}/traj" if over else "n/a"
        L.append(f"| `{s['name']}` | {s['n_traj']} | {s['description']} | {chk_s} | {ref['n_events']:.0f} | "
                 f"{ref['max_gap'] * 1e6:+.2f} um | {ref['min_slip_velocity']:+.3g} m/s | {over_s} |")  # fmt: skip
    ss = [s for s in scenes if s["friction_law"] == "coulomb"]
    for s in ss:
        v = s["reference"]["min_slip_velocity"]
        L.append("")
        L.append(f"Stick-slip check (`{s['name']}`): the reference's minimum sliding velocity is {v:+.3g} m/s "
                 + ("<= 0: the contact point sticks." if v <= 0 else "> 0: NO sticking; the scene does not test "
                    "what it should."))  # fmt: skip
        for key, var in (s.get("variants") or {}).items():
            v, eta = var["reference"]["min_slip_velocity"], var.get("stick_band", math.nan)
            L.append(f"With the {var['friction_law']} law (`{key}` lines) the minimum is {v:+.3g} m/s, "
                     + (f"within the stick band {eta:g} m/s: it sticks." if v <= eta * (1 + 1e-6) else
                        f"outside the stick band {eta:g} m/s: NO sticking."))  # fmt: skip
    laws = law_comparison(rows, scenes)
    if laws:
        L += ["", "## Friction laws at matched error", "",
              ("Each line read at the same error (against its own law's reference) as in the ratios below; "
               "ratio = tanh / switch (> 1: the switch law is cheaper). The right-hand-side counts are the "
               "integrator's own (event location adds none), so their ratio does not depend on the machine."),
              "", "| scene | method | error | tanh time | switch time | time ratio | tanh rhs | switch rhs | "
              "rhs ratio |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for q in laws:
            L.append(f"| `{q['scene']}` | {q['method']} | {q['error']:.0e} | {_fmt_s(q['base_seconds'])} | "
                     f"{_fmt_s(q['variant_seconds'])} | **{q['time_ratio']:.3g}x** | {q['base_rhs']:.3g} | "
                     f"{q['variant_rhs']:.3g} | **{q['rhs_ratio']:.3g}x** |")  # fmt: skip

    L += ["", "## Speed ratio of the Rust core at matched error", "",
          ("Ratio = baseline time / Rust time per trajectory, both read off their work-precision lines "
           "(linear interpolation in log error - log time, no extrapolation) at the same error; > 1: Rust "
           "faster. Rust runs through `ensemble` with one thread; numba is the one-core DP5 kernel of "
           "`benches/baselines.py` (same scheme as `dopri5`); scipy is `solve_ivp` on the independent "
           "`tribosweep.reference` (event-driven `solve_unilateral` for unilateral scenes)."), ""]  # fmt: skip
    ratios = speed_ratios(rows)
    if ratios:
        L += ["| scene | error | Rust | baseline | Rust time | baseline time | ratio |", "|---|---|---|---|---|---|---|"]
        for q in ratios:
            rl = q["rust_label"] + (" (fastest Rust)" if q["rust"] == "rust (fastest)" else "")
            bl = q["baseline_label"] + (" (fastest scipy)" if q["baseline"] == "scipy (fastest)" else "")
            L.append(f"| `{q['scene']}` | {q['error']:.0e} | {rl} | {bl} | "
                     f"{_fmt_s(q['rust_seconds'])} | {_fmt_s(q['baseline_seconds'])} | **{q['ratio']:.3g}x** |")
    else:
        L.append("No pair of lines reaches a common error (too few rungs, or baselines skipped).")
    missing = []
    for s in scenes:
        for target in MATCHED_ERRORS:
            at = times_at(rows, s["name"], target)
            for rust, base in RATIO_PAIRS:
                have_base = any(r["scene"] == s["name"] and r["label"] == base for r in rows) or \
                    (base == "scipy (fastest)" and any(r["scene"] == s["name"] and r["impl"] == "scipy" for r in rows))
                if have_base and not (rust in at and base in at):
                    missing.append(f"`{s['name']}` {target:.0e}: {rust} / {base}")
    if missing:
        L += ["", "Not quoted (a line does not reach that error): " + "; ".join(missing) + "."]

    L += ["", "## Fastest method per scene", "", "| scene | " + " | ".join(f"error {e:.0e}" for e in FASTEST_AT)
          + " |", "|---|" + "---|" * len(FASTEST_AT)]  # fmt: skip
    fast = fastest(rows)
    for s in scenes:
        cells = []
        for e in FASTEST_AT:
            f = next(x for x in fast if x["scene"] == s["name"] and x["error"] == e)
            if f["label"] is None:
                cells.append(f.get("why", "not reached"))
            else:
                nxt = f" ({f['next_seconds'] / f['seconds']:.2g}x ahead of the next)" if math.isfinite(
                    f["next_seconds"]) else ""  # fmt: skip
                cells.append(f"{f['label']}, {_fmt_s(f['seconds'])}{nxt}")
        L.append(f"| `{s['name']}` | " + " | ".join(cells) + " |")

    fails = [r for r in rows if r["failed"]]
    L += ["", "## Failed rungs", ""]
    if fails:
        L += ["Recorded and drawn (x in the grey band), never dropped:", "",
              "| scene | method | rtol | status | failed/traj | error | reason |", "|---|---|---|---|---|---|---|"]
        for r in fails:
            L.append(f"| `{r['scene']}` | {r['label']} | {r['rtol']:.0e} | {r['status']} | {r['n_failed']}/"
                     f"{r['n_traj']} | {r['error']:.2e} | {r['reason'] or ''} |")  # fmt: skip
    else:
        L.append("None: every rung of every method finished with status 0 and an error below 1.")
    if payload.get("notes"):
        L += ["", "## Notes", ""] + [f"- {n}" for n in payload["notes"]]

    L += ["", "## Work-precision data", ""]
    for s in scenes:
        L.append(f"### `{s['name']}`: {s['title']}")
        L.append("")
        if images and s["name"] in images:
            L += [f"![work-precision {s['name']}]({images[s['name']]})", ""]
        L += ["<details><summary>every rung</summary>", "",
              "| method | rtol | time/traj | error | rhs/traj | steps/traj | status |", "|---|---|---|---|---|---|---|"]
        for r in rows:
            if r["scene"] == s["name"]:
                L.append(f"| {r['label']} | {r['rtol']:.0e} | {_fmt_s(r['seconds_per_traj'])} | {r['error']:.2e} | "
                         f"{r['n_rhs']:.0f} | {r['steps']:.0f} | {r['status']} |")  # fmt: skip
        L += ["", "</details>", ""]
    if extra:
        L += [extra.rstrip(), ""]
    return "\n".join(L).rstrip() + "\n"


def run_work_precision(out_dir: os.PathLike, config: BenchConfig | None = None, *, failure_maps: bool = True,
                       docs: os.PathLike | None = None, progress: bool = True, command: str | None = None,
                       map_threads: int | None = None) -> dict:  # fmt: skip
    """Measure and write everything into ``out_dir``; returns the payload (with ``files``).

    Files: ``work_precision.csv`` and ``.json`` (every scene x method x rtol), ``wp_<scene>.png`` (one
    chart per scene), ``failure_*.png`` / ``.nc`` (with ``failure_maps``), ``summary.md``; with ``docs``
    also that markdown page (the same summary, no images).
    """
    config = config or BenchConfig()
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    payload = measure(config, progress=progress)
    files = {"csv": out / "work_precision.csv", "json": out / "work_precision.json", "summary": out / "summary.md"}
    write_table(payload["rows"], files["csv"])
    images = {}
    for s in payload["scenes"]:
        fig = plot_work_precision(payload["rows"], s)
        path = out / f"wp_{s['name']}.png"
        fig.savefig(path, dpi=110)
        images[s["name"]] = path.name
        files[f"wp_{s['name']}"] = path
    extra = ""
    if failure_maps:
        from ._failure import failure_maps as _maps

        _log("failure maps", progress)
        fm = _maps(out, quick=payload["meta"]["quick"], threads=map_threads, progress=progress)
        payload["failure_maps"] = fm["summary"]
        payload["failure_maps_markdown"] = fm["markdown"]
        files.update(fm["files"])
        extra = fm["markdown"]
    if failure_maps:
        from ._model_cost import model_cost

        _log("model cost (describing function, shooting, transient, auto)", progress)
        mc = model_cost(out, quick=payload["meta"]["quick"])
        payload["model_cost"] = mc["numbers"]
        files.update(mc["files"])
        extra = (extra + "\n\n" + mc["markdown"]).strip()
    payload["files"] = {k: str(v) for k, v in files.items()}
    payload["command"] = command
    with open(files["json"], "w") as f:
        json.dump(_json_safe(payload), f, indent=1)
    files["summary"].write_text(render_summary(payload, images=images, extra=extra, command=command))
    if docs is not None:
        docs = pathlib.Path(docs)
        docs.parent.mkdir(parents=True, exist_ok=True)
        docs.write_text(render_docs(payload, command=command, extra=extra))
        payload["files"]["docs"] = str(docs)
    return payload


def render_docs(payload: dict, *, command: str | None = None, extra: str = "") -> str:
    """The docs page (``docs/benchmarks.md``): the summary without images, with how to regenerate it."""
    head = ("<!-- Generated by tribosweep bench (python/tribosweep/_workprecision.py): do not edit by hand. "
            "Regenerate with `tribosweep bench --quick --out bench_out --docs docs/benchmarks.md` "
            "(or without --quick for the full ladder). -->\n")  # fmt: skip
    extra = "\n".join(line for line in extra.splitlines() if not line.startswith("!["))
    text = head + render_summary(payload, images=None, extra=extra, command=command)
    while "\n\n\n" in text:
        text = text.replace("\n\n\n", "\n\n")
    return text
