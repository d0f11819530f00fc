"""Every non-success status comes with a reason that says why, with its numbers.

Each failure is provoked for real (the recipes of test_detectors.py, numbers from the seed of
MODEL.md §3: past the bilateral law's saddle z blows up in finite time at t = 2.93 ms from 300 um at
rest; the default escape limit is 1 mm), on ``simulate`` and on every route of ``ensemble`` (the
batch for the bilateral end state, the lanes with ``t_eval``, the scalar driver with Rodas4). The
reason must name the status's cause and carry the time reached, which must be the run's own
``t_reached`` (printed with 7 significant digits: the relative tolerance 1e-6 is the printing's).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import tribosweep as ts
from tribosweep import _core

SEED = ts.SliderModel(contact="bilateral")
BLOW_UP = SEED.replace(escape_limit=1e100)
#: Printed times carry 7 significant digits (``{:.6e}``).
PRINTED = 1e-6


def y0(z: float) -> list[float]:
    return [z, 0.0, 0.0, 0.0, 0.0, 0.0]


def number_after(label: str, text: str) -> float:
    m = re.search(re.escape(label) + r"\s*=?\s*([-+0-9.eE]+|NaN|inf)", text)
    assert m, f"no {label!r} in {text!r}"
    return float(m.group(1))


def check_time(reason: str, t_reached: float) -> None:
    assert number_after("t =", reason) == pytest.approx(t_reached, rel=PRINTED), reason


# (model, t_end, start z, options, status, words the reason must contain)
CASES = {
    "max_steps": (SEED, 0.5, 1e-6, {"max_steps": 10}, "max_steps", ["step budget", "max_steps = 10", "t_end = 5.000000e-1"]),
    "step_too_small": (BLOW_UP, 1.0, 300e-6, {}, "step_too_small", ["step size underflow", "below the floor", "rtol = 1.0e-8"]),
    "non_finite": (SEED.replace(escape_limit=1e300), 0.1, 1e150, {}, "non_finite", ["not finite"]),
    "diverged": (SEED, 1.0, 300e-6, {}, "diverged", ["escape limit 1.0000e-3 m"]),
    "event_chatter": (SEED.replace(contact="unilateral", mu=0.35), 12.0, 1e-6, {"max_events": 500}, "event_chatter",
                      ["max_events = 500"]),
}  # fmt: skip


@pytest.mark.parametrize("case", list(CASES))
def test_simulate_failures_have_a_reason_with_their_numbers(case):
    model, t_end, z0, opts, status, words = CASES[case]
    ds = ts.simulate(model, t_end, y0=y0(z0), rtol=1e-8, t_eval=[0.0, t_end], **opts)
    assert ts.STATUS_NAMES[int(ds.status)] == status
    reason = str(ds.reason.values)
    for w in words:
        assert w in reason, reason
    check_time(reason, float(ds.t_reached))
    if case == "step_too_small":
        # The step asked for is below the floor, and the run ended at the singularity.
        assert number_after("h =", reason) < number_after("floor", reason)
        assert 2.90e-3 < float(ds.t_reached) < 2.95e-3


ROUTES = {
    "batch": dict(method="dopri5", t_eval=None),
    "lanes": dict(method="dopri5", t_eval="ends"),
    "scalar": dict(method="rodas4", t_eval=None),
}


@pytest.mark.parametrize("route", list(ROUTES))
@pytest.mark.parametrize("case", ["step_too_small", "non_finite", "diverged", "max_steps"])
def test_ensemble_failures_have_the_same_reason_on_every_route(case, route):
    model, t_end, z0, opts, status, words = CASES[case]
    r = ROUTES[route]
    t_eval = [0.0, t_end] if r["t_eval"] else None
    # A success next to the failure: the reason is per trajectory, and empty for the success.
    ens = ts.ensemble(model, t_end, {"normal_load": [84.46, 84.46]}, y0=[y0(z0), y0(1e-6)], method=r["method"],
                      rtol=1e-8, t_eval=t_eval, threads=1, **opts)  # fmt: skip
    names = [ts.STATUS_NAMES[int(s)] for s in ens.status.values]
    if case == "max_steps":
        # 10 steps do not reach t_end from either start.
        assert names == ["max_steps", "max_steps"]
    else:
        assert names == [status, "success"]
        assert str(ens.reason.values[1]) == ""
    reason = str(ens.reason.values[0])
    for w in words:
        assert w in reason, reason
    check_time(reason, float(ens.t_reached[0]))


def test_a_steady_run_that_never_settles_says_so():
    # A 10 ms run to steady state of the growing bilateral motion at mu = 0.35 (sliding unstable):
    # neither decayed nor periodic by t_max.
    ens = ts.ensemble(SEED, 0.01, {"mu": [0.35]}, steady=True, threads=1)
    assert ts.STATUS_NAMES[int(ens.status[0])] == "not_converged"
    reason = str(ens.reason.values[0])
    assert "no steady state by t_max = 1.000000e-2 s" in reason and "periodic_tol = 1.0e-5" in reason, reason
    # A run that escapes is a recognised end (diverged outcome), a success with no reason.
    ens = ts.ensemble(SEED, 1.0, {"mu": [0.215]}, y0=y0(300e-6), steady=True, threads=1)
    assert int(ens.status[0]) == 0 and str(ens.reason.values[0]) == ""


def test_an_unconverged_orbit_is_nan_with_stability_unset():
    df = ts.describing_function(SEED)
    root = df.where(df.physical == 1, drop=True).isel(root=0)
    orb = ts.periodic_orbit(SEED, root, max_iter=0)
    assert ts.STATUS_NAMES[int(orb.status)] == "newton_not_converged"
    for v in ("period", "omega", "A0", "A1", "A2", "A3", "theta", "z_max", "fraction_off_disk", "min_normal_force"):
        assert np.isnan(float(orb[v])), v
    assert np.all(np.isnan(orb.floquet_moduli.values)) and np.all(np.isnan(orb.state0.values))
    assert "stable" not in orb and "contact_opens" not in orb and "period_doubling" not in orb
    assert ts.INSTABILITY_NAMES[int(orb.instability)] == "unknown"
    reason = str(orb.reason.values)
    assert "max_iter = 0" in reason and "Newton did not converge" in reason, reason
    # The residual in the reason is the attempt's, above the tolerance.
    assert number_after("residual is", reason) == pytest.approx(float(orb.residual), rel=1e-3)
    assert float(orb.residual) > 1e-9
    # The converged orbit (MODEL.md §6: T = 9.702674 ms) has its flags and no reason.
    ok = ts.periodic_orbit(SEED, root)
    assert int(ok.status) == 0 and str(ok.reason.values) == "" and not bool(ok.stable)
    assert float(ok.period) == pytest.approx(9.702674e-3, rel=1e-6)


def test_batched_orbits_carry_reasons_too():
    df = ts.describing_function(SEED)
    root = df.where(df.physical == 1, drop=True).isel(root=0)
    r = np.array([[float(root[k]) for k in ("omega", "A0", "A1", "A2", "theta")]] * 2)
    out = _core.periodic_orbits(SEED.values(), "bilateral", "constant", ["mu"], np.array([[0.215], [0.215]]), roots=r,
                                max_iter=0, threads=1)  # fmt: skip
    assert [ts.STATUS_NAMES[s] for s in out["status"]] == ["newton_not_converged"] * 2
    assert all("max_iter = 0" in s for s in out["reason"])
    assert np.all(np.isnan(out["period"])) and not np.any(out["stable"])


@pytest.mark.parametrize("threads", [0, 1025, 2**62])
def test_threads_out_of_range_is_a_value_error_not_a_panic(threads):
    with pytest.raises(ValueError, match="threads"):
        ts.ensemble(SEED, 0.01, {"mu": [0.2]}, threads=threads)
    # The private core refuses it too (it used to panic), naming the argument and the range.
    with pytest.raises(ValueError, match=rf"threads = {threads} is out of range: must be an integer in \[1, 1024\]"):
        _core.ensemble(SEED.values(), "bilateral", "constant", ["mu"], np.array([[0.2]]), np.zeros((1, 6)), 0.01,
                       "dopri5", 1e-8, threads=threads)  # fmt: skip
    with pytest.raises(ValueError, match="threads"):
        _core.describing_function(SEED.values(), "bilateral", "constant", ["mu"], np.array([[0.2]]), threads=threads)


def test_a_failed_sweep_point_says_why():
    # Two transients from 300 um on the bilateral law: with the default 1 mm escape limit the blow-up
    # is located (regime diverged, a recognised end); with the limit lifted the step size
    # collapses onto the singularity at 2.93 ms (status step_too_small, regime failed), and the
    # point's reason carries the integrator's.
    ds = ts.sweep(SEED, extra_axes={"escape_limit": [1e-3, 1e100]}, strategy="transient", disturbance=300e-6,
                  census=False, boundaries=False, progress=False, threads=1, t_max=1.0)  # fmt: skip
    status = ds.status.values.ravel()
    reason = ds.reason.values.ravel().astype(str)
    regime = ds.regime.values.ravel()
    assert [ts.STATUS_NAMES[s] for s in status] == ["success", "step_too_small"]
    assert ts.REGIME_NAMES[regime[1]] == "failed"
    assert "step size underflow" in reason[1] and "below the floor" in reason[1], reason[1]
    assert 2.90e-3 < number_after("t =", reason[1]) < 2.95e-3
    assert all(r != "" for s, r in zip(status, reason) if s != 0)
