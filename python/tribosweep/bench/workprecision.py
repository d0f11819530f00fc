"""Work-precision: error against wall time over a tolerance ladder, per integrator and scene.

For each *scene* (a small batch of trajectories of one physical situation) and each method, the
batch is integrated once per rung of a relative-tolerance ladder; a rung records the best-of-``repeat``
wall time per trajectory, the error against a tight reference, and the work counters. The Rust core's
integrators (``dopri5``, ``dop853``, ``rodas4``, through :func:`tribosweep.ensemble` with one thread)
are measured beside baselines run in the same process: scipy ``solve_ivp`` (the independent
``tribosweep.bench.reference``), the numba Dormand-Prince kernel of
:mod:`tribosweep.bench.baselines` and diffrax (only where it is importable). A failed rung (a non-zero status, a NaN, or an
error above 1) is recorded and drawn, never dropped.

Error of a rung: ``max_i |z_i(t_end) - z_ref,i(t_end)| / max|z_ref,i|`` over the batch, where the
reference is the Rust DOP853 at ``rtol = 1e-13`` and ``max|z_ref,i|`` the largest ``|z|`` of reference
run ``i``. Each reference is checked against a second solver (scipy DOP853 at 1e-13 for the bilateral
seed, the event-driven scipy solver for unilateral scenes, the Rust Dopri5 at 1e-12 where scipy has no
model); errors below that check are not resolved and the charts shade them.

Every method gets the same absolute tolerance, ``rtol`` times each component's characteristic size
(``|z_st|`` for z and x, ``|z_st|/L`` for phi, those times ``omega_torsion`` for rates).

Entry points: :func:`run_work_precision` (measure, write CSV/JSON/PNG/markdown),
:func:`render_summary` (markdown from the JSON table), :func:`time_at_error` (log-log interpolation
of a work-precision line), :func:`plot_work_precision` (one scene's chart as a Figure).
"""

from __future__ import annotations

import csv
import dataclasses
import datetime
import importlib.util
import json
import math
import os
import pathlib
import platform
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._simulate import ensemble
from .analysis import make_row
from .charts import plot_work_precision, render_summary
from .runners import (
    _best_of,
    _diffrax_batch,
    _numba_batch,
    _scipy_batch,
    _scipy_switch_batch,
    _status_name,
    diffrax_available,
    error_of,
    find_baselines_module,
    run_rust,
)
from .scenes import (
    COLUMNS,
    FULL_LADDER,
    QUICK_LADDER,
    REF_RTOL,
    RUST_METHODS,
    SCIPY_CAP_FULL,
    SCIPY_CAP_QUICK,
    Scene,
    make_scenes,
)


def _log(msg: str, progress: bool) -> None:
    if progress:
        print(msg, file=sys.stderr, flush=True)


def _reference(scene: Scene, *, check_k: int, progress: bool) -> dict:
    """Rust DOP853 at REF_RTOL over the batch, checked on ``check_k`` trajectories by a second solver."""
    t0 = time.perf_counter()
    ref = run_rust(scene, "dop853", REF_RTOL, repeat=1)
    seconds = time.perf_counter() - t0
    scale = np.maximum(np.abs(ref.extra["max_abs_z"]), 1e-300)
    info = {
        "method": "rust dop853", "rtol": REF_RTOL, "seconds_per_traj": seconds / scene.n,
        "status": _status_name(ref.status), "n_failed": int(np.count_nonzero(ref.status)),
        "max_abs_z": float(np.max(ref.extra["max_abs_z"])), "max_gap": float(np.max(ref.extra["max_gap"])),
        "min_slip_velocity": float(np.min(ref.extra["min_slip_velocity"])),
        "min_normal_force": float(np.min(ref.extra["min_normal_force"])),
        "n_events": float(np.mean(ref.extra["n_events"])), "n_rhs": float(np.mean(ref.n_rhs)),
    }  # fmt: skip
    # The fixed cost of one ensemble call over this batch (validation, GIL hand-off, Dataset building):
    # a run of 1 ns, best of 5. It is part of every Rust time; reported beside them.
    over, _ = _best_of(lambda: ensemble(scene.model, 1e-9, scene.params, y0=scene.y0, method="dopri5", rtol=1e-6,
                                        atol=scene.atol(1e-6), threads=1), 5)  # fmt: skip
    info["api_overhead_per_call"] = over
    info["api_overhead_per_traj"] = over / scene.n
    head = scene.head(check_k)
    try:
        if scene.is_bilateral_constant() and _has("scipy"):
            chk = _scipy_batch(head, "DOP853", REF_RTOL, 1)
            info["check_method"] = "scipy DOP853 rtol 1e-13"
        elif scene.is_unilateral_constant() and _has("scipy"):
            chk = _scipy_batch(head, "DOP853", 1e-12, 1)
            info["check_method"] = "scipy DOP853 rtol 1e-12, event-driven (reference.solve_unilateral)"
        elif scene.model.friction_law == "switch" and scene.model.contact == "bilateral" and _has("scipy"):
            chk = _scipy_switch_batch(head, 1e-13)
            info["check_method"] = "scipy DOP853 rtol 1e-13, event-driven switch law (reference_switch.SwitchReference)"
        else:
            chk = run_rust(head, "dopri5", 1e-12, repeat=1)
            info["check_method"] = "rust dopri5 rtol 1e-12"
        info["check_value"] = error_of(chk.z_end, ref.z_end, scale)
    except Exception as e:  # noqa: BLE001 - a failed check is reported, not fatal
        info["check_method"], info["check_value"] = f"check failed: {e}", math.nan
    info["check_n"] = head.n
    _log(f"  reference {scene.name}: {info['seconds_per_traj'] * 1e3:.1f} ms/traj, status {info['status']}, "
         f"check ({info['check_method']}) {info['check_value']:.1e}", progress)  # fmt: skip
    return {"info": info, "z_end": ref.z_end, "scale": scale}


