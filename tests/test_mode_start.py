"""The start on the least stable linear mode (``stages.mode_start``): ``|z|`` set, other components held in
proportion (``MODE_START_CAP``)."""

from __future__ import annotations

import numpy as np
import pytest

import tribosweep as ts
from tribosweep import _core
from tribosweep._irregular import characteristic_sizes
from tribosweep._sweep import stages


def _start(model: ts.SliderModel) -> tuple[np.ndarray, np.ndarray, float]:
    """The sweep's start at ``model`` (``|z| = |z_st|``), the characteristic sizes and ``|z_st|``."""
    vals = model.values()
    lin = _core.linear_stability(vals, model.contact, model.friction_law, [], np.zeros((1, 0)), threads=1)
    assert not lin["stable"][0]
    full = {k: np.array([v]) for k, v in vals.items()}
    z_st = abs(float(stages.static_penetration(full, np.array([0]))[0]))
    y0 = stages.mode_start(full, model.friction_law, np.array([0]), np.array([z_st]), np.asarray(lin["eigenvalues"]))
    return y0[0], characteristic_sizes(full)[0], z_st


def test_a_torsion_mode_start_has_the_static_penetration_in_z():
    # Below the seed's Hopf load (24.9 N): the self-excited torsion mode, phi about 5.5 of its size
    # for z at 1. The cap is not reached.
    y0, size, z_st = _start(ts.SliderModel(contact="unilateral", normal_load=15.0))
    assert abs(y0[0]) == z_st
    assert np.abs(y0 / size).max() == pytest.approx(5.5, rel=0.05)


def test_a_frictional_mode_start_is_held_to_the_cap():
    # A short arm puts the torsion mode out of reach: at 0.1 m/s on a falling Stribeck curve the least
    # stable mode is the frictional one (x at omega_friction, 306 rad/s), with little z. Scaled by |z|
    # alone its x' was some 400 characteristic sizes, 4 m/s against the 0.1 m/s of sliding.
    m = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3, sliding_speed=0.1, moment_arm=0.01)
    y0, size, z_st = _start(m)
    rel = np.abs(y0 / size)
    assert rel.max() == pytest.approx(stages.MODE_START_CAP, rel=1e-12)
    assert np.argmax(rel) == 3  # x'
    assert 0.0 < abs(y0[0]) < 0.1 * z_st  # z held well below |z_st| with it
    # The mode's shape is kept: x' / z as on the mode, whatever the scale.
    free = stages.mode_start({k: np.array([v]) for k, v in m.values().items()}, m.friction_law, np.array([0]),
                             np.array([1e-30]), np.asarray(_core.linear_stability(
                                 m.values(), m.contact, m.friction_law, [], np.zeros((1, 0)), threads=1)["eigenvalues"]))[0]  # fmt: skip
    np.testing.assert_allclose(y0 / y0[0], free / free[0], rtol=1e-12)
