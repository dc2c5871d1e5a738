"""The peak resident memory of the running process, for probes run in a fresh interpreter.

``ru_maxrss`` is no measure there: Linux carries the parent's high-water mark across
``fork`` + ``exec``, so a probe started from a large pytest process reports that process's
size (1.2 GB for a 2 GiB BigTIFF that took 140 MB) and any growth below it is invisible.
``VmHWM`` of ``/proc/self/status`` belongs to the new address space alone.
"""

#: source defining ``peak_rss_bytes()``, to prepend to a probe's code
PEAK_RSS_SOURCE = '''
def peak_rss_bytes():
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
'''
