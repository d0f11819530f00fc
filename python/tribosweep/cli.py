"""Command line: a thin layer over the Python API (``tribosweep`` or ``python -m tribosweep``).

Sub-commands live in the ``COMMANDS`` registry (name -> :class:`Command`); adding one is adding
an entry. Bad input exits with status 2 and a one-line message, never a traceback; an
interrupted sweep exits with 130 and keeps its finished chunks for ``--resume``.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from . import _cli_curves

#: The default sweep around the seed (used when no axis is given on the command line or in a config).
DEFAULT_AXES: dict[str, str] = {"normal_load": "10:150:15", "arm_length": "0.05:0.127:4", "sliding_speed": "0.46"}
_PHYSICS = ("normal_load", "arm_length", "sliding_speed")


@dataclass(frozen=True)
class Command:
    """A sub-command: its help line, how it adds its arguments, and what it runs (-> exit status)."""

    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


class UsageError(ValueError):
    """Bad command-line or config input (exit status 2)."""


#: Most values along one axis from the command line (a typo's 10^8 would fill memory before the
#: sweep's own point cap could refuse it).
MAX_AXIS: int = 10_000_000


def parse_axis(text: str) -> np.ndarray:
    """An axis from ``START:STOP:NUM`` (``numpy.linspace``), ``a,b,c`` or a single number.

    Examples
    --------
    >>> parse_axis("10:30:3").tolist(), parse_axis("1,2.5").tolist(), parse_axis("0.46").tolist()
    ([10.0, 20.0, 30.0], [1.0, 2.5], [0.46])
    """
    text = str(text).strip()
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError
            start, stop, num = float(parts[0]), float(parts[1]), int(parts[2])
            if not 1 <= num <= MAX_AXIS:
                raise argparse.ArgumentTypeError(f"{text!r}: NUM = {num} is out of range: must be an integer in "
                                                 f"[1, {MAX_AXIS}] (values along one axis)")  # fmt: skip
            return np.linspace(start, stop, num)
        return np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not an axis: use START:STOP:NUM, a comma-separated list a,b,c, or one number"
        ) from None


def _axis_value(v, where: str) -> np.ndarray:
    """An axis from a config value: a string spec or a list of numbers."""
    if isinstance(v, str):
        try:
            return parse_axis(v)
        except argparse.ArgumentTypeError as e:
            raise UsageError(f"{where}: {e}") from None
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return np.array([float(v)])
    if isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
        return np.asarray(v, dtype=np.float64)
    raise UsageError(f"{where} = {v!r}: must be a string START:STOP:NUM or a,b,c, a number, or a list of numbers")


def _named_axis(text: str) -> tuple[str, np.ndarray]:
    name, sep, spec = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: use NAME=SPEC, e.g. mu=0.2:0.3:3")
    return name.strip(), parse_axis(spec)


#: Integer settings for which 0 is valid (off, or none), checked by the settings themselves.
_ZERO_OK = {"ftle_warmup", "irregular_block", "transient_irregular_block", "approach_periods"}


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 1")
    return v


# --- sweep -------------------------------------------------------------------------------------

#: Every analysis setting of :func:`tribosweep.sweep`: a flag ``--name-with-dashes`` and a key of the
#: [solver] table of --config, with the API's name and default (``tribosweep._settings``). The value:
#: (argparse group, type, metavar, help).
_SETTINGS: dict[str, tuple[str, object, str, str]] = {
    "t_max": ("integration", float, "S", "longest transient run [s]"),
    "integrator": ("integration", str, "NAME", "time integrator: dop853, dopri5 or rodas4"),
    "rtol": ("integration", float, "R", "relative tolerance of what is measured: irregular motion's window, and the "
             "cycles' shooting checks at ten times tighter"),
    "transient_rtol": ("integration", float, "R", "relative tolerance of the transients, which find each point's "
                       "attractor (1e-6)"),
    "atol": ("integration", "floats", "A", "absolute tolerance: one value or six (default rtol x each state's size)"),
    "periodic_tol": ("integration", float, "R", "relative repetition tolerance that declares a cycle"),
    "approach_periods": ("integration", int, "M", "periods per block of the test that checks an auto transient's "
                         "slow approach to a cycle by shooting inside the run (0: off)"),
    "decay_amplitude": ("integration", float, "M", "amplitude below which a motion has decayed [m] (default "
                        "1e-3 |z_st|)"),
    "disturbance": ("integration", "floats", "Z", "initial z offset [m] of transients, or a state of six values "
                    "(default 1e-6)"),
    "unstable_disturbance": ("integration", float, "X", "auto: transients at unstable points start on the unstable "
                             "mode with |z| = X |z_st|"),
    "shooting_rtol": ("integration", float, "R", "integration tolerance of the shooting stage"),
    "shooting_tol": ("integration", float, "R", "Newton tolerance of the shooting stage"),
    "samples": ("census", int, "K", "census disturbances per point"),
    "census_t_max": ("census", float, "S", "longest run of one census disturbance [s]"),
    "disturbance_scale": ("census", float, "X", "largest modal amplitude of a census disturbance in units of |z_st|"),
    "census_rtol": ("census", float, "R", "relative tolerance of the census disturbances' runs (1e-6)"),
    "census_stop_tol": ("census", float, "R", "repetition tolerance of a census sample's first stop on a cycle, "
                        "checked by shooting (default 1e-3 under speed-dependent friction, none under constant)"),
    "irregular_block": ("irregular", int, "N", "sections per block of the stationarity test that ends a census "
                        "disturbance as irregular motion (0: run to census_t_max)"),
    "transient_irregular_block": ("irregular", int, "N", "the same for the auto transients (0: run to t_max)"),
    "irregular_window": ("irregular", float, "S", "measurement window of irregular motion [s]"),
    "irregular_sample_dt": ("irregular", float, "S", "its sampling interval [s]"),
    "ftle_tau": ("irregular", float, "S", "segment of the Lyapunov exponent [s]"),
    "ftle_segments": ("irregular", int, "M", "segments averaged into the exponent at most (>= 2)"),
    "ftle_min_segments": ("irregular", int, "M", "segments averaged at least; a point 5 standard errors from 0 "
                          "stops there (>= 2)"),
    "ftle_warmup": ("irregular", int, "M", "segments run first and not counted"),
    "ftle_d0": ("irregular", float, "D", "separation of the two trajectories in characteristic sizes"),
    "ftle_rtol": ("irregular", float, "R", "tolerance of the exponent's runs"),
}
_CONFIG_KEYS = {"normal_load", "arm_length", "sliding_speed", "strategy", "method", "output", "chunk_size", "threads",
                "max_points", "boundaries",
                "plot", "axes", "model", "solver", "census", "wear_reference", "dask"}  # fmt: skip
#: Keys of the [dask] table.
_DASK_KEYS = {"scheduler"}
_SOLVER_KEYS = set(_SETTINGS) | {"census"}
#: [census] keys -> sweep() arguments.
_CENSUS_KEYS = {"enabled": "census", "samples": "samples", "t_max": "census_t_max",
                "disturbance_scale": "disturbance_scale", "rtol": "census_rtol", "recurrence": "census_recurrence",
                "stop_tol": "census_stop_tol"}  # fmt: skip


def _default(name: str):
    """The API's default of a setting, for the help text (one source: ``tribosweep._settings``)."""
    from ._settings import DEFAULTS

    opts = DEFAULTS.to_options()
    return {"disturbance": None}.get(name, opts.get(name))


