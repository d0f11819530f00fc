"""Tests of the independent reference (tribosweep.bench.reference) and the numba baseline.

Truth first: the reference is checked against closed forms and the values of docs/model.md /
seed_values.json before anything else is compared with it.
"""

import json
import math
import pathlib

import numpy as np
import pytest
from scipy.optimize import brentq

ROOT = pathlib.Path(__file__).resolve().parents[1]
SEED_VALUES = ROOT.parents[0] / "shared" / "reference" / "seed_values.json"


from tribosweep.bench import reference as ref  # noqa: E402


@pytest.fixture(scope="module")
def seed_values():
    for path in (ROOT / "tests" / "data" / "seed_values.json", SEED_VALUES, ROOT / "shared" / "reference" / "seed_values.json"):
        if path.exists():
            return json.loads(path.read_text())
    raise FileNotFoundError("seed_values.json not found (tests/data or ../shared/reference)")


def _damped(q0, v0, mass, damping, stiffness, t):
    """Closed-form free response of m q'' + c q' + k q = 0 (underdamped): (q, q')."""
    sigma = damping / (2.0 * mass)
    wd = math.sqrt(stiffness / mass - sigma**2)
    a, b = q0, (v0 + sigma * q0) / wd
    e, cs, sn = np.exp(-sigma * t), np.cos(wd * t), np.sin(wd * t)
    q = e * (a * cs + b * sn)
    v = e * ((b * wd - sigma * a) * cs - (a * wd + sigma * b) * sn)
    return q, v


# --- static point and linearisation ---------------------------------------------------------------


def test_static_point_seed(seed_values):
    p = ref.seed_parameters()
    z_st, k_s = ref.static_point(p)
    # docs/model.md §3: z_st = -16.5612 um, K_s = 5.4607e6 N/m at 84.46 N (half a unit in the last digit).
    assert abs(z_st - (-16.5612e-6)) <= 0.5e-10
    assert abs(k_s - 5.4607e6) <= 50.0
    sp = seed_values["static_point"]
    assert z_st == pytest.approx(sp["z_st"], rel=5e-6)
    assert k_s == pytest.approx(sp["K_s"], rel=1e-5)
    # The total law reproduces the load, and K_s is its slope there.
    k0, ka, f = p["contact_stiffness"], p["contact_quadratic"], p["normal_load"]
    assert -k0 * z_st + ka * z_st**2 == pytest.approx(f, rel=1e-14)
    assert k_s == pytest.approx(k0 - 2 * ka * z_st, rel=1e-15)


def test_static_point_linear_law_and_bad_load():
    p = dict(ref.seed_parameters(), contact_quadratic=0.0)
    z_st, k_s = ref.static_point(p)
    assert z_st == pytest.approx(-p["normal_load"] / p["contact_stiffness"], rel=1e-15)
    assert k_s == p["contact_stiffness"]
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="normal_load"):
            ref.static_point(dict(p, normal_load=bad))


def test_sliding_is_equilibrium():
    p = ref.seed_parameters()
    assert np.all(ref.rhs(0.0, np.zeros(6), p) == 0.0)
    for mode in ("contact", None):
        assert np.all(ref.rhs(0.0, np.zeros(6), p, contact="unilateral", mode=mode) == 0.0)


def test_linear_jacobian_against_hand_linearisation():
    p = dict(ref.seed_parameters(), mu=0.27, normal_load=40.0)
    _, k_s = ref.static_point(p)
    m, mu = p["mass"], p["mu"]
    g = p["torsion_sign"] * p["moment_arm"] / p["inertia"]
    wz, wx, wt = p["omega_normal"], p["omega_friction"], p["omega_torsion"]
    dfz = np.array([-k_s, -p["contact_damping"], 0, 0, p["twist_coupling"], 0])  # dF_z/dy at y = 0
    jac = np.zeros((6, 6))
    jac[0, 1] = jac[2, 3] = jac[4, 5] = 1.0
    jac[1] = dfz / m
    jac[3] = mu * dfz / m
    jac[5] = g * mu * dfz
    jac[1, :2] += [-wz**2, -2 * p["zeta_normal"] * wz]
    jac[3, 2:4] += [-wx**2, -2 * p["zeta_friction"] * wx]
    jac[5, 4:] += [-wt**2, -2 * p["zeta_torsion"] * wt]
    np.testing.assert_allclose(ref.linear_jacobian(p), jac, rtol=1e-9, atol=1e-9)


