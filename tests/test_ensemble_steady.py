"""`ensemble(steady=True)` with a sweep's early stops: the stationarity test of sustained irregular
motion (`irregular_block`) and the slow-approach checks (`approach_periods`).

Points of the issue-10 Stribeck sweep (switch law, unilateral contact, mu_static 0.3); the
intermittent one is in tests/test_irregular.py. Each verdict is checked against an independent
computation: the orbit by shooting at rtol 1e-11, chaos by the Lyapunov exponent of
test_irregular.py::test_a_stribeck_point_is_chaotic, and none pins one chaotic run's fate: the
chaotic point's runs end irregular from every start and at any last bit, only their stop times
move.
"""

from __future__ import annotations

import numpy as np
import pytest

import tribosweep as ts
from conftest import slow_approach_start
from tribosweep import _codes, _core

LAW = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3)
LOADS, ARMS = np.linspace(10, 150, 10), np.linspace(0.05, 0.127, 4)
END = ("z", "z_dot", "x", "x_dot", "phi", "phi_dot")


def _runs(load, arm, speed, starts, t_end, **kw):
    """The apparatus point's model and its runs to steady state from ``z = starts``."""
    m = ts.apparatus_model(load, arm, speed, base=LAW)
    y0 = np.zeros((len(starts), 6))
    y0[:, 0] = starts
    return m, ts.ensemble(m, t_end, {"normal_load": [load] * len(starts)}, y0=y0, steady=True, **kw)


def test_stationary_irregular_motion_ends_early_with_its_residual_and_a_reason():
    # 87.8 N, 7.57 cm, 0.2 m/s: chaotic (largest Lyapunov exponent 5 standard errors above 0 in
    # test_irregular.py). Without the test the runs go on to t_end unsettled; with blocks of 128
    # sections (a sweep's) each stops once three blocks in a row agree. Measured when written:
    # at 2.7 and 5.2 s, mean residuals 2.7 and 2.5 characteristic sizes.
    starts, t_end = (1e-6, 5e-6, -3e-6), 30.0
    _, plain = _runs(LOADS[5], ARMS[1], 0.2, starts, t_end)
    assert np.all(plain.outcome.values == _codes.OUTCOME_NAMES.index("unsettled"))
    assert np.all(plain.t_end.values == t_end)
    _, ds = _runs(LOADS[5], ARMS[1], 0.2, starts, t_end, irregular_block=128)
    assert np.all(ds.outcome.values == _codes.OUTCOME_NAMES.index("irregular")), ds.reason.values
    assert np.all(ds.status.values == ts.STATUS["success"])
    # Before t_end: 2-11 s with rtol or the inputs moved by 1-2 % or 1-2 ulps (a chaotic run's
    # stop moves with its last bits; its verdict does not).
    assert np.all(ds.t_end.values < t_end)
    # Irregular, not a cycle's approach: the mean residual is above the floor of 1e-3 (a cycle's
    # sections repeat to periodic_tol = 1e-5) by three orders.
    assert np.all(ds.irregular_residual.values > 1.0), ds.irregular_residual.values
    for text, t in zip(ds.reason.values, ds.t_end.values):
        assert text == f"bounded motion, neither periodic nor decayed and stationary over three blocks of 128 sections by t = {t:.3g} s"
    # Not intermittent, not a slow approach.
    assert np.all(np.isnan(ds.intermittent_period.values)) and not ds.approach.values.any()
    assert np.all(ds.intermittent_instability.values == 0)


def test_slow_approach_ends_on_the_orbit_that_shooting_finds():
    # 10 N, 10.1 cm, 0.2 m/s: a period-2 contact-loss cycle whose slowest multiplier is 0.9933
    # (x's light damping). From conftest's start on its section with x moved (no chaotic phase,
    # only the slow approach) the run repeats to periodic_tol = 1e-5 at 15.35 s. With the
    # slow-approach checks (a sweep's 10 periods per block) it shoots from its section once the
    # residual has shrunk three blocks in a row to 1e-3, ends on the orbit and is measured there:
    # at 8.76 s (both the same to 1e-6 s with rtol moved by 1 %).
    m, y0, _ = slow_approach_start()
    runs = {k: ts.ensemble(m, 40.0, {"normal_load": [10.0]}, y0=y0, steady=True, approach_periods=k) for k in (0, 10)}
    plain, ds = runs[0], runs[10]
    periodic = _codes.OUTCOME_NAMES.index("periodic")
    assert int(plain.outcome[0]) == periodic and int(ds.outcome[0]) == periodic
    assert bool(ds.approach[0]) and not bool(plain.approach[0])
    assert float(ds.t_end[0]) < float(plain.t_end[0]) - 5.0, (float(ds.t_end[0]), float(plain.t_end[0]))
    assert int(ds.multiplicity[0]) == 2
    # An independent shooting at rtol 1e-11 from where the run ended: a stable orbit of the run's
    # period, on which the run was measured (its frequency to 1e-8 and its A1 to 1e-7; the
    # in-run check converged at rtol 1e-9 to Newton tolerance 1e-8).
    y_end = [float(ds[f"{v}_end"][0]) for v in END]
    orb = ts.periodic_orbit(m, (y_end, float(ds.period[0])), rtol=1e-11, tol=1e-10)
    assert int(orb.status) == ts.STATUS["success"] and bool(orb.stable)
    assert abs(float(ds.omega[0]) / float(orb.omega) - 1) < 1e-8
    assert abs(float(ds.z1_amplitude[0]) / float(orb.A1) - 1) < 1e-7
    # Its slowest non-trivial multiplier (a complex pair of modulus 0.9933, just below the trivial
    # one, 1, which sorts last) is what made the approach slow.
    moduli = np.sort(orb.floquet_moduli.values)
    assert 0.99 < moduli[-2] < 0.999, moduli


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(steady=True, irregular_block=-1), r"irregular_block = -1 is out of range: must be an integer in \[0, 1000000\]"),
        (dict(steady=True, irregular_block=12.5), r"irregular_block = 12.5 is out of range"),
        (dict(steady=True, approach_periods=True), r"approach_periods = True is out of range: must be an integer in \[0, 10000\]"),
        (dict(steady=True, approach_periods=20_000), r"approach_periods = 20000 is out of range"),
        (dict(irregular_block=128), r"irregular_block = 128 needs steady=True"),
        (dict(approach_periods=10), r"approach_periods = 10 needs steady=True"),
    ],
)  # fmt: skip
def test_ensemble_rejects_bad_early_stop_settings_before_work_starts(monkeypatch, kwargs, match):
    def no_work(*a, **k):
        raise AssertionError("work started")

    monkeypatch.setattr(_core, "ensemble", no_work)
    with pytest.raises(ValueError, match=match):
        ts.ensemble(LAW, 1.0, {"normal_load": [50.0]}, **kwargs)
