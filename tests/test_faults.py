"""Sweeps that survive: dead workers, crashing points, full disks, existing files, other code, provenance.

Every fault here is real, not a mock of one: worker processes are killed from inside a chunk
(``os._exit``, ``os.abort``) through the runner's test hook (``TRIBOSWEEP_TEST_CRASH``), and disks
are filled for real on a small tmpfs (skipped with the reason where one cannot be mounted).
"""

from __future__ import annotations

import collections
import concurrent.futures
import concurrent.futures.process
import json
import multiprocessing
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

import tribosweep as ts
from tribosweep import cli
from tribosweep._codes import DECIDED_BY, REGIME, STATUS_CRASHED
from tribosweep._sweep import chunk as _chunk
from tribosweep._sweep import cluster as _cluster
from tribosweep._sweep import disk as _disk
from tribosweep._sweep import netcdf as _netcdf
from tribosweep._sweep import plan as _plan
from tribosweep._sweep.runner import TEST_CRASH_ENV

#: Eight points, one arm length: the crash tests poison one load.
ROW = {"normal_load": np.linspace(10.0, 80.0, 8), "strategy": "linear", "progress": False, "boundaries": False}
#: Time integration across processes: the bitwise claims are about real numerics (8 transients).
TRANSIENT = {"normal_load": [10.0, 20.0, 40.0, 80.0], "arm_length": [0.05, 0.1], "strategy": "transient",
             "t_max": 0.2, "progress": False, "boundaries": False}  # fmt: skip
#: A sweep that needs a few MB on disk: 20 loads x 1000 arm lengths, 20 chunks.
BIG = {"normal_load": np.linspace(10.0, 150.0, 20), "arm_length": np.linspace(0.05, 0.127, 1000),
       "strategy": "linear", "chunk_size": 1000, "progress": False, "boundaries": False}  # fmt: skip
BIG_ARGV = ["sweep", "--normal-load", "10:150:20", "--arm-length", "0.05:0.127:1000", "--strategy", "linear",
            "--chunk-size", "1000", "--no-progress", "--no-boundaries"]  # fmt: skip


def strip(ds: xr.Dataset) -> xr.Dataset:
    """What a rerun must reproduce: no wall time, no timestamp, no record of where it ran."""
    ds = ds.drop_vars("wall_time").load()
    ds.attrs = {k: v for k, v in ds.attrs.items() if k != "history" and not k.startswith("dask")}
    return ds


def crash_hook(monkeypatch, *specs: dict) -> None:
    """Arm the runner's test hook for every process started from now on (see runner._test_crash_hook)."""
    specs = [{k: str(v) if isinstance(v, os.PathLike) else v for k, v in spec.items()} for spec in specs]
    monkeypatch.setenv(TEST_CRASH_ENV, json.dumps(specs))


def spawn_pool(n: int = 2) -> concurrent.futures.ProcessPoolExecutor:
    return concurrent.futures.ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("spawn"))


# --- crashes ----------------------------------------------------------------------------------------


def test_a_point_that_aborts_its_process_is_quarantined_and_every_other_point_completes(tmp_path, monkeypatch, caplog):
    reference = strip(ts.sweep(chunk_size=4, **ROW))
    crash_hook(monkeypatch, {"normal_load": 30.0, "action": "abort"})  # SIGABRT on every attempt
    with caplog.at_level("WARNING", logger="tribosweep"), spawn_pool() as ex:
        ds = ts.sweep(executor=ex, output=tmp_path / "q.nc", chunk_size=4, **ROW)
    got = strip(ds)
    bad = {"normal_load": 30.0}
    point = got.sel(bad).squeeze()
    assert int(point.regime) == REGIME["crashed"] and int(point.status) == STATUS_CRASHED
    assert int(point.decided_by) == DECIDED_BY["quarantine"]
    assert str(point.reason.values).startswith("crashed:") and "SIGABRT" in str(point.reason.values)
    assert ts.labels(got.regime).sel(bad).values.ravel().tolist() == ["crashed"]
    assert np.isnan(float(point.growth_rate))
    # Its chunk was split down to the point: its neighbours in the chunk (10, 20 and 40 N) completed.
    assert "splitting it" in caplog.text and "quarantined the point 2" in caplog.text
    xr.testing.assert_identical(got.drop_sel(bad), reference.drop_sel(bad))
    ds.close()


