"""Maps of any sweep variable: the figure's content, not its file size."""

from __future__ import annotations

import numpy as np
import pytest

import tribosweep as ts

pytest.importorskip("matplotlib")
from tribosweep.plot import variable_map  # noqa: E402


@pytest.fixture(scope="module")
def sweep3():
    return ts.sweep(normal_load=[10.0, 40.0, 90.0], arm_length=[0.05, 0.1], sliding_speed=[0.3, 0.5, 0.7, 0.9, 1.1],
                    strategy="linear", progress=False)  # fmt: skip


def test_a_continuous_variable_has_a_labelled_colour_bar_and_its_values_in_every_facet(sweep3):
    fig = variable_map(sweep3, "growth_rate")
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.collections and ax.get_label() != "<colorbar>"]
    assert len(panels) == 5  # every speed gets its panel: none dropped
    for k, ax in enumerate(panels):
        want = sweep3.growth_rate.isel(sliding_speed=k).transpose("arm_length", "normal_load").values
        np.testing.assert_array_equal(np.asarray(ax.collections[0].get_array()).reshape(want.shape), want)
        assert ax.get_title() == f"sliding_speed = {sweep3.sliding_speed.values[k]:.4g} m s-1"
    bar = fig.axes[-1]
    assert bar.get_ylabel().replace("\n", " ") == f"{sweep3.growth_rate.attrs['long_name']} [s-1]"  # wrapped to fit
    # Panels wrap in rows of 4: the fifth starts the second row, and every column shows its x ticks.
    assert panels[4].get_position().y0 < panels[0].get_position().y0


def test_a_categorical_variable_gets_its_flag_names_in_the_legend(sweep3):
    fig = variable_map(sweep3, "regime", facet="sliding_speed")
    names = str(sweep3.regime.attrs["flag_meanings"]).split()
    present = sorted({int(v) for v in np.unique(sweep3.regime.values)})
    assert [t.get_text() for t in fig.legends[0].get_texts()] == [names[i].replace("_", " ") for i in present]


def test_an_unknown_variable_names_the_valid_ones(sweep3):
    with pytest.raises(ValueError, match="var = 'nope' is not in the sweep: its per-point variables are"):
        variable_map(sweep3, "nope")


@pytest.mark.parametrize("var", ["regime", "growth_rate"])
def test_grid_points_are_marked_on_request_and_the_mark_is_in_the_legend(sweep3, var):
    from tribosweep.plot import regime_map

    def draw(mark):
        return regime_map(sweep3, mark_points=mark) if var == "regime" else variable_map(sweep3, var, mark_points=mark)

    fig = draw(True)
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.collections and ax.get_label() != "<colorbar>"]
    n_grid = sweep3.sizes["normal_load"] * sweep3.sizes["arm_length"]
    for ax in panels:
        dots = [c for c in ax.collections if c.get_offsets().shape == (n_grid, 2)]
        assert len(dots) == 1  # one dot per computed point, at the points' coordinates
        xy = np.asarray(dots[0].get_offsets())
        assert set(np.round(xy[:, 0], 9)) == set(np.round(sweep3.normal_load.values, 9))
    labels = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert "computed point" in labels
    # Without the option: no dots, no legend entry.
    plain = draw(False)
    assert "computed point" not in [t.get_text() for leg in plain.legends for t in leg.get_texts()]


def test_a_wide_grid_marks_multi_period_cycles_instead_of_labels_that_would_run_together():
    from tribosweep.plot import MAX_LABELLED_COLUMNS, regime_map

    loads = np.linspace(30.0, 150.0, MAX_LABELLED_COLUMNS + 4)
    ds = ts.sweep(normal_load=loads, arm_length=[0.05, 0.1], strategy="linear", progress=False)
    ratio = np.full(ds.regime.shape, np.nan)
    ratio[3, 0, 0] = ratio[7, 1, 0] = 2.0  # two period-doubled cells (synthetic values)
    ds["cycle_period_ratio"] = (ds.regime.dims, ratio)
    fig = regime_map(ds)
    ax = fig.axes[0]
    assert not [t for t in ax.texts if t.get_text().endswith("T")]
    marks = [c for c in ax.collections if c.get_offsets().shape == (2, 2)]
    assert len(marks) == 1
    labels = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert any(lbl.startswith("a cycle of 2 or more mode periods") for lbl in labels)
    # The contact law's identified range (22-93 N) is drawn only where it lies inside the map.
    assert [ln.get_xdata()[0] for ln in ax.lines if ln.get_linestyle() == "--"] == [93.0]
    # A narrow grid keeps its "2T" labels.
    narrow = ds.isel(normal_load=slice(0, MAX_LABELLED_COLUMNS))
    assert sum(t.get_text() == "2T" for t in regime_map(narrow).axes[0].texts) == 2


def test_unstable_points_whose_label_few_disturbances_reach_get_a_ring():
    from tribosweep.plot import WEAK_LABEL, regime_map

    ds = ts.sweep(normal_load=[10.0, 40.0, 90.0], arm_length=[0.05, 0.1], strategy="linear", progress=False)
    grow = np.full(ds.regime.shape, -1.0)
    frac = np.full(ds.regime.shape, 0.2)  # synthetic values: only unstable cells below WEAK_LABEL get a ring
    grow[0, 0, 0] = grow[1, 1, 0] = grow[2, 1, 0] = 1.0
    frac[2, 1, 0] = WEAK_LABEL  # at the threshold: no ring
    ds["growth_rate"], ds["regime_fraction"] = (ds.regime.dims, grow), (ds.regime.dims, frac)
    fig = regime_map(ds)
    rings = [c for c in fig.axes[0].collections if c.get_offsets().shape[0] and np.allclose(c.get_facecolors(), 1.0)]
    assert len(rings) == 1 and rings[0].get_offsets().shape == (2, 2)
    xs = sorted(rings[0].get_offsets()[:, 0])
    assert xs[0] < 25.0 < xs[1] < 65.0  # in the cells of 10 N and 40 N (edges at 25 and 65 N)
    labels = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert any(lbl.startswith("sliding unstable: fewer than half") for lbl in labels)
    # Without the census's fractions: no ring, no legend entry.
    plain = regime_map(ds.drop_vars("regime_fraction"))
    assert not any(t.get_text().startswith("sliding unstable") for leg in plain.legends for t in leg.get_texts())
