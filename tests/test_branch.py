"""Branches of periodic orbits (issue 12, items 3-4) against docs/model.md, plain shooting and the attractor census."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts

SEED = ts.SliderModel(contact="bilateral")
SEED_U = ts.SliderModel(contact="unilateral")


def names(ds):
    return [ts.BRANCH_POINT_TYPE_NAMES[int(t)] for t in ds.point_type.values]


def first_of(ds, kind):
    return ds.isel(branch_point=names(ds).index(kind))


@pytest.fixture(scope="module")
def bilateral():
    """The bilateral branch from the seed's Hopf point to the seed load."""
    return ts.branch(SEED, "normal_load", 84.46, from_hopf=True)


@pytest.fixture(scope="module")
def bouncing():
    """The seed's unilateral bouncing cycle (natural continuation from mu = 0.30, where it is the attractor)."""
    orb, _ = ts.follow_cycle(SEED_U)
    return orb


def test_bilateral_branch_from_the_hopf_point_reaches_the_seed_saddle_cycle(bilateral, seed_values):
    ref = seed_values["bilateral_periodic_orbit_seed"]
    ds = bilateral
    assert ts.STATUS_NAMES[int(ds.status)] == "success" and ds.attrs["reason"]
    assert names(ds)[0] == "hopf" and names(ds)[-1] == "end"
    end = ds.isel(branch_point=-1)
    assert float(end.parameter) == 84.46
    # docs/model.md gives the period to 7 digits: 1e-6 relative is their resolution.
    assert abs(float(end.period) / ref["period_s"] - 1) < 1e-6
    # Moduli as printed (5 digits).
    np.testing.assert_allclose(end.floquet_modulus.values, ref["floquet_moduli"], atol=1e-4)
    # A1 as printed (5 digits; the branch's harmonics come from 256 samples of a smooth orbit).
    assert abs(float(end.A1) - ref["A1"]) < 1e-9


def test_the_branch_leaves_the_hopf_point_as_a_subcritical_one(bilateral):
    # Subcritical: the cycles are born on the side where sliding is stable (above 24.9 N), unstable.
    hopf, first = bilateral.isel(branch_point=0), bilateral.isel(branch_point=1)
    assert float(first.parameter) > float(hopf.parameter)
    lin = ts.linear_stability(SEED.replace(normal_load=float(first.parameter)))
    assert bool(lin.stable)
    assert int(first.stable) == 0 and int(first.n_unstable) == 1
    # On the whole branch the cycle stays a saddle with one real multiplier above 1.
    assert (bilateral.n_unstable.values[1:] == 1).all()


def test_a_grazing_point_agrees_with_a_direct_bisection_on_the_minimum_gap(bilateral):
    g = first_of(bilateral, "grazing")
    f_branch = float(g.parameter)
    assert abs(float(g.min_gap)) < 1e-12  # located on min_gap to locate_tol

    # Direct: bisection over the load with plain shooting at each value (guess: the nearest branch
    # point). The phase point zd = 0 of these orbits is the top of z, so min gap = -(z_st + z0).
    pts = bilateral.where(bilateral.point_type == 0, drop=True)

    def min_gap(load):
        i = int(np.argmin(np.abs(pts.parameter.values - load)))
        orb = ts.periodic_orbit(SEED.replace(normal_load=load), (pts.state0.values[i], float(pts.period[i])))
        assert ts.STATUS_NAMES[int(orb.status)] == "success"
        z_st = SEED.replace(normal_load=load).static_point()[0]
        assert abs(float(orb.state0[0]) - float(orb.z_max)) < 1e-12  # the phase point is the top
        return -(z_st + float(orb.state0[0]))

    lo, hi, tol = 30.0, 45.0, 1e-6
    assert min_gap(lo) > 0 > min_gap(hi)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if min_gap(mid) > 0 else (lo, mid)
    # The bisection's bracket, plus the branch's location tolerance in the load (locate_tol 1e-8
    # in scaled arclength times |dp/ds|, about 2.3 N per unit: 2e-8 N).
    assert lo - 1e-7 <= f_branch <= hi + 1e-7, (f_branch, lo, hi)