def test_a_dead_pool_worker_costs_only_its_own_chunk(tmp_path, monkeypatch):
    kw = {**ROW, "normal_load": np.linspace(10.0, 160.0, 16), "chunk_size": 2}  # 8 chunks
    reference = strip(ts.sweep(**kw))
    calls, once = tmp_path / "calls.log", tmp_path / "died"
    crash_hook(monkeypatch, {"normal_load": 70.0, "action": "exit", "once": once, "log": calls})  # first attempt dies
    with spawn_pool() as ex:
        ds = ts.sweep(executor=ex, output=tmp_path / "p.nc", **kw)
    assert once.exists()  # a worker really died
    counts = collections.Counter(float(line.split()[0]) for line in calls.read_text().splitlines())
    assert set(counts) == set(np.linspace(10.0, 160.0, 16)[::2])  # every chunk ran
    assert counts[70.0] == 2  # the chunk that died, run again alone
    # Besides it, only chunks the pool had already handed to its processes may run twice: the
    # other worker's and those in the pool's call queue (CPython keeps workers + EXTRA_QUEUED_CALLS
    # items there; one that the surviving worker finished before the pool noticed the death fails
    # with the pool). The chunks collected before, and those queued behind in the sweep, were kept.
    handed = 2 + concurrent.futures.process.EXTRA_QUEUED_CALLS  # 70's chunk among them
    assert sum(counts.values()) - len(counts) <= handed
    xr.testing.assert_identical(strip(ds), reference)
    ds.close()


def test_a_crash_in_process_is_survived_on_resume(tmp_path):
    """Without an executor a crash ends the sweep's own process; the chunk it was computing stays
    marked, and the resumed sweep runs it alone (split down to the point) instead of dying again."""
    out = tmp_path / "s.nc"
    code = ("import numpy as np, sys, tribosweep as ts\n"
            "ts.sweep(normal_load=np.linspace(10.0, 80.0, 8), strategy='linear', progress=False, boundaries=False, "
            f"chunk_size=2, output={str(out)!r}, resume=len(sys.argv) > 1)\n")  # fmt: skip
    env = dict(os.environ, **{TEST_CRASH_ENV: json.dumps({"normal_load": 50.0, "action": "abort"})})
    first = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300)
    assert first.returncode == -6, first.stderr  # SIGABRT: the in-process sweep died with the point
    assert sorted(p.name for p in (tmp_path / "s.nc.parts").glob("chunk_*.npz")) == [
        "chunk_000000.npz", "chunk_000001.npz"]  # fmt: skip
    second = subprocess.run([sys.executable, "-c", code, "resume"], env=env, capture_output=True, text=True,
                            timeout=300)  # fmt: skip
    assert second.returncode == 0, second.stderr
    reference = strip(ts.sweep(**{**ROW, "chunk_size": 2}))
    with xr.open_dataset(out) as ds:
        got = strip(ds)
    assert ts.labels(got.regime).sel(normal_load=50.0).values.ravel().tolist() == ["crashed"]
    xr.testing.assert_identical(got.drop_sel(normal_load=50.0), reference.drop_sel(normal_load=50.0))


# --- dask ---------------------------------------------------------------------------------------------


