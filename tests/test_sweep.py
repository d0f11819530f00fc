"""tribosweep.sweep: axes, regimes, chunking, executors, interruption and resume."""

from __future__ import annotations

import concurrent.futures
import json
import math
import multiprocessing
import pickle

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import _census, _codes, _core
from tribosweep._codes import REGIME
from tribosweep._settings import DEFAULTS, SweepSettings
from tribosweep._sweep import chunk as _chunk
from tribosweep._sweep import plan as _plan
from tribosweep._sweep import runner as _runner
from tribosweep._sweep import schema as _schema
from tribosweep._sweep import stages as _stages

LINEAR = {"strategy": "linear", "progress": False}
_REAL_COMPUTE_CHUNK = _chunk.compute_chunk


def strip(ds: xr.Dataset) -> xr.Dataset:
    """Everything a rerun must reproduce: drop the measured wall time and the history timestamp."""
    ds = ds.drop_vars("wall_time").load()
    ds.attrs = {k: v for k, v in ds.attrs.items() if k != "history"}
    return ds


# --- axes ----------------------------------------------------------------------------------------


def test_missing_axes_default_to_the_seed_as_length_one_dimensions():
    ds = ts.sweep(**LINEAR)
    assert ds.regime.dims == ("normal_load", "arm_length", "sliding_speed")
    assert ds.regime.shape == (1, 1, 1)
    assert ds.normal_load.values.tolist() == [84.46]
    assert ds.arm_length.values.tolist() == [0.072]
    assert ds.sliding_speed.values.tolist() == [0.46]
    assert ds.normal_load.attrs == {"units": "N", "long_name": "normal load F_st"}
    assert ds.sliding_speed.attrs["units"] == "m s-1"


@pytest.mark.parametrize("axis", ["normal_load", "arm_length", "sliding_speed"])
@pytest.mark.parametrize(
    ("values", "match"),
    [
        ([], "is empty"),
        ([3.0, 2.0], "not sorted"),
        ([2.0, 2.0], "duplicate"),
        ([1.0, float("nan")], "finite"),
        ([1.0, float("inf")], "finite"),
        ([0.0, 1.0], "> 0"),
        ([-1.0, 1.0], "> 0"),
        ([[1.0, 2.0]], "1-D"),
        (["a"], "not an array of numbers"),
    ],
)
def test_bad_axes_name_the_axis(axis, values, match):
    with pytest.raises(ValueError, match=match) as e:
        ts.sweep(**{axis: values}, **LINEAR)
    assert str(e.value).startswith(axis)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ({"mu": [0.3, 0.2]}, r"extra_axes\['mu'\] is not sorted"),
        ({"mu": [-0.1, 0.2]}, r"extra_axes\['mu'\]: mu = -0.1 is out of range"),
        ({"bogus": [1.0]}, "unknown field 'bogus'"),
        ({"normal_load": [1.0]}, "own argument"),
        ({"omega_torsion": [600.0]}, "follows arm_length"),
        ({"torsion_sign": [0.0]}, "torsion_sign"),
    ],
)
def test_bad_extra_axes(extra, match):
    with pytest.raises(ValueError, match=match):
        ts.sweep(extra_axes=extra, **LINEAR)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"strategy": "bogus"}, "strategy = 'bogus'"),
        ({"chunk_size": 0}, "chunk_size"),
        ({"threads": 0}, "threads"),
        ({"t_max": -1.0}, "t_max"),
        ({"integrator": "euler"}, "integrator"),
        ({"resume": True}, "resume=True needs output"),
        ({"disturbance": [1.0, 2.0]}, "disturbance"),
        ({"samples": 0}, r"samples = 0 is out of range: must be an integer in \[1, 100000\]"),
        ({"disturbance_scale": -1.0}, "disturbance_scale"),
        ({"census_t_max": 0.0}, "census_t_max"),
        ({"census_rtol": 1.5}, r"census_rtol = 1.5 is out of range: must be in \[1e-15, 1\)"),
        ({"transient_rtol": 1.5}, r"transient_rtol = 1.5 is out of range: must be in \[1e-15, 1\)"),
        ({"irregular_block": -1}, r"irregular_block = -1 is out of range: must be an integer in \[0, "),
        ({"transient_irregular_block": 2.5}, r"transient_irregular_block = 2.5 is out of range: must be an integer in "),
    ],
)
def test_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ts.sweep(**{"strategy": "linear", "progress": False, **kwargs})


@pytest.mark.parametrize(
    "kwargs",
    [{"model": "seed"}, {"extra_axes": [("mu", [0.2])]}, {"wear_reference": (1, 2, 3)}, {"wear_calibration": 1.0}],
)
def test_wrong_types(kwargs):
    with pytest.raises(TypeError, match=next(iter(kwargs))):
        ts.sweep(**{"strategy": "linear", "progress": False, **kwargs})


def test_the_transients_and_the_census_have_their_own_stationarity_blocks(monkeypatch):
    # The auto transients stop irregular motion after three blocks of 128 sections, the census's
    # disturbances after three of 256 (tribosweep._settings.Irregular: what each was measured at).
    seen = []
    real = _core.ensemble

    def spy(*args, **kw):
        if kw.get("kind") == "steady":  # the census's runs are those with its return-to-sliding thresholds
            seen.append(("census" if "decay_thresholds" in kw else "transient", kw["irregular_block"]))
        return real(*args, **kw)

    monkeypatch.setattr(_core, "ensemble", spy)
    ds = ts.sweep(normal_load=[10.0, 50.0], samples=4, threads=2, progress=False)
    assert ds.attrs["solver_transient_irregular_block"] == 128 and ds.attrs["solver_irregular_block"] == 256
    assert {"transient", "census"} == {who for who, _ in seen}
    assert all(block == {"transient": 128, "census": 256}[who] for who, block in seen), seen
    seen.clear()
    ts.sweep(normal_load=[10.0], census=False, transient_irregular_block=64, threads=2, progress=False)
    assert seen and all(block == 64 for _, block in seen), seen


