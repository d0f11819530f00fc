"""Shooting near a period doubling (issue 5): the flip is detected per orbit and mapped.

Unilateral contact at 80 N: the bouncing cycle's real Floquet multiplier crosses -1 near
mu = 0.4206 and a stable cycle of twice the period takes over (transients and shooting agree).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import INSTABILITY_NAMES
from tribosweep._simulate import STATE_VARS
from tribosweep.bench import pd_failure as pf

LOAD = 80.0


def _settle(mu: float):
    m = ts.SliderModel(contact="unilateral", normal_load=LOAD, mu=mu)
    tr = ts.ensemble(m, pf.T_MAX, {"mu": [mu]}, y0=pf._start(m, np.array([LOAD])), steady=True, rtol=1e-9,
                     periodic_tol=1e-6)  # fmt: skip
    assert ts.OUTCOME_NAMES[int(tr.outcome[0])] == "periodic"
    y = np.array([float(tr[f"{name}_end"][0]) for name, _, _ in STATE_VARS])
    return m, y, float(tr.period[0])


@pytest.fixture(scope="module")
def branch():
    """The period-1 orbit at mu = 0.415 (from the transient) and its continuation to 0.4225."""
    m, y, period = _settle(0.415)
    before = ts.periodic_orbit(m, (y, period))
    past = ts.periodic_orbit(m.replace(mu=0.4225), (before.state0.values, float(before.period)))
    return before, past


def test_period_doubling_flag_fires_past_the_flip_and_is_silent_before(branch):
    before, past = branch
    assert int(before.status) == 0 and int(past.status) == 0
    # Benign: stable, no real multiplier near -1.
    assert bool(before.stable) and INSTABILITY_NAMES[int(before.instability)] == "stable"
    assert not bool(before.period_doubling)
    # Past the crossing Newton still converges, to an orbit unstable by a flip.
    assert not bool(past.stable) and INSTABILITY_NAMES[int(past.instability)] == "flip"
    assert bool(past.period_doubling)
    assert -1.2 < float(past.flip_multiplier) < -1.05
    mult = past.floquet_multipliers.values
    assert np.min(mult.real[np.abs(mult.imag) < 1e-8]) == pytest.approx(float(past.flip_multiplier))


def test_the_attractor_past_the_flip_has_twice_the_period(branch):
    _, past = branch
    m, y, period = _settle(0.4225)
    # The transient's cycle, independent of the shooting: twice the period-1 orbit's (1 %).
    assert period / float(past.period) == pytest.approx(2.0, rel=0.01)
    # Shooting with that period from the transient's section state finds it, stable.
    orbit2 = ts.periodic_orbit(m, (y, period))
    assert int(orbit2.status) == 0 and bool(orbit2.stable)
    assert float(orbit2.period) == pytest.approx(period, rel=1e-5)


def test_bifurcation_diagram_locates_the_flip():
    bd = pf.bifurcation_diagram(np.linspace(0.41, 0.4275, 8))
    mu_pd = pf.flip_crossing(bd)
    assert 0.4195 < mu_pd < 0.4215
    # Two maxima of z per period-1 cycle, four per period-2 cycle (distinct to 0.05 um).
    def distinct(row):
        v = np.sort(row[np.isfinite(row)])
        return 1 + int(np.sum(np.diff(v) > 0.05e-6))

    assert distinct(bd.z_peaks.sel(mu=0.41, method="nearest").values) == 2
    assert distinct(bd.z_peaks.sel(mu=0.425, method="nearest").values) == 4
    assert INSTABILITY_NAMES[int(bd.instability.sel(mu=0.425, method="nearest"))] == "flip"


def test_shooting_map_codes():
    ds = pf.shooting_pd_map([LOAD], [0.41, 0.425])
    code = {mu: pf.SHOOTING_NAMES[int(ds.shooting.sel(normal_load=LOAD, mu=mu))] for mu in (0.41, 0.425)}
    assert code[0.41] == "valid"
    # From the period-2 attractor's state with the mode's period, period-1 shooting does not give
    # the attractor: it fails or lands on the flip-unstable orbit. Never "valid".
    assert code[0.425] in ("not_converged", "flip_unstable")
    ratio = ds.attractor_period_ratio.sel(normal_load=LOAD)
    assert float(ratio.sel(mu=0.41)) == pytest.approx(1.0, abs=0.1)
    assert float(ratio.sel(mu=0.425)) == pytest.approx(2.0, abs=0.15)
    assert int(ds.attractor_orbit_stable.sel(normal_load=LOAD, mu=0.425)) == 1


def test_sweep_reports_the_doubled_period():
    ds = ts.sweep(normal_load=[LOAD], extra_axes={"mu": [0.41, 0.425]}, strategy="transient", progress=False)
    ratio = ds.cycle_period_ratio.squeeze()
    assert float(ratio.sel(mu=0.41)) == pytest.approx(1.0, abs=0.1)
    assert float(ratio.sel(mu=0.425)) == pytest.approx(2.0, abs=0.15)


def test_maps_are_written(tmp_path, png_size, saved_figures, check_status_chart):
    r = pf.pd_failure_maps(tmp_path, quick=True)
    with xr.open_dataset(tmp_path / "failure_shooting_pd.nc") as smap, xr.open_dataset(tmp_path / "bifurcation_pd.nc") as bd:
        smap, bd = smap.load(), bd.load()
    code = np.array(pf.SHOOTING_NAMES)[smap.shooting.values]
    # Which points fail and why, against the transient's own cycle (time integration, not the shooting):
    # where it settled on a cycle of one mode period, period-1 shooting from its state finds a stable orbit
    # (valid, or near_flip beside the doubling); where it settled on twice the period, period-1 shooting
    # never passes (it fails, or lands on the flip-unstable orbit); where it found no cycle, nothing is shot.
    # The ratio is the cycle's period over the linear mode's: a few per cent off a whole number by the
    # cycle's nonlinear frequency shift, against a gap of 1 between the classes; 0.3 is the map's own cutoff.
    ratio = smap.attractor_period_ratio.values
    one, two, none = np.abs(ratio - 1) < 0.3, np.abs(ratio - 2) < 0.3, np.isnan(ratio)
    assert np.all(one | two | none), ratio
    assert np.all(np.isin(code[one], ["valid", "near_flip"])), code
    assert np.all(np.isin(code[two], ["flip_unstable", "not_converged"])), code
    assert np.all(code[none] == "no_cycle"), code
    assert one.any() and two.any()  # both sides of the doubling are on the quick grid
    assert r["counts"]["failure_shooting_pd"] == {n: int((code == n).sum()) for n in pf.SHOOTING_NAMES}
    assert r["numbers"]["period_2_points"] == int(two.sum())
    assert 0.4195 < r["numbers"]["flip_mu"] < 0.4215
    # The charts (6.4 x 4.6 in at 100 dpi). The map: a label at each failing cell, white circles on the
    # period-2 points; the diagram: the branch's flip multiplier against mu, its crossing of -1 marked.
    for name in ("failure_shooting_pd", "bifurcation_pd"):
        assert png_size(tmp_path / f"{name}.png") == (640, 460)
    ax = saved_figures["failure_shooting_pd.png"].axes[0]
    check_status_chart(ax, smap, "shooting", pf.SHOOTING_NAMES)
    (circles,) = [ln for ln in ax.lines if ln.get_label() == "period-2 attractor"]
    il, im = np.nonzero(two)
    assert sorted(zip(circles.get_xdata(), circles.get_ydata())) == sorted(
        zip(smap.mu.values[im], smap.normal_load.values[il]))
    fig = saved_figures["bifurcation_pd.png"]
    (branch,) = [ln for ax_ in fig.axes for ln in ax_.lines if ln.get_label() == "flip multiplier, period-1 branch"]
    np.testing.assert_array_equal(branch.get_xdata(), bd.mu.values)
    np.testing.assert_array_equal(branch.get_ydata(), bd.flip_multiplier.values)
    vlines = [ln.get_xdata()[0] for ln in fig.axes[0].lines if ln.get_linestyle() == ":"]
    assert vlines == [pytest.approx(r["numbers"]["flip_mu"], rel=1e-12)]


def test_bifurcation_diagram_rejects_bad_mu():
    with pytest.raises(ValueError, match="mu"):
        pf.bifurcation_diagram([0.42, 0.41])
    with pytest.raises(ValueError, match="contact"):
        pf.shooting_pd_map([80.0], [0.41], model=ts.SliderModel(contact="bilateral"))
