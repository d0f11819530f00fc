"""Issue 12 in the product: ``tribosweep branch`` / ``tribosweep boundary``, the fold and grazing curves
a sweep stores and draws, and the bifurcation diagram's legend. Numbers are checked against the API's
one-parameter tools (``hopf_load``, ``branch``), docs/model.md and plain shooting."""

from __future__ import annotations

import json
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import cli
from tribosweep._boundary import END_INSET

SEED = ts.SliderModel(contact="bilateral")
SEED_U = ts.SliderModel(contact="unilateral")
#: Where a special point may lie from another location of it: each branch locates it to
#: locate_tol = 1e-8 in scaled arclength, in which the load is scaled by its starting magnitude
#: (the Hopf load, at most 150 N here), so each location is good to 1.5e-6 N; two locations, 3e-6 N.
LOCATED_N = 3e-6


def run(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    assert "Traceback" not in out.err
    return code, out.out, out.err


def names(ds):
    return [ts.BRANCH_POINT_TYPE_NAMES[int(t)] for t in ds.point_type.values]


def legend_texts(fig):
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends)
    return [t.get_text() for leg in legends for t in leg.get_texts()]


def test_branch_command_finds_the_grazing_and_the_fold_the_api_finds(tmp_path, capsys, png_size, saved_figures):
    # Bilateral, from the seed's Hopf point to its first grazing point.
    nc = tmp_path / "out" / "b.nc"
    code, out, err = run(["branch", "--contact", "bilateral", "--stop-at", "grazing", "-o", nc], capsys)
    assert code == 0, err
    assert "from the Hopf point at 24.9043 N (subcritical)" in out and "G   grazing" in out
    api = ts.branch(SEED, "normal_load", 150.0, from_hopf=True, bounds=(10.0, 150.0), stop_at="grazing")
    with xr.open_dataset(nc) as ds:
        assert names(ds)[0] == "hopf" and names(ds)[-1] == "grazing"
        assert ds.attrs["Conventions"] == "CF-1.11" and "tribosweep branch --contact bilateral" in ds.attrs["history"]
        assert abs(float(ds.parameter[-1]) - float(api.parameter[-1])) < LOCATED_N
        # The Hopf point: docs/model.md's 24.904 N (3 decimals) and hopf_load's Brent search (the
        # start is located to 1e-13 of the window by sliding_branch; 1e-9 relative is both's accuracy).
        assert abs(float(ds.parameter[0]) / ts.hopf_load(SEED)[0]["normal_load"] - 1) < 1e-9
        assert abs(float(ds.parameter[0]) - 24.904) < 5e-4
        grazing = float(ds.parameter[-1])
    # The diagram: 7.5 x 4.5 in at 120 dpi; its legend names only what is drawn (no stable orbit here).
    png = tmp_path / "out" / "b.png"
    assert png_size(png) == (900, 540)
    texts = legend_texts(saved_figures["b.png"])
    assert texts[0] == "unstable orbit" and not any(t.startswith("stable") for t in texts)
    assert [t.split(":")[0] for t in texts[1:]] == ["H", "G"]

    # Unilateral: the saddle cycle's first fold is that grazing point, where the branch turns back
    # (a non-smooth fold): up to grazing the unilateral orbit is the bilateral one.
    nc2 = tmp_path / "u.nc"
    code, out, err = run(["branch", "--stop-at", "fold", "-o", nc2, "--plot", tmp_path / "u_diagram.png"], capsys)
    assert code == 0, err
    assert "G/F grazing" in out
    api = ts.branch(SEED_U, "normal_load", 150.0, from_hopf=True, bounds=(10.0, 150.0), stop_at="fold")
    with xr.open_dataset(nc2) as ds:
        last = ds.isel(branch_point=-1)
        assert names(ds)[-1] == "grazing" and int(last.flags) & (1 << ts.BRANCH_FLAG_NAMES.index("parameter_turns"))
        assert abs(float(last.parameter) - float(api.parameter[-1])) < LOCATED_N
        assert abs(float(last.parameter) - grazing) < LOCATED_N
    assert [t.split(":")[0] for t in legend_texts(saved_figures["u_diagram.png"])[1:]] == ["H", "G/F"]


