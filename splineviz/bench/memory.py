"""The peak memory the benchmarks (and the tests' memory probes) report."""

from __future__ import annotations


def peak_rss() -> int:
    """This process's peak resident memory in bytes.

    Linux's ``VmHWM`` of ``/proc/self/status``: ``ru_maxrss`` carries a parent's high-water
    mark across ``fork`` and ``exec``, so a child started from a large process (a benchmark's
    peer, a probe started by pytest) would report that process's size. ``ru_maxrss``
    elsewhere.
    """
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    import resource
    import sys

    scale = 1 if sys.platform == "darwin" else 1024  # macOS reports bytes, Linux KiB
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale
