"""Apparatus model (docs/model.md §7): arm-length power laws fitted to the report's tables, flags, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribosweep import SliderModel, _apparatus
from tribosweep._apparatus import (
    ARM_EXPONENTS,
    ARM_FIT,
    ARM_FIT_MAX_REL_ERROR,
    ARM_TABLES,
    L_SEED,
    apparatus_model,
    arm_extrapolated,
    arm_frequencies,
    load_extrapolated,
)

#: The largest relative error of each fit as the module docstring's table prints it (to 0.1 %).
DOCUMENTED_ERROR = {
    ("normal", "appendix4_table2"): 0.034,
    ("normal", "appendix3_table1"): 0.057,
    ("friction", "appendix3_table1"): 0.021,
    ("torsion", "appendix3_table1"): 0.022,
}
#: Column of each mode in seed_values.json's copy of the report's tables.
_COLUMN = {"normal": "normal_hz", "friction": "frictional_hz", "torsion": "torsional_hz"}


def _independent_fit(seed_values, mode):
    """scipy's closed-form regression of log f on log l over the report's tables as seed_values.json
    holds them (not the module's copy): exponent, prefactor [Hz m^-p] and the (arm [m], f [Hz]) of each table."""
    from scipy.stats import linregress

    tables = {name: (np.array(t["arm_cm"]) / 100, np.array(t[_COLUMN[mode]], dtype=float))
              for name, t in seed_values["arm_tables"].items() if _COLUMN[mode] in t}  # fmt: skip
    arm = np.concatenate([a for a, _ in tables.values()])
    f = np.concatenate([f for _, f in tables.values()])
    r = linregress(np.log(arm), np.log(f))
    return r.slope, math.exp(r.intercept), tables


def test_tables_are_the_reports(seed_values):
    ref = seed_values["arm_tables"]
    a3, a4 = ref["appendix3_table1"], ref["appendix4_table2"]
    np.testing.assert_allclose(ARM_TABLES["appendix3_table1"]["arm_length"], np.array(a3["arm_cm"]) / 100)
    np.testing.assert_allclose(ARM_TABLES["appendix4_table2"]["arm_length"], np.array(a4["arm_cm"]) / 100)
    assert ARM_TABLES["appendix3_table1"]["normal"] == tuple(a3["normal_hz"])
    assert ARM_TABLES["appendix3_table1"]["friction"] == tuple(a3["frictional_hz"])
    assert ARM_TABLES["appendix3_table1"]["torsion"] == tuple(a3["torsional_hz"])
    assert ARM_TABLES["appendix4_table2"]["normal"] == tuple(a4["normal_hz"])


@pytest.mark.parametrize(("mode", "expected"), [("normal", -0.68), ("friction", -0.82), ("torsion", -0.43)])
def test_exponents_near_model_md(mode, expected):
    # The exponents of the spec this reading started from, printed to two decimals: half a unit of the last.
    assert ARM_EXPONENTS[mode] == pytest.approx(expected, abs=0.005)


@pytest.mark.parametrize("mode", ["normal", "friction", "torsion"])
def test_fit_is_least_squares_on_log_log(seed_values, mode):
    # The module solves by SVD (lstsq), scipy by the closed-form normal equations: the same two-column
    # problem, whose condition number is small (log l spans 0.9), agrees to about 1e-14; rel 1e-9 leaves
    # room without hanging on the last bits.
    slope, prefactor, _ = _independent_fit(seed_values, mode)
    assert ARM_EXPONENTS[mode] == pytest.approx(slope, rel=1e-9)
    assert ARM_FIT[mode]["prefactor"] == pytest.approx(prefactor, rel=1e-9)


@pytest.mark.parametrize("key", list(DOCUMENTED_ERROR))
def test_fit_error_against_an_independent_fit_and_the_documented_figure(seed_values, key):
    mode, table = key
    slope, prefactor, tables = _independent_fit(seed_values, mode)
    arm, measured = tables[table]
    err = float(np.max(np.abs(prefactor * arm**slope / measured - 1)))
    assert ARM_FIT_MAX_REL_ERROR[key] == pytest.approx(err, rel=1e-9)  # as the fit above
    # The docstring's table prints each error to 0.1 %: it must be that figure, to half its last digit.
    assert err == pytest.approx(DOCUMENTED_ERROR[key], abs=0.0005)
    assert f"{100 * DOCUMENTED_ERROR[key]:.1f} %" in _apparatus.__doc__


def test_seed_arm_length_gives_the_seed_exactly():
    seed = SliderModel()  # apparatus_model's default base: the seed with the default contact law
    w = arm_frequencies(L_SEED)
    assert w["omega_normal"] == seed.omega_normal
    assert w["omega_friction"] == seed.omega_friction
    assert w["omega_torsion"] == seed.omega_torsion
    assert apparatus_model(84.46, 0.072, 0.46) == seed


def test_power_law_scaling_and_other_fields_unchanged():
    seed = SliderModel(contact="bilateral")
    m = apparatus_model(50.0, 0.05, 1.0)
    r = 0.05 / L_SEED
    assert m.omega_normal == pytest.approx(seed.omega_normal * r ** ARM_EXPONENTS["normal"], rel=1e-14)
    assert m.omega_friction == pytest.approx(seed.omega_friction * r ** ARM_EXPONENTS["friction"], rel=1e-14)
    assert m.omega_torsion == pytest.approx(seed.omega_torsion * r ** ARM_EXPONENTS["torsion"], rel=1e-14)
    assert (m.normal_load, m.sliding_speed) == (50.0, 1.0)
    for name in ("mass", "inertia", "moment_arm", "zeta_normal", "zeta_friction", "zeta_torsion",
                 "contact_stiffness", "contact_quadratic", "contact_damping", "twist_coupling", "mu"):  # fmt: skip
        assert getattr(m, name) == getattr(seed, name), name
    # A shorter arm is stiffer.
    assert m.omega_normal > seed.omega_normal


def test_vectorised_frequencies_match_scalar():
    # Bitwise: a sweep's point is the model apparatus_model() makes at its arm length (numpy's
    # SIMD power once made omega_friction differ by an ulp at 10.99 cm on an AVX-512 machine, and
    # with it the point's census samples).
    arm = np.concatenate([[0.04, 0.06, 0.072, 0.2, 0.1099], np.linspace(0.05, 0.127, 10), np.linspace(0.03, 0.3, 997)])
    w = arm_frequencies(arm)
    for i, a in enumerate(arm):
        one = arm_frequencies(float(a))
        for field in ("omega_normal", "omega_friction", "omega_torsion"):
            assert w[field][i].tobytes() == np.float64(one[field]).tobytes(), (field, a)


def test_base_model_is_kept():
    base = SliderModel(mu=0.3, contact="unilateral", omega_normal=400.0)
    m = apparatus_model(30.0, 0.1, 0.46, base=base)
    assert m.mu == 0.3 and m.contact == "unilateral"
    assert m.omega_normal == pytest.approx(400.0 * (0.1 / L_SEED) ** ARM_EXPONENTS["normal"])


def test_extrapolation_is_flagged_not_refused():
    np.testing.assert_array_equal(load_extrapolated([21.9, 22.0, 50.0, 93.0, 93.1]), [1, 0, 0, 0, 1])
    np.testing.assert_array_equal(arm_extrapolated([0.049, 0.05, 0.127, 0.128]), [1, 0, 0, 1])
    m = apparatus_model(250.0, 0.3, 2.0)  # far outside both ranges: computed
    assert m.normal_load == 250.0 and math.isfinite(m.omega_normal)


@pytest.mark.parametrize("name", ["normal_load", "arm_length", "sliding_speed"])
@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_impossible_values_are_rejected_naming_argument_value_and_range(name, bad):
    args = {"normal_load": 50.0, "arm_length": 0.07, "sliding_speed": 0.46}
    args[name] = bad
    with pytest.raises(ValueError, match=rf"{name} = {bad!r}.*> 0") as e:
        apparatus_model(**args)
    assert "finite" in str(e.value)


def test_array_argument_rejected_by_scalar_model():
    with pytest.raises(ValueError, match="arm_length"):
        apparatus_model(50.0, [0.05, 0.06], 0.46)


def test_module_docstring_states_the_fit():
    doc = _apparatus.__doc__
    for mode in ("normal", "frictional", "torsional"):
        assert mode in doc
    assert "-0.683" in doc and "-0.820" in doc and "-0.426" in doc
