"""A sweep checks every cycle its transients stop on by shooting (``stages.check_cycles``).

A transient stops once its section state repeats to ``periodic_tol``. Near a slowly attracting
cycle it is then still ``residual / (1 - |mu|)`` from the cycle; near an unstable cycle (a laminar
phase, or a start close to a saddle) it repeats too, on a cycle that is no steady state.

- Accuracy: on a slowly attracting bouncing cycle, the sweep's amplitude agrees with a cycle that
  Newton converges on the independent scipy implementation (``tribosweep.bench.reference``) to
  1e-6, where the transient's own stop is 1e-4 or more off.
- Failure detected: transients started near the bilateral seed's saddle cycle stop on it; the
  check finds it unstable and the run goes on to the state it really reaches.
- A shooting failure leaves the transient's cycle, flagged and explained.
- A run that reaches ``t_max`` on a slow approach (its newest section nearly repeating) is shot
  from there: the stable cycle it approaches is its outcome, at the rate its slowest multiplier
  gives; intermittent motion stays irregular.
"""

import numpy as np
import pytest

import tribosweep as ts
from conftest import SLOW_POINT, slow_approach_start, slow_law
from tribosweep import _census, _core, _cycles
from tribosweep._codes import OUTCOME_NAMES, REGIME
from tribosweep._settings import Steady, SweepSettings
from tribosweep._sweep import stages
from tribosweep.bench import reference as ref

#: The unilateral seed at 20 N and 5 cm: linearly unstable, a bouncing cycle whose slowest
#: multiplier is about 0.98 (a transient stopped at periodic_tol 1e-5 was 5.8e-4 off in A1).
BOUNCING = dict(normal_load=[20.0], arm_length=[0.05])
UNILATERAL = ts.SliderModel(contact="unilateral")
STATE = ("z", "z_dot", "x", "x_dot", "phi", "phi_dot")


def _sweep(**kw):
    # The transients' stops at periodic_tol, which these tests check (a slow approach checked in the
    # run ends on its orbit: test_a_slow_approach_is_checked_inside_the_run_and_ends_there_on_its_cycle).
    kw.setdefault("approach_periods", 0)
    return ts.sweep(model=UNILATERAL, census=False, t_max=20.0, threads=2, progress=False, **BOUNCING, **kw)


def _first(ds, name):
    return ds[name].values.ravel()[0]


def _scipy_cycle(params: dict, y0: np.ndarray, period: float) -> tuple[float, float]:
    """The cycle through ``y0`` of the scipy model, by Newton on ``(z, x, xd, phi, phid, T)`` with ``zd(0) = 0``.

    Returns its ``omega`` and the first-harmonic amplitude of ``z`` (4,096 samples a period).
    """
    free = [0, 2, 3, 4, 5]
    scale = np.array([1e-5, 1e-3, 1e-5, 1e-3, 1e-4, 1e-1])  # m, m/s, m, m/s, rad, rad/s

    def state(u):
        y = np.zeros(6)
        y[free] = u[:5]
        return y

    def residual(u):
        y = state(u)
        return ref.solve_unilateral(params, y, u[5], rtol=1e-12).y_end - y

    u = np.r_[np.asarray(y0)[free], period]
    for _ in range(10):
        f = residual(u)
        if np.max(np.abs(f) / scale) < 1e-11:
            break
        jac = np.empty((6, 6))
        for j in range(6):
            du = u.copy()
            du[j] += 1e-7 * (scale[free[j]] if j < 5 else u[5])
            jac[:, j] = (residual(du) - f) / (du[j] - u[j])
        u = u - np.linalg.solve(jac, f)
    else:
        raise AssertionError("the scipy Newton did not converge")
    n = 4096
    z = ref.solve_unilateral(params, state(u), u[5], rtol=1e-12, t_eval=np.arange(n) * u[5] / n).y[0]
    return 2 * np.pi / u[5], 2 / n * abs(np.sum(z * np.exp(-2j * np.pi * np.arange(n) / n)))


@pytest.fixture(scope="module")
def bouncing():
    ds = _sweep()
    point = ts.apparatus_model(20.0, 0.05, UNILATERAL.sliding_speed, base=UNILATERAL)
    omega = float(_first(ds, "cycle_omega"))
    # Newton's start: a state near the cycle, from a run of the core's (any such start converges
    # to the scipy model's own cycle), on the section zd = 0 where z is largest.
    t = 5.0 + np.linspace(0.0, 2.0, 4001) * 2 * np.pi / omega
    run = ts.simulate(point, float(t[-1]), y0=[1e-5, 0, 0, 0, 0, 0], t_eval=t)
    k = int(np.flatnonzero((run.z_dot.values[:-1] > 0) & (run.z_dot.values[1:] <= 0))[0])
    y0 = np.array([run[v].values[k] for v in STATE])
    return ds, _scipy_cycle(point.values(), y0, 2 * np.pi / omega)