def test_the_describing_functions_waveform_extremes():
    # z = A0 + A1 sin psi + A2 sin(2 psi + theta) of each root (the sweep's z_half_range where the
    # describing function decides is half their difference), against a million samples.
    ds = ts.describing_function(ts.SliderModel(normal_load=30.0))
    psi = np.linspace(0.0, 2 * np.pi, 1_000_000, endpoint=False)
    assert ds.sizes["root"] >= 2
    for r in range(ds.sizes["root"]):
        a0, a1, a2, th = (float(ds[k][r]) for k in ("A0", "A1", "A2", "theta"))
        z = a0 + a1 * np.sin(psi) + a2 * np.sin(2 * psi + th)
        scale = abs(a1) + abs(a2)
        assert float(ds.z_max[r]) == pytest.approx(z.max(), abs=1e-10 * scale)
        assert float(ds.z_min[r]) == pytest.approx(z.min(), abs=1e-10 * scale)
        assert float(ds.z_min[r]) < a0 < float(ds.z_max[r])


def test_tidf_and_shooting_stages_at_the_seed(seed_values):
    ref = seed_values["tidf_root_seed"]
    orb = seed_values["bilateral_periodic_orbit_seed"]
    d = ts.sweep(normal_load=[84.46], strategy="tidf", progress=False)
    assert int(d.decided_by.values.ravel()[0]) == _codes.DECIDED_BY["tidf"]
    assert int(d.tidf_roots.values.ravel()[0]) == 5
    assert abs(float(d.tidf_omega.values.ravel()[0]) - ref["omega"]) < 7e-4
    assert abs(float(d.tidf_a1.values.ravel()[0]) / ref["A1"] - 1) < 1e-3
    assert int(d.tidf_contact_opens.values.ravel()[0]) == 1
    s = ts.sweep(normal_load=[84.46], strategy="shooting", progress=False)
    assert int(s.decided_by.values.ravel()[0]) == _codes.DECIDED_BY["shooting"]
    assert abs(float(s.orbit_a1.values.ravel()[0]) / orb["A1"] - 1) < 1e-3
    assert int(s.orbit_stable.values.ravel()[0]) == 0
    # docs/model.md §6: the describing function is within 3.3 % in A1 of the orbit, below it. seed_values prints
    # both amplitudes to five digits; their rounding moves the ratio by at most 0.5/21524 + 0.5/22267 = 4.6e-5.
    assert float(s.tidf_a1_error.values.ravel()[0]) == pytest.approx(ref["A1"] / orb["A1"] - 1, abs=4.6e-5)
    assert int(s.newton_iterations.values.ravel()[0]) > 0


def test_auto_finds_the_seed_bistable():
    # docs/model.md §6: at the seed, stable sliding and a stable bouncing cycle coexist. The census sees
    # both (fractions near 0.7 / 0.3 at K = 32: each is more than 4 standard errors from 0 and 1).
    ds = ts.sweep(normal_load=[84.46], strategy="auto", progress=False)
    assert int(ds.regime.values.ravel()[0]) == REGIME["steady_sliding"]
    assert int(ds.bistable.values.ravel()[0]) == _codes.BISTABLE["coexisting"]
    p = ds.basin_fraction.values.reshape(-1, 4)[0]
    assert 0 < p[0] < 1 and 0 < p[1] < 1, p
    assert abs(float(ds.largest_cycle_omega.values.ravel()[0]) / 640.371 - 1) < 1e-3
    assert abs(float(ds.largest_cycle_fraction_off_disk.values.ravel()[0]) - 0.115) < 0.005
    # The point's own regime is sliding: its cycle variables stay empty (the coexisting cycle is the census's).
    assert np.isnan(ds.cycle_omega.values.ravel()[0])


# --- the linear stage ------------------------------------------------------------------------------


def test_linear_stage_at_the_seed(seed_values):
    ds = ts.sweep(**LINEAR)
    ev = seed_values["linear_eigenvalues_seed"]
    assert ds.growth_rate.item() == pytest.approx(ev[1][0], abs=1e-4)
    assert ds.linear_frequency.item() == pytest.approx(ev[1][1], abs=1e-3)
    assert ds.normal_mode_frequency.item() == pytest.approx(seed_values["normal_mode_frequency_hz_seed"], abs=0.05)
    assert ds.regime.item() == REGIME["steady_sliding"]
    assert ds.decided_by.item() == _codes.DECIDED_BY["linear"]
    assert ds.bistable.item() == -1  # not checked
    assert ds.n_rhs.item() == 0 and ds.newton_iterations.item() == 0
    assert math.isnan(ds.cycle_omega.item())


def test_linear_eigenvalues_match_the_reference_jacobian_at_several_points():
    # The vectorised numpy Jacobian against finite differences of an independent RHS (docs/model.md §2).
    base = ts.SliderModel(contact="bilateral", mu=0.3, normal_load=40.0)
    v = base.values()
    _z_st, k_s = base.static_point()

    def rhs(y):
        p = v
        fz = -k_s * y[0] + p["contact_quadratic"] * y[0] ** 2 - p["contact_damping"] * y[1] + p["twist_coupling"] * y[4]
        fx = p["mu"] * fz
        wz, wx, wt = p["omega_normal"], p["omega_friction"], p["omega_torsion"]
        return np.array([
            y[1], fz / p["mass"] - 2 * p["zeta_normal"] * wz * y[1] - wz**2 * y[0],
            y[3], fx / p["mass"] - 2 * p["zeta_friction"] * wx * y[3] - wx**2 * y[2],
            y[5], p["torsion_sign"] * p["moment_arm"] / p["inertia"] * fx - 2 * p["zeta_torsion"] * wt * y[5]
            - wt**2 * y[4],
        ])  # fmt: skip

    h = np.array([1e-9, 1e-6, 1e-9, 1e-6, 1e-7, 1e-4])
    j_fd = np.column_stack([(rhs(h[i] * np.eye(6)[i]) - rhs(-h[i] * np.eye(6)[i])) / (2 * h[i]) for i in range(6)])
    j = _census.jacobians(v)[0]
    np.testing.assert_allclose(j, j_fd, rtol=1e-6, atol=1e-6 * np.abs(j_fd).max())


