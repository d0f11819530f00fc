"""The sweep's netCDF output: CF compliance, ncdump, round trips, slabs, atomic writes."""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

import tribosweep as ts
from tribosweep import _census
from tribosweep._sweep import schema as _schema
from tribosweep._sweep.netcdf import MemoryWriter, NetCDFWriter, flat_slabs
from tribosweep._sweep.schema import VarSpec


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory) -> pathlib.Path:
    """A small sweep with every kind of variable: an extra axis, text reasons, the calibrated wear rate."""
    path = tmp_path_factory.mktemp("nc") / "sweep.nc"
    ds = ts.sweep(
        normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], extra_axes={"mu": [0.2, 0.25]}, strategy="auto",
        t_max=1e-3, output=path, chunk_size=5, progress=False, wear_calibration=ts.WearCalibration(b_w=1e-9),
    )  # fmt: skip
    assert (ds.reason.values != "").any()  # non-trivial text (failed or undetermined points)
    ds.close()
    return path


def _compliance_checker() -> list[str]:
    pytest.importorskip("compliance_checker", reason="compliance-checker is not installed (pip install '.[test]')")
    exe = pathlib.Path(sys.executable).with_name("compliance-checker")
    if exe.exists():
        return [str(exe)]
    found = shutil.which("compliance-checker")
    if found is None:
        pytest.skip("the compliance-checker command is not on PATH")
    return [found]


def test_cf_1_11_compliance(sweep_file, tmp_path):
    report = tmp_path / "cf.json"
    cmd = [*_compliance_checker(), "--test=cf:1.11", "--format=json", f"--output={report}", str(sweep_file)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=False)
    assert report.exists(), proc.stdout + proc.stderr
    result = next(iter(json.loads(report.read_text()).values()))
    assert result["possible_points"] > 0
    # A failed check scores below its maximum or carries messages; medium and low priorities are
    # recommendations (warnings), high priority ones are errors.
    errors = [
        f"{c['name']}: {c['msgs']}"
        for c in result["high_priorities"]
        if c["value"][0] < c["value"][1] or c["msgs"]
    ]
    assert not errors, "\n".join(errors)
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_ncdump_reads_the_header(sweep_file):
    if shutil.which("ncdump") is None:
        pytest.skip("ncdump is not on PATH (Debian: apt-get install netcdf-bin)")
    out = subprocess.run(["ncdump", "-h", str(sweep_file)], capture_output=True, text=True, timeout=60, check=True)
    for text in ("normal_load = 3", "arm_length = 2", "sliding_speed = 1", "mu = 2", "ubyte regime(", ":Conventions = \"CF-1.11\""):
        assert text in out.stdout, text


def test_every_variable_is_described(sweep_file):
    with xr.open_dataset(sweep_file) as ds:
        for name, var in ds.variables.items():
            assert "long_name" in var.attrs, name
            if "flag_values" in var.attrs:
                fv = np.asarray(var.attrs["flag_values"])
                assert fv.dtype == var.dtype, name
                assert len(var.attrs["flag_meanings"].split()) == fv.size, name
                assert "units" not in var.attrs
            elif var.dtype.kind in "fiu":
                assert "units" in var.attrs, name
        for key in ("Conventions", "title", "institution", "source", "history", "references", "comment"):
            assert key in ds.attrs, key
        assert ds.attrs["Conventions"] == "CF-1.11"
        assert ds.attrs["institution"] == "tribosweep"
        assert ds.attrs["source"] == f"tribosweep {ts.__version__}"
        assert "1985" in ds.attrs["references"]
        assert ds.attrs["history"][:4].isdigit() and "tribosweep.sweep" in ds.attrs["history"]
        assert "BELOW a Hopf load" in ds.attrs["comment"]
        assert ds.regime.dtype == np.uint8 and ds.bistable.dtype == np.int8
        assert ds.regime.attrs["flag_meanings"].split() == list(ts.REGIME_NAMES)
        assert ds.bistable.attrs["flag_values"].tolist() == [-1, 0, 1, 2]
        assert ds.bistable.attrs["flag_meanings"].split() == ["not_checked", "one_attractor", "coexisting", "no_saddle"]
        assert ds.attrs["arm_exponent_normal"] == pytest.approx(ts.ARM_EXPONENTS["normal"])


