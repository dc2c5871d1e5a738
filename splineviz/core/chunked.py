"""Volumes too big for memory: a lazily read, chunked 3-D grid with coarser levels.

Convention as :class:`~splineviz.core.volume.Volume`: ``data[i, j, k]`` is the sample at world
point ``origin + direction @ (i*sx, j*sy, k*sz)``; here ``data`` is a :mod:`dask.array`
(OME-Zarr, Zarr, HDF5 or any dask graph), never computed whole. ``levels`` are coarser versions
of the same box (an OME-Zarr multiscale pyramid, a pyramid sampled from an analytic field, or
one built by dask), each with its own spacing and origin, for previews and summaries that must
not read the full data. Levels, :attr:`ChunkedVolume.bounds` and the boxes
:meth:`ChunkedVolume.read` returns are in the volume's own axis-aligned frame
``origin + (i*sx, j*sy, k*sz)`` (world when ``direction`` is the identity), which
:mod:`splineviz.core.frame` turns about ``origin`` into world, as for a ``Volume``.

The *preview level* (:meth:`ChunkedVolume.preview_level`) is the finest level of at most
:data:`PREVIEW_SAMPLES` samples; a volume without such a level gets a strided downsample of
its coarsest one, read once. Its samples, held in memory as a :class:`Volume` spanning the
same world box (:meth:`ChunkedVolume.preview_volume`), make the pictures shown at once while
the exact bricks are computed, and the value range and histogram.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from splineviz.core.volume import Volume, VolumeError

#: samples of the coarse level used for previews and the value range (128^3: 2 MiB of
#: uint8, read in a fraction of a second, ray cast in milliseconds)
PREVIEW_SAMPLES = 128**3


@dataclass(frozen=True)
class Level:
    """One resolution of a chunked volume.

    Attributes
    ----------
    data : (nx, ny, nz) dask array
    spacing, origin : (3,) tuple of float
    label : str
        What the level is, in words (``"coarse level 2 of 3 (128^3 of 512^3)"``): shown
        with the previews made from it.
    """

    data: object
    spacing: tuple[float, float, float]
    origin: tuple[float, float, float]
    label: str = ""

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(int(n) for n in self.data.shape)

    def read_all(self) -> np.ndarray:
        """All samples of this (small, coarse) level, read here by dask's threads: a preview
        is wanted at once, not after a round trip through a cluster's queue."""
        return np.asarray(self.data.compute(scheduler="threads"))