def test_linear_eigenvalues_seed(seed_values):
    lam = ref.linear_eigenvalues(ref.seed_parameters())
    upper = lam[lam.imag > 0]
    assert upper.size == 3
    for got, (re, im) in zip(upper, seed_values["linear_eigenvalues_seed"]):
        # 4 significant digits of each part (docs/model.md §4).
        assert got.real == pytest.approx(re, rel=5e-4)
        assert got.imag == pytest.approx(im, rel=5e-4)
    assert np.all(lam.real < 0)  # sliding is stable at the seed point


def test_hopf_loads(seed_values):
    """docs/model.md §4: the torsion mode is unstable below the Hopf load (z_st, K_s follow the load)."""
    base = ref.seed_parameters()

    def growth(load, mu):
        return ref.linear_eigenvalues(dict(base, mu=mu, normal_load=load)).real.max()

    for mu, load in seed_values["hopf_load_N"].items():
        mu = float(mu)
        found = brentq(growth, 0.5 * load, 1.5 * load, args=(mu,), xtol=1e-6)
        assert found == pytest.approx(load, abs=1e-3)
        assert growth(0.9 * load, mu) > 0 > growth(1.1 * load, mu)


# --- time integration against closed forms --------------------------------------------------------


def test_decoupled_limit_closed_form():
    """K_a = mu = K_phi = 0: three independent damped oscillators, z with m w_z^2 + K_s, 2 zeta_z m w_z + C_zc."""
    p = dict(ref.seed_parameters(), contact_quadratic=0.0, mu=0.0, twist_coupling=0.0)
    _, k_s = ref.static_point(p)
    m = p["mass"]
    y0 = np.array([3e-6, 2e-3, -2e-6, 1e-3, 1e-4, -0.05])
    t = np.linspace(0.0, 0.1, 401)
    sol = ref.solve(p, y0, t[-1], t_eval=t, rtol=1e-13, atol=1e-22)
    wz, wx, wt = p["omega_normal"], p["omega_friction"], p["omega_torsion"]
    axes = [
        (m * wz**2 + k_s, 2 * p["zeta_normal"] * m * wz + p["contact_damping"]),
        (wx**2, 2 * p["zeta_friction"] * wx),  # per unit mass
        (wt**2, 2 * p["zeta_torsion"] * wt),
    ]
    masses = [m, 1.0, 1.0]
    for i, ((k, c), mass) in enumerate(zip(axes, masses)):
        q, v = _damped(y0[2 * i], y0[2 * i + 1], mass, c, k, t)
        for num, exact in ((sol.y[2 * i], q), (sol.y[2 * i + 1], v)):
            err = np.max(np.abs(num - exact)) / np.max(np.abs(exact))
            assert err < 1e-10, (i, err)