def test_round_trip_through_xarray(sweep_file, tmp_path):
    with xr.open_dataset(sweep_file) as ds:
        ds.load()
    again = tmp_path / "again.nc"
    ds.to_netcdf(again, engine="netcdf4")
    with xr.open_dataset(again) as back:
        xr.testing.assert_identical(ds, back)


def test_in_memory_dataset_round_trips_and_matches_the_file(sweep_file, tmp_path):
    mem = ts.sweep(
        normal_load=[10.0, 30.0, 60.0], arm_length=[0.05, 0.1], extra_axes={"mu": [0.2, 0.25]}, strategy="auto",
        t_max=1e-3, chunk_size=5, progress=False, wear_calibration=ts.WearCalibration(b_w=1e-9),
    )  # fmt: skip
    path = tmp_path / "mem.nc"
    mem.to_netcdf(path, engine="netcdf4")
    with xr.open_dataset(path) as back:
        xr.testing.assert_identical(mem, back)
    with xr.open_dataset(sweep_file) as f:
        keep = [v for v in mem.data_vars if v != "wall_time"]
        a, b = mem[keep], f[keep].load()
        a.attrs = {k: v for k, v in mem.attrs.items() if k != "history"}
        b.attrs = {k: v for k, v in f.attrs.items() if k != "history"}
        xr.testing.assert_identical(a, b)


def test_raw_netcdf4_reading_agrees_with_xarray(sweep_file):
    import netCDF4

    with xr.open_dataset(sweep_file) as ds, netCDF4.Dataset(sweep_file) as nc:
        nc.set_auto_maskandscale(False)
        assert nc.file_format == "NETCDF4"
        assert tuple(nc["regime"].dimensions) == ds.regime.dims
        for name in ("regime", "status", "decided_by", "bistable", "n_rhs", "reason"):
            np.testing.assert_array_equal(nc[name][...], ds[name].values)
        for name in ("growth_rate", "wear_rate_relative", "cycle_omega", "normal_load", "mu"):
            np.testing.assert_array_equal(nc[name][...], ds[name].values)
        assert nc["regime"].getncattr("flag_values").dtype == np.uint8
        assert nc.getncattr("Conventions") == "CF-1.11"


@settings(max_examples=300, deadline=None)
@given(
    shape=st.lists(st.integers(1, 5), min_size=1, max_size=4).map(tuple),
    data=st.data(),
)
def test_flat_slabs_tile_any_range_exactly(shape, data):
    n = int(np.prod(shape))
    a = data.draw(st.integers(0, n))
    b = data.draw(st.integers(a, n))
    seen = np.full(shape, -1)
    flat = np.arange(a, b)
    count = 0
    for idx, part in flat_slabs(a, b, shape):
        slab = tuple(s.stop - s.start for s in idx)
        assert (seen[idx] == -1).all()
        seen[idx] = flat[part].reshape(slab)
        count += 1
    expected = np.full(n, -1)
    expected[a:b] = flat
    np.testing.assert_array_equal(seen.ravel(), expected)
    assert count <= max(1, 2 * len(shape) - 1)


def _writer_args():
    coords = {"a": (np.array([1.0, 2.0, 3.0]), {"units": "m", "long_name": "a"}),
              "b": (np.array([0.5, 1.5]), {"units": "s", "long_name": "b"})}  # fmt: skip
    points = [VarSpec("v", ("a", "b"), "f8", {"units": "1", "long_name": "v"}),
              VarSpec("t", ("a", "b"), "str", {"long_name": "t"})]  # fmt: skip
    return coords, {}, points, {"Conventions": "CF-1.11", "flag": True, "skip": None}


def test_writers_agree_and_the_file_appears_only_when_complete(tmp_path):
    path = tmp_path / "w.nc"
    w = NetCDFWriter(path, *_writer_args())
    m = MemoryWriter(*_writer_args())
    values = np.arange(6.0)
    text = np.array([f"p{i}" for i in range(6)])
    for start, stop in ((0, 4), (4, 6)):
        chunk = {"v": values[start:stop], "t": text[start:stop]}
        w.write(start, stop, chunk)
        m.write(start, stop, chunk)
        assert not path.exists() and (tmp_path / "w.nc.tmp").exists()
    w.close()
    assert path.exists() and not (tmp_path / "w.nc.tmp").exists()
    with xr.open_dataset(path) as f:
        xr.testing.assert_identical(f.load(), m.to_dataset())
        assert f.attrs["flag"] == 1 and "skip" not in f.attrs
        assert f.v.values.tolist() == [[0.0, 1.0], [2.0, 3.0], [4.0, 5.0]]


