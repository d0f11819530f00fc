"""The onset of stick-slip as a boundary curve (switch law), and branches from Hopf points where
the family of cycles bends hard.

At 0.2 m/s with the Stribeck switch law (mu_static 0.3 down to mu = 0.215 at V) the cycles born
at the Hopf curve grow as the load falls, until their slip first reaches the stick band: the stick
curve. Its points are checked against an independent scipy integration of the switch law
(:class:`tribosweep.bench.reference_switch.SwitchReference`) and against the one-parameter branch;
the first orbits of a hard-bending branch against the Hopf normal form (``hopf_cycle_guess``).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import _core, cli
from tribosweep._boundary import default_kinds
from tribosweep.bench.reference_switch import SwitchReference

BASE = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3, sliding_speed=0.2)
X = ("normal_load", 10.0, 150.0)


@pytest.fixture(scope="module")
def curve():
    return ts.stick_curve(BASE, x=X, y=("arm_length", 0.07, 0.09), n=2, from_hopf=True, threads=2)


def test_a_hard_bending_branch_starts_from_its_hopf_point_at_a_smaller_amplitude():
    """At 5 cm the branch bends so hard (0.025 N of load for A1 = 2.3e-8 m) that the first orbit
    guessed at hopf_amplitude = 0.02 is out of Newton's reach (a step of 1.2 scaled units); the
    start now tries a tenth of it. Its first orbits are the normal form's cycle: against
    ``hopf_cycle_guess`` A1 differs by O(|p - p_H|) (the next term) and the period by
    O(|p - p_H|^2), so error / |p - p_H| and error / |p - p_H|^2 are the same at every point near
    the Hopf point (seen 6.52-6.54e-3 per N and 3.81-3.90e-8 per N^2, over 0.05-1.06 N from it)."""
    m = ts.apparatus_model(84.46, 0.05, 0.2, base=BASE)
    sb = ts.sliding_branch(m, X)
    (hp,) = np.flatnonzero((sb.is_hopf.values == 1) & (sb.hopf_status.values == 0))
    h = float(sb.hopf_normal_load[hp])
    b = ts.branch(m, "normal_load", 10.0, from_hopf=h, stop_at="stick")
    assert ts.STATUS_NAMES[int(b.status)] == "success"
    assert "first orbit at hopf_amplitude = 2e-3: Newton did not converge from 2e-2" in b.attrs["reason"]
    assert b.attrs["static_scales"] == 0 and "the critical mode's own motion" in b.attrs["arclength_scales"]
    p, a1 = b.parameter.values, b.A1.values
    assert 0 < h - p[1] < 0.05
    slope, curve = [], []
    near = np.flatnonzero((h - p >= 0.03) & (h - p <= 1.2))  # the orbits 0.03-1.2 N from the Hopf point
    assert near.size >= 4 and (h - p[near[-1]]) / (h - p[near[0]]) > 10, h - p[:12]
    for j in near:
        g = ts.hopf_cycle_guess(sb, float(p[j]), hopf=int(hp))
        slope.append(abs(g["amplitude"] / a1[j] - 1) / (h - p[j]))
        curve.append(abs(g["period"] / float(b.period[j]) - 1) / (h - p[j]) ** 2)
    assert max(slope) / min(slope) < 1.05, slope
    assert max(curve) / min(curve) < 1.1, curve
    # The branch ends where its cycle reaches the stick band (at 34.78 N).
    assert ts.BRANCH_POINT_TYPE_NAMES[int(b.point_type[-1])] == "stick" and 34.7 < float(p[-1]) < 34.9


def test_stick_curve_points_are_where_scipy_sees_the_slip_touch_the_band(curve):
    """Each point's orbit, integrated over its period by scipy (DOP853 at rtol 1e-12, the switch
    law written from the equations; the pin stays on the disk, so the bilateral reference holds):
    it closes (1e-11 of each component's range seen), and its sliding velocity comes down to the
    band's half-width, 1e-6 m/s: the curve locates min_slip_velocity to 1e-2 of it (1.00004e-6
    seen), and scipy's sampled minimum (4,001 samples a period: at most 1e-7 m/s above the true
    one here, 4e-9 seen) agrees. The reference runs with half the band, so that its slip goes on
    whichever side of the band's edge the location left the orbit (by 4e-11 m/s)."""
    assert curve.sizes["curve_point"] == 2 and curve.attrs["reason"] == "2 of 2 arm lengths located their stick point"
    eta = BASE.stick_band
    for i in range(2):
        assert ts.BRANCH_POINT_TYPE_NAMES[int(curve.point_type[i])] == "stick"
        assert abs(float(curve.min_slip_velocity[i]) / eta - 1) < 1e-2 and float(curve.min_gap[i]) > 0
        m = ts.apparatus_model(float(curve.normal_load[i]), float(curve.arm_length[i]), 0.2, base=BASE)
        y0, period = curve.state0.values[i], float(curve.period[i])
        ref = SwitchReference(m.values() | {"stick_band": 0.5 * eta})
        t = np.linspace(0.0, period, 4001)
        z, w, arm = abs(m.static_point()[0]), m.omega_torsion, m.moment_arm
        sizes = np.array([z, z * w, z, z * w, z / arm, z / arm * w])
        y, switches = ref.solve(y0, period, t, rtol=1e-12, atol=1e-13 * sizes)
        assert switches == []
        scale = np.abs(y).max(axis=0)
        assert (np.abs(y[-1] - y0) / scale < 1e-9).all(), np.abs(y[-1] - y0) / scale
        v_r = m.sliding_speed - (y[:, 3] + m.torsion_sign * m.moment_arm * y[:, 5])
        assert -1e-10 < v_r.min() - float(curve.min_slip_velocity[i]) < 1e-7, v_r.min()
        # The hopf load the slice started from, and the stick point on the low side of it (the
        # cycles are born unstable and grow as the load falls).
        assert float(curve.normal_load[i]) < float(curve.hopf_normal_load[i]) and not bool(curve.stable[i])