def _floats(text: str) -> float | list[float]:
    try:
        vals = [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number or a comma-separated list of numbers") from None
    return vals[0] if len(vals) == 1 else vals


def _load_config(path: str) -> tuple[dict, str]:
    """The config file as a dict (checked) and its text (recorded in the output file)."""
    try:
        tables = ("axes", "model", "solver", "census", "wear_reference", "dask")
        cfg, text = _cli_curves.read_config(path, _CONFIG_KEYS, tables)
    except ValueError as e:
        raise UsageError(str(e)) from None
    unknown = set(cfg.get("solver", {})) - _SOLVER_KEYS
    if unknown:
        raise UsageError(f"--config {path}: unknown [solver] keys {sorted(unknown)}; valid: {sorted(_SOLVER_KEYS)}")
    unknown = set(cfg.get("census", {})) - set(_CENSUS_KEYS)
    if unknown:
        raise UsageError(f"--config {path}: unknown [census] keys {sorted(unknown)}; valid: {sorted(_CENSUS_KEYS)}")
    unknown = set(cfg.get("dask", {})) - _DASK_KEYS
    if unknown:
        raise UsageError(f"--config {path}: unknown [dask] keys {sorted(unknown)}; valid: {sorted(_DASK_KEYS)}")
    return cfg, text


def _add_sweep_arguments(p: argparse.ArgumentParser) -> None:
    axes = p.add_argument_group(
        "axes (SI units; START:STOP:NUM for NUM evenly spaced values, a,b,c for a list, or one value)",
        "With no axis given (here or in --config): normal load 10:150:15 N x arm length 0.05:0.127:4 m x "
        "sliding speed 0.46 m/s. Otherwise a missing physics axis is its seed value (84.46 N, 0.072 m, 0.46 m/s).",
    )
    axes.add_argument("--normal-load", type=parse_axis, metavar="SPEC", help="normal load F_st [N]")
    axes.add_argument("--arm-length", type=parse_axis, metavar="SPEC", help="clamped arm length [m]")
    axes.add_argument("--sliding-speed", type=parse_axis, metavar="SPEC", help="sliding speed V [m/s]")
    axes.add_argument("--mu", type=parse_axis, metavar="SPEC", help="friction coefficient [1] (an extra axis)")
    axes.add_argument("--axis", type=_named_axis, action="append", default=[], metavar="NAME=SPEC",
                      help="an extra axis over any real model field, e.g. contact_damping=100:300:3 (SI units)")  # fmt: skip
    model = p.add_argument_group("model (also the [model] table of --config; these options win)",
                                 "The seed apparatus (docs/model.md); the arm length sets its natural frequencies.")
    _cli_curves.add_model_arguments(model, contact=True)
    p.add_argument("-o", "--output", metavar="FILE", help="netCDF output file (default sweep.nc)")
    p.add_argument("--strategy", choices=("auto", "linear", "tidf", "shooting", "transient"),
                   help="auto (default): each point gets the cheapest model that decides it (eigenvalues, the "
                   "describing function, shooting, a transient, the attractor census); linear: eigenvalues only; "
                   "tidf/shooting: also the describing function/periodic orbit everywhere; transient: integrate "
                   "every point")  # fmt: skip
    p.add_argument("--method", choices=("auto", "linear", "tidf", "shooting", "transient"),
                   help=argparse.SUPPRESS)  # deprecated name of --strategy
    p.add_argument("--threads", type=_positive_int, metavar="N", help="worker threads (default: all cores)")
    p.add_argument("--resume", action="store_true", help="finish an interrupted sweep from FILE.parts/")
    p.add_argument("--force-resume", action="store_true",
                   help="resume even though the parts were computed by other code (another version or core build); "
                   "the file records it")  # fmt: skip
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing output file (once the new one is complete); without it an existing file "
                   "is refused before any work")  # fmt: skip
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run the chunks on a dask cluster: a scheduler address (tcp://host:8786), or local:N to start "
                   "N worker processes here (needs tribosweep[dask]; also [dask] scheduler in --config)")  # fmt: skip
    p.add_argument("--config", metavar="FILE.toml",
                   help="TOML with keys normal_load, arm_length, sliding_speed, strategy, output, chunk_size, "
                   "threads, plot and tables [axes], [model] (SliderModel fields), [solver] (every setting below, "
                   "with its flag's name in snake_case), [census], [wear_reference], [dask] (scheduler); command-line "
                   "options win; its text is recorded in the output file")  # fmt: skip
    p.add_argument("--chunk-size", type=_positive_int, metavar="N", help="points per saved chunk")
    p.add_argument("--max-points", type=_positive_int, metavar="N",
                   help="largest sweep accepted (default 10000000): a bigger one is refused before any work")
    p.add_argument("--plot", metavar="PNG", help="also write the regime map to this image")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-boundaries", dest="boundaries", action="store_false",
                   help="do not store the Hopf, fold and grazing curves crossing a normal load x arm length box")
    groups = {
        "integration": p.add_argument_group("integration (also keys of the [solver] table of --config)"),
        "irregular": p.add_argument_group(
            "irregular motion (also keys of the [solver] table)",
            "a bounded run that neither repeats nor decays by --t-max is regime irregular, measured from where it "
            "ended: z range and dominant frequency over a window, and the largest finite-time Lyapunov exponent "
            "(about 0: quasi-periodic; > 0: chaotic) with its standard error.",
        ),
        "census": p.add_argument_group(
            "attractor census (also the [census] table: enabled, samples, t_max, disturbance_scale, rtol, "
            "recurrence)",
            "auto: at stable points with a saddle cycle, and at unstable points whose transient reached a motion, K "
            "disturbances on the torsion and normal modes are each run to their attractor; the sweep reports the "
            "fraction reaching sliding / a cycle / irregular motion / escape, with standard errors. It is most of an auto sweep's cost (about K runs of up to --census-t-max "
            "seconds each).",
        ),
    }
    groups["census"].add_argument("--no-census", action="store_true", help="skip the census (fractions left empty)")
    groups["census"].add_argument("--no-recurrence", action="store_true",
                                  help="every census disturbance decides by its own blocks, none by recurrence on an "
                                  "irregular attractor a pilot sample of its point established")  # fmt: skip
    for name, (group, kind, metavar, text) in _SETTINGS.items():
        default = _default(name)
        shown = "" if default is None or "(default" in text else f" (default {default:g})" if isinstance(
            default, (int, float)) else f" (default {default})"  # fmt: skip
        typ = _floats if kind == "floats" else _positive_int if kind is int and name not in _ZERO_OK else kind
        groups[group].add_argument("--" + name.replace("_", "-"), type=typ, metavar=metavar, help=text + shown)