def _has(module: str) -> bool:
    return importlib.util.find_spec(module) is not None


@dataclass
class BenchConfig:
    """What :func:`run_work_precision` measures.

    Attributes
    ----------
    quick : bool
        Fewer rungs and trajectories (about a minute on two cores, failure maps included).
    scenes : list of str, optional
        Scene names (default: all four).
    ladder : sequence of float, optional
        rtol rungs (default ``QUICK_LADDER`` or ``FULL_LADDER``).
    n_traj : int, optional
        Trajectories per scene (default per scene, see :func:`make_scenes`).
    methods : sequence of str
        Rust integrators.
    baselines : sequence of str
        Any of ``"scipy"``, ``"numba"``, ``"diffrax"`` (each skipped with a note when unavailable).
    repeat : int, optional
        Best-of repeats of each timed rung (Rust, numba: interleaved passes over the ladder; diffrax);
        default 3 quick, 5 full.
    scipy_repeat : int, optional
        Best-of repeats of the scipy rungs (default 1 quick, 3 full: scipy rungs are long).
    scipy_n : int, optional
        Trajectories of the scipy baselines (default 1 quick, 4 full).
    scipy_cap : float, optional
        Skip tighter scipy rungs once a rung takes longer than this per trajectory, s.
    check_n : int, optional
        Trajectories of the reference check (default 1 quick, 4 full).
    """

    quick: bool = False
    scenes: Sequence[str] | None = None
    ladder: Sequence[float] | None = None
    n_traj: int | None = None
    methods: Sequence[str] = RUST_METHODS
    baselines: Sequence[str] = ("scipy", "numba", "diffrax")
    repeat: int | None = None
    scipy_repeat: int | None = None
    scipy_n: int | None = None
    scipy_cap: float | None = None
    check_n: int | None = None

    def resolved(self) -> BenchConfig:
        """A copy with every default filled in."""
        q = self.quick
        return dataclasses.replace(
            self,
            ladder=tuple(float(r) for r in (self.ladder or (QUICK_LADDER if q else FULL_LADDER))),
            methods=tuple(self.methods),
            baselines=tuple(self.baselines),
            repeat=self.repeat or (3 if q else 5),
            scipy_repeat=self.scipy_repeat or (1 if q else 3),
            scipy_n=self.scipy_n or (1 if q else 4),
            scipy_cap=self.scipy_cap or (SCIPY_CAP_QUICK if q else SCIPY_CAP_FULL),
            check_n=self.check_n or (1 if q else 4),
        )


#: scipy methods per scene kind.
_SCIPY_BILATERAL = ("RK45", "DOP853", "Radau")
_SCIPY_UNILATERAL = ("RK45", "DOP853")


