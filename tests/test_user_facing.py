"""What a user sees (issue 15): one default contact law, negative CLI specs, regime-map facets that wrap,
and the attributes of a cycle that coexists with stable sliding."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import cli

LINEAR = dict(strategy="linear", progress=False)


def run(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    assert "Traceback" not in out.err
    return code, out.out, out.err


# --- one default contact law ---------------------------------------------------------------------


def test_the_model_the_sweep_and_the_cli_share_one_default_contact_law(tmp_path, capsys):
    assert ts.SliderModel().contact == "unilateral"
    assert ts.sweep(normal_load=[50.0], **LINEAR).attrs["model_contact"] == ts.SliderModel().contact
    code, _, _ = run(["sweep", "--normal-load", "50", "--strategy", "linear", "--no-progress",
                      "-o", tmp_path / "d.nc"], capsys)  # fmt: skip
    assert code == 0
    with xr.open_dataset(tmp_path / "d.nc") as ds:
        assert ds.attrs["model_contact"] == "unilateral"


def test_the_bilateral_law_pulls_the_pin_back_and_the_default_lets_it_fly():
    # From the seed's bouncing cycle (docs/model.md §6) the default law stays on it, off the disk part of
    # each period; the bilateral law, which pulls with up to 258 N past zc = 0, leaves it.
    orbit, _ = ts.follow_cycle(ts.SliderModel())
    y0 = orbit.state0.values
    uni = ts.ensemble(ts.SliderModel(), 1.0, {"mu": [0.215]}, y0=y0, steady=True, rtol=1e-9)
    bil = ts.ensemble(ts.SliderModel(contact="bilateral"), 1.0, {"mu": [0.215]}, y0=y0, steady=True, rtol=1e-9)
    assert ts.OUTCOME_NAMES[int(uni.outcome[0])] == "periodic"
    # 11.5 % off the disk (docs/model.md §6, printed to 3 digits)
    assert float(uni.fraction_off_disk[0]) == pytest.approx(0.115, abs=0.0005)
    # The bouncing cycle's start lies well outside the bilateral saddle cycle (A1 23.6 um against 22.3 um,
    # docs/model.md §6), where the bilateral motion escapes: not a near-boundary fate.
    assert ts.OUTCOME_NAMES[int(bil.outcome[0])] == "diverged"
    assert float(bil.max_gap[0]) > 0  # and it left the disk on the way: outside the bilateral law's validity


# --- negative range specs on the command line ------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--normal-load", "-5:100:3"], "normal_load contains -5.0 N at index 0: every value must be > 0"),
        (["--normal-load", "-5,7"], "normal_load contains -5.0 N at index 0: every value must be > 0"),
        (["--arm-length", "-.05:0.1:2"], "arm_length contains -0.05 m at index 0: every value must be > 0"),
        (["--mu", "-0.1:0.3:3"], "mu = -0.1 is out of range: must be a finite number >= 0"),
    ],
)
def test_a_negative_range_spec_reaches_the_range_check(argv, message, tmp_path, capsys):
    # argparse (before Python 3.13) read "-5:100:3" as an option: "expected one argument".
    code, _, err = run(["sweep", *argv, "--strategy", "linear", "--no-progress", "-o", tmp_path / "x.nc"], capsys)
    assert code == 2
    assert message in err and "expected one argument" not in err
    assert not (tmp_path / "x.nc").exists()


def test_a_negative_value_where_one_is_valid_is_used(tmp_path, capsys):
    parser = cli.build_parser()
    args = parser.parse_args(cli._attach_negative_values(parser, ["sweep", "--normal-load", "-5:95:3"]))
    np.testing.assert_array_equal(args.normal_load, [-5.0, 45.0, 95.0])
    # A disturbance of -2 um (towards the disk) is a valid value: it reaches the file's attributes.
    code, _, _ = run(["sweep", "--normal-load", "50", "--strategy", "transient", "--t-max", "0.05", "--disturbance",
                      "-2e-6", "--no-progress", "-o", tmp_path / "n.nc"], capsys)  # fmt: skip
    assert code == 0
    with xr.open_dataset(tmp_path / "n.nc") as ds:
        np.testing.assert_array_equal(ds.attrs["solver_y0"], [-2e-6, 0, 0, 0, 0, 0])
    # A flag takes no value: a number after it is still an error, not glued to it.
    assert cli._attach_negative_values(parser, ["sweep", "--no-progress", "-5"]) == ["sweep", "--no-progress", "-5"]


# --- regime-map facets ---------------------------------------------------------------------------------


def test_regime_map_wraps_facets_into_rows_and_drops_none():
    pytest.importorskip("matplotlib")
    from tribosweep.plot import regime_map

    speeds = np.linspace(0.2, 1.0, 7)
    speeds[1] = 0.0671111  # the title: printed to 4 significant digits
    speeds.sort()
    ds = ts.sweep(normal_load=[10.0, 40.0, 90.0], arm_length=[0.05, 0.1], sliding_speed=speeds, **LINEAR)
    fig = regime_map(ds, facet="sliding_speed")
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == 7  # every speed has its panel: none dropped
    for k, ax in enumerate(panels):
        want = ds.regime.isel(sliding_speed=k).transpose("arm_length", "normal_load").values
        np.testing.assert_array_equal(np.asarray(ax.collections[0].get_array()).reshape(want.shape), want)
        assert ax.get_title() == f"sliding_speed = {speeds[k]:.4g} m s-1"
    assert panels[0].get_title() == "sliding_speed = 0.06711 m s-1"
    # Rows of 4: the fifth panel starts the second row; the figure grows down, not across.
    assert panels[4].get_position().y0 < panels[0].get_position().y0
    assert panels[4].get_position().x0 == pytest.approx(panels[0].get_position().x0)
    assert tuple(fig.get_size_inches()) == pytest.approx((3.6 * 4 + 1.8, 3.6 * 2))
    # Each row's first panel names the y axis, each column's lowest panel the x axis.
    assert [bool(ax.get_ylabel()) for ax in panels] == [True, False, False, False, True, False, False]
    assert [bool(ax.get_xlabel()) for ax in panels] == [False, False, False, True, True, True, True]


# --- a cycle that coexists with stable sliding -------------------------------------------------------


def test_a_cycle_at_a_stable_point_says_it_coexists_with_sliding(seed_values):
    ref = seed_values["unilateral_bouncing_cycle_seed"]
    orbit, _ = ts.follow_cycle(ts.SliderModel())
    # A transient started on the seed's bouncing cycle: sliding is linearly stable there, the run stays on the cycle.
    ds = ts.sweep(normal_load=[84.46], strategy="transient", disturbance=orbit.state0.values.tolist(), t_max=20.0,
                  progress=False).squeeze()  # fmt: skip
    assert float(ds.growth_rate) < 0
    assert ts.REGIME_NAMES[int(ds.regime)] == "contact_loss"
    # The reference is printed to 6 digits; the transient's period comes from section returns that agree
    # to periodic_tol = 1e-5 of the amplitude, well inside that.
    assert float(ds.cycle_omega) == pytest.approx(ref["omega"], abs=1e-3)
    assert "coexists" in str(ds.reason.values)
    for name in ("cycle_omega", "z1_amplitude", "z2_amplitude", "phi1_amplitude", "fraction_off_disk"):
        assert "COEXISTS with stable sliding" in ds[name].attrs["comment"], name
    assert ds.cycle_omega.attrs["long_name"] == "angular frequency of the cycle the point's run ended on (NaN if none)"
    # auto from the default 1 um start: sliding, the cycle only in the census's variables, which say so.
    auto = ts.sweep(normal_load=[84.46], samples=8, t_max=20.0, progress=False).squeeze()
    assert ts.REGIME_NAMES[int(auto.regime)] == "steady_sliding"
    assert np.isnan(float(auto.cycle_omega)) and np.isnan(float(auto.z1_amplitude))
    assert str(ts.labels(auto.bistable).values) == "coexisting"
    assert float(auto.largest_cycle_omega) == pytest.approx(ref["omega"], abs=1e-3)  # as above
    assert "coexists with stable sliding" in auto.largest_cycle_omega.attrs["comment"]