def test_a_fold_of_cycles_agrees_with_a_dense_shooting_scan(bouncing):
    # The stable bouncing cycle followed in mu at the seed load meets a saddle at a smooth fold.
    ds = ts.branch(SEED_U, "mu", 0.5, orbit=bouncing, bounds=(0.05, 0.5), stop_at="fold")
    fold = ds.isel(branch_point=-1)
    assert names(ds)[-1] == "fold", ds.attrs["reason"]
    mu_f = float(fold.parameter)
    # Dense scan with plain shooting, each value from the last orbit, in steps h: the cycle
    # exists (converges on the branch) up to the fold and not beyond. The cell holding the fold
    # and its neighbours are left out (there Newton may stall on the nearly singular orbit).
    h = 2e-5
    start = ds.where((ds.parameter < mu_f - 40 * h) & (ds.point_type == 0), drop=True).isel(branch_point=-1)
    y, period = start.state0.values, float(start.period)
    mu = float(start.parameter)
    last_ok = None
    while mu < mu_f + 10 * h:
        orb = ts.periodic_orbit(SEED_U.replace(mu=mu), (y, period))
        ok = ts.STATUS_NAMES[int(orb.status)] == "success" and abs(float(orb.period) / period - 1) < 1e-4
        if ok:
            last_ok = mu
            y, period = orb.state0.values, float(orb.period)
        else:
            assert mu > mu_f - 2 * h, f"the scan lost the cycle at mu = {mu}, before the fold at {mu_f}"
        mu += h
    assert mu_f - 2 * h <= last_ok <= mu_f + h, (last_ok, mu_f)


def test_floquet_multipliers_agree_with_periodic_orbit(bouncing, bilateral):
    ds = ts.branch(SEED_U, "normal_load", 20.0, orbit=bouncing, max_points=60)
    for branch_ds, model in ((ds, SEED_U), (bilateral, SEED)):
        pts = branch_ds.where(branch_ds.point_type == 0, drop=True)
        for i in np.linspace(1, pts.sizes["branch_point"] - 1, 4).astype(int):
            p = pts.isel(branch_point=i)
            orb = ts.periodic_orbit(model.replace(normal_load=float(p.parameter)), (p.state0.values, float(p.period)))
            assert ts.STATUS_NAMES[int(orb.status)] == "success"
            a = np.sort_complex(orb.floquet_multipliers.values)
            b = np.sort_complex(p.floquet_multiplier_real.values + 1j * p.floquet_multiplier_imag.values)
            # Two monodromy matrices each accurate to about 1e-9 (their trivial multiplier's
            # error); 1e-6 leaves room for the eigenvalue conditioning of a non-normal matrix.
            np.testing.assert_allclose(a, b, atol=1e-6)
            assert abs(float(orb.period) / float(p.period) - 1) < 1e-8


@pytest.mark.slow
def test_the_fold_curve_bounds_the_coexistence_the_census_sees(bouncing):
    # Edge of the bouncing cycles in (load, mu): where the saddle and the bouncing family meet and
    # end (here a grazing turns the branch back: a non-smooth fold).
    curve = ts.fold_curve(SEED_U, x=("normal_load", 50.0, 300.0), y=("mu", 0.215, 0.225), n=3, orbit=bouncing)
    assert ts.STATUS_NAMES[int(curve.status)] == "success", curve.attrs["reason"]
    mus, folds = curve.mu.values, curve.normal_load.values
    np.testing.assert_allclose(mus, [0.215, 0.22, 0.225])
    assert np.all(np.diff(folds) > 0)
    for mu, fold in zip(mus, folds):
        # Well inside: the seed load, where the branch's cycle is stable and so is sliding. Well
        # outside: 30 N (about 20 %) above the fold, where no cycle of the family exists.
        inside = ts.census(SEED_U.replace(mu=float(mu)), samples=64, threads=1)
        outside = ts.census(SEED_U.replace(mu=float(mu), normal_load=float(fold) + 30.0), samples=64, threads=1)
        p, se = inside.basin_fraction.values, inside.basin_fraction_se.values
        # Coexistence, 3 standard errors clear of zero for both sliding and the cycle.
        assert p[0] > 3 * se[0] and p[1] > 3 * se[1], (mu, p, se)
        # Outside: sliding is the only attractor; no disturbance settles on a cycle or bounded
        # irregular motion (with 64 samples a basin above about 5 % would show with 95 % confidence).
        # A large disturbance may escape (|z| past 1 mm: out of the model's validity, no attractor).
        q = outside.basin_fraction.values
        assert int(outside.n_attractors) == 1 and q[1] == 0 and q[2] == 0 and q[0] > 0.9, (mu, fold, q)