def test_a_stick_curve_point_is_the_one_parameter_branch_s_stick_point(curve):
    arm = float(curve.arm_length[1])
    m = BASE.replace(**ts.arm_frequencies(arm, BASE))
    b = ts.branch(m, "normal_load", 10.0, from_hopf=float(curve.hopf_normal_load[1]), bounds=(10.0, 150.0),
                  stop_at="stick")  # fmt: skip
    assert float(b.parameter[-1]) == float(curve.normal_load[1])


def test_boundary_command_draws_the_stick_curve(tmp_path, capsys, saved_figures):
    nc = tmp_path / "st.nc"
    code = cli.main(["boundary", "--curves", "hopf,stick", "--friction-law", "switch", "--model", "mu_static=0.3",
                     "--sliding-speed", "0.2", "--arm-length", "0.07:0.09", "--slices", "2", "--threads", "2", "-o",
                     str(nc)])  # fmt: skip
    out = capsys.readouterr()
    assert code == 0, out.err
    assert "stick: 2 stick point(s) in the box" in out.out
    with xr.open_dataset(nc) as ds:
        assert ds.stick_normal_load.dims == ("stick_point",) and ds.stick_normal_load.attrs["units"] == "N"
        assert ds.stick_min_slip_velocity.attrs["units"] == "m s-1"
        assert ds.attrs["stick_curve_call"].startswith("tribosweep.stick_curve(model, x=('normal_load', 10.0, 150.0)")
        # The Hopf curve spans the whole arm window here: the same slices as the fixture's curve.
        got = ds.stick_normal_load.values
    ref = ts.stick_curve(BASE, x=X, y=("arm_length", 0.07, 0.09), n=2, from_hopf=True)
    np.testing.assert_allclose(got, ref.normal_load.values, rtol=1e-12)
    fig = saved_figures["st.png"]
    texts = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert "stick: the cycle from the\nHopf curve first sticks" in texts
    (line,) = [ln for ln in fig.axes[0].lines if ln.get_marker() == "^"]
    np.testing.assert_array_equal(line.get_xdata(), got)


def test_stick_curves_need_the_switch_law():
    assert default_kinds(BASE) == ("hopf", "fold", "grazing", "stick")
    assert default_kinds(BASE.replace(friction_law="coulomb")) == ("hopf", "fold", "grazing")
    with pytest.raises(ValueError, match=r"a stick curve needs friction_law='switch'.*model.friction_law = 'coulomb'"):
        ts.stick_curve(BASE.replace(friction_law="coulomb"), x=X, y=("arm_length", 0.07, 0.09), from_hopf=True)
    with pytest.raises(ValueError, match=r"'stick' needs friction_law='switch'.*model.friction_law = 'constant'"):
        ts.boundary_curves(ts.SliderModel(), curves=("hopf", "stick"))
    with pytest.raises(ValueError, match="kind = Stick needs friction_law = Switch, not Coulomb"):
        _core.special_curve(BASE.values(), "unilateral", "coulomb", "stick", "normal_load", 30.0, 10.0, 150.0,
                            "mu", np.array([0.215, 0.22]), hopf_omega=400.0)  # fmt: skip
    assert cli.main(["boundary", "--curves", "hopf,stick"]) == 2
    with pytest.raises(ValueError, match=r"stop_at = 'stick' needs friction_law='switch'.*= 'constant'"):
        ts.branch(ts.SliderModel(), "normal_load", 150.0, from_hopf=True, stop_at="stick")