def _strategy(args: argparse.Namespace, cfg: dict) -> str:
    """--strategy, else the config's ``strategy``; the old name ``method`` still works, with a note."""
    for given, where in ((args.method, "--method"), (cfg.get("method"), "config key method")):
        if given is not None:
            sys.stderr.write(f"tribosweep: {where} is renamed strategy (method is the time integrator elsewhere); "
                             "the old name goes away in 0.3\n")  # fmt: skip
    return args.strategy or args.method or cfg.get("strategy") or cfg.get("method") or "auto"


def _run_sweep(args: argparse.Namespace) -> int:
    from ._model import SliderModel
    from ._sweep import sweep
    from ._wear import WearReference

    cfg, config_text = _load_config(args.config) if args.config else ({}, None)
    axes = {}
    for name in _PHYSICS:
        cli = getattr(args, name)
        if cli is not None:
            axes[name] = cli
        elif name in cfg:
            axes[name] = _axis_value(cfg[name], f"config {name}")
    if not axes:
        axes = {name: parse_axis(spec) for name, spec in DEFAULT_AXES.items()}
    extra = {k: _axis_value(v, f"config [axes] {k}") for k, v in cfg.get("axes", {}).items()}
    if args.mu is not None:
        extra["mu"] = args.mu
    for name, values in args.axis:
        extra[name] = values
    try:
        model = SliderModel(**_cli_curves.model_fields(args, cfg))
    except TypeError as e:
        raise UsageError(f"config [model]: {e}") from None
    solver = dict(cfg.get("solver", {}))
    solver.update({_CENSUS_KEYS[k]: v for k, v in cfg.get("census", {}).items()})
    for key in _SETTINGS:
        if getattr(args, key) is not None:
            solver[key] = getattr(args, key)
    if args.no_census:
        solver["census"] = False
    if args.no_recurrence:
        solver["census_recurrence"] = False
    try:
        wear_reference = WearReference(**cfg["wear_reference"]) if "wear_reference" in cfg else None
    except TypeError as e:
        raise UsageError(f"config [wear_reference]: {e}") from None
    output = args.output or cfg.get("output") or "sweep.nc"
    plot = args.plot or cfg.get("plot")
    command = "tribosweep " + " ".join(args.argv)
    ds = sweep(
        model,
        **axes,
        extra_axes=extra or None,
        strategy=_strategy(args, cfg),
        output=output,
        chunk_size=args.chunk_size or cfg.get("chunk_size"),
        max_points=args.max_points or cfg.get("max_points", 10_000_000),
        boundaries=args.boundaries and cfg.get("boundaries", True),
        threads=args.threads or cfg.get("threads"),
        resume=args.resume,
        force_resume=args.force_resume,
        overwrite=args.overwrite,
        scheduler=args.scheduler or cfg.get("dask", {}).get("scheduler"),
        config_text=config_text,
        progress=not args.no_progress,
        wear_reference=wear_reference,
        command=command,
        **solver,
    )
    with ds:
        print(describe(ds, output))
        if plot:
            from .plot import save_regime_map

            save_regime_map(ds, plot)
            print(f"regime map: {plot}")
    return 0


