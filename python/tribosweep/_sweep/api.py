"""Sweeps over normal load x arm length x sliding speed (and any other real model field).

A sweep is an ensemble: the grid's points, numbered in C order, are cut into chunks, and each
chunk is one call of the pure function :func:`tribosweep._sweep.chunk.compute_chunk`. The loop runs
in-process, on any executor (``concurrent.futures``, a dask ``Client``) or on a dask cluster named by
``scheduler`` (``tribosweep._sweep.runner``, ``tribosweep._sweep.cluster``). With an output file,
every finished chunk is saved at once to ``<output>.parts/chunk_NNNNNN.npz`` (atomically, with a
checksum) next to a manifest of the configuration and the code identity, so an interrupted sweep
keeps its work and ``resume=True`` finishes it with results identical to an uninterrupted run. The
final netCDF file is assembled chunk by chunk through ``<output>.tmp`` in bounded memory (see
``tribosweep._sweep.netcdf``); a full disk is an error that names what is needed (``disk``).
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from .. import _checks, _settings, _wear
from .._model import SliderModel
from .._settings import DEFAULTS, SweepSettings
from . import chunk as _chunk
from . import cluster as _cluster
from . import disk, netcdf, runner, schema
from .parts import Parts
from .plan import (
    AXIS_ATTRS,
    SEED_AXES,
    Plan,
    check_axis,
    check_extra_axes,
    default_chunk_size,
    warn_units,
)
from .progress import Progress

_D = DEFAULTS

def sweep(
    model: SliderModel | None = None,
    *,
    normal_load: Sequence[float] | None = None,
    arm_length: Sequence[float] | None = None,
    sliding_speed: Sequence[float] | None = None,
    extra_axes: Mapping[str, Sequence[float]] | None = None,
    strategy: str = "auto",
    output: str | os.PathLike | None = None,
    chunk_size: int | None = None,
    threads: int | None = None,
    executor=None,
    scheduler: str | None = None,
    resume: bool = False,
    force_resume: bool = False,
    overwrite: bool = False,
    progress: bool = True,
    disturbance: float | Sequence[float] | None = None,
    wear_reference: _wear.WearReference | None = None,
    wear_calibration: _wear.WearCalibration | None = None,
    t_max: float = _D.steady.t_max,
    integrator: str = _D.integration.integrator,
    rtol: float = _D.integration.rtol,
    atol: float | Sequence[float] | None = None,
    transient_rtol: float = _D.steady.rtol,
    periodic_tol: float = _D.steady.periodic_tol,
    approach_periods: int = _D.steady.approach_periods,
    decay_amplitude: float | None = None,
    census: bool = _D.census.enabled,
    samples: int = _D.census.samples,
    census_t_max: float = _D.census.t_max,
    disturbance_scale: float = _D.census.disturbance_scale,
    census_rtol: float = _D.census.rtol,
    census_recurrence: bool = _D.census.recurrence,
    census_stop_tol: float | None = _D.census.stop_tol,
    unstable_disturbance: float = _D.unstable_disturbance,
    shooting_rtol: float = _D.shooting.rtol,
    shooting_tol: float = _D.shooting.tol,
    irregular_block: int = _D.irregular.block,
    transient_irregular_block: int = _D.irregular.transient_block,
    irregular_window: float = _D.irregular.window,
    irregular_sample_dt: float = _D.irregular.sample_dt,
    ftle_tau: float = _D.irregular.ftle_tau,
    ftle_segments: int = _D.irregular.ftle_segments,
    ftle_min_segments: int = _D.irregular.ftle_min_segments,
    ftle_warmup: int = _D.irregular.ftle_warmup,
    ftle_d0: float = _D.irregular.ftle_d0,
    ftle_rtol: float = _D.irregular.ftle_rtol,
    max_points: int = 10_000_000,
    boundaries: bool = True,
    method: str | None = None,
    check_bistability: bool | None = None,
    command: str | None = None,
    config_text: str | None = None,
) -> xr.Dataset:
    """Map the slider's regime over normal load x arm length x sliding speed (x extra axes).

    Every point is the apparatus at that load, arm length and speed (:func:`apparatus_model`);
    its regime is decided by ``strategy`` and recorded with how it was decided. A failed point is
    data (``regime = failed`` with a status and a reason), never an exception.

    Parameters
    ----------
    model : SliderModel, optional
        Everything not swept; its natural frequencies belong to the seed arm length 7.2 cm.
        Default: ``SliderModel()``, the seed with its default (physical) ``contact="unilateral"``.
    normal_load : array_like, N, optional
        Strictly increasing loads > 0. Default ``[84.46]`` (a length-1 dimension).
    arm_length : array_like, m, optional
        Strictly increasing arm lengths > 0. Default ``[0.072]``.
    sliding_speed : array_like, m/s, optional
        Strictly increasing speeds > 0. Default ``[0.46]``.
    extra_axes : dict of str to array_like, optional
        More dimensions: any real SliderModel field except those the three above set, e.g.
        ``{"mu": [0.2, 0.25, 0.3]}`` (units of ``tribosweep._model.PARAM_UNITS``).
    strategy : {"auto", "linear", "transient", "tidf", "shooting"}
        ``linear``: eigenvalues only (an unstable point is ``unstable_undetermined``);
        ``tidf``: eigenvalues, then the describing function at every point; ``shooting``: also the
        periodic orbit of every physical root; ``transient``: run every point to its steady state
        from ``disturbance``; ``auto``: each point gets the cheapest model that decides it
        (eigenvalues; the describing function at stable points; shooting where the disturbance
        nears the saddle cycle; a transient where sliding is unstable or the others cannot
        decide), see ``tribosweep._sweep.chunk``.
    output : path-like, optional
        netCDF file to write (through ``<output>.tmp``); finished chunks are kept in
        ``<output>.parts/`` until it is complete. Without it the Dataset is built in memory.
    chunk_size : int, optional
        Points per chunk (default 4096 for ``linear``; otherwise 256 computations: 256 points,
        or 256 times the number of speeds, at most 8192, under constant friction, where points
        that differ only in speed share one; with an executor or on a dask cluster at most that,
        and small enough for 4 chunks per worker). Results do not depend on it. Part
        of the configuration a resumed sweep must match; without it a resumed sweep keeps its own.
    threads : int, optional
        Rust worker threads inside a chunk (default ``TRIBOSWEEP_THREADS`` or all cores).
        Results do not depend on it.
    executor : object with ``submit`` or ``map``, optional
        Runs the chunks: a ``concurrent.futures`` executor or a dask ``Client`` (chunks are
        submitted and saved as they finish; a worker process that dies costs only its chunk, and a
        point that keeps killing its process is quarantined as ``crashed``: see
        ``tribosweep._sweep.runner``), or any object with ``map``. Default: in this process, one
        chunk at a time below 8 threads, else one chunk per 4 threads (at most 4) at once on
        threads of this process, so that one chunk's tail overlaps another's work (the same bits;
        ``tribosweep._sweep.runner.overlap``).
    scheduler : str, optional
        Run the chunks on a dask cluster: a scheduler's address (``"tcp://host:8786"``), or
        ``"local:N"`` to start ``N`` worker processes on this machine for the sweep. Needs
        ``dask.distributed`` (extra ``[dask]``). Each task uses its worker's thread budget (see
        ``tribosweep._sweep.cluster``); without ``chunk_size`` the chunks are sized for the
        cluster. Not together with ``executor``.
    resume : bool
        Finish the sweep whose chunks are in ``<output>.parts/`` (the configuration must match,
        else ``ValueError`` names the difference; it keeps the chunk size it started with).
    force_resume : bool
        Resume (implies ``resume``) even though the parts were computed by other code (another version or build of
        the core, whose numbers may differ): refused otherwise. The file records it
        (``tribosweep_resumed_from``).
    overwrite : bool
        Replace an existing ``output`` file (only once the new one is complete); without it an
        existing file is refused before any work.
    progress : bool
        Progress bar on stderr (tqdm if installed, else a plain line).
    disturbance : float or array_like (6,), optional
        Initial state of the transient runs: a ``z`` offset [m] or a full state
        ``[z, zd, x, xd, phi, phid]`` (default ``z = 1 um``).
    wear_reference : WearReference, optional
        Reference point of ``wear_rate_relative`` (default the seed: 84.46 N, 7.2 cm, 0.46 m/s).
    wear_calibration : WearCalibration, optional
        Adds the absolute ``wear_rate`` [kg/m].
    t_max : float, s
        Longest simulated time of a transient run (100). A bounded run that has neither repeated
        nor decayed by then is ``irregular`` (measured: ``irregular_*``); at a linearly stable point
        a motion below ``|z_st|/2`` is sliding still decaying (``steady_sliding``, status ``not_converged``).
    integrator : {"dop853", "dopri5", "rodas4"}
        Time integrator of the transient runs. DOP853 by default: on the unilateral (impacting)
        transients it is about twice as fast as Dopri5 at rtol 1e-8 and about 7x more accurate
        (the work-precision charts of ``tribosweep bench``); a 1,058-point seed sweep takes 18 s
        instead of 34 s.
    rtol, atol
        Integration tolerances of what is measured (as in :func:`tribosweep.simulate`): the
        cycles' shooting checks at ten times tighter than ``rtol`` (never tighter than
        ``shooting_rtol``; irregular motion is measured on the exponent's runs, at
        ``ftle_rtol``). ``atol`` applies to every run.
    transient_rtol : float
        Relative tolerance of the transients (1e-6), which find the attractor a point reaches:
        every number reported of it is measured afterwards (a cycle by shooting on the orbit at
        ten times tighter than ``rtol``, irregular motion over its window at ``ftle_rtol``), so
        this sets only where a chaotic transient happens to end. On the issue-10 Stribeck sweep no regime at 1e-6 differs from transients
        at 1e-10 run to ``t_max``, at 0.73x the right-hand sides of 1e-8 (see
        ``tribosweep._settings.Steady``).
    periodic_tol : float
        Relative repetition tolerance that declares a cycle.
    census : bool
        ``auto``: take the attractor census (``tribosweep.census``) at stable points with a saddle
        cycle, and at unstable points whose transient reached a motion (a cycle, irregular motion
        or an escape; the regime stays that motion, the census says what else coexists):
        ``samples`` disturbances on the torsion and normal modes, each run to its attractor
        with the model's contact law; ``basin_fraction`` (with ``basin_fraction_se`` and its 95 %
        Wilson interval ``basin_fraction_low`` .. ``basin_fraction_high``) on the ``attractor``
        dimension (sliding, cycle, irregular, escape), ``basin_stability``,
        ``n_attractors``, ``n_cycles`` and the largest cycle's frequency and amplitude. ``bistable``
        is derived from it: ``coexisting`` where more than one attractor was seen,
        ``one_attractor``, or ``no_saddle`` where the describing function predicts no saddle (no
        census: nothing to find). The census is most of an ``auto`` sweep's cost.
    samples : int
        Census disturbances per point ``K`` (default 32); fractions carry ``sqrt(p (1 - p) / K)``.
    census_t_max : float, s
        Longest simulated time of one census disturbance (30); bounded motion that has neither
        decayed nor repeated by then counts as ``irregular``.
    disturbance_scale : float
        Largest modal amplitude of a census disturbance in units of ``|z_st|`` (3).
    census_rtol : float
        Relative tolerance of the census disturbances' runs (1e-6; the integrator is
        ``integrator``'s). Labels agree with those at rtol 1e-10 as well as at 1e-8, at 0.78-0.86x the
        cost (see ``tribosweep._settings.Census``).
    census_recurrence : bool
        Let census samples stop as irregular once they keep to an irregular attractor one of the
        point's two pilot samples established, in its cells or on a block matching its statistics
        (default True; False: each sample decides by its own three blocks). See ``tribosweep._census``.
    census_stop_tol : float, optional
        The repetition tolerance at which a census sample after the pilots first stops on a cycle;
        every such stop is shot from, and the sample is on the stable orbit shooting converges to, or
        goes on (see ``tribosweep._settings.Census``). Default: 1e-3 under speed-dependent friction,
        none under constant friction; at ``periodic_tol`` or below: no first stops.
    unstable_disturbance : float
        ``auto``: transients of linearly unstable points start on the unstable mode with
        ``|z| = unstable_disturbance |z_st|``, or less where that would put another component beyond
        10 times as many of its characteristic sizes (a frictional mode with little ``z``:
        ``tribosweep._sweep.stages.MODE_START_CAP``).
    decay_amplitude : float, m, optional
        Amplitude below which a motion counts as decayed (default ``1e-3 |z_st|``).
    irregular_block : int
        Sections per block of the census's stationarity test (256; 0: off): a census disturbance
        in bounded motion that neither repeats nor decays ends as irregular once three
        consecutive blocks of Poincare sections agree (see :func:`tribosweep.census`), else at ``census_t_max``.
    transient_irregular_block : int
        The same for the ``auto`` transients (128; 0: off, else at ``t_max``): see
        ``tribosweep._settings.Irregular``.
    irregular_window, irregular_sample_dt : float, s
        A transient that stays bounded but neither repeats nor decays (stationary, or still so at
        ``t_max``) is regime ``irregular``; from where it ended, ``z`` is sampled every ``irregular_sample_dt`` (1e-4)
        over ``irregular_window`` (0.5) for ``irregular_z_min``, ``irregular_z_max`` and
        ``irregular_omega`` (the spectral peak), on the base run of the exponent (which runs at
        least that long).
    ftle_tau : float, s
        Segment length of its largest finite-time Lyapunov exponent ``irregular_ftle`` (0.05:
        about 5 torsion periods; see ``tribosweep._irregular``).
    ftle_segments, ftle_min_segments, ftle_warmup : int
        Segments averaged at most (40, >= 2; the standard error ``irregular_ftle_se`` is their
        spread over the square root of their number), at least (10, >= 2: a point whose exponent
        is then 5 standard errors from 0, clearly chaotic, stops; the others run on) and run
        first without counting (2, >= 0).
    ftle_d0 : float
        Separation of the two trajectories in units of the characteristic sizes (1e-8).
    ftle_rtol : float
        Relative tolerance of the exponent's runs (1e-7: two runs ``ftle_d0`` apart take the
        same steps, and their step errors cancel in the separation; chosen on replicates against
        1e-11, ``tribosweep._irregular``).
    shooting_rtol, shooting_tol : float
        Integration and Newton tolerances of the shooting stage (1e-10, 1e-8: the orbit's ``A1``
        is compared with the describing function's to a few 1e-3, and the monodromy matrix needs
        a few more digits than that).
    max_points : int
        Largest sweep accepted (10^7 points by default): a typo such as ``10:20:100000000`` is refused
        before any work, naming the shape.
    boundaries : bool
        Store the stability boundaries that cross a normal load x arm length box, from
        :func:`tribosweep.boundary_curves`: the Hopf curves (``hopf_*`` on ``hopf_point``), and for
        unilateral contact and a strategy other than ``linear`` the fold and grazing curves of the
        cycles born there (``fold_*`` on ``fold_point``, ``grazing_*`` on ``grazing_point``; about
        3 s on the default box); ``tribosweep plot`` draws them over the map.
    method : str, optional
        Deprecated name of ``strategy`` (``method`` is the time integrator everywhere else).
    command : str, optional
        Command recorded in the ``history`` attribute (the CLI passes its command line).
    config_text : str, optional
        Text of the configuration file the sweep came from, recorded in the ``config_toml``
        attribute (the CLI passes its ``--config`` file).

    Returns
    -------
    xarray.Dataset
        Dimensions ``normal_load``, ``arm_length``, ``sliding_speed`` (+ extras); per point
        ``regime``, ``status``, ``reason``, ``decided_by``, ``bistable``, linear stability,
        cycle summary, irregular motion (``irregular_z_min``, ``irregular_z_max``,
        ``irregular_omega``, ``irregular_ftle``, ``irregular_ftle_se``, and for intermittent motion
        ``irregular_intermittent_period``, ``irregular_intermittent_multiplier``,
        ``irregular_intermittent_instability``; NaN or 0 elsewhere), wear and cost
        variables (see ``tribosweep._sweep.schema.POINT_VARIABLES``).
        With ``output`` the Dataset is opened lazily from the file.

    Raises
    ------
    ValueError
        A bad axis (empty, not strictly increasing, NaN, non-positive), option, or a resume
        whose configuration differs.
    TypeError
        ``model``, ``extra_axes``, ``wear_reference`` or ``wear_calibration`` of the wrong type.
    FileExistsError
        ``<output>.parts/`` exists and ``resume`` is false.
    DiskFullError (an OSError)
        The disk is full: before any work when the parts alone cannot fit, or while writing a part
        or the file (the message names the path and the space needed; the parts are kept: free
        space and resume).
    KeyboardInterrupt
        Re-raised after an interruption; finished chunks stay in ``<output>.parts/``.

    Examples
    --------
    >>> import tribosweep as ts
    >>> ds = ts.sweep(normal_load=[10.0, 50.0], strategy="linear", progress=False)
    >>> [str(r) for r in ds.regime.attrs["flag_meanings"].split()[:2]]
    ['steady_sliding', 'self_excited']
    >>> ds.regime.sel(arm_length=0.072, sliding_speed=0.46).values.tolist()
    [6, 0]
    """
    if method is not None:
        warnings.warn("sweep(method=...) is renamed strategy=... (method is the time integrator in simulate and "
                      "ensemble); the old name goes away in 0.3", DeprecationWarning, stacklevel=2)  # fmt: skip
        strategy = method
    if check_bistability is not None:
        warnings.warn("sweep(check_bistability=...) is renamed census=...; the old name goes away in 0.3",
                      DeprecationWarning, stacklevel=2)  # fmt: skip
        census = bool(check_bistability)
    if model is None:
        model = SliderModel()
    if not isinstance(model, SliderModel):
        raise TypeError(f"model = {model!r} must be a tribosweep.SliderModel or None")
    if strategy not in _chunk.STRATEGIES:
        raise ValueError(f"strategy = {strategy!r} is not valid: must be one of {_chunk.STRATEGIES}")
    axes = {}
    for name, values in (("normal_load", normal_load), ("arm_length", arm_length), ("sliding_speed", sliding_speed)):
        values = [SEED_AXES[name]] if values is None else values
        axes[name] = check_axis(name, values, units=AXIS_ATTRS[name]["units"])
        warn_units(name, axes[name])
    axes.update(check_extra_axes(model, extra_axes))
    if chunk_size is not None and (isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer))
                                   or chunk_size < 1):  # fmt: skip
        raise ValueError(f"chunk_size = {chunk_size!r} is out of range: must be an integer >= 1")
    threads = _checks.threads(threads)
    wear_reference = _wear.WearReference() if wear_reference is None else wear_reference
    if not isinstance(wear_reference, _wear.WearReference):
        raise TypeError(f"wear_reference = {wear_reference!r} must be a tribosweep.WearReference or None")
    if wear_calibration is not None and not isinstance(wear_calibration, _wear.WearCalibration):
        raise TypeError(f"wear_calibration = {wear_calibration!r} must be a tribosweep.WearCalibration or None")
    resume = bool(resume or force_resume)
    if resume and output is None:
        raise ValueError("resume=True needs output: the finished chunks are kept next to the output file")
    if output is not None:
        output = _check_output(output, overwrite=overwrite)
    if scheduler is not None:
        if executor is not None:
            raise ValueError(f"scheduler = {scheduler!r} and executor = {executor!r}: give one of them, not both")
        scheduler = _cluster.check_scheduler(scheduler)
    if config_text is not None and not isinstance(config_text, str):
        raise TypeError(f"config_text = {config_text!r} must be a str (the text of a TOML file) or None")
    n_points = int(np.prod([a.size for a in axes.values()]))
    if n_points > max_points:
        raise ValueError(f"the sweep has {n_points} points (shape {tuple(a.size for a in axes.values())}), more than "
                         f"max_points = {max_points}: check the axes (START:STOP:NUM gives NUM values), or raise "
                         "max_points")  # fmt: skip
    settings = SweepSettings.from_flat(
        t_max=t_max, integrator=integrator, rtol=rtol, atol=atol, transient_rtol=transient_rtol,
        periodic_tol=periodic_tol, approach_periods=approach_periods,
        decay_amplitude=decay_amplitude, census=census, samples=samples, census_t_max=census_t_max,
        disturbance_scale=disturbance_scale, census_rtol=census_rtol, census_recurrence=census_recurrence,
        census_stop_tol=census_stop_tol,
        unstable_disturbance=unstable_disturbance, shooting_rtol=shooting_rtol,
        shooting_tol=shooting_tol, irregular_block=irregular_block,
        transient_irregular_block=transient_irregular_block, irregular_window=irregular_window,
        irregular_sample_dt=irregular_sample_dt,
        ftle_tau=ftle_tau, ftle_segments=ftle_segments, ftle_min_segments=ftle_min_segments,
        ftle_warmup=ftle_warmup, ftle_d0=ftle_d0, ftle_rtol=ftle_rtol,
        y0=_settings.disturbance(disturbance),
    )  # fmt: skip
    f_ref = wear_reference.frequency_hz(model)
    settings = settings.replace(wear={
        "normal_load": wear_reference.normal_load,
        "sliding_speed": wear_reference.sliding_speed,
        "frequency_hz": f_ref,
        "calibration": None if wear_calibration is None else wear_calibration.as_dict(),
    })  # fmt: skip
    specs = schema.point_specs(tuple(axes), wear_rate=wear_calibration is not None)
    if output is not None and not resume:
        disk.check_room(output, n_points, disk.fixed_point_bytes(specs, schema.TRAILING_DIMS))

    connection = _cluster.connect(scheduler) if scheduler is not None else contextlib.nullcontext(executor)
    with connection as executor:
        extra = {} if config_text is None else {"config_toml": config_text}
        if runner.is_dask(executor):
            _cluster.check_workers(executor)
            extra |= _cluster.provenance(executor)
        if chunk_size is None:
            chunk_size = (Parts.saved_chunk_size(output) if resume else None) or default_chunk_size(
                strategy, model.friction_law, axes["sliding_speed"].size)  # fmt: skip
            if executor is not None and not resume:
                # Enough chunks to keep every worker busy to the end.
                slots = _cluster.total_threads(executor) if runner.is_dask(executor) else runner.slots(executor)
                chunk_size = _cluster.chunk_size(n_points, chunk_size, slots)
        plan = Plan(model, axes, strategy, settings, int(chunk_size), wear_reference, wear_calibration)
        if command is None:
            command = f"tribosweep.sweep(shape={plan.shape}, dims={plan.dims}, strategy={strategy!r})"
        # The curves come before the first point and take a second or more: say so as they start.
        say = progress and boundaries and schema.boundary_box(plan)
        if say:
            sys.stderr.write("sweep: stability boundary curves of the load x arm box (boundaries=False, "
                             "--no-boundaries: none) ... ")  # fmt: skip
            sys.stderr.flush()
        t_curves = time.perf_counter()
        curves, curve_attrs = schema.boundary_vars(plan) if boundaries else ({}, {})
        if say:
            sys.stderr.write(f"{time.perf_counter() - t_curves:.1f} s\n")
        layout = (
            schema.coords(plan),
            schema.static_vars(plan) | curves,
            specs,
            schema.global_attrs(plan, command, f_ref) | curve_attrs | extra,
        )
        if output is None:
            writer = netcdf.MemoryWriter(*layout)
            bar = Progress(progress, plan.n_points, 0)
            try:
                runner.run(plan, range(plan.n_chunks), threads, executor,
                           lambda k, arrays: writer.write(*plan.chunk_range(k), arrays), bar)  # fmt: skip
            finally:
                bar.close()
            return writer.to_dataset()
        return _to_file(plan, Path(output), layout, resume, force_resume, threads, executor, progress)


def _to_file(plan: Plan, output: Path, layout, resume: bool, force: bool, threads, executor, progress) -> xr.Dataset:
    """Compute what the parts lack, then assemble the file (the parts stay until it is complete)."""
    output.parent.mkdir(parents=True, exist_ok=True)
    parts = Parts(output, plan, resume, force=force)
    try:
        return _compute_and_assemble(plan, output, parts, layout, resume, threads, executor, progress)
    finally:
        parts.release()


def _compute_and_assemble(plan: Plan, output: Path, parts: Parts, layout, resume: bool, threads, executor,
                          progress) -> xr.Dataset:  # fmt: skip
    if parts.forced_from is not None:
        layout[3]["tribosweep_resumed_from"] = (
            f"force_resume: some parts were computed by tribosweep {parts.forced_from['tribosweep_version']} core "
            f"{parts.forced_from['core_build']}, the rest by this code"
        )
    sums = parts.checksums()
    done = [k for k in range(plan.n_chunks) if parts.is_done(k, sums)]
    todo = sorted(set(range(plan.n_chunks)) - set(done))
    n_done = sum(plan.chunk_range(k)[1] - plan.chunk_range(k)[0] for k in done)
    if resume:
        disk.check_room(output, plan.n_points - n_done, disk.fixed_point_bytes(layout[2], schema.TRAILING_DIMS))
    bar = Progress(progress, plan.n_points, n_done)
    try:
        runner.run(plan, todo, threads, executor, parts.save, bar, markers=parts.running, suspects=parts.suspects())
    except KeyboardInterrupt:
        saved = sum(1 for k in range(plan.n_chunks) if parts.path(k).exists())
        sys.stderr.write(
            f"\ninterrupted: {saved} of {plan.n_chunks} chunks are saved in {parts.dir}; run again with "
            "resume=True (--resume) to finish\n"
        )
        raise
    finally:
        bar.close()
    widths = {s.name: max(parts.text_width(k, s.name) for k in range(plan.n_chunks)) for s in layout[2] if s.dtype == "str"}
    writer = netcdf.NetCDFWriter(output, *layout, parts_dir=parts.dir, text_widths=widths)
    try:
        for k in range(plan.n_chunks):
            writer.write(*plan.chunk_range(k), parts.load(k))
    except BaseException:
        writer.abort()
        raise
    writer.close()  # removes its temporary file itself on an error
    parts.remove()
    return xr.open_dataset(output, engine="netcdf4")


def _check_output(output, *, overwrite: bool = False) -> Path:
    """The output path, refused before any work if it cannot be written: empty, a directory, an existing
    file (without ``overwrite``), or in a directory that does not exist and cannot be made, or one without
    write permission."""
    if str(output).strip() == "":
        raise ValueError("output = '' is not a file name: give a path such as sweep.nc, or None for no file")
    path = Path(output)
    if path.is_dir():
        raise ValueError(f"output = {str(output)!r} is a directory: give a file name inside it, e.g. "
                         f"{str(path / 'sweep.nc')!r}")  # fmt: skip
    if path.exists() and not overwrite:
        raise ValueError(f"output = {str(output)!r} exists: pass overwrite=True (--overwrite) to replace it (only "
                         "once the new file is complete), or choose another name")  # fmt: skip
    parent = path.parent if str(path.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"output = {str(output)!r}: its folder cannot be made ({e.strerror or e})") from None
    if not os.access(parent, os.W_OK):
        raise ValueError(f"output = {str(output)!r}: the folder {str(parent)!r} is not writable")
    return path