def test_a_checked_cycle_agrees_with_an_independent_scipy_cycle(bouncing):
    ds, (omega_ref, a1_ref) = bouncing
    assert ts.labels(ds.regime).values.ravel()[0] == "contact_loss"
    assert ts.labels(ds.cycle_verified).values.ravel()[0] == "verified"
    assert abs(float(_first(ds, "cycle_period_ratio")) - 1) < 0.05  # the cycle of one period, as the reference's
    # Measured: 1.1e-8 in A1 and 2.3e-9 in omega (the transients at rtol 1e-8, shooting at 1e-9).
    assert float(_first(ds, "z1_amplitude")) / a1_ref - 1 == pytest.approx(0, abs=1e-6)
    assert float(_first(ds, "cycle_omega")) / omega_ref - 1 == pytest.approx(0, abs=1e-7)


def test_the_transients_find_at_their_tolerance_and_the_check_measures_at_rtols(bouncing, monkeypatch):
    # The transient runs at transient_rtol (1e-6 by default); the check (shooting) and the run on
    # the converged orbit that measures the cycle at ten times tighter than rtol: the measured
    # cycle does not follow the transients' tolerance.
    ds, (omega_ref, a1_ref) = bouncing
    seen = []
    real_ens, real_orb = _core.ensemble, _core.periodic_orbits

    def ens(*args, **kw):
        seen.append((kw.get("kind"), args[8]))
        return real_ens(*args, **kw)

    def orb(*args, **kw):
        seen.append(("shooting", kw["rtol"]))
        return real_orb(*args, **kw)

    monkeypatch.setattr(_core, "ensemble", ens)
    monkeypatch.setattr(_core, "periodic_orbits", orb)
    tight = _sweep(transient_rtol=1e-8)
    assert seen == [("steady", 1e-8), ("shooting", 1e-9), ("steady", 1e-9)]
    seen.clear()
    loose = _sweep(rtol=1e-7)
    assert seen == [("steady", 1e-6), ("shooting", 1e-8), ("steady", 1e-8)]
    assert tight.attrs["solver_transient_rtol"] == 1e-8 and loose.attrs["solver_transient_rtol"] == 1e-6
    # Both stops are shot to the same orbit: the amplitude moves by the shooting's own tolerances
    # (Newton 1e-8, integration 1e-9), not by the transients' 1e-6 against 1e-8.
    for d in (ds, tight):
        assert ts.labels(d.cycle_verified).values.ravel()[0] == "verified"
    assert float(_first(ds, "z1_amplitude")) / float(_first(tight, "z1_amplitude")) - 1 == pytest.approx(0, abs=1e-7)
    assert float(_first(tight, "z1_amplitude")) / a1_ref - 1 == pytest.approx(0, abs=1e-6)


def test_without_the_check_the_transients_stop_is_measurably_off(bouncing, monkeypatch):
    # What the check is for: the transient's own cycle, where it stopped (5.8e-4 off here; about
    # periodic_tol / (1 - |mu|) with |mu| about 0.98).
    _, (_, a1_ref) = bouncing
    monkeypatch.setattr(stages, "check_cycles", lambda p, sel, s: (_cycles.rows(s), np.ones(len(sel), bool)))
    raw = _sweep()
    assert ts.labels(raw.regime).values.ravel()[0] == "contact_loss"
    assert abs(float(_first(raw, "z1_amplitude")) / a1_ref - 1) > 1e-4


def _seed_points(t_max: float) -> stages.Points:
    values = ts.SliderModel(contact="bilateral").values()
    load = values.pop("normal_load")
    return stages.Points(values, "bilateral", "constant", {"normal_load": np.array([load])},
                         SweepSettings(steady=Steady(t_max=t_max)), 1)  # fmt: skip


@pytest.fixture(scope="module")
def saddle():
    """The bilateral seed's saddle cycle (unstable, largest multiplier 1.0076, docs/model.md §6)."""
    m = ts.SliderModel(contact="bilateral")
    df = ts.describing_function(m)
    orb = ts.periodic_orbit(m, df.isel(root=int(np.argmax(df.physical.values))))
    assert not bool(orb.stable)
    return np.asarray(orb.state0.values)


@pytest.mark.parametrize("factor, fate", [(1 - 1e-4, "decayed"), (1 - 1e-3, "decayed"), (1 + 1e-4, "diverged")])
def test_a_stop_near_an_unstable_cycle_goes_on_to_the_real_steady_state(saddle, factor, fate):
    # Started 1e-4 or 1e-3 inside (outside) the saddle, the transient repeats within periodic_tol
    # at once: the saddle's departure is 0.76 % a period. Inside, the motion decays to stable
    # sliding (slowly: t_max 100 s); outside it grows until it leaves the model. Offsets far above
    # the last bits: the fates do not depend on the machine.
    p = _seed_points(100.0)
    sel = np.array([0])
    first = stages.run_steady(p, sel, (saddle * factor)[None, :])
    assert OUTCOME_NAMES[int(first["outcome"][0])] == "periodic" and float(first["t_end"][0]) < 0.2
    s, verified = stages.check_cycles(p, sel, first)
    assert OUTCOME_NAMES[int(s["outcome"][0])] == fate and not verified[0]
    assert "stopped near an unstable cycle (largest multiplier 1.01) and went on" in s["reason"][0]
    assert float(s["t_end"][0]) > 5.0  # it went on from where it stopped
    assert int(s["n_rhs"][0]) > int(first["n_rhs"][0])
    regime, *_ = stages.classify(s, np.array([True]), 100.0)
    assert regime[0] == (REGIME["steady_sliding"] if fate == "decayed" else REGIME["diverged"])


