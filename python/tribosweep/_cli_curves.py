"""The ``branch`` and ``boundary`` sub-commands (registered in :mod:`tribosweep.cli`).

``tribosweep branch`` follows a branch of periodic orbits in one parameter from a Hopf point of
steady sliding and writes the branch Dataset (CF netCDF) and its bifurcation diagram (PNG).
``tribosweep boundary`` traces the Hopf, fold-of-cycles, grazing and (switch law) stick curves over a
normal load x arm length box and writes them (CF netCDF) with a map of them (PNG). Bad input raises ``ValueError``
(one line naming the argument, its value and the valid range), which the CLI turns into exit status 2.
"""

from __future__ import annotations

import argparse
import datetime
import math
import os

import numpy as np

#: Continuation settings of ``tribosweep branch``: a flag ``--name-with-dashes`` and a key of the
#: [continuation] table of --config, with the API's name and default (``tribosweep._branch.DEFAULTS``).
BRANCH_SETTINGS: dict[str, tuple[type, str, str]] = {
    "rtol": (float, "R", "relative tolerance of the orbits' integration"),
    "tol": (float, "R", "Newton tolerance of the scaled periodicity residual"),
    "ds": (float, "S", "first step in scaled arclength"),
    "ds_min": (float, "S", "smallest step: a step that fails below it ends the branch with a status and a reason"),
    "ds_max": (float, "S", "largest step"),
    "max_points": (int, "N", "most points on the branch"),
    "locate_tol": (float, "S", "tolerance of the special points, in scaled arclength"),
}
#: Variables of a branch the diagram can draw against the parameter (``--amplitude``).
AMPLITUDES: tuple[str, ...] = ("A1", "A0", "z_max", "z_min", "min_gap", "period", "omega", "min_law_force",
                               "min_slip_velocity", "fraction_off_disk")  # fmt: skip
_OPERATING = ("normal_load", "arm_length", "sliding_speed", "mu")
_BRANCH_KEYS = {"parameter", "range", "start", "stop_at", "amplitude", "contact", "output", "plot", "model",
                "continuation", *_OPERATING}  # fmt: skip
_BOUNDARY_KEYS = {"normal_load", "arm_length", "sliding_speed", "mu", "contact", "curves", "slices", "output", "plot",
                  "threads", "model"}  # fmt: skip
_MODE_FIELDS = ("omega_normal", "omega_friction", "omega_torsion")


def _number(text: str, flag: str) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"{flag} = {text!r} is not a number") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{flag} = {text!r} is out of range: must be a finite number")
    return v


def _range_arg(text: str) -> tuple[float, float]:
    """``LO:HI``, or any axis of the sweep (``START:STOP:NUM``, ``a,b,c``): its lowest and highest values."""
    s = str(text).strip()
    try:
        if ":" in s:
            parts = s.split(":")
            if len(parts) not in (2, 3):
                raise ValueError
            vals = [float(parts[0]), float(parts[1])]
        else:
            vals = [float(v) for v in s.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a range: use LO:HI (or an axis START:STOP:NUM, a,b,c)") from None
    lo, hi = min(vals), max(vals)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise argparse.ArgumentTypeError(f"{text!r} is out of range: must be LO:HI with finite LO < HI")
    return lo, hi


def read_config(path: str, valid: set[str], tables: tuple[str, ...]) -> tuple[dict, str]:
    """A ``--config`` TOML file as a dict (top-level keys in ``valid``, ``tables`` tables) and its text.

    Every way the file can be wrong (missing, unreadable, not UTF-8, not TOML, an unknown key, a
    table that is not one) raises ``ValueError`` naming the file; the CLI prints it in one line.
    """
    import tomllib

    try:
        with open(path, "rb") as f:
            text = f.read().decode("utf-8")
        cfg = tomllib.loads(text)
    except OSError as e:
        raise ValueError(f"--config {path}: {e.strerror or e}") from None
    except UnicodeDecodeError as e:
        raise ValueError(f"--config {path}: not UTF-8 text ({e})") from None
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"--config {path}: not valid TOML ({e})") from None
    unknown = set(cfg) - valid
    if unknown:
        raise ValueError(f"--config {path}: unknown keys {sorted(unknown)}; valid keys are {sorted(valid)}")
    for table in tables:
        if table in cfg and not isinstance(cfg[table], dict):
            raise ValueError(f"--config {path}: [{table}] must be a table")
    return cfg, text