def measure(config: BenchConfig, *, progress: bool = True) -> dict:
    """Run the work-precision measurements; returns the JSON-ready payload (meta, scenes, rows, notes).

    Nothing is written; see :func:`run_work_precision`.
    """
    cfg = config.resolved()
    scenes = make_scenes(cfg.quick, cfg.scenes, cfg.n_traj)
    rows: list[dict] = []
    notes: list[str] = []
    scene_info = []
    bl = None
    if "numba" in cfg.baselines:
        bl = find_baselines_module()
        if bl is None:
            notes.append("numba baseline skipped: numba is not installed (pip install tribosweep[bench])")
        else:
            t0 = time.perf_counter()
            # Compile only the one-core kernel (baselines.warmup() also compiles the prange variant).
            bl.numba_dp5_batch(np.zeros((1, 17)) + _seed_row(), np.array([[1e-6, 0, 0, 0, 0, 0]]), 1e-3, 1e-3)
            _log(f"numba kernel compiled in {time.perf_counter() - t0:.1f} s", progress)
    if "scipy" in cfg.baselines and not _has("scipy"):
        notes.append("scipy baselines skipped: scipy is not installed")
    use_diffrax = "diffrax" in cfg.baselines and diffrax_available()
    if "diffrax" in cfg.baselines and not use_diffrax:
        notes.append("diffrax baseline skipped: diffrax/jax not importable")

    t_start = time.perf_counter()
    load_start = _loadavg()
    for scene in scenes:
        _log(f"scene {scene.name}: {scene.n} trajectories, {scene.t_end} s", progress)
        ref = _reference(scene, check_k=cfg.check_n, progress=progress)
        z_ref, scale = ref["z_end"], ref["scale"]
        info = {"name": scene.name, "title": scene.title, "description": scene.description, "t_end": scene.t_end,
                "n_traj": scene.n, "contact": scene.model.contact, "friction_law": scene.model.friction_law,
                "reference": ref["info"]}  # fmt: skip
        # Each variant (another friction law on the same batch) is measured against its own reference.
        refs = {}
        for key in scene.variants:
            _log(f"  variant {key}", progress)
            vref = _reference(scene.variant(key), check_k=cfg.check_n, progress=progress)
            refs[key] = (vref["z_end"], vref["scale"])
            info.setdefault("variants", {})[key] = {
                "friction_law": scene.variants[key].friction_law, "reference": vref["info"],
                "stick_band": scene.variants[key].stick_band}  # fmt: skip
        scene_info.append(info)

        def add(impl, method, rtol, run, scene=scene, z_ref=z_ref, scale=scale, refs=refs):
            if impl in refs:
                z_ref, scale = refs[impl]
            row = make_row(scene.name, impl, method, rtol, run, z_ref, scale)
            rows.append(row)
            flag = f"  FAILED ({row['status']})" if row["failed"] else ""
            _log(f"  {row['label']:<14} rtol {rtol:.0e}: {row['seconds_per_traj'] * 1e3:9.3f} ms/traj, "
                 f"error {row['error']:.2e}, {row['n_rhs']:.0f} rhs{flag}", progress)  # fmt: skip
            return row

        # Rust and numba rungs are short: time them in interleaved passes over every (method, rtol) and keep
        # each rung's fastest pass, so a burst of load from other processes hits different rungs in different
        # passes instead of all repeats of one rung.
        jobs = {("rust", m, r): (lambda m=m, r=r, sc=scene: run_rust(sc, m, r, repeat=1)) for m in cfg.methods
                for r in cfg.ladder}  # fmt: skip
        for key in scene.variants:
            vscene = scene.variant(key)
            jobs.update({(key, m, r): (lambda m=m, r=r, sc=vscene: run_rust(sc, m, r, repeat=1))
                         for m in cfg.methods for r in cfg.ladder})  # fmt: skip
        if bl is not None and scene.is_bilateral_constant():
            jobs.update({("numba", "DP5", r): (lambda r=r, sc=scene: _numba_batch(bl, sc, r, 1)) for r in cfg.ladder})
        best: dict = {}
        _log(f"  timing {len(jobs)} rungs (Rust, numba) in {cfg.repeat} interleaved passes", progress)
        for _ in range(max(1, cfg.repeat)):
            for key, job in jobs.items():
                run = job()
                if key not in best or run.seconds < best[key].seconds:
                    best[key] = run
        for (impl, method, rtol), run in best.items():
            add(impl, method, rtol, run)
        if use_diffrax and scene.is_bilateral_constant():
            for rtol in cfg.ladder:
                try:
                    add("diffrax", "Dopri5", rtol, _diffrax_batch(scene, rtol, cfg.repeat))
                except Exception as e:  # noqa: BLE001 - an optional baseline must not stop the run
                    notes.append(f"diffrax on {scene.name} at rtol {rtol:.0e} raised {type(e).__name__}: {e}")
                    break
        if "scipy" in cfg.baselines and _has("scipy"):
            methods = (_SCIPY_BILATERAL if scene.is_bilateral_constant()
                       else _SCIPY_UNILATERAL if scene.is_unilateral_constant() else ())  # fmt: skip
            head = scene.head(cfg.scipy_n)
            for method in methods:
                for i, rtol in enumerate(cfg.ladder):
                    row = add("scipy", method, rtol, _scipy_batch(head, method, rtol, cfg.scipy_repeat))
                    if row["seconds_per_traj"] > cfg.scipy_cap and i + 1 < len(cfg.ladder):
                        notes.append(f"{scene.name}: scipy {method} stopped after rtol {rtol:.0e} "
                                     f"({row['seconds_per_traj']:.2f} s per trajectory > cap {cfg.scipy_cap:g} s); "
                                     f"tighter rungs not run")  # fmt: skip
                        break
            if not methods:
                notes.append(f"{scene.name}: no scipy baseline (tribosweep.reference has no regularised "
                             f"Coulomb friction)")  # fmt: skip
    meta = _meta(cfg, time.perf_counter() - t_start)
    meta["loadavg"] = [load_start, _loadavg()]
    return {"meta": meta, "scenes": scene_info, "rows": rows, "notes": notes}