@pytest.mark.parametrize(("mu", "hopf"), [(0.215, 24.904), (0.25, 74.514), (0.3, 148.277)])
def test_linear_regime_flips_at_the_hopf_load(mu, hopf):
    ds = ts.sweep(normal_load=[0.97 * hopf, 1.03 * hopf], extra_axes={"mu": [mu]}, **LINEAR)
    r = ds.regime.values.ravel().tolist()
    # Unstable BELOW the Hopf load in this model (docs/model.md §4).
    assert r == [REGIME["unstable_undetermined"], REGIME["steady_sliding"]]
    reason = ds.reason.values.ravel()
    assert "not computed" in reason[0] and reason[1] == ""
    assert "BELOW a Hopf load" in ds.attrs["comment"]


def test_extra_axis_dimension_and_attributes():
    ds = ts.sweep(normal_load=[50.0], extra_axes={"mu": [0.2, 0.25]}, **LINEAR)
    assert ds.regime.dims == ("normal_load", "arm_length", "sliding_speed", "mu")
    assert ds.mu.attrs["units"] == "1"
    # mu = 0.2 has its Hopf load at 4.2 N (stable at 50 N), mu = 0.25 at 74.5 N (unstable at 50 N).
    assert ds.regime.values.ravel().tolist() == [REGIME["steady_sliding"], REGIME["unstable_undetermined"]]


def test_mu_static_follows_a_swept_mu_when_unset():
    model = ts.SliderModel(contact="bilateral", friction_law="coulomb")
    ds = ts.sweep(model, normal_load=[50.0], extra_axes={"mu": [0.2, 0.25]}, **LINEAR)
    assert ds.regime.shape[-1] == 2
    plan_params = _plan.Plan(model, {"normal_load": np.array([1.0]), "arm_length": np.array([0.072]),
                                       "sliding_speed": np.array([0.46]), "mu": np.array([0.2, 0.3])},
                               "linear", SweepSettings(), 4, ts.WearReference(), None).point_params(0, 2)  # fmt: skip
    np.testing.assert_array_equal(plan_params["mu_static"], [0.2, 0.3])


def test_arm_length_sets_the_frequencies():
    ds = ts.sweep(arm_length=[0.05, 0.072, 0.127], **LINEAR)
    seed = ts.SliderModel(contact="bilateral")
    assert ds.omega_normal.sel(arm_length=0.072).item() == seed.omega_normal
    np.testing.assert_allclose(ds.omega_torsion.values, ts.arm_frequencies(ds.arm_length.values)["omega_torsion"])
    assert ds.arm_length_extrapolated.values.tolist() == [0, 0, 0]
    assert ds.normal_load_extrapolated.values.tolist() == [0]


def test_grid_order_invariance_and_chunk_size_invariance():
    small = ts.sweep(normal_load=[30.0], arm_length=[0.06], **LINEAR)
    big = ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.06], chunk_size=1, **LINEAR)
    sub = big.sel(normal_load=[30.0], arm_length=[0.06])
    for name in small.data_vars:
        if name != "wall_time":
            xr.testing.assert_identical(small[name], sub[name])
    other = ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.06], chunk_size=4, **LINEAR)
    xr.testing.assert_identical(strip(big), strip(other))


# --- transient and auto ------------------------------------------------------------------------


def _summary(outcome, status="success", off=0.0, vmin=0.1, reason=""):
    return {
        "status": [ts.STATUS[status]],
        "outcome": [ts.OUTCOME_NAMES.index(outcome)],
        "fraction_off_disk": [off],
        "min_slip_velocity": [vmin],
        "reason": [reason],
        "t_end": [5.25],
    }


@pytest.mark.parametrize(
    ("summary", "stable", "regime", "decided_by"),
    [
        (_summary("decayed"), True, "steady_sliding", "transient"),
        (_summary("periodic"), False, "self_excited", "transient"),
        (_summary("periodic", off=0.115), True, "contact_loss", "transient"),
        (_summary("periodic", off=0.115, vmin=-0.01), False, "stick_slip", "transient"),
        (_summary("periodic", vmin=0.0), False, "stick_slip", "transient"),
        (_summary("diverged"), False, "diverged", "transient"),
        (_summary("unsettled", status="not_converged"), False, "irregular", "transient"),
        (_summary("unsettled", status="not_converged"), True, "irregular", "transient"),
        (_summary("irregular"), False, "irregular", "transient"),
        (_summary("failed", status="panic", reason="panic: boom"), False, "failed", "transient"),
        (_summary("failed", status="step_too_small"), True, "failed", "transient"),
    ],
)
def test_classification_of_transient_summaries(summary, stable, regime, decided_by):
    r, status, reason, decided = _stages.classify(summary, np.array([stable]), 7.0)
    assert _codes.REGIME_NAMES[r[0]] == regime
    assert _codes.DECIDED_BY_NAMES[decided[0]] == decided_by
    if regime == "irregular":
        # Bounded, unsettled: an answer (status success), with what it is in the reason.
        assert status[0] == ts.STATUS["success"]
        when = "by t_max = 7 s" if ts.OUTCOME_NAMES[summary["outcome"][0]] == "unsettled" else "by t = 5.25 s"
        assert "neither periodic nor decayed" in reason[0] and when in reason[0], reason[0]
    else:
        assert status[0] == summary["status"][0]
    if regime == "failed":
        assert ts.STATUS_NAMES[summary["status"][0]] in reason[0]
    if summary["reason"][0]:
        assert summary["reason"][0] in reason[0]


def test_a_decay_where_sliding_is_linearly_unstable_is_a_failed_detection_not_sliding():
    # Small motion grows there, so no run comes to rest: the run's decay test was deceived.
    r, status, reason, decided = _stages.classify(_summary("decayed"), np.array([False]), 7.0)
    assert _codes.REGIME_NAMES[r[0]] == "unstable_undetermined"
    assert ts.STATUS_NAMES[status[0]] == "not_converged"
    assert _codes.DECIDED_BY_NAMES[decided[0]] == "transient"
    assert "t = 5.25 s" in reason[0] and "linearly unstable" in reason[0], reason[0]