def test_branch_command_reads_a_config(tmp_path, capsys, seed_values):
    cfg = tmp_path / "b.toml"
    cfg.write_text(f'contact = "bilateral"\nstop_at = "grazing"\noutput = "{tmp_path / "c.nc"}"\namplitude = "z_max"\n'
                   "[model]\nmu = 0.25\n[continuation]\nmax_points = 400\nds_max = 0.05\n")  # fmt: skip
    code, out, err = run(["branch", "--config", cfg, "--ds-max", "0.08"], capsys)
    assert code == 0, err
    with xr.open_dataset(tmp_path / "c.nc") as ds:
        assert ds.attrs["model_mu"] == 0.25 and ds.attrs["contact"] == "bilateral"
        assert ds.attrs["continuation_max_points"] == 400 and ds.attrs["continuation_ds_max"] == 0.08  # the flag wins
        # docs/model.md's Hopf load at mu = 0.25, printed to 3 decimals.
        assert abs(float(ds.parameter[0]) - seed_values["hopf_load_N"]["0.25"]) < 5e-4
    assert (tmp_path / "c.png").exists()


def test_branch_diagram_legend_shows_a_stable_branch_alone():
    # The bouncing cycle at the seed load is stable until its Neimark-Sacker point near 92 N.
    orbit, _ = ts.follow_cycle(SEED_U)
    ds = ts.branch(SEED_U, "normal_load", 88.0, orbit=orbit)
    assert ds.stable.values.all()
    assert legend_texts(ts.bifurcation_diagram(ds)) == ["stable orbit"]


def test_boundary_command_hopf_and_fold_curves(tmp_path, capsys, png_size, saved_figures):
    nc = tmp_path / "bd.nc"
    code, out, err = run(["boundary", "--curves", "hopf,fold", "--slices", "3", "--threads", "2", "-o", nc], capsys)
    assert code == 0, err
    assert "1 Hopf curve(s) in the box" in out and "map: " in out
    with xr.open_dataset(nc) as ds:
        assert "grazing_normal_load" not in ds
        assert ds.hopf_normal_load.dims == ("hopf_point",) and ds.fold_normal_load.dims == ("fold_point",)
        # Five points of the Hopf curve against hopf_load at their arm lengths (issue 12: 1e-6 relative;
        # the curve's corrector holds 1e-10 of the box, hopf_load's Brent 1e-10 relative).
        for i in np.linspace(0, ds.sizes["hopf_point"] - 1, 5).astype(int):
            arm = float(ds.hopf_arm_length[i])
            (h,) = ts.hopf_load(ts.apparatus_model(50.0, arm, 0.46, base=SEED_U), (1.0, 250.0))
            assert abs(float(ds.hopf_normal_load[i]) / h["normal_load"] - 1) < 1e-6
        # Each fold point is the fold that the one-parameter branch from the Hopf point finds at its arm length.
        arms = ds.fold_arm_length.values
        assert arms.size >= 3 and np.all(np.diff(arms) > 0)
        for i in (0, arms.size - 1):
            m = ts.apparatus_model(84.46, float(arms[i]), 0.46, base=SEED_U)
            b = ts.branch(m, "normal_load", 150.0, from_hopf=True, bounds=(10.0, 150.0), stop_at="fold")
            assert abs(float(ds.fold_normal_load[i]) - float(b.parameter[-1])) < LOCATED_N
        # The first slice (0.05 m) has no fold below 150 N: the curve's end there is located by
        # bisection, within 1/16 of the slice spacing of the box's edge in arm length.
        spacing = (arms.max() - 0.05) / 2
        assert 0.05 < arms[0] < 0.05 + spacing and ds.fold_normal_load.values[0] > 100.0
    assert png_size(tmp_path / "bd.png") == (792, 456)  # 6.6 x 3.8 in at 120 dpi
    texts = legend_texts(saved_figures["bd.png"])
    assert texts[:2] == ["steady sliding stable\n(linear)", "steady sliding unstable\n(growth rate > 0)"]
    assert texts[3:] == ["Hopf curve, subcritical\n(l1 > 0: a saddle cycle)", "fold of cycles: the\nsaddle cycle ends"]