# --- info --------------------------------------------------------------------------------------


def _model_line(ds) -> str:
    """The contact and friction laws a sweep file records (its ``model_*`` attributes)."""
    a = ds.attrs
    mu = "mu on an axis" if "mu" in ds.regime.dims else f"mu {float(a.get('model_mu', float('nan'))):g}"
    law = str(a.get("model_friction_law", "constant"))
    text = f"{a['model_contact']} contact, {law} friction law, {mu}"
    if law != "constant":
        ms = a.get("model_mu_static")
        ms = "= mu" if ms is None or not np.isfinite(ms) else f"{float(ms):g}"
        text += f", mu_static {ms}, Stribeck velocity {float(a.get('model_stribeck_velocity', float('nan'))):g} m/s"
    return text


def describe(ds, path: str | None = None) -> str:
    """A short text summary of a sweep Dataset: dimensions, regime counts, key attributes."""
    lines = [str(path)] if path else []
    dims = []
    for d in ds.regime.dims:
        v = ds[d].values
        units = ds[d].attrs.get("units", "")
        span = f"{v[0]:g}" if v.size == 1 else f"{v[0]:g} .. {v[-1]:g}"
        dims.append(f"{d} {v.size} [{span} {units}]".replace(" ]", "]"))
    lines.append("dimensions: " + ", ".join(dims) + f" ({int(ds.regime.size)} points)")
    if "model_contact" in ds.attrs:
        lines.append("model: " + _model_line(ds))
    for key in ("strategy", "source", "history"):
        if key in ds.attrs:
            lines.append(f"{key}: {ds.attrs[key]}")
    for var in ("regime", "decided_by", "status", "bistable"):
        if var not in ds:
            continue
        names = str(ds[var].attrs.get("flag_meanings", "")).split()
        values = np.asarray(ds[var].attrs.get("flag_values", np.arange(len(names))))
        codes = np.asarray(ds[var].values).ravel()
        counts = [(n, int(np.count_nonzero(codes == v))) for v, n in zip(values, names)]
        lines.append(f"{var}:")
        lines.extend(f"  {n:<24s}{c:>8d}" for n, c in counts if c)
    if "cycle_period_ratio" in ds:
        r = np.asarray(ds.cycle_period_ratio.values).ravel()
        multi = np.isfinite(r) & (np.rint(np.where(np.isfinite(r), r, 0)) >= 2)
        if multi.any():
            lines.append(f"cycles of several mode periods (period doubling, subharmonic): {int(multi.sum())}")
    for var, what in (("cycle_verified", "transient cycles"), ("largest_cycle_verified", "census largest cycles")):
        if var in ds:
            v = np.asarray(ds[var].values).ravel()
            if (v >= 0).any():
                slow = ""
                if var == "cycle_verified" and "reason" in ds:
                    from ._cycles import SLOW_MARK

                    n = sum(SLOW_MARK in str(r) for r in np.asarray(ds.reason.values).ravel())
                    slow = f"; {n} of them a slow approach, not repeating by t_max" if n else ""
                lines.append(f"{what} checked by shooting: {int((v == 1).sum())} verified (a stable orbit, measured on "
                             f"it), {int((v == 0).sum())} not verified (see reason){slow}")  # fmt: skip
    if "irregular_ftle" in ds:
        f = np.asarray(ds.irregular_ftle.values).ravel()
        se = np.asarray(ds.irregular_ftle_se.values).ravel()
        w = np.asarray(ds.irregular_omega.values).ravel()
        has = np.isfinite(f)
        if has.any():
            f, se, w = f[has], se[has], w[has]
            lines.append(f"irregular motion: {int(has.sum())} points measured; largest FTLE {f.min():.3g} .. "
                         f"{f.max():.3g} 1/s (median {np.median(f):.3g}); chaotic (FTLE > 5 SE) "
                         f"{int((f > 5 * se).sum())}, about 0 (within 3 SE: quasi-periodic, or slow) "
                         f"{int((np.abs(f) <= 3 * se).sum())}; dominant frequency {np.nanmin(w):.4g} .. "
                         f"{np.nanmax(w):.4g} rad/s")  # fmt: skip
    if "irregular_intermittent_instability" in ds:
        kind = np.asarray(ds.irregular_intermittent_instability.values).ravel()
        if (kind > 0).any():
            names = ds.irregular_intermittent_instability.attrs.get("flag_meanings", "").split()
            counts = ", ".join(f"{names[k] if k < len(names) else k} {int((kind == k).sum())}"
                               for k in np.unique(kind[kind > 0]))  # fmt: skip
            lines.append(f"intermittent motion (back near one unstable cycle between bursts): {int((kind > 0).sum())} "
                         f"points; the cycle's instability: {counts}")  # fmt: skip
    if "basin_fraction" in ds and "census_samples" in ds:
        k = np.asarray(ds.census_samples.values).ravel()
        if (k > 0).any():
            # Basin stability means something where sliding is stable; past it, what coexists.
            unstable = np.asarray(ds.growth_rate.values).ravel() > 0 if "growth_rate" in ds else np.zeros(k.size, bool)
            bs = np.asarray(ds.basin_stability.values).ravel()[(k > 0) & ~unstable]
            text = f"attractor census: {int((k > 0).sum())} points, {int(k.max())} disturbances each"
            if bs.size:
                text += (f"; stable sliding ({bs.size}): basin stability median {np.median(bs):.2f} (min {bs.min():.2f}, "
                         f"max {bs.max():.2f})")  # fmt: skip
            past = (k > 0) & unstable
            meanings = str(ds.bistable.attrs.get("flag_meanings", "")).split() if "bistable" in ds else []
            if past.any() and "coexisting" in meanings:
                code = np.asarray(ds.bistable.attrs["flag_values"])[meanings.index("coexisting")]
                both = int((np.asarray(ds.bistable.values).ravel()[past] == code).sum())
                text += f"; unstable sliding ({int(past.sum())}): more than one motion at {both}"
                if "regime_fraction" in ds:
                    rf = np.asarray(ds.regime_fraction.values).ravel()[past]
                    text += f", the regime reached by fewer than half the disturbances at {int((rf < 0.5).sum())}"
            lines.append(text)
    from ._boundary import CURVE_KINDS

    curves = []
    for kind in CURVE_KINDS:  # the stored boundary curves (a load x arm sweep)
        if f"{kind}_normal_load" in ds and ds[f"{kind}_normal_load"].size:
            load, arm = ds[f"{kind}_normal_load"].values, ds[f"{kind}_arm_length"].values
            curves.append(f"{kind} {load.size} points ({load.min():.4g} .. {load.max():.4g} N, arm length "
                          f"{arm.min():.4g} .. {arm.max():.4g} m)")  # fmt: skip
    if curves:
        lines.append("boundary curves: " + "; ".join(curves))
    for var, dim in (("normal_load_extrapolated", "loads"), ("arm_length_extrapolated", "arm lengths")):
        if var in ds:
            v = np.asarray(ds[var].values)
            lines.append(f"extrapolated {dim}: {int(v.sum())} of {v.size}")
    if "comment" in ds.attrs:
        lines.append(f"note: {ds.attrs['comment']}")
    return "\n".join(lines)


