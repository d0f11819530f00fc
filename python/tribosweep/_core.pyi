"""Type stubs of the compiled core (private; use the tribosweep package)."""

from typing import Any, Literal

import numpy as np
import numpy.typing as npt

__all__ = [
    "branch",
    "branch_defaults",
    "branch_flag_names",
    "branch_point_type_names",
    "special_curve",
    "hopf_curve",
    "hopf_flag_names",
    "sliding_branch",
    "__version__",
    "TribosweepError",
    "InvalidArgumentError",
    "param_names",
    "seed_params",
    "status_names",
    "method_names",
    "steady_outcome_names",
    "instability_names",
    "validate_params",
    "static_point",
    "simulate",
    "ensemble",
    "linear_stability",
    "hopf_loads",
    "describing_function",
    "tidf_solve",
    "periodic_orbit",
    "periodic_orbits",
    "stop_calls",
]

__version__: str

class TribosweepError(Exception):
    """Base class of every error tribosweep raises on purpose."""

class InvalidArgumentError(TribosweepError, ValueError):
    """An argument is out of its valid range or of the wrong shape; the message names it, its value and the valid range."""

#: Friction laws the core parses (anything else raises InvalidArgumentError naming the argument and the valid names).
_FrictionLawName = Literal["constant", "coulomb", "switch"]
#: Contact models the core parses.
_ContactName = Literal["bilateral", "unilateral"]

def param_names() -> list[str]: ...
def seed_params() -> dict[str, float]: ...
def status_names() -> list[str]: ...
def method_names() -> list[str]: ...
def steady_outcome_names() -> list[str]: ...
def instability_names() -> list[str]: ...
def validate_params(values: dict[str, float], contact: str, friction_law: _FrictionLawName) -> None: ...
def static_point(values: dict[str, float]) -> tuple[float, float]: ...
def simulate(
    values: dict[str, float],
    contact: str,
    friction_law: _FrictionLawName,
    y0: npt.NDArray[np.float64],
    t_end: float,
    method: str,
    rtol: float,
    *,
    atol: npt.NDArray[np.float64] | None = None,
    t_eval: npt.NDArray[np.float64] | None = None,
    max_steps: int | None = None,
    max_events: int | None = None,
) -> dict[str, Any]: ...
def ensemble(
    base: dict[str, float],
    contact: str,
    friction_law: _FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    y0: npt.NDArray[np.float64],
    t_end: float,
    method: str,
    rtol: float,
    *,
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
    watch_x: bool = True,
    decay_thresholds: npt.NDArray[np.float64] | None = None,
    irregular_block: int = 0,
    known_irregular: npt.NDArray[np.float64] | None = None,
    known_cells: npt.NDArray[np.uint64] | None = None,
    known_cell_extent: npt.NDArray[np.float64] | None = None,
    restart: npt.NDArray[np.float64] | None = None,
    stationary_tol: float | None = None,
    approach_periods: int = 0,
    approach_rtol: float | None = None,
    approach_tol: float | None = None,
    checked_stops: bool = False,
) -> dict[str, Any]: ...
def linear_stability(
    base: dict[str, float],
    contact: str,
    friction_law: _FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    *,
    threads: int | None = None,
) -> dict[str, Any]: ...
def hopf_loads(
    values: dict[str, float], friction_law: _FrictionLawName, load_min: float, load_max: float, n_grid: int
) -> list[dict[str, Any]]: ...
def describing_function(
    base: dict[str, float],
    contact: str,
    friction_law: _FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    *,
    variant: str = "consistent",
    w_min: float = 150.0,
    w_max: float = 3000.0,
    n_base: int = 1000,
    threads: int | None = None,
) -> dict[str, Any]: ...
def periodic_orbit(
    values: dict[str, float],
    contact: str,
    friction_law: _FrictionLawName,
    *,
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
    friction_law: _FrictionLawName,
    names: list[str],
    values: npt.NDArray[np.float64],
    *,
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
    friction_law: _FrictionLawName,
    guesses: npt.NDArray[np.float64],
    *,
    variant: str = "consistent",
    threads: int | None = None,
) -> dict[str, Any]: ...

#: ``(name, reference, [(field, base, exponent), ...])``: no terms sets the field ``name``;
#: terms set ``field = base (value / reference) ** exponent`` each (the arm length).
_AxisSpec = tuple[str, float, list[tuple[str, float, float]]]

def hopf_flag_names() -> dict[str, list[str]]: ...
def sliding_branch(
    values: dict[str, float],
    contact: _ContactName,
    friction_law: _FrictionLawName,
    axis: _AxisSpec,
    lo: float,
    hi: float,
    *,
    n_points: int = 201,
    xtol: float = 1e-13,
) -> dict[str, Any]: ...
def hopf_curve(
    values: dict[str, float],
    contact: _ContactName,
    friction_law: _FrictionLawName,
    x_axis: _AxisSpec,
    y_axis: _AxisSpec,
    x_range: tuple[float, float],
    y_range: tuple[float, float],
    *,
    grid: tuple[int, int] = ...,
    step: float = 0.01,
    step_min: float = 1e-7,
    step_max: float = 0.05,
    tol: float = 1e-10,
    max_points: int = 5000,
    max_angle: float = 0.1,
    chord_tol: float = 1e-5,
    x_marks: list[float] = ...,
    y_marks: list[float] = ...,
) -> dict[str, Any]: ...

# Branches of periodic orbits (rust_core/bindings/src/branch.rs).
def branch(
    values: dict[str, float],
    contact: _ContactName,
    friction_law: _FrictionLawName,
    parameter: str,
    value: float,
    lo: float,
    hi: float,
    *,
    y0: npt.NDArray[np.float64] | None = None,
    period: float | None = None,
    direction: float = 1.0,
    hopf_omega: float | None = None,
    options: dict[str, float] = ...,
    stop_at: str | None = None,
) -> dict[str, Any]: ...
def special_curve(
    values: dict[str, float],
    contact: _ContactName,
    friction_law: _FrictionLawName,
    kind: Literal["fold", "grazing", "stick"],
    x: str,
    x_value: float,
    x_lo: float,
    x_hi: float,
    y: str,
    ys: npt.NDArray[np.float64],
    *,
    y0: npt.NDArray[np.float64] | None = None,
    period: float | None = None,
    direction: float = 1.0,
    hopf_omega: float | None = None,
    options: dict[str, float] = ...,
) -> dict[str, Any]: ...
def branch_point_type_names() -> list[str]: ...
def branch_flag_names() -> list[str]: ...
def branch_defaults() -> dict[str, float]: ...
def stop_calls(stop: bool) -> None: ...