def test_the_writer_holds_xarrays_lock_of_the_netcdf_libraries_while_it_writes(tmp_path):
    """netCDF-C and HDF5 are not thread-safe. xarray closes a file it opened when the garbage
    collector finds it, in whatever thread, but only if it can take its lock at once: the writer
    holds that same lock around every library call, so such a close never runs beside a slab
    (it crashed a dask-client sweep with a segmentation fault, fresh-clone CI of 2026-11-26)."""
    from xarray.backends.netCDF4_ import NETCDF4_PYTHON_LOCK

    def xarray_could_close() -> bool:
        if NETCDF4_PYTHON_LOCK.acquire(blocking=False):
            NETCDF4_PYTHON_LOCK.release()
            return True
        return False

    class Watched:
        """Values that record, each time the writer reads them, whether xarray could close a file."""

        def __init__(self, a):
            self.a, self.seen = a, []

        def __array__(self, dtype=None, copy=None):
            self.seen.append(xarray_could_close())
            return np.asarray(self.a, dtype=dtype)

    w = NetCDFWriter(tmp_path / "w.nc", *_writer_args())
    v = Watched(np.arange(6.0))
    w.write(0, 6, {"v": v, "t": np.array([f"p{i}" for i in range(6)])})
    assert False in v.seen  # read inside the slab loop, under the lock
    assert xarray_could_close()  # and released after
    with w.lock:
        assert not xarray_could_close()
    w.close()
    assert xarray_could_close()
    with xr.open_dataset(tmp_path / "w.nc") as f:
        assert f.v.values.ravel().tolist() == list(range(6))


def test_abort_leaves_nothing(tmp_path):
    path = tmp_path / "w.nc"
    w = NetCDFWriter(path, *_writer_args())
    w.abort()
    assert not path.exists() and not os.path.exists(str(path) + ".tmp")


def test_a_failed_assembly_leaves_no_file(tmp_path, monkeypatch):
    def broken(self, start, stop, arrays):
        raise RuntimeError("disk full")

    monkeypatch.setattr(NetCDFWriter, "write", broken)
    with pytest.raises(RuntimeError, match="disk full"):
        ts.sweep(normal_load=[10.0, 20.0], strategy="linear", output=tmp_path / "s.nc", progress=False)
    assert not (tmp_path / "s.nc").exists() and not (tmp_path / "s.nc.tmp").exists()
    assert (tmp_path / "s.nc.parts" / "chunk_000000.npz").exists()  # the work is kept
    monkeypatch.undo()
    ts.sweep(normal_load=[10.0, 20.0], strategy="linear", output=tmp_path / "s.nc", resume=True,
             progress=False).close()  # fmt: skip
    assert (tmp_path / "s.nc").exists()


def test_point_specs_cover_the_chunk_output():
    specs = {s.name for s in _schema.point_specs(("x",))}
    assert specs == set(_schema.POINT_VARIABLES) | set(_census.CENSUS_VARIABLES)
    assert {s.name: s.dims for s in _schema.point_specs(("x",))}["basin_fraction"] == ("x", "attractor")
    assert {s.name for s in _schema.point_specs(("x",), wear_rate=True)} == specs | {"wear_rate"}


def test_labels_turn_every_flag_variable_into_its_names(sweep_file):
    with xr.open_dataset(sweep_file) as ds:
        for var in ("regime", "status", "decided_by", "bistable", "wear_applicability"):
            names = str(ds[var].attrs["flag_meanings"]).split()
            values = np.atleast_1d(ds[var].attrs["flag_values"]).tolist()
            got = ts.labels(ds[var])
            assert got.dims == ds[var].dims
            for v, name in zip(ds[var].values.ravel().tolist(), got.values.ravel().tolist()):
                assert name == names[values.index(v)]
        with pytest.raises(ValueError, match="not a categorical variable"):
            ts.labels(ds["growth_rate"])
