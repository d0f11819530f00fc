"""Time-domain core against truth: scipy at tight tolerance, analytic limits, the bouncing cycle of docs/model.md §6."""

from __future__ import annotations

import numpy as np
import pytest

import tribosweep as ts
from tribosweep.bench import reference

METHODS = ["dopri5", "dop853", "rodas4"]


@pytest.fixture(scope="module")
def seed_scipy():
    """Seed trajectory (bilateral, z(0) = 1 um) from scipy DOP853 at rtol 1e-13."""
    t = np.linspace(0.0, 0.5, 1001)
    sol = reference.solve(reference.seed_parameters(), ts.DEFAULT_Y0, 0.5, t_eval=t, rtol=1e-13)
    return t, sol.y.T


@pytest.mark.parametrize("method", METHODS)
def test_seed_trajectory_matches_scipy(method, seed_scipy):
    t, y_ref = seed_scipy
    ds = ts.simulate(ts.SliderModel(contact="bilateral"), 0.5, method=method, rtol=1e-10, t_eval=t)
    assert int(ds.status) == ts.STATUS["success"]
    zmax = np.abs(y_ref[:, 0]).max()
    err = np.abs(ds.z.values - y_ref[:, 0]).max() / zmax
    assert err < 1e-7, f"{method}: max |z - z_scipy| / max|z| = {err:.2e}"
    # The other components too, each relative to its own range.
    for i, name in enumerate(["z_dot", "x", "x_dot", "phi", "phi_dot"], start=1):
        scale = np.abs(y_ref[:, i]).max()
        assert np.abs(ds[name].values - y_ref[:, i]).max() < 1e-6 * scale, name


def _damped(x0, v0, k, c, m, t):
    """Closed-form free response of m x'' + c x' + k x = 0 (underdamped)."""
    wn = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - zeta**2)
    a = x0
    b = (v0 + zeta * wn * x0) / wd
    return np.exp(-zeta * wn * t) * (a * np.cos(wd * t) + b * np.sin(wd * t))


@pytest.mark.parametrize("method", METHODS)
def test_decoupled_limit_is_three_damped_oscillators(method):
    # K_a = 0, mu = 0, K_phi = 0: each axis is an independent damped oscillator (the z one
    # stiffened by K_s and damped by C_zc).
    m = ts.SliderModel(contact_quadratic=0.0, mu=0.0, twist_coupling=0.0)
    y0 = np.array([2e-6, 1e-3, -1.5e-6, 4e-4, 3e-4, -0.2])
    t = np.linspace(0, 0.2, 401)
    ds = ts.simulate(m, 0.2, y0=y0, method=method, rtol=1e-12, t_eval=t)
    assert int(ds.status) == 0
    z_st, k_s = m.static_point()
    assert k_s == m.contact_stiffness
    z = _damped(y0[0], y0[1], m.mass * m.omega_normal**2 + k_s,
                2 * m.zeta_normal * m.mass * m.omega_normal + m.contact_damping, m.mass, t)
    x = _damped(y0[2], y0[3], m.omega_friction**2, 2 * m.zeta_friction * m.omega_friction, 1.0, t)
    phi = _damped(y0[4], y0[5], m.omega_torsion**2, 2 * m.zeta_torsion * m.omega_torsion, 1.0, t)
    for name, exact in [("z", z), ("x", x), ("phi", phi)]:
        err = np.abs(ds[name].values - exact).max() / np.abs(exact).max()
        assert err < 1e-9, f"{method} {name}: {err:.2e}"


def test_threads_give_identical_results():
    rng = np.random.default_rng(1)
    n = 64
    params = {"mu": rng.uniform(0.15, 0.3, n), "normal_load": rng.uniform(17, 152, n)}
    a = ts.ensemble(ts.SliderModel(contact="bilateral"), 0.05, params, rtol=1e-7, threads=1)
    b = ts.ensemble(ts.SliderModel(contact="bilateral"), 0.05, params, rtol=1e-7, threads=2)
    c = ts.ensemble(ts.SliderModel(contact="bilateral"), 0.05, params, rtol=1e-7, threads=5)
    for v in ["z_end", "phi_dot_end", "n_rhs", "min_normal_force"]:
        assert np.array_equal(a[v].values, b[v].values), v
        assert np.array_equal(a[v].values, c[v].values), v
    assert np.all(a.status.values == 0)