def _add_info_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", help="a sweep's netCDF file")


def _open(path: str):
    import xarray as xr

    if not os.path.isfile(path):
        raise UsageError(f"{path}: no such file")
    try:
        ds = xr.open_dataset(path, engine="netcdf4")
    except (OSError, ValueError) as e:
        raise UsageError(f"{path}: not a readable netCDF file ({e})") from None
    if "regime" not in ds:
        ds.close()
        raise UsageError(f"{path}: not a tribosweep sweep (no regime variable)")
    return ds


def _run_info(args: argparse.Namespace) -> int:
    with _open(args.file) as ds:
        print(describe(ds, args.file))
    return 0


# --- plot --------------------------------------------------------------------------------------


def _add_plot_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", help="a sweep's netCDF file")
    p.add_argument("-o", "--output", required=True, metavar="PNG", help="image file (format from the extension)")
    p.add_argument("--x", metavar="DIM", help="dimension on the x axis (default normal_load)")
    p.add_argument("--y", metavar="DIM", help="dimension on the y axis (default arm_length)")
    p.add_argument("--facet", metavar="DIM", help="dimension with one panel per value (default sliding_speed)")
    p.add_argument("--mark-points", action="store_true", help="mark each computed grid point with a dot")
    p.add_argument("--var", metavar="NAME", default="regime",
                   help="the variable to draw (default regime): any per-point variable, e.g. growth_rate, "
                   "z1_amplitude, basin_fraction (one panel per attractor), status")

