"""Type stubs of the compiled core (private; use the tribosweep package)."""

from typing import Any, Literal

import numpy as np
import numpy.typing as npt

__version__: str

#: Friction laws the core parses (anything else raises ValueError naming the argument and the valid names).
FrictionLawName = Literal["constant", "coulomb", "switch"]
#: Contact models the core parses.
ContactName = Literal["bilateral", "unilateral"]

def param_names() -> list[str]: ...
def seed_params() -> dict[str, float]: ...
def status_names() -> list[str]: ...
def method_names() -> list[str]: ...
def steady_outcome_names() -> list[str]: ...
def instability_names() -> list[str]: ...
def validate_params(values: dict[str, float], contact: str, friction_law: FrictionLawName) -> None: ...
def static_point(values: dict[str, float]) -> tuple[float, float]: ...
def simulate(
    values: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    y0: npt.NDArray[np.float64],
    t_end: float,
    method: str,
    rtol: float,
    atol: npt.NDArray[np.float64] | None = None,
    t_eval: npt.NDArray[np.float64] | None = None,
    max_steps: int | None = None,
    max_events: int | None = None,
) -> dict[str, Any]: ...
def ensemble(
    base: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    y0: npt.NDArray[np.float64],
    t_end: float,
    method: str,
    rtol: float,
    atol: npt.NDArray[np.float64] | None = None,
    t_eval: npt.NDArray[np.float64] | None = None,
    threads: int | None = None,
    kind: str = "final",
    periodic_tol: float = 1e-5,
    decay_amplitude: float | None = None,
    n_fourier: int = 512,
    max_steps: int | None = None,
    max_events: int | None = None,
    decay_amplitudes: npt.NDArray[np.float64] | None = None,
) -> dict[str, Any]: ...
def linear_stability(
    base: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    threads: int | None = None,
) -> dict[str, Any]: ...
def hopf_loads(
    values: dict[str, float], friction_law: FrictionLawName, load_min: float, load_max: float, n_grid: int
) -> list[dict[str, Any]]: ...
def describing_function(
    base: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    variant: str = "consistent",
    w_min: float = 150.0,
    w_max: float = 3000.0,
    n_base: int = 1000,
    threads: int | None = None,
) -> dict[str, Any]: ...
def periodic_orbit(
    values: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    y0: npt.NDArray[np.float64] | None = None,
    period: float | None = None,
    root: npt.NDArray[np.float64] | None = None,
    variant: str = "consistent",
    rtol: float = 1e-11,
    max_iter: int = 30,
    tol: float = 1e-9,
) -> dict[str, Any]: ...
def periodic_orbits(
    base: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    roots: npt.NDArray[np.float64] | None = None,
    y0: npt.NDArray[np.float64] | None = None,
    periods: npt.NDArray[np.float64] | None = None,
    variant: str = "consistent",
    rtol: float = 1e-11,
    max_iter: int = 30,
    tol: float = 1e-9,
    threads: int | None = None,
) -> dict[str, Any]: ...
def tidf_solve(
    values: dict[str, float],
    friction_law: FrictionLawName,
    guesses: npt.NDArray[np.float64],
    variant: str = "consistent",
    threads: int | None = None,
) -> dict[str, Any]: ...

# Branches of periodic orbits (rust_core/bindings/src/branch.rs).
def branch(
    values: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    parameter: str,
    value: float,
    lo: float,
    hi: float,
    y0: npt.NDArray[np.float64] | None = None,
    period: float | None = None,
    direction: float = 1.0,
    hopf_omega: float | None = None,
    options: dict[str, float] = ...,
    stop_at: str | None = None,
) -> dict[str, Any]: ...
def special_curve(
    values: dict[str, float],
    contact: str,
    friction_law: FrictionLawName,
    kind: Literal["fold", "grazing"],
    x: str,
    x_value: float,
    x_lo: float,
    x_hi: float,
    y: str,
    ys: npt.NDArray[np.float64],
    y0: npt.NDArray[np.float64] | None = None,
    period: float | None = None,
    direction: float = 1.0,
    hopf_omega: float | None = None,
    options: dict[str, float] = ...,
) -> dict[str, Any]: ...
def branch_point_type_names() -> list[str]: ...
def branch_flag_names() -> list[str]: ...
def branch_defaults() -> dict[str, float]: ...