def test_simulate_and_ensemble_default_to_the_sweeps_integrator(seed_scipy):
    # DOP853, as sweeps (Integration.integrator): at the default rtol its end state is within
    # 1e-6 of scipy's DOP853 at 1e-13 (relative to max |z|), and an explicit method= gives the same bits.
    from tribosweep._settings import DEFAULTS

    assert DEFAULTS.integration.integrator == "dop853"
    t, y_ref = seed_scipy
    m = ts.SliderModel(contact="bilateral")
    ds = ts.simulate(m, 0.5)
    assert ds.attrs["method"] == "dop853"
    assert abs(float(ds.z.values[-1]) - y_ref[-1, 0]) < 1e-6 * np.abs(y_ref[:, 0]).max()
    explicit = ts.simulate(m, 0.5, method="dop853")
    assert np.array_equal(ds.z.values, explicit.z.values)
    ens = ts.ensemble(m, 0.05, {"mu": [0.2, 0.25]})
    assert ens.attrs["method"] == "dop853"


def test_ensemble_matches_single_runs():
    # The ensemble runs on the lane-batched path, a single run on the scalar driver: the same method,
    # tolerances and step sequence, so they agree far inside the integration tolerance (the two differ
    # by rounding per step, not bitwise).
    params = {"mu": [0.2, 0.3], "normal_load": [30.0, 120.0]}
    t = np.linspace(0, 0.02, 5)
    for contact in ["bilateral", "unilateral"]:
        ens = ts.ensemble(ts.SliderModel(contact=contact), 0.02, params, t_eval=t, rtol=1e-9)
        for i in range(2):
            one = ts.simulate(ts.SliderModel(contact=contact, mu=params["mu"][i], normal_load=params["normal_load"][i]),
                              0.02, t_eval=t, rtol=1e-9)
            scale = np.abs(one.z.values).max()
            np.testing.assert_allclose(ens.z.values[i], one.z.values, rtol=0, atol=1e-3 * 1e-9 * scale)
            assert int(ens.n_accept.values[i]) == int(one.n_accept.values)


def test_ensemble_samples_of_runs_that_escape_end_in_nan():
    # The ensemble writes its samples straight into the returned array; a run that escapes has the
    # samples up to its end and NaN after it, as a single run's. Past the bilateral law's saddle
    # (300 um at rest) z escapes at about 2.04 ms; 30 um stays bounded.
    t = np.linspace(0, 4e-3, 41)
    y0 = np.array([[300e-6, 0, 0, 0, 0, 0], [30e-6, 0, 0, 0, 0, 0]])
    for method in ["dopri5", "dop853"]:
        m = ts.SliderModel(contact="bilateral")
        ens = ts.ensemble(m, 4e-3, {"mu": [0.3, 0.3]}, y0=y0, t_eval=t, method=method, rtol=1e-9)
        t_esc = float(ens.t_reached.values[0])
        assert 2.0e-3 < t_esc < 2.1e-3 and ens.status.values[0] == ts.STATUS["diverged"]
        assert np.isnan(ens.z.values[0, t > t_esc]).all() and np.isfinite(ens.z.values[0, t <= t_esc]).all()
        assert np.isfinite(ens.z.values[1]).all()
        for i in range(2):
            one = ts.simulate(m.replace(mu=0.3), 4e-3, y0=y0[i], t_eval=t, method=method, rtol=1e-9)
            np.testing.assert_allclose(ens.z.values[i], one.z.values, rtol=1e-9, atol=0, equal_nan=True)


def bouncing_start(factor: float = 1.05) -> np.ndarray:
    """A state 5 % outside the seed's bouncing cycle (on its section), found by following the cycle from mu = 0.30."""
    orb, _ = ts.follow_cycle(ts.SliderModel(contact="unilateral"))
    return orb.state0.values * factor


@pytest.mark.slow
def test_unilateral_seed_reaches_bouncing_cycle(seed_values):
    """docs/model.md §6: with unilateral contact the seed has a stable bouncing cycle.

    The run starts 5 % off the cycle (found by continuation from mu = 0.30, not by one long
    transient, whose landing flips with the last bit of a float) and must settle back on it: a
    property of the cycle's own basin, checked under perturbed inputs in test_robustness.py.
    """
    ref = seed_values["unilateral_bouncing_cycle_seed"]
    ds = ts.ensemble(ts.SliderModel(contact="unilateral"), 30.0, {"mu": [0.215]}, y0=bouncing_start(), steady=True,
                     rtol=1e-9)  # fmt: skip
    assert ts.OUTCOME_NAMES[int(ds.outcome[0])] == "periodic", ds
    assert abs(float(ds.omega[0]) / ref["omega"] - 1) < 0.01
    assert abs(float(ds.z1_amplitude[0]) / ref["A1"] - 1) < 0.01
    assert abs(float(ds.fraction_off_disk[0]) - ref["fraction_off_disk"]) < 0.01
    assert float(ds.min_normal_force[0]) == 0.0  # the pin leaves the disk
    # z_half_range: half z's range over the period, against a dense sampling of one period from the
    # section state (the Fourier's 512 samples miss an extreme by under (pi / 512)^2 / 2 = 2e-5).
    start = [float(ds[f"{v}_end"][0]) for v in ("z", "z_dot", "x", "x_dot", "phi", "phi_dot")]
    t = np.linspace(0.0, 2 * np.pi / float(ds.omega[0]), 20001)
    z = ts.simulate(ts.SliderModel(contact="unilateral", mu=0.215), float(t[-1]), y0=start, t_eval=t, rtol=1e-10).z
    np.testing.assert_allclose(float(ds.z_half_range[0]), 0.5 * float(np.ptp(z.values)), rtol=1e-4)
    assert float(ds.z_half_range[0]) > float(ds.z1_amplitude[0])