def test_a_diverged_run_says_where_and_when_it_left_the_models_validity():
    # The steady-state core gives no reason for an escape; the sweep writes one from the run's summary.
    fly = _summary("diverged") | {"max_abs_z": [1e-3], "max_gap": [0.994e-3]}
    press = _summary("diverged") | {"max_abs_z": [1e-3], "max_gap": [-2e-5]}
    (r1,), _, (why1,), _ = _stages.classify(fly, np.array([False]), 7.0)
    (r2,), _, (why2,), _ = _stages.classify(press, np.array([False]), 7.0)
    assert r1 == r2 == REGIME["diverged"]
    assert why1 == ("|z| reached the escape limit (0.001 m) at t = 5.25 s: the motion left the model's validity; "
                    "the pin flew 0.000994 m off the disk")  # fmt: skip
    assert why2.endswith("; the pin was pressed into the disk past it") and "t = 5.25 s" in why2
    # A reason the core gave is kept.
    (_,), _, (why3,), _ = _stages.classify(_summary("diverged", reason="escape at t = 1 s"), np.array([False]), 7.0)
    assert why3 == "escape at t = 1 s"


def test_an_unsettled_run_with_a_non_finite_end_is_a_failure_not_irregular():
    s = _summary("unsettled", status="not_converged") | {"y_end": np.array([[np.nan, 0, 0, 0, 0, 0]])}
    r, status, reason, _ = _stages.classify(s, np.array([False]), 7.0)
    assert _codes.REGIME_NAMES[r[0]] == "failed"
    assert status[0] != ts.STATUS["success"] and "unsettled" in reason[0]


def test_a_failed_point_is_data_not_an_exception(monkeypatch):
    # Whatever goes wrong in the core for one point (here a simulated panic) becomes that point's
    # status and reason; the sweep goes on with the others.
    def panicking(points, sel, y0, decay=None, **kw):
        n = sel.size
        return {"status": np.full(n, ts.STATUS["panic"], np.uint8), "outcome": np.full(n, 4, np.uint8),
                "reason": ["panic: boom"] * n, **{k: np.full(n, np.nan) for k in (
                    "omega", "z1_amplitude", "z2_amplitude", "z_half_range", "phi1_amplitude", "fraction_off_disk",
                    "min_normal_force", "min_slip_velocity")}, "n_rhs": np.zeros(n, np.int64)}  # fmt: skip

    monkeypatch.setattr(_stages, "run_steady", panicking)
    ds = ts.sweep(normal_load=[10.0, 50.0], strategy="auto", progress=False)
    r = ds.regime.values.ravel()
    assert r.tolist() == [REGIME["failed"], REGIME["steady_sliding"]]
    assert ds.status.values.ravel().tolist() == [ts.STATUS["panic"], ts.STATUS["success"]]
    assert "panic: boom" in ds.reason.values.ravel()[0]
    assert ds.decided_by.values.ravel().tolist() == [_codes.DECIDED_BY["transient"], _codes.DECIDED_BY["tidf"]]
    # undetermined; mild in part (sliding coexists with a cycle at 50 N: the census says so)
    assert ds.wear_applicability.values.ravel().tolist() == [2, 3]
    assert int(ds.bistable.values.ravel()[1]) == _codes.BISTABLE["coexisting"]
    # Sliding is linearly unstable at 10 N whatever the failed transient did: no disturbance returns.
    assert ds.mild_wear_fraction.values.ravel()[0] == 0.0


def test_an_unsettled_bounded_run_is_irregular_unless_it_is_sliding_still_decaying():
    # 10 N: sliding unstable; the run is bounded and unsettled at t_max: irregular motion, measured.
    # 50 N: sliding stable, the 1 um disturbance (< |z_st|/2) still decaying: sliding, by linear stability.
    ds = ts.sweep(normal_load=[10.0, 50.0], strategy="transient", t_max=1e-3, progress=False)
    assert ds.regime.values.ravel().tolist() == [REGIME["irregular"], REGIME["steady_sliding"]]
    assert ds.status.values.ravel().tolist() == [ts.STATUS["success"], ts.STATUS["not_converged"]]
    assert ds.decided_by.values.ravel().tolist() == [_codes.DECIDED_BY["transient"], _codes.DECIDED_BY["linear"]]
    reason = ds.reason.values.ravel()
    assert "neither periodic nor decayed by t_max = 0.001 s" in reason[0] and "FTLE" in reason[0]
    assert "did not settle by t_max = 0.001 s" in reason[1] and "still decaying" in reason[1]
    assert (ds.n_rhs.values > 0).all()
    irr = {k: ds[k].values.ravel() for k in ("irregular_z_min", "irregular_z_max", "irregular_omega", "irregular_ftle",
                                             "irregular_ftle_se")}  # fmt: skip
    assert all(np.isfinite(v[0]) and np.isnan(v[1]) for v in irr.values())
    assert irr["irregular_z_min"][0] < irr["irregular_z_max"][0]
    for k in irr:
        assert ds[k].attrs["units"] and ds[k].attrs["long_name"]


def test_auto_runs_the_transient_only_where_sliding_is_unstable():
    ds = ts.sweep(normal_load=[10.0, 50.0], strategy="auto", progress=False, threads=2, census=False)
    r = ds.regime.values.ravel()
    assert r[1] == REGIME["steady_sliding"] and ds.n_rhs.values.ravel()[1] == 0
    assert r[0] in (REGIME["self_excited"], REGIME["contact_loss"], REGIME["stick_slip"], REGIME["diverged"])
    assert ds.n_rhs.values.ravel()[0] > 0
    if r[0] in (REGIME["self_excited"], REGIME["contact_loss"]):
        assert ds.cycle_omega.values.ravel()[0] == pytest.approx(ds.linear_frequency.values.ravel()[0], rel=0.1)
        assert math.isnan(ds.wear_rate_relative.values.ravel()[0])


def test_transient_decays_at_a_stable_point_and_is_thread_independent():
    kw = {"normal_load": [50.0, 80.0], "strategy": "transient", "progress": False}
    one = ts.sweep(threads=1, **kw)
    two = ts.sweep(threads=2, **kw)
    assert one.regime.values.ravel().tolist() == [REGIME["steady_sliding"]] * 2
    assert (one.decided_by.values == _codes.DECIDED_BY["transient"]).all()
    xr.testing.assert_identical(strip(one), strip(two))


