"""The switch friction law (event-driven stick-slip, Leine et al. 1998) against independent answers.

- Trajectories against ``tribosweep.bench.reference_switch.SwitchReference``: the same switch model written separately with
  scipy's ``solve_ivp`` (DOP853 at rtol 1e-12) and its own directional, terminal events.
- Floquet multipliers of stick-slip cycles from the shooting (saltation matrices at every stick,
  slip and transition switch) against the finite-difference monodromy of the integrated flow.

The scenes stick for real: a low sliding speed (0.01 m/s, 1/46 of the seed's) and a Stribeck curve
from mu_s = 0.3 (or 0.6) down to mu = 0.215 at V make steady sliding unstable, and the pin then
spends most of each cycle stuck to the disk (v_r held at the band edge) before the spring force
tears it loose. Started stuck (v_r = 0, mid-band), a run crosses every kind of switch of the law:
stick -> transition -> slip at the start, slip -> stick and stick -> slip on every cycle, and in the
second scene a transition across the whole band into reverse slip (v_r < 0). The cycles are stable
or only weakly unstable, so two correct solvers stay together over many cycles and the comparison
measures the switching, not chaos.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tribosweep import SliderModel, _core
from tribosweep._frequency import periodic_orbit
from tribosweep.bench.reference_switch import SwitchReference

STICK_SLIP = dict(contact="bilateral", friction_law="switch", sliding_speed=0.01, mu_static=0.3, stribeck_velocity=0.02)
REVERSING = dict(STICK_SLIP, mu_static=0.6, stribeck_velocity=0.005)


def _scales(m: SliderModel) -> np.ndarray:
    z = abs(m.static_point()[0])
    w, arm = m.omega_torsion, m.moment_arm
    return np.array([z, z * w, z, z * w, z / arm, z / arm * w])


@pytest.mark.parametrize("cfg", [STICK_SLIP, REVERSING], ids=["stick_slip", "reversing"])
@pytest.mark.parametrize("method", ["dop853", "rodas4"])
def test_switch_law_matches_scipy_event_reference(cfg, method):
    m = SliderModel(**cfg)
    y0 = np.zeros(6)
    y0[3] = m.sliding_speed  # v_r = 0: stuck, mid-band
    t_end = 0.3
    t_eval = np.linspace(0.0, t_end, 3001)
    ref = SwitchReference(m.values())
    y_ref, switches = ref.solve(y0, t_end, t_eval, rtol=1e-12, atol=1e-13 * _scales(m))
    assert np.isfinite(y_ref).all()
    # The scene really sticks, on every cycle: several stick phases, most of the time stuck.
    kinds = [(a, b) for _, a, b in switches]
    assert kinds[:2] == [("stick", "transition"), ("transition", "slip")]
    assert kinds.count(("slip", "stick")) >= 5, kinds
    v_r = m.sliding_speed - (y_ref[:, 3] + m.torsion_sign * m.moment_arm * y_ref[:, 5])
    assert np.mean(np.abs(v_r) <= 1.001 * m.stick_band) > 0.5
    if cfg is REVERSING:
        # A transition across the band into reverse slip.
        assert v_r.min() < -1.001 * m.stick_band
        assert kinds.count(("stick", "transition")) >= 3

    rtol = 1e-12 if method == "dop853" else 1e-10
    out = _core.simulate(m.values(), m.contact, m.friction_law, y0, t_end, method, rtol, t_eval=t_eval)
    assert out["status"][0] == 0
    y = np.asarray(out["y"])
    amplitude = np.abs(y_ref).max(axis=0)
    err = np.abs(y - y_ref).max(axis=0) / amplitude
    # Seen: 2e-9 to 3e-8 on every component.
    assert (err < 1e-6).all(), err


def _cycle(m: SliderModel) -> tuple[np.ndarray, float]:
    """A state on the attracting (or slowly leaving) stick-slip cycle, in slip, and its period guess."""
    y0 = np.zeros(6)
    y0[3] = m.sliding_speed
    t_eval = np.linspace(0.8, 1.0, 20001)
    out = _core.simulate(m.values(), m.contact, m.friction_law, y0, 1.0, "dop853", 1e-11, t_eval=t_eval)
    y = np.asarray(out["y"])
    v_r = m.sliding_speed - (y[:, 3] + m.torsion_sign * m.moment_arm * y[:, 5])
    slip = np.abs(v_r) > 2.0 * m.stick_band
    onsets = t_eval[1:][slip[:-1] & ~slip[1:]]  # slip -> stick
    # A maximum of z (zd from + to -) well inside a slip phase: shooting starts just before it.
    zd = y[:, 1]
    deep = np.convolve(~slip, np.ones(13), mode="same") == 0  # slipping for 6 samples either side
    k = np.flatnonzero((zd[:-1] > 0) & (zd[1:] <= 0) & deep[:-1])
    assert k.size and onsets.size >= 2
    return y[k[-1] - 5], float(onsets[-1] - onsets[-2])


def _fd_monodromy(m: SliderModel, y0: np.ndarray, period: float, rel: float = 1e-4) -> np.ndarray:
    """Central differences of the flow map over one period (each column 2 runs at rtol 1e-13)."""
    sc = _scales(m)
    phi = np.empty((6, 6))
    for j in range(6):
        h = rel * sc[j]
        ends = []
        for sgn in (1.0, -1.0):
            y = np.array(y0, dtype=float)
            y[j] += sgn * h
            out = _core.simulate(m.values(), m.contact, m.friction_law, y, period, "dop853", 1e-13)
            assert out["status"][0] == 0
            ends.append(np.asarray(out["y_end"]).ravel())
        phi[:, j] = (ends[0] - ends[1]) / (2.0 * h)
    return phi


@pytest.mark.parametrize(
    ("cfg", "stable"),
    [
        (STICK_SLIP, True),  # largest non-trivial |rho| 0.9609
        (dict(STICK_SLIP, normal_load=20.0, mu=0.23, mu_static=0.32), False),  # 1.0080 (complex pair)
        (dict(STICK_SLIP, normal_load=20.0, contact="unilateral"), False),  # 1.0488, with contact loss
    ],
    ids=["stable", "unstable_bilateral", "unstable_unilateral"],
)
def test_stick_slip_floquet_multipliers_match_finite_differences(cfg, stable):
    m = SliderModel(**cfg)
    y0, period = _cycle(m)
    ds = periodic_orbit(m, (y0, period))
    assert int(ds.status) == 0, int(ds.status)
    assert int(ds.n_switches) >= 2  # at least one stick phase per period
    moduli = ds.floquet_moduli.values
    trivial = int(np.argmin(np.abs(ds.floquet_multipliers.values - 1.0)))
    nontrivial = np.delete(moduli, trivial)
    # Entering stick projects every perturbation onto the band edge: one multiplier is zero.
    assert nontrivial.min() < 1e-8
    if stable:
        assert nontrivial.max() < 0.99, moduli
        assert bool(ds.stable)
    else:
        assert nontrivial.max() > 1.005, moduli
        assert not bool(ds.stable)

    phi = _fd_monodromy(m, ds.state0.values, float(ds.period))
    fd = np.sort(np.abs(np.linalg.eigvals(phi)))[::-1]
    # Seen: within 7e-5 (event location to 1e-13 s over perturbations of 1e-4 of each scale).
    np.testing.assert_allclose(fd, moduli, rtol=0, atol=5e-4)
    assert math.isclose(fd[0], moduli[0], abs_tol=5e-4)


def test_switch_law_arguments():
    m = SliderModel(contact="bilateral", friction_law="switch", mu_static=0.3, stick_band=1e-5)
    assert m.values()["stick_band"] == 1e-5
    with pytest.raises(ValueError, match=r"mu_static = 0\.2 .*>= mu"):
        SliderModel(contact="bilateral", friction_law="switch", mu_static=0.2)
    with pytest.raises(ValueError, match=r"stick_band = 0\.5 .*below sliding_speed"):
        SliderModel(contact="bilateral", friction_law="switch", stick_band=0.5)
    with pytest.raises(ValueError, match=r"stick_band = -1\.0 .*> 0"):
        SliderModel(contact="bilateral", stick_band=-1.0)
    with pytest.raises(ValueError, match=r"friction_law = 'stick' .*'switch'"):
        SliderModel(contact="bilateral", friction_law="stick")
    with pytest.raises(ValueError, match=r"friction_law = \"stick\" .*'switch'"):
        _core.validate_params(SliderModel(contact="bilateral").values(), "bilateral", "stick")