def test_boundary_command_takes_the_friction_law_and_model_fields(tmp_path, capsys):
    """--friction-law and --model reach the curves: the Hopf curve of the Stribeck law (tanh,
    mu_static 0.3, at the default 0.46 m/s) is hopf_load's for that model (issue 12's 1e-6), at
    arm lengths where the constant law has none."""
    nc = tmp_path / "st.nc"
    code, out, err = run(["boundary", "--curves", "hopf", "--friction-law", "coulomb", "--model", "mu_static=0.3",
                          "-o", nc], capsys)  # fmt: skip
    assert code == 0, err
    assert "coulomb friction law (mu_static 0.3, Stribeck velocity 0.1 m/s)" in out
    base = ts.SliderModel(contact="unilateral", friction_law="coulomb", mu_static=0.3)
    with xr.open_dataset(nc) as ds:
        assert ds.attrs["model_friction_law"] == "coulomb" and ds.attrs["model_mu_static"] == 0.3
        inside = np.flatnonzero((ds.hopf_normal_load.values > 11.0) & (ds.hopf_normal_load.values < 149.0))
        assert inside.size > 10
        for i in inside[np.linspace(0, inside.size - 1, 3).astype(int)]:
            arm = float(ds.hopf_arm_length[i])
            (h,) = [r for r in ts.hopf_load(ts.apparatus_model(50.0, arm, 0.46, base=base), (1.0, 250.0))
                    if abs(r["normal_load"] / float(ds.hopf_normal_load[i]) - 1) < 1e-3]  # fmt: skip
            assert abs(float(ds.hopf_normal_load[i]) / h["normal_load"] - 1) < 1e-6
            # The constant law has no Hopf load there at all.
            assert ts.hopf_load(ts.apparatus_model(50.0, arm, 0.46, base=SEED_U), (1.0, 250.0)) == []


def _cf_errors(paths) -> dict[str, list[str]]:
    """High-priority CF 1.11 findings of each file, from one run of the IOOS compliance checker."""
    pytest.importorskip("compliance_checker", reason="compliance-checker is not installed (pip install '.[test]')")
    exe = pathlib.Path(sys.executable).with_name("compliance-checker")
    cmd = str(exe) if exe.exists() else shutil.which("compliance-checker")
    if cmd is None:
        pytest.skip("the compliance-checker command is not on PATH")
    report = pathlib.Path(str(paths[0]) + ".json")
    proc = subprocess.run([cmd, "--test=cf:1.11", "--format=json_new", f"--output={report}", *map(str, paths)],
                          capture_output=True, text=True, timeout=300, check=False)  # fmt: skip
    assert report.exists(), proc.stdout + proc.stderr
    found = {}
    for path, results in json.loads(report.read_text()).items():
        r = results["cf:1.11"]
        assert r["possible_points"] > 0
        found[path] = [f"{c['name']}: {c['msgs']}" for c in r["high_priorities"] if c["value"][0] < c["value"][1] or c["msgs"]]
    assert len(found) == len(paths)
    return found


@pytest.fixture(scope="module")
def unilateral_sweep(tmp_path_factory):
    """A 2 x 2 unilateral sweep that computes cycles (tidf, no census) over the default box: it stores all three curves."""
    path = tmp_path_factory.mktemp("curves") / "s.nc"
    ts.sweep(SEED_U, normal_load=[10.0, 150.0], arm_length=[0.05, 0.127], strategy="tidf", census=False,
             progress=False, threads=1, output=path).close()  # fmt: skip
    return path


