"""tribosweep: friction-induced vibration of sliding contacts, mapped over load, stiffness and speed.

The numerics run in a Rust core (``tribosweep._core``); this package organises them as xarray
Datasets. Units are SI throughout (m, kg, s, N, rad; frequencies in rad/s unless marked Hz).
"""

from __future__ import annotations

from . import _core
from ._flags import OUTCOME_NAMES, STATUS, STATUS_NAMES
from ._model import PARAM_NAMES, SliderModel
from ._simulate import DEFAULT_Y0, ensemble, simulate

__version__: str = _core.__version__

__all__ = [
    "DEFAULT_Y0",
    "OUTCOME_NAMES",
    "PARAM_NAMES",
    "STATUS",
    "STATUS_NAMES",
    "SliderModel",
    "__version__",
    "ensemble",
    "simulate",
]
