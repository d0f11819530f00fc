"""The command line: tests call cli.main([...]) and check exit codes, files and messages."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import cli
from tribosweep._sweep import chunk as _chunk

_REAL_COMPUTE_CHUNK = _chunk.compute_chunk


def run(argv, capsys):
    code = cli.main([str(a) for a in argv])
    out = capsys.readouterr()
    assert "Traceback" not in out.err
    return code, out.out, out.err


def _check_regime_png(path, ds, x, y, png_size):
    """The regime map a command wrote: its pixel size, the Figure's content through the API, and in the file
    itself each point's cell painted in its regime's colour."""
    import matplotlib.image
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import to_rgb

    from tribosweep.plot import REGIME_COLORS, regime_map

    # One panel: Figure(figsize=(3.6 + 1.8, 3.6)) inches, saved at 120 dpi.
    assert png_size(path) == (648, 432)
    fig = regime_map(ds, x=x, y=y)
    ax = fig.axes[0]
    regime = ds.regime.isel({d: 0 for d in ds.regime.dims if d not in (x, y)}).transpose(y, x).values
    np.testing.assert_array_equal(np.asarray(ax.collections[0].get_array()).reshape(regime.shape), regime)
    for dim, label in ((x, ax.get_xlabel()), (y, ax.get_ylabel())):
        assert label == f"{ds[dim].attrs['long_name']} [{ds[dim].attrs['units']}]"
    names = [ts.REGIME_NAMES[r] for r in sorted(set(regime.ravel().tolist()))]
    texts = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    # The regimes present, in code order, then the marks drawn: the identified load range, and the
    # Hopf curve where the file holds one.
    assert texts[: len(names)] == [n.replace("_", " ") for n in names]
    assert texts[len(names)] == "contact law identified\n(22-93 N)"
    assert texts[len(names) + 1 :] == (["Hopf curve, subcritical\n(l1 > 0: a saddle cycle)"] if "hopf_normal_load" in ds else [])
    # Lay the Figure out as savefig did (120 dpi) to find each cell's centre in the file's pixels.
    fig.set_dpi(120)
    FigureCanvasAgg(fig).draw()
    img = matplotlib.image.imread(path)
    for (j, i), r in np.ndenumerate(regime):
        px, py = ax.transData.transform((ds[x].values[i], ds[y].values[j]))
        rgb = img[img.shape[0] - int(py), int(px), :3]
        np.testing.assert_allclose(rgb, to_rgb(REGIME_COLORS[ts.REGIME_NAMES[r]]), atol=1 / 255)  # 8-bit colour


def test_sweep_info_plot(tmp_path, capsys, png_size):
    nc, png = tmp_path / "s.nc", tmp_path / "s.png"
    code, out, err = run(["sweep", "--normal-load", "10,30,60", "--arm-length", "0.05:0.1:2", "--strategy", "linear",
                          "-o", nc, "--plot", png, "--no-progress", "--threads", "1"], capsys)  # fmt: skip
    assert code == 0, err
    assert "regime:" in out and "steady_sliding" in out
    with xr.open_dataset(nc) as ds:
        assert ds.regime.shape == (3, 2, 1)
        _check_regime_png(png, ds.load(), "normal_load", "arm_length", png_size)
        assert ds.attrs["history"].endswith("--no-progress --threads 1")
        assert "tribosweep sweep --normal-load 10,30,60" in ds.attrs["history"]

    code, out, err = run(["info", nc], capsys)
    assert code == 0, err
    assert "dimensions: normal_load 3 [10 .. 60 N], arm_length 2 [0.05 .. 0.1 m]" in out
    assert "(6 points)" in out and "regime:" in out and "decided_by:" in out and "BELOW a Hopf load" in out

    png2 = tmp_path / "again.png"
    code, out, err = run(["plot", nc, "-o", png2, "--x", "arm_length", "--y", "normal_load"], capsys)
    assert code == 0, err
    with xr.open_dataset(nc) as ds:
        _check_regime_png(png2, ds.load(), "arm_length", "normal_load", png_size)


def test_default_sweep_and_extra_axes(tmp_path, capsys, png_size):
    nc = tmp_path / "new_dir" / "d.nc"
    png = tmp_path / "other_dir" / "d.png"
    code, _, err = run(["sweep", "--strategy", "linear", "-o", nc, "--plot", png, "--no-progress",
                         "--no-boundaries"], capsys)
    assert code == 0, err
    with xr.open_dataset(nc) as ds:
        assert "hopf_normal_load" not in ds  # --no-boundaries: the cells alone, their colours checked
        _check_regime_png(png, ds.load(), "normal_load", "arm_length", png_size)
        np.testing.assert_allclose(ds.normal_load, np.linspace(10, 150, 15))
        np.testing.assert_allclose(ds.arm_length, np.linspace(0.05, 0.127, 4))
        assert ds.sliding_speed.values.tolist() == [0.46]
        assert ds.attrs["model_contact"] == "unilateral"
    nc2 = tmp_path / "e.nc"
    code, _, err = run(["sweep", "--normal-load", "50", "--mu", "0.2,0.25", "--axis", "contact_damping=200:300:2",
                        "--strategy", "linear", "-o", nc2, "--no-progress"], capsys)  # fmt: skip
    assert code == 0, err
    with xr.open_dataset(nc2) as ds:
        assert ds.regime.dims == ("normal_load", "arm_length", "sliding_speed", "mu", "contact_damping")
        assert ds.arm_length.values.tolist() == [0.072]  # one axis given: the others are the seed's


def test_config_file(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text(
        'normal_load = [10.0, 60.0]\narm_length = "0.05:0.1:2"\nmethod = "auto"\nchunk_size = 2\n'
        f'output = "{tmp_path / "cfg.nc"}"\n[axes]\nmu = "0.2,0.25"\n[model]\ntwist_coupling = -45.2e3\n'
        "[solver]\nt_max = 0.001\n"
    )
    code, _, err = run(["sweep", "--config", cfg, "--strategy", "linear", "--no-progress"], capsys)
    assert code == 0, err
    with xr.open_dataset(tmp_path / "cfg.nc") as ds:
        assert ds.attrs["strategy"] == "linear"  # the command line wins
        assert ds.attrs["model_twist_coupling"] == -45.2e3
        assert ds.attrs["solver_t_max"] == 0.001
        assert ds.mu.values.tolist() == [0.2, 0.25]
        assert ds.normal_load.values.tolist() == [10.0, 60.0]


def test_model_options_make_the_api_model_and_win_over_the_config(tmp_path, capsys):
    """Issue 10's Stribeck sweep from the command line: --friction-law and --model FIELD=VALUE give
    the API's model (the same points, bit for bit), field by field over the config's [model] table,
    and `info` names the laws."""
    cfg = tmp_path / "m.toml"
    cfg.write_text('[model]\nfriction_law = "coulomb"\nmu_static = 0.25\nstick_band = 2e-6\n')
    nc = tmp_path / "s.nc"
    axes = dict(normal_load=[20.0, 120.0], arm_length=[0.05, 0.09], sliding_speed=[0.2, 0.6])
    code, out, err = run(["sweep", "--normal-load", "20,120", "--arm-length", "0.05,0.09", "--sliding-speed", "0.2,0.6",
                          "--config", cfg, "--friction-law", "switch", "--model", "mu_static=0.3", "--no-census",
                          "--t-max", "20", "--threads", "1", "-o", nc, "--no-progress"], capsys)  # fmt: skip
    assert code == 0, err
    model = ts.SliderModel(contact="unilateral", friction_law="switch", mu_static=0.3, stick_band=2e-6)
    api = ts.sweep(model, **axes, census=False, t_max=20.0, threads=1, progress=False)
    with xr.open_dataset(nc) as ds:
        assert ds.attrs["model_friction_law"] == "switch" and ds.attrs["model_mu_static"] == 0.3
        assert ds.attrs["model_stick_band"] == 2e-6  # the config's, where no option overrides it
        for var in ("regime", "status", "z1_amplitude", "cycle_omega", "min_slip_velocity"):
            np.testing.assert_array_equal(ds[var].values, api[var].values)
    assert "model: unilateral contact, switch friction law, mu 0.215, mu_static 0.3, Stribeck velocity 0.1 m/s" in out


def test_census_flags_and_config(tmp_path, capsys):
    # Every census setting is a flag and a [census] key; the flag wins over the file.
    nc = tmp_path / "c.nc"
    cfg = tmp_path / "c.toml"
    cfg.write_text("[census]\nsamples = 6\nt_max = 4.0\ndisturbance_scale = 2.5\nrtol = 1e-5\n[solver]\nirregular_block = 64\n")
    code, out, err = run(["sweep", "--normal-load", "84.46", "--config", cfg, "--samples", "4", "--rtol", "1e-7",
                          "--irregular-block", "32", "--census-rtol", "2e-7", "-o", nc, "--no-progress"], capsys)  # fmt: skip
    assert code == 0, err
    with xr.open_dataset(nc) as ds:
        assert ds.attrs["solver_samples"] == 4 and ds.attrs["solver_census_t_max"] == 4.0
        assert ds.attrs["solver_disturbance_scale"] == 2.5 and ds.attrs["solver_rtol"] == 1e-7
        assert ds.attrs["solver_irregular_block"] == 32 and ds.attrs["solver_census_rtol"] == 2e-7
        assert int(ds.census_samples.item()) + int(ds.census_failed.item()) == 4
    assert "attractor census: 1 points, 4 disturbances each" in out
    # 0 turns these off, as their help says (the positive-integer check refused it until 2026-11-28).
    code, _, err = run(["sweep", "--normal-load", "84.46", "--samples", "4", "--irregular-block", "0",
                        "--transient-irregular-block", "0", "--approach-periods", "0", "--census-stop-tol", "1e-4",
                        "-o", tmp_path / "z.nc", "--no-progress"], capsys)  # fmt: skip
    assert code == 0, err
    with xr.open_dataset(tmp_path / "z.nc") as ds:
        assert ds.attrs["solver_irregular_block"] == ds.attrs["solver_transient_irregular_block"] == 0
        assert ds.attrs["solver_approach_periods"] == 0 and ds.attrs["solver_census_stop_tol"] == 1e-4
    code, _, err = run(["sweep", "--normal-load", "84.46", "--no-census", "-o", tmp_path / "n.nc", "--no-progress"],
                       capsys)  # fmt: skip
    assert code == 0, err
    with xr.open_dataset(tmp_path / "n.nc") as ds:
        assert int(ds.census_samples.item()) == 0 and int(ds.bistable.item()) == -1
    # Recurrence: on by default, off by the flag or the [census] key (recorded in the file).
    with xr.open_dataset(nc) as ds:
        assert ds.attrs["solver_census_recurrence"] == 1
    for extra, text in (([], "[census]\nrecurrence = false\n"), (["--no-recurrence"], "")):
        cfg.write_text(text)
        out_nc = tmp_path / f"r{len(extra)}.nc"
        code, _, err = run(["sweep", "--normal-load", "84.46", "--config", cfg, "--samples", "4", "-o", out_nc,
                            "--no-progress", *extra], capsys)  # fmt: skip
        assert code == 0, err
        with xr.open_dataset(out_nc) as ds:
            assert ds.attrs["solver_census_recurrence"] == 0
    cfg.write_text("[census]\nrecurrence = 1\n")
    code, _, err = run(["sweep", "--normal-load", "84.46", "--config", cfg, "-o", tmp_path / "y.nc"], capsys)
    assert code == 2 and "census_recurrence = 1 is not valid: must be true or false" in err, err
    cfg.write_text("[census]\nsamplez = 6\n")
    code, _, err = run(["sweep", "--config", cfg, "-o", tmp_path / "x.nc"], capsys)
    assert code == 2 and "unknown [census] keys ['samplez']" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["sweep", "--normal-load", "3,2"], "not sorted"),
        (["sweep", "--normal-load", "1,1"], "duplicate"),
        (["sweep", "--normal-load=-5,2"], "> 0"),
        (["sweep", "--normal-load", "nan"], "finite"),
        (["sweep", "--normal-load", "a:b:c"], "not an axis"),
        (["sweep", "--normal-load", "1:2:0"], "NUM = 0 is out of range"),
        (["sweep", "--arm-length", "1:2"], "not an axis"),
        (["sweep", "--method", "bogus"], "invalid choice"),
        (["sweep", "--threads", "0"], "must be >= 1"),
        (["sweep", "--chunk-size", "x"], "not an integer"),
        (["sweep", "--axis", "nonsense"], "NAME=SPEC"),
        (["sweep", "--axis", "bogus=1,2"], "unknown field 'bogus'"),
        (["sweep", "--axis", "omega_normal=1,2"], "follows arm_length"),
        (["sweep", "--model", "mu_static"], "--model 'mu_static': must be FIELD=VALUE"),
        (["sweep", "--model", "bogus=1"], "--model bogus: not a SliderModel field; valid: contact_damping, "),
        (["sweep", "--model", "normal_load=5"], "--model normal_load: give it with --normal-load"),
        (["sweep", "--model", "friction_law=2"], "--model friction_law: give it with --friction-law"),
        (["sweep", "--model", "stick_band=x"], "--model stick_band = 'x' is not a number"),
        (["sweep", "--model", "stick_band=-1"], "stick_band = -1.0 is out of range: must be a finite number > 0"),
        (["sweep", "--friction-law", "switch", "--model", "mu_static=0.1"], "mu_static = 0.1 is out of range"),
        (["sweep", "--friction-law", "tanh"], "invalid choice: 'tanh'"),
        (["sweep", "--config", "missing.toml"], "missing.toml"),
        (["info", "missing.nc"], "no such file"),
        (["plot", "missing.nc", "-o", "x.png"], "no such file"),
        (["plot", "x.nc"], "required"),
        (["bogus"], "invalid choice"),
        ([], "give a command"),
    ],
)
def test_bad_input_exits_2_with_a_message(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(argv, capsys)
    assert code == 2
    assert message in err
    assert not (tmp_path / "sweep.nc").exists()


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("bogus = 1\n", "unknown keys ['bogus']"),
        ("normal_load = [1, 'a']\n", "config normal_load"),
        ("[solver]\nfoo = 1\n", "unknown [solver] keys"),
        ("[model]\nfoo = 1\n", "config [model]"),
        ("[model]\nmu = -1.0\n", "mu = -1.0 is out of range"),
        ("normal_load = \n", "not valid TOML"),
        ("[wear_reference]\nload = 1\n", "config [wear_reference]"),
        ("[solver]\nt_max = 'long'\n", "t_max"),
        (b"mu = 0.3 # \xe9t\xe9\n", "not UTF-8 text"),
        ("model = 1\n", "[model] must be a table"),
    ],
)
def test_bad_config_exits_2(text, message, tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_bytes(text) if isinstance(text, bytes) else cfg.write_text(text)
    code, _, err = run(["sweep", "--config", cfg, "-o", tmp_path / "x.nc", "--strategy", "linear"], capsys)
    assert code == 2
    assert message in err


def test_info_on_a_file_that_is_not_a_sweep(tmp_path, capsys):
    path = tmp_path / "other.nc"
    xr.Dataset({"a": ("x", [1.0])}).to_netcdf(path)
    code, _, err = run(["info", path], capsys)
    assert code == 2 and "not a tribosweep sweep" in err
    (tmp_path / "junk.nc").write_text("junk")
    code, _, err = run(["info", tmp_path / "junk.nc"], capsys)
    assert code == 2 and "not a readable netCDF file" in err


def test_interrupt_exits_130_and_resume_finishes(tmp_path, monkeypatch, capsys):
    nc = tmp_path / "r.nc"
    argv = ["sweep", "--normal-load", "10,30,60", "--strategy", "linear", "--chunk-size", "1", "-o", nc, "--no-progress"]
    calls = []

    def interrupt_after_one(*args):
        if calls:
            raise KeyboardInterrupt
        calls.append(1)
        return _REAL_COMPUTE_CHUNK(*args)

    monkeypatch.setattr(_chunk, "compute_chunk", interrupt_after_one)
    code, _, err = run(argv, capsys)
    assert code == 130
    assert "--resume" in err and "1 of 3 chunks" in err
    monkeypatch.undo()
    code, _, err = run(argv, capsys)  # without --resume: refuses to discard the saved chunks
    assert code == 1 and "--resume" in err
    code, _, err = run([*argv, "--resume"], capsys)
    assert code == 0, err
    assert nc.exists() and not (tmp_path / "r.nc.parts").exists()


def test_help_and_version(capsys):
    assert cli.main(["--help"]) == 0
    assert "sweep" in capsys.readouterr().out
    assert cli.main(["sweep", "--help"]) == 0
    out = capsys.readouterr().out
    assert "[N]" in out and "[m]" in out and "[m/s]" in out and "SI units" in out
    assert cli.main(["--version"]) == 0
    assert "tribosweep" in capsys.readouterr().out


def test_python_dash_m(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "tribosweep", "info", tmp_path / "none.nc"], capture_output=True,
                          text=True, timeout=120, check=False)  # fmt: skip
    assert proc.returncode == 2 and "no such file" in proc.stderr and "Traceback" not in proc.stderr


def test_parse_axis():
    assert cli.parse_axis("10:150:15").tolist() == np.linspace(10, 150, 15).tolist()
    assert cli.parse_axis(" 1, 2 ,3").tolist() == [1.0, 2.0, 3.0]
    assert cli.parse_axis("0.46").tolist() == [0.46]


def test_commands_registry_is_extensible():
    assert set(cli.COMMANDS) >= {"sweep", "info", "plot"}
    called = []
    cmd = cli.Command("say hello", lambda p: p.add_argument("--who", default="x"), lambda a: called.append(a.who) or 0)
    cli.COMMANDS["hello"] = cmd
    try:
        assert cli.main(["hello", "--who", "y"]) == 0
        assert called == ["y"]
    finally:
        del cli.COMMANDS["hello"]


def _info_of_edited(tmp_path, capsys, edits: dict) -> str:
    """`tribosweep info` of a small linear sweep with ``edits`` ({(variable, index): value}) written in."""
    nc = tmp_path / "edited.nc"
    ds = ts.sweep(normal_load=[10.0, 30.0], arm_length=[0.05, 0.1], strategy="linear", progress=False)
    for (var, idx), value in edits.items():
        ds[var][idx] = value
    ds.to_netcdf(nc)
    code, out, _ = run(["info", nc], capsys)
    assert code == 0
    return out


def test_info_counts_bistable_points_and_multi_period_cycles(tmp_path, capsys):
    out = _info_of_edited(tmp_path, capsys, {("cycle_period_ratio", (1, 0, 0)): 2.03, ("bistable", (0, 1, 0)): 1,
                                             ("cycle_verified", (1, 0, 0)): 1, ("cycle_verified", (1, 1, 0)): 0})  # fmt: skip
    assert "cycles of several mode periods (period doubling, subharmonic): 1" in out
    assert "transient cycles checked by shooting: 1 verified (a stable orbit, measured on it), 1 not verified" in out
    assert "census largest cycles checked" not in out  # no census: nothing to say
    assert "bistable:" in out and "not_checked" in out and "coexisting" in out
    assert "intermittent motion" not in out  # none: nothing to say


def test_info_counts_intermittent_points_by_their_cycles_instability(tmp_path, capsys):
    kind = "irregular_intermittent_instability"
    out = _info_of_edited(tmp_path, capsys, {(kind, (0, 0, 0)): 2, (kind, (1, 1, 0)): 2, (kind, (1, 0, 0)): 1})
    assert "intermittent motion (back near one unstable cycle between bursts): 3 points; the cycle's instability: " \
        "fold 1, flip 2" in out


def test_every_sweep_argument_is_a_cli_flag_and_a_config_key():
    """The CLI equals the API: each sweep() argument has a flag (or is one of the named CLI-only
    forms) and each analysis setting also a [solver] key, under the API's own name."""
    import inspect

    params = set(inspect.signature(ts.sweep).parameters)
    parser = cli.build_parser()
    sub = next(a for a in parser._subparsers._group_actions[0].choices.values() if a.prog.endswith("sweep"))
    dests = {a.dest for a in sub._actions}
    # Arguments with another form on the command line, and why:
    other = {
        "model": "--contact, --friction-law, --model FIELD=VALUE and the [model] table of --config",
        "extra_axes": "--mu and --axis NAME=SPEC",
        "executor": "an object: no command-line form (dask runs through the API)",
        "progress": "--no-progress",
        "census": "--no-census and [census] enabled",
        "census_recurrence": "--no-recurrence and [census] recurrence",
        "wear_reference": "the [wear_reference] table",
        "wear_calibration": "an object of the API only",
        "command": "the command line itself",
        "method": "deprecated name of --strategy",
        "check_bistability": "deprecated name of census",
        "config_text": "the text of the --config file",
    }
    missing = sorted(p for p in params - set(other) if p not in dests)
    assert missing == []
    settings = params - set(other) - {"normal_load", "arm_length", "sliding_speed", "strategy", "output", "chunk_size", "max_points", "boundaries",
                                      "threads", "resume", "force_resume", "overwrite", "scheduler"}  # fmt: skip
    assert settings <= cli._SOLVER_KEYS
    # The help states the API's default for each (one source of defaults).
    for name in ("t_max", "rtol", "samples", "census_t_max", "ftle_tau", "shooting_rtol"):
        default = inspect.signature(ts.sweep).parameters[name].default
        action = next(a for a in sub._actions if a.dest == name)
        assert f"(default {default:g})" in action.help


def test_an_axis_of_a_hundred_million_values_is_refused_in_one_line(capsys):
    code, _, err = run(["sweep", "--normal-load", "10:20:100000000", "--no-progress"], capsys)
    assert code == 2 and "NUM = 100000000 is out of range" in err and "Traceback" not in err


def test_info_counts_the_slow_approaches(tmp_path, capsys, slow_transients):
    # The switch-law Stribeck point at 10 N, 10.1 cm, 0.2 m/s, its transient started near its cycle
    # (tests/conftest.py), has not repeated by t_max = 10 s; info says which verified cycles were
    # such slow approaches.
    nc = tmp_path / "s.nc"
    code, out, err = run(["sweep", "--friction-law", "switch", "--model", "mu_static=0.3", "--sliding-speed", "0.2",
                          "--normal-load", "10", "--arm-length", "0.10133333333333333", "--no-census", "--t-max", "10",
                          "--approach-periods", "0", "-o", nc, "--no-progress", "--threads", "2"], capsys)  # fmt: skip
    assert code == 0, err
    assert ("transient cycles checked by shooting: 1 verified (a stable orbit, measured on it), 0 not verified (see "
            "reason); 1 of them a slow approach, not repeating by t_max") in out  # fmt: skip