def test_the_sweep_stores_the_fold_and_grazing_curves_of_the_api(unilateral_sweep):
    with xr.open_dataset(unilateral_sweep) as ds:
        for kind in ("fold", "grazing"):
            assert ds[f"{kind}_normal_load"].dims == (f"{kind}_point",)
            assert ds[f"{kind}_normal_load"].attrs["units"] == "N" and ds[f"{kind}_arm_length"].attrs["units"] == "m"
        # The fold curve's call that the file records, made again: the same points (the same
        # deterministic computation in one process; 1e-12 relative is far inside any location tolerance).
        call = ds.attrs["fold_curve_call"]
        assert call.startswith("tribosweep.fold_curve(model, x=('normal_load', 10.0, 150.0), y=('arm_length', 0.05, ")
        y_high = float(call.split("('arm_length', 0.05, ")[1].split(")")[0])
        api = ts.fold_curve(SEED_U, x=("normal_load", 10.0, 150.0), y=("arm_length", 0.05, y_high), n=12,
                            from_hopf=float(call.split("from_hopf=")[1].rstrip(")")))  # fmt: skip
        np.testing.assert_allclose(ds.fold_normal_load.values, api.normal_load.values, rtol=1e-12)
        np.testing.assert_allclose(ds.fold_arm_length.values, api.arm_length.values, rtol=1e-12)
        # The curve spans the Hopf curve's arm lengths in the box: from where it leaves the load
        # window (above 0.05 m) to where the Hopf curve leaves the box at 10 N. The last slice is
        # moved along the Hopf curve until its Hopf point lies END_INSET of the window inside (on
        # the bound, finding it was a matter of the last bit: found on one CPU, not on an AMD EPYC).
        # The Hopf load falls by about 2,200 N/m there: 1e-6 of 140 N is some 6e-8 m of arm length.
        hopf_end = ds.hopf_arm_length.values.max()
        assert 0.0 < hopf_end - y_high < 10 * END_INSET * 140.0 / 2200.0
        assert ds.fold_normal_load.values[0] > 145.0 and ds.fold_arm_length.values[-1] == y_high
    # Plain shooting at two points of the stored grazing curve, bilateral law, from the orbit that the
    # one-parameter branch locates there: the top of the orbit touches the disk (shooting converges to
    # a scaled residual of 1e-9 of |z_st|; 1e-11 m is 1e-6 of |z_st|).
    with xr.open_dataset(unilateral_sweep) as ds:
        for i in (1, ds.sizes["grazing_point"] - 2):
            load, arm = float(ds.grazing_normal_load[i]), float(ds.grazing_arm_length[i])
            # The bilateral law, as the grazing curve is computed: at the grazing point the two laws'
            # orbits coincide, and the bilateral flow has no grazing singularity (unilateral shooting
            # converges there or not with the last bit: seen on an AMD EPYC at 146.9 N).
            m = ts.apparatus_model(84.46, arm, 0.46).replace(contact="bilateral")
            b = ts.branch(m, "normal_load", 150.0, from_hopf=True, bounds=(10.0, 150.0), stop_at="grazing")
            assert abs(float(b.parameter[-1]) - load) < LOCATED_N
            m = m.replace(normal_load=load)
            orbit = ts.periodic_orbit(m, (b.state0.values[-1], float(b.period[-1])))
            assert ts.STATUS_NAMES[int(orbit.status)] == "success"
            assert abs(m.static_point()[0] + float(orbit.state0[0])) < 1e-11


def test_the_regime_map_draws_the_fold_and_grazing_curves_with_a_legend_entry_each(unilateral_sweep):
    pytest.importorskip("matplotlib")
    from tribosweep.plot import regime_map

    with xr.open_dataset(unilateral_sweep) as ds:
        fig = regime_map(ds)
        ax = fig.axes[0]
        for kind, width in (("grazing", 2.4), ("fold", 1.1)):
            (line,) = [ln for ln in ax.lines if ln.get_linewidth() == width]
            np.testing.assert_array_equal(line.get_xdata(), ds[f"{kind}_normal_load"].values)
            np.testing.assert_array_equal(line.get_ydata(), ds[f"{kind}_arm_length"].values)
        texts = legend_texts(fig)
        assert "grazing: the saddle cycle\nfirst leaves the disk" in texts
        assert "fold of cycles: the\nsaddle cycle ends" in texts


def test_branch_and_boundary_files_are_cf_1_11(tmp_path, capsys):
    # The boundary file holds the curve variables a sweep stores, with the same attributes (the
    # whole sweep file's check, in test_netcdf, takes 15 s).
    code, _, err = run(["branch", "--contact", "bilateral", "--stop-at", "grazing", "-o", tmp_path / "b.nc"], capsys)
    assert code == 0, err
    code, _, err = run(["boundary", "--curves", "hopf,grazing", "--slices", "2", "-o", tmp_path / "g.nc"], capsys)
    assert code == 0, err
    errors = _cf_errors([tmp_path / "b.nc", tmp_path / "g.nc"])
    assert not any(errors.values()), errors


