"""A volume's histogram (what the isovalue slider is drawn over): computed once per volume,
off the GUI thread, and kept for the volume's lifetime."""

from __future__ import annotations

import threading
import weakref

import numpy as np

#: bins of the histogram drawn behind the isovalue slider
HISTOGRAM_BINS = 128

_histograms: dict[int, tuple] = {}
_lock = threading.Lock()


def log_histogram(data: np.ndarray, bins: int = HISTOGRAM_BINS):
    """``(log(1 + counts), edges)`` of the finite samples; counts ``(bins,)``, edges
    ``(bins + 1,)``. A constant volume gives one full bin around its value."""
    d = np.asarray(data).ravel()
    d = d[np.isfinite(d)]
    if d.size == 0:
        return np.zeros(bins), np.linspace(0.0, 1.0, bins + 1)
    lo, hi = float(d.min()), float(d.max())
    if hi <= lo:
        hi = lo + 1.0
    counts, edges = np.histogram(d, bins=bins, range=(lo, hi))
    return np.log1p(counts.astype(np.float64)), edges


def remember_histogram(volume, histogram) -> None:
    """Keep ``histogram`` (made elsewhere, e.g. by the reading process) for ``volume``."""
    key = id(volume)
    with _lock:
        _histograms[key] = (weakref.ref(volume, lambda _r, k=key: _histograms.pop(k, None)),
                            histogram)


def cached_histogram(volume):
    """``log_histogram(volume.data)``, computed once per volume object (thread safe)."""
    with _lock:
        hit = _histograms.get(id(volume))
        if hit is not None and hit[0]() is volume:
            return hit[1]
    hist = log_histogram(volume.data)
    remember_histogram(volume, hist)
    return hist
