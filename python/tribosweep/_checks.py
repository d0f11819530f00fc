"""Argument checks shared by the public API: each raises ValueError naming the argument, its value and the range."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np

from . import _core

METHODS: tuple[str, ...] = tuple(_core.method_names())


def positive(name: str, value, *, allow_inf: bool = False) -> float:
    """A finite number > 0."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r} is not a number: must be a finite number > 0") from None
    if not (v > 0) or (math.isinf(v) and not allow_inf) or math.isnan(v):
        raise ValueError(f"{name} = {value!r} is out of range: must be a finite number > 0")
    return v


def rtol(value) -> float:
    """A relative tolerance in [1e-15, 1)."""
    v = positive("rtol", value)
    if not (1e-15 <= v < 1):
        raise ValueError(f"rtol = {value!r} is out of range: must be in [1e-15, 1)")
    return v


def method(value: str) -> str:
    """One of the integration methods."""
    if value not in METHODS:
        raise ValueError(f"method = {value!r} is not valid: must be one of {METHODS}")
    return value


def state(name: str, value, n: int | None = None) -> np.ndarray:
    """A finite state array of shape (6,) or, with ``n``, (6,), (1, 6) or (n, 6) -> always 2-D."""
    a = np.asarray(value, dtype=np.float64)
    ok_shapes = [(6,)] + ([(1, 6)] + ([(n, 6)] if n != 1 else []) if n is not None else [])
    if a.shape not in ok_shapes:
        want = " or ".join(str(s) for s in ok_shapes)
        raise ValueError(f"{name} has shape {a.shape}: must be {want}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} = {a.tolist()} contains NaN or inf: every entry must be finite")
    return a


def atol(value) -> np.ndarray | None:
    """None, a positive scalar (broadcast to 6), or 6 positive values."""
    if value is None:
        return None
    a = np.asarray(value, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(6, float(a))
    if a.shape != (6,):
        raise ValueError(f"atol has shape {a.shape}: must be a scalar or (6,), one per state component")
    if not np.all(np.isfinite(a) & (a > 0)):
        raise ValueError(f"atol = {a.tolist()} is out of range: every entry must be a finite number > 0")
    return a


def times(name: str, value, t_end: float) -> np.ndarray | None:
    """None or a strictly increasing 1-D array of finite times in [0, t_end]."""
    if value is None:
        return None
    a = np.asarray(value, dtype=np.float64)
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"{name} has shape {a.shape}: must be a non-empty 1-D array")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} contains NaN or inf: every time must be finite")
    if a[0] < 0 or a[-1] > t_end:
        raise ValueError(f"{name} spans [{a[0]}, {a[-1]}]: must lie within [0, t_end = {t_end}]")
    if np.any(np.diff(a) <= 0):
        raise ValueError(f"{name} is not strictly increasing")
    return a


#: Most worker threads accepted: far above any machine's cores, far below what would exhaust
#: memory on thread stacks (a huge value used to panic in the bindings or hang).
MAX_THREADS: int = 1024


def default_threads() -> int:
    """The threads a core call takes when given None: ``TRIBOSWEEP_THREADS``, else the cores this
    process may use (as the core's own default)."""
    env = os.environ.get("TRIBOSWEEP_THREADS", "").strip()
    if env.isdigit() and int(env) > 0:
        return int(env)
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def threads(value) -> int | None:
    """None or an int in [1, MAX_THREADS]."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= MAX_THREADS:
        raise ValueError(f"threads = {value!r} is out of range: must be an integer in [1, {MAX_THREADS}] or None")
    return int(value)


def param_arrays(params: dict[str, Sequence[float]], names: Sequence[str]) -> tuple[list[str], np.ndarray]:
    """``{name: 1-D array}`` of equal lengths -> (names, values (n, k)); names checked."""
    if not isinstance(params, dict) or not params:
        raise ValueError(f"params = {params!r} must be a non-empty dict {{parameter name: 1-D array}}")
    cols, keys, n = [], [], None
    for k, v in params.items():
        if k not in names:
            raise ValueError(f"params has unknown parameter {k!r}: valid names are {tuple(names)}")
        a = np.asarray(v, dtype=np.float64)
        if a.ndim != 1 or a.size == 0:
            raise ValueError(f"params[{k!r}] has shape {a.shape}: must be a non-empty 1-D array")
        if n is not None and a.size != n:
            raise ValueError(f"params[{k!r}] has {a.size} values but earlier arrays have {n}: lengths must agree")
        n = a.size
        if not np.all(np.isfinite(a)):
            bad = a[~np.isfinite(a)][0]
            raise ValueError(f"params[{k!r}] contains {bad}: every value must be finite")
        keys.append(k)
        cols.append(a)
    return keys, np.column_stack(cols)


def budget(name: str, value) -> int | None:
    """None or an integer >= 1 (a step or event budget)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name} = {value!r} is out of range: must be an integer >= 1 or None")
    return int(value)


#: Largest block of the census's stationarity test (sections).
MAX_BLOCK: int = 1_000_000


def block(name: str, value) -> int:
    """An integer in [0, MAX_BLOCK]: sections per block of a stationarity test, 0 for off."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value <= MAX_BLOCK:
        raise ValueError(
            f"{name} = {value!r} is out of range: must be an integer in [0, {MAX_BLOCK}] (sections per block; 0: off)"
        )
    return int(value)


def approach_periods(name: str, value) -> int:
    """An integer in [0, 10000]: periods per block of the slow-approach test, 0 for off."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value <= 10_000:
        raise ValueError(f"{name} = {value!r} is out of range: must be an integer in [0, 10000] (periods per "
                         "block of the slow-approach test; 0: off)")  # fmt: skip
    return int(value)


def switch_law(what: str, friction_law: str) -> None:
    """``what`` (a stick curve, a stop at a stick point) needs the switch friction law, the only one
    with a stick band: a ValueError naming both otherwise."""
    if friction_law != "switch":
        raise ValueError(f"{what} needs friction_law='switch' (only the switch law has a stick band), and "
                         f"model.friction_law = {friction_law!r}")  # fmt: skip