def test_near_the_stick_point_no_orbit_flow_creeps_along_zero_slip():
    """Newton's trial orbits near the stick point dip their slip through zero. On the law's own
    field the force reverses there, pushes v_r back, and the flow crept along v_r = 0 (a Filippov
    sliding motion, two steps in three rejected) to its budget of 50,000 steps: at 7.1 cm such
    flows made 85 % of the branch's 7.3M right-hand sides (7,610 per flow on average, over 956
    flows). A slip segment now flows on its direction's field continued past zero
    (``Slider::with_slip_sign``) and ends where its slip reaches zero, also inside a step: 1.09M,
    1,163 per flow, the same 370 orbits and the same stick point to the last bit."""
    m = BASE.replace(**ts.arm_frequencies(0.071, BASE))
    sb = ts.sliding_branch(m, X)
    (hp,) = np.flatnonzero((sb.is_hopf.values == 1) & (sb.hopf_status.values == 0))
    b = ts.branch(m, "normal_load", 10.0, from_hopf=float(sb.hopf_normal_load[hp]), bounds=(10.0, 150.0),
                  stop_at="stick")  # fmt: skip
    assert ts.BRANCH_POINT_TYPE_NAMES[int(b.point_type[-1])] == "stick" and 28.2 < float(b.parameter[-1]) < 28.4
    assert b.attrs["n_rhs"] / b.attrs["n_flows"] < 3000, (b.attrs["n_rhs"], b.attrs["n_flows"])


def test_a_switch_law_load_arm_sweep_stores_its_stick_curve(tmp_path):
    """A normal load x arm length sweep under the switch law stores the stick curve with the Hopf,
    fold and grazing curves (``stick_*`` on ``stick_point``), as its recorded call computes it;
    under the tanh law it has none and says nothing of one."""
    path = tmp_path / "sw.nc"
    m = BASE.replace(sliding_speed=0.46)  # the sweep's own axis sets the speed
    ts.sweep(m, normal_load=[10.0, 150.0], arm_length=[0.07, 0.09], sliding_speed=[0.2], census=False, progress=False,
             threads=2, output=path).close()  # fmt: skip
    with xr.open_dataset(path) as ds:
        assert ds.stick_normal_load.dims == ("stick_point",) and ds.sizes["stick_point"] == 12
        call = ds.attrs["stick_curve_call"]
        assert call.startswith("tribosweep.stick_curve(model, x=('normal_load', 10.0, 150.0), y=('arm_length', 0.07, 0.09)")
        api = ts.stick_curve(BASE, x=X, y=("arm_length", 0.07, 0.09), n=12,
                             from_hopf=float(call.split("from_hopf=")[1].rstrip(")")))  # fmt: skip
        np.testing.assert_allclose(ds.stick_normal_load.values, api.normal_load.values, rtol=1e-12)
        # The fixture's two slices are this curve's ends.
        assert abs(float(ds.stick_normal_load[0]) - 28.851) < 1e-3 and abs(float(ds.stick_normal_load[-1]) - 22.543) < 1e-3
        # `tribosweep info` lists the curves the file holds.
        text = cli.describe(ds)
        assert "boundary curves: hopf " in text and "; stick 12 points (22.54 .. 28.85 N, arm length 0.07 .. 0.09 m)" in text
    tanh = ts.sweep(BASE.replace(friction_law="coulomb"), normal_load=[10.0, 150.0], arm_length=[0.07, 0.09],
                    sliding_speed=[0.2], strategy="linear", progress=False)  # fmt: skip
    assert "stick_normal_load" not in tanh and "stick_curves" not in tanh.attrs