def _fail(out):
    out["status"] = np.full_like(np.asarray(out["status"]), ts.STATUS_NAMES.index("not_converged"))
    out["reason"] = ["Newton did not converge (injected)"] * len(out["reason"])


def _elsewhere(out):
    out["A1"] = np.asarray(out["A1"]) * 1.06  # another orbit: 6 % larger


@pytest.mark.parametrize("inject, says", [
    (_fail, "not verified: shooting from it failed (Newton did not converge (injected))"),
    (_elsewhere, "not verified: shooting from it converged to another orbit (period"),
])  # fmt: skip
def test_a_failed_check_keeps_the_transients_cycle_flagged_and_explained(monkeypatch, bouncing, inject, says):
    real = _core.periodic_orbits

    def injected(*args, **kwargs):
        out = real(*args, **kwargs)
        inject(out)
        return out

    monkeypatch.setattr(_core, "periodic_orbits", injected)
    ds = _sweep()
    assert ts.labels(ds.regime).values.ravel()[0] == "contact_loss"
    assert ts.labels(ds.cycle_verified).values.ravel()[0] == "not_verified"
    assert says in str(_first(ds, "reason"))
    # The transient's own cycle, as without the check: within its 5.8e-4 of the scipy cycle.
    _, (_, a1_ref) = bouncing
    assert abs(float(_first(ds, "z1_amplitude")) / a1_ref - 1) < 2e-3


def test_points_that_end_on_no_cycle_are_not_checked():
    ds = ts.sweep(model=UNILATERAL, census=False, t_max=20.0, threads=2, progress=False,
                  normal_load=[84.46], arm_length=[0.065])  # fmt: skip
    assert ts.labels(ds.regime).values.ravel()[0] == "steady_sliding"
    assert ts.labels(ds.cycle_verified).values.ravel()[0] == "no_transient_cycle"


def test_checked_cycles_do_not_depend_on_the_chunking_or_the_threads():
    # Stribeck points with cycles of 1-6 periods (one of them grazing the disk at 150 N, 7.6 cm,
    # 0.2 m/s): whatever else shares a call, each point's check and measurement are its own.
    model = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3)
    axes = dict(normal_load=[134.44444444444446, 150.0], arm_length=[0.07566666666666667, 0.10133333333333334],
                sliding_speed=[0.2, 0.4])  # fmt: skip
    runs = [ts.sweep(model=model, census=False, t_max=20.0, threads=t, progress=False, chunk_size=c, **axes)
            for t, c in ((2, None), (1, 1), (2, 3))]  # fmt: skip
    assert (runs[0].cycle_verified.values == 1).sum() >= 2
    for other in runs[1:]:
        for name in runs[0].data_vars:
            if name != "wall_time":
                np.testing.assert_array_equal(other[name].values, runs[0][name].values, err_msg=name)


def test_the_census_does_not_count_stops_near_an_unstable_orbit_as_a_cycle():
    # At 120 N, 9 cm, 0.3 m/s about 18 % of the census's disturbances stop "periodic": their
    # section states repeat to periodic_tol near a period orbit (A1 2.39 um, 21.7 ms). Shooting
    # from such a stop converges to it with a largest multiplier 1.0867, and a direct simulation
    # started 1e-9 off it confirms it: the deviation grows by that factor a period. The census
    # sends those samples on; none ends on a cycle.
    m = ts.apparatus_model(120.0, 0.09, 0.3)
    c = ts.census(m, samples=64)
    vals = m.values()
    raw = _core.ensemble(vals, m.contact, m.friction_law, ["normal_load"], np.full((64, 1), vals["normal_load"]),
                         np.ascontiguousarray(c.y0.values), 30.0, "dop853", 1e-6, kind="steady", periodic_tol=1e-5,
                         watch_x=False, irregular_block=256)  # fmt: skip
    stops = np.flatnonzero(np.asarray(raw["outcome"]) == OUTCOME_NAMES.index("periodic"))
    # Each disturbance stops there with odds of about 0.18: none of 64 would have odds of 3e-6.
    assert stops.size >= 1
    j = int(stops[0])
    orb = _core.periodic_orbit(vals, m.contact, m.friction_law, y0=np.asarray(raw["y_end"][j]),
                               period=float(raw["period"][j]), rtol=1e-11, tol=1e-10)  # fmt: skip
    assert orb["status"] == 0 and not orb["stable"]
    mu = float(np.max(orb["moduli"]))
    assert mu == pytest.approx(1.0867, abs=1e-3)
    period = float(orb["period"])
    t = np.arange(121) * period
    y0 = np.asarray(orb["state0"])
    a = ts.simulate(m, float(t[-1]), y0=y0, rtol=1e-12, t_eval=t)
    b = ts.simulate(m, float(t[-1]), y0=y0 * (1 + 1e-9), rtol=1e-12, t_eval=t)
    dev = np.max(np.abs(np.stack([(a[v].values - b[v].values) / s for v, s in (("z", 1e-5), ("phi", 1e-3))])), axis=0)
    growth = (dev[100] / dev[60]) ** (1 / 40)  # past the start's projection onto the other directions
    assert growth == pytest.approx(mu, abs=2e-3)
    assert float(c.basin_fraction.sel(attractor=1)) == 0.0 and int(c.n_cycles) == 0