def test_the_grazing_curve_is_made_of_grazing_orbits():
    curve = ts.grazing_curve(SEED_U, x=("normal_load", 1.0, 250.0), y=("mu", 0.21, 0.225), n=4, from_hopf=True)
    assert ts.STATUS_NAMES[int(curve.status)] == "success", curve.attrs["reason"]
    np.testing.assert_allclose(curve.mu.values, [0.21, 0.215, 0.22, 0.225])
    # The grazing load rises with mu, as the Hopf load does (docs/model.md §4).
    assert np.all(np.diff(curve.normal_load.values) > 0)
    for i in range(curve.sizes["curve_point"]):
        c = curve.isel(curve_point=i)
        model = SEED.replace(mu=float(c.mu), normal_load=float(c.normal_load))
        orb = ts.periodic_orbit(model, (c.state0.values, float(c.period)))
        # Plain shooting from the curve's orbit: its top touches the disk. Shooting converges to a
        # scaled residual of 1e-9 (of |z_st|, about 1e-14 m here); 1e-11 m is 1e-6 of |z_st|.
        assert abs(model.static_point()[0] + float(orb.state0[0])) < 1e-11


def test_the_unilateral_branch_goes_through_grazing_onto_flights():
    # From the Hopf point: the saddle grazes at 36.83 N, where the branch turns back (a non-smooth
    # fold) onto orbits with a flight, which fold smoothly near 19 N.
    ds = ts.branch(SEED_U, "normal_load", 50.0, from_hopf=True, bounds=(1.0, 50.0), max_points=400)
    g = first_of(ds, "grazing")
    assert abs(float(g.parameter) - 36.83) < 0.01
    assert int(g.flags) & (1 << ts.BRANCH_FLAG_NAMES.index("parameter_turns"))
    after = ds.isel(branch_point=slice(names(ds).index("grazing") + 1, None))
    assert (after.n_switches.values[:5] == 2).all() and (after.min_gap.values[:5] < 0).all()
    assert "fold" in names(after)


def test_a_step_that_cannot_converge_is_halved_and_the_branch_ends_with_a_reason(bouncing):
    # Two Newton steps and a smallest step of 0.4: the first step (0.5) needs more, is halved below
    # ds_min, and the branch ends after its first point.
    ds = ts.branch(SEED_U, "normal_load", 120.0, orbit=bouncing, max_newton=2, ds=0.5, ds_min=0.4, ds_max=0.5)
    assert ts.STATUS_NAMES[int(ds.status)] == "newton_not_converged"
    assert "halved below ds_min" in ds.attrs["reason"]
    assert ds.sizes["branch_point"] == 1


def test_a_switch_law_branch_ends_at_the_located_point_where_its_cycle_reaches_stick():
    """The Stribeck switch law under bilateral contact (the grazing curve's model for issue 10's
    slider at 0.2 m/s, 7.91 cm): continued down in load from its Hopf point, the cycle's slip phase
    comes down to the stick band near 25.31 N and gains a stick phase, a sliding bifurcation that
    continuation does not follow. Before, a fixed-mode flow went on across v_r = 0, chattering in
    ever smaller steps (the sweep's boundary stage ran for more than ten minutes). Now the point is
    located (a secant on min_slip_velocity - stick_band) and the branch ends there, every flow within
    the orbit flows' step budget."""
    from tribosweep import _core

    base = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3, sliding_speed=0.2)
    m = ts.apparatus_model(84.46, 0.0791, 0.2, base=base)
    sb = ts.sliding_branch(m, ("normal_load", 20.0, 140.0))
    ok = sb.is_hopf.values == 1
    h, om = float(sb.hopf_normal_load.values[ok][0]), float(sb.hopf_frequency.values[ok][0])
    out = _core.branch(m.replace(normal_load=h).values(), "bilateral", "switch", "normal_load", h, 20.0, 140.0,
                       hopf_omega=om, options=dict(_core.branch_defaults()), stop_at="grazing")  # fmt: skip
    assert ts.STATUS_NAMES[int(out["status"])] == "success"
    assert "reaches the stick band" in str(out["reason"]) and "gains a stick phase" in str(out["reason"])
    p, kinds = np.asarray(out["parameter"]), np.asarray(out["point_type"])
    assert p.size > 20 and 25.2 < p[-1] < 25.4 and ts.BRANCH_POINT_TYPE_NAMES[int(kinds[-1])] == "stick"
    assert not np.isin(kinds[:-1], [ts.BRANCH_POINT_TYPE_NAMES.index("stick")]).any()
    # Each flow within the budget (50,000 steps of DOP853's 12 stages, with event location).
    assert int(out["n_rhs"]) < int(out["n_flows"]) * 50_000 * 16
    bil = m.replace(contact="bilateral")
    got = np.asarray(out["min_slip_velocity"])
    assert abs(got[0] / 0.2 - 1) < 1e-12  # the sliding speed itself at the Hopf point
    assert abs(got[-1] / bil.stick_band - 1) < 1e-2  # located: 1.00003e-6 against the band's 1e-6
    # The branch's min_slip_velocity (located at the extremes of v_r on the dense output) against
    # an independent simulation's sampled minimum (2,001 samples a period: at most 2.4e-7 m/s above
    # the true one at this curvature): at the stick point and at the last orbit 1 cm/s clear.
    clear = int(np.flatnonzero(got > 1e-2)[-1])
    assert clear < p.size - 2
    for j in (-1, clear):
        at = bil.replace(normal_load=float(p[j]))
        period = float(np.asarray(out["period"])[j])
        run = ts.simulate(at, period, y0=np.asarray(out["state0"])[j], rtol=1e-11, t_eval=np.linspace(0, period, 2001))
        low = float(np.min(at.sliding_speed - (run.x_dot.values + at.torsion_sign * at.moment_arm
                                               * run.phi_dot.values)))  # fmt: skip
        assert -1e-12 <= low - got[j] < 5e-7, (j, low, got[j])
    # No orbit of the branch slips inside the band (the flag for those: none here).
    in_band = 1 << ts.BRANCH_FLAG_NAMES.index("slip_in_stick_band")
    flagged = (np.asarray(out["flags"]) & in_band) != 0
    assert np.array_equal(flagged, got < bil.stick_band) and not flagged.any()


