"""Run-time checks that flag a failure: each fires on a constructed failing case and stays silent on a benign one.

Numbers are from the seed configuration (docs/model.md §3): z_st = -16.56 um; the bilateral law's static saddle
is at z = 256.7 um, past which K_a z^2 blows the motion up in finite time (t = 2.93 ms from 300 um at rest);
sliding is unstable at mu = 0.35 below 225 N (docs/model.md §4).
"""

from __future__ import annotations

import numpy as np
import pytest

import tribosweep as ts
from tribosweep import STATUS
from tribosweep.bench import reference

SEED = ts.SliderModel(contact="bilateral")
Z_ST = SEED.static_point()[0]


def y0(z: float) -> list[float]:
    return [z, 0.0, 0.0, 0.0, 0.0, 0.0]


def run(model, t_end, z0, method="dopri5", rtol=1e-8):
    ds = ts.simulate(model, t_end, y0=y0(z0), method=method, rtol=rtol, t_eval=[0.0, t_end])
    return ds, ts.STATUS_NAMES[int(ds.status)]


# --- (i) max_steps -------------------------------------------------------------------------------


def test_max_steps_fires_past_the_step_budget():
    # The default budget (10^7 steps) is reached in practice by explicit methods on stiff friction
    # regularisation (eps = 1e-8 m/s, the failure map); the test lowers it to exercise the detector.
    ds = ts.simulate(SEED, 0.5, max_steps=10)
    assert ts.STATUS_NAMES[int(ds.status)] == "max_steps"
    assert int(ds.n_accept) + int(ds.n_reject) == 10 and float(ds.t_reached) < 0.5
    # In an ensemble: only the point that runs out is flagged; benign with the default budget.
    ens = ts.ensemble(SEED, 0.5, {"mu": [0.215, 0.215]}, max_steps=10)
    assert [ts.STATUS_NAMES[int(v)] for v in ens.status.values] == ["max_steps", "max_steps"]
    assert int(ts.simulate(SEED, 0.5).status) == 0


# --- (ii) step_too_small, non_finite, escape -----------------------------------------------------


@pytest.mark.parametrize("method", ["dopri5", "dop853", "rodas4"])
def test_step_too_small_on_finite_time_blow_up(method):
    # Past the saddle the quadratic law blows z up in finite time; with the escape event out of the way the
    # step size collapses onto the singularity.
    blow = SEED.replace(escape_limit=1e100)
    ds, status = run(blow, 1.0, 300e-6, method)
    assert status == "step_too_small"
    assert 2.90e-3 < float(ds.t_reached) < 2.95e-3
    assert float(ds.max_abs_z) > 1e12
    # benign: the same model from 1 um runs to the end
    ds, status = run(blow, 0.05, 1e-6, method)
    assert status == "success" and float(ds.t_reached) == 0.05


def test_non_finite_on_overflowing_state():
    # K_a z^2 = 2.179e10 * 1e300 overflows to inf on the first right-hand side.
    ds, status = run(SEED.replace(escape_limit=1e300), 0.1, 1e150)
    assert status == "non_finite"
    assert float(ds.t_reached) < 1e-6
    ds, status = run(SEED.replace(escape_limit=1e300), 0.1, 1e-6)
    assert status == "success"


def test_escape_limit_stops_the_blow_up():
    # Default escape limit (1 mm): the same blow-up is declared diverged exactly at |z| = 1 mm (t = 2.04 ms),
    # 0.9 ms before the singularity.
    ds, status = run(SEED, 1.0, 300e-6)
    assert status == "diverged"
    assert float(ds.max_abs_z) == pytest.approx(1e-3, rel=1e-9)
    assert 1.95e-3 < float(ds.t_reached) < 2.15e-3


def test_tiny_escape_limit():
    # escape_limit = 0.5 um: a 1 um motion crosses it within the first normal period (~1.5 ms) ...
    ds, status = run(SEED.replace(escape_limit=0.5e-6), 0.5, 1e-6)
    assert status == "diverged"
    assert float(ds.t_reached) < 2e-3
    # ... a 0.1 um motion (largest |z| 0.106 um) never reaches it.
    ds, status = run(SEED.replace(escape_limit=0.5e-6), 0.5, 0.1e-6)
    assert status == "success"
    assert float(ds.max_abs_z) == pytest.approx(0.106e-6, rel=0.02)


# --- (iii) diverged --------------------------------------------------------------------------------


def test_diverged_bilateral_mu_035_and_not_at_seed():
    # mu = 0.35 at 84.46 N: sliding unstable (Hopf load 225 N), the bilateral model has no stable cycle, so a
    # 1 um disturbance grows until it escapes (at t = 4.34 s); at the seed mu = 0.215 it decays.
    ens = ts.ensemble(SEED, 8.0, {"mu": [0.35, 0.215]}, rtol=1e-8, threads=1)
    status = [ts.STATUS_NAMES[int(s)] for s in ens.status.values]
    assert status == ["diverged", "success"]  # the failed point is data; the other one still runs to the end
    assert 3.5 < float(ens.t_reached[0]) < 5.5
    assert float(ens.max_abs_z[0]) == pytest.approx(1e-3, rel=1e-9)
    assert float(ens.t_reached[1]) == 8.0
    assert float(ens.max_abs_z[1]) == pytest.approx(1.06e-6, rel=0.02)  # the initial swing: it only decays
    # ... as the linearised motion e^(J t) y0 does (J: the numpy reference's Jacobian), down to 3.2 nm at 8 s.
    # The quadratic contact term departs from it by at most 2 K_a |z| / K_s = 0.8 % of the restoring force
    # (at the initial 1 um, less as it decays): the tolerance.
    from scipy.linalg import expm

    z_lin = (expm(8.0 * reference.linear_jacobian(SEED.values())) @ np.array(y0(1e-6)))[0]
    k_s = SEED.static_point()[1]
    assert float(ens.z_end[1]) == pytest.approx(z_lin, rel=2 * SEED.contact_quadratic * 1e-6 / k_s)


