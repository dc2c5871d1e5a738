"""The volume data model: a 3-D scalar grid with spacing and origin.

Convention: ``data[i, j, k]`` is the sample at world point ``origin + (i*sx, j*sy, k*sz)``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from splineviz.core.errors import SplinevizError


class VolumeError(SplinevizError, ValueError):
    """A volume that cannot be used (wrong shape, no finite samples, bad spacing)."""


@dataclass(frozen=True, eq=False)
class Volume:
    """Scalar samples on a regular grid.

    Parameters
    ----------
    data : (nx, ny, nz) array_like
        Samples; stored as C-contiguous float32 (the compute precision).
    spacing : (3,) sequence of float, optional
        Grid step along x, y, z; all must be finite and positive.
    origin : (3,) sequence of float, optional
        World position of ``data[0, 0, 0]``.

    Examples
    --------
    >>> import numpy as np
    >>> v = Volume(np.zeros((4, 5, 6)), spacing=(1, 1, 2))
    >>> v.shape, v.bounds[2]
    ((4, 5, 6), (0.0, 10.0))

    ``Volume.from_dask(array, spacing, origin)`` wraps a dask array as a lazily read
    :class:`~splineviz.core.chunked.ChunkedVolume`; :mod:`splineviz.core.chunked` defines it,
    since the chunked volume builds on this module and not the reverse.
    """

    data: np.ndarray
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self):
        data = np.asarray(self.data)
        if data.ndim != 3:
            raise VolumeError(f"a volume needs a 3-D array, got {data.ndim} dimension(s)")
        if min(data.shape) < 1:
            raise VolumeError("a volume needs at least one sample per axis, got shape "
                              f"{data.shape}")
        if not (np.issubdtype(data.dtype, np.number) or data.dtype == bool):
            raise VolumeError(f"volume samples must be numeric, got dtype {data.dtype}")
        spacing = tuple(float(s) for s in np.broadcast_to(np.asarray(self.spacing, float), 3))
        origin = tuple(float(o) for o in np.broadcast_to(np.asarray(self.origin, float), 3))
        if not all(np.isfinite(s) and s > 0 for s in spacing):
            raise VolumeError(f"spacing must be finite and positive, got {spacing}")
        if not all(np.isfinite(o) for o in origin):
            raise VolumeError(f"origin must be finite, got {origin}")
        object.__setattr__(self, "data", np.ascontiguousarray(data, dtype=np.float32))
        object.__setattr__(self, "spacing", spacing)
        object.__setattr__(self, "origin", origin)

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.data.shape)

    @property
    def bounds(self) -> tuple[tuple[float, float], ...]:
        """((xmin, xmax), (ymin, ymax), (zmin, zmax)) of the sample grid."""
        return tuple(
            (o, o + (n - 1) * s)
            for o, n, s in zip(self.origin, self.shape, self.spacing, strict=True)
        )

    @functools.cached_property
    def finite_range(self) -> tuple[float, float]:
        """(min, max) over the finite samples; raises VolumeError if there are none.

        Computed once (a full pass over the data: ~0.1 s for 256^3), so callers in a GUI
        thread can ask again for free; the samples are not meant to change in place."""
        finite = self.data[np.isfinite(self.data)]
        if finite.size == 0:
            raise VolumeError("the volume has no finite samples")
        return float(finite.min()), float(finite.max())

    @functools.cached_property
    def nonfinite_count(self) -> int:
        """Number of NaN or infinite samples (computed once, like :attr:`finite_range`)."""
        return int(self.data.size - np.count_nonzero(np.isfinite(self.data)))

    def world_to_index(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) world coordinates -> (N, 3) continuous grid indices (float64)."""
        p = np.asarray(points, dtype=np.float64)
        return (p - np.asarray(self.origin)) / np.asarray(self.spacing)

    def index_to_world(self, index: np.ndarray) -> np.ndarray:
        """(N, 3) continuous grid indices -> (N, 3) world coordinates (float64)."""
        i = np.asarray(index, dtype=np.float64)
        return i * np.asarray(self.spacing) + np.asarray(self.origin)

    @classmethod
    def from_function(cls, func, shape, bounds) -> Volume:
        """Sample ``func(x, y, z)`` on a grid of ``shape`` spanning ``bounds``.

        Parameters
        ----------
        func : callable
            Vectorised ``f(x, y, z) -> values`` over arrays of equal shape.
        shape : (3,) sequence of int
        bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax))
        """
        shape = tuple(int(n) for n in shape)
        axes = [np.linspace(lo, hi, n) for (lo, hi), n in zip(bounds, shape, strict=True)]
        x, y, z = np.meshgrid(*axes, indexing="ij")
        spacing = tuple((hi - lo) / max(n - 1, 1)
                        for (lo, hi), n in zip(bounds, shape, strict=True))
        return cls(func(x, y, z), spacing=spacing, origin=tuple(lo for lo, _ in bounds))