def _loadavg() -> float | None:
    """1-minute load average (other processes competing for the cores skew the times), None where unknown."""
    try:
        return round(os.getloadavg()[0], 2)
    except (OSError, AttributeError):
        return None


def _seed_row() -> np.ndarray:
    from . import reference

    return reference.params_to_array([reference.seed_parameters()])[0]


def _git_commit() -> str:
    try:
        here = pathlib.Path(__file__).resolve().parents[2]
        out = subprocess.run(["git", "-C", str(here), "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=5, check=False)  # fmt: skip
        return out.stdout.strip() if out.returncode == 0 else ""
    except (OSError, subprocess.SubprocessError):
        return ""


def _cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _simd() -> str:
    """The lane copies the core picks on this CPU, as it detects them (x86-64: AVX-512F, else AVX2)."""
    try:
        with open("/proc/cpuinfo") as f:
            flags = next((line.split(":", 1)[1].split() for line in f if line.startswith("flags")), [])
    except OSError:
        return "unknown SIMD"
    return "AVX-512 lanes" if "avx512f" in flags else "AVX2 lanes" if "avx2" in flags else "portable lanes"


def machine_line() -> str:
    """One line for a bench's output: CPU model, cores, the lane copies in use, 1-minute load average."""
    load = _loadavg()
    return (f"{_cpu_name()}, {os.cpu_count()} cores, {_simd()}, load average "
            f"{'unknown' if load is None else f'{load:.2f}'}")  # fmt: skip


def _versions() -> dict:
    from .. import __version__

    out = {"tribosweep": __version__, "python": platform.python_version(), "numpy": np.__version__}
    for mod in ("scipy", "numba", "diffrax", "jax", "matplotlib"):
        if _has(mod):
            try:
                out[mod] = __import__(mod).__version__
            except Exception:  # noqa: BLE001
                out[mod] = "?"
    return out


def _meta(cfg: BenchConfig, seconds: float) -> dict:
    return {
        "quick": cfg.quick,
        "ladder": list(cfg.ladder),
        "methods": list(cfg.methods),
        "baselines": list(cfg.baselines),
        "repeat": cfg.repeat,
        "scipy_repeat": cfg.scipy_repeat,
        "scipy_n": cfg.scipy_n,
        "scipy_cap_s": cfg.scipy_cap,
        "reference": f"rust dop853 rtol {REF_RTOL:.0e}",
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "machine": f"{_cpu_name()}, {os.cpu_count()} logical cores, {platform.system()} {platform.machine()}",
        "versions": _versions(),
        "commit": _git_commit(),
        "threads": 1,
        "cores": os.cpu_count(),
        "seconds": seconds,
    }


# --- output ----------------------------------------------------------------------------------------


def write_table(rows: list[dict], csv_path: os.PathLike) -> None:
    """Every row as CSV (``COLUMNS``; floats with full precision)."""
    with open(csv_path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (repr(v) if isinstance(v, float) else v) for k, v in r.items()})


def _json_safe(o):
    if isinstance(o, float) and not math.isfinite(o):
        return None
    if isinstance(o, dict):
        return {k: _json_safe(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_json_safe(v) for v in o]
    if isinstance(o, np.generic):
        return _json_safe(o.item())
    if isinstance(o, np.ndarray):
        return _json_safe(o.tolist())
    return o


def _json_load_rows(payload: dict) -> dict:
    """Undo ``_json_safe`` (None -> NaN in numeric columns)."""
    for r in payload["rows"]:
        for k in ("error", "seconds_per_traj", "n_rhs", "steps", "n_reject"):
            if r.get(k) is None:
                r[k] = math.nan
    return payload


def load_payload(path: os.PathLike) -> dict:
    """Read a ``work_precision.json`` written by :func:`run_work_precision`."""
    with open(path) as f:
        return _json_load_rows(json.load(f))


def run_work_precision(out_dir: os.PathLike, config: BenchConfig | None = None, *, failure_maps: bool = True,
                       docs: os.PathLike | None = None, progress: bool = True, command: str | None = None,
                       map_threads: int | None = None) -> dict:  # fmt: skip
    """Measure and write everything into ``out_dir``; returns the payload (with ``files``).

    Files: ``work_precision.csv`` and ``.json`` (every scene x method x rtol), ``wp_<scene>.png`` (one
    chart per scene), ``failure_*.png`` / ``.nc`` (with ``failure_maps``), ``summary.md``; with ``docs``
    also that markdown page (the same summary, no images).
    """
    config = config or BenchConfig()
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    payload = measure(config, progress=progress)
    files = {"csv": out / "work_precision.csv", "json": out / "work_precision.json", "summary": out / "summary.md"}
    write_table(payload["rows"], files["csv"])
    images = {}
    for s in payload["scenes"]:
        fig = plot_work_precision(payload["rows"], s)
        path = out / f"wp_{s['name']}.png"
        fig.savefig(path, dpi=110)
        images[s["name"]] = path.name
        files[f"wp_{s['name']}"] = path
    extra = ""
    if failure_maps:
        from .failure import failure_maps as _maps

        _log("failure maps", progress)
        fm = _maps(out, quick=payload["meta"]["quick"], threads=map_threads, progress=progress)
        payload["failure_maps"] = fm["summary"]
        payload["failure_maps_markdown"] = fm["markdown"]
        files.update(fm["files"])
        extra = fm["markdown"]
    if failure_maps:
        from .model_cost import model_cost

        _log("model cost (describing function, shooting, transient, auto)", progress)
        mc = model_cost(out, quick=payload["meta"]["quick"])
        payload["model_cost"] = mc["numbers"]
        files.update(mc["files"])
        extra = (extra + "\n\n" + mc["markdown"]).strip()
        from .sweep_settings import sweep_settings

        _log("the Stribeck sweep's settings (transient rtol x transient_irregular_block)", progress)
        ss = sweep_settings(out, quick=payload["meta"]["quick"])
        payload["sweep_settings"] = ss["numbers"]
        files.update(ss["files"])
        extra = (extra + "\n\n" + ss["markdown"]).strip()
        from .cycle_check import cycle_check

        _log("checking the cycles the Stribeck sweep's transients stop on", progress)
        cc = cycle_check(out, quick=payload["meta"]["quick"])
        payload["cycle_check"] = cc["numbers"]
        files.update(cc["files"])
        extra = (extra + "\n\n" + cc["markdown"]).strip()
    payload["files"] = {k: str(v) for k, v in files.items()}
    payload["command"] = command
    with open(files["json"], "w") as f:
        json.dump(_json_safe(payload), f, indent=1)
    files["summary"].write_text(render_summary(payload, images=images, extra=extra, command=command))
    if docs is not None:
        docs = pathlib.Path(docs)
        docs.parent.mkdir(parents=True, exist_ok=True)
        docs.write_text(render_docs(payload, command=command, extra=extra))
        payload["files"]["docs"] = str(docs)
    return payload


def render_docs(payload: dict, *, command: str | None = None, extra: str = "") -> str:
    """The docs page (``docs/benchmarks.md``): the summary without images, with how to regenerate it."""
    head = ("<!-- Generated by tribosweep bench (python/tribosweep/bench/workprecision.py): do not edit by hand. "
            "Regenerate with `tribosweep bench --quick --out bench_out --docs docs/benchmarks.md` "
            "(or without --quick for the full ladder). -->\n")  # fmt: skip
    extra = "\n".join(line for line in extra.splitlines() if not line.startswith("!["))
    text = head + render_summary(payload, images=None, extra=extra, command=command)
    while "\n\n\n" in text:
        text = text.replace("\n\n\n", "\n\n")
    return text