def test_bilateral_seed_decays_to_sliding_from_small_disturbance():
    ds = ts.ensemble(ts.SliderModel(contact="bilateral"), 60.0, {"mu": [0.215]}, y0=[0.5e-6, 0, 0, 0, 0, 0], steady=True,
                     rtol=1e-8, decay_amplitude=0.2e-6)
    assert ts.OUTCOME_NAMES[int(ds.outcome[0])] == "decayed"
    # The torsion mode decays slowest (Re = -0.33 /s): its frequency, 646.63 rad/s, is what is left.
    assert abs(float(ds.omega[0]) - 646.627) < 0.5
    # Decay is judged on every component: it takes seconds, not the 50 ms the normal mode needs.
    assert float(ds.t_end[0]) > 1.0


def test_unstable_sliding_without_unilateral_contact_diverges():
    # mu = 0.35 at the seed load is below its Hopf load (225 N): sliding is unstable (growth
    # 0.88 /s) and the bilateral model has no stable cycle, so the motion escapes.
    ds = ts.ensemble(ts.SliderModel(contact="bilateral"), 20.0, {"mu": [0.35]}, steady=True, rtol=1e-8)
    assert ts.OUTCOME_NAMES[int(ds.outcome[0])] == "diverged"
    assert int(ds.status[0]) == 0
    assert float(ds.max_abs_z[0]) >= 1e-3 * (1 - 1e-9)
    # The unilateral model stays bounded: a bouncing cycle near the torsion frequency.
    uni = ts.ensemble(ts.SliderModel(contact="unilateral"), 20.0, {"mu": [0.35]}, steady=True, rtol=1e-8)
    assert ts.OUTCOME_NAMES[int(uni.outcome[0])] == "periodic"
    assert 640 < float(uni.omega[0]) < 660 and float(uni.fraction_off_disk[0]) > 0.1


def test_batched_path_locates_the_escape_as_the_scalar_path_does():
    # Bilateral, constant mu, Dopri5, end state only: the lane-batched path. mu 0.35 escapes
    # (|z| reaches the 1 mm limit) at about 4.3 s; the batch locates it inside the step.
    m = ts.SliderModel(contact="bilateral")
    mus = np.array([0.2, 0.35, 0.21, 0.36])
    batch = ts.ensemble(m, 20.0, {"mu": mus}, y0=[1e-6, 0, 0, 0, 0, 0], rtol=1e-6, method="dopri5")
    for i, mu in enumerate(mus):
        one = ts.simulate(m.replace(mu=float(mu)), 20.0, y0=[1e-6, 0, 0, 0, 0, 0], rtol=1e-6, method="dopri5")
        assert int(batch.status[i]) == int(one.status), mu
        assert float(batch.t_reached[i]) == pytest.approx(float(one.t_reached), rel=1e-9)
        if mu >= 0.35:
            assert ts.STATUS_NAMES[int(batch.status[i])] == "diverged"
            assert abs(float(batch.z_end[i])) == pytest.approx(1e-3, rel=1e-9)
            assert float(batch.max_abs_z[i]) == pytest.approx(float(one.max_abs_z), rel=1e-9)


@pytest.mark.parametrize("method", ["dop853", "dopri5"])
def test_landings_on_the_bouncing_cycle_do_not_waste_rejected_steps(method):
    # On the seed's bouncing cycle (about 200 contact events in 0.5 s) the first step after each
    # landing used to come from the free flight and be rejected: 52 of 867 accepted DOP853 steps,
    # 105 of 2,651 Dopri5 steps. The first step after a switch is now capped at the step the run had
    # when it last left the mode it enters (`ModeSteps`): 2 and 4. The bound, 1 % of the accepted
    # steps, is a quarter of the old rate and several times the new one.
    m = ts.SliderModel(contact="unilateral")
    orbit, _ = ts.follow_cycle(m)
    ds = ts.simulate(m, 0.5, y0=np.asarray(orbit.state0.values, dtype=float), method=method, rtol=1e-6,
                     t_eval=[0.0, 0.5])  # fmt: skip
    assert ts.STATUS_NAMES[int(ds.status)] == "success"
    assert int(ds.n_events) >= 150  # it bounces: lift-offs and landings
    assert int(ds.n_reject) < 0.01 * int(ds.n_accept)