def test_the_fold_and_grazing_curves_read_their_points_off_the_stick_curve_s_branches(monkeypatch):
    """Under the switch law every branch from a Hopf point runs to its stick point, and up to there
    it does not depend on where it is asked to stop: ``boundary_curves`` runs one branch per slice
    (the stick curve's) and reads the first fold off it; the grazing curve's bilateral branch is
    that unilateral branch, bit for bit, wherever the latter has no grazing point (and the other
    way round at their end bisections). The points and the reasons are those of the curves' own
    calls, each with its own branches, to the last bit."""
    calls = []
    branch = _core.branch

    def counted(values, contact, *args, **kwargs):
        calls.append((contact, kwargs.get("stop_at")))
        return branch(values, contact, *args, **kwargs)

    monkeypatch.setattr(_core, "branch", counted)
    # Folds (grazings where the branch turns back) on 5.8-6.7 cm only: at the middle slice; the
    # curves' two ends are bisected at once, 4 times each. The middle slice's unilateral branch
    # grazes, so the grazing curve runs its own there; the outer ones stick first. The fold and
    # grazing curves bisect the same arm lengths and share the branches that never graze (which
    # curve runs one depends on the threads' timing): 16 of their 1 + 8 + 8 + 3 (17-19 where a
    # stick branch failed on the critical mode's scales and ran again on the static ones, whose
    # points a fold branch stopped before the failure does not share).
    box = (0.057, 0.068)
    ds = ts.boundary_curves(BASE, arm_length=box, slices=3, threads=2)
    assert calls[:3] == [("unilateral", "stick")] * 3, calls
    assert 16 <= len(calls) - 3 <= 19 and set(calls[3:]) <= {("bilateral", "grazing"), ("unilateral", "fold")}, calls
    assert ds.sizes["fold_point"] > 1 and ds.sizes["grazing_point"] > 1 and ds.sizes["stick_point"] == 3
    start = float(ds.attrs["fold_curve_call"].split("from_hopf=")[1].rstrip(")"))
    calls.clear()
    for kind, func in (("fold", ts.fold_curve), ("grazing", ts.grazing_curve), ("stick", ts.stick_curve)):
        own = func(BASE, x=X, y=("arm_length", *box), n=3, from_hopf=start, threads=1)  # the ends one after the other
        for v in ("normal_load", "arm_length", "A1", "period", "min_gap", "min_slip_velocity"):
            np.testing.assert_array_equal(ds[f"{kind}_{v}"].values, own[v].values)
        assert ds.attrs[f"{kind}_curves"].endswith("from Hopf curve 0: " + own.attrs["reason"])
    assert [c[1] for c in calls] == ["fold"] * 11 + ["grazing"] * 11 + ["stick"] * 3, calls


def test_a_branch_through_a_cascade_of_grazings_reaches_its_stick_point_whatever_the_last_bits():
    """At 6.25 cm the branch from the Hopf point passes some 40 special points (grazings, folds,
    period doublings, Neimark-Sacker pairs) before its stick point at 30.74 N. On the critical
    mode's scales its longer steps take another way through that cascade, where a change of mode
    sequence at 34.45 N failed with the inputs moved by one ulp; the branch then runs again on the
    static scales (``static_scales``, and its reason says why). Moved by -1, 0 and +1 ulp, every
    input: the same stick point each time, to 1e-6 N."""
    from conftest import moved

    m = BASE.replace(**ts.arm_frequencies(0.0625, BASE))
    sb = ts.sliding_branch(m, X)
    (hp,) = np.flatnonzero((sb.is_hopf.values == 1) & (sb.hopf_status.values == 0))
    h, om = float(sb.hopf_normal_load[hp]), float(sb.hopf_frequency[hp])
    ends = []
    for k in (-1, 0, 1):
        values = {n: (float(moved(v, k)) if isinstance(v, float) and v != 0.0 and n != "torsion_sign" else v)
                  for n, v in m.replace(normal_load=h).values().items()}  # fmt: skip
        out = _core.branch(values, "unilateral", "switch", "normal_load", h, 10.0, 150.0, hopf_omega=om,
                           options={"max_points": 5000.0}, stop_at="stick")  # fmt: skip
        assert ts.STATUS_NAMES[int(out["status"])] == "success", out["reason"]
        assert ts.BRANCH_POINT_TYPE_NAMES[int(out["point_type"][-1])] == "stick", out["reason"]
        assert ("on the static scales" in out["reason"]) == bool(out["static_scales"])
        ends.append(float(out["parameter"][-1]))
    assert max(ends) - min(ends) < 1e-6 and abs(ends[1] - 30.7407) < 1e-3, ends