def test_a_repeating_slow_decay_at_a_stable_point_is_sliding_not_a_cycle(monkeypatch):
    # At 11.5 N, 8.08 cm sliding is linearly stable and a transient from the disturbance decays so
    # slowly (near the Hopf load) that its sections repeat to periodic_tol at 0.17 um: it stopped
    # as a "cycle". Shooting from there ends on no orbit of that size (there is none near stable
    # sliding), so the sweep calls it sliding still decaying, as it does a slow irregular run.
    axes = dict(normal_load=[11.521739130434783], arm_length=[0.0808], census=False, progress=False)
    ds = ts.sweep(**axes)
    assert ts.labels(ds.regime).values.ravel()[0] == "steady_sliding"
    assert ts.labels(ds.decided_by).values.ravel()[0] == "linear"
    assert ts.STATUS_NAMES[int(_first(ds, "status"))] == "not_converged"
    assert "though its sections repeated to periodic_tol" in str(_first(ds, "reason"))
    assert float(_first(ds, "growth_rate")) < 0 and np.isnan(float(_first(ds, "z1_amplitude")))
    # Without the check (every stop taken as it was, as before it), a cycle.
    monkeypatch.setattr(stages, "check_cycles", lambda p, sel, s: (_cycles.rows(s), np.ones(len(sel), bool)))
    raw = ts.sweep(**axes)
    assert ts.labels(raw.regime).values.ravel()[0] in ("self_excited", "contact_loss")
    assert float(_first(raw, "z1_amplitude")) < 1e-6  # the 'cycle': a fraction of a micrometre


def test_census_samples_still_stopping_near_unstable_orbits_after_the_last_check_are_undecided(monkeypatch):
    # One round of checks, and a hold of 4 periods only: the 120 N samples that go on from the
    # unstable orbit stop near it again at once. They are not taken for a cycle: unsettled, i.e.
    # bounded motion (irregular).
    m = ts.apparatus_model(120.0, 0.09, 0.3)
    monkeypatch.setattr(_cycles, "CHECK_ROUNDS", 1)
    monkeypatch.setattr(_cycles, "LEAVE_GROWTH", 1.0)
    one = ts.census(m, samples=64)
    assert float(one.basin_fraction.sel(attractor=1)) == 0.0 and int(one.n_cycles) == 0
    assert float(one.basin_fraction.sel(attractor=2)) > 0.05


def test_ensemble_checks_its_cycles_when_asked(bouncing):
    # The public ensemble, steady=True, check_cycles=True: each start's stop converged and measured
    # on the orbit, within 1e-6 of the scipy cycle whatever the start (1.1e-8 measured).
    _, (omega_ref, a1_ref) = bouncing
    m = ts.apparatus_model(20.0, 0.05, UNILATERAL.sliding_speed, base=UNILATERAL)
    starts = [[1e-5, 0, 0, 0, 0, 0], [2e-5, 0, 0, 0, 0, 0]]
    ds = ts.ensemble(m, 20.0, {"normal_load": [20.0, 20.0]}, y0=starts, steady=True, check_cycles=True)
    assert list(ts.labels(ds.cycle_verified).values) == ["verified", "verified"]
    np.testing.assert_allclose(ds.z1_amplitude.values, a1_ref, rtol=1e-6)
    np.testing.assert_allclose(ds.omega.values, omega_ref, rtol=1e-7)
    with pytest.raises(ValueError, match="check_cycles = True needs steady=True"):
        ts.ensemble(m, 0.1, {"normal_load": [20.0]}, check_cycles=True)


def test_a_stop_is_within_periodic_tol_over_the_multiplier_gap_of_its_orbit():
    # The bound of tribosweep.bench.cycle_check: consecutive sections differ by (1 - |mu|) of the
    # distance to the cycle, so a stop at periodic_tol is up to about periodic_tol / (1 - |mu|) off
    # (on the full Stribeck sweep the largest error, 7.1e-3, sits at 0.97 of it). Here on 16 of its
    # points, both laws; A1s below a tenth of the motion are left out (quadrature-limited).
    from tribosweep.bench.cycle_check import slowest_multiplier, stops, summary

    np.testing.assert_array_equal(slowest_multiplier([[1.2, 1.0, 0.5], [0.999999, 0.7, 0.9]]), [1.2, 0.9])
    axes = dict(normal_load=[57.0, 134.44444444444446], arm_length=[0.07566666666666667, 0.10133333333333334],
                sliding_speed=[0.2, 0.4])  # fmt: skip
    for law in ("switch", "coulomb"):
        d = stops(law, **axes)
        s = summary(d, 1e-5)
        assert s["n"] >= 3 and s["within_3x"] == 1.0, (law, s)


#: The slow point's law and axes (tests/conftest.py): its transients settle after some seconds of
#: chaotic motion, at a time that moves with the last bits (22-25 s from the default start at -2..+2
#: ulps of the inputs; the sweep's, 21.5 s at 0 ulps).
SLOW_LAW = slow_law()
SLOW = SLOW_POINT