def test_unilateral_free_flight_and_landing():
    """A pin released above the disk flies freely (F_z = -F_st) and lands where zc = 0.

    With K_phi = 0 the law pushes at touch-down (N = -C_zc zd > 0), so the landing time is
    the closed-form root of zc(t) = 0. With the seed's K_phi the arm's twist (the friction
    preload relaxes in flight) makes the law pull at zc = 0: the pin must stay free until
    N_law rises through 0 inside the disk.
    """
    p = dict(ref.seed_parameters(), twist_coupling=0.0)
    z_st, _ = ref.static_point(p)
    m, wz, zeta = p["mass"], p["omega_normal"], p["zeta_normal"]
    z_eq = -p["normal_load"] / (m * wz**2)  # equilibrium of the free flight, m
    z0 = 50e-6  # zc = +33.4 um: off the disk
    y0 = np.array([z0, 0, 0, 0, 0, 0])

    def z_free(t):
        return z_eq + _damped(z0 - z_eq, 0.0, m, 2 * zeta * m * wz, m * wz**2, np.asarray(t))[0]

    wd = wz * math.sqrt(1 - zeta**2)
    t_land = brentq(lambda t: z_free(t) + z_st, 0.0, math.pi / wd, xtol=1e-16, rtol=1e-15)
    t_eval = np.linspace(0.0, 0.9 * t_land, 50)
    sol = ref.solve_unilateral(p, y0, 2.0 * t_land, rtol=1e-12, t_eval=t_eval)
    assert sol.modes[:2] == ["free", "contact"]
    assert sol.t_switch[0] == pytest.approx(t_land, rel=1e-10)
    assert sol.y_switch[0, 0] == pytest.approx(-z_st, rel=1e-10)
    assert sol.y_switch[1, 0] < 0  # landing, not grazing
    assert ref.normal_law_force(sol.y_switch[:, 0], p) > 1.0
    np.testing.assert_allclose(sol.y[0], z_free(t_eval), rtol=0, atol=1e-10 * z0)
    assert np.all(sol.mode == "free") and sol.min_normal_force == 0.0

    seed = ref.seed_parameters()
    late = ref.solve_unilateral(seed, y0, 2.0 * t_land, rtol=1e-12)
    y_sw = late.y_switch[:, 0]
    assert late.modes[:2] == ["free", "contact"]
    assert late.t_switch[0] > t_land * (1 + 1e-3)
    assert z_st + y_sw[0] < -1e-8  # already inside the disk
    assert abs(ref.normal_law_force(y_sw, seed)) < 1e-9  # where the law starts to push


def test_unilateral_without_opening_equals_bilateral():
    p = ref.seed_parameters()
    y0 = np.array([1e-6, 0, 0, 0, 0, 0])
    uni = ref.solve_unilateral(p, y0, 0.05, rtol=1e-12)
    bil = ref.solve(p, y0, 0.05, rtol=1e-12)
    assert uni.t_switch.size == 0 and uni.modes == ["contact"]
    np.testing.assert_allclose(uni.y_end, bil.y[:, -1], rtol=1e-13, atol=1e-25)
    assert uni.min_normal_force > 0


def test_unilateral_bouncing_switches_alternate():
    """A large disturbance at mu = 0.35 bounces: switches alternate and obey the contact conditions."""
    p = dict(ref.seed_parameters(), mu=0.35)
    sol = ref.solve_unilateral(p, [30e-6, 0, 0, 0, 0, 0], 0.1, rtol=1e-11)
    z_st, _ = ref.static_point(p)
    assert sol.t_switch.size >= 4 and np.all(np.diff(sol.t_switch) > 0)
    assert all(a != b for a, b in zip(sol.modes, sol.modes[1:]))
    for k, new_mode in enumerate(sol.modes[1:]):
        y = sol.y_switch[:, k]
        zc, n_law = z_st + y[0], ref.normal_law_force(y, p)
        if new_mode == "contact":  # touched down with a pushing law
            assert zc <= 1e-15 and n_law >= -1e-9
        else:  # lifted off (zc = 0) or the law stopped pushing (N = 0)
            assert abs(zc) < 1e-15 or abs(n_law) < 1e-9


# --- numba baseline against the reference ---------------------------------------------------------


