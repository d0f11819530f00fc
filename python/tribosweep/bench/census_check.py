"""An independent classification of census disturbances, by the event-driven scipy reference.

The census labels each disturbance by the core's steady-state detectors (cycle repeat, decay
below the saddle, escape). This module judges the same starts with
:func:`tribosweep.bench.reference.solve_unilateral` and its own criteria, sharing no code with
the core, so that the two can be compared (``tests/test_census.py``, ``benches/bench_census.py``).
"""

import math

import numpy as np

from .reference import _Coeffs, solve_unilateral

__all__ = ["CLASS_LABELS", "classify_unilateral", "cycle_half_range"]

#: Labels of :func:`classify_unilateral`; "unsettled" runs are left out of comparisons.
CLASS_LABELS = ("sliding", "cycle", "escape", "unsettled")


def cycle_half_range(params: dict, state0) -> float:
    """Half the peak-to-peak ``z`` of the stable cycle through ``state0`` (m), the ``cycle_half_range``
    of :func:`classify_unilateral`: the event-driven reference over 0.1-0.3 s from that state."""
    cyc = solve_unilateral(params, state0, 0.3, rtol=1e-9, t_eval=np.linspace(0.1, 0.3, 4001))
    return 0.5 * float(np.ptp(cyc.y[0]))


def classify_unilateral(params: dict, y0, t_end: float, saddle_a1: float, cycle_half_range: float, *,
                        rtol: float = 1e-7, window: float = 0.1, escape_limit: float = 1e-3) -> str:
    """What one disturbance of the unilateral model is heading for, judged from its last two windows.

    An independent classifier for the census (it shares no code with the core's steady-state
    detectors): :func:`solve_unilateral` to ``t_end``, sampled at 50 points per linear period in the
    last ``2 window`` seconds, then

    * ``escape``: ``|z|`` passed ``escape_limit`` (outside the model's validity);
    * ``cycle``: the pin leaves the disk in both windows and the half-range of ``z`` is within 1 %
      of the stable cycle's (``cycle_half_range``) in both (a trajectory that lingers near the
      saddle bounces with a slowly drifting half-range and is ``unsettled``, not a cycle);
    * ``sliding``: the pin stays on the disk in both windows, the half-range of ``z`` shrank, and it
      is below 0.8 of the saddle cycle's ``A1`` (inside the saddle, moving inwards: in the normal
      form of the subcritical Hopf point such motion returns to sliding);
    * ``unsettled``: anything else by ``t_end`` (for example still near the saddle).

    Parameters
    ----------
    params : dict
        Parameter set (SI), as :func:`seed_parameters`.
    y0 : array_like, shape (6,)
        Start state.
    t_end : float
        Horizon, s.
    saddle_a1 : float
        First-harmonic amplitude of ``z`` on the saddle cycle, m (the describing function's root).
    cycle_half_range : float
        Half of the peak-to-peak ``z`` on the stable cycle, m.
    rtol : float
        Relative tolerance of the segments.
    window : float
        Length of each judged window, s.
    escape_limit : float
        ``|z|`` beyond which the run has escaped, m.

    Returns
    -------
    str
        One of :data:`CLASS_LABELS`.
    """
    c = _Coeffs.of(params)
    n = max(int(2 * window * math.sqrt(c.wt2) / (2 * math.pi) * 50), 200)
    t_eval = np.linspace(t_end - 2 * window, t_end, n)
    sol = solve_unilateral(params, y0, t_end, rtol=rtol, t_eval=t_eval)
    z = sol.y[0]
    if not np.all(np.isfinite(z)) or np.abs(z).max() > escape_limit or abs(sol.y_end[0]) > escape_limit:
        return "escape"
    first, last = z[: n // 2], z[n // 2 :]
    half = [0.5 * float(np.ptp(w)) for w in (first, last)]
    off = [bool(np.any(c.z_st + w > 0.0)) for w in (first, last)]
    if all(off) and all(abs(h - cycle_half_range) < 0.01 * cycle_half_range for h in half):
        return "cycle"
    if not any(off) and half[1] < half[0] and half[1] < 0.8 * saddle_a1:
        return "sliding"
    return "unsettled"