def test_a_run_unsettled_at_t_max_on_a_slow_approach_ends_on_the_stable_cycle_shooting_finds(monkeypatch):
    m, y0, done = slow_approach_start()

    def run(t_end, y0=None, check=True):
        return ts.ensemble(m, t_end, {"normal_load": [10.0]}, y0=y0, steady=True, check_cycles=check)

    assert ts.labels(done.outcome).values[0] == "periodic"
    assert np.isnan(done.nearest_residual.values[0]) and int(done.nearest_multiplicity[0]) == 0
    # From the start near the cycle: no chaotic phase, only the slow approach (it repeats at 15.4 s).
    assert 12.0 < float(run(60.0, y0, check=False).t_end[0]) < 20.0
    times = np.array([4.0, 6.0, 8.0, 10.0])
    runs = [run(t, y0, check=False) for t in times]
    for ds in runs:
        assert ts.labels(ds.outcome).values[0] == "unsettled"
        # Its closest repetition is the cycle's: after 2 sections, over the cycle's period.
        assert int(ds.nearest_multiplicity[0]) == 2
        np.testing.assert_allclose(ds.nearest_period.values, 2 * np.pi / done.omega.values, rtol=1e-4)
    r = np.array([float(ds.nearest_residual[0]) for ds in runs])
    assert 1e-5 < r[-1] < _cycles.NEAREST_TOL and r[-1] < 0.1 * r[0]
    # Analytic: a slow approach shrinks along the slowest Floquet mode, by |mu| = 0.9933 a period
    # (a least-squares line through the residuals at 4-10 s: 0.9937).
    per_period = np.exp(np.polyfit(times, np.log(r), 1)[0] * float(runs[-1].nearest_period[0]))
    checked = run(10.0, y0)
    reason = str(checked.reason.values[0])
    mu = float(reason.split("largest multiplier ")[1].rstrip(")"))
    assert abs(mu - 0.9933) < 5e-4, reason
    assert abs(per_period - mu) < 1e-3, (per_period, mu)
    # Shot from its newest section, it is the cycle a run to 60 s repeats on, verified and measured.
    assert ts.labels(checked.outcome).values[0] == "periodic" and "a slow approach" in reason
    assert ts.labels(checked.cycle_verified).values[0] == "verified"
    # To the runs' accuracy (rtol 1e-8: 1.0e-9 apart in omega, 6e-8 in A1, as measured).
    ref = run(60.0)
    np.testing.assert_allclose(checked.omega.values, ref.omega.values, rtol=1e-7)
    np.testing.assert_allclose(checked.z1_amplitude.values, ref.z1_amplitude.values, rtol=1e-5)
    # The half-range from 512 samples a period: its minimum falls between them, off by up to about
    # (pi / 512)^2 / 2 = 2e-5 (2.4e-5 apart here).
    np.testing.assert_allclose(checked.z_half_range.values, ref.z_half_range.values, rtol=1e-4)
    # Without the shooting it stays unsettled.
    monkeypatch.setattr(_cycles, "NEAREST_TOL", 0.0)
    assert ts.labels(run(10.0, y0).outcome).values[0] == "unsettled"


def test_the_sweep_reports_a_slow_approach_as_its_cycle(slow_transients):
    # The transient starts near the cycle (the slow_transients fixture) and has not repeated by
    # t_max = 10 s (at 15.4 s), but its newest section has.
    m, _, _ = slow_transients
    slow = ts.sweep(model=SLOW_LAW, census=False, t_max=10.0, threads=2, progress=False, approach_periods=0, **SLOW)
    assert ts.labels(slow.regime).values.ravel()[0] == "contact_loss"
    assert int(_first(slow, "cycle_verified")) == 1 and "a slow approach" in str(_first(slow, "reason"))
    assert np.isnan(_first(slow, "irregular_ftle"))
    # Its size: the cycle's own, as a run to 60 s measures it.
    on = ts.ensemble(m, 60.0, {"normal_load": [10.0]}, steady=True, check_cycles=True)
    assert float(_first(slow, "z_half_range")) == pytest.approx(float(on.z_half_range[0]), rel=1e-4)


def test_a_slow_approach_is_checked_inside_the_run_and_ends_there_on_its_cycle(slow_transients):
    """The run from near the slow point's cycle (x moved by 0.3 of its amplitude: only the slow
    approach, by 0.9933 a period) repeats to periodic_tol at 15.4 s. With the slow-approach test
    (blocks of 10 periods, the default) it is shot from, inside the run, once the largest residual
    has shrunk over three blocks to 1e-3: it ends at 8.8 s on the stable orbit, measured on it (the
    cycle a run to 60 s repeats on, to 1e-7 in omega and 1e-5 in A1), for 0.58x the right-hand
    sides (2026-11-28). Through the sweep: the same cycle, verified, before t_max = 10 s."""
    m, y0, done = slow_transients
    base, names, vals = m.values(), ["normal_load"], np.array([[10.0]])

    def run(approach):
        return _core.ensemble(base, "unilateral", "switch", names, vals, np.atleast_2d(y0), 60.0, "dop853", 1e-8,
                              threads=1, kind="steady", periodic_tol=1e-5, approach_periods=approach)  # fmt: skip

    strict, fast = run(0), run(Steady().approach_periods)
    assert Steady().approach_periods == 10
    assert not strict["approach"][0] and 12.0 < strict["t_end"][0] < 20.0
    assert fast["approach"][0] and fast["outcome"][0] == _cycles.PERIODIC and int(fast["multiplicity"][0]) == 2
    assert fast["t_end"][0] < 0.75 * strict["t_end"][0], (fast["t_end"], strict["t_end"])
    assert fast["n_rhs"][0] < 0.75 * strict["n_rhs"][0]
    np.testing.assert_allclose(fast["omega"], done.omega.values, rtol=1e-7)
    np.testing.assert_allclose(fast["z1_amplitude"], done.z1_amplitude.values, rtol=1e-5)
    sweep = ts.sweep(model=SLOW_LAW, census=False, t_max=10.0, threads=2, progress=False, **SLOW)
    assert ts.labels(sweep.regime).values.ravel()[0] == "contact_loss"
    assert int(_first(sweep, "cycle_verified")) == 1 and "a slow approach" not in str(_first(sweep, "reason"))
    np.testing.assert_allclose(float(_first(sweep, "cycle_omega")), float(done.omega[0]), rtol=1e-7)
    with pytest.raises(ValueError, match=r"approach_periods = -1 is out of range: must be an integer in \[0, 10000\]"):
        ts.sweep(model=SLOW_LAW, census=False, progress=False, approach_periods=-1, **SLOW)


