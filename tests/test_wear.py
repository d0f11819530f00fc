"""Mild-wear model (MODEL.md §8) and the appendix-3 arithmetic (MODEL.md §9)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tribosweep as ts
from tribosweep import _wear
from tribosweep._wear import (
    A_APP,
    BETA,
    E_EFF,
    L1,
    SIGMA,
    WearCalibration,
    WearReference,
    appendix3_energy_balance,
    calibrated_wear_rate,
    effective_modulus,
    normal_mode_frequency_hz,
    relative_wear_rate,
    slide_frequency_hz,
)


def test_constants():
    assert L1 == pytest.approx(0.514e-2, rel=1e-3)
    assert slide_frequency_hz(0.46) == pytest.approx(89.5, abs=0.05)
    assert E_EFF / 1e9 == pytest.approx(74.4, abs=0.05)
    assert effective_modulus(207e9, 0.3, 103e9, 0.26) == E_EFF
    assert BETA == pytest.approx(L1**2 / (4 * SIGMA))
    assert SIGMA == pytest.approx(0.026e-3 * 1e-3)
    assert 20.0 / A_APP / 1e6 == pytest.approx(1.02, abs=0.005)  # nominal pressure at 20 N on the 5 mm pin
    np.testing.assert_allclose(slide_frequency_hz(np.array([0.46, 0.6])), [0.46 / L1, 0.6 / L1])


def test_normal_mode_frequency_at_seed(seed_values):
    f = normal_mode_frequency_hz(ts.SliderModel())
    assert f == pytest.approx(seed_values["normal_mode_frequency_hz_seed"], abs=0.05)
    assert f == pytest.approx(seed_values["linear_eigenvalues_seed"][2][1] / (2 * math.pi), rel=1e-5)
    assert WearReference().frequency_hz() == f


def test_relative_rate_is_one_at_the_reference():
    f = normal_mode_frequency_hz(ts.SliderModel())
    assert relative_wear_rate(84.46, 0.46, f) == pytest.approx(1.0, rel=1e-14)
    assert relative_wear_rate(50.0, 1.0, 300.0, reference_load=50.0, reference_speed=1.0,
                              reference_frequency_hz=300.0) == pytest.approx(1.0, rel=1e-14)  # fmt: skip


def test_relative_rate_scales_linearly_with_load_at_fixed_frequency():
    loads = np.array([10.0, 20.0, 40.0, 80.0])
    r = relative_wear_rate(loads, 0.46, 229.2, reference_frequency_hz=229.2)
    np.testing.assert_allclose(r / r[0], loads / loads[0], rtol=1e-14)


def test_relative_rate_speed_and_frequency_dependence():
    f_ref = 229.2
    # (V_ref/V)(f + V/l_1)/(f_ref + V_ref/l_1)
    v = 0.92
    expected = (0.46 / v) * (f_ref + v / L1) / (f_ref + 0.46 / L1)
    assert relative_wear_rate(84.46, v, f_ref, reference_frequency_hz=f_ref) == pytest.approx(expected)
    assert relative_wear_rate(84.46, 0.46, 2 * f_ref, reference_frequency_hz=f_ref) > 1


def test_appendix3_arithmetic(seed_values):
    ref = seed_values["appendix3_K3"]
    r = appendix3_energy_balance()
    assert r["phi0"] == pytest.approx(ref["phi0_rad"], abs=5e-5)
    assert r["c2"] == pytest.approx(ref["c2_Ns"], abs=5e-4)
    assert r["W_s"] == pytest.approx(ref["W_s_J"], abs=5e-4)
    assert r["W_d"] == pytest.approx(ref["W_d_J"], abs=5e-4)
    assert r["W_s"] == pytest.approx(r["W_d"], rel=1e-12)  # identically, not by luck
    # The report's rounded phi0 = 0.128 gives its c2 = 1.133.
    w = 2 * math.pi * 86.25
    assert 78.62 / (w * 0.128) == pytest.approx(ref["c2_Ns_with_report_rounded_phi0"], abs=5e-4)


def test_calibration_by_slope():
    c = WearCalibration(b_w=2e-9)
    f = 229.2
    assert calibrated_wear_rate(c, 84.46, 0.46, f) == pytest.approx(2e-9 * (f + 0.46 / L1))
    # Proportional to the relative rate.
    r = calibrated_wear_rate(c, [20.0, 84.46], 0.46, [300.0, f]) / calibrated_wear_rate(c, 84.46, 0.46, f)
    np.testing.assert_allclose(r, relative_wear_rate([20.0, 84.46], 0.46, [300.0, f], reference_frequency_hz=f))


def test_calibration_by_cycles_eq13():
    c = WearCalibration(cycles_to_failure=1e3, particle_volume=1e-15)
    w = calibrated_wear_rate(c, 84.46, 0.46, 229.2)
    a_t = 84.46 * math.sqrt(math.pi * BETA / SIGMA) / E_EFF
    assert w == pytest.approx(a_t * 5250.0 * 1e-15 * (229.2 + 0.46 / L1) / (1e3 * A_APP * 0.46))
    w2 = calibrated_wear_rate(c.as_dict() | {"cycles_to_failure": 2e3}, 84.46, 0.46, 229.2)
    assert w2 == pytest.approx(w / 2)


@pytest.mark.parametrize(
    "kwargs",
    [{}, {"b_w": 1.0, "cycles_to_failure": 1.0, "particle_volume": 1.0}, {"cycles_to_failure": 10.0},
     {"b_w": -1.0}, {"b_w": float("nan")}, {"b_w": 1.0, "normal_load": 0.0}],
)  # fmt: skip
def test_bad_calibrations(kwargs):
    with pytest.raises(ValueError, match="WearCalibration"):
        WearCalibration(**kwargs)


def test_bad_reference():
    with pytest.raises(ValueError, match="WearReference.arm_length"):
        WearReference(arm_length=-0.1)


def test_caveats_are_documented():
    for text in (_wear.__doc__, _wear.WEAR_CAVEATS):
        assert "negative" in text and "|a_w|" in text and "mild" in text
    assert "self-excited" in _wear.__doc__


def test_sweep_wear_is_one_at_the_reference_and_nan_outside_the_mild_regime():
    ds = ts.sweep(normal_load=[10.0, 84.46], strategy="linear", progress=False)
    rel = ds.wear_rate_relative.sel(arm_length=0.072, sliding_speed=0.46).values
    regime = ds.regime.sel(arm_length=0.072, sliding_speed=0.46).values
    assert regime.tolist() == [ts.REGIME_NAMES.index("unstable_undetermined"), 0]
    assert math.isnan(rel[0]) and rel[1] == pytest.approx(1.0, rel=1e-12)
    appl = ds.wear_applicability.sel(arm_length=0.072, sliding_speed=0.46).values
    names = ds.wear_applicability.attrs["flag_meanings"].split()
    assert [names[a] for a in appl] == ["outside_mild_wear_regime", "mild_wear_regime"]
    assert "negative" in ds.attrs["wear_model_caveats"]
    assert "wear_rate" not in ds


def test_sweep_wear_reference_and_calibration_options():
    ref = WearReference(normal_load=50.0, arm_length=0.1, sliding_speed=0.46)
    ds = ts.sweep(normal_load=[50.0], arm_length=[0.1], strategy="linear", progress=False, wear_reference=ref,
                  wear_calibration=WearCalibration(b_w=1e-9, normal_load=50.0))  # fmt: skip
    assert ds.wear_rate_relative.item() == pytest.approx(1.0, rel=1e-12)
    f = ds.normal_mode_frequency.item()
    assert ds.wear_rate.item() == pytest.approx(1e-9 * (f + 0.46 / L1), rel=1e-12)
    assert ds.wear_rate.attrs["units"] == "kg m-1"
    assert ds.attrs["wear_reference_normal_load"] == 50.0
