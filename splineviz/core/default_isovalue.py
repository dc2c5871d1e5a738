"""The first isovalue of a volume: the level that separates background from object.

The middle of the data range is a poor first surface: on a cryo-EM map (noise around 0,
a molecule of positive density and a few extreme samples) it cuts the noise and fills the box
with a wall of speckles; on CT and MRI the range is stretched by a few bright samples
(metal, bone) and the middle misses the tissue. The rule here:

1. Otsu's threshold of the histogram: the level that best splits the samples into two
   classes (background, object), as ImageJ's and 3D Slicer's automatic thresholds do.
2. Unless the histogram has no two classes to split: Otsu's separability (between-class
   variance over total variance) of a single Gaussian is 2/pi = 0.637, and a histogram split
   hardly better than that (below :data:`MIN_SEPARABILITY`) is noise around one level, as
   in a cryo-EM map. Otsu's level would then cut the noise at its mean; instead the level
   that encloses :data:`NOISE_ENCLOSED` of the samples is used, ChimeraX's rule for maps.
3. Unless Otsu's upper class holds more than half of the samples: the background around an
   object is the bigger class, so a split that puts most of the samples in the "object" has
   found no object in a background but a box its subject fills (a crystal lattice in a
   cryo-EM map such as EMD-3197, whose Otsu surface runs as a wall through the whole box; a
   scan cropped inside the body such as carotid.vtk, where that class is the tissue around
   the vessels of interest). The
   densest structure is then what a first surface can show: the level enclosing
   :data:`NOISE_ENCLOSED` of the samples, as for noise.

``tests/model/test_default_isovalue.py`` renders the result on the shared data.

Everything is read off a histogram, so the rule is cheap on big and chunked volumes: the
scene passes the histogram the volume already has (the one drawn behind the isovalue slider,
:func:`splineviz.model.summaries.cached_histogram`); :func:`default_isovalue` makes one of a
subsample (a stride through an in-memory volume, at most :data:`MAX_SAMPLES` samples; the
coarse level of a chunked one).
"""

from __future__ import annotations

import math

import numpy as np

#: samples the histogram is made of, at most (a stride over bigger volumes)
MAX_SAMPLES = 2_000_000
#: bins of the histogram Otsu's threshold is found in
BINS = 256
#: Otsu's separability below which the samples count as one noisy class (2/pi for a Gaussian)
MIN_SEPARABILITY = 0.65
#: fraction of the samples above the level chosen for noise-like data (ChimeraX: 1 %)
NOISE_ENCLOSED = 0.01


def threshold_samples(volume) -> np.ndarray:
    """The finite samples ``(M,)`` float64 a histogram for the default isovalue is made of:
    every sample of a small volume, a regular stride through a big one, the coarse level of a
    chunked one."""
    from splineviz.core.chunked import ChunkedVolume

    if isinstance(volume, ChunkedVolume):
        data = np.asarray(volume.preview_level().read_all())
    else:
        data = np.asarray(volume.data)
        # the same stride on every axis keeps the sample spread over the whole box
        step = max(1, math.ceil((data.size / MAX_SAMPLES) ** (1.0 / 3.0)))
        data = data[::step, ::step, ::step]
    d = np.asarray(data, dtype=np.float64).ravel()
    return d[np.isfinite(d)]


def separability(counts: np.ndarray, centres: np.ndarray, level: float) -> float:
    """Otsu's separability of a histogram split at ``level``: the between-class variance
    over the total variance, in [0, 1] (1: two values; 2/pi: a Gaussian split at its mean).

    Parameters
    ----------
    counts : (B,) samples per bin
    centres : (B,) the bins' centres
    level : float
    """
    w = np.asarray(counts, dtype=np.float64)
    x = np.asarray(centres, dtype=np.float64)
    n = w.sum()
    if not n > 0:
        return 0.0
    mean = (w * x).sum() / n
    total = (w * (x - mean) ** 2).sum() / n
    upper = x > level
    n_up = w[upper].sum()
    if not total > 0.0 or n_up in (0.0, n):
        return 0.0
    gap = (w[upper] * x[upper]).sum() / n_up - (w[~upper] * x[~upper]).sum() / (n - n_up)
    p = n_up / n
    return float(p * (1.0 - p) * gap * gap / total)


def enclosing_level(counts: np.ndarray, edges: np.ndarray, fraction: float) -> float:
    """The level above which ``fraction`` of a histogram's samples lie (linear within a bin).

    Parameters
    ----------
    counts : (B,) samples per bin
    edges : (B + 1,) bin edges
    fraction : float in (0, 1)
    """
    w = np.asarray(counts, dtype=np.float64)
    below = np.concatenate([[0.0], np.cumsum(w)]) / max(w.sum(), 1e-300)
    return float(np.interp(1.0 - fraction, below, np.asarray(edges, dtype=np.float64)))


def isovalue_from_histogram(counts: np.ndarray, edges: np.ndarray) -> float:
    """The default isovalue (see the module docstring) of a histogram.

    Parameters
    ----------
    counts : (B,) samples per bin (not their logarithm)
    edges : (B + 1,) increasing bin edges over the finite data range

    Returns
    -------
    float
        Otsu's threshold, or the level enclosing :data:`NOISE_ENCLOSED` of the samples for
        a noise-like histogram or one whose Otsu object would be the bigger class;
        strictly inside ``(edges[0], edges[-1])``. The middle of the edges when one bin
        holds every sample (nothing to separate).
    """
    from skimage.filters import threshold_otsu

    w = np.asarray(counts, dtype=np.float64)
    e = np.asarray(edges, dtype=np.float64)
    lo, hi = float(e[0]), float(e[-1])
    if np.count_nonzero(w) < 2:
        return 0.5 * (lo + hi)
    centres = 0.5 * (e[1:] + e[:-1])
    level = float(threshold_otsu(hist=(w, centres)))
    if (separability(w, centres, level) < MIN_SEPARABILITY
            or w[centres > level].sum() > 0.5 * w.sum()):
        level = enclosing_level(w, e, NOISE_ENCLOSED)
    if not lo < level < hi:
        return 0.5 * (lo + hi)
    return level


def default_isovalue(volume) -> float:
    """The isovalue a volume's first isosurface starts with (see the module docstring),
    from a histogram of :func:`threshold_samples`.

    Parameters
    ----------
    volume : Volume or ChunkedVolume
        Samples ``(nx, ny, nz)``; only a subsample is read.

    Returns
    -------
    float, inside the finite data range
    """
    lo, hi = volume.finite_range
    if not hi > lo:
        return lo
    counts, edges = np.histogram(threshold_samples(volume), bins=BINS, range=(lo, hi))
    return isovalue_from_histogram(counts, edges)