def _config(path: str | None, valid: set[str], tables: tuple[str, ...]) -> dict:
    return {} if path is None else read_config(path, valid, tables)[0]


def _pick(args, cfg: dict, name: str, default=None):
    """The command line's value, else the config's, else ``default``."""
    v = getattr(args, name, None)
    return v if v is not None else cfg.get(name, default)


def _scalar(cfg_value, where: str) -> float:
    if isinstance(cfg_value, bool) or not isinstance(cfg_value, (int, float)):
        raise ValueError(f"{where} = {cfg_value!r} must be one number (SI units)")
    return float(cfg_value)


#: Model fields with their own options (axes, the operating point, the laws): not for ``--model``.
_OWN_OPTIONS = {"normal_load": "--normal-load", "sliding_speed": "--sliding-speed", "mu": "--mu",
                "contact": "--contact", "friction_law": "--friction-law"}  # fmt: skip


def _model_field(text: str) -> tuple[str, float]:
    """``--model FIELD=VALUE``: a real field of SliderModel and its value (checked by the model)."""
    import dataclasses

    from ._model import SliderModel

    name, eq, value = text.partition("=")
    name = name.strip()
    real = sorted(f.name for f in dataclasses.fields(SliderModel) if f.name not in _OWN_OPTIONS)
    if not eq or not name:
        raise argparse.ArgumentTypeError(f"--model {text!r}: must be FIELD=VALUE, e.g. mu_static=0.3")
    if name in _OWN_OPTIONS:
        raise argparse.ArgumentTypeError(f"--model {name}: give it with {_OWN_OPTIONS[name]}")
    if name not in real:
        raise argparse.ArgumentTypeError(f"--model {name}: not a SliderModel field; valid: {', '.join(real)}")
    return name, _number(value.strip(), f"--model {name}")


def add_model_arguments(group, *, contact: bool) -> None:
    """``--friction-law`` and ``--model FIELD=VALUE`` (and ``--contact`` where ``contact``) on ``group``."""
    if contact:
        group.add_argument("--contact", choices=("unilateral", "bilateral"), help="contact law (default unilateral)")
    group.add_argument("--friction-law", choices=("constant", "coulomb", "switch"),
                       help="friction law (default constant mu): coulomb is a Stribeck curve regularised by tanh, "
                       "switch the same curve with stick-slip as an event-driven switch; the curve's static "
                       "coefficient and velocity by --model mu_static=X, stribeck_velocity=V")  # fmt: skip
    group.add_argument("--model", type=_model_field, action="append", default=[], metavar="FIELD=VALUE",
                       help="any other real SliderModel field, e.g. mu_static=0.3 or contact_damping=150 (SI "
                       "units; repeatable; wins over the config's [model] table)")  # fmt: skip


def model_fields(args, cfg: dict) -> dict:
    """The SliderModel fields of the config's [model] table, overridden by ``--contact``,
    ``--friction-law`` and ``--model``; contact unilateral by default."""
    fields = dict(cfg.get("model", {}))
    for name in ("contact", "friction_law"):
        v = _pick(args, cfg, name)
        if v is not None:
            fields[name] = v
    fields.update(dict(args.model))
    fields.setdefault("contact", "unilateral")
    return fields


def law_text(model, sep: str = ", ") -> str:
    """The friction law after ``sep`` for a summary or a title: empty for constant mu, else the law
    and its Stribeck curve."""
    if model.friction_law == "constant":
        return ""
    ms = model.mu if model.mu_static is None else model.mu_static
    return f"{sep}{model.friction_law} friction law (mu_static {ms:g}, Stribeck velocity {model.stribeck_velocity:g} m/s)"


def _model(args, cfg: dict, need: tuple[str, ...]):
    """The model of the operating point: [model] table and the model options (:func:`model_fields`),
    the apparatus at the arm length."""
    from ._apparatus import arm_frequencies
    from ._model import SliderModel

    try:
        base = SliderModel(**model_fields(args, cfg))
    except TypeError as e:
        raise ValueError(f"config [model]: {e}") from None
    values = {}
    for name in need:
        v = _pick(args, cfg, name)
        if v is None:
            continue
        values[name] = _scalar(v, f"--{name.replace('_', '-')}")
    arm = values.pop("arm_length", None)
    if arm is not None and not arm > 0:
        raise ValueError(f"--arm-length = {arm!r} is out of range: must be > 0 [m]")
    return base.replace(**values, **(arm_frequencies(arm, base) if arm is not None else {})), arm