def test_a_branch_starts_at_a_hopf_point_of_a_mode_that_is_not_the_least_stable():
    """Under the Stribeck switch law at 0.2 m/s, 7.91 cm, sliding is unstable at every load (the
    torsion mode grows), and the friction mode's pair crosses the imaginary axis at 39.6 N (283.6
    rad/s): a Hopf point all the same, which sliding_branch and hopf_curve report. branch(from_hopf=...) starts
    there (it refused it: "the largest growth rate there is 4.079"), with that pair's frequency;
    its cycles are born unstable (the growing mode), and the branch ends where they gain a stick
    phase."""
    base = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3, sliding_speed=0.2)
    m = ts.apparatus_model(84.46, 0.0791, 0.2, base=base)
    sb = ts.sliding_branch(m, ("normal_load", 20.0, 140.0))
    ok = sb.is_hopf.values == 1
    h, om = float(sb.hopf_normal_load.values[ok][0]), float(sb.hopf_frequency.values[ok][0])
    lin = ts.linear_stability(m.replace(normal_load=h))
    assert float(lin.growth_rate) > 1.0  # the least stable mode (torsion) grows there
    friction = lin.sel(mode="friction")
    assert abs(float(friction.mode_growth_rate)) < 1e-6 * om and abs(float(friction.mode_frequency) / om - 1) < 1e-9
    ds = ts.branch(m, "normal_load", 140.0, from_hopf=h, bounds=(20.0, 140.0))
    assert abs(float(ds.period[0]) * om / (2 * np.pi) - 1) < 1e-6
    assert not bool(ds.stable[1]) and int(ds.n_unstable[1]) >= 1
    assert ts.STATUS_NAMES[int(ds.status)] == "success" and "gains a stick phase" in ds.attrs["reason"]
    assert ts.BRANCH_POINT_TYPE_NAMES[int(ds.point_type.values[-1])] == "stick"
    assert 25.2 < float(ds.parameter[-1]) < 25.4


def test_dataset_is_labelled_and_survives_netcdf(bilateral, tmp_path):
    ds = bilateral
    for name, v in ds.data_vars.items():
        assert "long_name" in v.attrs, name
        if name not in ("stable", "point_type", "flags", "status", "state0"):
            assert "units" in v.attrs, name
    assert ds.point_type.attrs["flag_meanings"].split() == list(ts.BRANCH_POINT_TYPE_NAMES)
    assert ds.attrs["continuation_ds_max"] == 0.1 and ds.attrs["continuation_rtol"] == 1e-11
    path = tmp_path / "branch.nc"
    ds.to_netcdf(path)
    back = xr.open_dataset(path)
    np.testing.assert_array_equal(back.period.values, ds.period.values)
    back.close()