# --- the chunk function and executors ----------------------------------------------------------


def test_compute_chunk_is_pure_and_picklable():
    assert pickle.loads(pickle.dumps(_chunk.compute_chunk)) is _chunk.compute_chunk
    args = (ts.SliderModel(contact="bilateral").values(), "unilateral", "constant",
            {"normal_load": np.array([10.0, 50.0]), "mu": np.array([0.2, 0.3])}, "linear",
            {"wear": {"normal_load": 84.46, "sliding_speed": 0.46, "frequency_hz": 229.2}})  # fmt: skip
    a = _chunk.compute_chunk(*pickle.loads(pickle.dumps(args)))
    b = _chunk.compute_chunk(*args)
    assert set(a) == set(_schema.POINT_VARIABLES) | set(_census.CENSUS_VARIABLES)
    for k in a:
        if k != "wall_time":
            np.testing.assert_array_equal(a[k], b[k])


def test_thread_pool_executor_gives_the_serial_result():
    kw = {"normal_load": [10.0, 30.0, 60.0], "arm_length": [0.05, 0.1], "chunk_size": 2, **LINEAR}
    serial = ts.sweep(**kw)
    with concurrent.futures.ThreadPoolExecutor(2) as ex:
        pooled = ts.sweep(executor=ex, **kw)
    xr.testing.assert_identical(strip(serial), strip(pooled))


def test_process_pool_executor_runs_the_chunk_function(tmp_path):
    kw = {"normal_load": [10.0, 60.0], "chunk_size": 1, **LINEAR}
    serial = ts.sweep(**kw)
    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=ctx) as ex:
        pooled = ts.sweep(executor=ex, output=tmp_path / "p.nc", **kw)
    xr.testing.assert_identical(strip(serial), strip(pooled))
    pooled.close()


class _FutureExecutor:
    """A dask-Client-like executor: ``map`` returns futures."""

    def map(self, fn, tasks):
        out = []
        for t in tasks:
            f = concurrent.futures.Future()
            f.set_result(fn(t))
            out.append(f)
        return out


def test_executor_returning_futures_fed_in_windows(monkeypatch):
    monkeypatch.setattr(_runner, "EXECUTOR_WINDOW", 2)
    kw = {"normal_load": [10.0, 30.0, 60.0], "arm_length": [0.05, 0.1], "chunk_size": 1, **LINEAR}
    xr.testing.assert_identical(strip(ts.sweep(**kw)), strip(ts.sweep(executor=_FutureExecutor(), **kw)))


# --- output, interruption, resume ---------------------------------------------------------------

GRID = {"normal_load": [10.0, 30.0, 60.0], "arm_length": [0.05, 0.1], "chunk_size": 2, **LINEAR}  # 6 points, 3 chunks


class _Interrupt:
    """Patch for compute_chunk: runs ``k`` chunks, then raises KeyboardInterrupt."""

    def __init__(self, k):
        self.k, self.calls = k, 0
        self.real = _REAL_COMPUTE_CHUNK

    def __call__(self, *args):
        if self.calls >= self.k:
            raise KeyboardInterrupt
        self.calls += 1
        return self.real(*args)


def test_output_file_is_lazy_and_the_parts_are_removed(tmp_path):
    out = tmp_path / "s.nc"
    ds = ts.sweep(output=out, **GRID)
    assert ds.encoding["source"] == str(out)
    assert not ds.regime.variable._in_memory  # opened lazily from the file
    assert not (tmp_path / "s.nc.parts").exists()
    assert not (tmp_path / "s.nc.tmp").exists()
    mem = ts.sweep(**GRID)
    xr.testing.assert_identical(strip(mem), strip(ds))
    ds.close()


def test_interrupt_then_resume_is_identical_to_an_uninterrupted_run(tmp_path, monkeypatch):
    full = ts.sweep(output=tmp_path / "full.nc", **GRID)
    out = tmp_path / "s.nc"
    patch = _Interrupt(2)
    monkeypatch.setattr(_chunk, "compute_chunk", patch)
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, **GRID)
    parts = tmp_path / "s.nc.parts"
    assert sorted(p.name for p in parts.glob("chunk_*.npz")) == ["chunk_000000.npz", "chunk_000001.npz"]
    assert not out.exists() and not (tmp_path / "s.nc.tmp").exists()
    assert json.loads((parts / "manifest.json").read_text())["n_chunks"] == 3

    counter = _Interrupt(99)
    monkeypatch.setattr(_chunk, "compute_chunk", counter)
    resumed = ts.sweep(output=out, resume=True, **GRID)
    assert counter.calls == 1  # only the missing chunk
    assert not parts.exists()
    xr.testing.assert_identical(strip(full), strip(resumed))
    # wall_time of the saved chunks came through the parts unchanged and is finite everywhere.
    assert np.isfinite(resumed.wall_time.values).all()
    full.close()
    resumed.close()


def test_resume_recomputes_deleted_and_corrupt_chunks(tmp_path, monkeypatch):
    full = ts.sweep(**GRID)
    out = tmp_path / "s.nc"
    monkeypatch.setattr(_chunk, "compute_chunk", _Interrupt(2))
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, **GRID)
    parts = tmp_path / "s.nc.parts"
    (parts / "chunk_000000.npz").unlink()
    (parts / "chunk_000001.npz").write_bytes(b"not an npz")
    counter = _Interrupt(99)
    monkeypatch.setattr(_chunk, "compute_chunk", counter)
    resumed = ts.sweep(output=out, resume=True, **GRID)
    assert counter.calls == 3
    xr.testing.assert_identical(strip(full), strip(resumed))
    resumed.close()