def _history(args) -> str:
    now = datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds")
    return f"{now} tribosweep " + " ".join(args.argv)


def _write(ds, path: str, title: str, args) -> None:
    from . import __version__

    if "state" in ds.coords:  # a text label, not a CF coordinate (those must be numeric and monotonic)
        names = [str(v) for v in ds.state.values]
        ds = ds.drop_vars("state")
        ds["state_name"] = (("state",), np.array(names, dtype=object), {"long_name": "name of each state component"})

    ds.attrs |= {"Conventions": "CF-1.11", "title": title, "institution": "tribosweep",
                 "source": f"tribosweep {__version__}", "history": _history(args)}  # fmt: skip
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    ds.to_netcdf(path, engine="netcdf4")


def _png_path(output: str, plot: str | None) -> str:
    return plot if plot else os.path.splitext(output)[0] + ".png"


# --- branch ------------------------------------------------------------------------------------


def add_branch_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``tribosweep branch``."""
    from ._branch import DEFAULTS, POINT_TYPE_NAMES

    p.add_argument("--parameter", metavar="NAME",
                   help="the model field to continue in (default normal_load): any real SliderModel field but "
                   "torsion_sign (the arm length sets three of them: give it with --arm-length)")  # fmt: skip
    p.add_argument("--range", type=_range_arg, metavar="LO:HI",
                   help="window of the parameter: the branch ends where it leaves it (default for normal_load "
                   "10:150 N; required for any other parameter)")  # fmt: skip
    p.add_argument("--start", type=lambda t: _number(t, "--start"), metavar="X",
                   help="start at the Hopf point of steady sliding nearest X in the window (default: the "
                   "operating point's value)")  # fmt: skip
    p.add_argument("--stop-at", choices=[n for n in POINT_TYPE_NAMES if n not in ("regular", "end", "hopf")],
                   help="end at the first special point of this type")  # fmt: skip
    op = p.add_argument_group(
        "operating point (SI units; one value each; default the seed's 84.46 N, 0.072 m, 0.46 m/s)",
        "The arm length sets the natural frequencies (the apparatus model); the continued parameter starts "
        "at its Hopf point.",
    )
    op.add_argument("--normal-load", type=lambda t: _number(t, "--normal-load"), metavar="N", help="F_st [N]")
    op.add_argument("--arm-length", type=lambda t: _number(t, "--arm-length"), metavar="L", help="arm length [m]")
    op.add_argument("--sliding-speed", type=lambda t: _number(t, "--sliding-speed"), metavar="V", help="V [m/s]")
    op.add_argument("--mu", type=lambda t: _number(t, "--mu"), metavar="MU", help="friction coefficient [1]")
    add_model_arguments(op, contact=True)
    p.add_argument("-o", "--output", metavar="FILE", help="netCDF output file (default branch.nc)")
    p.add_argument("--plot", metavar="PNG", help="bifurcation diagram (default: the output's name with .png)")
    p.add_argument("--amplitude", metavar="VAR",
                   help="vertical axis of the diagram (default A1): one of " + ", ".join(AMPLITUDES))  # fmt: skip
    p.add_argument("--config", metavar="FILE.toml",
                   help="TOML with keys parameter, range, start, stop_at, amplitude, contact, output, plot, "
                   "normal_load, arm_length, sliding_speed, mu and tables [model] (SliderModel fields) and "
                   "[continuation] (the settings below); command-line options win")  # fmt: skip
    g = p.add_argument_group("continuation (also keys of the [continuation] table of --config)")
    for name, (typ, metavar, text) in BRANCH_SETTINGS.items():
        default = DEFAULTS[name]
        shown = f"{int(default)}" if typ is int else f"{default:g}"
        g.add_argument("--" + name.replace("_", "-"), type=typ, metavar=metavar, help=f"{text} (default {shown})")


def _continuation(args, cfg: dict) -> dict:
    from ._branch import _options

    opts = dict(cfg.get("continuation", {}))
    unknown = set(opts) - set(BRANCH_SETTINGS)
    if unknown:
        raise ValueError(f"config [continuation]: unknown keys {sorted(unknown)}; valid: {sorted(BRANCH_SETTINGS)}")
    for name in BRANCH_SETTINGS:
        if getattr(args, name) is not None:
            opts[name] = getattr(args, name)
    for name, v in opts.items():
        try:
            _options({name: v})
        except ValueError as e:
            raise ValueError(f"--{name.replace('_', '-')}: {e}") from None
    _options(opts)  # the step order ds_min <= ds <= ds_max
    return opts


def run_branch(args: argparse.Namespace) -> int:
    """``tribosweep branch``: the branch Dataset and its bifurcation diagram."""
    from . import _branch, _hopf
    from ._codes import STATUS_NAMES

    cfg = _config(args.config, _BRANCH_KEYS, ("model", "continuation"))
    parameter = _branch._parameter(_pick(args, cfg, "parameter", "normal_load"), "--parameter")
    window = args.range if args.range is not None else cfg.get("range")
    if isinstance(window, str):
        try:
            window = _range_arg(window)
        except argparse.ArgumentTypeError as e:
            raise ValueError(f"config range: {e}") from None
    if window is None:
        if parameter != "normal_load":
            raise ValueError(f"--range is required for --parameter {parameter} (give its window LO:HI)")
        window = (10.0, 150.0)
    lo, hi = (float(v) for v in window)
    opts = _continuation(args, cfg)
    stop_at = _pick(args, cfg, "stop_at")
    if stop_at is not None and stop_at not in _branch.POINT_TYPE_NAMES:
        raise ValueError(f"stop_at = {stop_at!r} is not valid: must be one of {_branch.POINT_TYPE_NAMES}")
    amplitude = _pick(args, cfg, "amplitude", "A1")
    if amplitude not in AMPLITUDES:
        raise ValueError(f"--amplitude = {amplitude!r} is not valid: must be one of {', '.join(AMPLITUDES)}")
    model, arm = _model(args, cfg, _OPERATING)
    if parameter in ("omega_normal", "omega_friction", "omega_torsion") and arm is not None:
        raise ValueError(f"--parameter {parameter} is set by --arm-length through the apparatus model: give one")
    output = _pick(args, cfg, "output", "branch.nc")
    png = _png_path(output, _pick(args, cfg, "plot"))
    start = _pick(args, cfg, "start", float(getattr(model, parameter)))
    start = _scalar(start, "--start")
    try:
        sb = _hopf.sliding_branch(model, (parameter, lo, hi))
    except ValueError as e:
        raise ValueError(f"--range {lo:g}:{hi:g}: {e}") from None
    ok = (sb.is_hopf.values == 1) & (sb.hopf_status.values == 0)
    if not ok.any():
        state = "stable" if bool(sb.stable.values.all()) else "unstable" if not sb.stable.values.any() else "mixed"
        raise ValueError(f"--range {lo:g}:{hi:g}: no Hopf point of steady sliding in {parameter} at this operating "
                         f"point (sliding is {state} throughout): no branch of cycles starts there")  # fmt: skip
    values = sb[f"hopf_{parameter}"].values
    i = int(np.flatnonzero(ok)[np.argmin(np.abs(values[ok] - start))])
    hopf = float(values[i])
    crit = _hopf.CRITICALITY_NAMES[int(sb.criticality.values[i])]
    ds = _branch.branch(model, parameter, hi, from_hopf=hopf, bounds=(lo, hi), stop_at=stop_at, **opts)
    ds.attrs |= {"hopf_criticality": crit, "hopf_l1": float(sb.l1.values[i])}
    if arm is not None:
        ds.attrs["arm_length"] = arm
    _write(ds, output, f"tribosweep branch of periodic orbits in {parameter}", args)
    fig = _branch.bifurcation_diagram(ds, amplitude=amplitude)
    os.makedirs(os.path.dirname(os.path.abspath(png)), exist_ok=True)
    fig.savefig(png, dpi=120)
    units = "" if ds.attrs["parameter_units"] == "1" else " " + ds.attrs["parameter_units"]
    print(output)
    print(f"{parameter} from the Hopf point at {hopf:.6g}{units} ({crit}), {model.contact} contact{law_text(model)}: "
          f"{ds.sizes['branch_point']} points in [{lo:g}, {hi:g}]{units}")  # fmt: skip
    print(f"status: {STATUS_NAMES[int(ds.status)]} ({ds.attrs['reason']})")
    names = [_branch.POINT_TYPE_NAMES[int(t)] for t in ds.point_type.values]
    turns = 1 << _branch.BRANCH_FLAG_NAMES.index("parameter_turns")
    special = [k for k, n in enumerate(names) if n not in ("regular", "end")]
    if special:
        print("special points:")
    for k in special:
        pt = ds.isel(branch_point=k)
        label = "G/F" if names[k] == "grazing" and int(pt.flags) & turns else _branch._LABELS[names[k]]
        print(f"  {label:<4}{names[k]:<16}{parameter} = {float(pt.parameter):<14.8g} period = "
              f"{float(pt.period) * 1e3:.6f} ms  A1 = {float(pt.A1) * 1e6:.4g} um  "
              f"{'stable' if int(pt.stable) else 'unstable'}")  # fmt: skip
    print(f"bifurcation diagram: {png}")
    return 0


# --- boundary ----------------------------------------------------------------------------------


def add_boundary_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``tribosweep boundary``."""
    box = p.add_argument_group(
        "box (SI units; LO:HI, or a sweep's axis START:STOP:NUM or a,b,c, of which the ends are taken)",
        "Default: normal load 10:150 N x arm length 0.05:0.127 m, the default sweep's box.",
    )
    box.add_argument("--normal-load", type=_range_arg, metavar="LO:HI", help="normal load F_st [N]")
    box.add_argument("--arm-length", type=_range_arg, metavar="LO:HI", help="clamped arm length [m]")
    box.add_argument("--sliding-speed", type=lambda t: _number(t, "--sliding-speed"), metavar="V",
                     help="sliding speed [m/s] (one value; default 0.46)")  # fmt: skip
    box.add_argument("--mu", type=lambda t: _number(t, "--mu"), metavar="MU", help="friction coefficient [1]")
    add_model_arguments(p, contact=True)
    p.add_argument("--curves", type=_curves_arg, metavar="LIST",
                   help="which curves, comma-separated: hopf,fold,grazing,stick (default all the model can "
                        "have: stick under --friction-law switch only)")  # fmt: skip
    p.add_argument("--slices", type=_slices_arg, metavar="N",
                   help="arm lengths per Hopf curve where the fold, grazing and stick points are located "
                        "(default 12)")
    p.add_argument("--threads", type=_threads_arg, metavar="N",
                   help="threads for the fold, grazing and stick continuations (default: all cores; the curves are the "
                   "same on any number)")  # fmt: skip
    p.add_argument("-o", "--output", metavar="FILE", help="netCDF output file (default boundary.nc)")
    p.add_argument("--plot", metavar="PNG", help="map of the curves (default: the output's name with .png)")
    p.add_argument("--config", metavar="FILE.toml",
                   help="TOML with keys normal_load, arm_length (ranges as strings, or a sweep's axes), "
                   "sliding_speed, mu, contact, curves, slices, threads, output, plot and table [model]; "
                   "command-line options win")  # fmt: skip