def test_a_local_cluster_sweep_equals_the_in_process_sweep_also_with_a_worker_killed_and_a_dead_client(
        tmp_path, monkeypatch):  # fmt: skip
    pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install '.[dask]')")
    from tribosweep._sweep import parts as _parts

    reference = strip(ts.sweep(**TRANSIENT))
    # The workers' hook kills the worker computing 40 N on the first attempt, armed by removing `once`.
    once = tmp_path / "died"
    once.touch()
    crash_hook(monkeypatch, {"normal_load": 40.0, "action": "exit", "once": once})
    with _cluster.connect("local:2") as client:
        assert len(client.nthreads()) == 2  # two worker processes
        # Each task takes its worker's share of the cores (one slot per worker), never more.
        assert set(client.run(_cluster.worker_threads).values()) == {max(1, (os.cpu_count() or 1) // 2)}
        ds = ts.sweep(executor=client, output=tmp_path / "d.nc", **TRANSIENT)
        assert ds.attrs["dask_workers"] == 2 and ds.attrs["dask_version"]
        xr.testing.assert_identical(strip(ds), reference)
        ds.close()

        once.unlink()  # now a worker dies inside the chunk of 40 N; dask runs it again elsewhere
        ds = ts.sweep(executor=client, output=tmp_path / "k.nc", **TRANSIENT)
        assert once.exists()  # a worker really died
        xr.testing.assert_identical(strip(ds), reference)
        ds.close()

        # The client dies after two saved chunks; the parts directory alone finishes the sweep, without dask.
        real, saved = _parts.Parts.save, []

        def dying_client(self, k, arrays):
            if len(saved) == 2:
                raise KeyboardInterrupt
            saved.append(k)
            real(self, k, arrays)

        monkeypatch.setattr(_parts.Parts, "save", dying_client)
        with pytest.raises(KeyboardInterrupt):
            ts.sweep(executor=client, output=tmp_path / "e.nc", **TRANSIENT)
    monkeypatch.undo()
    resumed = ts.sweep(output=tmp_path / "e.nc", resume=True, **TRANSIENT)  # keeps the cluster's chunking
    xr.testing.assert_identical(strip(resumed), reference)
    resumed.close()


def test_a_point_that_kills_every_dask_worker_is_quarantined(tmp_path, monkeypatch):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install '.[dask]')")
    import dask

    kw = {**TRANSIENT, "arm_length": [0.072], "chunk_size": 2}  # chunks (10, 20 N) and (40, 80 N)
    reference = strip(ts.sweep(**kw))
    crash_hook(monkeypatch, {"normal_load": 80.0, "action": "abort"})
    # Once dask gives up on a task whose workers died (KilledWorker; here after the first death, to
    # keep the test short), the chunk is split. The scheduler blames every task that was on the dying
    # worker, so 40 N may be blamed too when it shares a worker with 80 N: each blamed point runs alone
    # in a fresh process, where 40 N completes and 80 N aborts again and is quarantined. One worker
    # process (the scheduler keeps two tasks on it) makes bystanders certain.
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):  # the scheduler of local:N runs here
        ds = ts.sweep(scheduler="local:1", output=tmp_path / "q.nc", **kw)
    got = strip(ds)
    point = got.sel(normal_load=80.0).squeeze()
    assert int(point.regime) == REGIME["crashed"] and int(point.status) == STATUS_CRASHED
    assert "dask workers died" in str(point.reason.values)
    assert "alone in a fresh process: killed by SIGABRT" in str(point.reason.values)
    xr.testing.assert_identical(got.drop_sel(normal_load=80.0), reference.drop_sel(normal_load=80.0))
    ds.close()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--scheduler", "local:0"], "scheduler = 'local:0' is out of range: N must be an integer in [1, 256]"),
        (["--scheduler", " "], "scheduler = ' ' is not valid"),
    ],
)
def test_a_bad_scheduler_is_refused_in_one_line(argv, message, tmp_path, capsys):
    code = cli.main(["sweep", "--strategy", "linear", "-o", str(tmp_path / "x.nc"), "--no-progress", *argv])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1


# --- full disks ---------------------------------------------------------------------------------------


@pytest.fixture
def small_disk(tmp_path):
    """A 32 MB tmpfs (needs root; skipped with the reason otherwise)."""
    if shutil.which("mount") is None or os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root and mount(8)")
    mnt = tmp_path / "disk"
    mnt.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=32m", "tmpfs", str(mnt)], capture_output=True, text=True)
    if r.returncode:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip() or r.returncode}")
    yield mnt
    subprocess.run(["umount", "-l", str(mnt)], check=False)


def fill(mnt, leave: int):
    """Fill the disk but ``leave`` bytes: the ballast file, to delete when space is freed."""
    ballast = mnt / "ballast"
    with open(ballast, "ab") as f:
        os.posix_fallocate(f.fileno(), f.tell(), _disk.free_bytes(mnt) - leave)
    return ballast


def one_line_error(capsys, code) -> str:
    err = capsys.readouterr().err
    assert code == 1, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


