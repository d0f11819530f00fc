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

from .schema import TRAILING_DIMS, VarSpec


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


class NetCDFWriter:
    """Write a sweep's netCDF file chunk by chunk (netCDF4, ``<path>.tmp`` then ``os.replace``).

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
    """

    def __init__(self, path, coords, static_vars, points, attrs):
        import netCDF4

        self.schema = _Schema(coords, static_vars, points, attrs)
        self.path = os.fspath(path)
        self.tmp = self.path + ".tmp"
        self.nc = netCDF4.Dataset(self.tmp, "w", format="NETCDF4")
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
        for spec in self.schema.points:
            if spec.dtype == "str":
                var = nc.createVariable(spec.name, str, spec.dims)
            elif spec.dtype == "f8":
                var = nc.createVariable(spec.name, "f8", spec.dims, fill_value=np.nan, zlib=True, complevel=1)
            else:
                var = nc.createVariable(spec.name, spec.dtype, spec.dims, zlib=True, complevel=1)
            var.set_auto_maskandscale(False)
            var.setncatts(clean_attrs(spec.attrs))
            self.vars[spec.name] = (spec, var)
        nc.setncatts(self.schema.attrs)

    def write(self, start: int, stop: int, arrays: Mapping[str, np.ndarray]) -> None:
        """Write the points ``[start, stop)`` (C-order flat indices) of every per-point variable."""
        for idx, part in flat_slabs(start, stop, self.schema.shape):
            shape = _slab_shape(idx)
            for name, (spec, var) in self.vars.items():
                tail = self.schema.tail(spec)
                data = np.asarray(arrays[name])[part].reshape(shape + tail)
                if spec.dtype == "str":
                    data = data.astype(object)
                var[idx + (slice(None),) * len(tail)] = data

    def close(self) -> None:
        """Close the file and move it to its final path (atomic on one file system)."""
        self.nc.close()
        os.replace(self.tmp, self.path)

    def abort(self) -> None:
        """Close and delete the temporary file."""
        try:
            self.nc.close()
        finally:
            if os.path.exists(self.tmp):
                os.remove(self.tmp)


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