def test_bifurcation_diagram_marks_and_labels_the_special_points(bilateral):
    fig = ts.bifurcation_diagram(bilateral)
    ax = fig.axes[0]
    labels = [t.get_text() for t in ax.texts]
    assert labels == ["H", "G"]
    curves = [line for line in ax.lines if len(line.get_xdata()) > 1]
    # The saddle branch is unstable throughout: one dashed line through every point.
    assert len(curves) == 1 and curves[0].get_linestyle() == "--"
    assert len(curves[0].get_xdata()) == bilateral.sizes["branch_point"]


@pytest.mark.parametrize(
    ("args", "kwargs", "needle"),
    [
        (("torsion_sign", 1.0), {"from_hopf": True}, "parameter = 'torsion_sign'"),
        (("nope", 1.0), {"from_hopf": True}, "parameter = 'nope'"),
        (("normal_load", float("nan")), {"from_hopf": True}, "stop = nan"),
        (("normal_load", 84.46), {}, "exactly one of from_hopf and orbit"),
        (("normal_load", 84.46), {"from_hopf": True, "ds": 2.0}, "ds = 2.0"),
        (("normal_load", 84.46), {"from_hopf": True, "max_points": 1}, "max_points = 1"),
        (("normal_load", 84.46), {"from_hopf": True, "stop_at": "cusp"}, "stop_at = 'cusp'"),
        (("normal_load", 84.46), {"from_hopf": 50.0}, "from_hopf = 50.0 is not a Hopf point"),
        (("normal_load", 84.46), {"orbit": ([0.0] * 5, 0.01)}, "shape (5,)"),
        (("normal_load", 84.46), {"orbit": ([0.0] * 6, -1.0)}, "orbit period [s] = -1.0"),
        (("normal_load", 84.46), {"from_hopf": True, "bounds": (90.0, 80.0)}, "bounds"),
        (("normal_load", 84.46), {"orbit": ([0.0] * 6, 0.01), "start": 200.0, "bounds": (1, 100)}, "start = 200.0"),
    ],
)
def test_bad_input_raises_a_value_error_naming_it(args, kwargs, needle):
    with pytest.raises(ValueError, match=None) as e:
        ts.branch(SEED, *args, **kwargs)
    assert needle in str(e.value), str(e.value)


def test_bad_curve_input_raises_a_value_error_naming_it():
    with pytest.raises(ValueError, match="must be two different parameters"):
        ts.fold_curve(SEED, x=("mu", 0.1, 0.3), y=("mu", 0.1, 0.3), from_hopf=0.215)
    with pytest.raises(ValueError, match="n = 1"):
        ts.grazing_curve(SEED, x=("normal_load", 1, 100), y=("mu", 0.2, 0.3), n=1, from_hopf=True)
    with pytest.raises(ValueError, match="must lie within it"):
        ts.fold_curve(SEED, x=("normal_load", 1, 100), y=("mu", 0.25, 0.3), from_hopf=True)
    with pytest.raises(ValueError, match="y = "):
        ts.fold_curve(SEED, x=("normal_load", 1, 100), y="mu", from_hopf=True)
    with pytest.raises(ValueError, match=r"must contain the model's own arm length 0.072 m"):
        ts.fold_curve(SEED_U, x=("normal_load", 50, 300), y=("arm_length", 0.08, 0.1), orbit=(np.zeros(6), 0.01))
    with pytest.raises(ValueError, match="ds must be a tribosweep.branch Dataset"):
        ts.bifurcation_diagram(xr.Dataset())