def test_intermittent_motion_at_t_max_stays_irregular():
    # At 25.6 N, 0.4 m/s the motion is intermittent: laminar phases near a period-2 cycle, bursts
    # every 4 s (unsettled at 200 s). At t_max it may be in a laminar phase, repeating to 1.6e-3;
    # shooting from there finds no stable cycle (Newton does not converge), so it stays irregular.
    burst = ts.sweep(model=SLOW_LAW, census=False, t_max=20.0, threads=2, progress=False, normal_load=[25.555555555555557],
                     arm_length=SLOW["arm_length"], sliding_speed=[0.4])  # fmt: skip
    assert ts.labels(burst.regime).values.ravel()[0] == "irregular"
    assert "a slow approach" not in str(_first(burst, "reason"))


def test_the_census_counts_a_sample_on_a_slow_approach_with_the_cycle_it_approaches(monkeypatch):
    # Two samples of the slow point's census, started as above: one unsettled at t_max = 10 s,
    # one run on until it repeats. The first is shot from its newest section and joins the second's
    # cycle (one cluster) instead of counting as irregular motion.
    m, y0, done = slow_approach_start()
    base, names, vals = m.values(), ["normal_load"], np.array([[10.0]])

    def steady(rows, starts, known, restart=None, t_max=10.0):
        return _core.ensemble(base, "unilateral", "switch", names, vals[rows], np.atleast_2d(starts), t_max, "dop853",
                              1e-6, threads=1, kind="steady", periodic_tol=1e-5, n_fourier=512, irregular_block=256,
                              restart=restart)  # fmt: skip

    def shoot(rows, y, p, z1, size):
        return _cycles.shoot(base, "unilateral", "switch", names, vals[rows], y, p, z1, size, rtol=1e-9, tol=1e-8,
                             threads=1)  # fmt: skip

    def census_check():
        runs = [_cycles.rows(steady([0], y0, None, t_max=t)) for t in (10.0, 60.0)]
        res = {k: np.stack([r[k] for r in runs], axis=1) for k in runs[0]}
        check = _cycles.CensusCheck(res, _census.CYCLE_TOL, steady, lambda: None, 10.0, 1e-9, 1e-8)
        check.settle(shoot)
        return res, check

    res, check = census_check()
    assert list(res["outcome"][0]) == [_cycles.PERIODIC, _cycles.PERIODIC]
    assert "a slow approach" in res["reason"][0, 0] and res["reason"][0, 1] == ""
    assert check.orbit[(0, 0)][0] and check.orbit[(0, 1)][0]  # both stable, verified
    label, _ = _cycles.cluster_of(res, 0, np.arange(2), _census.CYCLE_TOL)
    assert list(label) == [0, 0] and list(res["multiplicity"][0]) == [2, 2]
    np.testing.assert_allclose(res["omega"][0, 0], done.omega.values[0], rtol=1e-6)
    # Without it, the first sample stays unsettled: the census's irregular attractor.
    monkeypatch.setattr(_cycles, "NEAREST_TOL", 0.0)
    res, _ = census_check()
    assert list(res["outcome"][0]) == [_cycles.UNSETTLED, _cycles.PERIODIC]


def test_cycles_are_told_apart_by_three_harmonics_in_units_of_the_motion():
    tol = _census.CYCLE_TOL
    # Default grid, 52.9 N, 5.8 cm: two period-2 cycles with the same A1 and frequencies 0.2 %
    # apart, and A2 four times apart (stops of each, as the census measured them).
    omega = np.array([707.016631, 705.575347, 707.007009, 705.573791])
    amps = np.array([[1.41260e-05, 4.06756e-06, 4.11515e-07], [1.41135e-05, 1.52727e-05, 6.07993e-07],
                     [1.41265e-05, 4.06608e-06, 4.12261e-07], [1.41134e-05, 1.52730e-05, 6.07925e-07]])  # fmt: skip
    label, heads = _cycles.cluster(omega, [2, 2, 2, 2], amps, np.full(4, np.nan), tol)
    assert list(label) == [0, 1, 0, 1] and heads == [0, 1]
    # A period-4 cycle at 168.33 rad/s whose first three harmonics (4e-8 m) are a small part of
    # its motion (half z's range, 9.9e-6 m): its stops spread by 1.1 % of them, and are one cycle
    # in units of the motion; in units of those harmonics they were two.
    omega = np.array([168.329539, 168.330981])
    amps = np.array([[4.16929e-08, 4.38001e-08, 4.51089e-08], [4.14910e-08, 4.33313e-08, 4.48290e-08]])
    assert list(_cycles.cluster(omega, [4, 4], amps, np.full(2, 9.91e-6), tol)[0]) == [0, 0]
    assert list(_cycles.cluster(omega, [4, 4], amps, np.full(2, np.nan), tol)[0]) == [0, 1]
    # Another multiplicity, or a frequency 2 % off, is another cycle.
    assert list(_cycles.cluster(omega, [4, 2], amps, np.full(2, 9.91e-6), tol)[0]) == [0, 1]
    assert list(_cycles.cluster(omega * [1, 1.02], [4, 4], amps, np.full(2, 9.91e-6), tol)[0]) == [0, 1]


