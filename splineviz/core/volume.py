"""The volume data model: a 3-D scalar grid with spacing, origin and direction.

Convention: ``data[i, j, k]`` is the sample at world point
``origin + direction @ (i*sx, j*sy, k*sz)`` (ITK's and Slicer's). ``direction`` is a
rotation, the identity for an axis-aligned grid; everything that works on the grid itself
(splines, ray casters, sections, slices) works in the volume's own axis-aligned frame
``origin + (i*sx, j*sy, k*sz)``, which :mod:`splineviz.core.frame` maps rigidly to world.

Samples keep their own type when float32 holds every value of it exactly (8- and 16-bit
integers, float32 itself), so a 1 GiB uint8 file stays 1 GiB; computations convert where they
need floats, a piece at a time (:meth:`Volume.values`), and get the numbers a float32 volume
would give. Other types become float32, the compute precision, as before.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from splineviz.core.errors import SplinevizError

#: sample types a volume keeps: float32 holds each of their values exactly
NATIVE_TYPES = frozenset(np.dtype(t) for t in (np.uint8, np.int8, np.uint16, np.int16,
                                               np.float32))
#: samples per slab of the whole-volume passes (range, non-finite count): bounded temporaries
SLAB_SAMPLES = 2**24


class VolumeError(SplinevizError, ValueError):
    """A volume that cannot be used (wrong shape, no finite samples, bad spacing)."""


@dataclass(frozen=True, eq=False)
class Volume:
    """Scalar samples on a regular grid.

    Parameters
    ----------
    data : (nx, ny, nz) array_like
        Samples, stored C-contiguous in their own type if it is one of :data:`NATIVE_TYPES`
        (no copy of an array that already is, a memory-mapped file included), bool as uint8,
        anything else as float32 (the compute precision). :meth:`values` gives float32.
    spacing : (3,) sequence of float, optional
        Grid step along x, y, z; all must be finite and positive.
    origin : (3,) sequence of float, optional
        World position of ``data[0, 0, 0]``.
    direction : (3, 3) array_like, optional
        World direction of the i, j, k axes (columns): a rotation (orthonormal, determinant
        +1), the identity by default. An oblique scan keeps its rotation here (see
        :mod:`splineviz.core.frame`); :attr:`bounds` and :meth:`index_to_world` stay in
        the volume's own axis-aligned frame.
    unit : str, optional
        The unit of world coordinates the file states ("mm", "µm", "Å"; see
        :mod:`splineviz.core.units`), ``""`` when it does not say.

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
    direction: np.ndarray | None = None
    unit: str = ""

    def __post_init__(self):
        from splineviz.core.units import canonical_unit

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
        object.__setattr__(self, "data", _stored(data))
        object.__setattr__(self, "spacing", spacing)
        object.__setattr__(self, "origin", origin)
        object.__setattr__(self, "direction", _rotation(self.direction))
        object.__setattr__(self, "unit", canonical_unit(self.unit))

    @property
    def axis_aligned(self) -> bool:
        """Whether the grid's axes are the world axes (``direction`` is the identity)."""
        return not np.any(self.direction != np.eye(3))

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(self.data.shape)

    @property
    def bounds(self) -> tuple[tuple[float, float], ...]:
        """((xmin, xmax), (ymin, ymax), (zmin, zmax)) of the sample grid in the volume's own
        frame (world for an axis-aligned volume; :attr:`world_bounds` in general)."""
        return tuple(
            (o, o + (n - 1) * s)
            for o, n, s in zip(self.origin, self.shape, self.spacing, strict=True)
        )

    @property
    def dtype(self) -> np.dtype:
        """The type the samples are stored in (see :data:`NATIVE_TYPES`)."""
        return self.data.dtype

    def values(self, region=None) -> np.ndarray:
        """The samples of ``region`` as float32, the type computations take.

        Parameters
        ----------
        region : tuple of slices or int index arrays, optional
            A NumPy index into :attr:`data`; the whole volume when omitted (a full-size copy
            unless the samples are float32 already: convert pieces where you can).

        Returns
        -------
        ndarray of float32, the shape ``data[region]`` has (``data`` itself when float32
        and ``region`` is omitted)
        """
        part = self.data if region is None else self.data[region]
        return np.asarray(part, dtype=np.float32)

    @functools.cached_property
    def finite_range(self) -> tuple[float, float]:
        """(min, max) over the finite samples; raises VolumeError if there are none.

        Computed once, slab by slab (no full-size temporary; a full pass over the data,
        ~0.1 s for 256^3), so callers in a GUI thread can ask again for free; the samples are
        not meant to change in place."""
        lo, hi = np.inf, -np.inf
        for slab in slabs(self.data):
            if slab.dtype.kind == "f":
                slab = slab[np.isfinite(slab)]
                if slab.size == 0:
                    continue
            lo, hi = min(lo, float(slab.min())), max(hi, float(slab.max()))
        if lo > hi:
            raise VolumeError("the volume has no finite samples")
        return lo, hi

    @functools.cached_property
    def nonfinite_count(self) -> int:
        """Number of NaN or infinite samples (computed once, like :attr:`finite_range`)."""
        if self.data.dtype.kind != "f":
            return 0
        return sum(int(slab.size - np.count_nonzero(np.isfinite(slab)))
                   for slab in slabs(self.data))

    @property
    def world_bounds(self) -> tuple[tuple[float, float], ...]:
        """((xmin, xmax), ...) of the grid's eight corners in world: the box a camera
        frames and clips (:attr:`bounds` itself when axis-aligned)."""
        from splineviz.core.frame import world_bounds

        return world_bounds(self)

    def to_world(self, points) -> np.ndarray:
        """(N, 3) points of the volume's own frame -> (N, 3) world points (float64)."""
        from splineviz.core.frame import to_world

        return to_world(self, points)

    def from_world(self, points) -> np.ndarray:
        """(N, 3) world points -> (N, 3) points of the volume's own frame (float64)."""
        from splineviz.core.frame import from_world

        return from_world(self, points)

    def world_to_index(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) coordinates of the volume's own frame (world when axis-aligned) -> (N, 3)
        continuous grid indices (float64); world points go through :meth:`from_world`."""
        p = np.asarray(points, dtype=np.float64)
        return (p - np.asarray(self.origin)) / np.asarray(self.spacing)

    def index_to_world(self, index: np.ndarray) -> np.ndarray:
        """(N, 3) continuous grid indices -> (N, 3) coordinates of the volume's own frame
        (world when axis-aligned; :meth:`to_world` rotates them into place)."""
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

    def show(self, size=None, camera=None, **options):
        """The picture of a new scene holding just this volume and its default isosurface,
        framed isometric (see :func:`splineviz.notebook.show`)."""
        from splineviz.core.pictures import show

        return show(self, size=size, camera=camera, **options)

    def _repr_png_(self) -> bytes:
        """A notebook shows the volume as :meth:`show`'s picture."""
        return self.show().png()


