"""Bad input raises ValueError naming the argument, its value and the valid range, before any work."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import tribosweep as ts


@pytest.mark.parametrize(
    "field, value, needle",
    [
        ("mass", 0.0, "> 0"),
        ("mass", -2.0, "> 0"),
        ("inertia", math.nan, "finite"),
        ("contact_stiffness", -1.0, "> 0"),
        ("contact_quadratic", -1.0, ">= 0"),
        ("contact_damping", -0.1, ">= 0"),
        ("zeta_torsion", -0.01, ">= 0"),
        ("mu", -0.2, ">= 0"),
        ("normal_load", 0.0, "> 0"),
        ("normal_load", math.inf, "finite"),
        ("normal_load", -5.0, "> 0"),
        ("sliding_speed", 0.0, "> 0"),
        ("omega_torsion", math.nan, "finite"),
        ("torsion_sign", 0.5, "-1 or +1"),
        ("twist_coupling", math.inf, "finite"),
    ],
)
def test_bad_model_parameter(field, value, needle):
    with pytest.raises(ValueError) as e:
        ts.SliderModel(**{field: value})
    msg = str(e.value)
    assert field in msg and needle in msg and str(value).lower() in msg.lower(), msg


def test_bad_categoricals():
    with pytest.raises(ValueError, match="contact.*bilateral"):
        ts.SliderModel(contact="sticky")
    with pytest.raises(ValueError, match="friction_law"):
        ts.SliderModel(contact="bilateral", friction_law="viscous")
    with pytest.raises(ValueError, match="mu_static"):
        ts.SliderModel(contact="bilateral", friction_law="coulomb", mu_static=5.0, mu=0.1, stribeck_velocity=10.0)


@pytest.mark.parametrize(
    "kwargs, needle",
    [
        ({"t_end": 0.0}, "t_end"),
        ({"t_end": -1.0}, "t_end"),
        ({"t_end": math.nan}, "t_end"),
        ({"rtol": 0.0}, "rtol"),
        ({"rtol": -1e-6}, "rtol"),
        ({"rtol": 2.0}, "rtol"),
        ({"atol": -1.0}, "atol"),
        ({"atol": [1e-9] * 5}, "atol"),
        ({"y0": [0.0] * 5}, "y0"),
        ({"y0": [math.nan] + [0.0] * 5}, "y0"),
        ({"t_eval": [0.0, 2.0]}, "t_eval"),
        ({"t_eval": [0.01, 0.005]}, "t_eval"),
        ({"method": "euler"}, "method"),
    ],
)
def test_bad_simulate_arguments(kwargs, needle):
    args = {"t_end": 0.01} | kwargs
    t_end = args.pop("t_end")
    with pytest.raises(ValueError, match=needle):
        ts.simulate(ts.SliderModel(contact="bilateral"), t_end, **args)


@pytest.mark.parametrize(
    "params, kwargs, needle",
    [
        ({"mu": [0.1, 0.2], "normal_load": [10.0]}, {}, "lengths must agree"),
        ({"no_such": [1.0]}, {}, "unknown parameter"),
        ({"mu": [[0.1, 0.2]]}, {}, "1-D"),
        ({"mu": [0.1, math.nan]}, {}, "finite"),
        ({"normal_load": [10.0, -3.0]}, {}, "normal_load"),
        ({"mu": [0.1, 0.2]}, {"y0": np.zeros((3, 6))}, "y0"),
        ({"mu": [0.1, 0.2]}, {"threads": 0}, "threads"),
        ({}, {}, "non-empty"),
    ],
)
def test_bad_ensemble_arguments(params, kwargs, needle):
    with pytest.raises(ValueError, match=needle):
        ts.ensemble(ts.SliderModel(contact="bilateral"), 0.01, params, **kwargs)


def test_model_is_frozen_and_replace_revalidates():
    m = ts.SliderModel(contact="bilateral")
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.mu = 0.3  # type: ignore[misc]
    assert m.replace(mu=0.3).mu == 0.3
    with pytest.raises(ValueError, match="mu"):
        m.replace(mu=-1.0)
    # mu_static follows mu unless given.
    assert m.replace(mu=0.3).values()["mu_static"] == 0.3
    # A field the model does not have: named, with the fields it has; the arm length is a hint.
    with pytest.raises(TypeError, match=r"no field 'mus' = 0.3; the fields are mass, .*stick_band"):
        m.replace(mus=0.3)
    with pytest.raises(TypeError, match=r"no field 'arm_length' = 0.11 \(.*apparatus_model"):
        m.replace(arm_length=0.11)


@pytest.mark.parametrize(
    "call",
    [
        lambda m: ts.simulate(m, 0.01),
        lambda m: ts.ensemble(m, 0.01, {"mu": [0.2]}),
        lambda m: ts.linear_stability(m),
        lambda m: ts.hopf_load(m),
        lambda m: ts.describing_function(m),
        lambda m: ts.periodic_orbit(m, None),
        lambda m: ts.census(m),
        lambda m: ts.sweep(m, progress=False),
    ],
    ids=["simulate", "ensemble", "linear_stability", "hopf_load", "describing_function", "periodic_orbit", "census",
         "sweep"],
)  # fmt: skip
def test_a_model_of_the_wrong_type_is_a_type_error_everywhere(call):
    with pytest.raises(TypeError, match="model = .* must be a tribosweep.SliderModel"):
        call({"mu": 0.2})
