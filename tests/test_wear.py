"""Mild-wear model (docs/model.md §8) and the appendix-3 arithmetic (docs/model.md §9)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import tribosweep as ts
from tribosweep import _wear
from tribosweep._apparatus import apparatus_model
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
from tribosweep.bench import reference


def test_constants_against_the_report():
    # The report's printed inputs (appendix 4): tau_s = |b/a| = 0.857e-2 s at the wear runs' 60 cm/s;
    # rms roughness 0.026e-3 mm; pin 207 GPa / 0.3, disk 103 GPa / 0.26; a 5 mm pin.
    # l_1 = tau_s V = 0.857e-2 s x 0.6 m/s = 5.142e-3 m (the report prints 0.51 cm).
    assert L1 == pytest.approx(5.142e-3, rel=1e-12)  # four exact digits times one: rounding only
    assert SIGMA == pytest.approx(0.026e-3 * 1e-3, rel=1e-12)  # 0.026e-3 mm in metres
    # f_s = V / l_1: at 0.46 m/s docs/model.md's 89.5 Hz; at the fit speed 0.6 m/s it is 1/tau_s = 116.686 Hz,
    # the report's 116.7 Hz of b_w (f - 116.7 Hz). abs 0.05: both are printed to 0.1 Hz.
    np.testing.assert_allclose(slide_frequency_hz(np.array([0.46, 0.6])), [89.5, 116.7], atol=0.05)
    assert slide_frequency_hz(0.6) == pytest.approx(1 / 0.857e-2, rel=1e-12)
    # 1/E' = (1 - 0.3^2)/207 GPa + (1 - 0.26^2)/103 GPa = (4.396135e-3 + 9.052427e-3)/GPa, by hand:
    # E' = 74.3574 GPa (docs/model.md 74.4; the report prints 74.6). rel 1e-6: the hand value has 6 digits.
    assert E_EFF == pytest.approx(74.3574e9, rel=1e-6)
    assert effective_modulus(103e9, 0.26, 207e9, 0.3) == pytest.approx(74.3574e9, rel=1e-6)  # symmetric
    # beta = l_1^2 / (4 sigma) = (5.142e-3 m)^2 / (4 x 2.6e-8 m) = 2.6440164e-5 / 1.04e-7 = 254.2323 m, by hand.
    assert BETA == pytest.approx(254.2323, rel=1e-6)  # the hand value has 7 digits
    # The report prints beta = 2.47e4 cm from l_1 = 0.51 cm and sigma = 0.026e-3 mm: two-digit inputs, whose
    # rounding alone (half a unit: 0.005/0.51 twice in l_1^2, 0.0005/0.026 in sigma) moves beta by 3.9 %.
    assert BETA == pytest.approx(247.0, rel=2 * 0.005 / 0.51 + 0.0005 / 0.026)
    assert 20.0 / A_APP / 1e6 == pytest.approx(1.02, abs=0.005)  # docs/model.md: 1.02 MPa at 20 N on the 5 mm pin


def test_normal_mode_frequency_at_seed(seed_values):
    f = normal_mode_frequency_hz(ts.SliderModel(contact="bilateral"))
    assert f == pytest.approx(seed_values["normal_mode_frequency_hz_seed"], abs=0.05)
    assert f == pytest.approx(seed_values["linear_eigenvalues_seed"][2][1] / (2 * math.pi), rel=1e-5)


def test_reference_frequency_is_the_normal_mode_of_the_apparatus():
    # f_ref away from the seed (50 N, 5 cm arm, 1 m/s) against the independent numpy reference: eigenvalues
    # of its finite-difference Jacobian; the normal mode is the fastest pair (in contact K_s/m = 2.1e6 1/s^2
    # puts it near 1420 rad/s, twice the torsion mode's 756). The central difference of the quadratic
    # right-hand side is exact up to rounding (about 1e-13 relative), hence rel 1e-9.
    ref = WearReference(normal_load=50.0, arm_length=0.05, sliding_speed=1.0)
    lam = reference.linear_eigenvalues(apparatus_model(50.0, 0.05, 1.0).values())
    f_normal = float(np.max(np.abs(lam.imag))) / (2 * math.pi)
    assert ref.frequency_hz() == pytest.approx(f_normal, rel=1e-9)
    # The seed reference gives docs/model.md's 229.2 Hz (printed to 0.1 Hz).
    assert WearReference().frequency_hz() == pytest.approx(229.2, abs=0.05)


def test_relative_rate_is_one_at_the_reference():
    f = normal_mode_frequency_hz(ts.SliderModel(contact="bilateral"))
    assert relative_wear_rate(84.46, 0.46, f) == pytest.approx(1.0, rel=1e-14)
    assert relative_wear_rate(50.0, 1.0, 300.0, reference_load=50.0, reference_speed=1.0,
                              reference_frequency_hz=300.0) == pytest.approx(1.0, rel=1e-14)  # fmt: skip


def test_relative_rate_scales_linearly_with_load_at_fixed_frequency():
    loads = np.array([10.0, 20.0, 40.0, 80.0])
    r = relative_wear_rate(loads, 0.46, 229.2, reference_frequency_hz=229.2)
    np.testing.assert_allclose(r / r[0], loads / loads[0], rtol=1e-14)


def test_relative_rate_speed_and_frequency_dependence():
    f_ref = 229.2
    # (V_ref/V)(f + V/l_1)/(f_ref + V_ref/l_1) at twice the speed, by hand with l_1 = 5.142e-3 m:
    # 0.5 x (229.2 + 178.9187) / (229.2 + 89.4594) = 0.640368 (rel 1e-6: six digits).
    assert relative_wear_rate(84.46, 0.92, f_ref, reference_frequency_hz=f_ref) == pytest.approx(0.640368, rel=1e-6)
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


def test_sweep_mild_wear_fraction_comes_from_the_census():
    """Wear uses the census fractions: mild wear holds after the disturbances that return to sliding.

    At the seed (unilateral contact) sliding is stable and coexists with the bouncing cycle, so the
    mild-wear model holds only in part: its fraction is the census's basin stability, with the
    census's binomial standard error. At 20 N sliding is linearly unstable: no disturbance
    returns, exactly (fraction 0, SE 0).
    """
    ds = ts.sweep(normal_load=[20.0, 84.46], arm_length=[0.072], sliding_speed=[0.46], samples=64, progress=False,
                  model=ts.SliderModel(contact="unilateral"))  # fmt: skip
    frac = ds.mild_wear_fraction.values.ravel()
    se = ds.mild_wear_fraction_se.values.ravel()
    names = ds.wear_applicability.attrs["flag_meanings"].split()
    appl = [names[a] for a in ds.wear_applicability.values.ravel()]
    assert float(ds.growth_rate.values.ravel()[0]) > 0
    assert (frac[0], se[0]) == (0.0, 0.0) and appl[0] == "outside_mild_wear_regime"
    seed = ds.isel(normal_load=1).squeeze()
    assert frac[1] == seed.basin_stability.item()
    assert se[1] == seed.basin_fraction_se.sel(attractor=0).item()
    # Coexistence: the fraction is strictly inside (0, 1), more than 3 standard errors from both ends
    # (the seed's basin stability is about 0.7: test_census.py finds sliding and the cycle both).
    assert 3 * se[1] < frac[1] < 1 - 3 * se[1]
    assert appl[1] == "mild_wear_in_part"
    assert seed.wear_rate_relative.item() == pytest.approx(1.0, rel=1e-12)  # the rate while sliding