def test_a_linear_sweep_stores_no_fold_or_grazing_curve_and_a_bilateral_one_no_fold_and_says_why():
    ds = ts.sweep(SEED_U, normal_load=[10.0, 150.0], arm_length=[0.05, 0.127], strategy="linear", progress=False)
    assert "hopf_normal_load" in ds and "fold_normal_load" not in ds and "grazing_normal_load" not in ds
    assert ds.attrs["fold_curves"].startswith("not computed: strategy linear")
    ds = ts.sweep(SEED, normal_load=[10.0, 150.0], arm_length=[0.05, 0.127], strategy="tidf", census=False,
                  progress=False)  # fmt: skip
    # Bilateral: the grazing curve (where its cycles open the contact) is stored, the fold is not.
    assert "fold_normal_load" not in ds and "bilateral contact" in ds.attrs["fold_curves"]
    assert ds.sizes["grazing_point"] >= 2
    uni = ts.boundary_curves(SEED_U, (10.0, 150.0), (0.05, 0.127), curves=("hopf", "grazing"))
    np.testing.assert_allclose(ds.grazing_normal_load.values, uni.grazing_normal_load.values, rtol=1e-12)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["branch", "--parameter", "bogus"], "--parameter = 'bogus' is not valid: must be a real SliderModel field"),
        (["branch", "--parameter", "mu"], "--range is required for --parameter mu"),
        (["branch", "--range", "5"], "'5' is out of range: must be LO:HI with finite LO < HI"),
        (["branch", "--range", "a:b"], "is not a range"),
        (["branch", "--range", "100:150"], "no Hopf point of steady sliding in normal_load"),
        (["branch", "--ds", "2"], "--ds: ds = 2.0 is out of range: must be in (0.0, 1.0)"),
        (["branch", "--ds", "0.2"], "ds = 0.2 is out of range: must be <= ds_max"),
        (["branch", "--max-points", "1"], "max_points = 1 is out of range: must be an integer >= 2"),
        (["branch", "--normal-load", "-5"], "normal_load"),
        (["branch", "--arm-length", "0"], "--arm-length = 0.0 is out of range: must be > 0"),
        (["branch", "--mu", "nan"], "--mu = 'nan' is out of range: must be a finite number"),
        (["branch", "--stop-at", "bogus"], "invalid choice"),
        (["branch", "--amplitude", "bogus"], "--amplitude = 'bogus' is not valid: must be one of A1"),
        (["branch", "--parameter", "omega_normal", "--range", "3000:5000", "--arm-length", "0.06"],
         "is set by --arm-length"),
        (["branch", "--config", "missing.toml"], "missing.toml"),
        (["boundary", "--curves", "hopf,bogus"], "must be a comma-separated subset of hopf,fold,grazing"),
        (["boundary", "--slices", "1"], "--slices = '1' is out of range: must be an integer in [2, 1000]"),
        (["boundary", "--threads", "0"], "--threads = '0' is out of range: must be an integer in [1, 1024]"),
        (["boundary", "--normal-load", "0:150"], "--normal-load = 0:... is out of range: must be > 0"),
        (["boundary", "--arm-length", "0.1:0.1"], "must be LO:HI with finite LO < HI"),
        (["boundary", "--sliding-speed", "x"], "--sliding-speed = 'x' is not a number"),
        (["boundary", "--model", "mu=0.3"], "--model mu: give it with --mu"),
        (["branch", "--friction-law", "switch", "--model", "stick_band=0"], "stick_band = 0.0 is out of range"),
    ],
)
def test_bad_input_exits_2_with_a_one_line_message(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(argv, capsys)
    assert code == 2
    # One line says it all (argparse prints its usage above it).
    (line,) = [ln for ln in err.splitlines() if ln.startswith(f"tribosweep {argv[0]}: error: ")]
    assert message in line
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("command", "text", "message"),
    [
        ("branch", "bogus = 1\n", "unknown keys ['bogus']"),
        ("branch", "[continuation]\nfoo = 1\n", "config [continuation]: unknown keys ['foo']"),
        ("branch", "[model]\nfoo = 1\n", "config [model]"),
        ("branch", "range = 'x'\n", "config range"),
        ("boundary", "normal_load = 5\n", "config normal_load = 5"),
        ("boundary", "model = 1\n", "[model] must be a table"),
        ("boundary", "threads = 0\n", "threads = 0 is out of range: must be an integer in [1, 1024]"),
        ("branch", b"mu = 0.3 # \xe9t\xe9\n", "not UTF-8 text"),
        ("boundary", "normal_load = \n", "not valid TOML"),
    ],
)
def test_bad_config_exits_2(command, text, message, tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_bytes(text) if isinstance(text, bytes) else cfg.write_text(text)
    code, _, err = run([command, "--config", cfg, "-o", tmp_path / "x.nc"], capsys)
    assert code == 2
    assert message in err