def test_diverged_unilateral_at_low_load_high_mu():
    # Not even the unilateral model stays bounded everywhere: at 20 N and mu = 0.35 the bouncing grows to
    # centimetres (28 mm by 0.2 s with the limit lifted); the 1 mm escape limit flags it near 0.065 s.
    m = SEED.replace(contact="unilateral", mu=0.35, normal_load=20.0)
    ds, status = run(m, 0.2, 30e-6)
    assert status == "diverged"
    assert 0.05 < float(ds.t_reached) < 0.08
    ds, status = run(m.replace(mu=0.215, normal_load=84.46), 0.2, 30e-6)
    assert status == "success" and float(ds.max_abs_z) < 1e-4


# --- (iv) contact opening --------------------------------------------------------------------------


def test_contact_opening_flag_bilateral():
    # max_gap = z_st + max z: a 40 um disturbance lifts the pin 25.8 um off the disk (outside the bilateral
    # law's validity); a 1 um one keeps it 15.5 um inside.
    ds, status = run(SEED, 0.1, 40e-6)
    assert status == "success"
    assert float(ds.max_gap) == pytest.approx(25.8e-6, rel=0.02)
    assert float(ds.max_gap) == pytest.approx(Z_ST + float(ds.max_abs_z), abs=1e-9)
    ds, _ = run(SEED, 0.1, 1e-6)
    assert -15.6e-6 < float(ds.max_gap) < -15.4e-6
    assert float(ds.min_normal_force) > 70.0


def test_contact_opening_unilateral_events_and_zero_force():
    uni = SEED.replace(contact="unilateral", mu=0.30)
    ds, status = run(uni, 0.2, 30e-6)
    assert status == "success"
    assert float(ds.max_gap) > 10e-6
    # N = 0 while open, never tension: at a lift-off event N is zero to the event's time tolerance
    # (1e-13 s) times its rate, k0 |zd| <= 2e5 N/s here, so within 2e-8 N. A lift-off stepped across
    # would leave tension of order k0 |zd| h, about 1 N. The bound, 1e-9 of the load (8.4e-8 N):
    assert -1e-9 * float(uni.normal_load) < float(ds.min_normal_force) <= 0.0
    assert int(ds.n_events) >= 6  # lift-offs and landings are located events
    ds, _ = run(uni.replace(mu=0.215), 0.2, 1e-6)
    assert float(ds.max_gap) < 0 and int(ds.n_events) == 0


# --- (v) stick-slip ----------------------------------------------------------------------------------


def test_stick_slip_flag_constant_friction():
    # Constant mu at V = 0.01 m/s: a 20 um disturbance swings the contact point faster than V (the twist lever
    # L phi_dot dominates), so v_r dips to -0.03 m/s: the report's constant-mu law is invalid there.
    slow = SEED.replace(sliding_speed=0.01)
    ds, _ = run(slow, 0.1, 20e-6)
    assert float(ds.min_slip_velocity) == pytest.approx(-0.0305, abs=0.002)
    ds, _ = run(SEED, 0.1, 1e-6)  # seed: v_r stays near V = 0.46 m/s
    assert float(ds.min_slip_velocity) == pytest.approx(0.458, abs=0.002)


def test_stick_slip_regularised_friction_sticks():
    # With regularised Coulomb friction and a falling Stribeck curve the contact sticks: v_r reaches 0 and
    # dips only to the order of the regularisation eps (the work-precision stick-slip scene).
    eps = 1e-4
    m = SEED.replace(friction_law="coulomb", friction_regularization=eps, sliding_speed=0.01, mu_static=0.3,
                     stribeck_velocity=0.02)  # fmt: skip
    ds, status = run(m, 0.2, 1e-6, method="rodas4", rtol=1e-6)
    assert status == "success"
    assert -10 * eps < float(ds.min_slip_velocity) <= 0.0
    ds, _ = run(m.replace(sliding_speed=0.46, stribeck_velocity=0.1, mu_static=None), 0.1, 1e-6, method="rodas4")
    assert float(ds.min_slip_velocity) > 0.4


# --- (vi) event chatter ------------------------------------------------------------------------------


def test_event_chatter_fires_past_the_event_budget():
    # EventChatter fires when a run exceeds its event budget (default 10^7); the guard against grazing
    # re-triggers keeps real scenes far from that, so the test lowers the budget.
    # mu = 0.35: sliding unstable, the motion grows into a bouncing cycle (about 3,000 located contact
    # events in 12 s). A budget of 500 events flags it; the default budget lets it finish.
    bouncing = SEED.replace(contact="unilateral", mu=0.35)
    ds = ts.simulate(bouncing, 12.0, t_eval=[12.0], max_events=500)
    assert ts.STATUS_NAMES[int(ds.status)] == "event_chatter"
    assert int(ds.n_events) > 500 and float(ds.t_reached) < 12.0
    ds = ts.simulate(bouncing, 12.0, t_eval=[12.0])
    assert int(ds.status) == 0 and int(ds.n_events) > 1000


def test_status_codes_are_the_documented_ones():
    assert STATUS["max_steps"] == 1 and STATUS["step_too_small"] == 2 and STATUS["non_finite"] == 3
    assert STATUS["diverged"] == 5 and STATUS["event_chatter"] == 6
    assert np.all(np.diff(sorted(STATUS.values())) == 1)
