"""Writing sweep results: chunk slabs and two writers (netCDF file, in memory); the schema is in ``schema``.

A sweep's points are numbered in C order over its dimensions. A chunk is a contiguous range of
that numbering; :func:`flat_slabs` splits any range into at most ``2 ndim - 1`` hyperslabs, so
a chunk's results go straight into the full-shape netCDF variables without holding the sweep in
memory. :class:`NetCDFWriter` writes ``<path>`` through ``<path>.tmp`` and ``os.replace``: no
half-written file ever sits at the final path. :class:`MemoryWriter` builds the same Dataset
in memory (for sweeps without an output file); both give identical Datasets.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping

import numpy as np
import xarray as xr

from . import disk
from .schema import TRAILING_DIMS, VarSpec

#: Target size of one HDF5 chunk of a per-point variable (bytes). Each variable's chunk cache holds
#: two chunks, so the writer's memory is bounded by about ``2 x CHUNK_BYTES x variables`` (about
#: 60 MB for the 55 variables of a sweep), whatever the sweep's size.
CHUNK_BYTES: int = 512 << 10
#: Width (UTF-8 bytes) of a text variable whose longest value the writer is not told.
DEFAULT_TEXT_WIDTH: int = 256


def _library_lock():
    """xarray's lock of the netCDF-C and HDF5 libraries, which are not thread-safe.

    The writer holds it around every call into netCDF4. Without it, the garbage collector closed a
    file that xarray had opened, in another thread of the process (a dask client's event loop),
    while this writer was handing a slab to HDF5: a segmentation fault (fresh-clone CI, 2026-11-26,
    ``tests/test_faults.py``). xarray closes a collected file only when it can take this lock at
    once, so holding it makes that close wait for a later collection.
    """
    from xarray.backends.locks import HDF5_LOCK, NETCDFC_LOCK, combine_locks

    return combine_locks([NETCDFC_LOCK, HDF5_LOCK])


def flat_slabs(start: int, stop: int, shape: tuple[int, ...]) -> Iterator[tuple[tuple[slice, ...], slice]]:
    """Split the C-order flat index range ``[start, stop)`` of an array of ``shape`` into hyperslabs.

    Yields
    ------
    (tuple of slice, slice)
        The slab's index in the full array and the matching slice of the range's flat data
        (relative to ``start``). The slab's data, reshaped to the slab's shape, is that slice.
    """

    def rec(a: int, b: int, shape: tuple[int, ...], prefix: tuple) -> Iterator[tuple]:
        if a >= b:
            return
        if len(shape) == 1:
            yield prefix + (slice(a, b),), (a, b)
            return
        stride = int(np.prod(shape[1:]))
        rest = tuple(slice(0, s) for s in shape[1:])
        i0, r0 = divmod(a, stride)
        i1, r1 = divmod(b, stride)
        if i0 == i1:  # within one index of the leading axis
            for idx, (x, y) in rec(r0, r1, shape[1:], prefix + (slice(i0, i0 + 1),)):
                yield idx, (x + i0 * stride, y + i0 * stride)
            return
        if r0:
            for idx, (x, y) in rec(r0, stride, shape[1:], prefix + (slice(i0, i0 + 1),)):
                yield idx, (x + i0 * stride, y + i0 * stride)
            i0 += 1
        if i1 > i0:
            yield prefix + (slice(i0, i1),) + rest, (i0 * stride, i1 * stride)
        if r1:
            for idx, (x, y) in rec(0, r1, shape[1:], prefix + (slice(i1, i1 + 1),)):
                yield idx, (x + i1 * stride, y + i1 * stride)

    for idx, (a, b) in rec(start, stop, tuple(shape), ()):
        yield idx, slice(a - start, b - start)


def _slab_shape(idx: tuple[slice, ...]) -> tuple[int, ...]:
    return tuple(s.stop - s.start for s in idx)


def _attr_value(v):
    if isinstance(v, (bool, np.bool_)):
        return int(v)
    if isinstance(v, (list, tuple)):
        return np.asarray(v)
    return v


def clean_attrs(attrs: Mapping) -> dict:
    """Attributes netCDF can store: ``None`` dropped, bools as ints, sequences as arrays."""
    return {k: _attr_value(v) for k, v in attrs.items() if v is not None}


class _Schema:
    def __init__(self, coords, static_vars, points, attrs):
        self.coords = coords  # {dim: (values, attrs)}
        self.static_vars = static_vars  # {name: (dims, values, attrs)}
        self.points = points  # [VarSpec]
        self.attrs = clean_attrs(attrs)
        self.dims = tuple(coords)
        self.shape = tuple(len(coords[d][0]) for d in self.dims)
        self.trailing = {d: TRAILING_DIMS[d] for p in points for d in p.dims[len(self.dims) :]}

    def tail(self, spec: VarSpec) -> tuple[int, ...]:
        """Shape of a variable's dimensions after the sweep's own."""
        return tuple(len(self.trailing[d][0]) for d in spec.dims[len(self.dims) :])


def chunk_shape(shape: tuple[int, ...], itemsize: int, target: int = CHUNK_BYTES) -> tuple[int, ...]:
    """HDF5 chunk of a variable of ``shape``: contiguous in C order (the trailing dimensions whole,
    then as many rows of the next one as fit in ``target`` bytes, the leading ones 1), so that a
    sweep's chunks, which are ranges of the C-order numbering, fill HDF5 chunks one after another.

    Examples
    --------
    >>> chunk_shape((1000, 1000, 1), 8)
    (65, 1000, 1)
    >>> chunk_shape((3, 2), 8)
    (3, 2)
    """
    room = max(1, target // itemsize)
    out = [1] * len(shape)
    for i in range(len(shape) - 1, -1, -1):
        n = max(1, int(shape[i]))
        if n <= room:
            out[i], room = n, room // n
        else:
            out[i] = max(1, room)
            break
    return tuple(out)


class NetCDFWriter:
    """Write a sweep's netCDF file chunk by chunk (netCDF4, ``<path>.tmp`` then ``os.replace``).

    Memory is bounded whatever the sweep's size: per-point variables are stored in HDF5 chunks of
    about ``CHUNK_BYTES`` that follow the C-order numbering, each with a cache of two chunks.

    A full disk is an error, never a crash: before each slab is handed to the HDF5 library (which
    can crash the process when a write meets a full disk) the free space is checked against the
    slab's uncompressed size plus what the library may still hold unwritten; when that is short,
    the library's buffers are flushed first (``sync``) and the check repeated, and if it still does
    not fit :class:`tribosweep._sweep.disk.DiskFullError` is raised before the write. Any error of
    the library (its return codes) is raised as ``OSError`` naming the file.

    Parameters
    ----------
    path : path-like
        Final file.
    coords : dict of str to (array, dict)
        Dimension coordinates in dimension order, with their attributes.
    static_vars : dict of str to (tuple, array, dict)
        Small variables written at once: ``{name: (dims, values, attrs)}``.
    points : list of VarSpec
        Per-point variables over all dimensions, written by :meth:`write`.
    attrs : dict
        Global attributes.
    parts_dir : path-like, optional
        Where the sweep's parts are kept (named in the error of a full disk).
    text_widths : dict of str to int, optional
        Longest UTF-8 value (bytes) of each text variable (default ``DEFAULT_TEXT_WIDTH``); text is
        stored as a character array of that width.
    """

    def __init__(self, path, coords, static_vars, points, attrs, *, parts_dir=None, text_widths=None):
        import netCDF4

        self.schema = _Schema(coords, static_vars, points, attrs)
        self.text_widths = dict(text_widths or {})
        self.path = os.fspath(path)
        self.tmp = self.path + ".tmp"
        self.parts_dir = parts_dir
        self.unsynced = 0  # bytes handed to the library since its buffers were last flushed (upper bound)
        self.written = self.slack = 0
        n = int(np.prod(self.schema.shape))
        self.total = n * disk.fixed_point_bytes(points, self.schema.trailing)
        self.total += n * sum(int(self.text_widths.get(p.name, DEFAULT_TEXT_WIDTH)) for p in points if p.dtype == "str")
        self.lock = _library_lock()
        self._reserve(disk.MARGIN)
        try:
            with self.lock:
                self.nc = netCDF4.Dataset(self.tmp, "w", format="NETCDF4")
                self._define()
        except (RuntimeError, OSError) as e:
            err = self._library_error(e)
            self.abort()
            raise err from e
        except BaseException:
            self.abort()
            raise

    def _define(self) -> None:
        nc = self.nc
        for dim, (values, a) in self.schema.coords.items():
            nc.createDimension(dim, len(values))
            var = nc.createVariable(dim, "f8", (dim,))
            var.setncatts(clean_attrs(a))
            var[:] = np.asarray(values, dtype=np.float64)
        for dim, (values, a) in self.schema.trailing.items():
            nc.createDimension(dim, len(values))
            var = nc.createVariable(dim, values.dtype, (dim,))
            var.setncatts(clean_attrs(a))
            var[:] = values
        for name, (dims, values, a) in self.schema.static_vars.items():
            values = np.asarray(values)
            for dim, size in zip(dims, values.shape):
                if dim not in nc.dimensions:  # a variable on its own dimension (e.g. hopf_point)
                    nc.createDimension(dim, size)
            fill = np.nan if values.dtype.kind == "f" else None
            var = nc.createVariable(name, values.dtype, dims, fill_value=fill)
            var.setncatts(clean_attrs(a))
            var[...] = values
        self.vars = {}
        self.slack = 0  # one HDF5 chunk of every variable: what a flush of half-written chunks costs again
        for spec in self.schema.points:
            if spec.dtype == "str":
                # Text as a CF character array (UTF-8, padded to the longest value): read lazily by
                # xarray, where a variable-length string variable is decoded whole on opening.
                width = max(1, int(self.text_widths.get(spec.name, DEFAULT_TEXT_WIDTH)))
                dim = f"{spec.name}_length"
                nc.createDimension(dim, width)
                shape = self.schema.shape + (width,)
                chunks = chunk_shape(shape, 1)
                var = nc.createVariable(spec.name, "S1", spec.dims + (dim,), zlib=True, complevel=1, chunksizes=chunks,
                                        chunk_cache=2 * int(np.prod(chunks)) + (64 << 10))  # fmt: skip
                var.setncattr("_Encoding", "utf-8")
                var.set_auto_chartostring(False)  # written as characters (stringtochar), read back as text
                self.slack += int(np.prod(chunks))
            else:
                size = np.dtype(spec.dtype).itemsize
                chunks = chunk_shape(self.schema.shape + self.schema.tail(spec), size)
                cache = 2 * size * int(np.prod(chunks)) + (64 << 10)
                fill = {"fill_value": np.nan} if spec.dtype == "f8" else {}
                var = nc.createVariable(spec.name, spec.dtype, spec.dims, zlib=True, complevel=1, chunksizes=chunks,
                                        chunk_cache=cache, **fill)  # fmt: skip
                self.slack += size * int(np.prod(chunks))
            var.set_auto_maskandscale(False)
            var.setncatts(clean_attrs(spec.attrs))
            self.vars[spec.name] = (spec, var)
        nc.setncatts(self.schema.attrs)

    def _reserve(self, nbytes: int) -> None:
        """Make sure ``nbytes`` more (uncompressed) can be handed to the library without a full disk."""
        free = disk.free_bytes(self.tmp)
        if free >= self.unsynced + nbytes + disk.MARGIN:
            return
        if self.unsynced > self.slack and free >= self.unsynced + disk.MARGIN:
            with self.lock:
                self.nc.sync()  # the library's buffers go to disk now, while they still fit
            # A chunk flushed half-written is written again, whole, when it is finished.
            self.unsynced = self.slack
            free = disk.free_bytes(self.tmp)
            if free >= self.unsynced + nbytes + disk.MARGIN:
                return
        raise disk.file_full(self.path, max(nbytes, self.total - self.written) + disk.MARGIN, free, self.parts_dir)

    def _library_error(self, e: Exception) -> OSError:
        free = disk.free_bytes(self.tmp)
        if disk.is_full(e) or free < self.unsynced + disk.MARGIN:
            return disk.file_full(self.path, self.total - self.written + disk.MARGIN, free, self.parts_dir)
        return OSError(f"writing {self.tmp} failed: {e}")

    def write(self, start: int, stop: int, arrays: Mapping[str, np.ndarray]) -> None:
        """Write the points ``[start, stop)`` (C-order flat indices) of every per-point variable.

        Raises
        ------
        DiskFullError
            The slab would not fit on the disk (checked before anything is written).
        OSError
            The netCDF library reported an error.
        """
        import netCDF4

        arrays = dict(arrays)
        nbytes = 0
        for spec, var in self.vars.values():
            a = np.asarray(arrays[spec.name])
            if spec.dtype == "str":
                width = var.shape[-1]
                raw = np.char.encode(a.astype(str), "utf-8")
                if raw.dtype.itemsize > width:
                    raise ValueError(f"{spec.name}: a value of {raw.dtype.itemsize} bytes is longer than the file's "
                                     f"{width} (text_widths)")  # fmt: skip
                arrays[spec.name] = netCDF4.stringtochar(raw.astype(f"S{width}"))
                nbytes += a.size * width
            else:
                nbytes += a.size * np.dtype(spec.dtype).itemsize
        self._reserve(nbytes)
        try:
            with self.lock:
                for idx, part in flat_slabs(start, stop, self.schema.shape):
                    shape = _slab_shape(idx)
                    for name, (spec, var) in self.vars.items():
                        tail = (var.shape[-1],) if spec.dtype == "str" else self.schema.tail(spec)
                        data = np.asarray(arrays[name])[part].reshape(shape + tail)
                        var[idx + (slice(None),) * len(tail)] = data
        except (RuntimeError, OSError) as e:
            raise self._library_error(e) from e
        self.unsynced += nbytes
        self.written += nbytes

    def close(self) -> None:
        """Close the file and move it to its final path (atomic on one file system); on an error
        the temporary file is removed and the error raised (``DiskFullError`` for a full disk)."""
        try:
            self._reserve(0)
            try:
                with self.lock:
                    self.nc.close()
            except (RuntimeError, OSError) as e:
                raise self._library_error(e) from e
            os.replace(self.tmp, self.path)
        except BaseException:
            self.abort()
            raise

    def abort(self) -> None:
        """Delete the temporary file, closing it without risk on a full disk (this runs on error paths).

        The file is truncated first, which frees its space, so that what the library flushes on
        closing always fits; errors of the close are ignored (the original error is what matters).
        """
        nc = getattr(self, "nc", None)
        try:
            if os.path.exists(self.tmp):
                os.truncate(self.tmp, 0)
        except OSError:
            pass
        try:
            if nc is not None and nc.isopen():
                with self.lock:
                    nc.close()
        except Exception:  # noqa: BLE001 - the file is deleted anyway
            pass
        finally:
            disk.remove_quietly(self.tmp)


class MemoryWriter:
    """The same interface as :class:`NetCDFWriter`, building an in-memory ``xarray.Dataset``."""

    def __init__(self, coords, static_vars, points, attrs):
        self.schema = _Schema(coords, static_vars, points, attrs)
        n = int(np.prod(self.schema.shape))
        self.data = {}
        for spec in self.schema.points:
            dtype = object if spec.dtype == "str" else spec.dtype
            self.data[spec.name] = np.empty((n,) + self.schema.tail(spec), dtype=dtype)

    def write(self, start: int, stop: int, arrays: Mapping[str, np.ndarray]) -> None:
        """Store the points ``[start, stop)``."""
        for name, buf in self.data.items():
            buf[start:stop] = np.asarray(arrays[name]).astype(buf.dtype, copy=False)

    def to_dataset(self) -> xr.Dataset:
        """The finished Dataset."""
        s = self.schema
        coords = {d: (d, np.asarray(v, dtype=np.float64), clean_attrs(a)) for d, (v, a) in s.coords.items()}
        coords.update({d: (d, v, clean_attrs(a)) for d, (v, a) in s.trailing.items()})
        data = {name: (dims, np.asarray(v), clean_attrs(a)) for name, (dims, v, a) in s.static_vars.items()}
        for spec in s.points:
            shape = s.shape + s.tail(spec)
            data[spec.name] = (spec.dims, self.data[spec.name].reshape(shape), clean_attrs(spec.attrs))
        return xr.Dataset(data, coords=coords, attrs=s.attrs)