def test_cluster_labels_are_those_of_same_cycle():
    # cluster tests pairs on Python floats for speed; same_cycle is the rule on arrays (the
    # transients' cycles are matched with it). Both must give the same labels, also at the
    # tolerance's edges: samples whose frequency and harmonics differ from the first sample's by
    # exactly its bounds (to the last bit), by half or 1.5 of them, with mixed multiplicities and
    # NaN sizes.
    tol = _census.CYCLE_TOL

    def reference(omega, mult, amps, size):
        size = np.where(np.isfinite(size), size, np.max(amps, axis=1, initial=0.0))
        label, heads = [], []
        for s in range(omega.size):
            for c, h in enumerate(heads):
                if mult[s] == mult[h] and _cycles.same_cycle(omega[s], amps[s], omega[h], amps[h], size[h], tol):
                    label.append(c)
                    break
            else:
                label.append(len(heads))
                heads.append(s)
        return label, heads

    def round_bound(x, bound, refs):
        """``x`` moved by a few ulps until ``bound(x)`` is so round (trailing zero bits) that each of
        ``refs(x)`` plus 0.5, 1 or 1.5 of it is exact: differences then sit on the bound to the bit."""
        for _ in range(100_000):
            b = bound(x)
            if all((r + f * b) - r == f * b for r in refs(x) for f in (0.5, 1.0, 1.5, -0.5, -1.0, -1.5)):
                return x
            x = np.nextafter(x, np.inf)
        raise AssertionError("no round bound found")

    rng = np.random.default_rng(7)
    splits = exact = 0
    for _ in range(200):
        n = int(rng.integers(2, 17))
        # Inside one binary exponent's range with their bounds (560-1000 rad/s, 1.1-1.4e-5 m), so
        # that the differences can be exact at all.
        om0 = round_bound(560.0 + 440.0 * rng.random(), lambda w: tol * w, lambda w: [w])
        a0 = 1.1e-5 + 0.3e-5 * rng.random(3)
        size0 = round_bound(1e-5 * (1 + 0.1 * rng.random()), lambda z: tol * max(z, 1e-12), lambda z, a=a0: a)
        omega, amps = np.full(n, om0), np.tile(a0, (n, 1))
        size = np.where(rng.random(n) < 0.3, np.nan, 1e-5 * (1 + 0.1 * rng.random(n)))
        size[0] = size0
        mult = rng.choice([1, 1, 1, 2], n)
        for s in range(1, n):  # the first sample's bounds, exactly at, inside or outside them
            omega[s] = om0 + rng.choice([-1.0, 1.0]) * rng.choice([0.0, 0.5, 1.0, 1.0, 1.5]) * (tol * om0)
            amps[s] = a0 + rng.choice([-1.0, 1.0], 3) * rng.choice([0.0, 0.5, 1.0, 1.0, 1.5], 3) * (tol * size0)
            exact += abs(omega[s] - om0) == tol * om0
        label, heads = _cycles.cluster(omega, mult, amps, size, tol)
        want = reference(omega, mult, amps, size)
        assert (label.tolist(), heads) == want, (omega, mult, amps, size)
        splits += len(heads) > 1
    # The draws split into several cycles, and many differences sit exactly on a bound.
    assert splits > 50 and exact > 300, (splits, exact)


def test_census_rows_of_arrays_without_columns():
    # Without stationarity blocks (irregular_block=0) the census's cell arrays have no columns; a
    # sample going on from an unstable cycle reads every per-sample array as one row per sample
    # (it raised "cannot reshape array of size 0").
    res = {"irregular_cells": np.zeros((2, 3, 0), dtype=np.uint64), "t_end": np.arange(6.0).reshape(2, 3)}
    check = _cycles.CensusCheck(res, _census.CYCLE_TOL, None, lambda: None, 1.0, 1e-9, 1e-8)
    assert check.flat("irregular_cells").shape == (6, 0)
    check.flat("t_end")[4] = -1.0
    assert res["t_end"][1, 1] == -1.0