@pytest.mark.parametrize(
    ("change", "named"),
    [
        ({"normal_load": [10.0, 30.0, 61.0]}, "normal_load"),
        ({"strategy": "auto"}, "strategy"),
        ({"chunk_size": 3}, "chunk_size"),
        ({"extra_axes": {"mu": [0.2]}}, r"axes 'mu' differs \(saved \(absent\), now \[0.2\]\)"),
        ({"model": ts.SliderModel(contact="unilateral", mu=0.25)}, "mu"),
        ({"t_max": 5.0}, "t_max"),
    ],
)
def test_resume_with_a_different_configuration_names_the_mismatch(tmp_path, monkeypatch, change, named):
    out = tmp_path / "s.nc"
    monkeypatch.setattr(_chunk, "compute_chunk", _Interrupt(1))
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, **GRID)
    monkeypatch.undo()
    with pytest.raises(ValueError, match=f"cannot resume.*{named}"):
        ts.sweep(output=out, resume=True, **{**GRID, **change})


def test_existing_parts_without_resume_are_not_discarded(tmp_path, monkeypatch):
    out = tmp_path / "s.nc"
    monkeypatch.setattr(_chunk, "compute_chunk", _Interrupt(1))
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, **GRID)
    monkeypatch.undo()
    with pytest.raises(FileExistsError, match="resume=True"):
        ts.sweep(output=out, **GRID)
    assert (tmp_path / "s.nc.parts" / "chunk_000000.npz").exists()


def test_threads_do_not_enter_the_configuration(tmp_path, monkeypatch):
    # A run interrupted on one thread resumes on two: the saved chunk is reused (only the other two are
    # computed, no "cannot resume") and the result is the uninterrupted one-thread run's.
    full = ts.sweep(threads=1, **GRID)
    out = tmp_path / "s.nc"
    monkeypatch.setattr(_chunk, "compute_chunk", _Interrupt(1))
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, threads=1, **GRID)
    counter = _Interrupt(99)
    monkeypatch.setattr(_chunk, "compute_chunk", counter)
    resumed = ts.sweep(output=out, resume=True, threads=2, **GRID)
    assert counter.calls == 2
    xr.testing.assert_identical(strip(full), strip(resumed))
    resumed.close()


#: The grid on which auto and transient must agree (its verdicts are checked under ulp-moved loads
#: and rtol +-1 % in test_robustness.py).
AGREE_GRID = dict(normal_load=[8.0, 30.0, 70.0, 140.0], extra_axes={"mu": [0.2, 0.3, 0.4]}, progress=False, t_max=40.0)


def robust_transient_regimes(kw: dict) -> tuple[np.ndarray, np.ndarray]:
    """The regime of ``strategy="transient"`` per point (flattened), and whether it is robust.

    A transient is one trajectory from one small disturbance. Where it passes near a basin
    boundary (at 140 N, mu 0.4 it either settles on the stick-slip cycle or escapes), its regime
    flips with the last bit of a float. Robust: the same with the loads moved by +-1 and +-2 ulps
    and the transients' tolerance (``transient_rtol``) moved by +-1 %; only those regimes are
    single-run facts a test may compare.
    """
    from conftest import RTOL_FACTORS, ULPS, moved

    ref = ts.sweep(strategy="transient", **kw)
    rt = ref.regime.values.ravel()
    robust = np.ones(rt.size, dtype=bool)
    loads = np.asarray(kw["normal_load"])
    for k in ULPS:
        robust &= ts.sweep(strategy="transient", **(kw | dict(normal_load=moved(loads, k)))).regime.values.ravel() == rt
    for f in RTOL_FACTORS:
        moved_rtol = dict(transient_rtol=DEFAULTS.steady.rtol * f)
        robust &= ts.sweep(strategy="transient", **(kw | moved_rtol)).regime.values.ravel() == rt
    return ref, robust


def test_auto_agrees_with_transient_where_the_transient_settles():
    # Issue 4: on a test grid, the regime of `auto` (cheapest model per point) equals the regime of
    # always integrating, at every point where the integration settled robustly.
    kw = AGREE_GRID
    auto = ts.sweep(strategy="auto", **kw)
    full, robust = robust_transient_regimes(kw)
    ra, rt = auto.regime.values.ravel(), full.regime.values.ravel()
    # Settled: the transient reached a cycle, sliding or an escape (irregular motion did not settle),
    # and reaches it under inputs moved by ulps and rtol by 1 %.
    settled = (full.status.values.ravel() == ts.STATUS["success"]) & ~np.isin(
        rt, [REGIME["unstable_undetermined"], REGIME["irregular"]]) & robust
    # auto's own transient (from the unstable mode, not the transient strategy's start) is one
    # trajectory too: where its census says that most disturbances reach another regime, the one
    # it reached is the fate of one chaotic run (on this grid, 70 N at mu 0.4: an escape at 3.5 s,
    # which 1 of the census's 32 samples shares; 31 reach the cycle the transient strategy finds).
    # Its last-bit fate is no verdict; elsewhere auto's regime is what most disturbances reach.
    by_run = auto.decided_by.values.ravel() == _codes.DECIDED_BY["transient"]
    minority = by_run & (auto.regime_fraction.values.ravel() < 0.5)
    settled &= ~minority
    assert settled.sum() >= 8, settled
    assert np.array_equal(ra[settled], rt[settled]), (ra, rt)
    # auto decides many points without integrating, and without the bistability question (which
    # `transient` from a small disturbance does not ask) it integrates less.
    assert (auto.decided_by.values != _codes.DECIDED_BY["transient"]).sum() >= 4
    lean = ts.sweep(strategy="auto", census=False, **kw)
    assert np.array_equal(lean.regime.values, auto.regime.values)
    cheap = (lean.decided_by.values.ravel() != _codes.DECIDED_BY["transient"]) & ~np.isin(
        lean.regime.values.ravel(), [REGIME["unstable_undetermined"], REGIME["irregular"]])
    assert np.all(lean.n_rhs.values.ravel()[cheap] == 0) and np.all(full.n_rhs.values.ravel()[cheap] > 10_000)
    assert lean.n_rhs.values.sum() < full.n_rhs.values.sum()


