"""Where the describing function fails, detected per point (issue 5): validity map and Newton basin."""

from __future__ import annotations

import numpy as np

from tribosweep.bench import df_failure as dff


def test_validity_map_flags_contact_opening_at_the_seed_and_passes_a_valid_point():
    ds = dff.tidf_validity_map([84.46, 100.0], [0.05, 0.072])
    code = {(f, a): dff.VALIDITY_NAMES[int(ds.tidf_validity.sel(normal_load=f, arm_length=a))]
            for f in (84.46, 100.0) for a in (0.05, 0.072)}
    # Seed: the root's two-harmonic waveform reaches 27.5 um > |z_st| = 16.56 um: outside the law.
    assert code[(84.46, 0.072)] == "contact_opens"
    # The stiff 5 cm arm at 100 N: contact closed and A1 within 5 % of the orbit's.
    assert code[(100.0, 0.05)] == "valid"
    assert abs(float(ds.tidf_a1_error.sel(normal_load=100.0, arm_length=0.05))) < dff.ACCURACY


def test_validity_map_no_root_below_the_hopf_load():
    ds = dff.tidf_validity_map([10.0], [0.072])
    assert dff.VALIDITY_NAMES[int(ds.tidf_validity.values.ravel()[0])] == "no_root"


def test_newton_basin_converges_near_the_root_and_fails_far_away():
    ds = dff.newton_basin_map([-0.3, 0.0, 0.02], [0.1, 1.0, 1.05])
    code = ds.newton.values
    assert code[1, 1] == 0 and code[2, 2] == 0  # the root itself and a 2-5 % perturbation converge to it
    assert code[0, 0] != 0  # 30 % low in frequency with a tenth of the amplitude: not to the root
    assert np.all(ds.iterations.values >= 0)


def test_maps_are_written(tmp_path):
    r = dff.tidf_failure_maps(tmp_path, quick=True)
    for name in ("failure_tidf_validity", "failure_tidf_newton"):
        assert (tmp_path / f"{name}.png").stat().st_size > 1000
        assert (tmp_path / f"{name}.nc").exists()
    assert sum(r["counts"]["failure_tidf_validity"].values()) == 18


def test_model_cost_numbers(tmp_path):
    from tribosweep.bench.model_cost import model_cost

    r = model_cost(tmp_path, quick=True)
    d = r["numbers"]
    assert d["points"] == 12 and d["orbits"] >= 5
    # The describing function is cheaper than integrating and within 10 % of the orbits (MODEL.md §6).
    assert d["tidf_ms_per_point"] < d["transient_ms_per_point"]
    assert d["tidf_a1_error_max"] < 0.10
    # auto decides every settled point as the transient does.
    assert d["regime_agreement"] == 1.0 and d["settled_points"] >= 8
    assert (tmp_path / "model_cost.png").stat().st_size > 1000