#: largest deviation of ``direction.T @ direction`` from the identity a rotation may have
#: (headers store directions in float32)
ROTATION_TOLERANCE = 1e-5


def _rotation(direction) -> np.ndarray:
    """``direction`` as a read-only (3, 3) float64 rotation (the identity for None);
    orthonormalised when within :data:`ROTATION_TOLERANCE` of one, else refused."""
    if direction is None:
        d = np.eye(3)
    else:
        try:
            d = np.array(direction, dtype=np.float64).reshape(3, 3)
        except (TypeError, ValueError):
            raise VolumeError("direction must be a 3x3 matrix of numbers") from None
        if not np.all(np.isfinite(d)):
            raise VolumeError("direction must be finite")
        if np.abs(d.T @ d - np.eye(3)).max() > ROTATION_TOLERANCE or np.linalg.det(d) < 0:
            raise VolumeError("direction must be a rotation (orthonormal columns, determinant "
                              "+1); flip the axes of a mirrored grid instead")
        if np.any(d != np.eye(3)):
            u, _, vt = np.linalg.svd(d)
            d = u @ vt
    d.flags.writeable = False
    return d


def _stored(data: np.ndarray) -> np.ndarray:
    """``data`` in the type and layout a :class:`Volume` keeps (see its ``data``)."""
    if data.dtype == bool:
        return np.ascontiguousarray(data).view(np.uint8)
    if data.dtype.newbyteorder("=") in NATIVE_TYPES:
        return np.ascontiguousarray(data, dtype=data.dtype.newbyteorder("="))
    return np.ascontiguousarray(data, dtype=np.float32)


def slabs(data: np.ndarray):
    """``data`` in slabs along its first axis of about :data:`SLAB_SAMPLES` samples."""
    step = max(1, SLAB_SAMPLES // max(1, data[0].size))
    for i in range(0, len(data), step):
        yield data[i:i + step]