def test_a_check_near_a_weakly_unstable_cycle_converges_and_finds_it_unstable(monkeypatch):
    # A census sample's stop on the 2,000-point grid (unilateral seed at 10 N, 0.46 m/s; its
    # state and period as the census recorded them): Newton needs 11 iterations to the unstable
    # orbit it is near (largest multiplier 1.021), more than the 8 the check allowed until
    # 2026-11-27, which left the sample counted as an unverified cycle.
    names = ["normal_load", "omega_friction", "omega_normal", "omega_torsion", "sliding_speed"]
    values = np.array([[10.0, 256.2792306396808, 297.8639429981659, 565.5657484215244, 0.46]])
    y = np.array([[2.1640345695254352e-06, -1.1881771608268643e-15, 4.1290719292967672e-07, 1.1320509809288176e-05,
                   -2.5268663151866962e-04, 5.6005733275590927e-02]])  # fmt: skip
    period, nan = np.array([0.0106404432481817]), np.full(1, np.nan)

    def check():
        return _cycles.shoot(UNILATERAL.values(), "unilateral", "constant", names, values, y, period, nan, nan,
                             rtol=1e-7, tol=1e-8, threads=1)  # fmt: skip

    orb = check()
    assert bool(orb["unstable"][0]) and not bool(orb["stable"][0])
    assert _cycles.slowest_multiplier(orb["moduli"])[0] == pytest.approx(1.0208, abs=5e-4)
    assert 9 <= int(orb["newton_iterations"][0]) <= _cycles.CHECK_MAX_ITER
    monkeypatch.setattr(_cycles, "CHECK_MAX_ITER", 8)
    assert "Newton did not converge after 8" in check()["note"][0]


def test_a_census_first_stop_is_its_stable_orbit_or_goes_on_from_there():
    """``CensusCheck.resolve``'s bookkeeping on three first stops, with the core replaced by records.

    Shooting finds a stable orbit of the first stop's period (the sample becomes that orbit, measured
    by a run started on it, verified), an unstable one from the second (it goes on with the hold of
    a sample leaving an unstable cycle: ``ceil(ln 1e3 / ln 1.5) = 18`` periods of 0.02 s, and says
    so) and fails from the third (it goes on from its stop, no hold, nothing said). The two that go
    on do so in one call, each with the time it has left.
    """
    periodic, decayed = OUTCOME_NAMES.index("periodic"), OUTCOME_NAMES.index("decayed")
    res = {"outcome": np.full((1, 3), periodic), "status": np.zeros((1, 3), dtype=np.int64),
           "y_end": np.arange(18.0).reshape(1, 3, 6), "period": np.full((1, 3), 0.01),
           "t_end": np.array([[1.0, 2.0, 3.0]]), "n_rhs": np.array([[10, 20, 30]]),
           "reason": np.full((1, 3), "", dtype=object), "omega": np.full((1, 3), 600.0)}  # fmt: skip
    state0 = np.full((3, 6), 7.0)
    calls = []

    def shoot(rows, y, p, z1, size):
        calls.append(("shoot", rows, y.copy(), p.copy(), z1, size))
        return {"status": np.array([0, 0, 1]), "stable": np.array([True, False, False]),
                "unstable": np.array([False, True, False]), "state0": state0, "n_rhs": np.array([1, 1, 1]),
                "moduli": np.array([[0.5] * 6, [1.5] + [0.5] * 5, [np.nan] * 6]),
                "period": np.array([0.01, 0.02, np.nan])}  # fmt: skip

    def steady(rows, y0, known, restart=None):
        calls.append(("steady", rows, y0.copy(), restart))
        n = len(rows)
        out = {"outcome": np.full(n, periodic if restart is None else decayed), "n_rhs": np.full(n, 5),
               "t_end": np.full(n, 0.5), "omega": np.full(n, 640.0), "reason": np.full(n, "", dtype=object),
               "status": np.zeros(n, dtype=np.int64), "y_end": np.zeros((n, 6)), "period": np.full(n, np.nan)}  # fmt: skip
        return out

    check = _cycles.CensusCheck(res, 1e-2, steady, lambda: None, 30.0, 1e-7, 1e-10)
    check.resolve(shoot, np.array([0, 1, 2]))
    kinds = [c[0] for c in calls]
    assert kinds == ["shoot", "steady", "steady"], kinds
    _, rows, y, p, z1, size = calls[0]
    np.testing.assert_array_equal(y, np.arange(18.0).reshape(3, 6))
    assert np.all(np.isnan(z1)) and np.all(np.isnan(size))  # held to the period alone
    # The stable orbit: measured on it, the sample's cycle, verified.
    _, rows, y0, restart = calls[1]
    assert restart is None and list(rows) == [0]
    np.testing.assert_array_equal(y0, state0[:1])
    assert res["omega"][0, 0] == 640.0 and res["outcome"][0, 0] == periodic
    np.testing.assert_array_equal(res["y_end"][0, 0], state0[0])
    assert check.orbit[(0, 0)][0] is True and res["n_rhs"][0, 0] == 10 + 1 + 5
    # The other two go on in one call from where they stopped, with the time they have left.
    _, rows, y0, restart = calls[2]
    np.testing.assert_array_equal(y0, np.arange(6.0, 18.0).reshape(2, 6))
    np.testing.assert_allclose(restart, [[28.0, 18 * 0.02], [27.0, 0.0]])
    assert "largest multiplier 1.5" in res["reason"][0, 1] and res["reason"][0, 2] == ""
    np.testing.assert_array_equal(res["outcome"][0, 1:], [decayed, decayed])
    np.testing.assert_allclose(res["t_end"][0, 1:], [2.5, 3.5])
    assert (0, 1) not in check.orbit and (0, 2) not in check.orbit
