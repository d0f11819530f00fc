"""The Stribeck sweep's settings bench (`tribosweep.bench.sweep_settings`): its comparison with the
reference, counted by hand on edited copies, and the chart drawn from its numbers."""

import numpy as np
import pytest

from tribosweep import REGIME_NAMES

pytest.importorskip("matplotlib")

R = {name: i for i, name in enumerate(REGIME_NAMES)}


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """The bench on a 2 x 1 x 2 corner of the issue-10 grid, one setting, one repeat."""
    from tribosweep.bench import sweep_settings as ss

    mp = pytest.MonkeyPatch()
    mp.setattr(ss, "AXES", dict(normal_load=[60.0, 150.0], arm_length=[0.05], sliding_speed=[0.2, 1.0]))
    mp.setattr(ss, "RTOLS", (1e-6,))
    mp.setattr(ss, "BLOCKS", (256,))
    out = tmp_path_factory.mktemp("settings")
    try:
        yield ss, out, ss.sweep_settings(out, quick=True)
    finally:
        mp.undo()


def test_compare_counts_what_was_changed(small):
    ss, _, _ = small
    from tribosweep import SliderModel, sweep

    ref = sweep(model=SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3), census=False,
                t_max=20.0, progress=False, **ss.AXES)  # fmt: skip
    same = ss.compare(ref, ref)
    cyc = np.isin(ref.regime.values.ravel(), [R["self_excited"], R["contact_loss"], R["stick_slip"]])
    cyc &= np.isfinite(ref.z1_amplitude.values.ravel()) & np.isfinite(ref.cycle_omega.values.ravel())
    assert cyc.sum() >= 2 and (~cyc).any(), "the corner has two cycles and a point that is none"
    assert same["regimes_differ"] == 0 and same["cycles_other"] == 0 and same["cycles_same"] == cyc.sum()
    assert same["a1_error_median"] == same["a1_error_max"] == 0.0
    # One cycle's amplitude off by 1e-3, another cycle's frequency doubled (another cycle), one label changed.
    ds = ref.copy(deep=True)
    i, j = np.flatnonzero(cyc)[:2]
    k = np.flatnonzero(~cyc)[0]
    ds["z1_amplitude"].values.reshape(-1)[i] *= 1 + 1e-3
    ds["cycle_omega"].values.reshape(-1)[j] *= 2.0
    ds["regime"].values.reshape(-1)[k] = R["diverged"]
    c = ss.compare(ds, ref)
    assert c["regimes_differ"] == 1
    assert (c["cycles_same"], c["cycles_other"]) == (cyc.sum() - 1, 1)
    assert c["a1_error_max"] == pytest.approx(1e-3, rel=1e-9)


def test_numbers_and_chart(small, png_size):
    ss, out, res = small
    d = res["numbers"]
    assert d["points"] == 4 and len(d["rows"]) == 1 and len(d["floor"]) == 2
    row = d["rows"][0]
    assert (row["transient_rtol"], row["block"]) == (1e-6, 256)
    assert 0 <= row["regimes_differ"] <= 4 and row["points_per_s"] > 0 and row["rhs_per_point"] > 0
    # A looser rtol costs fewer right-hand sides than the reference at 1e-10 run to t_max.
    assert row["rhs_per_point"] < d["reference_rhs_per_point"]
    # Cycle amplitudes found by transients at 1e-6 are measured on the orbit at the checks' 1e-9,
    # against the reference's 1e-10 (median 2e-9 on the whole grid). Of the corner's two cycles,
    # one has a first harmonic of 0.24 um beside the other's 35 um: 6e-9 and 3.7e-6 off (that is
    # 1e-12 m, and 3.5e-6 with the transients at 1e-8), a median of 1.9e-6.
    if row["cycles_same"]:
        assert row["a1_error_median"] < 1e-5
    # The chart (10.5 x 4.8 in at 100 dpi) plots each row at its numbers, and the table lists it.
    assert png_size(out / "sweep_settings.png") == (1050, 480)
    assert "| 1e-06 | 256 |" in res["markdown"]
    ax_l, ax_a = ss._chart(d).axes[:2]
    marks = lambda ax: [(ln.get_xdata()[0], ln.get_ydata()[0]) for ln in ax.lines if ln.get_marker() != "None"]  # noqa: E731
    assert marks(ax_l) == [(row["points_per_s"], row["regimes_differ"])]
    assert marks(ax_a) == [(row["points_per_s"], row["a1_error_median"])] or np.isnan(row["a1_error_median"])
