"""Status codes and categorical flags, defined once (mirrors ``rust_core/src/status.rs``)."""

from __future__ import annotations

import numpy as np

from . import _core

#: Status names in code order: ``STATUS_NAMES[code]``.
STATUS_NAMES: tuple[str, ...] = tuple(_core.status_names())
#: Status code by name.
STATUS: dict[str, int] = {name: i for i, name in enumerate(STATUS_NAMES)}
#: Outcome names of a run to steady state, in code order.
OUTCOME_NAMES: tuple[str, ...] = tuple(_core.steady_outcome_names())
#: How a periodic orbit is unstable (its largest non-trivial Floquet multiplier), in code order.
INSTABILITY_NAMES: tuple[str, ...] = tuple(_core.instability_names())


def flag_attrs(names: tuple[str, ...] | list[str], long_name: str) -> dict:
    """CF attributes of a categorical variable whose value ``i`` means ``names[i]``."""
    return {
        "long_name": long_name,
        "flag_values": np.arange(len(names), dtype=np.uint8),
        "flag_meanings": " ".join(names),
    }