def _run_plot(args: argparse.Namespace) -> int:
    from .plot import save_regime_map

    with _open(args.file) as ds:
        save_regime_map(ds, args.output, x=args.x, y=args.y, facet=args.facet, var=args.var,
                        mark_points=args.mark_points)
    print(f"{args.var} map: {args.output}")
    return 0


# --- bench -------------------------------------------------------------------------------------

_BENCH_SKIPPABLE = ("scipy", "numba", "diffrax", "maps")


def _skip_list(text: str) -> list[str]:
    items = [t.strip() for t in str(text).split(",") if t.strip()]
    bad = [t for t in items if t not in _BENCH_SKIPPABLE]
    if bad:
        raise argparse.ArgumentTypeError(f"{','.join(bad)}: can skip only {', '.join(_BENCH_SKIPPABLE)}")
    return items


def _rtol_list(text: str) -> list[float]:
    values = parse_axis(text).tolist()
    if not values or not all(1e-15 <= v < 1 for v in values):
        raise argparse.ArgumentTypeError(f"{text!r}: every rtol must be in [1e-15, 1)")
    return values


def _add_bench_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quick", action="store_true",
                   help="fewer rtol rungs (1e-4..1e-12, every other decade), trajectories and map points: "
                   "about a minute on two cores")  # fmt: skip
    p.add_argument("-o", "--out", default="bench_out", metavar="DIR",
                   help="output folder: work_precision.csv/.json, wp_<scene>.png, failure_*.png/.nc, summary.md "
                   "(default bench_out)")  # fmt: skip
    p.add_argument("--docs", metavar="FILE.md", help="also write the summary (no images) here, e.g. docs/benchmarks.md")
    p.add_argument("--scene", action="append", choices=("seed", "unilateral", "stick_slip", "large_amplitude"),
                   help="only this scene (repeatable; default all four)")  # fmt: skip
    p.add_argument("--rtol", type=_rtol_list, metavar="SPEC", help="the rtol ladder, e.g. 1e-4,1e-8 (overrides --quick's)")
    p.add_argument("--n", type=_positive_int, metavar="N", help="trajectories per scene (default: per scene)")
    p.add_argument("--method", action="append", choices=("dopri5", "dop853", "rodas4"),
                   help="only this Rust integrator (repeatable; default all three)")  # fmt: skip
    p.add_argument("--skip", type=_skip_list, action="append", default=[], metavar="WHAT",
                   help="skip baselines or parts: any of scipy,numba,diffrax,maps (comma-separated)")  # fmt: skip
    p.add_argument("--threads", type=_positive_int, metavar="N",
                   help="threads of the failure maps (default all cores; the timed runs always use one)")  # fmt: skip
    p.add_argument("--no-progress", action="store_true", help="no progress lines on stderr")


