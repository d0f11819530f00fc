"""Where the describing function fails, detected per point (issue 5): validity map and Newton basin."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import _core
from tribosweep._apparatus import apparatus_model
from tribosweep.bench import df_failure as dff
from tribosweep.bench import reference


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


def _expected_validity(loads, arms, a1_error):
    """The validity code of each point by criteria that do not go through the map's code: linear stability
    from the numpy reference (docs/model.md §6: where sliding is unstable the Hopf bifurcation is subcritical and
    the describing function has no root), and the root's two-harmonic waveform A0 + A1 sin psi +
    A2 sin(2 psi + theta) sampled here against |z_st| from the reference's static point (contact opens)."""
    base = ts.SliderModel(contact="bilateral")
    psi = np.linspace(0.0, 2 * np.pi, 3600, endpoint=False)
    code = np.empty((loads.size, arms.size), dtype=int)
    for i, f in enumerate(loads):
        for j, a in enumerate(arms):
            v = apparatus_model(float(f), float(a), 0.46, base=base).values()
            growth = float(np.max(reference.linear_eigenvalues(v).real))
            # Every point is far from the Hopf load (|growth| > 0.05 1/s, against eigenvalues exact to about
            # 1e-10 1/s): the verdict cannot hang on rounding.
            assert abs(growth) > 0.05, (f, a, growth)
            if growth > 0:
                code[i, j] = dff.VALIDITY_NAMES.index("no_root")
                continue
            df = _core.describing_function(v, "bilateral", "constant", ["mu"], np.array([[0.215]]))
            k = np.flatnonzero(df["physical"][0] == 1)
            assert k.size, (f, a)  # stable here and past the subcritical Hopf load: a saddle cycle exists
            a0, a1, a2, th = (float(df[n][0, k[0]]) for n in ("A0", "A1", "A2", "theta"))
            z_max = a0 + np.max(a1 * np.sin(psi) + a2 * np.sin(2 * psi + th))
            opens = z_max / abs(reference.static_point(v)[0]) - 1
            assert abs(opens) > 0.05, (f, a, opens)  # far from grazing; sampling error is below 1e-5
            if opens > 0:
                code[i, j] = dff.VALIDITY_NAMES.index("contact_opens")
            elif not np.isfinite(a1_error[i, j]):
                code[i, j] = dff.VALIDITY_NAMES.index("orbit_not_found")
            else:
                code[i, j] = dff.VALIDITY_NAMES.index("valid" if abs(a1_error[i, j]) <= dff.ACCURACY else "inaccurate")
    return code


def test_maps_are_written(tmp_path, png_size, saved_figures, check_status_chart):
    r = dff.tidf_failure_maps(tmp_path, quick=True)
    with xr.open_dataset(tmp_path / "failure_tidf_validity.nc") as v, \
            xr.open_dataset(tmp_path / "failure_tidf_newton.nc") as nb:  # fmt: skip
        v, nb = v.load(), nb.load()
    # Which points fail and why: every code as the independent criteria give it. The quick grid (30-150 N x
    # 5-12.7 cm) has all three kinds: no root below the 5 cm arm's Hopf load, contact opening on the longer
    # arms, and valid roots on the stiff arm.
    expected = _expected_validity(v.normal_load.values, v.arm_length.values, v.tidf_a1_error.values)
    np.testing.assert_array_equal(v.tidf_validity.values, expected)
    assert {dff.VALIDITY_NAMES[c] for c in expected.ravel()} == {"valid", "no_root", "contact_opens"}
    # The returned counts are the files' codes.
    for name, ds, var, names in (("failure_tidf_validity", v, "tidf_validity", dff.VALIDITY_NAMES),
                                 ("failure_tidf_newton", nb, "newton", dff.NEWTON_NAMES)):  # fmt: skip
        assert r["counts"][name] == {n: int((ds[var].values == c).sum()) for c, n in enumerate(names)}
        # The charts: 6.4 x 4.6 in at 100 dpi, one labelled cell per failing point, at that point.
        assert png_size(tmp_path / f"{name}.png") == (640, 460)
        check_status_chart(saved_figures[f"{name}.png"].axes[0], ds, var, names)


def test_model_cost_numbers(tmp_path, monkeypatch, png_size, saved_figures):
    from tribosweep.bench import model_cost as _model_cost

    runs = {}
    real_sweep = _model_cost.sweep

    def recording_sweep(**kw):
        runs[kw.get("strategy", kw.get("method")), kw.get("census", True)] = ds = real_sweep(**kw)
        return ds

    monkeypatch.setattr(_model_cost, "sweep", recording_sweep)
    r = _model_cost.model_cost(tmp_path, quick=True)
    d = r["numbers"]
    assert d["points"] == 12 and d["orbits"] >= 5
    # The describing function is cheaper than integrating, counted in right-hand-side evaluations (not
    # timed): it is algebraic (none at any point), while the transient integrates every point.
    assert np.all(runs["tidf", True].n_rhs.values == 0)
    assert np.all(runs["transient", True].n_rhs.values > 0)
    assert d["tidf_a1_error_max"] < 0.10  # within 10 % of the orbits (docs/model.md §6)
    # auto decides every settled point as the transient does.
    assert d["regime_agreement"] == 1.0 and d["settled_points"] >= 8
    # The chart (6.0 x 4.4 in at 100 dpi): log-log, the describing function's point at its median A1 error.
    assert png_size(tmp_path / "model_cost.png") == (600, 440)
    ax = saved_figures["model_cost.png"].axes[0]
    assert ax.get_xscale() == ax.get_yscale() == "log"
    (tidf,) = [ln for ln in ax.lines if ln.get_label().startswith("describing function")]
    assert tidf.get_xdata()[0] == d["tidf_a1_error_median"]
    err = np.abs(runs["shooting", True].tidf_a1_error.values)
    assert d["tidf_a1_error_median"] == pytest.approx(np.median(err[np.isfinite(err)]), rel=1e-12)