def test_numba_dp5_matches_scipy_dop853():
    pytest.importorskip("numba")
    from tribosweep.bench import baselines as bl
    params_list, y0, t_end = bl.seed_ensemble_params(5, seed=0)
    P = ref.params_to_array(params_list)
    truth, scale = [], []
    for p, y in zip(params_list, y0):
        sol = ref.solve(p, y, t_end, rtol=1e-13)
        truth.append(sol.y[:, -1])
        scale.append(np.max(np.abs(sol.y), axis=1))  # max |y_i| over the run
    truth, scale = np.array(truth), np.array(scale)
    for rtol, tol in ((1e-9, 1e-6), (1e-6, 1e-3)):
        y_end, n_steps, n_rhs = bl.numba_dp5_batch(P, y0, t_end, rtol)
        assert np.all(n_steps > 0) and np.all(n_rhs >= 6 * n_steps)
        rel = np.abs(y_end - truth) / scale
        assert rel.max() < tol, (rtol, rel.max())
    y_par, _, _ = bl.numba_dp5_batch_parallel(P, y0, t_end, 1e-9)
    np.testing.assert_array_equal(y_par, bl.numba_dp5_batch(P, y0, t_end, 1e-9)[0])


def test_numba_dp5_decoupled_closed_form():
    """Truth for the kernel: the decoupled linear limit, and fifth-order convergence."""
    pytest.importorskip("numba")
    from tribosweep.bench import baselines as bl
    p = dict(ref.seed_parameters(), contact_quadratic=0.0, mu=0.0, twist_coupling=0.0)
    _, k_s = ref.static_point(p)
    m, wz = p["mass"], p["omega_normal"]
    y0 = np.array([[3e-6, 0, 0, 0, 0, 0]])
    t_end = 0.05
    z_exact = _damped(3e-6, 0.0, m, 2 * p["zeta_normal"] * m * wz + p["contact_damping"],
                      m * wz**2 + k_s, np.array(t_end))[0]
    errs, steps = [], []
    for rtol in (1e-7, 1e-9, 1e-11):
        y_end, n_steps, _ = bl.numba_dp5_batch(ref.params_to_array([p]), y0, t_end, rtol, atol=1e-30)
        errs.append(abs(y_end[0, 0] - z_exact) / 3e-6)
        steps.append(n_steps[0])
    assert errs[-1] < 1e-9
    # error ~ steps^-5: the observed order over two decades of tolerance
    order = -math.log(errs[0] / errs[-1]) / math.log(steps[0] / steps[-1])
    assert 4.0 < order < 6.5, (order, errs, steps)


@pytest.mark.parametrize("rtol", [1e-8, 1e-12])
def test_unilateral_follows_the_bouncing_cycle_through_every_contact_phase(rtol):
    """On the seed's bouncing cycle the reference keeps every contact phase and passes grazing touches.

    Each restart sits on an event's root. An event function of exactly 0 there re-triggered at once
    in solve_ivp: a zero-length segment that skipped a whole contact phase (at rtol 1e-8 the
    half-range of z then drifted by 3 %, and from the census's starts the pin could stay free
    inside the disk). At grazing touches both modes ended at once, a chatter error from rtol 1e-9
    down. The cycle (found by the core's continuation, then run here by scipy alone) must stay
    the stable cycle over 0.3 s (31 periods): its half-range of z is the same in the first and last
    0.1 s to 1e-5, the pin leaves the disk in both, it never rests free inside the disk, and it
    switches as often as the core's event-driven run (two flights a period; within 2, for a
    grazing touch that one side may count).
    """
    import tribosweep as ts

    m = ts.SliderModel(contact="unilateral")
    orbit, _ = ts.follow_cycle(m)
    p = {k: float(v) for k, v in m.values().items()}
    t = np.linspace(0.0, 0.3, 6001)
    sol = ref.solve_unilateral(p, orbit.state0.values, 0.3, rtol=rtol, t_eval=t)
    z_st, _ = ref.static_point(p)
    first, last = sol.y[0][t <= 0.1], sol.y[0][t >= 0.2]
    assert np.ptp(last) == pytest.approx(np.ptp(first), rel=1e-5)
    assert (z_st + first).max() > 0 and (z_st + last).max() > 0
    free_inside = (sol.mode == "free") & (z_st + sol.y[0] < -1e-3 * abs(z_st))
    assert not free_inside.any()
    core = ts.simulate(m, 0.3, y0=orbit.state0.values, rtol=rtol, method="dop853")
    assert abs(sol.t_switch.size - int(core.n_events)) <= 2, (sol.t_switch.size, int(core.n_events))