def test_a_disk_that_fills_while_writing_parts_keeps_them_and_the_resume_is_identical(small_disk, capsys, monkeypatch):
    reference = strip(ts.sweep(**BIG))
    out = small_disk / "s.nc"
    real, calls, ballast = _chunk.compute_chunk, [], []

    def fill_after_four(*args):
        calls.append(1)
        if len(calls) == 5:
            ballast.append(fill(small_disk, leave=64 << 10))  # no room for the fifth part (about 0.4 MB)
        return real(*args)

    monkeypatch.setattr(_chunk, "compute_chunk", fill_after_four)
    err = one_line_error(capsys, cli.main([*BIG_ARGV, "-o", str(out)]))
    parts = small_disk / "s.nc.parts"
    assert f"no space left on device writing {parts / 'chunk_000004.npz'}" in err
    assert f"4 of 20 chunks are saved in {parts}" in err and "--resume" in err and "more is needed" in err
    assert sorted(p.name for p in parts.iterdir() if p.suffix == ".tmp") == []  # no torn temporary file
    assert not out.exists()
    ballast[0].unlink()  # space freed
    monkeypatch.setattr(_chunk, "compute_chunk", real)
    assert cli.main([*BIG_ARGV, "-o", str(out), "--resume"]) == 0
    with xr.open_dataset(out) as ds:
        xr.testing.assert_identical(strip(ds), reference)


def test_a_disk_that_fills_during_assembly_is_an_error_not_a_crash_and_the_resume_is_identical(small_disk, capsys,
                                                                                              monkeypatch):  # fmt: skip
    reference = strip(ts.sweep(**BIG))
    out = small_disk / "s.nc"
    # Compute every part, stopping where the file would be written.
    monkeypatch.setattr(_netcdf.NetCDFWriter, "__init__", lambda *a, **k: (_ for _ in ()).throw(KeyboardInterrupt))
    assert cli.main([*BIG_ARGV, "-o", str(out)]) == 130
    monkeypatch.undo()
    ballast = fill(small_disk, leave=_disk.MARGIN + (2 << 20))  # the file needs several MB more
    # In a child process: the HDF5 library crashed its process on a full disk (segmentation fault).
    proc = subprocess.run([sys.executable, "-m", "tribosweep", *BIG_ARGV, "-o", str(out), "--resume"],
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert proc.returncode == 1, proc.stderr
    err = proc.stderr
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert f"no space left on device writing {out}" in err and "the unfinished file is removed" in err
    assert f"every chunk is kept in {small_disk / 's.nc.parts'}" in err and "--resume" in err
    assert not out.exists() and not (small_disk / "s.nc.tmp").exists()
    assert len(list((small_disk / "s.nc.parts").glob("chunk_*.npz"))) == 20
    ballast.unlink()
    assert cli.main([*BIG_ARGV, "-o", str(out), "--resume"]) == 0
    with xr.open_dataset(out) as ds:
        xr.testing.assert_identical(strip(ds), reference)


def test_a_sweep_whose_parts_cannot_fit_is_refused_before_any_work(small_disk, monkeypatch):
    monkeypatch.setattr(_chunk, "compute_chunk", lambda *a: pytest.fail("work started"))
    kw = {**BIG, "arm_length": np.linspace(0.05, 0.127, 10_000)}  # 200,000 points: about 70 MB of parts
    with pytest.raises(_disk.DiskFullError, match=r"output = .*s.nc': the sweep's 200000 points need at least"):
        ts.sweep(output=small_disk / "s.nc", **kw)
    assert list(small_disk.iterdir()) == []


# --- existing files, other code, provenance -------------------------------------------------------------


def test_an_existing_output_is_refused_before_any_work_unless_overwrite(tmp_path, monkeypatch, capsys):
    out = tmp_path / "o.nc"
    out.write_text("an earlier result")
    monkeypatch.setattr(_chunk, "compute_chunk", lambda *a: pytest.fail("work started"))
    with pytest.raises(ValueError, match=r"output = '.*o.nc' exists: pass overwrite=True \(--overwrite\)"):
        ts.sweep(output=out, **ROW)
    code = cli.main(["sweep", "--normal-load", "10,20", "--strategy", "linear", "-o", str(out), "--no-progress"])
    assert code == 2 and "--overwrite" in capsys.readouterr().err
    assert out.read_text() == "an earlier result"
    monkeypatch.undo()
    code = cli.main(["sweep", "--normal-load", "10,20", "--strategy", "linear", "-o", str(out), "--no-progress",
                     "--overwrite"])  # fmt: skip
    assert code == 0
    with xr.open_dataset(out) as ds:
        assert ds.regime.size == 2


def test_a_forced_resume_across_builds_is_recorded(tmp_path, monkeypatch):
    reference = strip(ts.sweep(chunk_size=2, **ROW))
    out = tmp_path / "s.nc"
    real, calls = _chunk.compute_chunk, []

    def stop_after_two(*a):
        calls.append(1)
        if len(calls) > 2:
            raise KeyboardInterrupt
        return real(*a)

    monkeypatch.setattr(_chunk, "compute_chunk", stop_after_two)
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, chunk_size=2, **ROW)
    monkeypatch.setattr(_chunk, "compute_chunk", real)
    saved = _plan.core_build()
    monkeypatch.setattr(_plan, "core_build", lambda: "0123456789abcdef")  # "rebuilt" code
    with pytest.raises(ValueError, match="core_build differs.*force_resume=True"):
        ts.sweep(output=out, resume=True, chunk_size=2, **ROW)
    ds = ts.sweep(output=out, force_resume=True, chunk_size=2, **ROW)
    assert f"core {saved}, the rest by this code" in ds.attrs["tribosweep_resumed_from"]
    assert ds.attrs["tribosweep_core_build"] == "0123456789abcdef"
    got = strip(ds)
    for name in ("tribosweep_resumed_from", "tribosweep_core_build", "tribosweep_config"):
        got.attrs.pop(name), reference.attrs.pop(name, None)
    xr.testing.assert_identical(got, reference)  # here the code was in fact the same
    ds.close()


