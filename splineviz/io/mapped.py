"""Uncompressed samples in a file, memory-mapped: a small picklable region reader.

A ``.npy`` or raw volume too large to render in one piece is opened through the chunked path
(:class:`~splineviz.core.chunked.ChunkedVolume`, rendered in bricks): its dask array and
region reads go through a :class:`MappedArray`, which each process maps on first use, so a
brick reads only its own box of the file and nothing but the path travels to the workers.
"""

from __future__ import annotations

import os

import numpy as np

from splineviz.io._util import memory_budget

#: environment variable: share of :func:`~splineviz.io._util.memory_budget` above which a
#: volume (a TIFF or slice stack, a mapped file too big to render in one piece) is read
#: lazily through the chunked path
LAZY_SHARE_ENV = "SPLINEVIZ_LAZY_SHARE"
#: default share (the eager path holds the stored samples and the volume made of them:
#: :func:`~splineviz.io._util.held_bytes`)
LAZY_SHARE = 0.25
#: bytes a volume costs in one piece beside its samples, per sample: the ray caster's device
#: buffers (16-bit padded samples of 8-bit data, the min-max octree, classification slots;
#: host memory on a CPU OpenCL device) or the float32 copy of the NumPy paths
RENDER_BYTES_PER_SAMPLE = 4
#: stored bytes per dask chunk of a mapped volume (a brick reads whole chunks' rows)
CHUNK_BYTES = 16 * 2**20


class MappedArray:
    """Region reads ``source[i0:i1, j0:j1, k0:k1]`` of a 3-D array stored uncompressed.

    Parameters
    ----------
    path : path-like
    offset : int
        Bytes before the first sample.
    dtype : numpy dtype, byte order included
        The type as stored; reads come in its native byte order (:attr:`dtype`), the
        file's is kept in :attr:`stored`.
    shape : (nx, ny, nz)
        The volume's shape, ``data[i, j, k]`` with i along x.
    order : {"C", "F"}
        "C": k varies fastest in the file (``.npy``); "F": i varies fastest (raw, x fastest).
    """

    def __init__(self, path, offset: int, dtype, shape, order: str = "C"):
        self.path = str(path)
        self.offset = int(offset)
        self.stored = np.dtype(dtype)
        self.dtype = self.stored.newbyteorder("=")
        self.shape = tuple(int(n) for n in shape)
        self.ndim = 3
        self.order = order

    def __dask_tokenize__(self):
        import os

        st = os.stat(self.path)
        return (self.path, st.st_mtime_ns, st.st_size, self.offset, self.stored.str,
                self.shape, self.order)

    def __getitem__(self, key) -> np.ndarray:
        """The samples of ``key`` (a NumPy index), copied out of the file, C-ordered, in the
        native byte order of their type.

        The file is mapped for this read only: the pages read leave the process's resident
        memory with the mapping (one kept open would hold every page any brick read)."""
        stored = np.memmap(self.path, dtype=self.stored, mode="r", offset=self.offset,
                           shape=self.shape, order=self.order)
        # a copy: nothing refers to the mapping afterwards, so it is unmapped on return
        return np.array(stored[key], dtype=self.dtype, order="C")

    def chunks(self) -> tuple[int, int, int]:
        """Dask chunks of this array (:func:`cube_chunks`)."""
        return cube_chunks(self.shape, self.dtype)


def cube_chunks(shape, dtype) -> tuple[int, int, int]:
    """Dask chunks: cubes of about :data:`CHUNK_BYTES` (sides a multiple of 16), the shape
    the bricks of the ray caster are cut in (:mod:`splineviz.compute.bricked`)."""
    side = int(round((CHUNK_BYTES / np.dtype(dtype).itemsize) ** (1 / 3)))
    side = max(16, side - side % 16)
    return tuple(min(int(n), side) for n in shape)


def lazy_threshold() -> int:
    """Bytes above which a volume is read lazily (TIFF and slice stacks:
    :func:`~splineviz.io._util.held_bytes`; mapped files: :func:`renders_in_pieces`):
    ``$SPLINEVIZ_LAZY_SHARE``
    (default :data:`LAZY_SHARE`) of the memory budget."""
    share = LAZY_SHARE
    env = os.environ.get(LAZY_SHARE_ENV)
    if env:
        try:
            share = min(max(float(env), 0.0), 1.0)
        except ValueError:
            pass
    return int(share * memory_budget())


def renders_in_pieces(shape, dtype) -> bool:
    """Whether a volume of ``shape`` samples of ``dtype`` costs more in one piece (its samples
    and :data:`RENDER_BYTES_PER_SAMPLE` per sample) than the share of memory above which TIFF
    stacks are read lazily too (:func:`lazy_threshold`)."""
    count = int(np.prod([int(n) for n in shape], dtype=object))
    return count * (np.dtype(dtype).itemsize + RENDER_BYTES_PER_SAMPLE) > lazy_threshold()


def lazy_array(source):
    """The dask array of ``source`` (a :class:`MappedArray`, or any region reader with
    ``shape`` and ``dtype``), in :func:`cube_chunks`; nothing is read."""
    import dask.array as da

    return da.from_array(source, chunks=cube_chunks(source.shape, source.dtype),
                         asarray=False)


class OrientedArray:
    """Region reads, in world order, of an array stored in a file's index order: the lazy
    form of :meth:`~splineviz.io.geometry.Orientation.apply` (axes transposed by ``perm``,
    reversed by ``flips``), so a brick reads only its own mirrored box of the file.

    Parameters
    ----------
    source : region reader with ``shape`` (n0, n1, n2), ``dtype`` and ``__getitem__``
    perm : (3,) int
        ``perm[w]``: the stored axis that runs along world axis ``w``.
    flips : (3,) bool
        ``flips[w]``: world axis ``w`` runs against its stored axis.
    """

    def __init__(self, source, perm, flips):
        self.source = source
        self.perm = tuple(int(p) for p in perm)
        self.flips = tuple(bool(f) for f in flips)
        self.shape = tuple(int(source.shape[p]) for p in self.perm)
        self.dtype = np.dtype(source.dtype)
        self.ndim = 3

    def __dask_tokenize__(self):
        from dask.base import tokenize

        return ("oriented", tokenize(self.source), self.perm, self.flips)

    def __getitem__(self, key) -> np.ndarray:
        """The samples of ``key`` (up to three slices of step 1, in world order), C-ordered."""
        key = tuple(key) if isinstance(key, tuple) else (key,)
        key = key + (slice(None),) * (3 - len(key))
        stored: list = [None] * 3
        for w, (k, n) in enumerate(zip(key, self.shape, strict=True)):
            if not isinstance(k, slice):
                raise TypeError(f"region reads take slices, got {k!r}")
            start, stop, step = k.indices(n)
            if step != 1:
                raise ValueError(f"region reads take slices of step 1, got {k!r}")
            stop = max(stop, start)
            stored[self.perm[w]] = slice(n - stop, n - start) if self.flips[w] else \
                slice(start, stop)
        block = np.transpose(np.asarray(self.source[tuple(stored)]), self.perm)
        flipped = tuple(w for w in range(3) if self.flips[w])
        return np.ascontiguousarray(np.flip(block, flipped) if flipped else block)