def _run_bench(args: argparse.Namespace) -> int:
    # The bench wing is reached only from here (its extra: pip install tribosweep[bench]).
    from .bench.analysis import law_comparison, speed_ratios
    from .bench.scenes import MATCHED_ERRORS
    from .bench.workprecision import BenchConfig, run_work_precision

    skip = {s for group in args.skip for s in group}
    config = BenchConfig(
        quick=args.quick,
        scenes=args.scene,
        ladder=args.rtol,
        n_traj=args.n,
        methods=tuple(args.method) if args.method else ("dopri5", "dop853", "rodas4"),
        baselines=tuple(b for b in ("scipy", "numba", "diffrax") if b not in skip),
    )
    payload = run_work_precision(args.out, config, failure_maps="maps" not in skip, docs=args.docs,
                                 progress=not args.no_progress, command="tribosweep " + " ".join(args.argv),
                                 map_threads=args.threads)  # fmt: skip
    rows = payload["rows"]
    n_fail = sum(r["failed"] for r in rows)
    print(f"{len(rows)} rungs measured ({n_fail} failed) in {payload['meta']['seconds']:.0f} s")
    for q in speed_ratios(rows, MATCHED_ERRORS):
        r = q["ratio"]
        speed = f"{r:.3g}x faster than" if r >= 1 else f"{1 / r:.3g}x slower than"
        print(f"  {q['scene']:<16} error {q['error']:.0e}: {q['rust_label']} {speed} {q['baseline_label']}")
    for q in law_comparison(rows, payload["scenes"], MATCHED_ERRORS):
        print(f"  {q['scene']:<16} error {q['error']:.0e}: {q['method']} tanh / {q['variant']} law: "
              f"{q['rhs_ratio']:.3g}x the rhs calls, {q['time_ratio']:.3g}x the time")
    for name in ("summary", "csv", "json", "docs"):
        if name in payload["files"]:
            print(f"{name}: {payload['files'][name]}")
    return 0