def _curves_arg(text: str) -> list[str]:
    from ._boundary import CURVE_KINDS

    items = [t.strip() for t in str(text).split(",") if t.strip()]
    bad = [t for t in items if t not in CURVE_KINDS]
    if bad or not items:
        raise argparse.ArgumentTypeError(f"{text!r} is not valid: must be a comma-separated subset of "
                                         f"{','.join(CURVE_KINDS)}")  # fmt: skip
    return items


def _threads_arg(text: str) -> int:
    from ._checks import MAX_THREADS

    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--threads = {text!r} is not an integer") from None
    if not 1 <= v <= MAX_THREADS:
        raise argparse.ArgumentTypeError(f"--threads = {text!r} is out of range: must be an integer in [1, {MAX_THREADS}]")
    return v


def _slices_arg(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--slices = {text!r} is not an integer") from None
    if not 2 <= v <= 1000:
        raise argparse.ArgumentTypeError(f"--slices = {text!r} is out of range: must be an integer in [2, 1000]")
    return v


def _box(args, cfg: dict, name: str, default: tuple[float, float]) -> tuple[float, float]:
    v = getattr(args, name)
    if v is not None:
        return v
    v = cfg.get(name)
    if v is None:
        return default
    text = v if isinstance(v, str) else ",".join(str(x) for x in v) if isinstance(v, list) else None
    if text is None:
        raise ValueError(f"config {name} = {v!r}: must be a range LO:HI (a string) or a list of numbers")
    try:
        return _range_arg(text)
    except argparse.ArgumentTypeError as e:
        raise ValueError(f"config {name}: {e}") from None


def growth_grid(model, normal_load: tuple[float, float], arm_length: tuple[float, float], n: tuple[int, int] = (141, 78)):
    """Largest growth rate of steady sliding on a grid of the box (the map's shading), as a DataArray."""
    import xarray as xr

    from . import _apparatus, _core

    loads = np.linspace(*normal_load, n[0])
    arms = np.linspace(*arm_length, n[1])
    names = ["normal_load", *_apparatus.MODE_FIELDS.values()]
    ll, aa = np.meshgrid(loads, arms, indexing="ij")
    freqs = [_apparatus.arm_frequencies(a, model) for a in aa.ravel()]
    table = np.column_stack([ll.ravel()] + [[f[k] for f in freqs] for k in names[1:]])
    out = _core.linear_stability(model.values(), model.contact, model.friction_law, names, table, threads=1)
    return xr.DataArray(np.asarray(out["growth_rate"]).reshape(ll.shape), dims=("normal_load", "arm_length"),
                        coords={"normal_load": loads, "arm_length": arms})  # fmt: skip


def run_boundary(args: argparse.Namespace) -> int:
    """``tribosweep boundary``: the Hopf, fold, grazing and stick curves of a normal load x arm length box."""
    from ._boundary import CURVE_KINDS, boundary_curves
    from .plot import boundary_map

    cfg = _config(args.config, _BOUNDARY_KEYS, ("model",))
    loads = _box(args, cfg, "normal_load", (10.0, 150.0))
    arms = _box(args, cfg, "arm_length", (0.05, 0.127))
    for name, (lo, _) in (("--normal-load", loads), ("--arm-length", arms)):
        if not lo > 0:
            raise ValueError(f"{name} = {lo:g}:... is out of range: must be > 0")
    curves = args.curves if args.curves is not None else cfg.get("curves")
    slices = args.slices if args.slices is not None else cfg.get("slices", 12)
    model, _ = _model(args, cfg, ("sliding_speed", "mu"))
    output = _pick(args, cfg, "output", "boundary.nc")
    png = _png_path(output, _pick(args, cfg, "plot"))
    threads = args.threads if args.threads is not None else cfg.get("threads")
    ds = boundary_curves(model, loads, arms, curves=curves, slices=slices, threads=threads)
    # The law on a second line: on one the title overran the axes.
    title = (f"stability boundaries ({model.contact} contact, mu = {model.mu:g}, V = {model.sliding_speed:g} m/s)"
             f"{law_text(model, sep=chr(10))}")  # fmt: skip
    ds.attrs |= {f"model_{k}": v for k, v in model.values().items() if k not in ("normal_load", *_MODE_FIELDS)}
    ds.attrs |= {"model_contact": model.contact, "model_friction_law": model.friction_law,
                 "model_frequencies_at_arm_length": 0.072}  # fmt: skip
    _write(ds, output, "tribosweep stability boundaries over normal load x arm length", args)
    fig = boundary_map(ds, growth=growth_grid(model, loads, arms), title=title)
    os.makedirs(os.path.dirname(os.path.abspath(png)), exist_ok=True)
    fig.savefig(png, dpi=120)
    print(output)
    print(f"box: normal load {loads[0]:g}..{loads[1]:g} N x arm length {arms[0]:g}..{arms[1]:g} m, "
          f"{model.contact} contact, sliding speed {model.sliding_speed:g} m/s, mu {model.mu:g}{law_text(model)}")  # fmt: skip
    for kind in CURVE_KINDS:
        if f"{kind}_curves" in ds.attrs:
            print(f"{kind}: {ds.attrs[f'{kind}_curves']}")
    print(f"map: {png}")
    return 0
