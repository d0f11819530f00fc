"""Work-precision scenes: small batches of trajectories of one physical situation each."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from .._model import SliderModel

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
    contact="bilateral", friction_law="coulomb", friction_regularization=1e-5, sliding_speed=0.01, mu_static=0.3, stribeck_velocity=0.02
)
#: The same scene with the event-driven switch law (stick band 1e-6 m/s): no stiffness, every stick and
#: slip a located event.
STICK_SLIP_SWITCH_MODEL = STICK_SLIP_MODEL.replace(friction_law="switch")


def make_scenes(quick: bool = False, names: Iterable[str] | None = None, n: int | None = None) -> list[Scene]:
    """The benchmark scenes (docs/model.md §3, §6): seed, unilateral, stick_slip, large_amplitude.

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

    seed = SliderModel(contact="bilateral")  # the report's model; the unilateral scenes say so
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