def test_points_that_differ_only_in_speed_share_their_dynamics_exactly():
    # Constant friction: V only shifts v_r. The sweep computes the dynamics once per (load, arm)
    # and must give the same numbers as separate single-speed sweeps.
    kw = dict(normal_load=[8.0, 84.46], strategy="auto", progress=False, census=False, t_max=20.0)
    both = ts.sweep(sliding_speed=[0.3, 0.6], **kw)
    for j, v in enumerate([0.3, 0.6]):
        one = ts.sweep(sliding_speed=[v], **kw)
        for name in ("regime", "cycle_omega", "z1_amplitude", "growth_rate", "n_rhs"):
            np.testing.assert_array_equal(both[name].values[:, :, j], one[name].values[:, :, 0], err_msg=name)
        # v_min(V_rep) + (V - V_rep) against v_min(V): equal to rounding.
        np.testing.assert_allclose(both.min_slip_velocity.values[:, :, j], one.min_slip_velocity.values[:, :, 0],
                                   rtol=1e-14)
    # The cycle at 8 N slides at V - max(xd + s L phid): the shift is exactly the speed difference.
    d = both.min_slip_velocity.values[0, 0, 1] - both.min_slip_velocity.values[0, 0, 0]
    assert d == pytest.approx(0.3, abs=1e-12)


def test_regime_map_marks_bistable_points():
    from tribosweep.plot import regime_map

    ds = ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], strategy="linear", progress=False)
    labels = lambda fig: [t.get_text() for leg in fig.legends for t in leg.get_texts()]  # noqa: E731
    assert not any("coexists" in s for s in labels(regime_map(ds)))
    ds["bistable"][1, 0, 0] = _codes.BISTABLE["coexisting"]
    fig = regime_map(ds)
    assert any("coexists" in s for s in labels(fig))
    assert any(p.get_hatch() == "//" for p in fig.axes[0].patches)


def test_regime_map_labels_multi_period_cycles():
    from tribosweep.plot import regime_map

    ds = ts.sweep(normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], strategy="linear", progress=False)
    texts = lambda fig: [t.get_text() for t in fig.axes[0].texts]  # noqa: E731
    assert "2T" not in texts(regime_map(ds))
    ds["cycle_period_ratio"][2, 1, 0] = 2.08  # the period-2 cycle at 80 N, mu 0.425
    ds["cycle_period_ratio"][0, 0, 0] = 1.04  # an ordinary cycle: no label
    fig = regime_map(ds)
    assert texts(fig) == ["2T"]
    assert any("mode periods" in t.get_text() for leg in fig.legends for t in leg.get_texts())


def test_a_returning_census_sample_stops_inside_the_saddle(monkeypatch):
    # A returning disturbance stops once it is back inside the saddle with the pin on the disk,
    # not after decaying to 1e-3 |z_st|: the same fractions for a fraction of the work. At 130 N,
    # 6.1 cm every disturbance returns (the run is far from any basin boundary).
    from tribosweep import _census

    point = dict(normal_load=[130.0], arm_length=[0.061], progress=False, samples=8)
    early = ts.sweep(**point)
    monkeypatch.setattr(_census, "RETURN_FRACTION", 0.0)
    late = ts.sweep(**point)
    assert early.basin_stability.item() == late.basin_stability.item() == 1.0
    # Decaying from about 0.2 A1 to 1e-3 |z_st| at 0.5 1/s costs several seconds of simulated time
    # per sample: the early stop must save at least a quarter of the work.
    assert int(early.n_rhs.item()) < 0.75 * int(late.n_rhs.item()), (int(early.n_rhs.item()), int(late.n_rhs.item()))


def test_stable_point_without_a_saddle_is_marked_no_saddle():
    # 30 N, mu 0.05: sliding stable, and the describing function has no physical root there (no
    # saddle cycle: no census); 84.46 N, mu 0.05 has one, and every disturbance returns to sliding.
    ds = ts.sweep(normal_load=[30.0, 84.46], extra_axes={"mu": [0.05]}, progress=False)
    names = [_codes.BISTABLE_NAMES[_codes.BISTABLE_VALUES.index(int(v))] for v in ds.bistable.values.ravel()]
    assert names == ["no_saddle", "one_attractor"]
    assert ds.basin_stability.values.ravel()[1] == 1.0 and ds.census_samples.values.ravel().tolist() == [0, 32]
    assert np.isnan(ds.tidf_a1.values.ravel()[0]) and np.isfinite(ds.tidf_a1.values.ravel()[1])


@pytest.mark.parametrize(
    "axis, values, hint",
    [("arm_length", [5.0, 7.0], "centimetres"), ("normal_load", [50e3], "newtons"), ("sliding_speed", [460.0], "mm/s")],
)
def test_a_likely_unit_mistake_is_named_in_a_warning(axis, values, hint):
    with pytest.warns(UserWarning, match=f"{axis} reaches .*{hint}"):
        ts.sweep(**{axis: values}, **LINEAR)


def test_results_do_not_depend_on_the_chunking_when_speeds_share_their_dynamics():
    """Constant law: points that differ only in V share one computation at the model's V0, so a
    point's numbers are the same whichever points its chunk holds (chunk sizes 1, 7 and 64)."""
    kw = dict(normal_load=[15.0, 60.0], arm_length=[0.06, 0.1], sliding_speed=[0.2, 0.46, 0.9], strategy="transient",
              t_max=0.5, progress=False)  # fmt: skip
    runs = [strip(ts.sweep(chunk_size=c, **kw)) for c in (1, 7, 64)]
    for other in runs[1:]:
        xr.testing.assert_identical(runs[0], other)
    # The speed only shifts the sliding velocity: V - min_slip_velocity is the same at every speed.
    u = (runs[0].min_slip_velocity - runs[0].sliding_speed).transpose(*runs[0].min_slip_velocity.dims).values
    assert runs[0].min_slip_velocity.dims[-1] == "sliding_speed"
    # 1e-15 m/s: the shift V - V0 is one rounding of numbers below 1 m/s.
    np.testing.assert_allclose(u, np.broadcast_to(u[..., :1], u.shape), rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"threads": 2**62}, r"threads = 4611686018427387904 is out of range: must be an integer in \[1, 1024\]"),
        ({"normal_load": np.linspace(10, 20, 2001), "arm_length": np.linspace(0.05, 0.1, 5000), "max_points": 10**7},
         r"10005000 points \(shape \(2001, 5000, 1\)\), more than max_points = 10000000"),
        ({"output": ""}, "output = '' is not a file name"),
    ],
)  # fmt: skip
def test_bad_requests_are_refused_before_any_work(kwargs, needle, monkeypatch):
    monkeypatch.setattr(_chunk, "compute_chunk", lambda *a: pytest.fail("work started"))
    with pytest.raises(ValueError, match=needle):
        ts.sweep(**{**LINEAR, **kwargs})


