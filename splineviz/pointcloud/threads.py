"""How many threads the point-cloud code may use, and numba's threading layer.

A GUI job process runs on all cores but one (:mod:`splineviz.gui.jobs` sets its affinity), so
the parallel loops and k-d tree queries here ask the process's affinity, not the machine's
core count.
"""

from __future__ import annotations

import os

import numba

# numba's parallel loops on OpenMP (libgomp1, which install.sh installs): numba tries TBB
# first, and warns when the TBB already loaded in the process is too old (open3d and
# pymeshlab bring TBB 2021.5); OpenMP first, TBB is never probed. Set on import, before any
# parallel kernel of this package starts (numba picks its layer at the first launch).
numba.config.THREADING_LAYER_PRIORITY = ["omp", "tbb", "workqueue"]


def allowed_cores() -> int:
    """Number of cores this process may run on (a GUI job process leaves the GUI one:
    :mod:`splineviz.gui.jobs`)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # no affinity on this platform
        return os.cpu_count() or 1


def use_allowed_cores() -> None:
    """numba's threads for the next parallel loops: one per allowed core."""
    numba.set_num_threads(max(1, min(allowed_cores(), numba.config.NUMBA_NUM_THREADS)))
