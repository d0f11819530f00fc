"""Sweeps: the path from :func:`tribosweep.sweep` to the Rust core, one job per module.

``api``      :func:`sweep`: checks the arguments, builds the plan and runs its chunks (in-process or
             on any executor), with a progress bar and the resumable store
``plan``     the axes (checked), the points in C order, the chunks, the configuration and its hash
``parts``    the resumable store ``<output>.parts/`` (manifest, one atomic ``.npz`` per chunk)
``chunk``    :func:`compute_chunk`, the pure function a worker runs, and the strategies' policy
``stages``   linear | describing function | shooting | transient (+ irregular) | census
``schema``   every output variable with its units, long name and CF flags; coordinates and attributes
``netcdf``   the writers (netCDF file through ``.tmp``, or in memory), slab by slab, in bounded memory
``runner``   the chunk loop on each backend (in-process, a pool, dask) and the crash quarantine
``cluster``  dask.distributed: ``scheduler=`` (an address or ``local:N``), threads per task, chunk sizes
``disk``     disk space: the check before any work and the one error of a full disk
"""

from .api import sweep

__all__ = ["sweep"]