#: Sub-commands by name (add one here to extend the CLI).
def _add_seed_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="out", help="output directory for seed_report.md and seed_report.json (default: out)")


def _run_seed(args: argparse.Namespace) -> int:
    from ._report import write_seed_report

    print(write_seed_report(args.out))
    return 0


COMMANDS: dict[str, Command] = {
    "seed": Command("analyse the seed configuration: stability, describing function, orbits, comparison table",
                    _add_seed_arguments, _run_seed),
    "sweep": Command("map the regime over normal load x arm length x sliding speed", _add_sweep_arguments, _run_sweep),
    "info": Command("summarise a sweep file", _add_info_arguments, _run_info),
    "plot": Command("draw a sweep file's regime map", _add_plot_arguments, _run_plot),
    "branch": Command("follow a branch of periodic orbits in one parameter from a Hopf point: netCDF and a "
                      "bifurcation diagram", _cli_curves.add_branch_arguments, _cli_curves.run_branch),
    "boundary": Command("the Hopf, fold and grazing curves over a normal load x arm length box: netCDF and a map",
                        _cli_curves.add_boundary_arguments, _cli_curves.run_boundary),
    "bench": Command(
        "work-precision charts and failure maps of the integrators against scipy/numba baselines",
        _add_bench_arguments,
        _run_bench,
    ),
}


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (the usage is for ``--help``)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every registered sub-command."""
    from . import __version__

    parser = _Parser(
        prog="tribosweep",
        description="Friction-induced vibration of the 1985 pin-on-disk slider: regime maps over load, arm length "
        "and sliding speed. SI units: N, m, m/s.",
    )
    parser.add_argument("--version", action="version", version=f"tribosweep {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, cmd in COMMANDS.items():
        p = sub.add_parser(name, help=cmd.help, description=cmd.help)
        cmd.add_arguments(p)
    return parser


#: A value that starts like a negative number (``-5``, ``-.5``, ``-5:100:3``, ``-1e-6,0``).
_NEGATIVE = re.compile(r"-\.?\d")


def _attach_negative_values(parser: argparse.ArgumentParser, argv: list[str]) -> list[str]:
    """``--opt -5:100:3`` as ``--opt=-5:100:3``, for every option that takes a value.

    argparse (before Python 3.13) reads a word that starts with ``-`` and is not a plain number as
    an option, so ``--normal-load -5:100:3`` failed with "expected one argument". No option of ours
    looks like a number, so such a word after a value-taking option is its value; the range check
    (a load must be > 0, ...) then says what is wrong with it.
    """
    takes_value = set()
    for action in parser._actions:  # argparse's own list (private, stable since 2.7)
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                takes_value.update(_value_options(sub))
    takes_value.update(_value_options(parser))
    out: list[str] = []
    i = 0
    while i < len(argv):
        word = argv[i]
        if word in takes_value and i + 1 < len(argv) and _NEGATIVE.match(argv[i + 1]):
            out.append(f"{word}={argv[i + 1]}")
            i += 2
        else:
            out.append(word)
            i += 1
    return out


def _value_options(parser: argparse.ArgumentParser) -> set[str]:
    return {s for a in parser._actions if a.nargs is None and a.option_strings and not
            isinstance(a, argparse._SubParsersAction) for s in a.option_strings if s.startswith("--")}  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 1 failure, 2 bad input, 130 interrupted)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    try:
        args = parser.parse_args(_attach_negative_values(parser, argv))
    except SystemExit as e:  # argparse has printed its message (or --help)
        return e.code if isinstance(e.code, int) else 2
    if args.command is None:
        parser.print_usage(sys.stderr)
        print("tribosweep: error: give a command: " + ", ".join(COMMANDS), file=sys.stderr)
        return 2
    args.argv = argv
    prog = f"tribosweep {args.command}"
    try:
        return COMMANDS[args.command].run(args)
    except (ValueError, TypeError, NotImplementedError) as e:  # bad input (UsageError is a ValueError)
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 2
    except ImportError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        # The reader went away (``tribosweep info f.nc | head``): not an error of ours. Point stdout
        # at devnull so that the interpreter's final flush does not raise again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"\n{prog}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