def test_every_file_records_the_code_the_software_and_the_whole_configuration(tmp_path, capsys):
    import netCDF4

    toml = tmp_path / "c.toml"
    toml.write_text('normal_load = "10,40"\nstrategy = "linear"\n[model]\nmu = 0.25\n[solver]\nrtol = 1e-7\n')
    out = tmp_path / "p.nc"
    assert cli.main(["sweep", "--config", str(toml), "-o", str(out), "--no-progress"]) == 0
    with xr.open_dataset(out) as ds:
        a = ds.attrs
    assert a["config_toml"] == toml.read_text()
    assert a["tribosweep_version"] == ts.__version__ and a["tribosweep_core_build"] == _plan.core_build()
    assert (a["numpy_version"], a["xarray_version"], a["netCDF4_version"]) == (np.__version__, xr.__version__,
                                                                              netCDF4.__version__)  # fmt: skip
    assert a["hdf5_version"] == netCDF4.__hdf5libversion__
    config = json.loads(a["tribosweep_config"])
    assert config["model"]["mu"] == 0.25 and config["contact"] == "unilateral" and config["strategy"] == "linear"
    assert config["options"]["rtol"] == 1e-7 and config["core_build"] == _plan.core_build()


def test_a_second_writer_of_the_same_output_is_refused_while_the_first_holds_it(tmp_path, monkeypatch):
    import fcntl

    out = tmp_path / "s.nc"
    real, calls = _chunk.compute_chunk, []

    def stop_after_one(*a):
        calls.append(1)
        if len(calls) > 1:
            raise KeyboardInterrupt
        return real(*a)

    monkeypatch.setattr(_chunk, "compute_chunk", stop_after_one)
    with pytest.raises(KeyboardInterrupt):
        ts.sweep(output=out, chunk_size=2, **ROW)
    monkeypatch.undo()
    # Another writer (here this test, through its own open file) holds the sweep's lock.
    fd = os.open(tmp_path / "s.nc.parts" / "lock", os.O_RDWR)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    try:
        with pytest.raises(FileExistsError, match=r"another sweep \(process \d+\) is writing .*s.nc now"):
            ts.sweep(output=out, resume=True, chunk_size=2, **ROW)
    finally:
        os.close(fd)  # the other writer is gone (a crash drops its lock the same way)
    ds = ts.sweep(output=out, resume=True, chunk_size=2, **ROW)
    xr.testing.assert_identical(strip(ds), strip(ts.sweep(chunk_size=2, **ROW)))
    ds.close()