@dataclass(frozen=True, eq=False)
class ChunkedVolume:
    """A volume read chunk by chunk (see module docstring).

    Parameters
    ----------
    data : (nx, ny, nz) dask array
        Full-resolution samples in their stored type (converted to float32 per brick).
    spacing, origin : (3,) sequence of float
    levels : sequence of Level, optional
        Coarser versions, finest first (without the full-resolution level itself).
    name : str
        What the data is called in messages and ``splineviz info``.
    source : object, optional
        Region reader of the full level in the same axis order (``source[i0:i1, j0:j1,
        k0:k1]`` -> ndarray): a zarr array or HDF5 dataset reads just the chunks a brick
        meets, an analytic field samples just the brick; without it bricks come from dask.
    unit : str, optional
        The unit of world coordinates (see :attr:`splineviz.Volume.unit`).
    direction : (3, 3) array_like, optional
        World direction of the i, j, k axes (columns): a rotation, the identity by default,
        checked as :class:`~splineviz.core.volume.Volume` checks its own (an oblique scan
        read brick by brick).

    Examples
    --------
    >>> import dask.array as da
    >>> v = ChunkedVolume(da.zeros((64, 64, 32), chunks=32), spacing=(1, 1, 2))
    >>> v.shape, v.chunks, v.bounds[2]
    ((64, 64, 32), (32, 32, 32), (0.0, 62.0))
    """

    data: object
    spacing: tuple[float, float, float] = (1.0, 1.0, 1.0)
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    levels: tuple = ()
    name: str = "chunked volume"
    source: object = None
    unit: str = ""
    direction: np.ndarray | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        import dask.array as da

        data = self.data if isinstance(self.data, da.Array) else da.asarray(self.data)
        if data.ndim != 3:
            raise VolumeError(f"a volume needs a 3-D array, got {data.ndim} dimension(s)")
        if min(data.shape) < 2:
            raise VolumeError(f"a chunked volume needs 2 samples per axis, got {data.shape}")
        if not (np.issubdtype(data.dtype, np.number) or data.dtype == bool) or \
                np.issubdtype(data.dtype, np.complexfloating):
            raise VolumeError(f"volume samples must be real numbers, got dtype {data.dtype}")
        # the geometry checks of Volume, on a 1-sample stand-in (nothing is read)
        probe = Volume(np.zeros((1, 1, 1), np.float32), self.spacing, self.origin,
                       self.direction, self.unit)
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "spacing", probe.spacing)
        object.__setattr__(self, "origin", probe.origin)
        object.__setattr__(self, "direction", probe.direction)
        object.__setattr__(self, "levels", tuple(self.levels))
        object.__setattr__(self, "unit", probe.unit)

    # -- geometry, without reading ------------------------------------------------------

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(int(n) for n in self.data.shape)

    @property
    def dtype(self) -> np.dtype:
        return np.dtype(self.data.dtype)

    @property
    def chunks(self) -> tuple[int, int, int]:
        """The largest chunk along each axis (the storage block)."""
        return tuple(int(max(c)) for c in self.data.chunks)

    @property
    def nbytes(self) -> int:
        """Bytes of the full data as float32 (what one in-memory Volume would take)."""
        return 4 * math.prod(self.shape)

    @property
    def bounds(self) -> tuple[tuple[float, float], ...]:
        """((xmin, xmax), (ymin, ymax), (zmin, zmax)) of the sample grid in the volume's own
        frame (world when axis-aligned; :attr:`world_bounds` in general)."""
        return tuple((o, o + (n - 1) * s)
                     for o, n, s in zip(self.origin, self.shape, self.spacing, strict=True))

    @property
    def axis_aligned(self) -> bool:
        """Whether the grid's axes are the world axes (``direction`` is the identity)."""
        return not np.any(self.direction != np.eye(3))

    @property
    def world_bounds(self) -> tuple[tuple[float, float], ...]:
        """((xmin, xmax), ...) of the grid's eight corners in world (:attr:`bounds` when
        axis-aligned)."""
        from splineviz.core.frame import world_bounds

        return world_bounds(self)

    def all_levels(self) -> list[Level]:
        """The full-resolution level followed by the coarser ones."""
        return [Level(self.data, self.spacing, self.origin), *self.levels]

    def preview_level(self, max_samples: int = PREVIEW_SAMPLES) -> Level:
        """The finest level with at most ``max_samples`` samples, labelled with its place in
        the pyramid; without such a level, a strided downsample of the coarsest level (every
        f-th sample along each axis: its chunks are read once, here, and the result kept in
        memory)."""
        levels = self.all_levels()
        full = _size(levels[0].shape)
        for n, level in enumerate(levels):
            # (a pyramid of a thin volume may end in levels one sample thick: no grid)
            if math.prod(level.shape) <= max_samples and min(level.shape) >= 2:
                label = (f"full level ({full})" if n == 0 else
                         f"coarse level {n} of {len(levels) - 1} ({_size(level.shape)} of "
                         f"{full})")
                return Level(level.data, level.spacing, level.origin, label)
        key = ("pyramid", max_samples)
        if key not in self._cache:
            k = len(levels) - 1
            name = f"coarse level {k} of {k} downsampled" if k else "downsample"
            self._cache[key] = strided_level(levels[-1], max_samples, name, full)
        return self._cache[key]

    def preview_volume(self, max_samples: int = PREVIEW_SAMPLES) -> Volume:
        """The samples of :meth:`preview_level` in memory (read once), as a volume spanning
        this volume's world box (its direction kept: the grid turns about the same origin).

        A level of ``m`` samples along an axis gets the spacing ``(n - 1) s / (m - 1)`` of
        the full level's ``n`` samples of spacing ``s``, and the full level's origin: the
        coarse surface then fills the box the exact one does (a level's own spacing,
        ``f s`` for ``m = n / f``, would end ``f - 1`` samples short of the box's far side).
        """
        key = ("preview", max_samples)
        if key not in self._cache:
            level = self.preview_level(max_samples)
            data = level.read_all()
            spacing = tuple((n - 1) * s / (m - 1) for n, s, m in zip(
                self.shape, self.spacing, data.shape, strict=True))
            self._cache[key] = Volume(data, spacing, self.origin, self.direction, self.unit)
        return self._cache[key]

    @property
    def finite_range(self) -> tuple[float, float]:
        """(min, max) of the finite samples of :meth:`preview_volume` (computed once).

        The full data are never read for it: an isovalue slider or a default isovalue needs
        the range, not every sample (extremes finer than the coarse level may lie outside).
        """
        if "range" not in self._cache:
            d = np.asarray(self.preview_volume().data, dtype=np.float64)
            finite = d[np.isfinite(d)]
            if finite.size == 0:
                raise VolumeError(f"{self.name} has no finite samples in its coarse level")
            self._cache["range"] = (float(finite.min()), float(finite.max()))
        return self._cache["range"]

    def read(self, box) -> Volume:
        """The samples of an index box as an in-memory, axis-aligned :class:`Volume` placed in
        this volume's own frame (world when this volume is axis-aligned): a brick or slab
        is cast and cut there, and :mod:`splineviz.core.frame` turns the results into
        world by this volume's direction.

        Parameters
        ----------
        box : ((i0, i1), (j0, j1), (k0, k1))
            Half-open sample index ranges.
        """
        sl = tuple(slice(int(a), int(b)) for a, b in box)
        if self.source is not None:
            data = np.asarray(self.source[sl])
        else:
            data = np.asarray(self.data[sl].compute(scheduler="synchronous"))
        origin = tuple(o + int(a) * s for o, (a, _), s in zip(self.origin, box, self.spacing,
                                                                strict=True))
        return Volume(data, spacing=self.spacing, origin=origin, unit=self.unit)

    # -- constructors -------------------------------------------------------------------

    @classmethod
    def from_dask(cls, array, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0), levels=(),
                  name: str = "dask array") -> ChunkedVolume:
        """A volume of a 3-D dask array, read lazily brick by brick, never whole (also
        spelt ``Volume.from_dask``).

        :class:`splineviz.RayCaster`-like rendering of it goes through
        :class:`splineviz.compute.bricked.BrickedRayCaster`.

        Parameters
        ----------
        array : (nx, ny, nz) dask array
        spacing, origin : (3,) float
        levels : sequence of :class:`Level`, coarser versions
        name : str
        """
        return cls(array, spacing, origin, tuple(levels), name)

    @classmethod
    def from_function(cls, func, shape, bounds, chunks=256, name: str = "analytic field",
                      dtype=np.float32) -> ChunkedVolume:
        """A lazy volume sampling ``func(x, y, z)`` per chunk, with a pyramid of coarser
        samplings of the same function (no level is ever computed whole).

        Parameters
        ----------
        func : callable
            Vectorised ``f(x, y, z)`` over broadcastable arrays: chunks pass (n, 1, 1),
            (1, n, 1) and (1, 1, n) coordinate arrays, so a separable field costs little.
        shape : (3,) int
        bounds : ((xmin, xmax), (ymin, ymax), (zmin, zmax))
        chunks : int
        dtype : stored type of the samples
        """
        shape = tuple(int(n) for n in shape)
        full = _function_level(func, shape, bounds, chunks, dtype)
        source = FunctionSource(func, shape, bounds, dtype)
        levels = []
        factor = 2
        while max(shape) // factor >= 8:
            coarse = tuple(max(2, (n - 1) // factor + 1) for n in shape)
            levels.append(_function_level(func, coarse, bounds, chunks, dtype))
            factor *= 2
        return cls(full.data, full.spacing, full.origin, tuple(levels), name, source)


class FunctionSource:
    """Region reads of an analytic field: ``source[slices]`` samples ``func`` on exactly that
    box of the grid (a brick never computes the neighbouring chunks its halo meets)."""

    def __init__(self, func, shape, bounds, dtype=np.float32):
        self.func = func
        self.shape = tuple(int(n) for n in shape)
        self.dtype = np.dtype(dtype)
        self.axes = [np.linspace(lo, hi, n)
                     for (lo, hi), n in zip(bounds, self.shape, strict=True)]

    def __getitem__(self, key) -> np.ndarray:
        x, y, z = (ax[k] for ax, k in zip(self.axes, key, strict=True))
        out = np.empty((len(x), len(y), len(z)), dtype=self.dtype)
        out[...] = self.func(x[:, None, None], y[None, :, None], z[None, None, :])
        return out


def _function_level(func, shape, bounds, chunks, dtype) -> Level:
    """A dask array of ``func`` on the ``shape`` grid spanning ``bounds``."""
    import dask.array as da

    axes = [np.linspace(lo, hi, n) for (lo, hi), n in zip(bounds, shape, strict=True)]

    def block(block_info=None):
        (i0, i1), (j0, j1), (k0, k1) = block_info[None]["array-location"]
        x = axes[0][i0:i1, None, None]
        y = axes[1][None, j0:j1, None]
        z = axes[2][None, None, k0:k1]
        out = np.empty((i1 - i0, j1 - j0, k1 - k0), dtype=dtype)
        out[...] = func(x, y, z)
        return out

    data = da.map_blocks(block, chunks=da.core.normalize_chunks(chunks, shape), dtype=dtype,
                         meta=np.empty((0, 0, 0), dtype))
    spacing = tuple((hi - lo) / (n - 1) for (lo, hi), n in zip(bounds, shape, strict=True))
    return Level(data, spacing, tuple(float(lo) for lo, _ in bounds))


def coarsen_level(level: Level, max_samples: int) -> Level:
    """Block means of ``level`` by the smallest power-of-two factor that brings it to at most
    ``max_samples`` samples (a dask pyramid level; computing it reads the whole level).

    The mean of samples ``f i .. f i + f - 1`` sits at their centre, so the origin moves by
    ``(f - 1) / 2`` samples along each axis.
    """
    import dask.array as da

    f = 2
    while math.prod(-(-n // f) for n in level.shape) > max_samples:
        f *= 2
    shape = level.shape
    trimmed = level.data[tuple(slice(0, max(f, n - n % f)) for n in shape)]
    factors = {a: min(f, trimmed.shape[a]) for a in range(3)}
    data = da.coarsen(np.mean, trimmed.astype(np.float32), factors, trim_excess=True)
    spacing = tuple(s * factors[a] for a, s in enumerate(level.spacing))
    origin = tuple(o + 0.5 * (factors[a] - 1) * s
                   for a, (o, s) in enumerate(zip(level.origin, level.spacing, strict=True)))
    return Level(data.astype(np.float32), spacing, origin)


def strided_level(level: Level, max_samples: int, name: str = "downsample",
                  of: str = "") -> Level:
    """Every f-th sample of ``level`` along each axis, for the smallest whole f that leaves at
    most ``max_samples`` samples, read now (dask's threads) and held in memory.

    Strides, not block means: the samples are the data's own (a surface through them is the
    data's at that isovalue, the value range is the data's), and no arithmetic runs over
    the full level (a 512^3 uint8 store: 0.14 s against 1.2 s for means, measured).

    Parameters
    ----------
    level : Level
    max_samples : int
    name, of : str
        What the level is and the full level's size, for the label (``"downsample 1:4
        (128^3 of 512^3)"``).
    """
    import dask.array as da

    shape = level.shape

    def factors(f):
        # a thin axis keeps two samples (a grid needs them)
        return tuple(max(1, min(f, n - 1)) for n in shape)

    f = max(1, math.floor((math.prod(shape) / max_samples) ** (1.0 / 3.0)))
    while math.prod(-(-n // g) for n, g in zip(shape, factors(f), strict=True)) > max_samples \
            and max(factors(f)) == f:
        f += 1
    step = factors(f)
    data = np.asarray(level.data[tuple(slice(None, None, g) for g in step)]
                      .compute(scheduler="threads"))
    spacing = tuple(s * g for s, g in zip(level.spacing, step, strict=True))
    size = _size(data.shape) + (f" of {of}" if of else "")
    label = f"{name} 1:{max(step)} ({size})"
    return Level(da.from_array(data, chunks=data.shape), spacing, level.origin, label)


def _size(shape) -> str:
    """A grid's size in words: ``128^3``, ``256x256x64``."""
    n = tuple(int(k) for k in shape)
    return f"{n[0]}^3" if len(set(n)) == 1 else "x".join(map(str, n))


# ``Volume.from_dask`` (the README's spelling) returns a ChunkedVolume, so it is set here, where
# ChunkedVolume lives: volume.py must not import this module, which builds on it. The package
# ``splineviz.core`` imports this module, so the name exists wherever Volume can be imported.
Volume.from_dask = staticmethod(ChunkedVolume.from_dask)