def test_an_output_that_is_a_directory_is_refused_before_any_work(tmp_path, monkeypatch):
    monkeypatch.setattr(_chunk, "compute_chunk", lambda *a: pytest.fail("work started"))
    with pytest.raises(ValueError, match="is a directory: give a file name inside it"):
        ts.sweep(output=tmp_path, **LINEAR)
    assert list(tmp_path.iterdir()) == []


def _interrupted_sweep(tmp_path, monkeypatch):
    """A 6-point, 3-chunk sweep stopped after two chunks: its parts directory and keywords."""
    out = tmp_path / "s.nc"
    calls = {"n": 0}
    real = _chunk.compute_chunk

    def stop_after_two(*a):
        calls["n"] += 1
        if calls["n"] > 2:
            raise KeyboardInterrupt
        return real(*a)

    monkeypatch.setattr(_chunk, "compute_chunk", stop_after_two)
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, **GRID)
    monkeypatch.setattr(_chunk, "compute_chunk", real)
    return out, out.with_name(out.name + ".parts")


def test_a_part_with_a_flipped_bit_or_foreign_values_is_recomputed_not_trusted(tmp_path, monkeypatch, caplog):
    reference = strip(ts.sweep(**GRID))
    out, parts = _interrupted_sweep(tmp_path, monkeypatch)
    first, second = parts / "chunk_000000.npz", parts / "chunk_000001.npz"
    data = bytearray(first.read_bytes())
    data[len(data) // 2] ^= 0x01  # one bit, inside the arrays
    first.write_bytes(bytes(data))
    # A valid part of this configuration, but with other values: the checksum ledger rejects it.
    with np.load(second) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["growth_rate"] = arrays["growth_rate"] + 1.0
    with open(second, "wb") as f:
        np.savez(f, **arrays)
    with caplog.at_level("WARNING", logger="tribosweep"):
        ds = ts.sweep(output=out, resume=True, **GRID)
    assert "chunk_000000.npz: its checksum does not match" in caplog.text
    assert "chunk_000001.npz: its checksum does not match" in caplog.text
    xr.testing.assert_identical(strip(ds.load()), reference)


def test_resuming_with_another_core_build_is_refused(tmp_path, monkeypatch):
    out, parts = _interrupted_sweep(tmp_path, monkeypatch)
    monkeypatch.setattr(_plan, "core_build", lambda: "0123456789abcdef")
    with pytest.raises(ValueError, match="core_build differs"):
        ts.sweep(output=out, resume=True, **GRID)


def test_the_stored_hopf_curve_separates_stable_from_unstable_points(tmp_path):
    """A normal load x arm length sweep stores the Hopf curves crossing its box; at every arm length
    the points more than 1 N below the curve are unstable and those more than 1 N above are stable
    (the seed's mu: unstable below the Hopf load). 1 N: the curve is exact to 1e-10 of the box,
    and the growth rate's sign is decided far from zero there (about 0.07 1/s per N)."""
    ds = ts.sweep(normal_load=np.linspace(10.0, 150.0, 15), arm_length=np.linspace(0.05, 0.127, 5),
                  output=tmp_path / "h.nc", **LINEAR)  # fmt: skip
    with ds:
        assert ds.hopf_normal_load.dims == ("hopf_point",) and ds.hopf_normal_load.attrs["units"] == "N"
        assert "1 Hopf curve(s) in the box" in ds.attrs["hopf_curves"]
        crit = str(ds.hopf_criticality.attrs["flag_meanings"]).split()
        assert {crit[int(c)] for c in ds.hopf_criticality.values} == {"subcritical"}  # docs/model.md: subcritical
        order = np.argsort(ds.hopf_arm_length.values)
        arms, loads = ds.hopf_arm_length.values[order], ds.hopf_normal_load.values[order]
        g = ds.growth_rate.isel(sliding_speed=0)
        checked = 0
        for arm in ds.arm_length.values:
            if not arms[0] <= arm <= arms[-1]:
                # The curve leaves the box: at this arm length every point lies on one side of it.
                assert np.all(g.sel(arm_length=arm).values < 0) or np.all(g.sel(arm_length=arm).values > 0)
                continue
            f_h = np.interp(arm, arms, loads)
            for f, rate in zip(ds.normal_load.values, g.sel(arm_length=arm).values):
                if abs(f - f_h) > 1.0:
                    assert (rate > 0) == (f < f_h), (arm, f, f_h, rate)
                    checked += 1
        assert checked >= 20
    # A third swept axis: no curve, and the attribute says why.
    ds3 = ts.sweep(normal_load=[10.0, 80.0], arm_length=[0.05, 0.1], sliding_speed=[0.3, 0.6], **LINEAR)
    assert "hopf_normal_load" not in ds3 and "third axis" in ds3.attrs["hopf_curves"]


def test_the_regime_map_draws_the_stored_hopf_curve_and_names_every_mark():
    pytest.importorskip("matplotlib")
    from tribosweep.plot import regime_map

    ds = ts.sweep(normal_load=np.linspace(10.0, 150.0, 8), arm_length=np.linspace(0.05, 0.127, 4), **LINEAR)
    fig = regime_map(ds)
    ax = fig.axes[0]
    solid = [ln for ln in ax.lines if ln.get_linestyle() == "-" and len(ln.get_xdata()) > 2]
    assert len(solid) == 1
    np.testing.assert_array_equal(solid[0].get_xdata(), ds.hopf_normal_load.values)
    np.testing.assert_array_equal(solid[0].get_ydata(), ds.hopf_arm_length.values)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert any(lab.startswith("Hopf curve, subcritical") for lab in labels)
    assert any(lab.startswith("contact law identified") for lab in labels)