def test_the_bouncing_cycles_fold_over_the_arm_length_matches_fresh_branches_and_locates_its_jump(bouncing):
    # The family of the seed's bouncing cycle is not born at a Hopf point: the orbit is carried from
    # slice to slice. Independent check: at each arm length the cycle is found afresh (followed from
    # mu = 0.30 by shooting) and its own branch run to its first fold.
    curve = ts.fold_curve(SEED_U, x=("normal_load", 50.0, 300.0), y=("arm_length", 0.0705, 0.0725), n=3,
                          orbit=bouncing)  # fmt: skip
    assert ts.STATUS_NAMES[int(curve.status)] == "success", curve.attrs["reason"]
    for arm in (0.0705, 0.0715, 0.0725):
        model = SEED_U.replace(**ts.arm_frequencies(arm, SEED_U))
        orb, _ = ts.follow_cycle(model)
        fresh = ts.branch(model, "normal_load", 300.0, orbit=orb, stop_at="fold", bounds=(50.0, 300.0))
        got = curve.sel(curve_point=np.flatnonzero(np.isclose(curve.arm_length.values, arm, rtol=0, atol=1e-12))[0])
        # Both locate the fold to locate_tol (1e-8 of the scaled arclength); 1e-6 N is well above.
        assert abs(float(got.normal_load) - float(fresh.parameter[-1])) < 1e-6, (arm, float(got.normal_load))
    # Near 0.0712 m the first fold from the cycle jumps from about 105 N to about 140 N (the lower
    # fold disappears): two segments, the jump bracketed to 1/16 of the 1 mm slice step.
    seg, arms, loads = curve.segment.values, curve.arm_length.values, curve.normal_load.values
    assert set(seg) == {0, 1} and np.all(np.diff(seg) >= 0)
    last0, first1 = arms[seg == 0].max(), arms[seg == 1].min()
    assert 0.0710 < last0 < first1 < 0.0715 and first1 - last0 <= 1e-3 / 16 + 1e-12
    assert loads[seg == 0].max() < 110.0 and loads[seg == 1].min() > 135.0


def test_arm_slices_in_order_with_wrong_guesses_are_those_of_a_loop_in_order():
    """``_slices_in_order`` guesses each slice's Hopf point as if every slice before it found its point,
    runs all guesses at once and corrects them in order: the slices of a plain loop, whatever the
    threads. Fakes: two Hopf points per slice, a branch that finds its point except from 22 N at
    0.07 m, so that the next slice's guess (nearest 22 N) is wrong: it must start nearest 20 N."""
    from tribosweep._curves import _slices_in_order

    ys = [0.05, 0.06, 0.07, 0.08, 0.09]
    values = [[20.0, 20.9], [], [22.0, 23.5], [19.5, 22.5], [24.0, 26.0]]
    hopfs = [(np.array(v), 600.0 + np.arange(len(v))) for v in values]
    calls = []

    def run(y, h, omega):
        calls.append((y, h))
        return (y, h, omega)

    def take(y, h, out):
        assert out[:2] == (y, h)
        return (None, "missed") if (y, h) == (0.07, 22.0) else ({"y": y, "hopf": h, "omega": out[2]}, "")

    def in_order(target):
        out = []
        for y, (v, omegas) in zip(ys, hopfs):
            if not v.size:
                out.append((y, None, "no Hopf point"))
                continue
            i = int(np.argmin(np.abs(v - target)))
            pt, why = take(y, float(v[i]), (y, float(v[i]), float(omegas[i])))
            target = pt["hopf"] if pt is not None else target
            out.append((y, pt, why))
        return out

    want = in_order(19.0)
    assert [pt["hopf"] if pt else why for _, pt, why in want] == [20.0, "no Hopf point", "missed", 19.5, 24.0]
    for workers in (1, 2, 5):
        calls.clear()
        assert _slices_in_order(ys, hopfs, 19.0, run, take, workers) == want
        # Every guess ran once; the wrong one (22.5 N at 0.08 m) was run again from 19.5 N.
        assert sorted(calls) == [(0.05, 20.0), (0.07, 22.0), (0.08, 19.5), (0.08, 22.5), (0.09, 24.0)]


def test_boundary_curves_are_the_same_bits_on_any_number_of_threads():
    """The fold and grazing curves' slices and kinds run in parallel; the dataset does not change."""
    one = ts.boundary_curves(SEED_U, curves=("hopf", "fold", "grazing"), slices=4, threads=1)
    three = ts.boundary_curves(SEED_U, curves=("hopf", "fold", "grazing"), slices=4, threads=3)
    assert one.sizes["fold_point"] > 0 and one.sizes["grazing_point"] > 0
    xr.testing.assert_identical(one, three)
    for k in one.data_vars:
        assert np.array_equal(one[k].values, three[k].values, equal_nan=one[k].dtype.kind == "f"), k
    with pytest.raises(ValueError, match=r"threads = 0 is out of range: must be an integer in \[1, 1024\]"):
        ts.boundary_curves(SEED_U, threads=0)
    with pytest.raises(ValueError, match=r"threads = 2.5 is out of range"):
        ts.fold_curve(SEED_U, x=("normal_load", 10, 150), y=("arm_length", 0.05, 0.1), from_hopf=True, threads=2.5)
