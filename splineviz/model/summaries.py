"""Summaries of data that views show: a volume's histogram (what the isovalue slider is
drawn over) and a point cloud's sample spacing (the remesher's default edge length).

Each is computed once per data object, off the GUI thread (the reading process makes them
with the data), and kept for the object's lifetime."""

from __future__ import annotations

import threading
import weakref

import numpy as np

#: bins of the histogram drawn behind the isovalue slider
HISTOGRAM_BINS = 128

_kept: dict[tuple[str, int], tuple] = {}
_lock = threading.Lock()


def remember(what: str, obj, value) -> None:
    """Keep ``value`` as the ``what`` summary of ``obj`` (until ``obj`` is gone)."""
    key = (what, id(obj))
    with _lock:
        _kept[key] = (weakref.ref(obj, lambda _r, k=key: _kept.pop(k, None)), value)


def _kept_value(what: str, obj):
    with _lock:
        hit = _kept.get((what, id(obj)))
    return hit[1] if hit is not None and hit[0]() is obj else None


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


def summary_samples(volume) -> np.ndarray:
    """The samples a volume's summaries are made of: all of an in-memory volume, the coarse
    level of a chunked one (:meth:`~splineviz.core.chunked.ChunkedVolume.preview_level`: a
    histogram must not read a volume bigger than memory)."""
    from splineviz.core.chunked import ChunkedVolume

    if isinstance(volume, ChunkedVolume):
        return np.asarray(volume.preview_level().read_all())
    return volume.data


def cached_histogram(volume):
    """``log_histogram`` of :func:`summary_samples`, computed once per volume object
    (thread safe)."""
    hist = _kept_value("histogram", volume)
    if hist is None:
        hist = log_histogram(summary_samples(volume))
        remember("histogram", volume, hist)
    return hist


def median_spacing(points: np.ndarray) -> float:
    """Median nearest-neighbour distance of (up to 2000 sampled) ``(N, 3)`` points."""
    from scipy.spatial import cKDTree

    points = np.asarray(points)
    if len(points) < 2:
        return 1.0
    rng = np.random.default_rng(0)
    sample = points[rng.choice(len(points), size=min(2000, len(points)), replace=False)]
    d, _ = cKDTree(points).query(sample, k=2)
    return float(np.median(d[:, 1])) or 1.0


def cached_spacing(cloud) -> float:
    """:func:`median_spacing` of a point cloud, computed once per cloud (thread safe)."""
    spacing = _kept_value("spacing", cloud)
    if spacing is None:
        spacing = median_spacing(cloud.points)
        remember("spacing", cloud, spacing)
    return spacing


def known_spacing(cloud) -> float | None:
    """The cloud's spacing if it was computed already (None: ask for it in a worker)."""
    return _kept_value("spacing", cloud)
