"""Disk space: what a sweep's files take, what is free, and the one error a full disk gives.

A sweep writes two things: its parts (``<output>.parts/``, one uncompressed ``.npz`` per chunk,
kept until the final file is complete) and the final netCDF file (compressed). Before any work,
a sweep whose parts alone would not fit is refused (:func:`check_room`: a lower bound, so it never
refuses a sweep that fits). While writing, a full disk raises :class:`DiskFullError`: one line that
names the path, the space still needed and how to resume; the parts written so far are kept. The
netCDF writer also checks the free space before every slab it hands to the HDF5 library, because
that library can crash the process (a segmentation fault, not an error code) when a write meets a
full disk: see :class:`tribosweep._sweep.netcdf.NetCDFWriter`.
"""

from __future__ import annotations

import errno
import os
import shutil
from pathlib import Path

import numpy as np

#: Bytes kept free beyond what a write needs: HDF5 metadata (B-tree nodes, object headers, the
#: global heap of the strings) and the parts' zip directories.
MARGIN: int = 4 << 20


class DiskFullError(OSError):
    """No space left on the device: the message names the path, the space needed and how to resume."""

    def __init__(self, message: str):
        super().__init__(errno.ENOSPC, message)

    def __str__(self) -> str:
        return str(self.strerror)


def is_full(e: BaseException) -> bool:
    """True for an OSError that means a full disk or quota (ENOSPC, EDQUOT)."""
    return isinstance(e, OSError) and e.errno in (errno.ENOSPC, errno.EDQUOT)


def free_bytes(path) -> int:
    """Free bytes (for an unprivileged writer) on the file system of ``path`` or its nearest existing parent."""
    p = Path(path).absolute()
    while not p.exists() and p != p.parent:
        p = p.parent
    return shutil.disk_usage(p).free


def human(n: float) -> str:
    """``1234567`` -> ``'1.2 MB'`` (decimal units, as ``df -H``)."""
    for unit in ("B", "kB", "MB", "GB", "TB"):
        if abs(n) < 1000 or unit == "TB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} TB"  # pragma: no cover


def fixed_point_bytes(specs, trailing: dict) -> int:
    """Bytes per point of every fixed-size per-point variable (text not counted), uncompressed."""
    total = 0
    for spec in specs:
        if spec.dtype == "str":
            continue
        tail = [len(trailing[d][0]) for d in spec.dims if d in trailing]
        total += np.dtype(spec.dtype).itemsize * int(np.prod(tail, dtype=np.int64))
    return total


def check_room(output: Path, n_points: int, point_bytes: int) -> None:
    """Refuse (before any work) a sweep whose parts alone would not fit on the output's file system.

    ``point_bytes`` counts only the fixed-size variables, so the estimate is a lower bound: the
    reasons' text and the final file come on top.
    """
    need = n_points * point_bytes
    free = free_bytes(output)
    if need + MARGIN > free:
        raise DiskFullError(
            f"output = {str(output)!r}: the sweep's {n_points} points need at least {human(need)} for their parts "
            f"({point_bytes} bytes per point, uncompressed, kept until the file is complete) and more for the file, "
            f"but {human(free)} is free there: free space, or write the output to another disk"
        )


def parts_full(path, saved: int, total: int, parts_dir, need: int, free: int) -> DiskFullError:
    """The error of a part that does not fit: where, what is kept, what is still needed, how to resume."""
    return DiskFullError(
        f"no space left on device writing {path}: {saved} of {total} chunks are saved in {parts_dir}; about "
        f"{human(need)} more is needed to finish the parts (and the final file on top), {human(free)} is free; free "
        "space, then run the same sweep again with resume=True (--resume)"
    )


def file_full(path, need: int, free: int, parts_dir) -> DiskFullError:
    """The error of a final file that does not fit: its temporary file is removed, the parts are kept."""
    return DiskFullError(
        f"no space left on device writing {path}: the rest of the file needs up to {human(need)} (uncompressed), "
        f"{human(free)} is free; the unfinished file is removed and every chunk is kept in {parts_dir}; free space, "
        "then run the same sweep again with resume=True (--resume) to write the file"
    )


def remove_quietly(path) -> None:
    """Delete a file if it exists, ignoring errors (cleanup on an error path must not mask the error)."""
    try:
        os.remove(path)
    except OSError:
        pass
