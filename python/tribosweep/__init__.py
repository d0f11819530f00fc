"""tribosweep: friction-induced vibration of sliding contacts, mapped over load, stiffness and speed.

The numerics run in a Rust core (``tribosweep._core``); this package organises them as xarray
Datasets. Units are SI throughout (m, kg, s, N, rad; frequencies in rad/s unless marked Hz).
"""

from __future__ import annotations

from . import _core
from ._apparatus import ARM_EXPONENTS, apparatus_model, arm_frequencies
from ._boundary import boundary_curves
from ._branch import BRANCH_FLAG_NAMES, bifurcation_diagram, branch
from ._branch import POINT_TYPE_NAMES as BRANCH_POINT_TYPE_NAMES
from ._census import census
from ._codes import (
    ATTRACTOR_NAMES,
    BISTABLE_NAMES,
    DECIDED_BY_NAMES,
    INSTABILITY_NAMES,
    OUTCOME_NAMES,
    REGIME_NAMES,
    STATUS,
    STATUS_NAMES,
    WEAR_APPLICABILITY_NAMES,
    labels,
)
from ._core import InvalidArgumentError, TribosweepError
from ._curves import fold_curve, grazing_curve, stick_curve
from ._frequency import describing_function, follow_cycle, hopf_load, linear_stability, periodic_orbit
from ._hopf import (
    CRITICALITY_NAMES,
    END_STATUS_NAMES,
    HOPF_PARAMETERS,
    hopf_curve,
    hopf_cycle_guess,
    sliding_branch,
)
from ._hopf import POINT_TYPE_NAMES as HOPF_POINT_TYPE_NAMES
from ._model import PARAM_NAMES, SliderModel
from ._simulate import DEFAULT_Y0, ensemble, simulate
from ._sweep import sweep
from ._wear import WearCalibration, WearReference, normal_mode_frequency_hz, relative_wear_rate

__version__: str = _core.__version__

__all__ = [
    "ARM_EXPONENTS",
    "ATTRACTOR_NAMES",
    "BISTABLE_NAMES",
    "BRANCH_FLAG_NAMES",
    "BRANCH_POINT_TYPE_NAMES",
    "CRITICALITY_NAMES",
    "DECIDED_BY_NAMES",
    "DEFAULT_Y0",
    "END_STATUS_NAMES",
    "INSTABILITY_NAMES",
    "InvalidArgumentError",
    "OUTCOME_NAMES",
    "HOPF_PARAMETERS",
    "PARAM_NAMES",
    "HOPF_POINT_TYPE_NAMES",
    "REGIME_NAMES",
    "STATUS",
    "STATUS_NAMES",
    "SliderModel",
    "TribosweepError",
    "WEAR_APPLICABILITY_NAMES",
    "WearCalibration",
    "WearReference",
    "__version__",
    "apparatus_model",
    "arm_frequencies",
    "bifurcation_diagram",
    "boundary_curves",
    "branch",
    "census",
    "describing_function",
    "ensemble",
    "follow_cycle",
    "fold_curve",
    "grazing_curve",
    "hopf_curve",
    "hopf_cycle_guess",
    "hopf_load",
    "labels",
    "linear_stability",
    "normal_mode_frequency_hz",
    "periodic_orbit",
    "relative_wear_rate",
    "simulate",
    "sliding_branch",
    "stick_curve",
    "sweep",
]
